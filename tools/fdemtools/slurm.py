"""`--scheduler slurm` for `batch`, `study` and `validate`: the runs of a grid as one Slurm job array.

One array task per run, each running the same `fdem run ...` command as the local pool (same run folder, same log
file), with `--threads T`, T = --cpus-per-task. The command then follows the array (squeue, sacct when the cluster
has accounting), collects the runs when every task has ended and writes the same results table as the local pool.

Files, in SLURM_DIR (BATCH/slurm for batch and study, OUT/slurm for validate):
  array-<k>.sh       the k-th job script submitted from this folder (the --dry-run output)
  jobs.json          every submission: job id, script, and per array index the run (name, run folder, log)
  out/<job>_<i>.out  Slurm's own output of a task (the run's output goes to its log, as with the local pool)
  exit/<job>_<i>     the exit code of the task's fdem run, written by the job script
Resume: a run whose summary.json says "completed" is never submitted again; a run whose task is still pending or
running is followed, not submitted again; every other run (failed, cancelled, timed out, never started) is submitted
again in a new array. A task that reaches its time limit gets SIGTERM --term-before seconds earlier (sbatch
--signal=B:TERM@S, passed on to fdem by the job script); fdem then stops cleanly (status "interrupted", exit 143).
When such a run folder holds a checkpoint (a file `checkpoint*`) and `fdem run --help` lists `--restart`, the task
restarts the run from it (`fdem run CASE ... --restart RUN_DIR`); otherwise the run is done again from the start.
The task decides this when it starts, so the job script is the same either way.
States: squeue -t all (the controller keeps finished tasks for MinJobAge, 300 s by default), else sacct, else the
exit file (COMPLETED for exit 0, FAILED otherwise), else CANCELLED when squeue still lists other tasks of the job
(a task cancelled while pending leaves no record of its own), else UNKNOWN.
"""
from __future__ import annotations

import datetime
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass, field

from .common import ToolError, write_json

CHECKPOINT_GLOB = "checkpoint*"  # a run folder holding a file of this name can be restarted (fdem run --restart)
ACTIVE = {"PENDING", "RUNNING", "CONFIGURING", "COMPLETING", "SUSPENDED", "REQUEUED", "REQUEUE_HOLD",
          "REQUEUE_FED", "RESIZING", "SIGNALING", "STAGE_OUT", "STOPPED", "RESV_DEL_HOLD"}
STARTED = {"RUNNING", "COMPLETING", "SIGNALING", "STAGE_OUT", "SUSPENDED", "STOPPED"}
LOG_TAIL = 8  # lines of a failed run's log in the report


@dataclass
class Options:
    """The sbatch settings of a submission and how the command follows it."""
    cpus_per_task: int = 1
    partition: str | None = None
    time: str | None = None
    mem: str | None = None
    account: str | None = None
    extra: list = field(default_factory=list)  # free sbatch arguments, given to sbatch before the script
    term_before: int = 120  # s: SIGTERM this long before the time limit (--signal=B:TERM@S)
    array_limit: int | None = None  # at most this many tasks at once (--array=...%N)
    job_name: str = "fdem"
    no_wait: bool = False
    collect_only: bool = False
    poll: float = 30.0  # s between two looks at the queue
    max_wait: float | None = None  # s: stop following after this long (the tasks go on)
    dry_run: bool = False


@dataclass
class Task:
    """One run: what the array task executes and where its results go."""
    name: str  # run name (batch's)
    label: str  # how progress and failure lines call it
    run_dir: str
    log: str
    cmd: list
    params: dict = field(default_factory=dict)
    prepare: object = None  # called before the task is submitted (batch: clears a stale run, writes its fingerprint)


SLURM_ONLY = ("partition", "time", "mem", "account", "sbatch_arg", "no_wait", "collect", "max_wait")


