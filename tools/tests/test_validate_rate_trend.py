"""`validate`: half-rate check of several cases, "is the peak a peak" and the trend with the axial load, with a
stand-in fdem whose curve shape comes from a [fake] table in the case file (no physics).

Fake curve (control displacement u, load F, 41 history rows from u = 0 to u_end):
  F = P u / u_peak up to u_peak, then F = P (1 - softening (u - u_peak) / 1 mm), and past u_rise (when given)
  F = F(u_rise) + P rise (u - u_rise) / 1 mm (a second branch), with
  P = peak_kN (1 + rate_sens vx) and vx the prescribed velocity (from --set stages.1.supports.1.vx, else the case);
  u_end = vx duration when [fake] gives a duration (the stage ends by time), else u_end.
"""
import csv
import json
import os
import stat

import numpy as np
import pytest

from fdemtools import validate

FAKE_SRC = r'''#!/usr/bin/python3
import json, os, sys, tomllib

def main(argv):
    if argv[0] == "check":  # the resolved case (fdem check --json): the stand-in of tests/fake_fdem.py
        sys.path.insert(0, "@TESTS@")
        import fake_fdem
        return fake_fdem.check(argv[1:])
    if argv[0] != "run":  # validate's rigid-block bound asks `fdem mesh`: this stand-in has no mesh (not a run)
        print("fake fdem: only 'run'", file=sys.stderr)
        return 1
    case, out, sets, i = argv[1], None, {}, 2
    while i < len(argv):
        if argv[i] == "--out":
            out = argv[i + 1]; i += 2
        elif argv[i] == "--set":
            k, v = argv[i + 1].split("=", 1); sets[k] = v; i += 2
        elif argv[i] == "--threads":
            i += 2
        else:
            i += 1
    with open(os.environ["FAKE_FDEM_LOG"], "a") as f:
        f.write(json.dumps({"case": os.path.basename(case), "sets": sets}, sort_keys=True) + "\n")
    with open(case, "rb") as f:
        tree = tomllib.load(f)
    fk = tree.get("fake", {})
    vx = float(sets.get("stages.1.supports.1.vx", tree["stages"][0]["supports"][0]["vx"]))
    P = fk.get("peak_kN", 10.0) * 1e3 * (1 + fk.get("rate_sens", 0.0) * vx)
    u_end = vx * fk["duration"] if "duration" in fk else fk.get("u_end", 1e-3)
    u_peak, soft = fk.get("u_peak", 0.5e-3), fk.get("softening", 0.0)
    u_rise = fk.get("u_rise", float("inf"))
    os.makedirs(out, exist_ok=True)
    rows, n = [], 41
    for k in range(n):
        u = u_end * k / (n - 1)
        F = P * u / u_peak if u <= u_peak else P * (1 - soft * (min(u, u_rise) - u_peak) / 1e-3)
        if u > u_rise:
            F += P * fk.get("rise", 0.0) * (u - u_rise) / 1e-3
        rows.append((u, F))
    with open(os.path.join(out, "history.csv"), "w") as f:
        f.write("time,step,stage,u,F\n")
        for k, (u, F) in enumerate(rows):
            f.write(f"{0.01 * k},{k},1,{u!r},{F!r}\n")
    Fs = [F for _, F in rows]
    summ = {"case": tree["case"]["name"], "status": "completed", "message": "",
            "curve": {"x": "u", "y": "F"}, "columns": {"u": "m", "F": "N"},
            "n_triangles": 100, "n_nodes": 60, "dt": 1e-6, "steps": 40, "wall_time_s": 0.5, "threads": 1,
            "monitors": {"u": {"min": 0, "max": u_end, "final": u_end},
                         "F": {"min": min(Fs), "max": max(Fs), "final": Fs[-1]}}}
    with open(os.path.join(out, "summary.json"), "w") as f:
        json.dump(summ, f)
    return 0

sys.exit(main(sys.argv[1:]))
'''

CASE = """[case]
name = "{name}"
[[stages]]
name = "shear"
  [[stages.supports]]
  group = "top"
  vx = 0.01
[fake]
{fake}
"""

