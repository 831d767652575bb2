"""`batch`: a parameter grid of fdem runs executed in parallel on the local cores, resumable, with a results table.

Layout of a batch folder:
  batch.json            the case, the fixed settings and every grid point (name -> {key: value})
  runs/<name>/          one fdem run folder per grid point; <name> is made from the point's settings, so it is
                        the same after a restart whatever the order of the grid
  logs/<name>.log       fdem's output for that run
  results.csv           one row per grid point: settings, status, run time, size, peak load, reference error
  slurm/                with --scheduler slurm: job scripts, jobs.json, Slurm's task output (see slurm.py)
A run counts as finished when its summary.json says "completed"; a restarted batch skips those and runs the
others again (failed, interrupted or never started). Each grid value is passed verbatim to `fdem run --set
KEY=VALUE`, so it is a TOML value: 0.025, "name", [0.01, 0].
"""
from __future__ import annotations

import hashlib
import itertools
import json
import os
import re
import shlex
import subprocess
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor

from .common import REPO, ToolError, fdem_binary, read_summary, resolved_case, write_csv, write_json  # noqa: F401


def split_values(text: str) -> list:
    """Splits 'a,b,[1,2],"x,y"' at the commas that are not inside brackets, braces or quotes."""
    out, cur, depth, quote = [], [], 0, None
    for ch in text:
        if quote:
            cur.append(ch)
            if ch == quote:
                quote = None
            continue
        if ch in "\"'":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        if ch == "," and depth == 0:
            out.append("".join(cur).strip())
            cur = []
        else:
            cur.append(ch)
    if quote or depth:
        raise ToolError(f"unbalanced brackets or quotes in '{text}'")
    out.append("".join(cur).strip())
    if any(v == "" for v in out):
        raise ToolError(f"empty value in '{text}'")
    return out


def parse_assignment(text: str, what: str = "--grid") -> tuple:
    if "=" not in text:
        raise ToolError(f"{what} '{text}': expected KEY=VALUE")
    k, v = text.split("=", 1)
    k = k.strip()
    if not k or any(c.isspace() for c in k):
        raise ToolError(f"{what} '{text}': bad key '{k}'")
    return k, v.strip()


def expand_grid(grid: list) -> list:
    """[(key, [values])] -> list of {key: value} in product order (the first key varies slowest)."""
    keys = [k for k, _ in grid]
    if len(set(keys)) != len(keys):
        raise ToolError("a key appears twice in the grid")
    return [dict(zip(keys, combo)) for combo in itertools.product(*[vals for _, vals in grid])]


def run_name(params: dict) -> str:
    if not params:
        return "run"
    parts = []
    for k, v in params.items():
        short = k.split(".")[-1] if k.split(".")[-1] and not k.split(".")[-1].isdigit() else k
        parts.append(f"{short}={v}")
    name = "".join(ch if ch.isalnum() or ch in "-_.=+" else "_" for ch in "__".join(parts))
    digest = hashlib.sha1(json.dumps(sorted(params.items())).encode()).hexdigest()[:8]
    if len(name) > 80:
        name = name[:70]
    return f"{name}__{digest}"


# ----------------------------------------------------------------------------------------------
# Run fingerprints: what a run was made from. A completed run is reused only when its fingerprint matches the one
# the batch would give it now (tools/README.md "batch": Resumable).

FINGERPRINT = "fingerprint.json"
FINGERPRINT_VERSION = 2  # 2: the case hashed by the engine (fdem check --json); 1: the tools' own TOML reading
_FILE_HASHES: dict = {}  # (path, size, mtime_ns) -> sha256, so a large binary is read once per process
_EXPECTED: dict = {}     # run folder -> the fingerprint the current batch gives it (is_finished checks it)


def _sha256_file(path: str) -> str:
    st = os.stat(path)
    key = (os.path.abspath(path), st.st_size, st.st_mtime_ns)
    if key not in _FILE_HASHES:
        h = hashlib.sha256()
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                h.update(block)
        _FILE_HASHES[key] = h.hexdigest()
    return _FILE_HASHES[key]


