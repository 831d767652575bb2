"""`study mesh` and `study speed`: parameter studies run through the batch machinery (so they resume too).

study mesh: the case at a list of values of a mesh key (default geometry.mesh_size, h in m; any other key, such as
  a scale factor, is tabulated and plotted under its own name, unscaled); quantities of interest per run: peak load
  (largest |load| of the case's curve, kN), the case's own reference quantity (its [reference] monitor and quantity,
  as the run computed it, with the reference value and the error), final fracture dissipation D_frac and external
  work W_ext when recorded, run time and triangle count. The change of each quantity relative to the finest mesh is
  tabulated and plotted; the observed convergence order is estimated from the three finest completed runs
  (Richardson: q(h) = q* + C h^p; for sizes h1 > h2 > h3, (q1 - q2) / (q2 - q3) = (h1^p - h2^p) / (h2^p - h3^p),
  solved for p; with a constant ratio r = h1/h2 = h2/h3, p = ln((q1 - q2) / (q2 - q3)) / ln r; q* = q3 + (q3 - q2)
  / ((h2/h3)^p - 1)). Differences of opposite sign (oscillating) or a zero difference give no order. A run that did
  not complete is reported with why: its summary's message, else the last error and warning lines of its log.
study speed: a grid of mesh sizes x loading rates x damping values. Error of a run: |P - P_ref| / |P_ref| of its
  peak load, with P_ref given (--reference, kN); else, when the case has a [reference] (monitor, quantity peak,
  first_peak or final, value), | |q| - |value| | / |value| of that quantity q as the run computed it (its
  summary.json reference.computed; the engine's comparison); else the peak of the most accurate run of the grid
  (smallest mesh size, slowest rate, least damping). The output, the JSON (reference, reference_quantity) and the
  figure say which. A run is on the Pareto front when
  no other run is at the same time both faster and more accurate.
  Whole-curve errors (curve_errors): every completed run's loading curve H(u) (the last stage, the tools' load sign
  rule, as `validate` and `eeep` read it) against a reference curve: a run folder given (--reference-run, e.g. a
  run at half the rate and half the mass scaling that no longer changes), else the most accurate run of the grid.
  Both curves are taken on their loading branch (the rows where u exceeds every earlier u) and interpolated
  linearly on 2001 points of [0, u_to]; with P_ref the reference curve's peak, curve_rms = sqrt(mean((H - H_ref)^2))
  / P_ref over [0, u_to] and curve_max = max |H - H_ref| / P_ref over [u_from, u_to] (u_to: --curve-to, default the
  smallest reach of the runs and the reference; u_from: --curve-from, default 5 % of u_to, the 0.5 mm of a 10 mm
  pushover, so that the first rows, where any two curves differ by their start-up, do not decide it). K_e, P_y,
  ductility (EEEP as `eeep` computes them) and the peak are compared with the reference curve's: signed relative
  differences. --curve-smooth MM adds curve_max_smoothed: curve_max with both loading branches first averaged over
  MM mm of travel (validate's --smooth), which tells a curve whose short load drops (slip events) sit a little
  elsewhere from one whose level differs. --error picks which error the Pareto front and the figure use (peak,
  curve_max, curve_rms or curve_max_smoothed).
"""
from __future__ import annotations

import math
import os
import sys

import numpy as np

from .batch import Batch, fdem_binary, parse_assignment, split_values
from .common import ToolError, load_run, write_csv, write_json
from .curves import loading_branch, smooth_curve  # noqa: F401


def _num(v: str):
    try:
        return float(v)
    except ValueError:
        return None


# How a reference quantity is shown: the unit of its monitor (summary.json columns) -> (shown unit, factor from it)
SHOWN_UNITS = {"N": ("kN", 1e-3), "m": ("mm", 1e3), "J": ("J", 1.0), "s": ("s", 1.0)}


def reference_shown(run, ref: dict) -> dict:
    """The case's reference quantity as study mesh tabulates and draws it: in kN (forces) or mm (lengths), and a force
    with the tools' one load sign rule (curves.resolve_sign: the case's output.curve.sign for the curve's load, else
    the sign whose loading work along the curve's displacement is positive), as plot, eeep and validate draw it. The
    reference value is compared by magnitude (the engine's relative_error is (|computed| - |value|) / |value|), so
    it is shown as |value|. Before, a reaction's -74 kN was drawn against +74 kN on an axis of +-80,000 (N)."""
    mon = ref.get("monitor")
    unit = run.unit(mon) if mon else ""
    shown, factor = SHOWN_UNITS.get(unit, (unit or "as recorded", 1.0))
    sign, rule = 1.0, "as recorded"
    if unit == "N":
        from .common import load_curve
        from .curves import loading_work_sign, resolve_sign
        try:
            c = load_curve(run.path, partial=True)
            if mon == c.y_name:
                sign, rule = resolve_sign(c)
            elif run.history is not None and run.history.has(mon):
                sign = loading_work_sign(c.x, run.history.numeric(mon))
                rule = "loading work along the curve's displacement"
        except ToolError:
            pass
    out = {"reference_unit": shown, "reference_sign": sign, "reference_sign_rule": rule,
           "reference_value_shown": None, "reference_computed_shown": None}
    try:
        if ref.get("value") is not None:
            out["reference_value_shown"] = abs(float(ref["value"])) * factor
        if ref.get("computed") is not None:
            out["reference_computed_shown"] = sign * float(ref["computed"]) * factor
    except (TypeError, ValueError):
        pass
    return out


