"""`validate`: runs a family of validation cases (a folder of case files) and writes report.md + report.csv.

Per case: peak load and displacement at peak (of the case's load-displacement curve, in the last stage, from
its start), initial stiffness (least-squares line through the origin up to 40 % of the peak, as `eeep`), error
against the experiment and against the published FDEM (from the family's reference.csv, else the case's
[reference]), triangles, steps, wall time, and the numerical settings read from the case file with the --set
overrides applied (mesh size, loading rate, local damping, penalties and stiffnesses, time step).
Quasi-static check (FORMULATION §4): one case is run again with its loading rate halved; the relative change of the
peak load is reported (the acceptance limit is 2 %).

Reference file (optional) FAMILY/reference.csv: one row per experiment with a column `cases` listing the case file
stems it applies to (space separated), `experiment_kN`, and the published predictions in `*_kN` columns; the column
compared as "published FDEM" is --published-column (default fdem_k25_kN).
Runs go through the batch machinery, so the command is resumable: completed runs are not run again.
"""
from __future__ import annotations

import csv
import glob
import os
import sys
import time
import tomllib
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from .batch import Batch, collect, default_jobs, fdem_binary, parse_assignment, run_name
from .common import ToolError, load_curve, load_run, write_csv

QS_LIMIT = 0.02  # the peak may change by less than this when the rate is halved


# ----------------------------------------------------------------------------------------------
# Case files: the settings as fdem reads them (TOML + --set overrides)


def parse_value(text: str):
    """A --set value as fdem parses it: TOML, or a bare word as a string."""
    try:
        return tomllib.loads("v = " + text)["v"]
    except tomllib.TOMLDecodeError:
        return text


def apply_set(tree: dict, key: str, text: str) -> None:
    cur = tree
    parts = key.split(".")
    for p in parts[:-1]:
        if isinstance(cur, list):
            cur = cur[int(p)]
        else:
            cur = cur.setdefault(p, {})
    last = parts[-1]
    if isinstance(cur, list):
        cur[int(last)] = parse_value(text)
    else:
        cur[last] = parse_value(text)


def read_case(path: str, sets: list | None = None) -> dict:
    try:
        with open(path, "rb") as f:
            tree = tomllib.load(f)
    except (OSError, tomllib.TOMLDecodeError) as e:
        raise ToolError(f"{path}: cannot read the case file ({e})") from None
    for k, v in sets or []:
        try:
            apply_set(tree, k, v)
        except (KeyError, IndexError, ValueError, TypeError):
            raise ToolError(f"--set {k}={v}: no such place in {path}") from None
    return tree


def rate_key(tree: dict) -> tuple:
    """(dotted key, value) of the loading rate: the last stage's non-zero prescribed velocity (vx or vy), else the
    rate of its cyclic protocol."""
    stages = tree.get("stages") or []
    for si in range(len(stages) - 1, -1, -1):
        for i, sup in enumerate(stages[si].get("supports") or []):
            for comp in ("vx", "vy"):
                if isinstance(sup.get(comp), (int, float)) and sup[comp] != 0:
                    return f"stages.{si}.supports.{i}.{comp}", float(sup[comp])
            cyc = sup.get("cyclic")
            if isinstance(cyc, dict) and isinstance(cyc.get("rate"), (int, float)):
                return f"stages.{si}.supports.{i}.cyclic.rate", float(cyc["rate"])
    return None, None


def numerical_settings(tree: dict) -> dict:
    """The settings the issue asks to report, as text per field (same order for every case)."""
    geo = tree.get("geometry") or {}
    out = {"mesh_size_m": geo.get("mesh_size", "")}
    for k in ("mesh_size_beam", "mesh_size_base"):
        if k in geo:
            out[k + "_m"] = geo[k]
    key, rate = rate_key(tree)
    out["loading_rate_m_s"] = rate if rate is not None else ""
    out["local_damping"] = " / ".join(str(s.get("local_damping", 0)) for s in tree.get("stages") or [])
    pens = []
    for name, m in (tree.get("materials") or {}).items():
        fr = m.get("fracture") if isinstance(m, dict) else None
        if isinstance(fr, dict) and "penalty" in fr:
            pens.append(f"{name} p_j={fr['penalty']:g} Pa")
    for itf in tree.get("interfaces") or []:
        regs = "/".join(itf.get("regions", []))
        for k, unit in (("normal_penalty", "Pa"), ("tangential_penalty", "Pa"), ("normal_stiffness", "Pa/m"),
                        ("shear_stiffness", "Pa/m"), ("penalty", "Pa")):
            if k in itf:
                pens.append(f"{regs} {k}={itf[k]:g} {unit}")
    out["penalties"] = "; ".join(pens)
    num = tree.get("numerics") or {}
    out["dt_setting"] = f"dt={num['dt']:g} s" if "dt" in num else f"safety={num.get('safety', 0.8)}"
    return out


