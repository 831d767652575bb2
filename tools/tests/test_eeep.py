import json

import numpy as np
import pytest

from fdemtools import eeep
from fdemtools.common import ToolError


def epp_curve(k, dy, du, n_el=7, n_pl=11):
    """Elastic-perfectly-plastic curve: stiffness k up to yield displacement dy, plateau to du."""
    d = np.concatenate((np.linspace(0, dy, n_el), np.linspace(dy, du, n_pl)[1:]))
    p = np.minimum(k * d, k * dy)
    return d, p


@pytest.mark.parametrize("ultimate", ["peak", "drop"])
@pytest.mark.parametrize("limit", [0.4, 0.7])
def test_ideal_epp_returns_itself(ultimate, limit):
    k, dy, du = 3.7e6, 1.3e-3, 11.9e-3  # N/m, m, m
    d, p = epp_curve(k, dy, du)
    r = eeep.eeep(d, p, fraction=limit, ultimate=ultimate)
    assert r["K_e"] == pytest.approx(k, rel=1e-9)
    assert r["P_y"] == pytest.approx(k * dy, rel=1e-9)
    assert r["Delta_y"] == pytest.approx(dy, rel=1e-9)
    assert r["Delta_u"] == pytest.approx(du, rel=1e-9)
    assert r["ductility"] == pytest.approx(du / dy, rel=1e-9)
    assert r["eeep_area"] == pytest.approx(r["area"], rel=1e-9)


def test_ideal_epp_secant_and_mirrored():
    k, dy, du = 2.0e7, 0.5e-3, 4e-3
    d, p = epp_curve(k, dy, du)
    r = eeep.eeep(-d, -p, stiffness="secant")
    assert r["mirrored"]
    assert r["K_e"] == pytest.approx(k, rel=1e-9)
    assert r["ductility"] == pytest.approx(du / dy, rel=1e-9)


def softening_curve(n=400, seed=0):
    """A smooth curve with hardening, a peak and softening, sampled irregularly, with a little noise."""
    rng = np.random.default_rng(seed)
    d = np.sort(rng.uniform(0, 20e-3, n))
    d[0] = 0.0
    p = 60e3 * (1 - np.exp(-d / 2.5e-3)) * np.exp(-((d / 14e-3) ** 2)) + 300.0 * rng.standard_normal(n)
    p[0] = 0.0
    return d, p


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("ultimate", ["peak", "drop"])
@pytest.mark.parametrize("limit", [0.4, 0.7])
def test_area_equivalence_any_curve(seed, ultimate, limit):
    d, p = softening_curve(seed=seed)
    r = eeep.eeep(d, p, fraction=limit, ultimate=ultimate)
    assert r["yield_note"].startswith("equal energy")
    # independent area: trapezoid of the curve up to Delta_u with the end point interpolated by np.interp
    # on the branch that contains Delta_u
    du = r["Delta_u"]
    keep = d < du
    if ultimate == "peak":
        keep = np.arange(len(d)) <= int(np.nonzero(p == p.max())[0][-1])
        xs, ys = d[keep], p[keep]
    else:
        xs = np.append(d[keep], du)
        ys = np.append(p[keep], r["P_u"])
    area = np.trapz(ys, xs)
    assert r["area"] == pytest.approx(area, rel=1e-12)
    assert r["eeep_area"] == pytest.approx(r["area"], rel=1e-9)
    bil = r["bilinear"]
    assert np.trapz(bil["y"], bil["x"]) == pytest.approx(r["area"], rel=1e-9)
    assert r["Delta_y"] < r["Delta_u"]
    if ultimate == "drop":
        assert r["P_u"] == pytest.approx(0.8 * r["P_peak"], rel=1e-12)
        assert r["Delta_u"] > r["Delta_peak"]


