"""`validate`: runs a family of validation cases (a folder of case files) and writes report.md + report.csv.

Per case: peak load and displacement at peak (of the case's load-displacement curve, in the last stage, from
its start), initial stiffness (least-squares line through the origin up to 40 % of the peak, as `eeep`), error
against the experiment and against the published FDEM (from the family's reference.csv, else the case's
[reference]), triangles, steps, wall time, and the numerical settings as the engine resolves the case with the --set
overrides (`fdem check --json`: mesh size, loading rate, the local, contact and mass damping each stage runs with,
penalties and stiffnesses, time step).

Is the peak a peak: the load at the last history row of the same curve and drop_after_peak = (peak - load at
end) / peak; past_peak = "yes" when the drop is at least PAST_PEAK_DROP (5 %); "plateau" when it is less but the
peak lies at or before PLATEAU_REACH (3/4) of the travel and the curve ends below it (an inner maximum, then a slow
fall); else the curve is still rising or flat and the "peak" is only the largest load reached so far.

Quasi-static check (fdem/README.md 'Physics and numerics'): the cases named by --rate-case (repeatable; `all` = every case; default the
first case) are run again with their loading rate halved, each as its own run; per checked case the report gives
both peaks, their relative change, the verdict (quasi-static when |change| < QS_LIMIT = 2 %) and the status of the
half-rate run, then "N of M checked cases quasi-static; largest change X %"; quasi_static.csv holds the same table.
Both peaks of a pair are maxima over the same displacement range: when the two runs reach different control
displacements (an unfinished run, a stage that ends by time), both are taken up to the smaller one and the row
says so.

Which peak (--peak, default largest): `largest` takes the largest load of the curve; `first` takes the first
peak, the largest load reached before the load first falls FIRST_PEAK_DROP (5 %) below the largest value so far,
once that value is at least FIRST_PEAK_FLOOR (half) of the curve's largest load (the start of a loading stage can
carry an inertia spike of a few per cent of the capacity, which is not a peak); a curve that never falls that far
has no first peak: its largest load is taken and past_peak says so. A wall that softens and then rises again on a
second mechanism (a growing vertical force, re-seated blocks) so reports its first capacity, which does not depend
on the branch the later response takes. `--peak-up-to MM` cuts every curve at MM mm of control displacement before
anything is measured (peak, load at the end, EEEP, half-rate check): a stated window, for runs that go further
than the test did. The largest load of the (cut) curve stays in the report (largest_load_kN, largest_at_mm), so a
chosen peak never hides a larger one.

Smoothing (--smooth MM, default 0 = off): the peak, the displacement at peak, the load at the end and the
quasi-static comparison are then taken on the load averaged over a window of MM millimetres of control displacement
centred on each history row (one-sided where the curve starts and ends). Explicit runs of rocking and sliding walls
carry oscillations of the whole wall on top of the quasi-static load (a few per cent of it); the largest raw load is
then one crest of them. The raw largest load stays in the report (peak_raw_kN) with the largest deviation of the raw
curve from the smoothed one where the window is whole (oscillation_kN), so the choice is visible.

Damping: the work the local damping (D_damp) and the viscous terms (D_visc: element viscosity, contact dashpots)
did in the loading stage, as shares of the loading work |integral F du| (local_damping_work_share,
viscous_work_share; D_visc also holds the mass-proportional damping). Local damping (-alpha |f| sign v) carries a load
that need not shrink with the rate, which the half-rate check may then not see; its work share shows it.

Trend: when reference.csv has an axial load column (--axial-column, default N_kN), the cases sorted by it are
checked for a peak load rising monotonically and a displacement at peak falling monotonically with that load, and
for the EEEP ductility ([K25] Eq. 14 via `eeep`: K_e by regression up to 70 % of the peak, Delta_u = displacement
at the peak; report.csv column ductility_eeep) falling monotonically.

Reference file (optional) FAMILY/reference.csv: one row per experiment with a column `cases` listing the case file
stems it applies to (space separated), `experiment_kN`, and the published predictions in `*_kN` columns; the column
compared as "published FDEM" is --published-column (default fdem_k25_kN).
Runs go through the batch machinery, so the command is resumable: completed runs are not run again. Run folders:
OUT/STEM/runs/run for a case, OUT/STEM/runs/<batch run name of {rate key: half rate}> for its half-rate rerun.
"""
from __future__ import annotations

import csv
import glob
import os
import shlex
import sys
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from .batch import Batch, collect, default_jobs, fdem_binary, is_finished, parse_assignment, run_name
from .eeep import eeep
from .common import SIGN_CHOICES, ToolError, load_curve, load_run, resolved_case, stage_curve, write_csv
from .curves import (FIRST_PEAK_DROP, FIRST_PEAK_FLOOR, PAST_PEAK_DROP, PEAK_RULES, PLATEAU_REACH,  # noqa: F401
                     cut_at, oscillation, peak_index, peak_up_to, plateau_or, polyline_area, smooth_curve)

QS_LIMIT = 0.02  # the peak may change by less than this when the rate is halved
BOUND_TOL = 0.02  # a peak more than this fraction above its case's rigid-block bound is flagged (it cannot be right)
SAME_END_RTOL = 0.005  # two runs whose control displacements reached differ by less than this (relative) end alike


# ----------------------------------------------------------------------------------------------
# Case settings: as the engine resolves them (common.resolved_case: fdem check --json, the --set overrides applied)


def list_index(p: str, n: int) -> int:
    """The 0-based position of array element `p` of a dotted key: elements count from 1, as in fdem --set."""
    i = int(p)
    if not 1 <= i <= n:
        raise IndexError(p)
    return i - 1