KEY = "stages.1.supports.1.vx"  # the rate key validate detects in CASE


@pytest.fixture
def fake(tmp_path):
    p = tmp_path / "fake_fdem_curves.py"
    p.write_text(FAKE_SRC.replace("@TESTS@", os.path.dirname(os.path.abspath(__file__))))
    p.chmod(p.stat().st_mode | stat.S_IXUSR)
    return str(p)


def make_family(tmp_path, cases: dict, reference: str | None = None):
    """cases: stem -> text of its [fake] table."""
    fam = tmp_path / "fam"
    fam.mkdir()
    for stem, fk in cases.items():
        (fam / f"{stem}.toml").write_text(CASE.format(name=stem, fake=fk))
    if reference is not None:
        (fam / "reference.csv").write_text(reference)
    return fam


def calls(log):
    if not os.path.exists(log):
        return []
    with open(log) as f:
        return [json.loads(line) for line in f]


def read_csv(p):
    with open(p, newline="") as f:
        return list(csv.DictReader(f))


def qs_table_rows(md: str) -> list:
    part = md.split("## Quasi-static check", 1)[1]
    return [ln for ln in part.splitlines() if ln.startswith("| ") and not ln.startswith("| case")]


def test_rate_case_all_one_rerun_per_case_and_resume(tmp_path, cli, fake):
    # c0 rate-independent, c1 and c2 peak +10 % per 0.01 m/s: halving the rate changes them by -4.5 %
    fam = make_family(tmp_path, {"c0": "peak_kN = 10.0", "c1": "peak_kN = 20.0\nrate_sens = 10.0",
                                 "c2": "peak_kN = 30.0\nrate_sens = 10.0"})
    out, log = tmp_path / "out", str(tmp_path / "calls.log")
    env = {"FAKE_FDEM_LOG": log}

    # first the default: only the first case is checked (3 cases + 1 rerun)
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--jobs", "2", env=env)
    assert rc == 0, err
    assert len(calls(log)) == 4
    assert len(qs_table_rows((out / "report.md").read_text())) == 1

    # then all cases: the completed runs (incl. c0's half-rate run) are reused, only c1, c2 at half rate run
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--rate-case", "all", "--jobs", "2", env=env)
    assert rc == 0, err
    c = calls(log)
    assert len(c) == 6
    assert sorted(x["case"] for x in c[4:]) == ["c1.toml", "c2.toml"]
    assert all(x["sets"] == {KEY: "0.005"} for x in c[4:])
    for stem in ("c0", "c1", "c2"):  # one batch folder per case: the full-rate run and the half-rate one
        assert sorted(os.listdir(out / stem / "runs")) == sorted(["run", validate.run_name({KEY: repr(0.005)})])

    md = (out / "report.md").read_text()
    rows = qs_table_rows(md)
    assert len(rows) == 3 and [r.split("|")[1].strip() for r in rows] == ["c0", "c1", "c2"]
    assert "| c0 | `stages.1.supports.1.vx` | 0.01 | 0.005 | 10 | 10 | +0.0 % | quasi-static | completed | - |" in md
    assert "| c1 | `stages.1.supports.1.vx` | 0.01 | 0.005 | 22 | 21 | -4.5 % | NOT quasi-static | completed |" in md
    assert "1 of 3 checked cases quasi-static; largest change -4.5 %." in md
    rep = {r["case"]: r for r in read_csv(out / "report.csv")}
    assert float(rep["c2"]["peak_half_rate_kN"]) == pytest.approx(31.5, rel=1e-12)
    assert float(rep["c2"]["rate_change"]) == pytest.approx(31.5 / 33 - 1, rel=1e-12)
    qs = read_csv(out / "quasi_static.csv")
    assert [q["case"] for q in qs] == ["c0", "c1", "c2"]
    assert [q["quasi_static"] for q in qs] == ["yes", "no", "no"]
    assert all(q["status_half"] == "completed" and q["note"] == "" for q in qs)

    # a third time: nothing runs again
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--rate-case", "all", env=env)
    assert rc == 0, err
    assert len(calls(log)) == 6


