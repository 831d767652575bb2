"""`validate`: family runs, report contents and the quasi-static check, with the stand-in fdem (no physics)."""
import csv
import os

import numpy as np
import pytest

from fdemtools import common, validate

FAKE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fake_fdem.py")
REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

CASE = """[case]
name = "{name}"
thickness = 0.1
rate = 0.2
[geometry]
type = "rectangle"
width = 1.0
height = 1.0
mesh_size = {h}
[[stages]]
name = "pre"
duration = 1.0
local_damping = 0.8
[[stages]]
name = "shear"
duration = 1.0
local_damping = 0.8
  [[stages.supports]]
  group = "top"
  vx = 0.01
"""


def family(tmp_path, sizes=(0.1, 0.05)):
    fam = tmp_path / "fam"
    fam.mkdir()
    for i, h in enumerate(sizes):
        (fam / f"c{i}.toml").write_text(CASE.format(name=f"c{i}", h=h))
    # c0: experiment 11 kN, published 12 kN; c1: none (no row)
    (fam / "reference.csv").write_text("cases,experiment_kN,fdem_k25_kN\nc0 other,11,12\n")
    return fam


def read_csv(p):
    with open(p, newline="") as f:
        return list(csv.DictReader(f))


def test_family_report_and_half_rate_check(tmp_path, cli):
    fam = family(tmp_path)
    out = tmp_path / "out"
    log = tmp_path / "calls.log"
    rc, o, err = cli("validate", fam, "--fdem", FAKE, "--out-dir", out, "--set", "rate=0.2", "--rate-key", "rate",
                     "--jobs", "2", env={"FAKE_FDEM_LOG": str(log)})
    assert rc == 0, err
    rows = {r["case"]: r for r in read_csv(out / "report.csv")}
    assert set(rows) == {"c0", "c1"}
    # fake peak = 10 kN (1 + h)(1 + rate) with rate = 0.2 and h = 0.1 (it reads h from --set only, not the case)
    for name, h in (("c0", 0.1), ("c1", 0.05)):
        r = rows[name]
        assert r["status"] == "completed"
        assert float(r["peak_load_kN"]) == pytest.approx(13.2, rel=1e-12)
        # fake curve: the load reaches its peak at half of the final 1 mm
        assert float(r["disp_at_peak_mm"]) == pytest.approx(0.5, rel=1e-9)
        # linear ascending branch: stiffness = peak / 0.5 mm
        assert float(r["initial_stiffness_kN_mm"]) == pytest.approx(13.2 / 0.5, rel=1e-9)
        assert float(r["mesh_size_m"]) == h
        assert float(r["loading_rate_m_s"]) == 0.01
        assert r["local_damping"] == "0.8 / 0.8"
        assert r["contact_damping"] == "0 / 0"
        assert float(r["energy_balance_error"]) == pytest.approx(0.0011, rel=1e-12)  # summary.json (fake: h = 0.1)
        assert float(r["wall_time_s"]) == pytest.approx(1.0)
        assert float(r["mesh_size_m"]) == h  # what the report states comes from the case file
    assert float(rows["c0"]["error_vs_experiment"]) == pytest.approx(13.2 / 11 - 1, rel=1e-9)
    assert float(rows["c0"]["error_vs_published_fdem"]) == pytest.approx(13.2 / 12 - 1, rel=1e-9)
    assert rows["c1"]["error_vs_experiment"] == ""  # no reference row, no [reference]
    md = (out / "report.md").read_text()
    # what made the runs, as the figures' stamp (the fake's summaries carry no build or hash: said so)
    assert "\nSource: fdem ? build unknown | fake [no hash]\n" in md
    # half the rate (default: the first case only): 10 (1.1)(1.1) against 10 (1.1)(1.2): -8.3 %, not quasi-static
    assert "| c0 | `rate` | 0.2 | 0.1 | 13.2 | 12.1 | -8.3 % | NOT quasi-static | completed | - |" in md
    assert "0 of 1 checked cases quasi-static; largest change -8.3 %." in md
    assert float(rows["c0"]["peak_half_rate_kN"]) == pytest.approx(12.1, rel=1e-12)
    assert float(rows["c0"]["rate_change"]) == pytest.approx(12.1 / 13.2 - 1, rel=1e-12)
    assert rows["c1"]["peak_half_rate_kN"] == "" and rows["c1"]["rate_change"] == ""  # not checked
    qs = read_csv(out / "quasi_static.csv")
    assert [q["case"] for q in qs] == ["c0"] and qs[0]["quasi_static"] == "no" and qs[0]["status_half"] == "completed"
    # the fake curve is flat after its peak: not past the peak
    assert rows["c0"]["past_peak"] == "no (still rising / flat)" and float(rows["c0"]["drop_after_peak"]) == 0.0
    assert "Trend with" not in md  # reference.csv has no N_kN column
    assert "Mean absolute error against the experiments: 20.0 % over 1 case(s)" in md
    assert "NOT the same for every case" in md  # the mesh sizes differ
    calls = log.read_text().splitlines()
    assert len(calls) == 3 and sum('"rate": "0.1"' in c for c in calls) == 1

    # resumable: nothing runs again
    rc, o, err = cli("validate", fam, "--fdem", FAKE, "--out-dir", out, "--set", "rate=0.2", "--rate-key", "rate",
                     env={"FAKE_FDEM_LOG": str(log)})
    assert rc == 0, err
    assert len(log.read_text().splitlines()) == 3