def rate_key(rc: dict) -> tuple:
    """(dotted key, value) of the loading rate of a resolved case (resolved_case): the last stage's non-zero
    prescribed velocity (vx or vy), else the rate of its cyclic protocol, found in the case's tree after the overrides
    (the key is one --set can change)."""
    stages = rc["case"].get("stages") or []
    for si in range(len(stages) - 1, -1, -1):
        for i, sup in enumerate(stages[si].get("supports") or []):
            for comp in ("vx", "vy"):
                if isinstance(sup.get(comp), (int, float)) and sup[comp] != 0:
                    return f"stages.{si + 1}.supports.{i + 1}.{comp}", float(sup[comp])
            cyc = sup.get("cyclic")
            if isinstance(cyc, dict) and isinstance(cyc.get("rate"), (int, float)):
                return f"stages.{si + 1}.supports.{i + 1}.cyclic.rate", float(cyc["rate"])
    return None, None


def _penalty_text(what: str, pen, ref) -> str:
    """"NAME p_j=1e+10 Pa", or with penalty = "auto" (from the element size, at most penalty_ref; fracture/README.md)
    "NAME p_j=auto (ref 1e+10 Pa)"."""
    if isinstance(pen, (int, float)):
        return f"{what} p_j={pen:g} Pa"
    return f"{what} p_j={pen}" + (f" (ref {ref:g} Pa)" if isinstance(ref, (int, float)) else "")


def numerical_settings(rc: dict) -> dict:
    """The settings the issue asks to report, as text per field (same order for every case), from the resolved case
    (resolved_case): the values the run uses, defaults applied; the damping of each stage is the one it runs with
    (a stage that does not set it keeps the stage before's)."""
    r = rc["resolved"]
    geo = r.get("geometry") or {}
    out = {"mesh_size_m": "" if geo.get("mesh_size_m") is None else geo["mesh_size_m"]}
    for k in ("mesh_size_beam", "mesh_size_base"):  # generated walls and piers with a beam / a base
        if geo.get(k + "_m") is not None:
            out[k + "_m"] = geo[k + "_m"]
    key, rate = rate_key(rc)
    out["loading_rate_m_s"] = rate if rate is not None else ""
    stages = r.get("stages") or []
    out["local_damping"] = " / ".join(str(s["local_damping"]) for s in stages)
    out["contact_damping"] = " / ".join(str(s["contact_damping"]) for s in stages)
    out["mass_damping_1_s"] = " / ".join(str(s["mass_damping_1_s"]) for s in stages)
    pens = []
    for name, m in (r.get("materials") or {}).items():
        fr = m.get("fracture")
        if isinstance(fr, dict):
            pens.append(_penalty_text(name, fr["penalty"], fr.get("penalty_ref_Pa")))
            if fr.get("contact_penalty_Pa") is not None:  # the crack faces' contact penalty
                pens.append(f"{name} crack faces p_n={fr['contact_penalty_Pa']:g} Pa")
            if fr.get("insertion") == "extrinsic":
                pens[-1] += " (extrinsic insertion)"
    for itf in r.get("interfaces") or []:
        regs = "/".join(itf.get("regions", []))
        for k, unit in (("normal_penalty", "Pa"), ("tangential_penalty", "Pa"), ("normal_stiffness", "Pa/m"),
                        ("shear_stiffness", "Pa/m")):
            v = itf.get(f"{k}_{unit.replace('/', '_')}")
            if v is not None:
                pens.append(f"{regs} {k}={v:g} {unit}")
        bond = itf.get("bond")
        if isinstance(bond, dict):  # bonded: the cohesive law's penalty (or "auto") and stiffnesses
            if bond.get("penalty") is not None:
                text = _penalty_text(regs, bond["penalty"], bond.get("penalty_ref_Pa"))
                pens.append(text.replace(" p_j=", " penalty=", 1))
            for k in ("normal_stiffness", "shear_stiffness"):
                if bond.get(k + "_Pa_m") is not None:
                    pens.append(f"{regs} {k}={bond[k + '_Pa_m']:g} Pa/m")
    out["penalties"] = "; ".join(pens)
    num = r.get("numerics") or {}
    out["dt_setting"] = (f"dt={num['dt_fixed_s']:g} s" if num.get("dt_fixed_s") is not None
                         else f"safety={num['safety']}")
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