def add_arguments(p, dry_run: bool = False) -> None:
    """--scheduler and the Slurm options of a sub-command (batch, study mesh/speed, validate)."""
    g = p.add_argument_group("cluster", "run the grid as a Slurm job array instead of on the local cores "
                                        "(tools/slurm/README.md)")
    g.add_argument("--scheduler", choices=["local", "slurm"], default="local",
                   help="local: a process pool on this machine (default); slurm: one job array, one task per run")
    g.add_argument("--cpus-per-task", type=int, default=None,
                   help="slurm: cores per task, passed to fdem as --threads (default 1)")
    g.add_argument("--partition", help="slurm: partition (sbatch --partition)")
    g.add_argument("--time", help="slurm: time limit per task, e.g. 2:00:00 (sbatch --time)")
    g.add_argument("--mem", help="slurm: memory per task, e.g. 2G (sbatch --mem)")
    g.add_argument("--account", help="slurm: account to charge (sbatch --account)")
    g.add_argument("--sbatch-arg", action="append", metavar="ARG",
                   help="slurm: a further sbatch argument, e.g. --sbatch-arg=--qos=short (repeatable)")
    g.add_argument("--term-before", type=int, default=120, metavar="S",
                   help="slurm: SIGTERM to the run S seconds before the time limit, so it stops cleanly and "
                        "can restart from a checkpoint (default 120)")
    g.add_argument("--poll", type=float, default=30.0, metavar="S",
                   help="slurm: seconds between two looks at the queue (default 30)")
    g.add_argument("--max-wait", type=float, metavar="S",
                   help="slurm: stop following after S seconds with exit 1 (the tasks go on; the same command "
                        "later collects them)")
    g.add_argument("--no-wait", action="store_true",
                   help="slurm: submit and return; the same command later follows the array and collects")
    g.add_argument("--collect", action="store_true",
                   help="slurm: submit nothing; follow the arrays already submitted, then write the table")
    if dry_run:
        g.add_argument("--dry-run", action="store_true",
                       help="print the fdem commands (slurm: the job script and the sbatch command), run nothing")


def options_from_args(args, job_name: str) -> Options | None:
    """The Slurm options of a parsed command line; None for the local pool (then no Slurm option may be given)."""
    sched = getattr(args, "scheduler", "local")
    if sched != "slurm":
        given = [o for o in SLURM_ONLY if getattr(args, o, None)]
        if getattr(args, "cpus_per_task", None) is not None:
            given.append("cpus_per_task")
        if given:
            raise ToolError(f"--{given[0].replace('_', '-')} is a Slurm option: add --scheduler slurm")
        return None
    cpus = args.cpus_per_task if args.cpus_per_task is not None else 1
    if cpus < 1:
        raise ToolError(f"--cpus-per-task must be >= 1, got {cpus}")
    threads = getattr(args, "threads", 1)
    if threads not in (1, cpus):
        raise ToolError(f"--threads {threads} with --scheduler slurm: the threads of a run are --cpus-per-task "
                        f"({cpus}); give --cpus-per-task {threads}")
    if getattr(args, "timeout", None) is not None:
        raise ToolError("--timeout is for the local pool; on Slurm give the time limit with --time")
    if args.term_before < 0:
        raise ToolError(f"--term-before must be >= 0 s, got {args.term_before}")
    if not args.poll > 0:
        raise ToolError(f"--poll must be > 0 s, got {args.poll}")
    if args.max_wait is not None and not args.max_wait > 0:
        raise ToolError(f"--max-wait must be > 0 s, got {args.max_wait}")
    if args.no_wait and args.collect:
        raise ToolError("--no-wait and --collect exclude each other")
    jobs = getattr(args, "jobs", None)
    if jobs is not None and jobs < 1:
        raise ToolError(f"--jobs must be >= 1, got {jobs}")
    return Options(cpus_per_task=cpus, partition=args.partition, time=args.time, mem=args.mem, account=args.account,
                   extra=list(args.sbatch_arg or []), term_before=args.term_before, array_limit=jobs,
                   job_name=job_name, no_wait=args.no_wait, collect_only=args.collect, poll=args.poll,
                   max_wait=args.max_wait,
                   dry_run=bool(getattr(args, "dry_run", False)))


def job_name(prefix: str, out_dir: str) -> str:
    base = os.path.basename(os.path.normpath(out_dir))
    return re.sub(r"[^A-Za-z0-9_.+-]", "_", f"{prefix}-{base}")[:64]


# ----------------------------------------------------------------------------------------------
# The job script


