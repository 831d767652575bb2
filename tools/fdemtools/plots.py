"""`plot`: force-displacement curves of runs against the experiment, energy histories, damage progression.

Figures (each as PNG and SVG):
  curves.png            load against control displacement for every run and experimental curve;
  energy_<run>.png      energies against time (J) and the relative energy-balance error;
  damage_<run>.png      cumulative broken cohesive elements in units and at interfaces against the control
                        displacement, over the run's force-displacement curve.
"""
from __future__ import annotations

import os

import numpy as np

from .common import (DEFAULT_X_UNIT, DEFAULT_Y_UNIT, FORCE_UNITS, LENGTH_UNITS, SIGN_CHOICES, ToolError, load_curve,
                     load_run)
from .curves import resolve_sign

ENERGY_COLUMNS = [  # column, label, style
    ("W_ext", "external work $W_{ext}$", {"color": "k", "lw": 2.0}),
    ("E_kin", "kinetic", {"color": "#ff7f0e"}),
    ("E_el", "elastic (triangles)", {"color": "#1f77b4"}),
    ("E_joint", "joint elastic", {"color": "#17becf"}),
    ("E_contact", "contact", {"color": "#bcbd22"}),
    ("D_damp", "dissipated: damping", {"color": "#7f7f7f", "ls": "--"}),
    ("D_visc", "dissipated: viscosity", {"color": "#8c564b", "ls": "--"}),
    ("D_frac", "dissipated: fracture", {"color": "#d62728", "ls": "--"}),
    ("D_fric", "dissipated: friction", {"color": "#2ca02c", "ls": "--"}),
]
BROKEN = {"unit": ["broken_unit_I", "broken_unit_II", "broken_unit_mixed"],
          "interface": ["broken_interface_I", "broken_interface_II", "broken_interface_mixed"]}