def curve_metrics(run_dir: str, smooth_m: float = 0.0, rule: str = "largest", up_to_m: float | None = None,
                  load_sign: str = "auto") -> dict:
    """Peak load (N), displacement at peak (m, from the start of the stage) and initial stiffness (N/m) of the
    load-displacement curve in the run's last stage (the loading after precompression); the load at the last
    history row (N), the drop after the peak (fraction of the peak) and the largest control displacement reached
    (m). The load is taken with the tools' one sign rule (curves.resolve_sign: --load-sign, else the case's
    output.curve.sign, else the sign that makes the loading work positive), the same curve `eeep` reads
    (common.stage_curve). `x`, `y` (|x - x0| in m, signed load in N) are kept for comparing two runs over the
    same range. With
    smooth_m > 0 all of these are taken on the load averaged over smooth_m of displacement (smooth_curve); the raw
    largest load is peak_raw_N and the largest |raw - smoothed| is oscillation_N. rule picks the peak (peak_index);
    up_to_m cuts the curve at that displacement first (after smoothing, so the window does not change the mean of
    the rows it keeps)."""
    run = load_run(run_dir, allow_unfinished=True)
    last = None
    if run.history is not None and run.history.has("stage") and len(run.history):
        last = int(np.max(run.history.numeric("stage")))
    c = load_curve(run_dir, None, None, "m", "N", last, True)
    if len(c.x) == 0:
        raise ToolError(f"{run_dir}: empty curve")
    x, raw, sign, sign_rule = stage_curve(c, load_sign)
    y = smooth_curve(x, raw, smooth_m)  # the raw (signed) load itself when smooth_m = 0
    n = len(x) if up_to_m is None else cut_at(x, up_to_m)
    x, y, raw = x[:n], y[:n], raw[:n]
    i, past = peak_index(y, rule)
    peak = float(y[i])
    d_peak = float(x[i])
    past = plateau_or(past, x, y, i)
    # initial stiffness: least-squares line through the origin of the ascending branch up to 40 % of the peak
    j = i
    for k in range(i + 1):
        if abs(y[k]) > 0.4 * peak:
            j = k
            break
    xs, ys = x[: j + 1], y[: j + 1]
    k0 = float(np.dot(xs, ys) / np.dot(xs, xs)) if np.dot(xs, xs) > 0 else float("nan")
    end = float(y[-1])
    il = int(np.argmax(y))
    out = {"peak_load_N": peak, "disp_at_peak_m": d_peak, "initial_stiffness_N_m": k0,
           "load_at_end_N": end, "drop_after_peak": (peak - end) / peak if peak > 0 else None, "past_peak": past,
           "largest_load_N": float(y[il]), "largest_at_m": float(x[il]), "rule": rule,
           "reach_m": float(np.max(x)), "x": x, "y": y,
           "peak_raw_N": float(np.max(raw)), "oscillation_N": oscillation(x, raw, y, smooth_m),
           "load_sign": sign, "load_sign_rule": sign_rule}
    out.update(damping_work_shares(run, last, c, n))
    out.update(crack_counts(run, last, n, i))
    # EEEP ductility of the same curve ([K25] Eq. 14, tools/README.md 'eeep': K_e by regression to 70 % of the peak,
    # Delta_u = displacement at the peak, the [K25] choice); None when the curve has no elastic branch to fit. With
    # --peak first the curve ends at the first peak, so that peak is eeep's.
    try:
        xe, ye = (x, y) if rule == "largest" else (x[: i + 1], y[: i + 1])
        e = eeep(xe, ye, source=run_dir, load_sign=1.0)
        mu = float(e["ductility"])
        out["ductility"] = mu if np.isfinite(mu) else None
        out["eeep_K_e_N_m"] = float(e["K_e"])
    except (ToolError, ValueError, ZeroDivisionError, FloatingPointError):
        out["ductility"] = None
        out["eeep_K_e_N_m"] = None
    return out


UNIT_CRACK_COLUMNS = ("broken_unit_I", "broken_unit_II", "broken_unit_mixed")


def rigid_block_bound(case: str, fixed: list, fdem: str, out_dir: str) -> dict:
    """The case's rigid-block collapse load (`fdem-tools limit`: the associative bound of its own blocks, joints,
    supports and loads; tools/README.md "limit"), in N, with the limit folder under out_dir; {"note": why} when the
    case has none (a refused case: no load to multiply; a confined one: unbounded; a tilting case: an angle)."""
    from .limit import analyse
    t0 = time.perf_counter()
    try:
        rep = analyse(case, [f"{k}={v}" for k, v in fixed], fdem, out_dir=out_dir, plot=False, nonassoc=False,
                      quiet=True)
    except (ToolError, OSError, ValueError, KeyError) as e:  # a refused or unbounded case, or no model to export
        return {"note": (str(e).splitlines() or [type(e).__name__])[0][:160]}
    if rep.get("collapse_load_N") is None:
        return {"note": "no collapse load (" + str(rep.get("mode")) + ")"}
    return {"bound_N": float(rep["collapse_load_N"]), "solve_s": rep.get("solve_time_s"),
            "time_s": time.perf_counter() - t0}


def crack_counts(run, stage, n: int, i_peak: int) -> dict:
    """Cracks through the units (stones, bricks) in the loading stage, for reading the failure mode: the broken
    unit-interior cohesive elements (history columns broken_unit_*, cumulative) at the peak row and at the last row
    of the (cut) curve, counted from the stage's start; and how the run's last stage ended (summary.json stage
    endings: until, past_peak, duration, ...). None where the run has no such columns."""
    out = {"unit_cracks_at_peak": None, "unit_cracks_at_end": None, "ended_by": None}
    h = run.history
    if h is not None and stage is not None and all(h.has(k) for k in UNIT_CRACK_COLUMNS):
        keep = h.numeric("stage") == stage
        tot = sum(h.numeric(k)[keep] for k in UNIT_CRACK_COLUMNS)
        if len(tot):
            tot = tot[:n] - tot[0]
            out["unit_cracks_at_peak"] = int(tot[min(i_peak, len(tot) - 1)])
            out["unit_cracks_at_end"] = int(tot[-1])
    ends = (run.summary or {}).get("stages") or []
    if isinstance(ends, list) and ends and isinstance(ends[-1], dict):
        out["ended_by"] = ends[-1].get("ended_by")
    return out


def damping_work_shares(run, stage, c, n: int | None = None) -> dict:
    """What the damping took of the loading work in the curve's stage: the growth of D_damp (local damping) and of
    D_visc (element viscosity, contact dashpots, mass damping) over the stage's rows, each divided by the work of the curve's
    load along its displacement, |integral F du| (trapezoids on the history rows). A load the local damping carries
    need not shrink when the rate is halved (-alpha |f| sign v), so the half-rate check may not see it; this share
    does. None where the history has no such column or the loading did no work. n: only the stage's first n rows
    (the --peak-up-to window)."""
    h = run.history
    out = {"local_damping_work_share": None, "viscous_work_share": None}
    if h is None or not h.has("stage"):
        return out
    keep = h.numeric("stage") == stage
    xs, ys = np.asarray(c.x, float)[:n], np.asarray(c.y, float)[:n]
    work = abs(polyline_area(xs, ys)) if len(xs) > 1 else 0.0
    if not work > 0:
        return out
    for col, key in (("D_damp", "local_damping_work_share"), ("D_visc", "viscous_work_share")):
        if h.has(col) and run.unit(col) == "J":
            d = h.numeric(col)[keep][:n]
            out[key] = float(d[-1] - d[0]) / work
    return out