def job_script(tasks: list, opts: Options, slurm_dir: str) -> str:
    """The sbatch script of one array over `tasks` (array index i runs tasks[i])."""
    n = len(tasks)
    array = f"0-{n - 1}" + (f"%{opts.array_limit}" if opts.array_limit else "")
    L = ["#!/bin/bash",
         f"#SBATCH --job-name={opts.job_name}",
         f"#SBATCH --array={array}",
         "#SBATCH --nodes=1",
         "#SBATCH --ntasks=1",
         f"#SBATCH --cpus-per-task={opts.cpus_per_task}",
         f"#SBATCH --output={os.path.join(slurm_dir, 'out', '%A_%a.out')}"]
    if opts.term_before > 0:
        L.append(f"#SBATCH --signal=B:TERM@{opts.term_before}")
    for key in ("partition", "time", "mem", "account"):
        v = getattr(opts, key)
        if v:
            L.append(f"#SBATCH --{key}={v}")
    L += ["",
          f"# fdem-tools: {n} fdem run(s), one per array task; written by `fdem-tools ... --scheduler slurm`.",
          "# Each task runs its fdem command with the output in the run's log (as the local pool does), passes",
          "# SIGTERM on to fdem (sbatch --signal above: fdem then stops cleanly before the time limit), restarts",
          f"# from a checkpoint when the run folder has one ({CHECKPOINT_GLOB}) and fdem knows --restart, and",
          "# writes fdem's exit code to the exit/ folder beside this script.",
          "set -u",
          f"EXIT_DIR={shlex.quote(os.path.join(slurm_dir, 'exit'))}",
          'case "${SLURM_ARRAY_TASK_ID:-}" in']
    for i, t in enumerate(tasks):
        L.append(f"  {i}) RUN={shlex.quote(t.run_dir)}")
        L.append(f"     LOG={shlex.quote(t.log)}")
        L.append(f"     CMD=({' '.join(shlex.quote(c) for c in t.cmd)}) ;;")
    L += ['  *) echo "fdem-tools: no run for array task \'${SLURM_ARRAY_TASK_ID:-}\'" >&2; exit 1 ;;',
          "esac",
          'mkdir -p "$(dirname "$LOG")" "$EXIT_DIR"',
          f'if compgen -G "$RUN/{CHECKPOINT_GLOB}" > /dev/null && '
          '"${CMD[0]}" run --help 2>&1 | grep -q -e --restart; then',
          '    CMD+=(--restart "$RUN")',
          "fi",
          "{ printf '$'; printf ' %q' \"${CMD[@]}\"; printf '\\n'; } > \"$LOG\"",
          'echo "fdem-tools: job ${SLURM_ARRAY_JOB_ID:-?} task ${SLURM_ARRAY_TASK_ID} on $(hostname), log $LOG"',
          '"${CMD[@]}" >> "$LOG" 2>&1 < /dev/null &',
          "pid=$!",
          "trap 'kill -TERM \"$pid\" 2> /dev/null' TERM INT",
          "rc=0",
          'wait "$pid" || rc=$?',
          'while kill -0 "$pid" 2> /dev/null; do  # wait returned for the trap: wait for fdem itself',
          '    rc=0',
          '    wait "$pid" || rc=$?',
          "done",
          'echo "$rc" > "$EXIT_DIR/${SLURM_ARRAY_JOB_ID:-0}_${SLURM_ARRAY_TASK_ID}"',
          'echo "fdem-tools: fdem exited with $rc"',
          'exit "$rc"']
    return "\n".join(L) + "\n"


def sbatch_command(opts: Options, script: str) -> list:
    return ["sbatch", "--parsable", *opts.extra, script]


# ----------------------------------------------------------------------------------------------
# Asking Slurm


def _tool(name: str) -> str:
    path = shutil.which(name)
    if not path:
        raise ToolError(f"'{name}' not found: --scheduler slurm needs the Slurm commands (run on a login node, or "
                        "start tools/slurm/local-cluster.sh and set SLURM_CONF)")
    return path


def _run(cmd: list, check: bool = True) -> subprocess.CompletedProcess:
    try:
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        raise ToolError(f"'{' '.join(cmd[:2])}' did not answer within 120 s") from None
    if check and r.returncode != 0:
        raise ToolError(f"{shlex.join(cmd)} failed (exit {r.returncode}): {r.stderr.strip() or r.stdout.strip()}")
    return r


def seconds(text: str) -> float | None:
    """Slurm's [D-]HH:MM:SS, MM:SS or MM:SS.mmm as seconds; None for anything else (INVALID, UNLIMITED)."""
    m = re.fullmatch(r"(?:(\d+)-)?(?:(\d+):)?(\d+):(\d+(?:\.\d+)?)", text.strip())
    if not m:
        return None
    d, h, mi, s = m.groups()
    return int(d or 0) * 86400 + int(h or 0) * 3600 + int(mi) * 60 + float(s)


def hms(s: float) -> str:
    s = int(round(s))
    return f"{s // 3600}:{s // 60 % 60:02d}:{s % 60:02d}"