def run_quantities(rec: dict) -> dict:
    """Quantities of interest of a finished run (None where the run does not record them, and for a run that did
    not complete: its values are not results, the row says why)."""
    done = rec.get("status") == "completed"
    peak = rec.get("peak_load_N") if done else None
    q = {"peak_load_kN": peak / 1e3 if peak is not None else None, "wall_time_s": rec.get("wall_time_s"),
         "n_triangles": rec.get("n_triangles"), "D_frac_J": None, "W_ext_J": None}
    ref = (rec.get("summary") or {}).get("reference")
    if isinstance(ref, dict) and ref.get("monitor"):
        q["reference"] = f"{ref.get('monitor')} {ref.get('quantity', 'peak')}"
        q["reference_value"] = ref.get("value")
        q["reference_computed"] = ref.get("computed") if done else None
        q["reference_error"] = ref.get("relative_error") if done else None
    if not done:
        return q
    run = load_run(rec["run_dir"])
    if isinstance(ref, dict) and ref.get("monitor"):
        q.update(reference_shown(run, ref))
    h = run.history
    for col, key in (("D_frac", "D_frac_J"), ("W_ext", "W_ext_J")):
        if h.has(col) and len(h):
            q[key] = float(h.numeric(col)[-1])
    if q["peak_load_kN"] is None:
        try:
            _, y = run.curve_columns()
            q["peak_load_kN"] = float(np.max(np.abs(h.numeric(y)))) / 1e3
        except ToolError:
            pass
    return q


def failure_reason(rec: dict, lines: int = 3) -> str:
    """Why a run did not complete: its summary's message, else the last error and warning lines of its log (the
    last lines of the log when none says error or warning), joined by ' | '."""
    msg = ((rec.get("summary") or {}).get("message") or rec.get("message") or "").strip()
    if msg:
        return msg
    log = os.path.join(os.path.dirname(os.path.dirname(rec["run_dir"])), "logs", rec["name"] + ".log")
    try:
        with open(log, encoding="utf-8", errors="replace") as f:
            text = [ln.strip() for ln in f if ln.strip() and not ln.startswith("$ ")]
    except OSError:
        return f"no summary and no log ({log})" if rec.get("exit_code") is not None else "not run"
    hits = [ln for ln in text if "error" in ln.lower() or "warning" in ln.lower()]
    pick = (hits or text)[-lines:]
    return " | ".join(pick) if pick else f"no summary, empty log (exit code {rec.get('exit_code')})"


def richardson(hs, qs) -> dict:
    """Observed convergence order p and extrapolated value q* from three (h, q) pairs, h1 > h2 > h3 after sorting:
    q(h) = q* + C h^p (module docstring). {'order': None, ...} with a note when the differences do not shrink
    monotonically."""
    pts = sorted(((float(h), float(q)) for h, q in zip(hs, qs)), reverse=True)
    out = {"order": None, "extrapolated": None, "sizes": [p[0] for p in pts], "note": ""}
    if len(pts) != 3 or len({p[0] for p in pts}) != 3:
        out["note"] = "needs three different sizes"
        return out
    (h1, q1), (h2, q2), (h3, q3) = pts
    d12, d23 = q1 - q2, q2 - q3
    if d23 == 0 or d12 == 0:
        out["note"] = "a difference is zero (converged or insensitive)"
        return out
    ratio = d12 / d23
    if ratio <= 0:
        out["note"] = "the changes alternate in sign (oscillating): no order"
        return out

    def f(p):
        return (h1 ** p - h2 ** p) / (h2 ** p - h3 ** p) - ratio

    lo, hi = 1e-3, 20.0
    if f(lo) * f(hi) > 0:
        out["note"] = f"no order in [{lo:g}, {hi:g}] (ratio of changes {ratio:.3g})"
        return out
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if f(lo) * f(mid) <= 0:
            hi = mid
        else:
            lo = mid
    p = 0.5 * (lo + hi)
    out["order"] = p
    out["extrapolated"] = q3 + (q3 - q2) / ((h2 / h3) ** p - 1.0)
    return out


def _is_size_key(key: str) -> bool:
    return key.split(".")[-1].startswith("mesh_size")


def pareto_front(times, errors) -> list:
    """Indices of the non-dominated points (lower time and lower error both better), fastest first."""
    order = sorted(range(len(times)), key=lambda i: (times[i], errors[i]))
    front, best = [], math.inf
    for i in order:
        if errors[i] < best:
            front.append(i)
            best = errors[i]
    return front


CURVE_POINTS = 2001