def test_failed_run_exits_2_and_is_reported(tmp_path, cli):
    fam = family(tmp_path, sizes=(0.1,))
    out = tmp_path / "out"
    rc, o, err = cli("validate", fam, "--fdem", FAKE, "--out-dir", out, "--set", "fail=true", "--no-rate-check")
    assert rc == 2
    assert "did not complete" in err
    rows = read_csv(out / "report.csv")
    assert rows[0]["status"] == "failed"
    assert "Not run (--no-rate-check)" in (out / "report.md").read_text()


def test_bad_input_is_one_line(tmp_path, cli):
    rc, o, err = cli("validate", tmp_path / "nowhere", "--fdem", FAKE)
    assert rc == 1 and "no such family folder" in err and len(err.strip().splitlines()) == 1
    fam = family(tmp_path)
    rc, o, err = cli("validate", fam, "--fdem", FAKE, "--rate-case", "zz")
    assert rc == 1 and "no such case" in err


def test_rate_and_settings_of_the_wall_cases():
    case = os.path.join(REPO, "cases", "lourenco2005", "k25_N100.toml")
    if not os.path.isfile(case):
        pytest.skip("wall cases not present")
    rc = common.resolved_case(case, [("stages.2.supports.1.vx", "0.05")])  # the engine's reading (fdem check --json)
    key, rate = validate.rate_key(rc)
    assert key == "stages.2.supports.1.vx" and rate == 0.05
    s = validate.numerical_settings(rc)
    assert s["mesh_size_m"] == 0.025
    # the damping each stage runs with (a stage without contact_damping has 0), the case's time-step setting
    assert s["local_damping"] == "0.8 / 0.05" and s["contact_damping"] == "0 / 0.3" and s["dt_setting"] == "safety=0.7"
    assert "stone p_j=auto (ref 1e+10 Pa)" in s["penalties"] and "units/units normal_penalty=1e+09 Pa" in s["penalties"]
    assert "stone crack faces p_n=1e+09 Pa (extrinsic insertion)" in s["penalties"]


def test_smoothing_window_removes_an_oscillation_of_its_own_wavelength():
    # y = a x + A sin(2 pi x / lam) sampled uniformly: the mean over a window of one wavelength is a x exactly
    # (interior rows, where the window is whole: the sine's samples over one period sum to zero)
    lam, a, amp = 0.5, 2.0, 0.3
    x = np.arange(0, 4001) * (lam / 100)  # 100 rows per wavelength, 0 to 20 lam
    y = a * x + amp * np.sin(2 * np.pi * x / lam)
    s = validate.smooth_curve(x, y, lam)
    inner = (x > lam) & (x < x[-1] - lam)
    # bound: the window holds the 100 rows of one period plus at most one extra row at each end
    assert np.max(np.abs(s[inner] - a * x[inner])) < 2 * amp / 100
    # a window of zero leaves the curve alone; a stalled actuator (x going back a little) does not break it
    assert np.array_equal(validate.smooth_curve(x, y, 0.0), y)
    xj = x.copy()
    xj[1000] -= lam / 50
    assert np.all(np.isfinite(validate.smooth_curve(xj, y, lam)))


def test_smoothed_report_keeps_the_raw_peak(tmp_path, cli):
    fam = family(tmp_path, sizes=(0.1,))
    out = tmp_path / "out"
    rc, o, err = cli("validate", fam, "--fdem", FAKE, "--out-dir", out, "--set", "rate=0.2", "--no-rate-check",
                     "--smooth", "0.15")
    assert rc == 0, err
    r = read_csv(out / "report.csv")[0]
    # fake curve: 21 rows 0.05 mm apart, linear to 13.2 kN at 0.5 mm, then flat to 1 mm. A window of 0.15 mm holds
    # a row and its two neighbours: the flat part stays at 13.2 kN, so the smoothed peak is the raw one. Where the
    # window is whole, the mean of a line is the line; the one deviation left is at the corner (0.5 mm):
    # 13.2 - (11.88 + 13.2 + 13.2) / 3 = 0.44 kN (the one-sided first row, 0.66 kN off, is not counted)
    assert float(r["peak_raw_kN"]) == pytest.approx(13.2, rel=1e-12)
    assert float(r["peak_load_kN"]) == pytest.approx(13.2, rel=1e-9)
    assert float(r["oscillation_kN"]) == pytest.approx(0.44, rel=1e-9)
    assert float(r["smoothing_mm"]) == 0.15
    assert "averaged over 0.15 mm of control displacement" in (out / "report.md").read_text()
    rc, o, err = cli("validate", fam, "--fdem", FAKE, "--out-dir", out, "--smooth", "-1")
    assert rc == 1 and "--smooth must be a window >= 0 mm" in err