def squeue_states(job: str) -> dict:
    """{array index: (state, elapsed s, reason)} of the tasks the controller still knows (pending, running, and
    finished ones for MinJobAge)."""
    r = _run([_tool("squeue"), "-h", "-r", "-t", "all", "-j", job, "-o", "%F|%K|%T|%M|%r"], check=False)
    if r.returncode != 0:
        if "Invalid job id" in r.stderr:
            return {}
        raise ToolError(f"squeue -j {job} failed (exit {r.returncode}): {r.stderr.strip()}")
    out = {}
    for line in r.stdout.splitlines():
        parts = line.strip().split("|")
        if len(parts) != 5 or parts[0] != job:
            continue
        for i in _indices(parts[1]):
            out[i] = (parts[2], seconds(parts[3]), parts[4])
    return out


def sacct_states(job: str) -> dict:
    """{array index: (state, elapsed s, exit code)} from the accounting database; {} when the cluster has none."""
    if not shutil.which("sacct"):
        return {}
    r = _run(["sacct", "-n", "-P", "-X", "-j", job, "--format=JobID,State,ElapsedRaw,ExitCode"], check=False)
    if r.returncode != 0:
        return {}
    out = {}
    for line in r.stdout.splitlines():
        parts = line.strip().split("|")
        if len(parts) != 4 or not parts[0].startswith(job + "_"):
            continue
        state = parts[1].split()[0] if parts[1].strip() else "UNKNOWN"
        try:
            el = float(parts[2])
        except ValueError:
            el = None
        for i in _indices(parts[0][len(job) + 1:]):
            out[i] = (state, el, parts[3])
    return out


def _indices(text: str) -> list:
    """'3' -> [3]; '[4-6,9%2]' -> [4, 5, 6, 9] (squeue's and sacct's pending array ranges)."""
    text = text.strip().strip("[]").split("%")[0]
    out = []
    for part in text.split(","):
        if re.fullmatch(r"\d+", part):
            out.append(int(part))
        elif re.fullmatch(r"\d+-\d+", part):
            a, b = map(int, part.split("-"))
            out.extend(range(a, b + 1))
    return out


# ----------------------------------------------------------------------------------------------
# Submissions and their tasks


class Submissions:
    """jobs.json of a Slurm folder: every array submitted from it."""

    def __init__(self, slurm_dir: str):
        self.dir = slurm_dir
        self.path = os.path.join(slurm_dir, "jobs.json")
        self.items = []
        if os.path.isfile(self.path):
            try:
                with open(self.path, encoding="utf-8") as f:
                    self.items = json.load(f)["submissions"]
            except (OSError, ValueError, KeyError, TypeError):
                raise ToolError(f"{self.path}: unreadable; move it away to start the Slurm bookkeeping afresh "
                                "(the run folders are kept)") from None

    def save(self):
        write_json(self.path, {"submissions": self.items})

    def latest(self, run_dir: str):
        """(job id, array index) of the latest submission of a run folder, or None."""
        for s in reversed(self.items):
            for t in s["tasks"]:
                if t["run_dir"] == run_dir:
                    return s["job_id"], t["index"]
        return None

    def next_script(self) -> str:
        return os.path.join(self.dir, f"array-{len(self.items) + 1}.sh")


class Follower:
    """Where each task of some jobs stands: squeue first, then sacct, then the exit files."""

    def __init__(self, slurm_dir: str, jobs: list):
        self.dir = slurm_dir
        self.jobs = sorted(set(jobs), key=lambda j: (len(j), j))
        self.sq = {}
        self.sa = {}

    def refresh(self, with_sacct: bool = False):
        self.sq = {j: squeue_states(j) for j in self.jobs}
        if with_sacct:
            self.sa = {j: sacct_states(j) for j in self.jobs}

    def exit_code(self, job: str, idx: int):
        p = os.path.join(self.dir, "exit", f"{job}_{idx}")
        try:
            with open(p) as f:
                return int(f.read().strip())
        except (OSError, ValueError):
            return None

    def state(self, job: str, idx: int) -> tuple:
        """(state, elapsed s or None)."""
        if idx in self.sq.get(job, {}):
            st, el, _ = self.sq[job][idx]
            return st, el
        if idx in self.sa.get(job, {}):
            st, el, _ = self.sa[job][idx]
            return st, el
        rc = self.exit_code(job, idx)
        if rc is not None:
            return ("COMPLETED" if rc == 0 else "FAILED"), None
        if self.sq.get(job):  # the controller knows the job but not this task, which never ended by itself:
            return "CANCELLED", None  # it was cancelled while pending (Slurm then keeps no record of the task)
        return "UNKNOWN", None


