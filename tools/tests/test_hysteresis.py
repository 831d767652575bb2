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
    (P = min(-F + K (d + D), F)). The largest load F is reached at d = 0, the start of the cycle, so k_i is not the
    loop's secant; the loads at the tips are +-F and k_ext = F / D exactly."""
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
        assert c["d_max"] == pytest.approx(D, rel=1e-12)
        assert c["P_at_d_max"] == pytest.approx(F, rel=1e-12)
        assert c["P_at_d_min"] == pytest.approx(-F, rel=1e-12)
        assert c["k_ext"] == pytest.approx(F / D, rel=1e-12)
        assert c["P_plus"] == pytest.approx(F, rel=1e-12)
        assert c["d_plus"] < 0.01 * D  # the largest load sits at the start of the flat branch, not at the tip


def test_given_references_and_trailing_half_cycle():
    d, p = loops(AMPS, HS, K)
    # a last excursion to +D without return: an incomplete cycle with no negative peak
    tail = np.linspace(0, 7e-3, 5)[1:]
    d2 = np.concatenate((d, tail))
    p2 = np.concatenate((p, K * tail + 6e3))
    r = hysteresis.analyse(d2, p2, k_el=2 * K, e_h=10.0)
    assert r["n_cycles"] == len(AMPS) + 1
    last = r["cycles"][-1]
    assert not last["complete"] and np.isnan(last["k_i"])
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