def test_drop_interpolates_crossing():
    # peak 10 at d=2, then falls linearly 10 -> 0 over d 2 -> 4: 80 % at d = 2.4
    d = np.array([0, 1, 2, 3, 4.0])
    p = np.array([0, 5, 10, 5, 0.0])
    r = eeep.eeep(d, p, ultimate="drop")
    assert r["Delta_u"] == pytest.approx(2.4, rel=1e-14)
    assert r["area"] == pytest.approx(10.0 + 0.4 * (10 + 8) / 2, rel=1e-14)
    # regression up to 70 %: points (0,0), (1,5), (1.4,7) on the line k = 5
    assert r["K_e"] == pytest.approx(5.0, rel=1e-14)


def test_regression_limit_matters():
    # a curve stiffer at first: K from the first 40 % is higher than from the first 70 %
    d = np.linspace(0, 10, 201)
    p = 10 * np.tanh(d / 2)
    r4 = eeep.eeep(d, p, fraction=0.4)
    r7 = eeep.eeep(d, p, fraction=0.7)
    assert r4["K_e"] > r7["K_e"]
    assert r4["regression_points"] < r7["regression_points"]


@pytest.mark.parametrize("d,p", [
    ([0, 1, 2], [0, 0, 0]),        # never loaded
    ([0, -1, -2], [0, 0, 0]),
    ([0, 1, 2], [5, 3, 1]),        # peak at the origin, nothing ascends
])
def test_no_peak_is_an_error(d, p):
    with pytest.raises(ToolError, match="no peak"):
        eeep.eeep(np.array(d, float), np.array(p, float))


@pytest.mark.parametrize("sx,sy", [(-1, -1), (1, -1), (-1, 1)])
def test_negative_loading_is_mirrored(sx, sy):
    # a reaction monitor has the opposite sign of the load: each axis is turned on its own
    d, p = epp_curve(2.0, 1.0, 5.0)
    r = eeep.eeep(sx * d, sy * p)
    assert (r["sign_x"], r["sign_y"]) == (sx, sy)
    assert r["ductility"] == pytest.approx(5.0, rel=1e-12)


def test_cli_csv_units_and_files(tmp_path, cli):
    k, dy, du = 4.0, 1.5, 12.0  # kN/mm, mm, mm
    d, p = epp_curve(k, dy, du)
    f = tmp_path / "exp.csv"
    f.write_text("disp_mm,load_kN,other\n" + "".join(f"{a!r},{b!r},1\n" for a, b in zip(d, p)))
    rc, out, err = cli("eeep", f, "--x", "disp_mm", "--y", "load_kN", "--x-unit", "mm", "--y-unit", "kN",
                       "--ultimate", "drop")
    assert rc == 0, err
    res = json.loads((tmp_path / "exp_eeep.json").read_text())
    assert res["K_e"] == pytest.approx(k, rel=1e-9)  # kN/mm
    assert res["P_y"] == pytest.approx(k * dy, rel=1e-9)  # kN
    assert res["Delta_y"] == pytest.approx(dy, rel=1e-9)  # mm
    assert res["ductility"] == pytest.approx(du / dy, rel=1e-9)
    assert res["si"]["K_e"] == pytest.approx(k * 1e6, rel=1e-9)  # N/m
    for ext in ("png", "svg"):
        assert (tmp_path / f"exp_eeep.{ext}").stat().st_size > 1000


@pytest.mark.parametrize("content,args,needle", [
    ("a,b\n0,0\n1,1\n2,2\n", ["--x", "u", "--y", "b"], "no column 'u'"),
    ("a,b\n0,0\n1,0\n2,0\n", [], "no peak"),
    ("a,b\n0,0\n1,x\n", [], "not numeric"),
    ("", [], "empty file"),
    ("a,b\n0,0\n1\n", [], "has 1 fields"),
])
def test_cli_bad_input_one_line(tmp_path, cli, content, args, needle):
    f = tmp_path / "c.csv"
    f.write_text(content)
    rc, out, err = cli("eeep", f, *args)
    assert rc == 1
    assert needle in err
    assert len(err.strip().splitlines()) == 1
    assert "Traceback" not in err


