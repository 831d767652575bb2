"""`study mesh` and `study speed`: parameter studies run through the batch machinery (so they resume too).

study mesh: the case at a list of mesh sizes h; quantities of interest per run: peak load (largest |load| of the
  case's curve), final fracture dissipation D_frac and external work W_ext when recorded, run time and triangle
  count. The change of each quantity relative to the finest mesh is tabulated and plotted against h.
study speed: a grid of mesh sizes x loading rates x damping values. Error of a run: |P - P_ref| / |P_ref| of its
  peak load, with P_ref given (--reference, kN), else the case's reference peak, else the peak of the most
  accurate run of the grid (smallest mesh size, slowest rate, least damping). A run is on the Pareto front when
  no other run is at the same time both faster and more accurate.
"""
from __future__ import annotations

import math
import os
import sys

import numpy as np

from .batch import Batch, fdem_binary, parse_assignment, split_values
from .common import ToolError, load_run, write_csv, write_json


def _num(v: str):
    try:
        return float(v)
    except ValueError:
        return None


def run_quantities(rec: dict) -> dict:
    """Quantities of interest of a finished run (None where the run does not record them)."""
    q = {"peak_load_N": rec.get("peak_load_N"), "wall_time_s": rec.get("wall_time_s"),
         "n_triangles": rec.get("n_triangles"), "D_frac_J": None, "W_ext_J": None}
    if rec.get("status") != "completed":
        return q
    run = load_run(rec["run_dir"])
    h = run.history
    for col, key in (("D_frac", "D_frac_J"), ("W_ext", "W_ext_J")):
        if h.has(col) and len(h):
            q[key] = float(h.numeric(col)[-1])
    if q["peak_load_N"] is None:
        try:
            _, y = run.curve_columns()
            q["peak_load_N"] = float(np.max(np.abs(h.numeric(y))))
        except ToolError:
            pass
    return q


def pareto_front(times, errors) -> list:
    """Indices of the non-dominated points (lower time and lower error both better), fastest first."""
    order = sorted(range(len(times)), key=lambda i: (times[i], errors[i]))
    front, best = [], math.inf
    for i in order:
        if errors[i] < best:
            front.append(i)
            best = errors[i]
    return front


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
    if any(h is None or h <= 0 for h in hs):
        raise ToolError(f"--sizes: expected positive numbers in m, got '{args.sizes}'")
    out = args.out_dir or os.path.join("runs", "study_mesh_" + os.path.splitext(os.path.basename(args.case))[0])
    recs = _batch(args, [{args.key: s} for s in sizes], out, [[args.key, sizes]])
    if recs is None:
        return 0
    rows = []
    for h, r in zip(hs, recs):
        q = run_quantities(r)
        rows.append({"mesh_size_m": h, "status": r["status"], **q, "run": r["name"]})
    ok = [r for r in rows if r["status"] == "completed"]
    if not ok:
        raise ToolError(f"no run of the mesh study completed (see {os.path.join(out, 'logs')})")
    finest = min(ok, key=lambda r: r["mesh_size_m"])
    qty = [("peak_load_N", "peak load", 1e-3, "kN"), ("D_frac_J", "fracture dissipation", 1.0, "J"),
           ("W_ext_J", "external work", 1.0, "J")]
    qty = [t for t in qty if any(r[t[0]] is not None for r in ok)]
    for r in rows:
        for key, *_ in qty:
            ref = finest[key]
            r[key + "_rel_to_finest"] = (r[key] - ref) / abs(ref) if r[key] is not None and ref else None
    header = list(rows[0].keys())
    write_csv(os.path.join(out, "mesh_study.csv"), header, [[r[k] for k in header] for r in rows])
    write_json(os.path.join(out, "mesh_study.json"), {"case": os.path.abspath(args.case), "key": args.key,
                                                     "finest_mesh_size_m": finest["mesh_size_m"], "runs": rows})
    from .figures import new_figure, save
    n = len(qty) + 1
    fig, axs = new_figure(1, n, figsize=(4.2 * n, 4.0), squeeze=False)
    h_ok = np.array([r["mesh_size_m"] for r in ok]) * 1e3
    for ax, (key, name, scale, unit) in zip(axs[0], qty):
        v = [r[key] for r in ok]
        sel = [i for i, x in enumerate(v) if x is not None]
        ax.plot(h_ok[sel], np.array([v[i] for i in sel]) * scale, "o-", color="#1f77b4")
        _mesh_axis(ax, h_ok)
        ax.set_ylabel(f"{name} ({unit})")
        ax.set_title(name, fontsize=9)
    ax = axs[0, -1]
    t = [r["wall_time_s"] for r in ok]
    ax.loglog(h_ok, t, "s-", color="#d62728")
    for x, y, r in zip(h_ok, t, ok):
        if r["n_triangles"]:
            ax.annotate(f"{r['n_triangles']} tri", (x, y), xytext=(4, 4), textcoords="offset points", fontsize=7)
    _mesh_axis(ax, h_ok)
    ax.set_ylabel("wall time (s)")
    ax.set_title("run time", fontsize=9)
    files = save(fig, os.path.join(out, "mesh_study"))
    print(format_rows(rows, ["mesh_size_m", "status", "peak_load_N", "D_frac_J", "wall_time_s", "n_triangles"]))
    print("wrote " + ", ".join([os.path.join(out, "mesh_study.csv"), os.path.join(out, "mesh_study.json")] + files))
    return 0 if len(ok) == len(rows) else 2