def past_peak(past) -> str | None:
    if past is None:
        return None
    if past == "plateau":
        return "plateau (an inner maximum, then falling less than 5 %)"
    return "yes" if past else "no (still rising / flat)"


def compare_rates(m_full: dict, m_half: dict) -> dict:
    """The two peaks of a half-rate pair over the same displacement range (N), and a note when the runs reach
    different control displacements (then both peaks are taken up to the smaller one)."""
    full, half = m_full.get("peak_load_N"), m_half.get("peak_load_N")
    out = {"peak_full_N": full, "peak_half_N": half, "reach_full_m": m_full.get("reach_m"),
           "reach_half_m": m_half.get("reach_m"), "compared_up_to_m": None, "note": ""}
    if full is None or half is None:
        return out
    a, b = m_full["reach_m"], m_half["reach_m"]
    d = min(a, b)
    out["compared_up_to_m"] = d
    if abs(a - b) > SAME_END_RTOL * max(a, b):
        out["peak_full_N"], out["peak_half_N"] = peak_up_to(m_full, d), peak_up_to(m_half, d)
        out["note"] = (f"runs end at different displacements ({1e3 * a:.4g} mm at the full rate, {1e3 * b:.4g} mm "
                       f"at half the rate): both peaks taken up to {1e3 * d:.4g} mm")
    return out


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


def share(v):
    return "-" if v is None else f"{100 * v:.2f} %"


def _stem(path: str) -> str:
    return os.path.splitext(os.path.basename(path))[0]


def rate_cases(cases: list, requested: list | None, family: str) -> list:
    """The case files to rerun at half the rate, in family order: --rate-case values (repeatable), `all` for every
    case, none given: the first case."""
    if not requested:
        return [cases[0]]
    if "all" in requested:
        return list(cases)
    stems = [_stem(c) for c in cases]
    for r in requested:
        if r not in stems:
            raise ToolError(f"--rate-case {r}: no such case in {family} (cases: {', '.join(stems)}, or all)")
    return [c for c in cases if _stem(c) in requested]


def rate_setting(rc: dict, case: str, given_key: str | None) -> tuple:
    """(dotted key, value) of the loading rate of one resolved case: --rate-key if given (read from the case's tree
    after the overrides), else the detected one."""
    if not given_key:
        key, rate = rate_key(rc)
        if key is None:
            raise ToolError(f"{case}: no prescribed velocity in its stages; give --rate-key or --no-rate-check")
        return key, rate
    try:
        cur = rc["case"]
        for p in given_key.split("."):
            cur = cur[list_index(p, len(cur))] if isinstance(cur, list) else cur[p]
        return given_key, float(cur)
    except (KeyError, IndexError, ValueError, TypeError):
        raise ToolError(f"--rate-key {given_key}: no such number in {case}") from None


def axial_trend(rows: list, refs: list, column: str) -> str | None:
    """One line on how peak load and displacement at peak change with the axial load of reference.csv's `column`
    (None when the file has no such column or no case has a value in it)."""
    if not refs or column not in refs[0]:
        return None
    name, unit = (column[:-3], "kN") if column.endswith("_kN") else (column, "")
    pts = []
    for r in rows:
        n = _float(reference_for(refs, r["case"]).get(column))
        if n is not None and r["peak_load_kN"] is not None:
            pts.append((n, r["case"], r["peak_load_kN"], r["disp_at_peak_mm"], r["status"], r.get("ductility_eeep")))
    if not pts:
        return None
    pts.sort()
    head = f"Trend with {name} (reference.csv column `{column}`): "
    if len(pts) < 2:
        return head + "fewer than two cases with a peak, not evaluated."
    ns = [p[0] for p in pts]
    if len(set(ns)) != len(ns):
        dup = sorted({f"{v:g}" for v in ns if ns.count(v) > 1})
        return head + (f"not evaluated: several cases share {name} = {', '.join(dup)} {unit} (run one variant per "
                       f"{name}, e.g. with --glob).")
    peaks = [p[2] for p in pts]
    dpk = [p[3] for p in pts]
    rising = all(b > a for a, b in zip(peaks, peaks[1:]))
    falling = all(b < a for a, b in zip(dpk, dpk[1:]))
    yn = lambda v: "yes" if v else "no"  # noqa: E731
    line = (head + f"capacity rising with {name}: {yn(rising)}; displacement at peak falling with {name}: "
            f"{yn(falling)} (values, sorted by {name}: {name} = {', '.join(f'{v:g}' for v in ns)} {unit}; "
            f"peak {', '.join(fmt(v) for v in peaks)} kN; displacement at peak {', '.join(fmt(v) for v in dpk)} mm).")
    mus = [p[5] for p in pts]
    if all(v is not None for v in mus):
        line += (f" EEEP ductility ([K25] Eq. 14, displacement at peak as Delta_u) falling with {name}: "
                 f"{yn(all(b < a for a, b in zip(mus, mus[1:])))} ({', '.join(fmt(v) for v in mus)}).")
    unfinished = [f"{p[1]} ({p[4]})" for p in pts if p[4] != "completed"]
    if unfinished:
        line += " Not completed, values so far: " + ", ".join(unfinished) + "."
    return line


