#!/usr/bin/env python3
"""Speed against error of the default wall (issue 25): fronts of `fdem-tools study speed` over the same grid (mass
scaling), each measured against its build's converged curve, drawn as time against the curve's RMS difference and
against the peak's difference, and tabulated.

/usr/bin/python3 cases/lourenco2005/plot_front.py [--table CSV] [LABEL=STUDY ...] [--out PREFIX]

--table reads fronts already measured from a table this script wrote (default: the committed
study_front_k25_N100_quick.csv, whose study folders are gone); each LABEL=STUDY adds the runs of a folder written by
`fdem-tools study speed ... --reference-run REF --error curve_rms` (its speed_study.csv: steps, wall and CPU times,
errors) as the front LABEL (a label already in the table is replaced). Writes PREFIX.csv and PREFIX.png (default
study_front_k25_N100_quick beside this script) and prints a markdown table and, for every front after the first,
the least time it takes to reach each curve RMS and peak error of the front before it and of the first front.

The fronts so far (lourenco2005/RESULTS.md): before (§32), after (§29, §32), per node (§33), faces (§34),
engine (§42).
"""
import argparse
import csv
import os

HERE = os.path.dirname(os.path.abspath(__file__))
FIELDS = ["settings", "mass_scale", "steps", "wall_time_s", "cpu_time_s", "curve_rms", "curve_max", "peak_error",
          "K_e_error", "ductility_error"]
# What each front is, for the legend (a label not listed here is drawn with its own name).
LEGEND = {
    "before": ("before (intrinsic cracks, penalty 1e10 Pa, 0.005 s ramp; against R)", "o--"),
    "after": ("after (extrinsic insertion, contact penalty 1e9 Pa, 0.1 s ramp; against R)", "s-"),
    "per node": ("per node (after, with mass_scaling = \"per_node\"; against R)", "^-"),
    "faces": ("faces (per node, contact on faces only, Gershgorin bound, safety 0.7; against R', its build's "
              "converged curve)", "D-"),
    "engine": ("engine (faces' settings, the step of 28 Nov: §35-§41; against R'', its build's converged curve)", "v-"),
}


def load_study(study, label):
    rows = []
    for r in csv.DictReader(open(os.path.join(study, "speed_study.csv"))):
        if r["status"] != "completed":
            continue
        rows.append(dict(settings=label, mass_scale=float(r["numerics.mass_scale"]), steps=int(r["steps"]),
                         wall_time_s=float(r["wall_time_s"]), cpu_time_s=float(r["cpu_time_s"] or "nan"),
                         curve_rms=float(r["curve_rms"]), curve_max=float(r["curve_max"]),
                         peak_error=float(r["peak_error"]), K_e_error=float(r["K_e_error"]),
                         ductility_error=float(r["ductility_error"])))
    if not rows:
        raise SystemExit(f"{study}/speed_study.csv: no completed run")
    return sorted(rows, key=lambda r: -r["mass_scale"])


def load_table(path):
    fronts = {}
    for r in csv.DictReader(open(path)):
        row = {k: (r[k] if k == "settings" else int(r[k]) if k == "steps" else float(r[k])) for k in FIELDS}
        fronts.setdefault(r["settings"], []).append(row)
    return fronts


TIME = "cpu_time_s"  # the runs' CPU time (1 thread: the time of the run alone); wall_time_s if a study has none


def least_time(rows, key, value):
    ok = [r for r in rows if abs(r[key]) <= abs(value)]
    return min(ok, key=lambda r: r[TIME]) if ok else None