def case_fingerprint(case: str, overrides: list, fdem: str) -> dict:
    """The case's part of a run fingerprint, from the engine (common.resolved_case): the hash of the case as resolved
    with the run's overrides (fdem check's case hash: the TOML tree after the overrides, so a comment or layout edit
    does not count) and the sha256 of every file the resolved case reads (the .geo script or .msh mesh of
    geometry.file), named relative to the case's folder. A case the engine refuses with these overrides has no hash
    but its message: the run fails the same way (and a completed run is not taken for it)."""
    here = os.path.dirname(os.path.abspath(case))
    try:
        rc = resolved_case(case, overrides, fdem=fdem)
    except ToolError as e:
        return {"case_hash": None, "error": str(e), "files": {}}
    files = {}
    for f in rc["resolved"].get("files") or []:
        p = f if os.path.isabs(f) else os.path.abspath(f)
        rel = os.path.relpath(p, here)
        if os.path.isfile(p):
            files[p if rel.startswith("..") else rel] = _sha256_file(p)
    return {"case_hash": rc["case_hash"], "files": files}


def build_fingerprint(fdem: str) -> dict:
    """The engine's part: the sha256 of the fdem executable (a rebuild that changes it changes the fingerprint), with
    the build id the executable embeds (fdem/version.hpp: the source tree's commit, which changes with every commit,
    also one that only touches documents) blanked out first, so that only a change of the code itself reruns runs."""
    try:
        with open(fdem, "rb") as f:
            data = f.read()
    except OSError:
        return {"path": fdem, "sha256": None}
    try:
        v = subprocess.run([fdem, "--version"], capture_output=True, text=True, timeout=30).stdout
        m = re.search(r"\(build ([^)]+)\)", v)
        if m:
            bid = m.group(1).encode()
            data = data.replace(bid, b"\0" * len(bid))
    except (OSError, subprocess.SubprocessError):
        pass
    return {"path": fdem, "sha256": hashlib.sha256(data).hexdigest()}


def fingerprint_changes(old: dict | None, new: dict) -> list:
    """What differs between a run's recorded fingerprint and the current one, as short phrases (empty: the same).
    None (no fingerprint recorded) is a difference: such a run cannot be checked."""
    if not isinstance(old, dict):
        return ["no fingerprint recorded (a run made before fdem-tools recorded them, or by another tool)"]
    if old.get("version") != new.get("version"):
        return [f"fingerprint of another fdem-tools (version {old.get('version')}, now {new.get('version')})"]
    out = []
    oc, nc = old.get("case") or {}, new["case"]
    oo, no = dict(map(tuple, old.get("overrides") or [])), dict(map(tuple, new["overrides"]))
    # the hash is of the case with its overrides: with the same overrides a different hash is an edited case file
    if oc.get("case_hash") != nc["case_hash"] and oo == no:
        out.append(f"case file ({new['case_file']} changed)")
    of, nf = oc.get("files") or {}, nc["files"]
    for name in sorted(set(of) | set(nf)):
        if of.get(name) != nf.get(name):
            out.append(f"file {name} " + ("changed" if name in of and name in nf else
                                          "now referenced" if name in nf else "no longer referenced"))
    diffs = []
    for k in sorted(set(oo) | set(no)):
        if oo.get(k) != no.get(k):
            diffs.append(f"{k}: {oo.get(k, '(not set)')} -> {no.get(k, '(not set)')}")
    if diffs:
        out.append("overrides (--set " + "; ".join(diffs) + ")")
    if (old.get("build") or {}).get("sha256") != new["build"]["sha256"]:
        out.append(f"build (the fdem executable {new['build']['path']} differs)")
    return out