def tail(path: str, n: int = LOG_TAIL) -> list:
    try:
        with open(path, errors="replace") as f:
            lines = f.read().splitlines()
    except OSError:
        return []
    return [ln for ln in lines if ln.strip()][-n:]


def run_tasks(tasks: list, opts: Options, slurm_dir: str, is_finished, log=print) -> list | None:
    """Submits the tasks that need it as one array, follows everything, returns one record per task (name, params,
    run_dir, resumed, exit_code, slurm_state, job) in the order given, or None for --dry-run and --no-wait."""
    slurm_dir = os.path.abspath(slurm_dir)
    subs = Submissions(slurm_dir)
    finished = {t.run_dir: is_finished(t.run_dir) for t in tasks}
    if opts.dry_run:
        todo = [t for t in tasks if not finished[t.run_dir]]
        if not todo:
            print("# fdem-tools: every run of this grid has completed already; nothing to submit")
            return None
        script_path = subs.next_script()
        sys.stdout.write(job_script(todo, opts, slurm_dir))
        print(f"# fdem-tools --dry-run: nothing submitted. This script would be written to {script_path} and "
              "submitted with:")
        print("#   " + shlex.join(sbatch_command(opts, script_path)))
        return None

    # runs still queued or running from an earlier call are followed, not submitted again
    earlier = {t.run_dir: subs.latest(t.run_dir) for t in tasks if not finished[t.run_dir]}
    fol = Follower(slurm_dir, [ji[0] for ji in earlier.values() if ji])
    fol.refresh()
    queued = {rd for rd, ji in earlier.items() if ji and fol.state(*ji)[0] in ACTIVE}
    todo = [t for t in tasks if not finished[t.run_dir] and t.run_dir not in queued]
    n_done = sum(finished.values())
    log(f"slurm: {len(tasks)} runs, {n_done} completed already, {len(queued)} in the queue, "
        f"{len(todo)} to submit" + (" (--collect: submitting nothing)" if opts.collect_only and todo else ""))
    if todo and not opts.collect_only:
        job = submit(todo, opts, slurm_dir, subs, log)
        fol.jobs = sorted(set(fol.jobs) | {job}, key=lambda j: (len(j), j))
    if opts.no_wait:
        jobs = ", ".join(fol.jobs) or "none"
        log(f"slurm: not waiting (--no-wait); job(s) {jobs}. Run the same command again (from any login that sees "
            f"{slurm_dir}) to follow them and write the results table; add --collect to submit nothing.")
        return None
    where = {t.run_dir: subs.latest(t.run_dir) for t in tasks if not finished[t.run_dir]}
    follow(tasks, where, fol, opts, log)
    fol.refresh(with_sacct=True)
    recs = []
    for t in tasks:
        rec = {"name": t.name, "params": t.params, "run_dir": t.run_dir, "resumed": finished[t.run_dir],
               "label": t.label, "log": t.log}
        if finished[t.run_dir]:
            rec.update(exit_code=0, slurm_state="", job="")
            log(f"  {t.label}: already completed, skipped")
        elif where.get(t.run_dir):
            job, idx = where[t.run_dir]
            state, el = fol.state(job, idx)
            rec.update(exit_code=fol.exit_code(job, idx), slurm_state=state, job=f"{job}_{idx}", elapsed_s=el)
        else:  # --collect and never submitted
            rec.update(exit_code=None, slurm_state="NOT SUBMITTED", job="")
        recs.append(rec)
    write_tasks_csv(recs, slurm_dir)
    return recs


def submit(todo: list, opts: Options, slurm_dir: str, subs: Submissions, log) -> str:
    os.makedirs(os.path.join(slurm_dir, "out"), exist_ok=True)
    os.makedirs(os.path.join(slurm_dir, "exit"), exist_ok=True)
    for t in todo:
        if t.prepare is not None:
            t.prepare()
    script_path = subs.next_script()
    with open(script_path, "w", encoding="utf-8") as f:
        f.write(job_script(todo, opts, slurm_dir))
    os.chmod(script_path, 0o755)
    cmd = sbatch_command(opts, script_path)
    cmd[0] = _tool("sbatch")
    r = _run(cmd)
    job = r.stdout.strip().split(";")[0]
    if not re.fullmatch(r"\d+", job):
        raise ToolError(f"sbatch did not print a job id (output: '{r.stdout.strip()}')")
    subs.items.append({"job_id": job, "script": script_path,
                       "submitted": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                       "sbatch": shlex.join(cmd),
                       "tasks": [{"index": i, "name": t.name, "label": t.label, "run_dir": t.run_dir, "log": t.log}
                                 for i, t in enumerate(todo)]})
    subs.save()
    log(f"slurm: submitted job {job}: array of {len(todo)} task(s), {opts.cpus_per_task} CPU(s) each "
        f"({script_path})")
    return job