def test_cli_missing_file_and_unfinished_run(tmp_path, cli_subprocess):
    cli = cli_subprocess  # through the executable entry: one line on stderr, no traceback
    rc, out, err = cli("eeep", tmp_path / "nope.csv")
    assert rc == 1 and "no such file" in err and len(err.strip().splitlines()) == 1
    run = tmp_path / "run"
    run.mkdir()
    (run / "summary.json").write_text(json.dumps({"status": "running", "curve": {"x": "u", "y": "F"}}))
    (run / "history.csv").write_text("time,step,stage,u,F\n0,0,1,0,0\n")
    rc, out, err = cli("eeep", run)
    assert rc == 1 and "not 'completed'" in err and len(err.strip().splitlines()) == 1


def test_cli_stage_and_zero_start(tmp_path, cli):
    """A run whose first stage (precompression) moves the control point: --stage 2 --zero-start analyses the
    shear stage from its own start."""
    import os
    k, dy, du = 2.0e6, 1e-3, 6e-3  # N/m, m, m
    d, p = epp_curve(k, dy, du)
    run = tmp_path / "run"
    os.makedirs(run)
    rows = [(0.0, 1, 0.0, 0.0), (0.1, 1, 0.3e-3, 0.0)] + [(0.2 + i, 2, 0.3e-3 + a, b) for i, (a, b) in enumerate(zip(d, p))]
    (run / "history.csv").write_text("time,step,stage,u,F\n" + "".join(f"{t},{i},{s},{a!r},{b!r}\n"
                                                                      for i, (t, s, a, b) in enumerate(rows)))
    (run / "summary.json").write_text(json.dumps({"status": "completed", "curve": {"x": "u", "y": "F"},
                                                  "columns": {"u": "m", "F": "N"}}))
    rc, out, err = cli("eeep", run, "--stage", "2", "--zero-start", "--ultimate", "drop")
    assert rc == 0, err
    r = json.loads((run / "post" / "eeep.json").read_text())
    assert r["si"]["K_e"] == pytest.approx(k, rel=1e-9)
    assert r["ductility"] == pytest.approx(du / dy, rel=1e-9)


def test_usage_errors_are_one_line(cli_subprocess):
    for args in (["eeep"], ["eeep", "x.csv", "--ultimate", "foo"], ["study", "mesh", "x.toml"], ["nonsense"]):
        rc, out, err = cli_subprocess(*args)
        assert rc == 1, args
        assert len(err.strip().splitlines()) == 1 and "error" in err, (args, err)


# ------------------------------------------------------------------------------------------------------------------
# Issue 51 (2): curves without a post-peak branch, and reversing (cyclic) records


@pytest.mark.parametrize("end,past", [(9.6, False), (9.4, True), (10.0, False)])
def test_post_peak_branch_or_lower_bound(end, past):
    """Peak 10 at d = 2, the load at the end 9.6 (4 % below: no post-peak branch), 9.4 (6 % below) or 10 (the
    largest load at the end): the ductility is a lower bound unless the load fell at least 5 % below the peak."""
    d = np.array([0.0, 1.0, 2.0, 3.0])
    p = np.array([0.0, 5.0, 10.0, end])
    r = eeep.eeep(d, p)
    assert r["past_peak"] is past and r["ductility_is_lower_bound"] is (not past)
    assert (r["post_peak_note"] == "no post-peak branch: ductility is a lower bound") is (not past)