def read_fingerprint(run_dir: str) -> dict | None:
    try:
        with open(os.path.join(run_dir, FINGERPRINT), encoding="utf-8") as f:
            v = json.load(f)
    except (OSError, ValueError):
        return None
    return v if isinstance(v, dict) else None


def stale_reason(run_dir: str) -> list:
    """Why a completed run folder does not match what its batch would run now (empty when it matches, or when no
    batch has registered it)."""
    want = _EXPECTED.get(os.path.abspath(run_dir))
    if want is None:
        return []
    return fingerprint_changes(read_fingerprint(run_dir), want)


def is_finished(run_dir: str) -> bool:
    """The run completed and, when a batch has registered what it would run there, from the same case, overrides and
    fdem build (its fingerprint)."""
    s = read_summary(run_dir)
    return bool(s) and s.get("status") == "completed" and not stale_reason(run_dir)


def reference_peak(summary: dict) -> float | None:
    """The case's reference peak load in N: `reference.peak_load_N` (run-folder contract), or a reference of
    quantity "peak" on the curve's load monitor (what the engine writes: monitor, quantity, value)."""
    ref = summary.get("reference")
    if not isinstance(ref, dict):
        return None
    try:
        if ref.get("peak_load_N") is not None:
            return abs(float(ref["peak_load_N"]))
        if ref.get("quantity") == "peak" and ref.get("monitor") == (summary.get("curve") or {}).get("y"):
            return abs(float(ref["value"]))
    except (TypeError, ValueError):
        return None
    return None


def curve_peak(summary: dict) -> float | None:
    """Largest absolute value of the load monitor named by the summary's curve, N."""
    try:
        y = summary["curve"]["y"]
        m = summary["monitors"][y]
        return max(abs(float(m["min"])), abs(float(m["max"])))
    except (KeyError, TypeError, ValueError):
        return None