# ----------------------------------------------------------------------------------------------
# Reference data


def read_reference(family: str) -> list:
    p = os.path.join(family, "reference.csv")
    if not os.path.isfile(p):
        return []
    with open(p, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))


def reference_for(rows: list, stem: str) -> dict:
    for r in rows:
        if stem in (r.get("cases") or "").split():
            return r
    return {}


def _float(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


# ----------------------------------------------------------------------------------------------
# Results of one run


def curve_metrics(run_dir: str) -> dict:
    """Peak |load| (N), displacement at peak (m, from the start of the stage) and initial stiffness (N/m) of the
    load-displacement curve in the run's last stage (the loading after precompression)."""
    run = load_run(run_dir, allow_unfinished=True)
    last = None
    if run.history is not None and run.history.has("stage") and len(run.history):
        last = int(np.max(run.history.numeric("stage")))
    c = load_curve(run_dir, None, None, "m", "N", last, True)
    x, y = np.asarray(c.x, float), np.asarray(c.y, float)
    if len(x) == 0:
        raise ToolError(f"{run_dir}: empty curve")
    x = x - x[0]
    i = int(np.argmax(np.abs(y)))
    peak = float(abs(y[i]))
    d_peak = float(abs(x[i]))
    # initial stiffness: least-squares line through the origin of the ascending branch up to 40 % of the peak
    j = i
    for k in range(i + 1):
        if abs(y[k]) > 0.4 * peak:
            j = k
            break
    xs, ys = np.abs(x[: j + 1]), np.abs(y[: j + 1])
    k0 = float(np.dot(xs, ys) / np.dot(xs, xs)) if np.dot(xs, xs) > 0 else float("nan")
    return {"peak_load_N": peak, "disp_at_peak_m": d_peak, "initial_stiffness_N_m": k0}


def rel(a, b):
    if a is None or b in (None, 0):
        return None
    return (a - b) / abs(b)


# ----------------------------------------------------------------------------------------------


def family_cases(family: str, pattern: str) -> list:
    if not os.path.isdir(family):
        raise ToolError(f"{family}: no such family folder")
    files = sorted(glob.glob(os.path.join(family, pattern)))
    if not files:
        raise ToolError(f"{family}: no case files matching '{pattern}'")
    return files


def fmt(v, nd=4):
    if v is None or v == "":
        return "-"
    if isinstance(v, float):
        if np.isnan(v):
            return "-"
        return f"{v:.{nd}g}"
    return str(v)


def pct(v):
    return "-" if v is None else f"{100 * v:+.1f} %"


def run_family(args) -> int:
    family = os.path.normpath(args.family)
    cases = family_cases(family, args.glob)
    fixed = [parse_assignment(s, "--set") for s in args.set or []]
    out = os.path.abspath(args.out_dir or os.path.join("runs", "validate_" + os.path.basename(family)))
    fdem = fdem_binary(args.fdem)
    refs = read_reference(family)
    trees = {c: read_case(c, fixed) for c in cases}

    # the tasks: every case once, plus the quasi-static rerun at half the rate
    tasks = []
    for c in cases:
        stem = os.path.splitext(os.path.basename(c))[0]
        tasks.append((stem, Batch(c, os.path.join(out, stem), fdem, threads=args.threads, fixed=fixed,
                                  log=lambda m: print(m, flush=True)), {}))
    qs = None
    if not args.no_rate_check:
        qs_case = next((c for c in cases if os.path.splitext(os.path.basename(c))[0] == args.rate_case), None) \
            if args.rate_case else cases[0]
        if qs_case is None:
            raise ToolError(f"--rate-case {args.rate_case}: no such case in {family}")
        key, rate = (args.rate_key, None) if args.rate_key else rate_key(trees[qs_case])
        if args.rate_key:
            tree = trees[qs_case]
            try:
                cur = tree
                for p in key.split("."):
                    cur = cur[int(p)] if isinstance(cur, list) else cur[p]
                rate = float(cur)
            except (KeyError, IndexError, ValueError, TypeError):
                raise ToolError(f"--rate-key {key}: no such number in {qs_case}") from None
        if key is None:
            raise ToolError(f"{qs_case}: no prescribed velocity in its stages; give --rate-key or --no-rate-check")
        stem = os.path.splitext(os.path.basename(qs_case))[0]
        qs = {"case": stem, "key": key, "rate": rate, "half": rate / 2}
        tasks.append((stem + "__half_rate", Batch(qs_case, os.path.join(out, stem), fdem, threads=args.threads,
                                                   fixed=fixed, log=lambda m: print(m, flush=True)),
                      {key: repr(rate / 2)}))

    print(f"validate: {len(cases)} cases of {family}{' + 1 half-rate rerun' if qs else ''}, "
          f"{args.jobs} at a time, {args.threads} thread(s) each, in {out}", flush=True)
    for _, b, _ in tasks:
        os.makedirs(b.out, exist_ok=True)
    t0 = time.monotonic()
    ex = ThreadPoolExecutor(max_workers=max(1, args.jobs))
    try:
        futs = [ex.submit(b._one, run_name(p), p) for _, b, p in tasks]
        recs = [collect(f.result()) for f in futs]
    except BaseException:
        for _, b, _ in tasks:
            b.stop()
        ex.shutdown(wait=True, cancel_futures=True)
        raise
    ex.shutdown(wait=True)

    rows = []
    by_task = {}
    for (label, b, p), rec in zip(tasks, recs):
        m = {}
        if rec["status"] in ("completed", "failed", "running") and os.path.isfile(os.path.join(rec["run_dir"], "history.csv")):
            try:
                m = curve_metrics(rec["run_dir"])
            except ToolError as e:
                m = {"note": str(e)}
        by_task[label] = (rec, m)
    for c in cases:
        stem = os.path.splitext(os.path.basename(c))[0]
        rec, m = by_task[stem]
        ref = reference_for(refs, stem)
        exp_N = _float(ref.get("experiment_kN"))
        exp_N = exp_N * 1e3 if exp_N is not None else rec.get("reference_peak_N")
        pub = _float(ref.get(args.published_column))
        pub_N = pub * 1e3 if pub is not None else None
        peak = m.get("peak_load_N")
        row = {"case": stem, "status": rec["status"],
               "peak_load_kN": peak / 1e3 if peak is not None else None,
               "disp_at_peak_mm": m["disp_at_peak_m"] * 1e3 if "disp_at_peak_m" in m else None,
               "initial_stiffness_kN_mm": m["initial_stiffness_N_m"] / 1e6 if "initial_stiffness_N_m" in m else None,
               "experiment_kN": exp_N / 1e3 if exp_N else None, "error_vs_experiment": rel(peak, exp_N),
               "published_fdem_kN": pub_N / 1e3 if pub_N else None, "error_vs_published_fdem": rel(peak, pub_N),
               "triangles": rec.get("n_triangles"), "steps": rec.get("steps"), "wall_time_s": rec.get("wall_time_s"),
               "dt_s": rec.get("dt")}
        row.update(numerical_settings(trees[c]))
        rows.append(row)

    qs_row = None
    if qs:
        full = by_task[qs["case"]][1].get("peak_load_N")
        half = by_task[qs["case"] + "__half_rate"][1].get("peak_load_N")
        change = rel(half, full)
        qs_row = dict(qs, peak_full_kN=full / 1e3 if full else None, peak_half_kN=half / 1e3 if half else None,
                      change=change, quasi_static=None if change is None else abs(change) < QS_LIMIT,
                      status_half=by_task[qs["case"] + "__half_rate"][0]["status"])

    header = list(rows[0].keys())
    write_csv(os.path.join(out, "report.csv"), header, [["" if r[k] is None else r[k] for k in header] for r in rows])
    md = report_markdown(family, rows, qs_row, fixed, args, time.monotonic() - t0)
    with open(os.path.join(out, "report.md"), "w", encoding="utf-8") as f:
        f.write(md)
    print(md)
    print(f"wrote {os.path.join(out, 'report.md')}, {os.path.join(out, 'report.csv')}")
    bad = [r for r in rows if r["status"] != "completed"]
    if qs_row and qs_row["status_half"] != "completed":
        bad.append(qs_row)
    if bad:
        print(f"fdem-tools validate: {len(bad)} run(s) did not complete (see the logs/ of each case); "
              "run the same command again to retry them", file=sys.stderr)
        return 2
    return 0


def report_markdown(family, rows, qs_row, fixed, args, elapsed) -> str:
    L = [f"# Validation report: {family}", ""]
    L.append(f"Cases: {len(rows)} (pattern `{args.glob}`); overrides: "
             + (", ".join(f"`{k}={v}`" for k, v in fixed) if fixed else "none")
             + f"; {args.threads} thread(s) per run; published FDEM column `{args.published_column}`.")
    L.append("")
    L.append("| case | status | peak (kN) | disp. at peak (mm) | K0 (kN/mm) | experiment (kN) | error | published FDEM (kN) "
             "| error vs FDEM | triangles | steps | wall time (s) |")
    L.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        L.append(f"| {r['case']} | {r['status']} | {fmt(r['peak_load_kN'])} | {fmt(r['disp_at_peak_mm'])} | "
                 f"{fmt(r['initial_stiffness_kN_mm'])} | {fmt(r['experiment_kN'])} | {pct(r['error_vs_experiment'])} | "
                 f"{fmt(r['published_fdem_kN'])} | {pct(r['error_vs_published_fdem'])} | {fmt(r['triangles'])} | "
                 f"{fmt(r['steps'])} | {fmt(r['wall_time_s'], 3)} |")
    errs = [abs(r["error_vs_experiment"]) for r in rows if r["error_vs_experiment"] is not None]
    if errs:
        L += ["", f"Mean absolute error against the experiments: {100 * sum(errs) / len(errs):.1f} % over {len(errs)} "
                  f"case(s); largest {100 * max(errs):.1f} %."]
    L += ["", "## Numerical settings", ""]
    keys = [k for k in rows[0] if k in ("mesh_size_m", "mesh_size_beam_m", "mesh_size_base_m", "loading_rate_m_s",
                                         "local_damping", "penalties", "dt_setting")]
    L.append("| case | " + " | ".join(keys) + " | dt used (s) |")
    L.append("|---|" + "---|" * (len(keys) + 1))
    for r in rows:
        L.append(f"| {r['case']} | " + " | ".join(fmt(r.get(k)) for k in keys) + f" | {fmt(r['dt_s'])} |")
    same = all(all(r.get(k) == rows[0].get(k) for r in rows) for k in keys if k != "penalties")
    L += ["", "Mesh size, rate, damping and time-step setting are " + ("the same for every case." if same else
                                                                     "NOT the same for every case (see the table).")]
    L += ["", "## Quasi-static check", ""]
    if qs_row is None:
        L.append("Not run (--no-rate-check).")
    else:
        L.append(f"Case `{qs_row['case']}` run again with `{qs_row['key']}` = {qs_row['half']:g} (half of "
                 f"{qs_row['rate']:g}): peak {fmt(qs_row['peak_full_kN'])} kN at the full rate, "
                 f"{fmt(qs_row['peak_half_kN'])} kN at half the rate ({qs_row['status_half']}); change "
                 f"{pct(qs_row['change'])}; limit {100 * QS_LIMIT:g} %: "
                 + ("-" if qs_row["quasi_static"] is None else ("quasi-static" if qs_row["quasi_static"] else
                                                                 "NOT quasi-static")) + ".")
    L += ["", f"Elapsed: {elapsed:.1f} s.", ""]
    return "\n".join(L)


def cmd_validate(args):
    if args.jobs is None:
        args.jobs = default_jobs(args.threads)
    return run_family(args)


def add_parser(sub):
    p = sub.add_parser("validate", help="run a family of validation cases and write report.md + report.csv",
                       description="Runs every case file of FAMILY_DIR (resumable, through the batch machinery), "
                                   "then writes report.md and report.csv: peak load, displacement at peak, initial "
                                   "stiffness, errors against the experiment and the published FDEM, size, steps, "
                                   "wall time and numerical settings per case, and a quasi-static check (one case "
                                   "rerun at half the loading rate).")
    p.add_argument("family", metavar="FAMILY_DIR", help="folder of case files (e.g. cases/lourenco2005)")
    p.add_argument("--glob", default="*.toml", help="case files to run (default *.toml)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="a setting for every run (repeatable)")
    p.add_argument("--out-dir", help="report folder (default runs/validate_<family>)")
    p.add_argument("--jobs", type=int, help="runs at a time (default: cores / threads)")
    p.add_argument("--threads", type=int, default=1, help="OpenMP threads per run (default 1)")
    p.add_argument("--fdem", help="fdem executable (default: $FDEM_BIN, else build/fdem/fdem)")
    p.add_argument("--published-column", default="fdem_k25_kN", help="reference.csv column of the published FDEM")
    p.add_argument("--rate-case", help="case stem for the half-rate rerun (default: the first case)")
    p.add_argument("--rate-key", help="dotted key of the loading rate (default: the last stage's prescribed velocity)")
    p.add_argument("--no-rate-check", action="store_true", help="skip the half-rate rerun")
    p.set_defaults(func=cmd_validate)