def curve_errors(x, y, xr, yr, u_to, u_from, smooth: float = 0.0) -> dict:
    """Whole-curve difference of H(u) = (x, y) from the reference (xr, yr), as shares of the reference peak:
    curve_rms over [0, u_to], curve_max over [u_from, u_to] (module doc). Either is None, with a reason, when a
    curve does not reach u_to. With smooth > 0 (m of travel) also curve_max_smoothed: curve_max of the two loading
    branches each averaged over smooth of travel first (curves.smooth_curve)."""
    xb, yb = loading_branch(x, y)
    xrb, yrb = loading_branch(xr, yr)
    p_ref = float(np.max(yrb)) if len(yrb) else 0.0
    out = {"curve_rms": None, "curve_max": None, "curve_note": ""}
    if smooth > 0:
        out["curve_max_smoothed"] = None
    if p_ref <= 0:
        out["curve_note"] = "the reference curve has no positive load"
        return out
    for name, xs in (("the run", xb), ("the reference", xrb)):
        if len(xs) < 2 or xs[-1] < u_to * (1 - 1e-9):
            reach = xs[-1] if len(xs) else 0.0
            out["curve_note"] = f"{name}'s curve ends at {reach * 1e3:.4g} mm, before {u_to * 1e3:.4g} mm"
            return out
    g = np.linspace(0.0, u_to, CURVE_POINTS)
    d = (np.interp(g, xb, yb) - np.interp(g, xrb, yrb)) / p_ref
    out["curve_rms"] = float(np.sqrt(np.mean(d * d)))
    out["curve_max"] = float(np.max(np.abs(d[g >= u_from])))
    if smooth > 0:
        ds = (np.interp(g, xb, smooth_curve(xb, yb, smooth)) - np.interp(g, xrb, smooth_curve(xrb, yrb, smooth))) / p_ref
        out["curve_max_smoothed"] = float(np.max(np.abs(ds[g >= u_from])))
    return out


def _signed_rel(a, b):
    if a is None or b is None or not np.isfinite(a) or not np.isfinite(b) or b == 0:
        return None
    return (a - b) / abs(b)


def curve_quantities(run_dir: str) -> dict:
    """The loading curve of a run and its EEEP quantities (validate.curve_metrics: last stage, the load sign rule)."""
    from .validate import curve_metrics
    m = curve_metrics(run_dir)
    py = None
    try:
        from .eeep import eeep
        py = float(eeep(m["x"], m["y"], source=run_dir, load_sign=1.0)["P_y"])
    except (ToolError, ValueError, ZeroDivisionError, FloatingPointError):
        pass
    return {"x": m["x"], "y": m["y"], "peak": m["peak_load_N"], "K_e": m.get("eeep_K_e_N_m"), "P_y": py,
            "ductility": m.get("ductility"), "reach": m["reach_m"]}


def _batch(args, points, out, grid):
    """The study's runs on the local pool or, with --scheduler slurm, as a job array; None when nothing is to be
    evaluated now (--dry-run, --no-wait)."""
    from .batch import print_commands
    from .slurm import job_name, options_from_args, report_failures
    fixed = [parse_assignment(s, "--set") for s in args.set or []]
    slurm = options_from_args(args, job_name("fdem-study", out))
    threads = slurm.cpus_per_task if slurm else args.threads
    if args.dry_run and not slurm:
        print_commands(Batch(args.case, out, fdem_binary(args.fdem, must_exist=False), threads=threads, fixed=fixed),
                       points)
        return None
    b = Batch(args.case, out, fdem_binary(args.fdem, must_exist=not args.dry_run), threads=threads, fixed=fixed,
              timeout=args.timeout)
    recs = b.run(points, jobs=args.jobs or 1, grid=grid, slurm=slurm)
    if recs is not None and slurm and any(r["status"] != "completed" for r in recs):
        print("fdem-tools study: runs that did not complete (Slurm state and log of each):", file=sys.stderr)
        report_failures(recs, os.path.join(b.out, "slurm"))
    return recs