def test_damping_work_shares_of_the_loading_stage(tmp_path):
    # synthetic run: D_damp = 0.1 w and D_visc = 0 with w the trapezoidal work of F_top along u_top over all rows, so
    # over the loading stage's rows D_damp grows by 0.1 x the stage's loading work (the same trapezoids)
    from synth import make_run
    run = tmp_path / "run"
    make_run(str(run), n=61)
    m = validate.curve_metrics(str(run))
    assert m["local_damping_work_share"] == pytest.approx(0.1, rel=1e-12)
    assert m["viscous_work_share"] == 0.0
    # a history without the energy columns gives no share, not zero
    lines = (run / "history.csv").read_text().splitlines()
    head = lines[0].split(",")
    keep = [i for i, k in enumerate(head) if k not in ("D_damp", "D_visc")]
    (run / "history.csv").write_text("\n".join(",".join(l.split(",")[i] for i in keep) for l in lines) + "\n")
    m = validate.curve_metrics(str(run))
    assert m["local_damping_work_share"] is None and m["viscous_work_share"] is None


def test_unit_crack_counts_at_the_peak_and_end_of_the_loading_stage(tmp_path):
    """The synthetic run (synth.make_run): unit cracks ramp = floor(clip((u - 2 mm) / 8 mm, 0, 1) x 12), broken_unit_I
    + _II + _mixed = ramp // 3 + ramp // 4 + ramp // 6; counted from the loading stage's first row (u = 1/59 x 10 mm
    < 2 mm: 0) to the peak row and to the last row (ramp 12: 4 + 3 + 2 = 9)."""
    import json
    from synth import make_run
    run = make_run(str(tmp_path / "run"))
    with open(os.path.join(run, "summary.json")) as f:
        s = json.load(f)
    s["stages"] = [{"name": "pre", "ended_by": "duration"}, {"name": "shear", "ended_by": "past_peak"}]
    with open(os.path.join(run, "summary.json"), "w") as f:
        json.dump(s, f)
    m = validate.curve_metrics(run)
    u_peak = m["disp_at_peak_m"] + 10e-3 / 59 * 6  # the stage starts at t = 6/59 (u from the stage's start)
    ramp = np.floor(np.clip((u_peak - 2e-3) / 8e-3, 0, 1) * 12)
    assert m["unit_cracks_at_peak"] == ramp // 3 + ramp // 4 + ramp // 6
    assert m["unit_cracks_at_end"] == 9
    assert m["ended_by"] == "past_peak"


def test_plateau_rising_and_falling_curves_are_told_apart():
    """past_peak: 'yes' 5 % below the peak at the end; a plateau whose maximum lies at 0.4 of the travel and that ends
    2 % below it: 'plateau'; the same maximum at 0.9 of the travel: not past; a curve rising to its end: not past."""
    x = np.linspace(0, 1, 101)
    plateau = 1 - np.exp(-x / 0.05) - 0.02 * np.clip(x - 0.4, 0, None) / 0.6
    late = 1 - np.exp(-x / 0.05) - 0.02 * np.clip(x - 0.9, 0, None) / 0.1
    falling = 1 - np.exp(-x / 0.05) - 0.10 * np.clip(x - 0.4, 0, None) / 0.6
    rising = x
    for y, expect in ((plateau, "plateau"), (late, False), (falling, True), (rising, False)):
        i, past = validate.peak_index(y)
        assert validate.plateau_or(past, x, y, i) == expect
    assert validate.past_peak("plateau").startswith("plateau")


def test_validate_reruns_a_case_whose_file_changed(tmp_path, cli):
    """Issue 51 (1), through validate (which runs its cases with batch's machinery): an edited case is run again,
    with its half-rate rerun, and the log says the case file changed; the unchanged case is reused."""
    fam = family(tmp_path)
    out = tmp_path / "out"
    log = tmp_path / "calls.log"
    args = ("validate", fam, "--fdem", FAKE, "--out-dir", out, "--set", "rate=0.2", "--rate-key", "rate",
            "--rate-case", "c0")
    rc, o, err = cli(*args, env={"FAKE_FDEM_LOG": str(log)})
    assert rc == 0 and len(log.read_text().splitlines()) == 3, err
    c0 = fam / "c0.toml"
    c0.write_text(c0.read_text().replace("local_damping = 0.8", "local_damping = 0.5"))
    rc, o, err = cli(*args, env={"FAKE_FDEM_LOG": str(log)})
    assert rc == 0, err
    assert len(log.read_text().splitlines()) == 5  # c0 and its half-rate rerun, not c1
    assert o.count("stale: case file") == 2 and "c1: already completed, skipped" in o