def _mesh_axis(ax, h_mm):
    """Log mesh-size axis labelled at the sizes run, finer meshes to the right."""
    from matplotlib.ticker import NullLocator
    ax.set_xscale("log")
    ax.xaxis.set_minor_locator(NullLocator())
    ax.set_xticks(sorted(set(h_mm)))
    ax.set_xticklabels([f"{h:g}" for h in sorted(set(h_mm))])
    ax.invert_xaxis()
    ax.set_xlabel("mesh size (mm)")


def format_rows(rows, keys):
    from .batch import format_table
    return format_table(keys, [[r.get(k) for k in keys] for r in rows])


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
    if args.reference is not None:
        ref, ref_src = args.reference * 1e3, "given (--reference)"
    elif ok[0].get("reference_peak_N"):
        ref, ref_src = ok[0]["reference_peak_N"], "case reference"
    else:
        def accuracy_key(r):  # smaller is more accurate in each dimension; non-numeric values: their list order
            key = []
            for k, vals, _ in dims:
                v = r["params"][k]
                x = _num(v)
                key.append(abs(x) if x is not None else vals.index(v))
            return key
        best = min(ok, key=accuracy_key)
        ref, ref_src = best["peak_load_N"], "most accurate run"
        ref_run = best["name"]
    if not ref:
        raise ToolError("the reference peak load is zero")
    rows = []
    for r in recs:
        err = abs(r["peak_load_N"] - ref) / abs(ref) if r in ok else None
        rows.append({**r["params"], "status": r["status"], "wall_time_s": r.get("wall_time_s"),
                     "peak_load_kN": r["peak_load_N"] / 1e3 if r.get("peak_load_N") is not None else None,
                     "error": err, "pareto": False, "run": r["name"]})
    valid = [i for i, r in enumerate(rows) if r["error"] is not None]
    front = [valid[i] for i in pareto_front([rows[i]["wall_time_s"] for i in valid], [rows[i]["error"] for i in valid])]
    for i in front:
        rows[i]["pareto"] = True
    header = list(rows[0].keys())
    write_csv(os.path.join(out, "speed_study.csv"), header, [[r[k] for k in header] for r in rows])
    write_json(os.path.join(out, "speed_study.json"), {"case": os.path.abspath(args.case), "reference_peak_N": ref,
                                                      "reference": ref_src, "reference_run": ref_run, "runs": rows})
    files = plot_speed(rows, dims, ref_src, os.path.join(out, "speed_study"))
    print(format_rows(rows, [k for k, _, _ in dims] + ["status", "wall_time_s", "peak_load_kN", "error", "pareto"]))
    print(f"reference peak load {ref / 1e3:.5g} kN: {ref_src}" + (f" ({ref_run})" if ref_run else ""))
    print("wrote " + ", ".join([os.path.join(out, "speed_study.csv"), os.path.join(out, "speed_study.json")] + files))
    return 0 if len(ok) == len(recs) else 2


