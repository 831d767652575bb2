"""`--scheduler slurm` on a real Slurm: a private single-node cluster (tools/slurm/local-cluster.sh, Debian's
slurm-wlm and munge) started once for this module. Short real fdem runs (an elastic cantilever, a dry-joint sliding
block) go through `fdem-tools batch --scheduler slurm` and must give the local pool's results table and the same
run files bit for bit; a run cancelled with scancel is submitted again by the next call, alone; a failing run is
reported with its Slurm state and the end of its log; SIGTERM to a task (what sbatch --signal sends before the time
limit) stops the run, and the next submission restarts it from its checkpoint when fdem offers --restart. If the
cluster cannot start, the tests fail with the daemons' logs: they are never skipped."""
import csv
import json
import os
import shlex
import shutil
import subprocess
import tempfile
import time

import pytest

from conftest import run_inprocess
from fdemtools import batch, slurm

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
CLUSTER = os.path.join(REPO, "tools", "slurm", "local-cluster.sh")
FAKE = os.path.join(HERE, "fake_fdem.py")
CANTILEVER = os.path.join(REPO, "cases", "elastic", "cantilever.toml")
SLIDING = os.path.join(REPO, "cases", "lourenco2005", "checks", "sliding_block.toml")
# dry-joint block pushed 0.3 and 0.5 mm (about 2.5 s each on one core)
DRY_GRID = ["--grid", "stages.2.until.value=0.0003,0.0005"]
# cantilever at safety 0.8 (completes, about 2 s) and 2.5 (a step 2.5 x its stable limit: a triangle inverts at step
# 9, exit 2)
ELASTIC_GRID = ["--grid", "numerics.safety=0.8,2.5"]
POLL = ["--poll", "0.5", "--max-wait", "300"]


def fdem_bin():
    return os.environ.get("FDEM_BIN") or os.path.join(REPO, "build", "fdem", "fdem")


@pytest.fixture(scope="module")
def cluster():
    """SLURM_CONF of a freshly started private cluster; stopped (after cancelling what is left) at the end."""
    if not os.access(fdem_bin(), os.X_OK):
        pytest.fail(f"no fdem executable at {fdem_bin()} (build it or set FDEM_BIN)")
    d = tempfile.mkdtemp(prefix="fdsl", dir="/tmp")
    r = subprocess.run([CLUSTER, "start", d], capture_output=True, text=True, timeout=120,
                       env=dict(os.environ, FDEM_SLURM_NICE="10"))  # the runs yield the CPU to other work
    if r.returncode != 0:
        subprocess.run([CLUSTER, "stop", d], capture_output=True, text=True, timeout=60)
        pytest.fail(f"the private Slurm cluster did not start (exit {r.returncode}):\n{r.stderr}\n{r.stdout}")
    conf = os.path.join(d, "slurm.conf")
    assert r.stdout.strip() == f"export SLURM_CONF={conf}"
    old = os.environ.get("SLURM_CONF")
    os.environ["SLURM_CONF"] = conf
    try:
        yield conf
    finally:
        subprocess.run(["scancel", "--user", str(os.getuid())], capture_output=True, timeout=60)
        s = subprocess.run([CLUSTER, "stop", d], capture_output=True, text=True, timeout=120)
        if old is None:
            os.environ.pop("SLURM_CONF", None)
        else:
            os.environ["SLURM_CONF"] = old
        assert s.returncode == 0, s.stderr
        for name in ("munged", "slurmctld", "slurmd"):
            assert not os.path.exists(os.path.join(d, name + ".pid")), f"{name} not stopped"
        shutil.rmtree(d)  # kept only when the stop failed (its logs are in d/log)


def tools_cli(*args, env=None):
    """fdem-tools in this process (an interpreter start costs seconds on a loaded machine), fdem from FDEM_BIN or
    the build; the Slurm commands follow for at most --max-wait (POLL)."""
    return run_inprocess(*args, env=dict(env or {}, FDEM_BIN=fdem_bin()))