def cmd_mesh(args):
    sizes = split_values(args.sizes)
    hs = [_num(s) for s in sizes]
    size_key = _is_size_key(args.key)
    if any(h is None or h <= 0 for h in hs):
        raise ToolError(f"--sizes: expected positive numbers{' in m' if size_key else ''}, got '{args.sizes}'")
    # the study's variable: a mesh size in m (plotted in mm), or any other key under its own name, unscaled
    var = "mesh_size_m" if size_key else args.key
    var_label, var_scale = ("mesh size (mm)", 1e3) if size_key else (f"{args.key} (as given)", 1.0)
    out = args.out_dir or os.path.join("runs", "study_mesh_" + os.path.splitext(os.path.basename(args.case))[0])
    recs = _batch(args, [{args.key: s} for s in sizes], out, [[args.key, sizes]])
    if recs is None:
        return 0
    rows = []
    for h, r in zip(hs, recs):
        q = run_quantities(r)
        why = "" if r["status"] == "completed" else failure_reason(r)
        rows.append({var: h, "status": r["status"], **q, "why": why, "run": r["name"]})
    for r in rows:
        for k in ("reference", "reference_value", "reference_computed", "reference_error", "reference_unit",
                  "reference_sign", "reference_sign_rule", "reference_value_shown", "reference_computed_shown"):
            r.setdefault(k, None)
    ok = [r for r in rows if r["status"] == "completed"]
    for r in rows:
        if r["why"]:
            print(f"  {var} = {r[var]:g}: {r['status']}: {r['why']}")
    if not ok:
        raise ToolError(f"no run of the mesh study completed (see {os.path.join(out, 'logs')}); "
                        + "; ".join(f"{r[var]:g}: {r['why']}" for r in rows))
    finest = min(ok, key=lambda r: r[var])
    ref_name = next((r["reference"] for r in ok if r["reference"]), None)
    ref_unit = next((r["reference_unit"] for r in ok if r["reference_unit"]), None)
    qty = [("peak_load_kN", "peak load", 1.0, "kN"),
           ("reference_computed_shown", f"reference: {ref_name}", 1.0, ref_unit),
           ("D_frac_J", "fracture dissipation", 1.0, "J"), ("W_ext_J", "external work", 1.0, "J")]
    qty = [t for t in qty if any(r[t[0]] is not None for r in ok)]
    orders = {}
    for r in rows:
        for key, *_ in qty:
            ref = finest[key]
            r[key + "_rel_to_finest"] = (r[key] - ref) / abs(ref) if r[key] is not None and ref else None
    for key, name, *_ in qty:
        pts = sorted([(r[var], r[key]) for r in ok if r[key] is not None])[:3]  # the three finest
        if len(pts) == 3:
            orders[key] = richardson([p[0] for p in pts], [p[1] for p in pts])
    header = list(rows[0].keys())
    write_csv(os.path.join(out, "mesh_study.csv"), header, [[r[k] for k in header] for r in rows])
    write_json(os.path.join(out, "mesh_study.json"), {"case": os.path.abspath(args.case), "key": args.key,
                                                     "variable": var, "finest": finest[var],
                                                     "convergence_order": orders, "runs": rows})
    from .figures import run_stamp, save
    fig, _ = mesh_figure(ok, qty, orders, var, var_label, var_scale, size_key, finest)
    files = save(fig, os.path.join(out, "mesh_study"), run_stamp([r.get("summary") for r in recs]))
    print(format_rows(rows, [var, "status", "peak_load_kN", "reference_computed_shown", "reference_error", "D_frac_J",
                             "wall_time_s", "n_triangles"]))
    if ref_name:
        val = finest["reference_value_shown"]
        print(f"reference quantity of the case: {ref_name}, value "
              + (f"{val:.6g} {finest['reference_unit']} (|value|, as the engine compares it)" if val is not None
                 else "none") + "; reference_computed_shown in "
              f"{finest['reference_unit']}, sign {finest['reference_sign']:+g} ({finest['reference_sign_rule']})")
    for key, o in orders.items():
        if o["order"] is not None:
            print(f"{key}: observed convergence order {o['order']:.3g} (three finest: {o['sizes']}), "
                  f"extrapolated {o['extrapolated']:.6g}")
        else:
            print(f"{key}: no convergence order: {o['note']}")
    print("wrote " + ", ".join([os.path.join(out, "mesh_study.csv"), os.path.join(out, "mesh_study.json")] + files))
    return 0 if len(ok) == len(rows) else 2


def mesh_figure(ok, qty, orders, var, var_label, var_scale, size_key, finest):
    """One panel per quantity and one of the run time, at most three panels a row (figure and axes, not saved)."""
    from .figures import new_figure
    n = len(qty) + 1
    ncol = min(3, n)
    nrow = (n + ncol - 1) // ncol
    fig, axs = new_figure(nrow, ncol, figsize=(4.4 * ncol, 3.9 * nrow), squeeze=False)
    flat = list(axs.ravel())
    for ax in flat[n:]:
        ax.set_visible(False)
    h_ok = np.array([r[var] for r in ok]) * var_scale
    for ax, (key, name, scale, unit) in zip(flat, qty):
        v = [r[key] for r in ok]
        sel = [i for i, x in enumerate(v) if x is not None]
        ax.plot(h_ok[sel], np.array([v[i] for i in sel]) * scale, "o-", color="#1f77b4", label="runs")
        if key == "reference_computed_shown" and finest.get("reference_value_shown") is not None:
            ax.axhline(finest["reference_value_shown"], color="k", lw=1.0, ls="--", label="reference value")
            ax.legend(fontsize=7)
        _mesh_axis(ax, h_ok, var_label, size_key)
        ax.set_ylabel(f"{name} ({unit})")
        ax.ticklabel_format(axis="y", style="plain", useOffset=False)
        o = orders.get(key)
        ax.set_title(name + (f"\nobserved order {o['order']:.2f}" if o and o["order"] is not None else ""),
                     fontsize=9)
    ax = flat[n - 1]
    t = [r["wall_time_s"] for r in ok]
    ax.loglog(h_ok, t, "s-", color="#d62728")
    for x, y, r in zip(h_ok, t, ok):
        if r["n_triangles"]:
            ax.annotate(f"{r['n_triangles']} tri", (x, y), xytext=(4, 4), textcoords="offset points", fontsize=7)
    _mesh_axis(ax, h_ok, var_label, size_key)
    ax.set_ylabel("wall time (s)")
    ax.set_title("run time", fontsize=9)
    return fig, axs


