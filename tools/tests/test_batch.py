import json
import os
import signal
import subprocess
import sys
import time

import pytest

from conftest import ENTRY
from fdemtools import batch
from fdemtools.common import ToolError

FAKE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fake_fdem.py")


def calls(log):
    if not os.path.exists(log):
        return []
    with open(log) as f:
        return [json.loads(line) for line in f]


def test_split_values_and_grid():
    assert batch.split_values('0.1, 0.05,[1, 2],"a,b"') == ["0.1", "0.05", "[1, 2]", '"a,b"']
    with pytest.raises(ToolError):
        batch.split_values("[1,2")
    pts = batch.expand_grid([("a", ["1", "2"]), ("b.c", ["x", "y", "z"])])
    assert len(pts) == 6 and pts[0] == {"a": "1", "b.c": "x"} and pts[-1] == {"a": "2", "b.c": "z"}
    names = {batch.run_name(p) for p in pts}
    assert len(names) == 6
    assert batch.run_name({"a": "1", "b.c": "x"}) == batch.run_name({"b.c": "x", "a": "1"}).replace(
        "c=x__a=1", "a=1__c=x")  # same digest whatever the key order


def test_batch_resumes(tmp_path, cli):
    case = tmp_path / "case.toml"
    case.write_text("# fake\n")
    log = str(tmp_path / "calls.log")
    out = tmp_path / "b"
    args = ["batch", case, "--grid", "geometry.mesh_size=0.1,0.05", "--grid", "fail=false,true",
            "--set", "rate=0.5", "--out-dir", out, "--fdem", FAKE, "--jobs", "2"]
    rc, o, err = cli(*args, env={"FAKE_FDEM_LOG": log})
    assert rc == 2 and "1 of 4" not in err and "2 of 4 runs did not complete" in err
    assert len(calls(log)) == 4
    assert all(c["rate"] == "0.5" for c in calls(log))
    table = (out / "results.csv").read_text().splitlines()
    assert len(table) == 5 and table[0].startswith("geometry.mesh_size,fail,name,status")
    # restart: the two completed runs are skipped, the two failed ones are run again
    rc, o, err = cli(*args, env={"FAKE_FDEM_LOG": log})
    assert rc == 2
    again = calls(log)[4:]
    assert len(again) == 2 and all(c["fail"] == "true" for c in again)
    assert o.count("already completed, skipped") == 2
    # a run left 'running' by an interruption is redone; a completed one with the same grid is not
    rc, o, err = cli("batch", case, "--grid", "geometry.mesh_size=0.1,0.05", "--set", "rate=0.5",
                     "--out-dir", out, "--fdem", FAKE, env={"FAKE_FDEM_LOG": log})
    assert rc == 0
    assert len(calls(log)) == 8  # first grid's names differ (no 'fail' key): both run
    rd = out / "runs" / batch.run_name({"geometry.mesh_size": "0.1"}) / "summary.json"
    s = json.loads(rd.read_text())
    s["status"] = "running"
    rd.write_text(json.dumps(s))
    rc, o, err = cli("batch", case, "--grid", "geometry.mesh_size=0.1,0.05", "--set", "rate=0.5",
                     "--out-dir", out, "--fdem", FAKE, env={"FAKE_FDEM_LOG": log})
    assert rc == 0 and len(calls(log)) == 9 and calls(log)[-1]["geometry.mesh_size"] == "0.1"
    res = (out / "results.csv").read_text()
    # peak 10 kN * (1 + h) * (1 + rate): 16.5 kN for h = 0.1, 15.75 kN for h = 0.05
    rows = [line.split(",") for line in res.splitlines()]
    col = rows[0].index("peak_load_kN")
    assert [float(r[col]) for r in rows[1:]] == pytest.approx([16.5, 15.75], rel=1e-12)
    assert all(r[rows[0].index("status")] == "completed" for r in rows[1:])