def table(out):
    """results.csv without the wall and CPU times (the only columns that may differ between two runs of the same
    case)."""
    with open(os.path.join(out, "results.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r.pop("wall_time_s")
        r.pop("cpu_time_s")
    return rows


def run_files(run_dir):
    """Every file of a run folder except run.log and summary.json (they hold dates and wall times)."""
    out = {}
    for root, _, files in os.walk(run_dir):
        for f in files:
            rel = os.path.relpath(os.path.join(root, f), run_dir)
            if rel not in ("run.log", "summary.json"):
                with open(os.path.join(root, f), "rb") as fh:
                    out[rel] = fh.read()
    return out


def same_runs(a, b):
    names = sorted(os.listdir(os.path.join(a, "runs")))
    assert names == sorted(os.listdir(os.path.join(b, "runs")))
    for n in names:
        fa, fb = run_files(os.path.join(a, "runs", n)), run_files(os.path.join(b, "runs", n))
        assert "history.csv" in fa and sorted(fa) == sorted(fb), n
        for k in fa:
            assert fa[k] == fb[k], f"{n}/{k} differs between the local pool and Slurm"


@pytest.fixture(scope="module")
def local_dry(tmp_path_factory):
    """The dry-joint grid on the local pool: the reference for the Slurm runs."""
    out = str(tmp_path_factory.mktemp("local_dry"))
    rc, o, err = tools_cli("batch", SLIDING, *DRY_GRID, "--out-dir", out, "--jobs", "2")
    assert rc == 0, err
    return out


def submissions(out):
    with open(os.path.join(out, "slurm", "jobs.json")) as f:
        return json.load(f)["submissions"]


# ----------------------------------------------------------------------------------------------


def test_dry_run_is_a_job_script_sbatch_accepts(cluster, tmp_path):
    out = tmp_path / "b"
    rc, o, err = tools_cli("batch", SLIDING, *DRY_GRID, "--set", 'case.name="a b"', "--out-dir", out,
                     "--scheduler", "slurm", "--dry-run", "--time", "0:10:00", "--mem", "500M", "--partition", "debug",
                     "--cpus-per-task", "2", "--jobs", "1", "--sbatch-arg=--comment=fdem test")
    assert rc == 0, err
    assert not out.exists()  # nothing written, nothing submitted
    lines = o.splitlines()
    assert lines[0] == "#!/bin/bash"
    for directive in ("--array=0-1%1", "--cpus-per-task=2", "--time=0:10:00", "--mem=500M", "--partition=debug",
                      "--signal=B:TERM@120", f"--output={out}/slurm/out/%A_%a.out"):
        assert f"#SBATCH {directive}" in lines
    # the commands: the local pool's, with --threads = --cpus-per-task, shell-quoted
    cmds = [ln.split("CMD=(", 1)[1].rsplit(") ;;", 1)[0] for ln in lines if "CMD=(" in ln]
    b = batch.Batch(SLIDING, str(out), fdem_bin(), threads=2, fixed=[("case.name", '"a b"')])
    pts = [{"stages.2.until.value": v} for v in ("0.0003", "0.0005")]
    assert [shlex.split(c) for c in cmds] == [b.command(p, os.path.join(b.out, "runs", batch.run_name(p)))
                                             for p in pts]
    assert lines[-1] == f"#   sbatch --parsable '--comment=fdem test' {out}/slurm/array-1.sh"
    script = tmp_path / "job.sh"
    script.write_text(o)
    r = subprocess.run(["sbatch", "--test-only", "--comment=fdem test", str(script)], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0 and "to start at" in r.stderr, r.stderr


def test_batch_dry_run_prints_shell_quoted_commands(tmp_path):
    """Local pool --dry-run (issue 31): one command per run that a shell splits back into fdem's exact argv."""
    out = tmp_path / "b b"
    rc, o, err = tools_cli("batch", CANTILEVER, "--grid", 'case.description="x y",\'q"z\'', "--out-dir", out,
                           "--dry-run")
    assert rc == 0, err
    lines = o.splitlines()
    assert len(lines) == 2
    b = batch.Batch(CANTILEVER, str(out), fdem_bin(), threads=1)
    for line, v in zip(lines, ['"x y"', "'q\"z'"]):
        p = {"case.description": v}
        assert shlex.split(line) == b.command(p, os.path.join(b.out, "runs", batch.run_name(p)))
    assert not out.exists()


def test_validate_names_the_case_in_its_progress_lines(tmp_path):
    fam = tmp_path / "fam"
    fam.mkdir()
    for stem in ("wall_a", "wall_b"):
        (fam / f"{stem}.toml").write_text("[[stages]]\n  [[stages.supports]]\n  vx = 0.01\n")
    args = ["validate", fam, "--fdem", FAKE, "--out-dir", tmp_path / "out", "--rate-case", "wall_b", "--jobs", "1"]
    rc, o, err = tools_cli(*args)
    assert rc == 0, err
    for label in ("wall_a", "wall_b", "wall_b__half_rate"):
        assert f"\n  {label}: exit 0, status completed" in o
    rc, o, err = tools_cli(*args)
    assert rc == 0 and o.count("already completed, skipped") == 3 and "  wall_a: already completed, skipped" in o


def test_slurm_results_equal_the_local_pool(cluster, local_dry, tmp_path):
    out = str(tmp_path / "slurm")
    rc, o, err = tools_cli("batch", SLIDING, *DRY_GRID, "--out-dir", out, "--scheduler", "slurm", *POLL)
    assert rc == 0, o + err
    assert "slurm: submitted job" in o and "2 done, 0 running, 0 pending, 0 failed" in o
    assert table(out) == table(local_dry)
    assert all(r["status"] == "completed" and r["exit_code"] == "0" for r in table(out))
    same_runs(out, local_dry)
    # the same command again: nothing submitted, nothing run, same table
    rc, o, err = tools_cli("batch", SLIDING, *DRY_GRID, "--out-dir", out, "--scheduler", "slurm", *POLL)
    assert rc == 0 and "0 to submit" in o and len(submissions(out)) == 1
    assert [r["resumed"] for r in table(out)] == ["1", "1"]


def test_failing_run_reported_with_its_slurm_state(cluster, tmp_path):
    local, out = str(tmp_path / "local"), str(tmp_path / "slurm")
    rc_l, _, err_l = tools_cli("batch", CANTILEVER, *ELASTIC_GRID, "--out-dir", local, "--jobs", "2")
    rc, o, err = tools_cli("batch", CANTILEVER, *ELASTIC_GRID, "--out-dir", out, "--scheduler", "slurm", *POLL)
    assert rc_l == 2 and rc == 2
    assert "1 of 2 runs did not complete" in err
    bad = batch.run_name({"numerics.safety": "2.5"})
    job = submissions(out)[0]["job_id"]
    assert f"  {bad}: Slurm state FAILED (job {job}_1), fdem exit 2, status failed" in err
    assert "inverted" in err.split(f"last lines of {out}/logs/{bad}.log:", 1)[1]  # fdem's own error message
    assert table(out) == table(local)
    same_runs(out, local)
    with open(os.path.join(out, "slurm", "tasks.csv"), newline="") as f:
        states = {r["name"]: (r["slurm_state"], r["exit_code"]) for r in csv.DictReader(f)}
    good = batch.run_name({"numerics.safety": "0.8"})
    assert states[bad] == ("FAILED", "2") and states[good] == ("COMPLETED", "0")


def test_resume_after_scancel_submits_only_the_cancelled_run(cluster, local_dry, tmp_path):
    out = str(tmp_path / "slurm")
    args = ["batch", SLIDING, *DRY_GRID, "--out-dir", out, "--scheduler", "slurm", *POLL]
    rc, o, err = tools_cli(*args, "--no-wait")
    assert rc == 0 and "--no-wait" in o, err
    job = submissions(out)[0]["job_id"]
    r = subprocess.run(["scancel", f"{job}_1"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    # follow and collect: task 1 cancelled, the run did not complete
    rc, o, err = tools_cli(*args, "--collect")
    assert rc == 2, o + err
    cancelled = batch.run_name({"stages.2.until.value": "0.0005"})
    assert f"  {cancelled}: Slurm state CANCELLED (job {job}_1)" in err
    assert len(submissions(out)) == 1
    # resume: only the cancelled run is submitted again, then the table is the local pool's
    rc, o, err = tools_cli(*args)
    assert rc == 0, o + err
    subs = submissions(out)
    assert len(subs) == 2 and [t["name"] for t in subs[1]["tasks"]] == [cancelled]
    res = table(out)
    assert [r["resumed"] for r in res] == ["1", "0"]
    ref = table(local_dry)
    for r in res + ref:
        r.pop("resumed")
    assert res == ref
    same_runs(out, local_dry)


def test_sigterm_before_the_limit_then_restart_from_the_checkpoint(cluster, tmp_path):
    """sbatch --signal=B:TERM@S signals the job script; it passes SIGTERM on to the run, which stops with a
    checkpoint (the stand-in fdem writes one). The next call submits the run again and, since this fdem lists
    --restart in `run --help`, the task restarts from the run folder instead of starting over."""
    case = tmp_path / "case.toml"
    case.write_text("# fake\n")
    log = str(tmp_path / "calls.log")
    out = str(tmp_path / "b")
    env = {"FAKE_FDEM_LOG": log, "FAKE_FDEM_RESTART": "1"}
    args = ["batch", case, "--grid", "slow=60", "--out-dir", out, "--fdem", FAKE, "--scheduler", "slurm", *POLL]
    rc, o, err = tools_cli(*args, "--no-wait", env=env)
    assert rc == 0, err
    job = submissions(out)[0]["job_id"]
    run_dir = os.path.join(out, "runs", batch.run_name({"slow": "60"}))
    t0 = time.monotonic()
    while not os.path.exists(log) and time.monotonic() - t0 < 90:  # the run has started (it logs first)
        time.sleep(0.2)
    assert os.path.exists(log), "the task did not start within 90 s"
    r = subprocess.run(["scancel", "--batch", "--signal=TERM", f"{job}_0"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    rc, o, err = tools_cli(*args, "--collect", env=env)
    assert rc == 2
    assert f"Slurm state FAILED (job {job}_0), fdem exit 143, status interrupted" in err
    assert os.path.isfile(os.path.join(run_dir, "checkpoint.bin"))
    rc, o, err = tools_cli(*args, env=env)
    assert rc == 0, o + err
    with open(log) as f:
        calls = [json.loads(line) for line in f]
    assert len(calls) == 2 and "--restart" not in calls[0] and calls[1]["--restart"] == run_dir
    with open(os.path.join(out, "logs", batch.run_name({"slow": "60"}) + ".log")) as f:
        assert f.readline().rstrip().endswith(f"--restart {run_dir}")


def test_options_need_the_slurm_scheduler(tmp_path, cluster):
    case = tmp_path / "case.toml"
    case.write_text("# fake\n")
    rc, o, err = tools_cli("batch", case, "--grid", "a=1", "--fdem", FAKE, "--partition", "x")
    assert rc == 1 and "--partition is a Slurm option: add --scheduler slurm" in err
    rc, o, err = tools_cli("batch", case, "--grid", "a=1", "--fdem", FAKE, "--scheduler", "slurm", "--threads", "2")
    assert rc == 1 and "--cpus-per-task" in err
    rc, o, err = tools_cli("batch", case, "--grid", "a=1", "--fdem", FAKE, "--scheduler", "slurm", "--timeout", "5")
    assert rc == 1 and "--time" in err


def test_time_left_estimate():
    # finished in 10 and 14 s (mean 12); running for 4 and 20 s; 3 pending: (3 * 12 + 8 + 0) / 2 = 22 s
    assert slurm.time_left([10.0, 14.0], [4.0, 20.0], 3) == 22.0
    assert slurm.time_left([], [4.0], 3) is None and slurm.time_left([10.0], [], 0) is None
    assert slurm.time_left([10.0], [], 2) == 20.0  # nothing running yet: one at a time


def test_validate_and_study_through_slurm_equal_the_local_pool(cluster, tmp_path):
    """The other two commands on the same plumbing, with the stand-in fdem (instant runs, deterministic wall
    times): validate's report.csv and quasi_static.csv and study mesh's mesh_study.csv are the local pool's, byte
    for byte."""
    fam = tmp_path / "fam"
    fam.mkdir()
    for stem in ("wall_a", "wall_b"):
        (fam / f"{stem}.toml").write_text("[[stages]]\n  [[stages.supports]]\n  vx = 0.01\n")
    v = ["validate", fam, "--fdem", FAKE, "--rate-case", "all", "--set", "geometry.mesh_size=0.05"]
    rc, o, err = tools_cli(*v, "--out-dir", tmp_path / "v_local", "--jobs", "1")
    assert rc == 0, err
    rc, o, err = tools_cli(*v, "--out-dir", tmp_path / "v_slurm", "--scheduler", "slurm", *POLL)
    assert rc == 0, o + err
    subs = submissions(tmp_path / "v_slurm")
    assert len(subs) == 1 and [t["label"] for t in subs[0]["tasks"]] == [
        "wall_a", "wall_b", "wall_a__half_rate", "wall_b__half_rate"]
    for f in ("report.csv", "quasi_static.csv"):
        assert (tmp_path / "v_slurm" / f).read_bytes() == (tmp_path / "v_local" / f).read_bytes(), f
    case = tmp_path / "case.toml"
    case.write_text("# fake\n")
    m = ["study", "mesh", case, "--fdem", FAKE, "--sizes", "0.1,0.05"]
    rc, o, err = tools_cli(*m, "--out-dir", tmp_path / "m_local")
    assert rc == 0, err
    rc, o, err = tools_cli(*m, "--out-dir", tmp_path / "m_slurm", "--scheduler", "slurm", *POLL)
    assert rc == 0, o + err
    assert (tmp_path / "m_slurm" / "mesh_study.csv").read_bytes() == \
        (tmp_path / "m_local" / "mesh_study.csv").read_bytes()


def test_time_and_array_index_parsing():
    assert slurm.seconds("1-02:03:04") == 93784 and slurm.seconds("03:04") == 184 and slurm.seconds("1:02:03") == 3723
    assert slurm.seconds("UNLIMITED") is None and slurm.seconds("INVALID") is None
    assert slurm._indices("[4-6,9%2]") == [4, 5, 6, 9] and slurm._indices("3") == [3]
