"""One load sign rule and one unit rule for every tool (issue 31 points 1, 2, 4).

Sign: a load is taken with the sign that makes its work on the loading branches positive (common.loading_work_sign),
unless the case (output.curve.sign) or the command line (--load-sign) says otherwise. The covariance of load and
displacement, the earlier rule of plot and hysteresis, turns an ordinary softening pushover upside down and leaves
a reaction that falls to a flat residual negative; the earlier rule of eeep (largest |load|) differed from both.
"""
import json
import os

import numpy as np
import pytest

from fdemtools import common, eeep, hysteresis, validate

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")


def pushover(n=201):
    """A softening pushover: H rises linearly to 40 kN at 3 mm, then falls linearly to 10 kN at 10 mm."""
    x = np.linspace(0.0, 10e-3, n)
    y = np.where(x <= 3e-3, 40e3 * x / 3e-3, 40e3 - 30e3 * (x - 3e-3) / 7e-3)
    return x, y


def reaction(n=201):
    """A reaction (negative while the structure is pushed in +x) that falls in magnitude from 30 kN at 2 mm to a
    flat residual of 8 kN from 5 mm on."""
    x = np.linspace(0.0, 10e-3, n)
    mag = np.where(x <= 2e-3, 30e3 * x / 2e-3, np.maximum(30e3 - 22e3 * (x - 2e-3) / 3e-3, 8e3))
    return x, -mag


def make_run(path, x, y, sign=None, case_sign=None, precompression=True):
    """A run folder by the contract: stage 1 precompression (x = 0, the load monitor reads a spurious value), stage
    2 the loading curve (x, y). sign: put curve.sign into summary.json; case_sign: write a case file whose
    [output] curve says sign = case_sign and name it in summary.json."""
    os.makedirs(path, exist_ok=True)
    rows = []
    t = 0.0
    if precompression:
        for k in range(20):  # precompression: the actuator reads -3 kN then 0, no displacement
            rows.append((t, k, 1, 0.0, -3e3 * (1 - k / 19)))
            t += 0.01
    for k, (a, b) in enumerate(zip(x, y)):
        rows.append((t, 100 + k, 2, a, b))
        t += 0.01
    with open(os.path.join(path, "history.csv"), "w") as f:
        f.write("time,step,stage,u,H\n")
        for r in rows:
            f.write(",".join(repr(v) for v in r) + "\n")
    curve = {"x": "u", "y": "H"}
    if sign is not None:
        curve["sign"] = sign
    s = {"case": os.path.basename(path), "status": "completed", "curve": curve, "columns": {"u": "m", "H": "N"}}
    if case_sign is not None:
        cf = os.path.join(path, "case.toml")
        with open(os.path.join(DATA, "tiny_shear.toml")) as f:  # a case the engine reads, its curve's sign stated
            text = f.read().replace('"u_top"', '"u"').replace('"F_base"', '"H"')
        with open(cf, "w") as f:
            f.write(text.replace('curve = { x = "u", y = "H" }', f'curve = {{ x = "u", y = "H", sign = {case_sign} }}'))
        s["case_file"] = cf
    with open(os.path.join(path, "summary.json"), "w") as f:
        json.dump(s, f)
    return path


def covariance_sign(x, y):  # the rule plot and hysteresis used before
    return -1.0 if float(np.dot(x - x.mean(), y - y.mean())) < 0 else 1.0


def test_rule_on_softening_pushover_and_reaction():
    x, y = pushover()
    assert covariance_sign(x, y) == -1.0  # the old rule turned it
    assert common.loading_work_sign(x, y) == 1.0
    x, y = reaction()
    assert covariance_sign(x, y) == 1.0  # the old rule left the reaction negative
    assert common.loading_work_sign(x, y) == -1.0
    # a pushover in the negative direction with its (negative) applied load: not turned
    x, y = pushover()
    assert common.loading_work_sign(-x, -y) == 1.0
    assert common.loading_work_sign(-x, y) == -1.0


@pytest.mark.parametrize("kind", ["pushover", "reaction"])
def test_every_tool_takes_the_same_sign(tmp_path, cli, kind):
    x, y = pushover() if kind == "pushover" else reaction()
    want = 1.0 if kind == "pushover" else -1.0
    peak = 40e3 if kind == "pushover" else 30e3
    run = make_run(str(tmp_path / kind), x, y)
    # plot: a turned load is labelled so and noted
    rc, out, err = cli("plot", run, "--figures", "curves", "--out-dir", tmp_path / "p")
    assert rc == 0, err
    assert ("load sign of" in out) == (want < 0)
    assert ("load sign turned" in (tmp_path / "p" / "curves.svg").read_text()) == (want < 0)
    # eeep: the JSON's sign and peak
    rc, out, err = cli("eeep", run, "-o", tmp_path / "e")
    assert rc == 0, err
    j = json.loads((tmp_path / "e.json").read_text())
    assert j["sign_y"] == want and j["P_peak"] == pytest.approx(peak / 1e3, rel=1e-12)
    # validate's measurement of the same run
    m = validate.curve_metrics(run)
    assert m["load_sign"] == want and m["peak_load_N"] == pytest.approx(peak, rel=1e-12)
    assert m["load_at_end_N"] == pytest.approx(10e3 if kind == "pushover" else 8e3, rel=1e-9)
    # hysteresis: the same load made cyclic (one loop out and back, then the mirror image)
    xc = np.concatenate((x, x[::-1][1:], -x[1:], -x[::-1][1:]))
    yc = np.concatenate((y, 0.5 * y[::-1][1:], -y[1:], -0.5 * y[::-1][1:]))
    assert hysteresis.analyse(xc, yc)["sign_y"] == want