def test_rising_curve_is_reported_as_lower_bound(tmp_path, cli):
    """A curve still rising at its end (no peak reached) gave a ductility with exit 0 and no word of it; now the
    terminal, the JSON and the figure say it is a lower bound."""
    d = np.linspace(0, 10, 101)
    p = 10 * np.tanh(d / 2)
    f = tmp_path / "rise.csv"
    f.write_text("d_mm,F_kN\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(d, p)))
    rc, out, err = cli("eeep", f)
    assert rc == 0, err
    assert "no post-peak branch: ductility is a lower bound" in out
    j = json.loads((tmp_path / "rise_eeep.json").read_text())
    assert j["past_peak"] is False and j["ductility_is_lower_bound"] is True
    assert "no post-peak branch: ductility is a lower bound" in (tmp_path / "rise_eeep.svg").read_text()
    # a softening curve is past its peak: no such note
    d2, p2 = softening_curve()
    g = tmp_path / "soft.csv"
    g.write_text("u_m,F_N\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(d2, p2)))
    rc, out, err = cli("eeep", g)
    assert rc == 0, err
    assert "lower bound" not in out and json.loads((tmp_path / "soft_eeep.json").read_text())["past_peak"] is True


def cyclic_epp(k, fy, fyn, amps, h):
    """A cyclic record whose envelope is elastic-perfectly-plastic in each direction: stiffness k, yield load fy
    (positive), fyn (negative, magnitude). Each cycle follows the positive envelope from the last positive extreme to
    the new amplitude, unloads at k to zero load, goes back to the last negative extreme and follows the negative
    envelope to the new amplitude, unloads at k. Displacements on a grid of step h."""
    env = lambda x, f: min(k * x, f)  # noqa: E731
    pts = [(0.0, 0.0)]
    last = 0.0
    for a in amps:
        for s, f in ((1.0, fy), (-1.0, fyn)):
            if last > 0:
                pts.append((s * last, s * env(last, f)))
            n0, n1 = int(round(last / h)), int(round(a / h))
            pts += [(s * i * h, s * env(i * h, f)) for i in range(n0 + 1, n1 + 1)]
            pts.append((s * (a - env(a, f) / k), 0.0))
        last = a
    d, p = np.array(pts).T
    return d, p


def test_cyclic_record_uses_the_envelope_of_each_direction(tmp_path, cli):
    """A cyclic record (k = 5 kN/mm, yield 10 kN positive and 8 kN negative, cycles to 1, 4, 8, 12 mm): EEEP of each
    direction's envelope gives back k, P_y = 10 and 8 kN, Delta_u = 12 mm, ductility 12 / 2 = 6 and 12 / 1.6 = 7.5
    (both lower bounds: the envelopes end on their plateau). Before, the record went into the monotonic fit: a
    ductility below 1 with Delta_y > Delta_u."""
    k, fy, fyn, amps = 5.0, 10.0, 8.0, (1.0, 4.0, 8.0, 12.0)  # kN/mm, kN, kN, mm
    d, p = cyclic_epp(k, fy, fyn, amps, 0.1)
    assert eeep.is_reversing(d)
    with pytest.raises(ToolError, match="reverses"):
        eeep.eeep(d, p)
    with pytest.raises(ToolError, match="reverses"):  # folded (|d|, as a stage curve is measured): refused too
        eeep.eeep(np.abs(d), p)
    xe, ye = eeep.envelope(d, p, -1.0)
    assert xe.max() == pytest.approx(12.0, rel=1e-12) and ye.max() == pytest.approx(fyn, rel=1e-12)
    f = tmp_path / "cyc.csv"
    f.write_text("d_mm,F_kN\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(d, p)))
    rc, out, err = cli("eeep", f)
    assert rc == 0, err
    j = json.loads((tmp_path / "cyc_eeep.json").read_text())
    assert j["cyclic"] is True and j["ductility"] is None
    for name, py in (("positive", fy), ("negative", fyn)):
        e = j["envelope"][name]
        assert e["K_e"] == pytest.approx(k, rel=1e-9)
        assert e["P_y"] == pytest.approx(py, rel=1e-9)
        assert e["Delta_u"] == pytest.approx(12.0, rel=1e-9)
        assert e["ductility"] == pytest.approx(12.0 / (py / k), rel=1e-9)
        assert e["Delta_y"] < e["Delta_u"] and e["ductility_is_lower_bound"] is True
    assert "positive envelope" in out and "negative envelope" in out and "lower bound" in out
    svg = (tmp_path / "cyc_eeep.svg").read_text()
    assert "positive envelope" in svg and "negative envelope" in svg
    # the ductility fit refuses one number for it
    rc, out, err = cli("ductility-fit", "--point", f"0.1={tmp_path / 'cyc_eeep.json'}", "--point", "0.2=x.json")
    assert rc == 1 and "per direction" in err


def test_monotonic_with_small_jitter_is_not_reversing():
    d, p = softening_curve()
    d = d + 1e-5 * np.sin(np.arange(len(d)))  # a 0.01 mm wobble on 20 mm
    assert not eeep.is_reversing(d)
    d2 = np.concatenate((d, d[-1] - np.linspace(0, 5e-3, 20)[1:]))  # unloaded by 5 mm (25 %) at the end
    assert eeep.is_reversing(d2)


def test_eeep_figure_labels_do_not_overlap():
    """Issue 51 (13): the legend sat on the curve and the Delta_u label; now it is below the axes and every text
    (title with its notes, axis labels, legend) has its own place."""
    d, p = softening_curve()
    r = eeep.eeep(d, p)
    fig, ax = eeep.figure(d, p, r, "a curve")
    fig.canvas.draw()
    rend = fig.canvas.get_renderer()
    leg = ax.get_legend().get_window_extent(rend)
    boxes = {"axes": ax.get_window_extent(rend), "title": ax.title.get_window_extent(rend),
             "xlabel": ax.xaxis.label.get_window_extent(rend)}
    for name, b in boxes.items():
        assert not leg.overlaps(b), name
    assert not boxes["title"].overlaps(boxes["axes"])
    import matplotlib.pyplot as plt
    plt.close(fig)


# Other bilinear idealisations (issue 51: EC8 / Tomazevic beside EEEP).
def test_ec8_returns_an_elastic_perfectly_plastic_curve_itself():
    k, dy, du = 3.7e6, 1.3e-3, 11.9e-3
    d, p = epp_curve(k, dy, du)
    r = eeep.eeep(d, p, **eeep.method_options("ec8", ultimate="peak"))
    assert r["P_y"] == pytest.approx(k * dy, rel=1e-12)
    assert r["Delta_y"] == pytest.approx(dy, rel=1e-9)
    assert r["K_e"] == pytest.approx(k, rel=1e-9)
    assert r["ductility"] == pytest.approx(du / dy, rel=1e-9)


def test_ec8_closed_form_on_a_trilinear_curve():
    # 0 -> (1, 10) -> (3, 14) -> (5, 11.2): peak 14 at 3, drop to 0.8 x 14 = 11.2 at 5 exactly.
    d = np.array([0.0, 1.0, 3.0, 5.0])
    p = np.array([0.0, 10.0, 14.0, 11.2])
    r = eeep.eeep(d, p, **eeep.method_options("ec8"))
    area = 0.5 * 10 * 1 + 0.5 * (10 + 14) * 2 + 0.5 * (14 + 11.2) * 2  # 54.2
    assert r["Delta_u"] == pytest.approx(5.0)
    assert r["area"] == pytest.approx(area)
    assert r["P_y"] == pytest.approx(14.0)
    assert r["Delta_y"] == pytest.approx(2 * (5.0 - area / 14.0))
    assert r["ductility"] == pytest.approx(5.0 / (2 * (5.0 - area / 14.0)))
    assert r["eeep_area"] == pytest.approx(area)  # the bilinear holds the curve's area
    assert r["K_e_branch"] == pytest.approx(10.0)  # the branch's own regression, for reference


def test_tomazevic_and_astm_presets_are_their_rules():
    d = np.array([0.0, 1.0, 3.0, 5.0, 6.0])
    p = np.array([0.0, 10.0, 14.0, 11.2, 8.0])
    t = eeep.eeep(d, p, **eeep.method_options("tomazevic"))
    assert t["K_e"] == pytest.approx(0.7 * 14.0 / 0.98)  # the secant at 9.8 = 0.7 x 14, on the first branch at 0.98
    assert t["Delta_u"] == pytest.approx(5.0)
    e = eeep.eeep(d, p, fraction=0.7, stiffness="secant", ultimate="drop", drop=0.8)
    assert t["P_y"] == e["P_y"] and t["ductility"] == e["ductility"]
    a = eeep.eeep(d, p, **eeep.method_options("astm"))
    assert a["K_e"] == pytest.approx(10.0)  # secant at 0.4 x 14 on the first branch
    assert a["eeep_area"] == pytest.approx(a["area"])


def test_a_preset_refuses_a_contradicting_rule():
    with pytest.raises(ToolError, match="--method astm fixes --limit 0.4"):
        eeep.method_options("astm", fraction=0.7)
    with pytest.raises(ToolError, match="must be one of"):
        eeep.method_options("fema")


def test_cli_method_ec8_names_its_source(tmp_path, cli):
    d = np.array([0.0, 1.0, 3.0, 5.0, 6.0])
    p = np.array([0.0, 10.0, 14.0, 11.2, 8.0])
    f = tmp_path / "c.csv"
    f.write_text("d_mm,F_kN\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(d, p)))
    rc, out, err = cli("eeep", f, "--x", "d_mm", "--y", "F_kN", "--x-unit", "mm", "--y-unit", "kN", "--method", "ec8")
    assert rc == 0, err
    assert "EN 1998-1 Annex B" in out
    res = json.loads((tmp_path / "c_eeep.json").read_text())
    assert res["method"] == "ec8"
    assert res["P_y"] == pytest.approx(14.0)
    assert res["Delta_u"] == pytest.approx(5.0)
    rc, out, err = cli("eeep", f, "--x", "d_mm", "--y", "F_kN", "--method", "astm", "--limit", "0.7")
    assert rc != 0 and "fixes --limit 0.4" in (out + err)


def test_cli_drift_height_gives_drift_ratios_and_an_axis(tmp_path, cli):
    k, dy, du = 4.0, 1.5, 12.0  # kN/mm, mm, mm
    d, p = epp_curve(k, dy, du)
    f = tmp_path / "w.csv"
    f.write_text("d_mm,F_kN\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(d, p)))
    rc, out, err = cli("eeep", f, "--x", "d_mm", "--y", "F_kN", "--x-unit", "mm", "--y-unit", "kN",
                       "--drift-height", "1.2")
    assert rc == 0, err
    res = json.loads((tmp_path / "w_eeep.json").read_text())
    assert res["drift_y_pct"] == pytest.approx(100 * 1.5e-3 / 1.2, rel=1e-9)
    assert res["drift_u_pct"] == pytest.approx(1.0, rel=1e-9)  # 12 mm over 1.2 m
    assert "drift ratios" in out
    svg = (tmp_path / "w_eeep.svg").read_text()
    assert "drift ratio (%)" in svg
    rc, out, err = cli("eeep", f, "--drift-height", "0")
    assert rc != 0 and "--drift-height must be" in (out + err)


def test_drift_axis_maps_displacement_to_percent():
    from fdemtools.figures import add_drift_axis, new_figure
    fig, ax = new_figure()
    ax.plot([0, 10], [0, 1])
    sec = add_drift_axis(ax, 1e-3, 2.5)  # mm over 2.5 m: 10 mm = 0.4 %
    fwd, inv = sec._functions
    assert fwd(10.0) == pytest.approx(0.4)
    assert inv(0.4) == pytest.approx(10.0)