def _safe(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_." else "_" for ch in name) or "run"


def run_labels(paths: list, runs: list) -> list:
    names = [r.name for r in runs]
    if len(set(names)) == len(names):
        return names
    return [os.path.basename(os.path.normpath(p)) for p in paths]


def plot_curves(curves: list, experiments: list, prefix: str, xu=("mm", 1e-3), yu=("kN", 1e3),
                load_sign: str = "auto", stamp: str = "", drift_height: float | None = None) -> list:
    """Every run and experiment, each load with the tools' one sign rule (curves.resolve_sign; experiments too).
    A turned load is labelled so and a note printed. drift_height (m): a drift-ratio axis on top."""
    from .figures import add_drift_axis, new_figure, save
    fig, ax = new_figure()
    for c in experiments:
        s, rule = resolve_sign(c, load_sign)
        if s < 0:
            print(f"note: load sign of {c.label} (experiment) turned: {rule}")
        ax.plot(c.x / xu[1], s * c.y / yu[1], color="k", lw=2.2, alpha=0.75,
                label=f"{c.label} (experiment)" + (" (load sign turned)" if s < 0 else ""))
    for c in curves:
        s, rule = resolve_sign(c, load_sign)
        if s < 0:
            print(f"note: load sign of {c.label} turned: {rule}")
        ax.plot(c.x / xu[1], s * c.y / yu[1], lw=1.4, label=c.label + (" (load sign turned)" if s < 0 else ""))
    ax.set_xlabel(f"control displacement ({xu[0]})")
    ax.set_ylabel(f"load ({yu[0]})")
    ax.axhline(0, color="0.6", lw=0.6)
    ax.legend(fontsize=8)
    ax.set_title("load against displacement", fontsize=9)
    if drift_height:
        add_drift_axis(ax, xu[1], drift_height)
    return save(fig, prefix, stamp)


def plot_energy(run, label: str, prefix: str) -> list:
    from .figures import new_figure, run_stamp, save
    h = run.history
    if not h.has("time"):
        raise ToolError(f"{run.path}: history.csv has no 'time' column")
    present = [e for e in ENERGY_COLUMNS if h.has(e[0])]
    if not present:
        raise ToolError(f"{run.path}: history.csv has no energy columns")
    t = h.numeric("time")
    has_bal = h.has("E_balance")
    fig, axs = new_figure(2 if has_bal else 1, 1, figsize=(6.8, 6.2 if has_bal else 4.6), sharex=True,
                          gridspec_kw={"height_ratios": [3, 1]} if has_bal else None, squeeze=False)
    ax = axs[0, 0]
    for col, lab, style in present:
        ax.plot(t, h.numeric(col), label=lab, **style)
    ax.set_ylabel("energy (J)")
    ax.legend(fontsize=7, ncol=2)
    ax.set_title(f"{label}: energy history", fontsize=9)
    if has_bal:
        b = axs[1, 0]
        bal = 100.0 * h.numeric("E_balance")
        if h.has("W_ext"):
            # a relative balance error means nothing while almost no work has been done: hide the start-up
            w = np.abs(h.numeric("W_ext"))
            bal = np.where(w > 1e-3 * (w.max() if len(w) else 0.0), bal, np.nan)
        b.plot(t, bal, color="#9467bd", lw=1.2)
        b.set_ylabel("balance error (%)")
        b.set_xlabel("time (s)")
    else:
        ax.set_xlabel("time (s)")
    return save(fig, prefix, run_stamp([run.summary]))


def dry_joint_record(run_dir: str):
    """{"open": control displacements (m), "slip": ...} of the dry-joint events of the run's cracks.csv (class
    interface-dry), or None when the run has no cracks.csv or no dry-joint event and no dry-joint rows at all."""
    from .cracks import read_cracks
    try:
        cr = read_cracks(run_dir)
    except ToolError:
        return None
    dry = cr["class"] == "dry"
    if not np.any(dry):
        return None
    cd = cr["control_displacement"]
    return {m: np.asarray(cd[dry & (cr["mode"] == m)], float) for m in ("open", "slip")}


def plot_damage(run, label: str, prefix: str, xu=("mm", 1e-3), yu=("kN", 1e3), load_sign: str = "auto") -> list:
    from .figures import new_figure, run_stamp, save
    h = run.history
    missing = [c for cols in BROKEN.values() for c in cols if not h.has(c)]
    dry = dry_joint_record(run.path)
    if missing and dry is None:
        raise ToolError(f"{run.path}: history.csv has no broken-element columns ({missing[0]}...) and cracks.csv no "
                        "dry-joint record: fracture off, and no dry joints in this run")
    c = load_curve(run.path, partial=True)
    x = c.x * (1.0 / xu[1])
    y = c.y * (1.0 / yu[1])
    sign, _ = resolve_sign(c, load_sign)
    y = sign * y
    fig, ax = new_figure(figsize=(7.0, 4.6))
    ax.plot(x, y, color="0.35", lw=1.4, label=f"load ({yu[0]})" + (", sign turned" if sign < 0 else ""))
    ax.set_xlabel(f"control displacement ({xu[0]})")
    ax.set_ylabel(f"load ({yu[0]})")
    ax2 = ax.twinx()
    ax2.grid(False)
    lines = []
    if not missing:
        for cls, colour, ls in (("unit", "#d62728", "-"), ("interface", "#1f77b4", "--")):
            n = sum(h.numeric(c) for c in BROKEN[cls])
            lines += ax2.plot(x, n, color=colour, ls=ls, lw=1.8,
                              label=f"broken in {'units' if cls == 'unit' else 'interfaces'} "
                                    f"(final {int(n[-1]) if len(n) else 0})")
    if dry is not None:
        # the dry-joint record of cracks.csv (fdem/README.md "The run folder"): segments first opened / slipped beyond the
        # output thresholds, counted against the control displacement at which each was recorded
        for mode, colour, ls in (("open", "#ff7f0e", "-."), ("slip", "#2ca02c", ":")):
            d = np.sort(dry[mode]) * (1.0 / xu[1])
            if len(d):
                xs = np.concatenate(([min(x[0], d[0])], np.repeat(d, 2), [max(x[-1], d[-1])]))
                ys = np.concatenate(([0], np.repeat(np.arange(len(d) + 1), 2)[1:-1], [len(d)]))
            else:
                xs, ys = np.array([x[0], x[-1]]), np.zeros(2)
            lines += ax2.plot(xs, ys, color=colour, ls=ls, lw=1.6,
                              label=f"dry joint segments {'opened' if mode == 'open' else 'slipped'} (final {len(d)})")
    ax2.set_ylabel("cumulative broken elements / dry joint segments (-)")
    ax2.set_ylim(bottom=0)
    handles = ax.get_lines()[:1] + lines
    ax.legend(handles, [hh.get_label() for hh in handles], fontsize=8, loc="upper left")
    ax.set_title(f"{label}: damage progression", fontsize=9)
    return save(fig, prefix, run_stamp([run.summary]))


def cmd_plot(args):
    if args.drift_height is not None and not args.drift_height > 0:
        raise ToolError(f"--drift-height must be a height > 0 in m, got {args.drift_height}")
    figs = [f.strip() for f in args.figures.split(",") if f.strip()]
    for f in figs:
        if f not in ("curves", "energy", "damage"):
            raise ToolError(f"unknown figure '{f}' (curves, energy, damage)")
    runs = [load_run(p, allow_unfinished=args.partial) for p in args.runs]
    labels = args.labels.split(",") if args.labels else run_labels(args.runs, runs)
    if len(labels) != len(runs):
        raise ToolError(f"--labels gives {len(labels)} labels for {len(runs)} runs")
    out = args.out_dir or (os.path.join(args.runs[0], "post") if len(runs) == 1 else "fdem-plots")
    xu = (args.report_x_unit, LENGTH_UNITS[args.report_x_unit])
    yu = (args.report_y_unit, FORCE_UNITS[args.report_y_unit])
    sign_arg = "1" if args.raw_sign else args.load_sign
    files = []
    if "curves" in figs:
        curves = [load_curve(p, args.x, args.y, stage=args.stage, partial=args.partial, label=lab)
                  for p, lab in zip(args.runs, labels)]
        exps = []
        for e in args.experiment or []:
            exps.append(load_curve(e, args.exp_x, args.exp_y, args.exp_x_unit, args.exp_y_unit))
        from .figures import run_stamp
        files += plot_curves(curves, exps, os.path.join(out, "curves"), xu, yu, load_sign=sign_arg,
                             stamp=run_stamp([r.summary for r in runs]), drift_height=args.drift_height)
    single = len(runs) == 1
    for run, lab in zip(runs, labels):
        suffix = "" if single else "_" + _safe(lab)
        if "energy" in figs:
            files += plot_energy(run, lab, os.path.join(out, "energy" + suffix))
        if "damage" in figs:
            try:
                files += plot_damage(run, lab, os.path.join(out, "damage" + suffix), xu, yu, load_sign=sign_arg)
            except ToolError as e:
                if args.figures != "curves,energy,damage":
                    raise  # asked for explicitly
                print(f"note: no damage figure: {e}")
    print("wrote " + ", ".join(files))


def add_parser(sub):
    p = sub.add_parser("plot", help="load-displacement curves, energy histories and damage progression",
                       description="Figures of one or several fdem runs (PNG and SVG): curves (load against control "
                                   "displacement, with experimental curves), energy (energy histories and balance "
                                   "error), damage (cumulative broken cohesive elements in units and interfaces over "
                                   "the load-displacement curve).")
    p.add_argument("runs", nargs="+", metavar="RUN", help="fdem run folders")
    p.add_argument("--experiment", action="append", metavar="CSV", help="experimental curve (repeatable)")
    p.add_argument("--exp-x", help="displacement column of the experiment (default: first)")
    p.add_argument("--exp-y", help="load column of the experiment (default: second)")
    p.add_argument("--exp-x-unit", choices=list(LENGTH_UNITS),
                   help=f"experiment displacement unit (default: the unit its column name ends in, as d_mm, else "
                        f"{DEFAULT_X_UNIT}, as every command)")
    p.add_argument("--exp-y-unit", choices=list(FORCE_UNITS),
                   help=f"experiment load unit (default: the unit its column name ends in, as F_kN, else "
                        f"{DEFAULT_Y_UNIT})")
    p.add_argument("--x", help="run displacement column (default: the run's curve)")
    p.add_argument("--y", help="run load column (default: the run's curve)")
    p.add_argument("--stage", type=int, help="plot only rows of this stage in the curves figure")
    p.add_argument("--labels", help="comma-separated legend labels, one per run")
    p.add_argument("--figures", default="curves,energy,damage", help="which figures (default curves,energy,damage)")
    p.add_argument("--report-x-unit", default="mm", choices=list(LENGTH_UNITS), help="displacement unit of the plots")
    p.add_argument("--report-y-unit", default="kN", choices=list(FORCE_UNITS), help="load unit of the plots")
    p.add_argument("--load-sign", choices=SIGN_CHOICES, default="auto",
                   help="sign of the loads: auto (default: the case's output.curve.sign, else the sign that makes "
                        "the loading work positive; a turned load is labelled so), 1 (as recorded) or -1 (turned)")
    p.add_argument("--raw-sign", action="store_true", help="same as --load-sign 1")
    p.add_argument("--partial", action="store_true", help="accept runs whose summary is not 'completed'")
    p.add_argument("--drift-height", type=float, metavar="H",
                   help="height H in m over which the drift is taken: the curves figure gets a top axis of drift ratio "
                        "d / H in %%")
    p.add_argument("--out-dir", help="output folder (default RUN/post for one run, else ./fdem-plots)")
    p.set_defaults(func=cmd_plot)