def follow(tasks: list, where: dict, fol: Follower, opts: Options, log) -> None:
    """Polls until no followed task is pending or running; a progress line when the counts change, at least every
    ten polls: done / running / pending / failed, elapsed since the follow started and an estimate of the time left
    (mean run time of the finished tasks times the work left, over the tasks running at once)."""
    followed = [where[t.run_dir] for t in tasks if where.get(t.run_dir)]
    if not followed:
        return
    t0 = time.monotonic()
    last, quiet = None, 0
    while True:
        fol.refresh()
        states = [fol.state(j, i) for j, i in followed]
        done = [el for st, el in states if st == "COMPLETED"]
        running = [el for st, el in states if st in STARTED]
        pending = sum(st in ACTIVE and st not in STARTED for st, _ in states)
        failed = len(states) - len(done) - len(running) - pending
        counts = (len(done), len(running), pending, failed)
        if counts != last or quiet >= 10:
            est = time_left([el for el in done if el is not None], running, pending)
            left = "" if est is None else f", about {hms(est)} left"
            log(f"slurm: job(s) {', '.join(fol.jobs)}: {counts[0]} done, {counts[1]} running, {counts[2]} pending, "
                f"{counts[3]} failed; elapsed {hms(time.monotonic() - t0)}{left}")
            last, quiet = counts, 0
        else:
            quiet += 1
        if not running and not pending:
            return
        if opts.max_wait is not None and time.monotonic() - t0 > opts.max_wait:
            raise ToolError(f"stopped following after {opts.max_wait:g} s (--max-wait) with {len(running)} task(s) "
                            f"running and {pending} pending in job(s) {', '.join(fol.jobs)}; they go on: run the "
                            "same command again (add --collect to submit nothing) to follow and collect them")
        time.sleep(opts.poll)


def time_left(done: list, running: list, pending: int) -> float | None:
    """Seconds left: with m the mean run time of the finished tasks, the work left is m per pending task plus
    m - elapsed (at least 0) per running one, shared by the tasks running at once. None before a task has finished
    or when nothing is left."""
    if not done or not (running or pending):
        return None
    m = sum(done) / len(done)
    work = pending * m + sum(max(m - (el or 0.0), 0.0) for el in running)
    return work / max(1, len(running))


def write_tasks_csv(recs: list, slurm_dir: str) -> None:
    from .common import write_csv
    rows = [[r["label"], r["name"], r.get("job", ""), r.get("slurm_state", ""),
             "" if r.get("exit_code") is None else r["exit_code"],
             "" if r.get("elapsed_s") is None else r["elapsed_s"], r["run_dir"]] for r in recs]
    write_csv(os.path.join(slurm_dir, "tasks.csv"),
              ["run", "name", "job", "slurm_state", "exit_code", "elapsed_s", "run_dir"], rows)


def report_failures(recs: list, slurm_dir: str, out=None) -> int:
    """Per run that did not complete: its Slurm state, fdem's exit code, the run's status and the last lines of its
    log (and of Slurm's own output of the task when that has anything). Returns how many."""
    out = out or sys.stderr
    bad = [r for r in recs if r.get("status") != "completed"]
    for r in bad:
        ec = r.get("exit_code")
        print(f"  {r['label']}: Slurm state {r.get('slurm_state') or '-'}"
              + (f" (job {r['job']})" if r.get("job") else "")
              + f", fdem exit {'-' if ec is None else ec}, status {r.get('status')}", file=out)
        lines = tail(r["log"])
        if lines:
            print(f"    last lines of {r['log']}:", file=out)
            for ln in lines:
                print("    | " + ln, file=out)
        if r.get("job"):
            so = os.path.join(slurm_dir, "out", r["job"] + ".out")
            extra = [ln for ln in tail(so) if not ln.startswith("fdem-tools: ")]
            if extra:
                print(f"    Slurm output {so}:", file=out)
                for ln in extra:
                    print("    | " + ln, file=out)
    return len(bad)