def test_repeated_rate_case_and_rate_key_for_each(tmp_path, cli, fake):
    fam = make_family(tmp_path, {"a": "", "b": "", "c": ""})
    out, log = tmp_path / "out", str(tmp_path / "calls.log")
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--rate-case", "c", "--rate-case", "a",
                     "--rate-case", "c", "--rate-key", KEY, env={"FAKE_FDEM_LOG": log})
    assert rc == 0, err
    half = [x for x in calls(log) if x["sets"]]
    assert sorted(x["case"] for x in half) == ["a.toml", "c.toml"] and all(x["sets"] == {KEY: "0.005"} for x in half)
    assert [q["case"] for q in read_csv(out / "quasi_static.csv")] == ["a", "c"]  # family order, once each
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--rate-case", "all", "--rate-key", "nope.x")
    assert rc == 1 and "--rate-key nope.x: no such number" in err


def test_past_peak_yes_on_a_10_percent_drop_no_while_rising(tmp_path, cli, fake):
    # drop: peak 10 kN at 0.5 mm, then -20 %/mm: 9 kN at the end (1 mm); rise: peak reached at the last row
    fam = make_family(tmp_path, {"drop": "u_peak = 0.5e-3\nsoftening = 0.2", "rise": "u_peak = 1e-3",
                                 "edge": "u_peak = 0.5e-3\nsoftening = 0.08"})
    out = tmp_path / "out"
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--no-rate-check",
                     env={"FAKE_FDEM_LOG": str(tmp_path / "calls.log")})
    assert rc == 0, err
    rep = {r["case"]: r for r in read_csv(out / "report.csv")}
    assert float(rep["drop"]["peak_load_kN"]) == pytest.approx(10, rel=1e-12)
    assert float(rep["drop"]["load_at_end_kN"]) == pytest.approx(9, rel=1e-12)
    assert float(rep["drop"]["drop_after_peak"]) == pytest.approx(0.1, rel=1e-9)
    assert rep["drop"]["past_peak"] == "yes"
    assert float(rep["rise"]["drop_after_peak"]) == pytest.approx(0, abs=1e-12)
    assert float(rep["rise"]["disp_at_peak_mm"]) == pytest.approx(1.0, rel=1e-12)
    assert rep["rise"]["past_peak"] == "no (still rising / flat)"
    # 4 % below the peak at the end: under PAST_PEAK_DROP = 5 %, but the peak lies at half the travel (before
    # PLATEAU_REACH = 3/4) and the curve falls after it: an inner maximum, a plateau, not a curve still rising
    assert float(rep["edge"]["drop_after_peak"]) == pytest.approx(0.04, rel=1e-9)
    assert rep["edge"]["past_peak"].startswith("plateau")
    md = (out / "report.md").read_text()
    assert "| drop | completed | 10 | 0.5 |" in md and "| 9 | 10.0 % | yes |" in md
    assert "| 10 | 0.0 % | no (still rising / flat) |" in md
    assert "at least 5 % below the peak (PAST_PEAK_DROP)" in md
    assert "Not past the peak: rise." in md
    assert "quasi_static" not in md and read_csv(out / "quasi_static.csv") == []


def test_half_rate_run_ending_earlier_is_compared_over_the_common_range(tmp_path, cli, fake):
    # the stage ends by time: the half-rate run reaches 0.5 mm instead of 1 mm; the load still rises (peak at
    # 0.8 mm) and does not depend on the rate, so over the common range the two peaks are equal (whole histories:
    # -37.5 %)
    fam = make_family(tmp_path, {"t": "duration = 0.1\nu_peak = 0.8e-3"})
    out = tmp_path / "out"
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out,
                     env={"FAKE_FDEM_LOG": str(tmp_path / "calls.log")})
    assert rc == 0, err
    rep = read_csv(out / "report.csv")[0]
    assert float(rep["peak_load_kN"]) == pytest.approx(10, rel=1e-12)  # the case's own peak: whole history
    q = read_csv(out / "quasi_static.csv")[0]
    assert float(q["peak_full_rate_kN"]) == pytest.approx(6.25, rel=1e-9)
    assert float(q["peak_half_rate_kN"]) == pytest.approx(6.25, rel=1e-9)
    assert float(q["rate_change"]) == pytest.approx(0, abs=1e-9) and q["quasi_static"] == "yes"
    assert float(q["reach_full_rate_mm"]) == pytest.approx(1.0) and float(q["reach_half_rate_mm"]) == pytest.approx(0.5)
    assert float(q["compared_up_to_mm"]) == pytest.approx(0.5)
    assert "runs end at different displacements (1 mm at the full rate, 0.5 mm at half the rate): both peaks " \
           "taken up to 0.5 mm" in q["note"]
    assert q["note"] in (out / "report.md").read_text()