def run_family(args) -> int:
    family = os.path.normpath(args.family)
    cases = family_cases(family, args.glob)
    fixed = [parse_assignment(s, "--set") for s in args.set or []]
    out = os.path.abspath(args.out_dir or os.path.join("runs", "validate_" + os.path.basename(family)))
    from .slurm import job_name, options_from_args, report_failures, run_tasks
    slurm = options_from_args(args, job_name("fdem-validate", out))
    threads = args.threads = slurm.cpus_per_task if slurm else args.threads  # the report states it
    fdem = fdem_binary(args.fdem, must_exist=not args.dry_run)
    refs = read_reference(family)
    cases_resolved = {c: resolved_case(c, fixed, fdem=fdem) for c in cases}
    log = lambda m: print(m, flush=True)  # noqa: E731

    # the tasks: every case once, plus one rerun at half the rate per checked case. The half-rate run lives in the
    # case's batch folder under the run name of its one override, so earlier runs are found again.
    tasks = []
    for c in cases:
        stem = _stem(c)
        tasks.append((stem, Batch(c, os.path.join(out, stem), fdem, threads=threads, fixed=fixed, log=log), {}))
    checks = []
    if not args.no_rate_check:
        for c in rate_cases(cases, args.rate_case, family):
            key, rate = rate_setting(cases_resolved[c], c, args.rate_key)
            stem = _stem(c)
            checks.append({"case": stem, "key": key, "rate": rate, "half": rate / 2})
            tasks.append((stem + "__half_rate", Batch(c, os.path.join(out, stem), fdem, threads=threads,
                                                      fixed=fixed, log=log), {key: repr(rate / 2)}))

    if args.dry_run and not slurm:
        for _, b, p in tasks:
            print(shlex.join(b.command(p, os.path.join(b.out, "runs", run_name(p)))))
        return 0
    t0 = time.monotonic()
    if slurm:
        if not slurm.dry_run:
            print(f"validate: {len(cases)} cases of {family} + {len(checks)} half-rate rerun(s) as a Slurm job array, "
                  f"{threads} thread(s) each, in {out}", flush=True)
            for _, b, _ in tasks:
                os.makedirs(b.out, exist_ok=True)
        recs = run_tasks([b.task(run_name(p), p, label) for label, b, p in tasks], slurm,
                         os.path.join(out, "slurm"), is_finished, log)
        if recs is None:  # --dry-run or --no-wait
            return 0
        recs = [collect(r) for r in recs]
    else:
        print(f"validate: {len(cases)} cases of {family} + {len(checks)} half-rate rerun(s), "
              f"{args.jobs} at a time, {threads} thread(s) each, in {out}", flush=True)
        for _, b, _ in tasks:
            os.makedirs(b.out, exist_ok=True)
        ex = ThreadPoolExecutor(max_workers=max(1, args.jobs))
        try:
            futs = [ex.submit(b._one, run_name(p), p, label) for label, b, p in tasks]
            recs = [collect(f.result()) for f in futs]
        except BaseException:
            for _, b, _ in tasks:
                b.stop()
            ex.shutdown(wait=True, cancel_futures=True)
            raise
        ex.shutdown(wait=True)

    by_task = {}
    for (label, b, p), rec in zip(tasks, recs):
        m = {}
        if rec["status"] in ("completed", "failed", "running") and \
                os.path.isfile(os.path.join(rec["run_dir"], "history.csv")):
            try:
                m = curve_metrics(rec["run_dir"], args.smooth * 1e-3, args.peak,
                                  None if args.peak_up_to is None else args.peak_up_to * 1e-3,
                                  getattr(args, "load_sign", "auto"))
            except ToolError as e:
                m = {"note": str(e)}
        by_task[label] = (rec, m)

    bounds = {}
    if not args.no_bound:
        for c in cases:
            bounds[c] = rigid_block_bound(c, fixed, fdem, os.path.join(out, _stem(c), "limit"))

    kn = lambda v: v / 1e3 if v is not None else None  # noqa: E731
    mm = lambda v: v * 1e3 if v is not None else None  # noqa: E731
    qs_rows = []
    for q in checks:
        rec_full, m_full = by_task[q["case"]]
        rec_half, m_half = by_task[q["case"] + "__half_rate"]
        cmp = compare_rates(m_full, m_half)
        change = rel(cmp["peak_half_N"], cmp["peak_full_N"])
        qs_rows.append(dict(q, status_full=rec_full["status"], status_half=rec_half["status"],
                            peak_full_kN=kn(cmp["peak_full_N"]), peak_half_kN=kn(cmp["peak_half_N"]), change=change,
                            quasi_static=None if change is None else abs(change) < QS_LIMIT,
                            reach_full_mm=mm(cmp["reach_full_m"]), reach_half_mm=mm(cmp["reach_half_m"]),
                            compared_up_to_mm=mm(cmp["compared_up_to_m"]), note=cmp["note"]))
    qs_by_case = {q["case"]: q for q in qs_rows}

    rows = []
    for c in cases:
        stem = _stem(c)
        rec, m = by_task[stem]
        ref = reference_for(refs, stem)
        exp_N = _float(ref.get("experiment_kN"))
        exp_N = exp_N * 1e3 if exp_N is not None else rec.get("reference_peak_N")
        pub = _float(ref.get(args.published_column))
        pub_N = pub * 1e3 if pub is not None else None
        peak = m.get("peak_load_N")
        q = qs_by_case.get(stem, {})
        row = {"case": stem, "status": rec["status"],
               "peak_load_kN": kn(peak),
               "peak_raw_kN": kn(m.get("peak_raw_N")), "oscillation_kN": kn(m.get("oscillation_N")),
               "smoothing_mm": args.smooth,
               "disp_at_peak_mm": mm(m.get("disp_at_peak_m")),
               "ductility_eeep": m.get("ductility"),
               "initial_stiffness_kN_mm": m["initial_stiffness_N_m"] / 1e6 if "initial_stiffness_N_m" in m else None,
               "load_at_end_kN": kn(m.get("load_at_end_N")), "drop_after_peak": m.get("drop_after_peak"),
               "past_peak": past_peak(m.get("past_peak")),
               "stage_ended_by": m.get("ended_by"),
               "unit_cracks_at_peak": m.get("unit_cracks_at_peak"), "unit_cracks_at_end": m.get("unit_cracks_at_end"),
               "largest_load_kN": kn(m.get("largest_load_N")), "largest_at_mm": mm(m.get("largest_at_m")),
               "peak_rule": args.peak, "peak_up_to_mm": args.peak_up_to,
               "experiment_kN": exp_N / 1e3 if exp_N else None, "error_vs_experiment": rel(peak, exp_N),
               "published_fdem_kN": pub_N / 1e3 if pub_N else None, "error_vs_published_fdem": rel(peak, pub_N),
               "rigid_block_bound_kN": kn(bounds.get(c, {}).get("bound_N")),
               "peak_over_bound": (peak / bounds[c]["bound_N"] if peak is not None and
                                   bounds.get(c, {}).get("bound_N") else None),
               "bound_note": bounds.get(c, {}).get("note"),
               "peak_half_rate_kN": q.get("peak_half_kN"), "rate_change": q.get("change"),
               "triangles": rec.get("n_triangles"), "steps": rec.get("steps"), "wall_time_s": rec.get("wall_time_s"),
               "dt_s": rec.get("dt"),
               "energy_balance_error": ((rec.get("summary") or {}).get("energy") or {}).get("balance_error"),
               "local_damping_work_share": m.get("local_damping_work_share"),
               "viscous_work_share": m.get("viscous_work_share")}
        row.update(numerical_settings(cases_resolved[c]))
        rows.append(row)

    header = list(rows[0].keys())
    write_csv(os.path.join(out, "report.csv"), header, [["" if r[k] is None else r[k] for k in header] for r in rows])
    qs_header = ["case", "rate_key", "rate", "half_rate", "status_full", "status_half", "peak_full_rate_kN",
                 "peak_half_rate_kN", "rate_change", "quasi_static", "reach_full_rate_mm", "reach_half_rate_mm",
                 "compared_up_to_mm", "note"]
    yn = {True: "yes", False: "no", None: ""}
    write_csv(os.path.join(out, "quasi_static.csv"), qs_header,
              [["" if v is None else v for v in
                (q["case"], q["key"], q["rate"], q["half"], q["status_full"], q["status_half"], q["peak_full_kN"],
                 q["peak_half_kN"], q["change"], yn[q["quasi_static"]], q["reach_full_mm"], q["reach_half_mm"],
                 q["compared_up_to_mm"], q["note"])] for q in qs_rows])
    trend = axial_trend(rows, refs, args.axial_column)
    from .figures import run_stamp
    md = report_markdown(family, rows, qs_rows, trend, fixed, args, time.monotonic() - t0,
                         stamp=run_stamp([rec.get("summary") for rec in recs], limit=None))
    with open(os.path.join(out, "report.md"), "w", encoding="utf-8") as f:
        f.write(md)
    print(md)
    print(f"wrote {os.path.join(out, 'report.md')}, {os.path.join(out, 'report.csv')}, "
          f"{os.path.join(out, 'quasi_static.csv')}")
    bad = [r for r in rows if r["status"] != "completed"] + [q for q in qs_rows if q["status_half"] != "completed"]
    if bad:
        print(f"fdem-tools validate: {len(bad)} run(s) did not complete (see the logs/ of each case); "
              "run the same command again to retry them", file=sys.stderr)
        if slurm:
            report_failures(recs, os.path.join(out, "slurm"))
        return 2
    return 0