def test_case_and_command_line_override(tmp_path, cli):
    x, y = pushover()
    for i, kw in enumerate(({"sign": -1}, {"case_sign": -1})):
        run = make_run(str(tmp_path / f"r{i}"), x, y, **kw)
        c = common.load_curve(run, stage=2)
        s, rule = common.resolve_sign(c)
        assert s == -1.0 and "case" in rule
        assert validate.curve_metrics(run)["load_sign"] == -1.0
        rc, out, err = cli("eeep", run, "-o", tmp_path / f"e{i}", "--no-plot")
        assert rc == 1 and "no peak" in err  # the case says -1: the curve is then never positive
        rc, out, err = cli("eeep", run, "-o", tmp_path / f"e{i}", "--no-plot", "--load-sign", "1")
        assert rc == 0, err
        assert json.loads((tmp_path / f"e{i}.json").read_text())["sign_y"] == 1.0
    run = make_run(str(tmp_path / "bad"), x, y, sign=2)
    rc, out, err = cli("eeep", run)
    assert rc == 1 and "expected 1 or -1" in err


def test_eeep_and_validate_agree_on_the_same_run(tmp_path, cli):
    """Same defaults (the last stage, displacement from its start, one sign rule), so the same K_e and ductility;
    also with --smooth. The old eeep read every row, the precompression too (its -3 kN at zero displacement)."""
    x = np.linspace(0.0, 8e-3, 400)
    rng = np.random.default_rng(1)
    y = -(45e3 * np.tanh(x / 1.5e-3) - 2e6 * np.maximum(x - 4e-3, 0) + 800 * rng.standard_normal(len(x)))
    run = make_run(str(tmp_path / "w"), x, y)
    for smooth in (0.0, 0.5):
        rc, out, err = cli("eeep", run, "--smooth", smooth, "-o", tmp_path / f"e{smooth}", "--no-plot")
        assert rc == 0, err
        j = json.loads((tmp_path / f"e{smooth}.json").read_text())
        m = validate.curve_metrics(run, smooth_m=smooth * 1e-3)
        assert j["si"]["K_e"] == pytest.approx(m["eeep_K_e_N_m"], rel=1e-12)
        assert j["ductility"] == pytest.approx(m["ductility"], rel=1e-12)
        assert j["P_peak"] * 1e3 == pytest.approx(m["peak_load_N"], rel=1e-12)
    # the whole record (precompression rows included) is still available, and then differs
    rc, out, err = cli("eeep", run, "--all-stages", "-o", tmp_path / "all", "--no-plot")
    assert rc == 0, err


def test_eeep_fallback_is_printed_and_drawn(tmp_path, cli):
    """A curve holding more energy than any elastic-plastic line of stiffness K_e can (soft start, stiff end):
    P_y = 0.85 P_peak (ASTM E2126), printed on the terminal and drawn, not only noted in the JSON."""
    x = np.linspace(0, 10e-3, 101)
    y = 40e3 * (x / 10e-3) ** 3  # stiffening: A = P d_u / 4 exceeds K_e d_u^2 / 2 (K_e = 0.473 P / d_u)
    f = tmp_path / "c.csv"
    f.write_text("u_m,F_N\n" + "".join(f"{a!r},{b!r}\n" for a, b in zip(x, y)))
    res = eeep.eeep(x, y)
    assert res["fallback"]
    rc, out, err = cli("eeep", f, "-o", tmp_path / "c")
    assert rc == 0, err
    assert "FALLBACK" in out and "0.85" in out
    assert json.loads((tmp_path / "c.json").read_text())["fallback"] is True
    assert "fallback" in (tmp_path / "c.svg").read_text().lower()


# ------------------------------------------------------------------------------------------------------------------
# Units


def test_units_from_column_names():
    L, F = common.LENGTH_UNITS, common.FORCE_UNITS
    for name, unit in (("d_mm", "mm"), ("disp_m", "m"), ("u [mm]", "mm"), ("d (in)", "in"), ("u", None),
                       ("u_beam", None), ("col1", None)):
        assert common.unit_from_name(name, L) == unit, name
    for name, unit in (("F_kN", "kN"), ("load_N", "N"), ("H (kN)", "kN"), ("P_kip", "kip"), ("H", None)):
        assert common.unit_from_name(name, F) == unit, name