class Batch:
    """Runs the points of a grid; thread-safe bookkeeping of the live processes so that an interruption can stop
    exactly the processes this batch started."""

    def __init__(self, case: str, out_dir: str, fdem: str, threads: int = 1, fixed: list | None = None,
                 log=print, timeout: float | None = None):
        if not os.path.isfile(case):
            raise ToolError(f"{case}: no such case file")
        self.case = os.path.abspath(case)
        self.out = os.path.abspath(out_dir)
        self.fdem = fdem
        self.threads = threads
        self.fixed = fixed or []
        self.log = log
        self.timeout = timeout
        self._build = None  # build_fingerprint(fdem), computed when first needed
        self._procs = {}
        self._lock = threading.Lock()
        self._stopping = False

    def fingerprint(self, params: dict) -> dict:
        """What a run of this grid point is made from: the case as the engine resolves it with the point's
        overrides (its hash and the files it reads), every --set (fixed, then the point's, as passed) and the fdem
        build (module section "Run fingerprints")."""
        overrides = [[k, v] for k, v in list(self.fixed) + list(params.items())]
        if self._build is None:
            self._build = build_fingerprint(self.fdem)
        return {"version": FINGERPRINT_VERSION, "case_file": self.case,
                "case": case_fingerprint(self.case, overrides, self.fdem), "overrides": overrides,
                "build": self._build}

    def register(self, name: str, params: dict, label: str | None = None, say: bool = True) -> tuple:
        """(run folder, fingerprint) of a grid point; from now on is_finished(run folder) also asks that the
        completed run there has this fingerprint. A completed run that does not is logged with what changed."""
        run_dir = os.path.join(self.out, "runs", name)
        fp = self.fingerprint(params)
        _EXPECTED[os.path.abspath(run_dir)] = fp
        s = read_summary(run_dir)
        if s and s.get("status") == "completed":
            changes = fingerprint_changes(read_fingerprint(run_dir), fp)
            if changes and say:
                self.log(f"  {label or name}: completed, but stale: " + "; ".join(changes) + "; run again")
        return run_dir, fp

    @staticmethod
    def prepare(run_dir: str, fp: dict) -> None:
        """Before a run starts in run_dir: when the folder holds a run of another fingerprint (or of none), its
        summary and checkpoints go (a failed start must not leave the old 'completed' summary behind, and a restart
        must not pick up the old checkpoint); then the new fingerprint is written."""
        os.makedirs(run_dir, exist_ok=True)
        if fingerprint_changes(read_fingerprint(run_dir), fp):
            import glob
            for f in [os.path.join(run_dir, "summary.json")] + glob.glob(os.path.join(run_dir, "checkpoint*")):
                if os.path.isfile(f):
                    os.remove(f)
        write_json(os.path.join(run_dir, FINGERPRINT), fp)

    def command(self, params: dict, run_dir: str) -> list:
        cmd = [self.fdem, "run", self.case, "--out", run_dir, "--threads", str(self.threads), "--quiet"]
        for k, v in list(self.fixed) + list(params.items()):
            cmd += ["--set", f"{k}={v}"]
        return cmd

    def _one(self, name: str, params: dict, label: str | None = None) -> dict:
        """Runs one grid point; label names it in the progress lines (default: its run name)."""
        label = label or name
        run_dir, fp = self.register(name, params, label)
        rec = {"name": name, "params": params, "run_dir": run_dir, "resumed": False}
        if is_finished(run_dir):
            rec.update(resumed=True, exit_code=0)
            self.log(f"  {label}: already completed, skipped")
            return rec
        if self._stopping:
            rec["exit_code"] = None
            return rec
        os.makedirs(os.path.join(self.out, "logs"), exist_ok=True)
        log_path = os.path.join(self.out, "logs", name + ".log")
        self.prepare(run_dir, fp)
        cmd = self.command(params, run_dir)
        t0 = time.monotonic()
        with open(log_path, "w") as lf:
            lf.write("$ " + shlex.join(cmd) + "\n")
            lf.flush()
            try:
                p = subprocess.Popen(cmd, stdout=lf, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
            except OSError as e:
                raise ToolError(f"cannot start {self.fdem}: {e.strerror}") from None
            with self._lock:
                self._procs[name] = p
            try:
                rc = p.wait(timeout=self.timeout)
            except subprocess.TimeoutExpired:
                p.kill()
                rc = p.wait()
                lf.write(f"\nfdem-tools: killed after {self.timeout} s\n")
            finally:
                with self._lock:
                    self._procs.pop(name, None)
        rec["exit_code"] = rc
        rec["elapsed_s"] = time.monotonic() - t0
        s = read_summary(run_dir) or {}
        self.log(f"  {label}: exit {rc}, status {s.get('status', 'no summary')} ({rec['elapsed_s']:.1f} s)"
                 + ("" if rc == 0 else f", log {log_path}"))
        return rec

    def stop(self):
        """Terminates the fdem processes this batch started (each by its own handle)."""
        self._stopping = True
        with self._lock:
            procs = list(self._procs.values())
        for p in procs:
            if p.poll() is None:
                p.terminate()
        for p in procs:
            try:
                p.wait(timeout=10)
            except subprocess.TimeoutExpired:
                p.kill()

    def task(self, name: str, params: dict, label: str | None = None):
        """The run of one grid point as a Slurm array task (same command, run folder and log as _one)."""
        from .slurm import Task
        run_dir, fp = self.register(name, params, label)
        return Task(name=name, label=label or name, run_dir=run_dir,
                    log=os.path.join(self.out, "logs", name + ".log"), cmd=self.command(params, run_dir),
                    params=params, prepare=lambda: self.prepare(run_dir, fp))

    def run(self, points: list, jobs: int = 1, grid: list | None = None, slurm=None) -> list | None:
        """Runs the grid on the local pool, or with slurm (slurm.Options) as a job array: then None when the
        options say not to wait (--no-wait, --dry-run)."""
        names = [run_name(p) for p in points]
        if len(set(names)) != len(names):
            raise ToolError("two grid points give the same run name (repeated values?)")
        if slurm is not None and slurm.dry_run:  # prints the job script, writes nothing
            from .slurm import run_tasks
            return run_tasks([self.task(n, p) for n, p in zip(names, points)], slurm,
                             os.path.join(self.out, "slurm"), is_finished, self.log)
        os.makedirs(self.out, exist_ok=True)
        manifest = {"case": self.case, "fdem": self.fdem, "threads": self.threads,
                    "fixed": [f"{k}={v}" for k, v in self.fixed], "grid": grid or [],
                    "runs": [{"name": n, "params": p, "fingerprint": self.fingerprint(p)}
                             for n, p in zip(names, points)]}
        write_json(os.path.join(self.out, "batch.json"), manifest)
        if slurm is not None:
            from .slurm import run_tasks
            recs = run_tasks([self.task(n, p) for n, p in zip(names, points)], slurm,
                             os.path.join(self.out, "slurm"), is_finished, self.log)
            return None if recs is None else [collect(r) for r in recs]
        for n, p in zip(names, points):
            self.register(n, p, say=False)
        todo = sum(not is_finished(os.path.join(self.out, "runs", n)) for n in names)
        self.log(f"batch: {len(points)} runs, {len(points) - todo} already completed (same case, overrides and "
                 f"build), {todo} to run "
                 f"({jobs} at a time, {self.threads} thread(s) each) in {self.out}")
        ex = ThreadPoolExecutor(max_workers=max(1, jobs))
        try:
            futures = [ex.submit(self._one, n, p) for n, p in zip(names, points)]
            recs = [f.result() for f in futures]
        except BaseException:  # interrupted: stop our runs; they are redone on the next start
            self.stop()
            ex.shutdown(wait=True, cancel_futures=True)
            raise
        ex.shutdown(wait=True)
        return [collect(r) for r in recs]


def collect(rec: dict) -> dict:
    """Adds what the run's summary says to a batch record."""
    s = read_summary(rec["run_dir"]) or {}
    rec["status"] = s.get("status", "not run" if rec.get("exit_code") is None else "no summary")
    rec["message"] = s.get("message", "")
    for k in ("wall_time_s", "cpu_time_s", "n_triangles", "n_nodes", "dt", "steps", "threads"):
        rec[k] = s.get(k)
    # a run that did not complete has no result: its peak so far is not tabulated as one (the status says why)
    rec["peak_load_N"] = curve_peak(s) if rec["status"] == "completed" else None
    ref = reference_peak(s)
    rec["reference_peak_N"] = ref
    rec["reference_error"] = (abs(rec["peak_load_N"] - ref) / abs(ref)
                              if ref and rec["peak_load_N"] is not None else None)
    rec["summary"] = s
    return rec


def results_table(recs: list, path: str) -> str:
    keys = []
    for r in recs:
        for k in r["params"]:
            if k not in keys:
                keys.append(k)
    header = keys + ["name", "status", "exit_code", "resumed", "wall_time_s", "cpu_time_s", "n_triangles", "dt", "steps",
                     "peak_load_kN", "reference_peak_kN", "reference_error"]
    rows = []
    for r in recs:
        kn = lambda v: v / 1e3 if v is not None else None  # noqa: E731
        rows.append([r["params"].get(k, "") for k in keys] +
                    [r["name"], r["status"], r.get("exit_code"), int(r["resumed"]), r.get("wall_time_s"),
                     r.get("cpu_time_s"), r.get("n_triangles"), r.get("dt"), r.get("steps"), kn(r.get("peak_load_N")),
                     kn(r.get("reference_peak_N")), r.get("reference_error")])
    write_csv(path, header, [["" if v is None else v for v in row] for row in rows])
    return format_table(header, rows)


def format_table(header: list, rows: list) -> str:
    def f(v):
        if v is None or v == "":
            return "-"
        if isinstance(v, float):
            return f"{v:.4g}"
        return str(v)
    cells = [[f(v) for v in r] for r in rows]
    widths = [max([len(h)] + [len(c[i]) for c in cells]) for i, h in enumerate(header)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(header, widths))]
    lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths)) for r in cells]
    return "\n".join(lines)