def bound_ratio(r: dict) -> str:
    q = r.get("peak_over_bound")
    if q is None:
        return "-"
    return f"{q:.3f}" + (" ABOVE THE BOUND" if q > 1 + BOUND_TOL else "")


def report_markdown(family, rows, qs_rows, trend, fixed, args, elapsed, stamp: str = "") -> str:
    L = [f"# Validation report: {family}", ""]
    L.append(f"Cases: {len(rows)} (pattern `{args.glob}`); overrides: "
             + (", ".join(f"`{k}={v}`" for k, v in fixed) if fixed else "none")
             + f"; {args.threads} thread(s) per run; published FDEM column `{args.published_column}`.")
    L.append("")
    if stamp:  # what made the runs (the figures' stamp; fdem-tools provenance reads it)
        L.append(f"Source: {stamp}")
        L.append("")
    L.append("| case | status | peak (kN) | disp. at peak (mm) | K0 (kN/mm) | load at end (kN) | drop after peak "
             "| past peak | stage ended by | unit cracks at peak / end | experiment (kN) | error | published FDEM (kN) "
             "| error vs FDEM | rigid-block bound (kN) | peak / bound | triangles | steps | wall time (s) |")
    L.append("|---" * 19 + "|")
    for r in rows:
        drop = "-" if r["drop_after_peak"] is None else f"{100 * r['drop_after_peak']:.1f} %"
        L.append(f"| {r['case']} | {r['status']} | {fmt(r['peak_load_kN'])} | {fmt(r['disp_at_peak_mm'])} | "
                 f"{fmt(r['initial_stiffness_kN_mm'])} | {fmt(r['load_at_end_kN'])} | {drop} | "
                 f"{fmt(r['past_peak'])} | {fmt(r['stage_ended_by'])} | "
                 f"{fmt(r['unit_cracks_at_peak'])} / {fmt(r['unit_cracks_at_end'])} | "
                 f"{fmt(r['experiment_kN'])} | {pct(r['error_vs_experiment'])} | "
                 f"{fmt(r['published_fdem_kN'])} | {pct(r['error_vs_published_fdem'])} | "
                 f"{fmt(r['rigid_block_bound_kN']) if r['rigid_block_bound_kN'] is not None else '-'} | "
                 f"{bound_ratio(r)} | {fmt(r['triangles'])} | "
                 f"{fmt(r['steps'])} | {fmt(r['wall_time_s'], 3)} |")
    if args.smooth > 0:
        L += ["", f"Smoothing: peak, displacement at peak, load at end and the quasi-static check use the load averaged "
                  f"over {args.smooth:g} mm of control displacement centred on each row (--smooth). Raw largest load / "
                  "largest |raw - smoothed| per case (kN): "
                  + "; ".join(f"{r['case']} {fmt(r['peak_raw_kN'])} / {fmt(r['oscillation_kN'])}" for r in rows) + "."]
    window = "" if args.peak_up_to is None else (f" up to {args.peak_up_to:g} mm of control displacement "
                                                  "(--peak-up-to: the rest of the curve is not measured)")
    if args.peak == "first":
        L += ["", f"Peak = first peak (--peak first) of |load| on the case's curve in its last stage{window}: the "
                  f"largest load reached before the load first falls {100 * FIRST_PEAK_DROP:g} % below it "
                  f"(FIRST_PEAK_DROP), counting maxima of at least {100 * FIRST_PEAK_FLOOR:g} % of the curve's "
                  "largest load (FIRST_PEAK_FLOOR); past peak = yes when it did, otherwise the curve never fell that "
                  "far and the peak is its largest load; load at end = its last history row."]
        later = [r for r in rows if r["largest_load_kN"] is not None and r["peak_load_kN"] is not None
                 and r["largest_load_kN"] > r["peak_load_kN"]]
        if later:
            L += ["", "Larger loads after the first peak (kN at mm): "
                      + "; ".join(f"{r['case']} {fmt(r['largest_load_kN'])} at {fmt(r['largest_at_mm'])}"
                                  for r in later) + "."]
    else:
        L += ["", f"Peak = largest |load| of the case's curve in its last stage{window}; load at end = its last "
                  f"history row; past peak = yes when the load at the end is at least {100 * PAST_PEAK_DROP:g} % "
                  "below the peak (PAST_PEAK_DROP); plateau when it is less far below but the peak lies before "
                  f"{100 * PLATEAU_REACH:g} % of the travel (PLATEAU_REACH: an inner maximum, then a slow fall); "
                  "otherwise the curve is still rising or flat and the peak is only the largest load reached so far."]
    L += ["", "Stage ended by: how the loading stage ended (until: its largest displacement; past_peak: the "
              "[[stages]] past_peak criterion). Unit cracks: broken cohesive elements inside the units (stones, "
              "bricks) since the start of the loading stage, at the peak row and at the end (history columns "
              "broken_unit_*)."]
    if not args.no_bound:
        L += ["", "Rigid-block bound: the collapse load of the case's own blocks, rigid, with no-tension Coulomb joints "
                  "and associative flow (`fdem-tools limit`, tools/README.md); a deformable model with non-associative "
                  f"friction stays below it. A peak more than {100 * BOUND_TOL:g} % above it (BOUND_TOL) is flagged "
                  "ABOVE THE BOUND: it cannot be right."]
        notes = [f"{r['case']}: {r['bound_note']}" for r in rows if r.get("bound_note")]
        if notes:
            L += ["", "No bound: " + "; ".join(notes) + "."]
        above = [r["case"] for r in rows if r["peak_over_bound"] is not None and r["peak_over_bound"] > 1 + BOUND_TOL]
        if above:
            L += ["", f"ABOVE THE BOUND (more than {100 * BOUND_TOL:g} %): {', '.join(above)}."]
    not_past = [r["case"] for r in rows if r["past_peak"] is not None and r["past_peak"].startswith("no")]
    if not_past:
        L += ["", f"Not past the peak: {', '.join(not_past)}."]
    errs = [abs(r["error_vs_experiment"]) for r in rows if r["error_vs_experiment"] is not None]
    if errs:
        L += ["", f"Mean absolute error against the experiments: {100 * sum(errs) / len(errs):.1f} % over {len(errs)} "
                  f"case(s); largest {100 * max(errs):.1f} %."]
    if trend:
        L += ["", trend]
    L += ["", "## Numerical settings", ""]
    keys = [k for k in rows[0] if k in ("mesh_size_m", "mesh_size_beam_m", "mesh_size_base_m", "loading_rate_m_s",
                                         "local_damping", "contact_damping", "mass_damping_1_s", "penalties",
                                         "dt_setting")]
    L.append("| case | " + " | ".join(keys) + " | dt used (s) | energy balance error | local damping work "
             "| viscous work |")
    L.append("|---|" + "---|" * (len(keys) + 4))
    for r in rows:
        L.append(f"| {r['case']} | " + " | ".join(fmt(r.get(k)) for k in keys) + f" | {fmt(r['dt_s'])} | "
                 f"{pct(r['energy_balance_error'])} | {share(r['local_damping_work_share'])} | "
                 f"{share(r['viscous_work_share'])} |")
    L += ["", "Local damping work / viscous work: what the local damping (D_damp) and the element viscosity and "
              "contact dashpots and mass damping (D_visc) dissipated in the loading stage, as a share of the loading "
              "work |integral F du| of the case's curve. The local damping's share is roughly the share of the load "
              "it carries, and halving the rate need not shrink it: the quasi-static check below may not see it."]
    same = all(all(r.get(k) == rows[0].get(k) for r in rows) for k in keys if k != "penalties")
    L += ["", "Mesh size, rate, damping and time-step setting are " + ("the same for every case." if same else
                                                                     "NOT the same for every case (see the table).")]
    L += ["", "## Quasi-static check", ""]
    if args.no_rate_check:
        L.append("Not run (--no-rate-check).")
    else:
        L.append(f"Each checked case is run again with its loading rate halved; quasi-static when the peak changes "
                 f"by less than {100 * QS_LIMIT:g} % (both peaks over the same displacement range).")
        L += ["", "| case | rate key | rate (m/s) | half rate (m/s) | peak full rate (kN) | peak half rate (kN) "
                  "| change | verdict | half-rate run | note |", "|---" * 10 + "|"]
        for q in qs_rows:
            verdict = "-" if q["quasi_static"] is None else ("quasi-static" if q["quasi_static"] else
                                                             "NOT quasi-static")
            L.append(f"| {q['case']} | `{q['key']}` | {q['rate']:g} | {q['half']:g} | {fmt(q['peak_full_kN'])} | "
                     f"{fmt(q['peak_half_kN'])} | {pct(q['change'])} | {verdict} | {q['status_half']} | "
                     f"{q['note'] or '-'} |")
        ok = sum(q["quasi_static"] is True for q in qs_rows)
        changes = [q["change"] for q in qs_rows if q["change"] is not None]
        largest = "-" if not changes else f"{100 * max(changes, key=abs):+.1f} %"
        L += ["", f"{ok} of {len(qs_rows)} checked cases quasi-static; largest change {largest}."]
    L += ["", f"Elapsed: {elapsed:.1f} s.", ""]
    return "\n".join(L)