def test_one_default_and_names_for_every_csv_command(tmp_path, cli):
    """The same mm/kN file gives the same numbers in eeep and in plot --experiment; its names say the units.
    Before, eeep read it in m and N (Delta_u = 4000 mm, no warning) and plot in mm and kN."""
    x, y = pushover()
    f = tmp_path / "exp.csv"
    f.write_text("d_mm,F_kN\n" + "".join(f"{a * 1e3!r},{b / 1e3!r}\n" for a, b in zip(x, y)))
    rc, out, err = cli("eeep", f, "--no-plot")
    assert rc == 0, err
    j = json.loads((tmp_path / "exp_eeep.json").read_text())
    assert j["P_peak"] == pytest.approx(40.0, rel=1e-12) and j["Delta_u"] == pytest.approx(3.0, rel=1e-12)
    assert j["input_units"]["x"] == "mm" and j["input_units"]["y"] == "kN" and "warning" not in out
    c = common.load_curve(str(f))
    assert c.x.max() == pytest.approx(10e-3, rel=1e-12) and c.y.max() == pytest.approx(40e3, rel=1e-12)
    # unnamed columns: the one default, m and N, for every command
    g = tmp_path / "plain.csv"
    g.write_text("u,H\n" + "".join(f"{a * 1e3!r},{b / 1e3!r}\n" for a, b in zip(x, y)))
    c = common.load_curve(str(g))
    assert (c.x_unit, c.y_unit) == ("m", "N") == (common.DEFAULT_X_UNIT, common.DEFAULT_Y_UNIT)
    # ... and the magnitudes look like mm and kN: warned, on the terminal and in the JSON
    rc, out, err = cli("eeep", g, "--no-plot")
    assert rc == 0, err
    assert "warning:" in out and "mm?" in out and "kN?" in out
    assert len(json.loads((tmp_path / "plain_eeep.json").read_text())["warnings"]) == 2
    rc, out, err = cli("plot", make_run(str(tmp_path / "r"), x, y), "--figures", "curves", "--experiment", g,
                       "--out-dir", tmp_path / "p")
    assert rc == 0 and "mm?" in out
    # a unit given on the command line wins over the name, with a warning
    rc, out, err = cli("eeep", f, "--x-unit", "m", "--no-plot", "-o", tmp_path / "forced")
    assert rc == 0 and "named in mm" in out


def test_csv_columns_by_name(tmp_path, cli):
    """Issue 51 (12): `time,d_mm,F_kN` was read as displacement = time, load = d_mm (the first two columns), with the
    advice to rename d_mm to 'd_mm_kN'. Now the columns are picked by their names; names that do not tell need --x and
    --y, with a message that says so."""
    x, y = pushover()
    f = tmp_path / "exp.csv"
    f.write_text("time,d_mm,F_kN\n" + "".join(f"{0.1 * i!r},{a * 1e3!r},{b / 1e3!r}\n"
                                              for i, (a, b) in enumerate(zip(x, y))))
    rc, out, err = cli("eeep", f, "--no-plot")
    assert rc == 0, err
    j = json.loads((tmp_path / "exp_eeep.json").read_text())
    assert (j["x_column"], j["y_column"], j["columns_rule"]) == ("d_mm", "F_kN", "by name")
    assert j["P_peak"] == pytest.approx(40.0, rel=1e-12) and j["Delta_u"] == pytest.approx(3.0, rel=1e-12)
    assert "warning" not in out and "columns d_mm, F_kN (by name)" in out
    g = tmp_path / "anon.csv"
    g.write_text("a,b,c\n0,0,0\n1,1,1\n2,2,1\n")
    rc, out, err = cli("eeep", g)
    assert rc == 1 and "give --x DISPLACEMENT_COLUMN --y LOAD_COLUMN" in err and len(err.strip().splitlines()) == 1
    rc, out, err = cli("eeep", g, "--x", "a", "--y", "b", "--no-plot", "--load-sign", "1")
    assert rc == 0, err
    # two displacement-like names: ambiguous, so not guessed
    h = tmp_path / "two.csv"
    h.write_text("u_mm,d_mm,F_kN\n0,0,0\n1,1,1\n2,2,1\n")
    rc, out, err = cli("eeep", h)
    assert rc == 1 and "displacement-like: u_mm, d_mm" in err


def test_unit_advice_names_the_right_column():
    """The advice for a load that looks like kN read in N renames the unit ('F_N' -> 'F_kN', was 'F_N_kN'); a load
    column whose name carries a length unit is the wrong column, and the advice says so (was: rename d_mm to
    'd_mm_kN')."""
    c = common.Curve(np.array([0.0, 1e-3]), np.array([0.0, 40.0]), "c", "c.csv", "u_m", "F_N", y_unit="N")
    (msg,) = common.check_magnitudes(c)
    assert "name it 'F_kN'" in msg and "F_N_kN" not in msg
    c = common.Curve(np.array([0.0, 1e-3]), np.array([0.0, 4.0]), "c", "c.csv", "time", "d_mm", y_unit="N")
    (msg,) = common.check_magnitudes(c)
    assert "d_mm_kN" not in msg and "its name says mm, a length: pick the right column with --y" in msg
