"""provenance (issue 51, 7): a committed figure is checked against its case through the stamp it carries: ok while
the case hashes as when the figure was made, stale once the case changed, unstamped without a stamp."""
import os
import shutil
import subprocess

import pytest

from fdemtools.figures import new_figure, save
from fdemtools.provenance import parse_stamp

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TINY = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "tiny_shear.toml")


def fdem_bin():
    return os.environ.get("FDEM_BIN") or os.path.join(REPO, "build", "fdem", "fdem")


def tiny_case_and_run(tmp_path):
    """tmp_path/cases/tiny_shear.toml and a completed run of it in tmp_path/run."""
    if not os.access(fdem_bin(), os.X_OK):
        pytest.fail(f"no fdem executable at {fdem_bin()} (build it or set FDEM_BIN)")
    cases = tmp_path / "cases"
    cases.mkdir()
    shutil.copy(TINY, cases / "tiny_shear.toml")
    run = tmp_path / "run"
    r = subprocess.run([fdem_bin(), "run", str(cases / "tiny_shear.toml"), "--out", str(run), "--quiet"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return cases, run


def test_parse_stamp():
    p = parse_stamp("fdem 0.1.0 build abc123 | w1 [00112233445566ff], old [no hash]")
    assert p["build"] == "abc123" and p["cases"] == [("w1", "00112233445566ff"), ("old", None)]
    p = parse_stamp("fdem 0.1.0 build a1; fdem 0.1.0 build b2 | w [0123456789abcdef]")
    assert p["build"] == "a1" and p["cases"] == [("w", "0123456789abcdef")]
    assert parse_stamp("made by hand") is None


def test_figures_ok_then_stale_after_the_case_changes(tmp_path, cli):
    if not os.access(fdem_bin(), os.X_OK):
        pytest.fail(f"no fdem executable at {fdem_bin()} (build it or set FDEM_BIN)")
    cases = tmp_path / "cases"
    cases.mkdir()
    case = cases / "tiny_shear.toml"
    shutil.copy(TINY, case)
    for f in os.listdir(os.path.dirname(TINY)):  # the case's geometry files beside it
        if f.endswith(".geo") or f.endswith(".msh"):
            shutil.copy(os.path.join(os.path.dirname(TINY), f), cases / f)
    run = tmp_path / "run"
    r = subprocess.run([fdem_bin(), "run", str(case), "--out", str(run), "--quiet"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    rc, out, err = cli("plot", str(run), "--figures", "curves", "--out-dir", str(cases / "fig"))
    assert rc == 0, err
    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1])
    save(fig, str(cases / "fig" / "hand"))  # no stamp
    rc, out, err = cli("provenance", str(cases / "fig"), "--cases", str(cases), "--fdem", fdem_bin(), "--strict")
    assert rc == 2, err  # the unstamped one
    lines = {os.path.basename(ln.split()[0]): ln for ln in out.splitlines() if ln.split() and ln.split()[0].endswith(".png")}
    assert " ok " in lines["curves.png"]
    assert " unstamped " in lines["hand.png"]
    # a comment alone leaves the resolved case, and so its hash, as it was
    text = case.read_text()
    case.write_text(text + "\n# a comment only\n")
    rc, out, err = cli("provenance", str(cases / "fig" / "curves.png"), "--cases", str(cases), "--fdem", fdem_bin())
    assert rc == 0 and " ok " in out, out + err
    # the case changes (E doubled): its figure is stale, and says from which hash to which
    import re
    case.write_text(re.sub(r"\bE = ([0-9.eE+-]+)", lambda m: f"E = {2 * float(m.group(1))!r}", text, count=1))
    rc, out, err = cli("provenance", str(cases / "fig" / "curves.png"), "--cases", str(cases), "--fdem", fdem_bin(),
                       "--strict")
    assert rc == 2
    assert " stale " in out and "now hashes" in out


def test_relative_paths_as_from_the_repository_root(tmp_path, cli, monkeypatch):
    """Run as the README says (`provenance cases` from the checkout): relative case paths reach fdem check."""
    cases, run = tiny_case_and_run(tmp_path)
    rc, out, err = cli("plot", str(run), "--figures", "curves", "--out-dir", str(cases / "fig"))
    assert rc == 0, err
    monkeypatch.chdir(tmp_path)
    rc, out, err = cli("provenance", "cases", "--fdem", fdem_bin(), "--strict")
    assert rc == 0, out + err
    assert "1 ok" in out


def test_a_validate_report_is_checked_by_its_source_line(tmp_path, cli):
    """validate's report.md carries "Source: <stamp>": provenance reads it as a figure's stamp."""
    cases, run = tiny_case_and_run(tmp_path)
    from fdemtools.figures import stamp_of_runs
    stamp = stamp_of_runs([str(run)])
    (cases / "validate_report.md").write_text(f"# Validation report: x\n\nCases: 1\n\nSource: {stamp}\n\n| a |\n")
    (cases / "validate_old_report.md").write_text("# Validation report: y\n\nno source line\n")
    # the same case with a --set run beside it (validate's half-rate check): ok while one hash is the case's now
    both = stamp + ", " + stamp.split(" | ")[1].split(" [")[0] + " [0123456789abcdef]"
    (cases / "validate_rate_report.md").write_text(f"# Validation report: z\n\nSource: {both}\n")
    (cases / "validate_gone_report.md").write_text(
        "# r\n\nSource: fdem 0.1.0 build x | " + stamp.split(" | ")[1].split(" [")[0] + " [0123456789abcdef]\n")
    rc, out, err = cli("provenance", str(cases), "--cases", str(cases), "--fdem", fdem_bin())
    assert rc == 0, err
    lines = {os.path.basename(ln.split()[0]): ln for ln in out.splitlines() if ln.split() and ln.split()[0].endswith(".md")}
    assert " ok " in lines["validate_report.md"]
    assert " unstamped " in lines["validate_old_report.md"]
    assert " ok " in lines["validate_rate_report.md"]
    assert " stale " in lines["validate_gone_report.md"]


def test_a_figure_from_a_dirty_build_is_flagged(tmp_path, cli):
    """A figure whose cases still match but whose build had uncommitted changes ("BUILD-dirty") is ok and flagged:
    the line says so and the count names it (no commit rebuilds what drew it)."""
    import json
    cases, run = tiny_case_and_run(tmp_path)
    summary = run / "summary.json"
    s = json.loads(summary.read_text())
    s["build"] = str(s.get("build", "abc")).replace("-dirty", "") + "-dirty"
    summary.write_text(json.dumps(s))
    rc, out, err = cli("plot", str(run), "--figures", "curves", "--out-dir", str(cases / "fig"))
    assert rc == 0, err
    rc, out, err = cli("provenance", str(cases / "fig"), "--cases", str(cases), "--fdem", fdem_bin())
    assert rc == 0, err
    line = next(ln for ln in out.splitlines() if "curves.png" in ln)
    assert " ok " in line and "uncommitted changes" in line
    assert "(1 of the ok ones made by a build with uncommitted changes)" in out
    # the same figure from a clean build: no flag
    s["build"] = s["build"].replace("-dirty", "")
    summary.write_text(json.dumps(s))
    rc, out, err = cli("plot", str(run), "--figures", "curves", "--out-dir", str(cases / "fig"))
    rc, out, err = cli("provenance", str(cases / "fig"), "--cases", str(cases), "--fdem", fdem_bin())
    assert "uncommitted" not in out


def test_every_committed_figure_matches_its_case(cli, monkeypatch):
    """The shipped figures and validate reports under cases/ (strict): each is stamped, every case it names hashes now
    as when it was drawn, and none was drawn by a build with uncommitted changes. A change to a case (or to what
    its hash covers) fails this until its figures are drawn again from runs of the changed case (each family's
    RESULTS.md says how)."""
    if not os.access(fdem_bin(), os.X_OK):
        pytest.fail(f"no fdem executable at {fdem_bin()} (build it or set FDEM_BIN)")
    monkeypatch.chdir(REPO)
    rc, out, err = cli("provenance", "cases", "--fdem", fdem_bin(), "--strict")
    bad = [ln for ln in out.splitlines() if ln.split() and len(ln.split()) > 1 and ln.split()[1] != "ok"
           and not ln.split()[0].isdigit()]
    assert rc == 0, "\n".join(bad) + err
    assert "uncommitted changes" not in out, out
    assert " 0 stale, 0 unknown, 0 unstamped " in out, out