REF = "cases,N_kN,experiment_kN\nw_N30,30,10\nw_N100,100,20\nw_N200,200,30\n"


def test_trend_line_ordered_family(tmp_path, cli, fake):
    # alphabetical order N100, N200, N30; sorted by N the peaks rise and the displacements at peak fall
    fam = make_family(tmp_path, {"w_N30": "peak_kN = 10.0\nu_peak = 0.9e-3",
                                 "w_N100": "peak_kN = 20.0\nu_peak = 0.7e-3",
                                 "w_N200": "peak_kN = 30.0\nu_peak = 0.5e-3"}, REF)
    out = tmp_path / "out"
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--no-rate-check",
                     env={"FAKE_FDEM_LOG": str(tmp_path / "calls.log")})
    assert rc == 0, err
    md = (out / "report.md").read_text()
    assert ("Trend with N (reference.csv column `N_kN`): capacity rising with N: yes; displacement at peak falling "
            "with N: yes (values, sorted by N: N = 30, 100, 200 kN; peak 10, 20, 30 kN; displacement at peak "
            "0.9, 0.7, 0.5 mm).") in md


def eeep_ductility(P, u_peak, soft, u_end):
    """[K25] Eq. 14 in closed form for the fake curve with hardening (soft < 0): linear to (u_peak, P), then a line
    to (u_end, P_max); K_e = P / u_peak (the 70 % regression points are all on the first branch), Delta_u = u_end."""
    p_max = P * (1 - soft * (u_end - u_peak) / 1e-3)
    area = 0.5 * P * u_peak + 0.5 * (P + p_max) * (u_end - u_peak)
    k_e = P / u_peak
    p_y = k_e * (u_end - (u_end ** 2 - 2 * area / k_e) ** 0.5)
    return u_end / (p_y / k_e)


def test_trend_line_reports_eeep_ductility(tmp_path, cli, fake):
    # hardening after a yield at u_peak (largest load at the end, 1 mm): the later the yield, the lower the ductility
    cases = {"w_N30": 0.25e-3, "w_N100": 0.5e-3, "w_N200": 0.75e-3}
    fam = make_family(tmp_path, {k: f"peak_kN = 10.0\nu_peak = {u}\nsoftening = -0.2" for k, u in cases.items()}, REF)
    out = tmp_path / "out"
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--no-rate-check",
                     env={"FAKE_FDEM_LOG": str(tmp_path / "calls.log")})
    assert rc == 0, err
    rep = {r["case"]: r for r in read_csv(out / "report.csv")}
    mus = {k: eeep_ductility(10e3, u, -0.2, 1e-3) for k, u in cases.items()}
    for k, mu in mus.items():
        assert float(rep[k]["ductility_eeep"]) == pytest.approx(mu, rel=1e-9)
    assert mus["w_N30"] > mus["w_N100"] > mus["w_N200"] > 1.0
    md = (out / "report.md").read_text()
    assert ("EEEP ductility ([K25] Eq. 14, displacement at peak as Delta_u) falling with N: yes ("
            + ", ".join(validate.fmt(mus[k]) for k in ("w_N30", "w_N100", "w_N200")) + ").") in md
    assert "displacement at peak falling with N: no" in md  # all three peak at the end, 1 mm


