import json

import numpy as np
import pytest

from fdemtools import hysteresis


def loops(amps, hs, k, n=9):
    """Parallelogram loops: upper branch P = k d + h, lower branch P = k d - h, vertical unloading jumps at +-D.
    Cycle i: 0 -> +D on the upper branch, jump down, +D -> -D on the lower branch, jump up, -D -> 0 upper.
    Enclosed area 4 h D; peaks +-(k D + h) at +-D; secant stiffness k + h / D."""
    d, p = [], []
    for D, h in zip(amps, hs):
        seg_d = [np.linspace(0, D, n), [D], np.linspace(D, -D, 2 * n - 1), [-D], np.linspace(-D, 0, n)]
        seg_p = [k * seg_d[0] + h, [k * D - h], k * seg_d[2] - h, [-k * D + h], k * seg_d[4] + h]
        d += [np.asarray(s, float) for s in seg_d]
        p += [np.asarray(s, float) for s in seg_p]
    return np.concatenate(d), np.concatenate(p)


AMPS = [1e-3, 2e-3, 4e-3, 6e-3]  # m
HS = [1e3, 3e3, 5e3, 6e3]        # N
K = 5e6                          # N/m


def test_known_loops():
    d, p = loops(AMPS, HS, K)
    r = hysteresis.analyse(d, p)
    assert r["n_cycles"] == len(AMPS)
    e_cum = np.cumsum([4 * h * D for D, h in zip(AMPS, HS)])
    k_true = [K + h / D for D, h in zip(AMPS, HS)]
    for c, D, h, kt, ec in zip(r["cycles"], AMPS, HS, k_true, e_cum):
        assert c["complete"]
        assert c["P_plus"] == pytest.approx(K * D + h, rel=1e-12)
        assert c["P_minus"] == pytest.approx(-(K * D + h), rel=1e-12)
        assert c["d_plus"] == pytest.approx(D, rel=1e-12)
        assert c["k_i"] == pytest.approx(kt, rel=1e-12)
        assert c["k_d"] == pytest.approx(kt / k_true[0], rel=1e-12)
        assert c["W_i"] == pytest.approx(4 * h * D, rel=1e-10)
        assert c["E_i"] == pytest.approx(ec, rel=1e-10)
        assert c["E_d"] == pytest.approx(ec / e_cum[-1], rel=1e-10)


def test_flat_loops_secant_at_the_tips():
    """Steady elastic-perfectly-plastic loops (stiffness K, yield load F, amplitude D >= 2 F / K), each cycle from
    d = 0 up to +D on the flat branch P = F, down to -D (P = max(F - K (D - d), -F)), back up to 0
    (P = min(-F + K (d + D), F)). The largest load F is reached at d = 0, the start of the cycle; the peaks of the
    M-DEM paper's Eq. 8 are the loads at the loop's tips, +-F at +-D, so k_i = F / D exactly (the largest-load rule
    gave P+ at d = 0 and a k_i that grows without bound as the start approaches 0)."""
    F = 2e3
    d_all, p_all = [], []
    amps = (2e-3, 2e-3, 4e-3, 4e-3)
    for D in amps:
        up0 = np.linspace(0, D, 201)
        down = np.linspace(D, -D, 801)[1:]
        up1 = np.linspace(-D, 0, 401)[1:]
        d_all += [up0 if not d_all else up0[1:], down, up1]
        p_all += [np.full_like(up0 if not p_all else up0[1:], F), np.maximum(F - K * (D - down), -F),
                  np.minimum(-F + K * (up1 + D), F)]
    d = np.concatenate(d_all)
    p = np.concatenate(p_all)
    r = hysteresis.analyse(d, p)
    assert r["n_cycles"] == len(amps)
    for c, D in zip(r["cycles"], amps):
        assert c["complete"]
        assert c["d_plus"] == pytest.approx(D, rel=1e-12)
        assert c["d_minus"] == pytest.approx(-D, rel=1e-12)
        assert c["P_plus"] == pytest.approx(F, rel=1e-12)
        assert c["P_minus"] == pytest.approx(-F, rel=1e-12)
        assert c["k_i"] == pytest.approx(F / D, rel=1e-12)
        assert c["W_i"] > 0 and not c["W_negative"]
        # the largest load of the positive excursion is reported apart, where it is: at the start of the flat branch
        assert c["P_largest_plus"] == pytest.approx(F, rel=1e-12)
        assert c["d_at_P_largest_plus"] < 0.01 * D