def default_jobs(threads: int) -> int:
    return max(1, (os.cpu_count() or 1) // max(1, threads))


def cmd_batch(args):
    grid = []
    for g in args.grid or []:
        k, v = parse_assignment(g)
        grid.append((k, split_values(v)))
    if not grid:
        raise ToolError("no --grid KEY=V1,V2,... given")
    fixed = [parse_assignment(s, "--set") for s in args.set or []]
    points = expand_grid(grid)
    out = args.out_dir or os.path.join("runs", "batch_" + os.path.splitext(os.path.basename(args.case))[0])
    from .slurm import options_from_args, job_name, report_failures
    slurm = options_from_args(args, job_name("fdem", out))
    threads = slurm.cpus_per_task if slurm else args.threads
    if args.dry_run and not slurm:
        print_commands(Batch(args.case, out, fdem_binary(args.fdem, must_exist=False), threads=threads, fixed=fixed),
                       points)
        return 0
    b = Batch(args.case, out, fdem_binary(args.fdem, must_exist=not args.dry_run), threads=threads, fixed=fixed,
              timeout=args.timeout)
    recs = b.run(points, jobs=args.jobs or default_jobs(args.threads), grid=[[k, v] for k, v in grid], slurm=slurm)
    if recs is None:  # submitted without waiting, or a dry run
        return 0
    table = results_table(recs, os.path.join(b.out, "results.csv"))
    print(table)
    print(f"wrote {os.path.join(b.out, 'results.csv')}")
    failed = [r for r in recs if r["status"] != "completed"]
    if failed:
        print(f"fdem-tools batch: {len(failed)} of {len(recs)} runs did not complete "
              f"({'see logs/' if not slurm else 'Slurm state and log of each below'}); "
              "run the same command again to retry them", file=sys.stderr)
        if slurm:
            report_failures(recs, os.path.join(b.out, "slurm"))
        return 2
    return 0


def print_commands(b: Batch, points: list) -> None:
    """--dry-run on the local pool: one shell-quoted fdem command per run (copy-paste ready)."""
    for p in points:
        name = run_name(p)
        print(shlex.join(b.command(p, os.path.join(b.out, "runs", name))))


def add_parser(sub):
    p = sub.add_parser("batch", help="run a parameter grid of fdem runs in parallel, resumable",
                       description="Expands a parameter grid (any case key, passed as fdem run --set KEY=VALUE) into "
                                   "fdem runs executed in parallel on the local cores. Restarting the same command "
                                   "skips the runs whose summary.json says completed. Ends with a results table "
                                   "(results.csv).")
    p.add_argument("case", metavar="CASE.toml", help="case file")
    p.add_argument("--grid", action="append", metavar="KEY=V1,V2,...",
                   help="a grid dimension: dotted case key and comma-separated TOML values (repeatable)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="a fixed setting for every run (repeatable)")
    p.add_argument("--out-dir", help="batch folder (default runs/batch_<case>)")
    p.add_argument("--jobs", type=int, help="runs at a time (default: cores / threads)")
    p.add_argument("--threads", type=int, default=1, help="OpenMP threads per run (default 1)")
    p.add_argument("--fdem", help="fdem executable (default: $FDEM_BIN, else build/fdem/fdem)")
    p.add_argument("--timeout", type=float, help="kill a run after this many seconds")
    p.add_argument("--dry-run", action="store_true",
                   help="print the fdem command of every run, shell-quoted (with --scheduler slurm: the job script "
                        "and the sbatch command), run nothing")
    from .slurm import add_arguments
    add_arguments(p)
    p.set_defaults(func=cmd_batch)