def _mesh_axis(ax, h, label="mesh size (mm)", log=True):
    """Mesh-variable axis labelled at the values run, finer meshes (smaller values) to the right."""
    from matplotlib.ticker import NullLocator
    if log:
        ax.set_xscale("log")
        ax.xaxis.set_minor_locator(NullLocator())
    ax.set_xticks(sorted(set(h)))
    ax.set_xticklabels([f"{v:g}" for v in sorted(set(h))])
    ax.invert_xaxis()
    ax.set_xlabel(label)


def format_rows(rows, keys):
    from .batch import format_table
    return format_table(keys, [[r.get(k) for k in keys] for r in rows])


def _accuracy_key(dims):
    """Sort key of a run: smaller is more accurate in each dimension (mesh size, rate, damping, ...: their absolute
    values; non-numeric values: their order in the list given)."""
    def key(r):
        out = []
        for k, vals, _ in dims:
            v = r["params"][k]
            x = _num(v)
            out.append(abs(x) if x is not None else vals.index(v))
        return out
    return key


def cmd_speed(args):
    dims = []
    if args.sizes:
        dims.append((args.size_key, split_values(args.sizes), "mesh size"))
    for vals, key, name in ((args.rates, args.rate_key, "rate"), (args.damping, args.damping_key, "damping")):
        if vals:
            if not key:
                raise ToolError(f"--{'rates' if name == 'rate' else 'damping'} needs --{name}-key (the case key to set)")
            dims.append((key, split_values(vals), name))
    if not dims:
        raise ToolError("give at least one of --sizes, --rates, --damping")
    for g in args.grid or []:
        k, v = parse_assignment(g)
        dims.append((k, split_values(v), k))
    from .batch import expand_grid
    points = expand_grid([(k, v) for k, v, _ in dims])
    out = args.out_dir or os.path.join("runs", "study_speed_" + os.path.splitext(os.path.basename(args.case))[0])
    recs = _batch(args, points, out, [[k, v] for k, v, _ in dims])
    if recs is None:
        return 0
    ok = [r for r in recs if r["status"] == "completed" and r.get("peak_load_N") is not None
          and r.get("wall_time_s") is not None]
    if not ok:
        raise ToolError(f"no run of the speed study completed (see {os.path.join(out, 'logs')})")
    # reference peak load
    ref_run = None
    case_ref = case_reference(ok)
    value_of = lambda r: r["peak_load_N"]  # noqa: E731  (the quantity each run's error is taken on)
    ref_qty = "peak load"
    if args.reference is not None:
        ref, ref_src = args.reference * 1e3, "given (--reference)"
    elif case_ref is not None:
        # the case's own [reference]: its monitor and quantity (peak, first_peak or final) as each run computed it,
        # against |value| (the engine's comparison: magnitudes)
        ref = abs(float(case_ref["value"]))
        ref_qty = f"{case_ref['monitor']} {case_ref.get('quantity', 'peak')}"
        ref_src = f"case reference ({ref_qty} = {_show(ref, case_ref['unit'])})"
        value_of = lambda r: _ref_computed(r)  # noqa: E731
    elif ok[0].get("reference_peak_N"):
        ref, ref_src = ok[0]["reference_peak_N"], "case reference (peak_load_N)"
    else:
        best = min(ok, key=_accuracy_key(dims))
        ref, ref_src = best["peak_load_N"], "most accurate run"
        ref_run = best["name"]
    if not ref:
        raise ToolError("the reference peak load is zero")
    # reference curve: --reference-run, else the most accurate run of the grid
    curves = {}
    for r in ok:
        try:
            curves[r["name"]] = curve_quantities(r["run_dir"])
        except ToolError as e:
            print(f"fdem-tools study: {r['name']}: no curve ({e})", file=sys.stderr)
    if args.reference_run:
        try:
            cref = curve_quantities(args.reference_run)
        except ToolError as e:
            raise ToolError(f"--reference-run {args.reference_run}: {e}")
        cref_src = f"run {args.reference_run}"
    else:
        best_curve = min([r for r in ok if r["name"] in curves], key=_accuracy_key(dims), default=None)
        cref = curves.get(best_curve["name"]) if best_curve else None
        cref_src = f"most accurate run ({best_curve['name']})" if best_curve else None
    u_to = args.curve_to
    if cref is not None and u_to is None:
        u_to = min([c["reach"] for c in curves.values()] + [cref["reach"]])
    if u_to is not None and not u_to > 0:
        raise ToolError(f"--curve-to must be a positive displacement in m, got {u_to:g}")
    u_from = args.curve_from if args.curve_from is not None else (0.05 * u_to if u_to else None)
    if u_from is not None and u_to is not None and not 0 <= u_from < u_to:
        raise ToolError(f"--curve-from must be in [0, {u_to:g}) m, got {u_from:g}")
    smooth = getattr(args, "curve_smooth", 0.0) or 0.0
    if not smooth >= 0:
        raise ToolError(f"--curve-smooth must be a window >= 0 mm, got {smooth}")
    smooth *= 1e-3
    if args.error == "curve_max_smoothed" and not smooth > 0:
        raise ToolError("--error curve_max_smoothed needs --curve-smooth MM (the window of travel, mm)")
    rows = []
    for r in recs:
        v = value_of(r) if r in ok else None
        err = abs(v - ref) / abs(ref) if v is not None else None
        row = {**r["params"], "status": r["status"], "wall_time_s": r.get("wall_time_s"),
               "cpu_time_s": r.get("cpu_time_s"), "steps": r.get("steps"),
               "peak_load_kN": r["peak_load_N"] / 1e3 if r.get("peak_load_N") is not None else None,
               "error": err, "error_quantity": ref_qty, "curve_rms": None, "curve_max": None,
               **({"curve_max_smoothed": None} if smooth > 0 else {}), "K_e_error": None, "P_y_error": None,
               "ductility_error": None, "peak_error": None, "curve_note": "", "pareto": False, "run": r["name"]}
        c = curves.get(r["name"])
        if c is not None and cref is not None:
            row.update(curve_errors(c["x"], c["y"], cref["x"], cref["y"], u_to, u_from, smooth))
            for k in ("K_e", "P_y", "ductility"):
                row[k + "_error"] = _signed_rel(c[k], cref[k])
            row["peak_error"] = _signed_rel(c["peak"], cref["peak"])
        rows.append(row)
    bound = None
    if not getattr(args, "no_bound", False):
        # the zero-cost end of speed against error: the rigid-block bound of the case's own blocks (fdem-tools limit),
        # with the time of its export and LP, as a point of the study (its peak error only: it has no curve)
        from .validate import rigid_block_bound
        fixed = [parse_assignment(s, "--set") for s in args.set or []]
        bound = rigid_block_bound(args.case, fixed, fdem_binary(args.fdem), os.path.join(out, "limit"))
        if "bound_N" in bound:
            v = bound["bound_N"]
            rows.append({**{k: "" for k in rows[0] if k not in ("status",)}, "status": "rigid-block bound",
                         "wall_time_s": bound["time_s"], "cpu_time_s": bound["time_s"], "steps": 0,
                         "peak_load_kN": v / 1e3, "error": abs(v - ref) / abs(ref) if ref_qty != "final" else None,
                         "error_quantity": ref_qty, "curve_note": "no curve (limit analysis)", "pareto": False,
                         "run": "rigid-block bound"})
            for k in ("curve_rms", "curve_max", "curve_max_smoothed", "K_e_error", "P_y_error", "ductility_error",
                      "peak_error"):
                if k in rows[0]:
                    rows[-1][k] = None
            if cref is not None:
                rows[-1]["peak_error"] = _signed_rel(v, cref["peak"])
        else:
            print(f"fdem-tools study: no rigid-block bound for this case ({bound['note']})", file=sys.stderr)
    measure = "error" if args.error == "peak" else args.error
    valid = [i for i, r in enumerate(rows) if r[measure] is not None]
    if not valid:
        raise ToolError(f"no run has a {args.error} error (" + "; ".join(sorted({r['curve_note'] for r in rows
                                                                                 if r['curve_note']})) + ")")
    tkey = "cpu_time_s" if getattr(args, "timing", "wall") == "cpu" else "wall_time_s"
    if tkey == "cpu_time_s":
        missing = [rows[i]["run"] for i in valid if rows[i]["cpu_time_s"] is None]
        if missing:
            raise ToolError(f"--timing cpu: no cpu_time_s in the summary of {len(missing)} run(s) (e.g. {missing[0]}; "
                            "written by fdem since 27 Nov 2026): rerun them or use --timing wall")
    front = [valid[i] for i in pareto_front([rows[i][tkey] for i in valid], [rows[i][measure] for i in valid])]
    for i in front:
        rows[i]["pareto"] = True
    header = list(rows[0].keys())
    write_csv(os.path.join(out, "speed_study.csv"), header, [[r[k] for k in header] for r in rows])
    write_json(os.path.join(out, "speed_study.json"), {"case": os.path.abspath(args.case), "reference_peak_N": ref,
                                                      "reference": ref_src, "reference_quantity": ref_qty, "reference_run": ref_run,
                                                      "reference_curve": cref_src, "curve_to_m": u_to,
                                                      "curve_from_m": u_from, "front_error": args.error, "runs": rows})
    from .figures import run_stamp
    files = plot_speed(rows, dims, ref_src if args.error == "peak" else cref_src, os.path.join(out, "speed_study"),
                       measure, args.error, tkey, stamp=run_stamp([r.get("summary") for r in recs]))
    print(format_rows(rows, [k for k, _, _ in dims] + ["status", "wall_time_s", "cpu_time_s", "peak_load_kN", "error", "curve_rms",
                                                       "curve_max"] + (["curve_max_smoothed"] if smooth > 0 else [])
                      + ["K_e_error", "ductility_error", "pareto"]))
    if case_ref is not None and args.reference is None:
        print(f"error against the {ref_src}: |computed| of each run (summary.json reference.computed) against "
              "|value|")
    else:
        print(f"reference peak load {ref / 1e3:.5g} kN: {ref_src}" + (f" ({ref_run})" if ref_run else ""))
    if cref_src:
        print(f"reference curve: {cref_src}; curve_rms over 0-{u_to * 1e3:.4g} mm, curve_max over "
              f"{u_from * 1e3:.4g}-{u_to * 1e3:.4g} mm, shares of its peak {cref['peak'] / 1e3:.5g} kN"
              + (f"; curve_max_smoothed: the same on both curves averaged over {smooth * 1e3:g} mm of travel"
                 if smooth > 0 else "") + f"; Pareto front on the {args.error} error")
    print("wrote " + ", ".join([os.path.join(out, "speed_study.csv"), os.path.join(out, "speed_study.json")] + files))
    return 0 if len(ok) == len(recs) else 2


