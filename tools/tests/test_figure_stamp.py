"""Figures name what made them (issue 51, 7): summary.json carries the fdem build (the source tree's commit when fdem
was built) and the resolved case's hash; the figures of `plot` and `cracks` write both small in a corner and into the
PNG/SVG metadata ("Source"), so a committed figure can be checked against the code and the case beside it."""
import json
import os
import re
import subprocess

import pytest
from PIL import Image

from fdemtools.figures import new_figure, run_stamp, save

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
TINY = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "tiny_shear.toml")


def fdem_bin():
    return os.environ.get("FDEM_BIN") or os.path.join(REPO, "build", "fdem", "fdem")


def test_stamp_text_and_metadata(tmp_path):
    s = [{"fdem_version": "0.1.0", "build": "abc123", "case": "w1", "case_hash": "00ff"},
         {"fdem_version": "0.1.0", "build": "abc123", "case": "w2", "case_hash": "0f0f"}, None]
    stamp = run_stamp(s)
    assert stamp == "fdem 0.1.0 build abc123 | w1 [00ff], w2 [0f0f]"
    assert run_stamp([{"case": "old"}]) == "fdem ? build unknown | old [no hash]"
    assert run_stamp([]) == ""
    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1])
    png, svg = save(fig, str(tmp_path / "f"), stamp)
    assert Image.open(png).info.get("Source") == stamp
    assert stamp in open(svg).read()


def test_plot_of_a_real_run_names_its_build_and_case_hash(tmp_path, cli):
    if not os.access(fdem_bin(), os.X_OK):
        pytest.fail(f"no fdem executable at {fdem_bin()} (build it or set FDEM_BIN)")
    runs = {}
    for tag, extra in (("a", []), ("b", ["--set", "stages.1.duration=0.002"])):
        out = tmp_path / tag
        r = subprocess.run([fdem_bin(), "run", TINY, "--out", str(out), "--quiet", *extra], capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        runs[tag] = json.loads((out / "summary.json").read_text())
    for s in runs.values():
        assert re.fullmatch(r"[0-9a-f]{16}", s["case_hash"])
        assert s["build"]  # the commit, or "unknown" outside a git checkout
    assert runs["a"]["case_hash"] != runs["b"]["case_hash"]  # a --set changes the resolved case
    rc, out, err = cli("plot", str(tmp_path / "a"), "--figures", "curves,energy")
    assert rc == 0, err
    rc, out, err = cli("eeep", str(tmp_path / "a"))
    assert rc == 0, err
    for name in ("curves", "energy", "eeep"):
        src = Image.open(tmp_path / "a" / "post" / f"{name}.png").info.get("Source", "")
        assert runs["a"]["case_hash"] in src and runs["a"]["build"] in src, src


def test_a_case_script_figure_is_stamped_with_its_runs(tmp_path):
    """The cases' own plot scripts save through figures.savefig_stamped: the stamp of the runs they show."""
    from fdemtools.figures import savefig_stamped
    runs = []
    for name, h in (("w1", "0123456789abcdef"), ("w2", "fedcba9876543210")):
        d = tmp_path / name
        d.mkdir()
        (d / "summary.json").write_text(json.dumps({"fdem_version": "0.1.0", "build": "abc", "case": name, "case_hash": h}))
        runs.append(str(d))
    runs.append(str(tmp_path / "missing"))  # no summary: left out
    fig, ax = new_figure()
    ax.plot([0, 1], [0, 1])
    stamp = savefig_stamped(fig, str(tmp_path / "f.png"), runs, dpi=50)
    assert stamp == "fdem 0.1.0 build abc | w1 [0123456789abcdef], w2 [fedcba9876543210]"
    assert Image.open(tmp_path / "f.png").info.get("Source") == stamp