def plot_speed(rows, dims, ref_src, prefix):
    from .figures import new_figure, save
    fig, ax = new_figure(figsize=(7.2, 5.0))
    valid = [r for r in rows if r["error"] is not None]
    floor = min([r["error"] for r in valid if r["error"] > 0], default=1e-6) / 3.0
    # colour by the first dimension, marker by the second
    k0 = dims[0][0]
    v0 = list(dict.fromkeys(r[k0] for r in valid))
    markers = "osD^v<>pH*"
    k1 = dims[1][0] if len(dims) > 1 else None
    v1 = list(dict.fromkeys(r[k1] for r in valid)) if k1 else [None]
    import matplotlib.pyplot as plt
    cmap = plt.get_cmap("viridis", max(2, len(v0)))
    for r in valid:
        e = max(r["error"], floor)
        ax.plot(r["wall_time_s"], 100 * e, markers[v1.index(r[k1]) % len(markers)] if k1 else "o",
                color=cmap(v0.index(r[k0])), ms=7, mec="k" if r["pareto"] else "none", mew=1.2, ls="none")
    front = sorted([r for r in valid if r["pareto"]], key=lambda r: r["wall_time_s"])
    ax.step([r["wall_time_s"] for r in front], [100 * max(r["error"], floor) for r in front], where="post",
            color="k", lw=1.0, ls="--", label="Pareto front")
    from matplotlib.lines import Line2D
    handles = [Line2D([], [], color="k", lw=1.0, ls="--", label="Pareto front (black edge)")]
    name0 = dims[0][2]
    handles += [Line2D([], [], marker="o", color=cmap(i), ls="none", label=f"{name0} = {v}") for i, v in enumerate(v0)]
    if k1:
        handles += [Line2D([], [], marker=markers[i % len(markers)], color="0.4", ls="none",
                           label=f"{dims[1][2]} = {v}") for i, v in enumerate(v1)]
    if len(dims) > 2:
        ax.set_title("other dimensions: " + ", ".join(d[2] for d in dims[2:]) + " (not told apart)", fontsize=8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("wall time (s)")
    ax.set_ylabel("peak-load error (%)")
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0),
              title=f"error against: {ref_src}", title_fontsize=7)
    if any(r["error"] == 0 for r in valid):
        ax.text(0.01, 0.01, "error 0 (the reference run) drawn at the bottom edge", transform=ax.transAxes,
                fontsize=7, color="0.4")
    return save(fig, prefix)


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
                      description="Runs the case at each mesh size and plots peak load, fracture dissipation, "
                                  "external work (when recorded) and run time against mesh size.")
    _common(m)
    m.add_argument("--sizes", required=True, help="comma-separated mesh sizes in m, e.g. 0.1,0.05,0.025")
    m.add_argument("--key", default="geometry.mesh_size", help="case key of the mesh size (default geometry.mesh_size)")
    m.add_argument("--out-dir", help="study folder (default runs/study_mesh_<case>)")
    m.set_defaults(func=cmd_mesh)
    s = ss.add_parser("speed", help="wall time against error over mesh sizes, loading rates and damping",
                      description="Runs the grid mesh sizes x loading rates x damping values and plots wall time "
                                  "against the peak-load error, marking the Pareto front.")
    _common(s)
    s.add_argument("--sizes", help="mesh sizes in m (comma-separated)")
    s.add_argument("--size-key", default="geometry.mesh_size", help="case key of the mesh size")
    s.add_argument("--rates", help="loading rates (TOML values, comma-separated), set at --rate-key")
    s.add_argument("--rate-key", help="case key of the loading rate, e.g. stages.1.supports.1.vx")
    s.add_argument("--damping", help="damping values (comma-separated), set at --damping-key")
    s.add_argument("--damping-key", help="case key of the damping, e.g. stages.1.local_damping")
    s.add_argument("--grid", action="append", metavar="KEY=V1,V2", help="a further grid dimension (repeatable)")
    s.add_argument("--reference", type=float, help="reference peak load in kN (default: case reference, else the "
                                                   "most accurate run)")
    s.add_argument("--out-dir", help="study folder (default runs/study_speed_<case>)")
    s.set_defaults(func=cmd_speed)
    p.set_defaults(func=lambda a: p.print_help() or 1)