def case_reference(recs) -> dict | None:
    """The case's [reference] as the runs' summaries carry it (monitor, quantity, value, and the monitor's unit),
    when it has a monitor and a non-zero value; else None."""
    for r in recs:
        s = r.get("summary") or {}
        ref = s.get("reference")
        if isinstance(ref, dict) and ref.get("monitor") and ref.get("value") not in (None, 0):
            try:
                float(ref["value"])
            except (TypeError, ValueError):
                continue
            return {**ref, "unit": (s.get("columns") or {}).get(ref["monitor"], "")}
    return None


def _ref_computed(rec) -> float | None:
    """|reference.computed| of a run (its value of the case's reference quantity), None if it has none."""
    ref = (rec.get("summary") or {}).get("reference")
    try:
        return abs(float(ref["computed"]))
    except (TypeError, KeyError, ValueError):
        return None


def _show(v: float, unit: str) -> str:
    shown, factor = SHOWN_UNITS.get(unit, (unit, 1.0))
    return f"{v * factor:.5g} {shown}".strip()


def plot_speed(rows, dims, ref_src, prefix, measure="error", label="peak", tkey="wall_time_s", stamp: str = ""):
    from .figures import new_figure, save
    fig, ax = new_figure(figsize=(7.2, 5.0))
    rows = [{**r, "error": r[measure]} for r in rows]
    valid = [r for r in rows if r["error"] is not None]
    floor = min([r["error"] for r in valid if r["error"] > 0], default=1e-6) / 3.0
    # colour by the first dimension, marker by the second
    k0 = dims[0][0]
    v0 = list(dict.fromkeys(r[k0] for r in valid if r.get("run") != "rigid-block bound"))
    markers = "osD^v<>pH*"
    k1 = dims[1][0] if len(dims) > 1 else None
    v1 = list(dict.fromkeys(r[k1] for r in valid if r.get("run") != "rigid-block bound")) if k1 else [None]
    import matplotlib.pyplot as plt
    cmap = plt.get_cmap("viridis", max(2, len(v0)))
    for r in [r for r in valid if r.get("run") == "rigid-block bound"]:
        ax.plot(r[tkey], 100 * max(r["error"], floor), "*", color="tab:red", ms=13,
                mec="k" if r["pareto"] else "none", ls="none")
    valid_runs = [r for r in valid if r.get("run") != "rigid-block bound"]
    for r in valid_runs:
        e = max(r["error"], floor)
        ax.plot(r[tkey], 100 * e, markers[v1.index(r[k1]) % len(markers)] if k1 else "o",
                color=cmap(v0.index(r[k0])), ms=7, mec="k" if r["pareto"] else "none", mew=1.2, ls="none")
    front = sorted([r for r in valid if r["pareto"]], key=lambda r: r[tkey])
    ax.step([r[tkey] for r in front], [100 * max(r["error"], floor) for r in front], where="post",
            color="k", lw=1.0, ls="--", label="Pareto front")
    from matplotlib.lines import Line2D
    handles = [Line2D([], [], color="k", lw=1.0, ls="--", label="Pareto front (black edge)")]
    name0 = dims[0][2]
    if any(r.get("run") == "rigid-block bound" for r in valid):
        handles.append(Line2D([], [], marker="*", color="tab:red", ms=11, ls="none",
                              label="rigid-block bound (limit analysis, export + LP)"))
    handles += [Line2D([], [], marker="o", color=cmap(i), ls="none", label=f"{name0} = {v}") for i, v in enumerate(v0)]
    if k1:
        handles += [Line2D([], [], marker=markers[i % len(markers)], color="0.4", ls="none",
                           label=f"{dims[1][2]} = {v}") for i, v in enumerate(v1)]
    if len(dims) > 2:
        ax.set_title("other dimensions: " + ", ".join(d[2] for d in dims[2:]) + " (not told apart)", fontsize=8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("CPU time (s)" if tkey == "cpu_time_s" else "wall time (s)")
    ax.set_ylabel({"peak": "peak-load error (%)", "curve_max": "largest curve difference (% of the reference peak)",
                   "curve_rms": "RMS curve difference (% of the reference peak)",
                   "curve_max_smoothed": "largest difference of the curves averaged over travel (% of the "
                                         "reference peak)"}[label])
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              title=f"error against: {ref_src}", title_fontsize=7)
    if any(r["error"] == 0 for r in valid):
        ax.text(0.01, 0.01, "error 0 (the reference run) drawn at the bottom edge", transform=ax.transAxes,
                fontsize=7, color="0.4")
    return save(fig, prefix, stamp)