def test_trend_line_unordered_family(tmp_path, cli, fake):
    fam = make_family(tmp_path, {"w_N30": "peak_kN = 10.0\nu_peak = 0.5e-3",
                                 "w_N100": "peak_kN = 30.0\nu_peak = 0.7e-3",
                                 "w_N200": "peak_kN = 20.0\nu_peak = 0.9e-3"}, REF)
    out = tmp_path / "out"
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--no-rate-check",
                     env={"FAKE_FDEM_LOG": str(tmp_path / "calls.log")})
    assert rc == 0, err
    md = (out / "report.md").read_text()
    assert "capacity rising with N: no; displacement at peak falling with N: no (values" in md
    assert "peak 10, 30, 20 kN; displacement at peak 0.5, 0.7, 0.9 mm" in md


def test_trend_line_skipped_or_not_evaluated(tmp_path, cli, fake):
    # no axial column: no line
    fam = make_family(tmp_path, {"w_N30": "", "w_N100": ""}, "cases,experiment_kN\nw_N30,10\nw_N100,20\n")
    out = tmp_path / "out"
    env = {"FAKE_FDEM_LOG": str(tmp_path / "calls.log")}
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--no-rate-check", env=env)
    assert rc == 0, err
    assert "Trend with" not in (out / "report.md").read_text()
    # two variants at the same N: not evaluated rather than a meaningless order
    (fam / "reference.csv").write_text("cases,N_kN\nw_N30 w_N100,30\n")
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--no-rate-check", env=env)
    assert rc == 0, err
    assert "not evaluated: several cases share N = 30 kN" in (out / "report.md").read_text()


def test_lourenco_reference_has_the_axial_column():
    """The default --axial-column is the column the wall family's reference.csv really has."""
    p = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                     "cases", "lourenco2005", "reference.csv")
    if not os.path.isfile(p):
        pytest.skip("wall cases not present")
    rows = read_csv(p)
    assert "N_kN" in rows[0] and [float(r["N_kN"]) for r in rows] == [30, 100, 200, 250]


# peak 10 kN at 0.3 mm, -20 %/mm to 0.6 mm (9.4 kN, 6 % down), then +50 %/mm to 1.2 mm (12.4 kN): a second branch
TWO_BRANCHES = "u_end = 1.2e-3\nu_peak = 0.3e-3\nsoftening = 0.2\nu_rise = 0.6e-3\nrise = 0.5"
# the same with a 3 % dip (-10 %/mm): no first peak by the 5 % rule
SHALLOW = "u_end = 1.2e-3\nu_peak = 0.3e-3\nsoftening = 0.1\nu_rise = 0.6e-3\nrise = 0.5"


def test_first_peak_rule_reports_the_first_capacity_and_the_larger_later_load(tmp_path, cli, fake):
    fam = make_family(tmp_path, {"two": TWO_BRANCHES, "shallow": SHALLOW})
    out = tmp_path / "out"
    env = {"FAKE_FDEM_LOG": str(tmp_path / "calls.log")}
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--no-rate-check", env=env)
    assert rc == 0, err
    rep = {r["case"]: r for r in read_csv(out / "report.csv")}
    # default rule: the largest load, at the end of the second branch
    assert float(rep["two"]["peak_load_kN"]) == pytest.approx(12.4, rel=1e-9)
    assert float(rep["two"]["disp_at_peak_mm"]) == pytest.approx(1.2, rel=1e-9)
    assert rep["two"]["peak_rule"] == "largest" and rep["two"]["peak_up_to_mm"] == ""
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--no-rate-check", "--peak", "first", env=env)
    assert rc == 0, err
    rep = {r["case"]: r for r in read_csv(out / "report.csv")}
    two, shallow = rep["two"], rep["shallow"]
    assert float(two["peak_load_kN"]) == pytest.approx(10.0, rel=1e-9)
    assert float(two["disp_at_peak_mm"]) == pytest.approx(0.3, rel=1e-9)
    assert two["past_peak"] == "yes" and two["peak_rule"] == "first"
    assert float(two["largest_load_kN"]) == pytest.approx(12.4, rel=1e-9)
    assert float(two["largest_at_mm"]) == pytest.approx(1.2, rel=1e-9)
    # EEEP of the run's curve up to the first peak (its first 11 rows), not of the whole curve
    from fdemtools.eeep import eeep
    h = read_csv(out / "two" / "runs" / "run" / "history.csv")
    u, F = np.array([float(r["u"]) for r in h]), np.array([float(r["F"]) for r in h])
    first, whole = eeep(u[:11], F[:11])["ductility"], eeep(u, F)["ductility"]
    assert float(two["ductility_eeep"]) == pytest.approx(first, rel=1e-12)
    assert abs(whole - first) > 0.5
    # a 3 % dip is not a peak: the largest load, and not past it
    assert float(shallow["peak_load_kN"]) == pytest.approx(float(shallow["largest_load_kN"]), rel=1e-12)
    assert float(shallow["disp_at_peak_mm"]) == pytest.approx(1.2, rel=1e-9)
    assert shallow["past_peak"] == "no (still rising / flat)"
    md = (out / "report.md").read_text()
    assert "Peak = first peak (--peak first)" in md
    assert "Larger loads after the first peak (kN at mm): two 12.4 at 1.2." in md


