#!/usr/bin/env python3
"""Speed against error of the default wall, before and after the settings of RESULTS.md §29 (issue 25), with
per-node mass scaling (§33), and with contact on faces only and the per-node bound at safety 0.7 (§34): two to four
`fdem-tools study speed` folders of the same grid (mass scaling), measured
against the same reference curve, drawn as fronts (time against the curve's RMS difference, and against the peak's
difference) and tabulated.

/usr/bin/python3 cases/lourenco2005/plot_front.py BEFORE_STUDY AFTER_STUDY [PER_NODE_STUDY [FACES_STUDY]] [--out PREFIX]

Each STUDY is a folder written by `fdem-tools study speed ... --reference-run REF --error curve_rms` (its
speed_study.csv, with the runs' steps and wall and CPU times). Writes PREFIX.csv and PREFIX.png (default study_front_k25_N100_quick) and prints a
markdown table and, for every run before (and every run after, given PER_NODE_STUDY), the least time of the next
front that reaches its curve RMS and its peak error.
"""
import argparse
import csv
import os


def load(study, label):
    rows = []
    for r in csv.DictReader(open(os.path.join(study, "speed_study.csv"))):
        if r["status"] != "completed":
            continue
        rows.append(dict(settings=label, mass_scale=float(r["numerics.mass_scale"]), steps=int(r["steps"]),
                         wall_time_s=float(r["wall_time_s"]), cpu_time_s=float(r["cpu_time_s"] or "nan"), curve_rms=float(r["curve_rms"]),
                         curve_max=float(r["curve_max"]), peak_error=float(r["peak_error"]),
                         K_e_error=float(r["K_e_error"]), ductility_error=float(r["ductility_error"])))
    return sorted(rows, key=lambda r: -r["mass_scale"])


TIME = "cpu_time_s"  # the runs' CPU time (1 thread: the time of the run alone); wall_time_s if a study has none


def least_time(rows, key, value):
    ok = [r for r in rows if abs(r[key]) <= abs(value)]
    return min(ok, key=lambda r: r[TIME]) if ok else None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("per_node", nargs="?", help="the study with [numerics] mass_scaling = \"per_node\" (RESULTS.md §33)")
    ap.add_argument("faces", nargs="?", help="the study of RESULTS.md §34 (faces only, Gershgorin bound, safety 0.7)")
    ap.add_argument("--out", default="study_front_k25_N100_quick")
    a = ap.parse_args()
    global TIME
    before, after = load(a.before, "before"), load(a.after, "after")
    per_node = load(a.per_node, "per node") if a.per_node else []
    faces = load(a.faces, "faces") if a.faces else []
    rows = before + after + per_node + faces
    if any(r["cpu_time_s"] != r["cpu_time_s"] for r in rows):  # NaN: a summary without cpu_time_s
        TIME = "wall_time_s"
    with open(a.out + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
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
    for old_name, olds, new_name, news in (("before", before, "after", after), ("after", after, "per node", per_node),
                                           ("per node", per_node, "faces", faces)):
        if not news:
            continue
        print()
        print(f"| {old_name}: mass scaling | its curve RMS | least time {new_name} reaching it | ratio of times | ratio of steps |"
              f" its peak error | least time {new_name} reaching it | ratio of times |")
        print("|---:|---:|---|---:|---:|---:|---|---:|")
        for r in olds:
            q = least_time(news, "curve_rms", r["curve_rms"])
            p = least_time(news, "peak_error", r["peak_error"])
            qs = (f"{q[TIME]:.1f} s (mass scaling {q['mass_scale']:g})", f"{r[TIME] / q[TIME]:.1f}",
                  f"{r['steps'] / q['steps']:.1f}") if q else ("not reached", "-", "-")
            ps = (f"{p[TIME]:.1f} s (mass scaling {p['mass_scale']:g})",
                  f"{r[TIME] / p[TIME]:.1f}") if p else ("not reached", "-")
            print(f"| {r['mass_scale']:g} | {100 * r['curve_rms']:.2f} % | {qs[0]} | {qs[1]} | {qs[2]} | "
                  f"{100 * r['peak_error']:+.2f} % | {ps[0]} | {ps[1]} |")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(11, 5.2))
    for ax, key, name in ((axes[0], "curve_rms", "RMS curve difference, 0-10 mm (% of the reference peak)"),
                          (axes[1], "peak_error", "peak difference (% of the reference peak)")):
        for label, rs, style in (("before (intrinsic cracks, penalty 1e10 Pa, 0.005 s ramp)", before, "o--"),
                                 ("after (extrinsic insertion, contact penalty 1e9 Pa, 0.1 s ramp)", after, "s-"),
                                 ("per node (after, with mass_scaling = \"per_node\")", per_node, "^-"),
                                 ("faces (per node, contact on faces only, Gershgorin bound, safety 0.7; against R', its build's converged curve)", faces, "D-")):
            if not rs:
                continue
            t = [r[TIME] for r in rs]
            e = [100 * abs(r[key]) for r in rs]
            ax.plot(t, e, style, label=label)
            for r, ti, ei in zip(rs, t, e):
                ax.annotate(f"{r['mass_scale']:g}", (ti, ei), textcoords="offset points", xytext=(4, 3), fontsize=7)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel(("CPU" if TIME == "cpu_time_s" else "wall") + " time, 1 thread (s)")
        ax.set_ylabel(name, fontsize=8)
        ax.grid(alpha=0.3, which="both")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=7, loc="lower center", ncol=2)
    fig.suptitle("Default wall (k25_N100_quick), mass scaling marked; reference: uniform mass scaling 10 at half the rate "
                 "(R of §29; R' of §34 for the faces front)",
                 fontsize=9)
    fig.tight_layout(rect=(0, 0.1, 1, 1))
    fig.savefig(a.out + ".png", dpi=130)
    print(f"wrote {a.out}.csv, {a.out}.png")


if __name__ == "__main__":
    main()