def _common(p):
    p.add_argument("case", metavar="CASE.toml", help="case file")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="a fixed setting for every run (repeatable)")
    p.add_argument("--jobs", type=int, help="runs at a time (default 1: run times are measured, so runs do not share cores)")
    p.add_argument("--threads", type=int, default=1, help="OpenMP threads per run (default 1)")
    p.add_argument("--fdem", help="fdem executable (default: $FDEM_BIN, else build/fdem/fdem)")
    p.add_argument("--timeout", type=float, help="kill a run after this many seconds")
    from .slurm import add_arguments
    add_arguments(p, dry_run=True)


def add_parser(sub):
    p = sub.add_parser("study", help="mesh study and speed-versus-error study",
                       description="Parameter studies of a case: 'study mesh' (quantities of interest and run time "
                                   "against mesh size) and 'study speed' (wall time against error over mesh size, "
                                   "loading rate and damping, with the Pareto front). Resumable like batch.")
    ss = p.add_subparsers(dest="study", metavar="STUDY")
    m = ss.add_parser("mesh", help="run a case at several mesh sizes",
                      description="Runs the case at each mesh size and plots peak load, the case's reference "
                                  "quantity, fracture dissipation, external work (when recorded) and run time against "
                                  "mesh size, with the observed convergence order from the three finest sizes "
                                  "(Richardson); a run that failed is reported with the last error lines of its log.")
    _common(m)
    m.add_argument("--sizes", required=True, help="comma-separated mesh sizes in m, e.g. 0.1,0.05,0.025")
    m.add_argument("--key", default="geometry.mesh_size",
                   help="case key of the mesh size (default geometry.mesh_size); another key (a scale factor) is "
                        "tabulated and plotted under its own name, unscaled")
    m.add_argument("--out-dir", help="study folder (default runs/study_mesh_<case>)")
    m.set_defaults(func=cmd_mesh)
    s = ss.add_parser("speed", help="wall time against error over mesh sizes, loading rates and damping",
                      description="Runs the grid mesh sizes x loading rates x damping values and plots wall time "
                                  "against the error (peak load by default; --error curve_max or curve_rms: the "
                                  "whole loading curve against a reference curve), marking the Pareto front. Every "
                                  "run's whole-curve errors and the signed errors of K_e, P_y, ductility (EEEP) "
                                  "and peak against the reference curve are tabulated.")
    _common(s)
    s.add_argument("--sizes", help="mesh sizes in m (comma-separated)")
    s.add_argument("--size-key", default="geometry.mesh_size", help="case key of the mesh size")
    s.add_argument("--rates", help="loading rates (TOML values, comma-separated), set at --rate-key")
    s.add_argument("--rate-key", help="case key of the loading rate, e.g. stages.2.supports.2.vx")
    s.add_argument("--damping", help="damping values (comma-separated), set at --damping-key")
    s.add_argument("--damping-key", help="case key of the damping, e.g. stages.2.local_damping")
    s.add_argument("--grid", action="append", metavar="KEY=V1,V2", help="a further grid dimension (repeatable)")
    s.add_argument("--reference", type=float, help="reference peak load in kN (default: case reference, else the "
                                                   "most accurate run)")
    s.add_argument("--reference-run", metavar="RUN_DIR",
                   help="run folder whose loading curve is the reference of the whole-curve errors (default: the "
                        "most accurate run of the grid)")
    s.add_argument("--curve-to", type=float, metavar="M", help="end of the curve comparison, m (default: the "
                                                              "smallest reach of the runs and the reference)")
    s.add_argument("--curve-from", type=float, metavar="M", help="start of the largest-difference range, m "
                                                                "(default 5 %% of --curve-to)")
    s.add_argument("--curve-smooth", type=float, default=0.0, metavar="MM",
                   help="also curve_max_smoothed: curve_max of the run's and the reference's curves each averaged "
                        "over MM mm of travel first, as validate --smooth (default 0: not computed); it separates a "
                        "short load drop's position (a slip event's) from the curve's level")
    s.add_argument("--error", choices=("peak", "curve_max", "curve_rms", "curve_max_smoothed"), default="peak",
                   help="error of the Pareto front and the figure (default peak)")
    s.add_argument("--timing", choices=("wall", "cpu"), default="wall",
                   help="time of the Pareto front and the figure: the runs' wall time (default) or their CPU time "
                        "(summary.json cpu_time_s; on a machine shared with other jobs it stays near the time of "
                        "the run alone)")
    s.add_argument("--no-bound", action="store_true",
                   help="leave out the rigid-block bound (fdem-tools limit), the study's zero-cost point (default: "
                        "computed for a case that has one; its peak error only)")
    s.add_argument("--out-dir", help="study folder (default runs/study_speed_<case>)")
    s.set_defaults(func=cmd_speed)
    p.set_defaults(func=lambda a: p.print_help() or 1)