def cmd_validate(args):
    if not args.smooth >= 0:
        raise ToolError(f"--smooth must be a window >= 0 mm, got {args.smooth}")
    if args.peak_up_to is not None and not args.peak_up_to > 0:
        raise ToolError(f"--peak-up-to must be a displacement > 0 mm, got {args.peak_up_to}")
    if args.jobs is None and args.scheduler == "local":
        args.jobs = default_jobs(args.threads)
    return run_family(args)


def add_parser(sub):
    p = sub.add_parser("validate", help="run a family of validation cases and write report.md + report.csv",
                       description="Runs every case file of FAMILY_DIR (resumable, through the batch machinery), "
                                   "then writes report.md and report.csv: peak load, displacement at peak, initial "
                                   "stiffness, load at the end and drop after the peak (past_peak: yes when the "
                                   f"load at the end is >= {100 * PAST_PEAK_DROP:g} %% below the peak), errors "
                                   "against the experiment and the published FDEM, size, steps, wall time and "
                                   "numerical settings per case; a quasi-static check (the --rate-case cases rerun "
                                   "at half the loading rate; quasi_static.csv) and, when reference.csv has the "
                                   "--axial-column, the trend of peak and displacement at peak with the axial load.")
    p.add_argument("family", metavar="FAMILY_DIR", help="folder of case files (e.g. cases/lourenco2005)")
    p.add_argument("--glob", default="*.toml", help="case files to run (default *.toml)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="a setting for every run (repeatable)")
    p.add_argument("--out-dir", help="report folder (default runs/validate_<family>)")
    p.add_argument("--jobs", type=int, help="runs at a time (default: cores / threads)")
    p.add_argument("--threads", type=int, default=1, help="OpenMP threads per run (default 1)")
    p.add_argument("--fdem", help="fdem executable (default: $FDEM_BIN, else build/fdem/fdem)")
    p.add_argument("--published-column", default="fdem_k25_kN", help="reference.csv column of the published FDEM")
    p.add_argument("--axial-column", default="N_kN",
                   help="reference.csv column of the axial load, for the trend line (default N_kN; skipped when "
                        "the file has no such column)")
    p.add_argument("--rate-case", action="append", metavar="STEM",
                   help="case stem to rerun at half its loading rate (repeatable; 'all' = every case; default: the "
                        f"first case); quasi-static when the peak changes by less than {100 * QS_LIMIT:g} %%")
    p.add_argument("--rate-key", help="dotted key of the loading rate, used for every checked case (default: each "
                                      "case's last-stage prescribed velocity)")
    p.add_argument("--no-rate-check", action="store_true", help="skip the half-rate reruns")
    p.add_argument("--no-bound", action="store_true",
                   help="do not compute each case's rigid-block bound (fdem-tools limit; about 1 s per case)")
    p.add_argument("--smooth", type=float, default=0.0, metavar="MM",
                   help="take peaks on the load averaged over MM mm of control displacement (default 0: raw); the "
                        "raw largest load and the oscillation are reported beside them")
    p.add_argument("--peak", choices=PEAK_RULES, default="largest",
                   help="which peak: the largest load (default) or the first one, the largest load before the load "
                        f"first falls {100 * FIRST_PEAK_DROP:g} %% below it (maxima under "
                        f"{100 * FIRST_PEAK_FLOOR:g} %% of the largest load do not count); the largest load is "
                        "reported beside it")
    p.add_argument("--peak-up-to", type=float, metavar="MM",
                   help="measure every curve only up to MM mm of control displacement (peak, load at the end, EEEP, "
                        "half-rate check)")
    p.add_argument("--load-sign", choices=SIGN_CHOICES, default="auto",
                   help="sign of the load: auto (default: the case's output.curve.sign, else the sign that makes the "
                        "loading work positive), 1 (as recorded) or -1 (turned)")
    from .slurm import add_arguments
    add_arguments(p, dry_run=True)
    p.set_defaults(func=cmd_validate)