def compare(old_name, olds, new_name, news):
    print()
    print(f"| {old_name}: mass scaling | its curve RMS | least time {new_name} reaching it | ratio of times | ratio of steps |"
          f" its peak error | least time {new_name} reaching it | ratio of times |")
    print("|---:|---:|---|---:|---:|---:|---|---:|")
    for r in olds:
        q = least_time(news, "curve_rms", r["curve_rms"])
        p = least_time(news, "peak_error", r["peak_error"])
        qs = (f"{q[TIME]:.1f} s (mass scaling {q['mass_scale']:g})", f"{r[TIME] / q[TIME]:.1f}",
              f"{r['steps'] / q['steps']:.1f}") if q else ("not reached", "-", "-")
        ps = (f"{p[TIME]:.1f} s (mass scaling {p['mass_scale']:g})", f"{r[TIME] / p[TIME]:.1f}") if p else ("not reached", "-")
        print(f"| {r['mass_scale']:g} | {100 * r['curve_rms']:.2f} % | {qs[0]} | {qs[1]} | {qs[2]} | "
              f"{100 * r['peak_error']:+.2f} % | {ps[0]} | {ps[1]} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("studies", nargs="*", metavar="LABEL=STUDY")
    ap.add_argument("--table", default=os.path.join(HERE, "study_front_k25_N100_quick.csv"),
                    help="fronts measured before (a CSV this script wrote); '' for none")
    ap.add_argument("--out", default=os.path.join(HERE, "study_front_k25_N100_quick"),
                    help="prefix of the table and figure written (default: the committed ones beside this script)")
    a = ap.parse_args()
    global TIME
    fronts = load_table(a.table) if a.table else {}
    for spec in a.studies:
        label, sep, study = spec.partition("=")
        if not sep or not label or not study:
            raise SystemExit(f"plot_front.py: '{spec}': expected LABEL=STUDY_FOLDER")
        fronts[label] = load_study(study, label)
    if not fronts:
        raise SystemExit("plot_front.py: no front (give --table or LABEL=STUDY)")
    rows = [r for rs in fronts.values() for r in rs]
    if any(r["cpu_time_s"] != r["cpu_time_s"] for r in rows):  # NaN: a summary without cpu_time_s
        TIME = "wall_time_s"
    with open(a.out + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        w.writerows(rows)
    print("| settings | mass scaling | steps | wall time (s) | CPU time (s) | curve RMS | largest difference past 0.5 mm | peak | K_e | "
          "ductility |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['settings']} | {r['mass_scale']:g} | {r['steps']:,} | {r['wall_time_s']:.1f} | {r['cpu_time_s']:.1f} | "
              f"{100 * r['curve_rms']:.2f} % | {100 * r['curve_max']:.1f} % | {100 * r['peak_error']:+.2f} % | "
              f"{100 * r['K_e_error']:+.1f} % | {100 * r['ductility_error']:+.1f} % |")
    print()
    print(f"times: {TIME}")
    names = list(fronts)
    for i in range(1, len(names)):
        compare(names[i - 1], fronts[names[i - 1]], names[i], fronts[names[i]])
    if len(names) > 2:
        compare(names[0], fronts[names[0]], names[-1], fronts[names[-1]])
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(11, 5.4))
    for ax, key, name in ((axes[0], "curve_rms", "RMS curve difference, 0-10 mm (% of the reference peak)"),
                          (axes[1], "peak_error", "peak difference (% of the reference peak)")):
        for label, rs in fronts.items():
            text, style = LEGEND.get(label, (label, "x-"))
            t = [r[TIME] for r in rs]
            e = [100 * abs(r[key]) for r in rs]
            ax.plot(t, e, style, label=text)
            for r, ti, ei in zip(rs, t, e):
                ax.annotate(f"{r['mass_scale']:g}", (ti, ei), textcoords="offset points", xytext=(4, 3), fontsize=7)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(("CPU" if TIME == "cpu_time_s" else "wall") + " time, 1 thread (s)")
        ax.set_ylabel(name, fontsize=8)
        ax.grid(alpha=0.3, which="both")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=7, loc="lower center", ncol=2)
    fig.suptitle("Default wall (k25_N100_quick), mass scaling marked; each front against its build's converged curve "
                 "(uniform mass scaling 10 at half the rate)", fontsize=9)
    fig.tight_layout(rect=(0, 0.13, 1, 1))
    fig.savefig(a.out + ".png", dpi=130)
    print(f"wrote {a.out}.csv, {a.out}.png")


if __name__ == "__main__":
    main()