def test_sliding_loop_largest_load_on_the_other_side():
    """A sliding loop whose largest positive load occurs at negative displacement (the load overshoots while the
    displacement is still coming back from -D, as in cycle 4 of the committed 0.30 MPa cyclic wall, P+ at -1.93
    mm): the peak of the positive excursion is still the load at +D."""
    D, F = 1e-3, 10e3
    d = np.array([0, 0.5e-3, D, 0.5e-3, 0, -0.5e-3, -D, -0.5e-3, -0.2e-3, 0])
    p = np.array([0, F, F, 0, -F, -F, -F, 0, 1.3 * F, F])  # 1.3 F at d = -0.2 mm (negative side)
    r = hysteresis.analyse(d, p, load_sign=1.0)
    c = r["cycles"][0]
    assert c["d_plus"] == D and c["P_plus"] == F and c["d_minus"] == -D and c["P_minus"] == -F
    assert c["k_i"] == pytest.approx(2 * F / (2 * D), rel=1e-12)


def test_negative_energy_is_flagged(tmp_path, cli):
    """A loop run anticlockwise (an applied load that returns energy: noise, an unclosed loop or a wrong sign) has
    W_i < 0; the cycle is flagged and a warning printed, not a silent negative dissipation."""
    D, h = 1e-3, 2e3
    up, down = np.linspace(-D, D, 41), np.linspace(D, -D, 41)[1:]
    # cycle 1: clockwise (upper branch going right); cycle 2: anticlockwise (upper branch going left)
    d = np.concatenate((np.linspace(0, D, 21), down, up[1:], down, up[1:], np.linspace(-D, 0, 21)[1:]))
    p = np.concatenate((K * np.linspace(0, D, 21) + h, K * down + h, K * up[1:] - h, K * down - h, K * up[1:] + h,
                        K * np.linspace(-D, 0, 21)[1:] + h))
    r = hysteresis.analyse(d, p, load_sign=1.0)
    w = [c["W_i"] for c in r["cycles"]]
    negs = [c["W_negative"] for c in r["cycles"]]
    assert any(negs) and not all(negs)
    assert all((wi < 0) == n for wi, n in zip(w, negs))
    assert any("negative dissipated energy" in m for m in r["warnings"])
    f = tmp_path / "noisy.csv"
    f.write_text("u_m,F_N\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(d, p)))
    rc, out, err = cli("hysteresis", f, "--load-sign", "1", "--no-plot")
    assert rc == 0, err
    assert "warning:" in out and "negative dissipated energy" in out and "(NEGATIVE)" in out


def test_given_references_and_trailing_half_cycle():
    d, p = loops(AMPS, HS, K)
    # a last excursion to +D without return: an incomplete cycle with no negative peak
    tail = np.linspace(0, 7e-3, 5)[1:]
    d2 = np.concatenate((d, tail))
    p2 = np.concatenate((p, K * tail + 6e3))
    r = hysteresis.analyse(d2, p2, k_el=2 * K, e_h=10.0)
    # the trailing partial cycle is kept apart (issue 51, 3): not a cycle of the table, listed as partial
    assert r["n_cycles"] == len(AMPS) and r["n_partial"] == 1
    assert all(c["complete"] and np.isfinite(c["k_i"]) for c in r["cycles"])
    last = r["partial"][0]
    assert not last["complete"] and last["cycle"] == len(AMPS) + 1 and last["d_plus"] == pytest.approx(7e-3)
    c1 = r["cycles"][0]
    assert c1["k_d"] == pytest.approx((K + HS[0] / AMPS[0]) / (2 * K), rel=1e-12)
    assert c1["E_d"] == pytest.approx(4 * HS[0] * AMPS[0] / 10.0, rel=1e-10)


def test_reaction_sign_is_turned():
    d, p = loops(AMPS, HS, K)
    r = hysteresis.analyse(d, -p)
    assert r["sign_y"] == -1
    assert r["E_total"] == pytest.approx(sum(4 * h * D for D, h in zip(AMPS, HS)), rel=1e-10)


def test_noise_at_zero_does_not_split_cycles():
    d, p = loops(AMPS, HS, K)
    rng = np.random.default_rng(3)
    d = d + 1e-9 * rng.standard_normal(len(d))  # far inside the dead band
    r = hysteresis.analyse(d, p)
    assert r["n_cycles"] == len(AMPS)


def test_cli(tmp_path, cli):
    d, p = loops(AMPS, HS, K)
    f = tmp_path / "cyc.csv"
    f.write_text("u,F\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(d, p)))
    rc, out, err = cli("hysteresis", f)
    assert rc == 0, err
    r = json.loads((tmp_path / "cyc_hysteresis.json").read_text())
    assert r["n_cycles"] == 4
    ki = r["columns"].index("k_i_kN_per_mm")
    assert r["cycles"][1][ki] == pytest.approx((K + HS[1] / AMPS[1]) * 1e-6, rel=1e-12)  # kN/mm
    assert (tmp_path / "cyc_hysteresis.png").exists()
    f.write_text("u,F\n0,0\n1,1\n2,2\n")
    rc, out, err = cli("hysteresis", f)
    assert rc == 1 and "not a cyclic curve" in err and len(err.strip().splitlines()) == 1


def test_trailing_partial_cycle_is_kept_apart(tmp_path, cli):
    """Issue 51 (3): a record that ends inside a cycle (0 -> +0.2 mm -> -0.1 mm, the load still high at d = 0) counted
    it as a cycle: k_i over 0.3 mm of travel (k_d of several times the elastic one) and a loop peak drawn at d = 0.
    Now the table, k_el, k_d, E_i, E_d and E_h are those of the complete loops exactly, and the partial cycle is listed
    apart, marked '*', with the mark explained, and drawn as partial."""
    d, p = loops(AMPS, HS, K)
    td = np.array([1e-4, 2e-4, 1e-4, 0.0, -1e-4])
    tp = np.array([8e3, 9e3, 8e3, 6e3, -2e3])
    d2, p2 = np.concatenate((d, td)), np.concatenate((p, tp))
    r = hysteresis.analyse(d2, p2, load_sign=1.0)
    ref = hysteresis.analyse(d, p, load_sign=1.0)
    assert r["n_cycles"] == len(AMPS) and r["n_partial"] == 1
    for a, b in zip(r["cycles"], ref["cycles"]):
        for k in ("k_i", "k_d", "E_i", "E_d", "P_plus", "P_minus"):
            assert a[k] == pytest.approx(b[k], rel=1e-12)
    assert r["E_h"] == pytest.approx(ref["E_h"], rel=1e-12) and r["k_el"] == pytest.approx(ref["k_el"], rel=1e-12)
    assert r["partial"][0]["d_plus"] == pytest.approx(2e-4) and r["partial"][0]["d_minus"] == pytest.approx(-1e-4)
    f = tmp_path / "cyc.csv"
    f.write_text("u_m,F_N\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(d2, p2)))
    rc, out, err = cli("hysteresis", f, "--load-sign", "1")
    assert rc == 0, err
    assert f"{len(AMPS)} complete cycles (+ 1 partial, not counted)" in out
    assert f"cycle   {len(AMPS) + 1}*" in out and "* partial cycle: the record ends" in out
    csv_rows = (tmp_path / "cyc_hysteresis.csv").read_text().splitlines()
    assert len(csv_rows) == 1 + len(AMPS)
    j = json.loads((tmp_path / "cyc_hysteresis.json").read_text())
    assert j["n_cycles"] == len(AMPS) and len(j["partial_cycles"]) == 1 and j["partial_cycles"][0]["cycle"] == 5
    assert "partial cycle 5" in (tmp_path / "cyc_hysteresis.svg").read_text()