def test_interrupted_batch_is_resumed(tmp_path):
    """SIGINT to a running batch stops its fdem processes; the next start only redoes the unfinished runs."""
    case = tmp_path / "case.toml"
    case.write_text("# fake\n")
    log = str(tmp_path / "calls.log")
    out = tmp_path / "b"
    cmd = [sys.executable, ENTRY, "batch", str(case), "--grid", "slow=0,30", "--out-dir", str(out),
           "--fdem", FAKE, "--jobs", "2"]
    env = dict(os.environ, FAKE_FDEM_LOG=log)
    p = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    slow_dir = out / "runs" / batch.run_name({"slow": "30"})
    fast_dir = out / "runs" / batch.run_name({"slow": "0"})
    t0 = time.monotonic()
    while time.monotonic() - t0 < 20 and not (batch.is_finished(str(fast_dir)) and (slow_dir / "summary.json").exists()):
        time.sleep(0.1)
    p.send_signal(signal.SIGINT)
    o, err = p.communicate(timeout=30)
    assert p.returncode == 130 and "interrupted" in err and "Traceback" not in err
    assert time.monotonic() - t0 < 25  # did not wait for the 30 s run
    assert not batch.is_finished(str(slow_dir))
    n = len(calls(log))
    # restart with the slow run made fast: only it runs again
    r = subprocess.run([sys.executable, ENTRY, "batch", str(case), "--grid", "slow=0,30", "--out-dir", str(out),
                        "--fdem", FAKE, "--dry-run"], env=env, capture_output=True, text=True)
    assert r.returncode == 0 and len(r.stdout.splitlines()) == 2
    # timeout 3 s against the fake's 30 s sleep: long enough for the fake to start and log its call on a loaded
    # machine (0.5 s was not: under two full-load runs the interpreter's start-up alone took longer)
    rc = subprocess.run(cmd[:-2] + ["--jobs", "1", "--timeout", "3"], env=env, capture_output=True, text=True)
    new = calls(log)[n:]
    assert len(new) == 1 and new[0]["slow"] == "30"  # the fast, finished one was not redone
    assert rc.returncode == 2  # killed by the timeout


def test_bad_batch_input(tmp_path, cli):
    case = tmp_path / "case.toml"
    case.write_text("")
    rc, o, err = cli("batch", case, "--grid", "a", "--fdem", FAKE)
    assert rc == 1 and "expected KEY=VALUE" in err
    rc, o, err = cli("batch", case, "--grid", "a=1", "--fdem", tmp_path / "nope")
    assert rc == 1 and "not found" in err
    rc, o, err = cli("batch", tmp_path / "none.toml", "--grid", "a=1", "--fdem", FAKE)
    assert rc == 1 and "no such case file" in err


def test_reference_peak_both_forms():
    assert batch.reference_peak({"reference": {"peak_load_N": -20e3, "source": "x"}}) == 20e3
    s = {"curve": {"x": "u", "y": "F"}, "reference": {"monitor": "F", "quantity": "peak", "value": -17.1e3}}
    assert batch.reference_peak(s) == 17.1e3
    s["reference"]["quantity"] = "final"
    assert batch.reference_peak(s) is None
    s = {"curve": {"x": "u", "y": "F"}, "reference": {"monitor": "u", "quantity": "peak", "value": 1.0}}
    assert batch.reference_peak(s) is None
    assert batch.reference_peak({}) is None


def test_stale_runs_are_rerun(tmp_path, cli):
    """Issue 51 (1): a completed run is reused only when its case (parsed contents and the mesh file it names), its
    overrides and the fdem build are those of the run folder's fingerprint; the log says which changed. Before,
    an edited case, a new --set and a rebuilt fdem all gave "already completed, skipped"."""
    import shutil
    case = tmp_path / "case.toml"
    case.write_text('[geometry]\ntype = "msh"\nfile = "wall.msh"\n[materials.stone]\nE = 1.0e9\n')
    (tmp_path / "wall.msh").write_text("mesh v1\n")
    fake = tmp_path / "fdem_fake.py"
    shutil.copy(FAKE, fake)
    log = str(tmp_path / "calls.log")
    out = tmp_path / "b"

    def go(*extra):
        return cli("batch", case, "--grid", "geometry.mesh_size=0.1,0.05", "--out-dir", out, "--fdem", fake,
                   *extra, env={"FAKE_FDEM_LOG": log})

    rc, o, err = go()
    assert rc == 0 and len(calls(log)) == 2, err
    fp = json.loads((out / "runs" / batch.run_name({"geometry.mesh_size": "0.1"}) / "fingerprint.json").read_text())
    assert fp["overrides"] == [["geometry.mesh_size", "0.1"]] and "wall.msh" in fp["case"]["files"]
    rc, o, err = go()  # nothing changed: both reused
    assert rc == 0 and len(calls(log)) == 2 and o.count("already completed, skipped") == 2
    # a comment does not change what the engine reads: still reused
    case.write_text("# a comment\n" + case.read_text())
    rc, o, err = go()
    assert rc == 0 and len(calls(log)) == 2
    # E edited in the case: both rerun, and the log says the case file changed
    case.write_text(case.read_text().replace("1.0e9", "2.0e9"))
    rc, o, err = go()
    assert rc == 0 and len(calls(log)) == 4 and o.count("stale: case file") == 2
    assert "0 already completed" in o
    # the mesh file it names changed
    (tmp_path / "wall.msh").write_text("mesh v2\n")
    rc, o, err = go()
    assert rc == 0 and len(calls(log)) == 6 and o.count("file wall.msh changed") == 2
    # a fixed --set added: rerun with it, the log names it
    rc, o, err = go("--set", "numerics.dt=8e-7")
    assert rc == 0 and len(calls(log)) == 8 and all(c["numerics.dt"] == "8e-7" for c in calls(log)[-2:])
    assert o.count("overrides (--set numerics.dt: (not set) -> 8e-7)") == 2
    rc, o, err = go("--set", "numerics.dt=8e-7")
    assert rc == 0 and len(calls(log)) == 8
    # another build of fdem: rerun
    with open(fake, "a") as f:
        f.write("# rebuilt\n")
    rc, o, err = go("--set", "numerics.dt=8e-7")
    assert rc == 0 and len(calls(log)) == 10 and o.count("stale: build") == 2
    m = json.loads((out / "batch.json").read_text())
    assert all(r["fingerprint"]["overrides"][0] == ["numerics.dt", "8e-7"] for r in m["runs"])
    # a completed run folder without a fingerprint (older tools) cannot be checked: rerun
    (out / "runs" / batch.run_name({"geometry.mesh_size": "0.05"}) / "fingerprint.json").unlink()
    rc, o, err = go("--set", "numerics.dt=8e-7")
    assert rc == 0 and len(calls(log)) == 11 and "no fingerprint recorded" in o