def test_peak_up_to_cuts_every_curve_and_the_half_rate_check(tmp_path, cli, fake):
    fam = make_family(tmp_path, {"two": TWO_BRANCHES + "\nrate_sens = 10.0"})
    out = tmp_path / "out"
    env = {"FAKE_FDEM_LOG": str(tmp_path / "calls.log")}
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--peak-up-to", "0.9", env=env)
    assert rc == 0, err
    r = read_csv(out / "report.csv")[0]
    P = 10.0 * (1 + 10.0 * 0.01)  # 11 kN at the full rate
    # up to 0.9 mm the largest load is at 0.9 mm: 0.94 P + 0.5 P 0.3 = 1.09 P, also the load at the end
    assert float(r["peak_load_kN"]) == pytest.approx(1.09 * P, rel=1e-9)
    assert float(r["disp_at_peak_mm"]) == pytest.approx(0.9, rel=1e-9)
    assert float(r["load_at_end_kN"]) == pytest.approx(1.09 * P, rel=1e-9)
    assert float(r["peak_up_to_mm"]) == 0.9
    q = read_csv(out / "quasi_static.csv")[0]
    Ph = 10.0 * (1 + 10.0 * 0.005)
    assert float(q["peak_full_rate_kN"]) == pytest.approx(1.09 * P, rel=1e-9)
    assert float(q["peak_half_rate_kN"]) == pytest.approx(1.09 * Ph, rel=1e-9)
    assert "up to 0.9 mm of control displacement (--peak-up-to" in (out / "report.md").read_text()
    rc, o, err = cli("validate", fam, "--fdem", fake, "--out-dir", out, "--peak-up-to", "0", env=env)
    assert rc == 1 and "--peak-up-to must be a displacement > 0 mm, got 0" in err


def test_peak_index_rules_and_peak_up_to():
    y = np.array([0.0, 5.0, 10.0, 9.6, 9.4, 11.0, 12.0])
    assert validate.peak_index(y, "largest") == (6, False)
    assert validate.peak_index(y, "first") == (2, True)  # 9.4 <= 0.95 x 10
    y2 = np.array([0.0, 5.0, 10.0, 9.6, 11.0, 8.0])
    assert validate.peak_index(y2, "first") == (4, True)  # 9.6 is a 4 % dip; 8 is 27 % below 11
    assert validate.peak_index(y2, "largest") == (4, True)  # the end is 27 % below
    m = {"x": np.arange(7) * 0.1e-3, "y": y, "rule": "first"}
    assert validate.peak_up_to(m, 0.25e-3) == 10.0  # rows 0-3 (0.3 mm is the first to reach 0.25 mm)
    assert validate.peak_up_to(m, 0.15e-3) == 10.0  # rows 0-2: never 5 % down, the largest
    assert validate.peak_up_to(m, 0.6e-3) == 10.0
    assert validate.peak_up_to(dict(m, rule="largest"), 0.6e-3) == 12.0
    # a start spike (3 of 12, then back to 1) is under half the largest load: not a peak
    y3 = np.array([0.0, 3.0, 1.0, 6.0, 12.0, 11.0, 10.0])
    assert validate.peak_index(y3, "first") == (4, True)
    assert validate.peak_index(y3[:5], "first") == (4, False)  # never falls past it: the largest, not past