def test_stale_run_that_fails_to_start_is_not_taken_as_completed(tmp_path, cli):
    """A stale completed run whose rerun dies before writing a summary must not keep its old 'completed' summary
    (it would be reused next time under the new fingerprint); its old checkpoint goes too."""
    case = tmp_path / "case.toml"
    case.write_text("# fake\n")
    out = tmp_path / "b"
    rc, o, err = cli("batch", case, "--grid", "geometry.mesh_size=0.1", "--out-dir", out, "--fdem", FAKE)
    assert rc == 0, err
    rd = out / "runs" / batch.run_name({"geometry.mesh_size": "0.1"})
    (rd / "checkpoint.bin").write_text("old\n")
    rc, o, err = cli("batch", case, "--grid", "geometry.mesh_size=0.1", "--set", "die=bad key", "--out-dir", out,
                     "--fdem", FAKE)
    assert rc == 2 and not (rd / "summary.json").exists() and not (rd / "checkpoint.bin").exists()
    rc, o, err = cli("batch", case, "--grid", "geometry.mesh_size=0.1", "--set", "die=bad key", "--out-dir", out,
                     "--fdem", FAKE)
    assert rc == 2 and "already completed, skipped" not in o and "0 already completed" in o


def test_failed_run_has_no_peak_in_the_results(tmp_path, cli):
    """Issue 51 (13): a failed run's largest load so far was tabulated as its peak load, as if it were a result."""
    case = tmp_path / "case.toml"
    case.write_text("# fake\n")
    out = tmp_path / "b"
    rc, o, err = cli("batch", case, "--grid", "fail=false,true", "--out-dir", out, "--fdem", FAKE)
    assert rc == 2
    rows = (out / "results.csv").read_text().splitlines()
    head = rows[0].split(",")
    got = {r.split(",")[head.index("status")]: r.split(",")[head.index("peak_load_kN")] for r in rows[1:]}
    assert got == {"completed": "11.0", "failed": ""}


def test_slurm_tasks_see_stale_runs(tmp_path, cli):
    """--scheduler slurm (batch, study, validate) asks batch.is_finished(run folder) which runs to submit: once the
    batch has made the task, a completed run of another fingerprint is not finished, and the task's prepare step
    (called before submission) clears its summary and checkpoint and writes the new fingerprint."""
    case = tmp_path / "case.toml"
    case.write_text("[materials.stone]\nE = 1.0e9\n")
    out = tmp_path / "b"
    rc, o, err = cli("batch", case, "--grid", "geometry.mesh_size=0.1", "--out-dir", out, "--fdem", FAKE)
    assert rc == 0, err
    name = batch.run_name({"geometry.mesh_size": "0.1"})
    rd = out / "runs" / name
    (rd / "checkpoint.bin").write_text("old\n")
    b = batch.Batch(str(case), str(out), FAKE, log=lambda m: None)
    t = b.task(name, {"geometry.mesh_size": "0.1"})
    assert batch.is_finished(str(rd))  # same case, overrides and build
    case.write_text("[materials.stone]\nE = 2.0e9\n")
    said = []
    b = batch.Batch(str(case), str(out), FAKE, log=said.append)
    t = b.task(name, {"geometry.mesh_size": "0.1"})
    assert not batch.is_finished(str(rd)) and "stale: case file" in said[0]
    t.prepare()
    assert not (rd / "summary.json").exists() and not (rd / "checkpoint.bin").exists()
    assert json.loads((rd / "fingerprint.json").read_text()) == b.fingerprint({"geometry.mesh_size": "0.1"})
