#!/usr/bin/env python3
"""The four walls of a family on one figure: each wall's loading curve (the load averaged over --smooth mm of travel,
as `validate --smooth`), its test peak (circle), the published FDEM peak (triangle) and its rigid-block bound
(dashed line, from the family report's rigid_block_bound_kN column), one colour per wall (RESULTS.md §43).

/usr/bin/python3 cases/lourenco2005/plot_family.py REPORT_DIR --title T --out FILE.png

REPORT_DIR is a `fdem-tools validate --out-dir` folder: report.csv and the runs under STEM/runs/run.
"""
import argparse
import csv
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools"))
from fdemtools.study import curve_quantities  # noqa: E402
from fdemtools.validate import smooth_curve  # noqa: E402
from fdemtools.figures import savefig_stamped  # noqa: E402


def _f(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("report_dir")
    ap.add_argument("--smooth", type=float, default=0.5, help="averaging window of the curves, mm")
    ap.add_argument("--title", default="")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    with open(os.path.join(a.report_dir, "report.csv"), newline="") as f:
        rows = sorted(csv.DictReader(f), key=lambda r: _f(r["experiment_kN"]) or 0)
    fig, ax = plt.subplots(figsize=(8.5, 5.5))
    for i, r in enumerate(rows):
        col = f"C{i}"
        c = curve_quantities(os.path.join(a.report_dir, r["case"], "runs", "run"))
        y = smooth_curve(c["x"], c["y"], a.smooth * 1e-3)
        ax.plot(1e3 * c["x"], y / 1e3, color=col, lw=1.2, label=f"{r['case']}: peak {float(r['peak_load_kN']):.1f} kN "
                                                             f"at {float(r['disp_at_peak_mm']):.1f} mm")
        bound = _f(r.get("rigid_block_bound_kN"))
        if bound:
            ax.axhline(bound, color=col, ls="--", lw=0.9)
            ax.text(1e3 * c["x"][-1], bound, f" bound {bound:.1f}", color=col, va="bottom", ha="right", fontsize=7)
        for key, mk in (("experiment_kN", "o"), ("published_fdem_kN", "^")):
            v = _f(r.get(key))
            if v:
                ax.plot(float(r["disp_at_peak_mm"]), v, mk, color=col, mec="k", ms=7)
    from matplotlib.lines import Line2D
    h, _ = ax.get_legend_handles_labels()
    h += [Line2D([], [], marker="o", color="0.5", mec="k", ls="none", label="test peak (drawn at fdem's peak travel)"),
          Line2D([], [], marker="^", color="0.5", mec="k", ls="none", label="published FDEM peak"),
          Line2D([], [], color="0.3", ls="--", label="rigid-block bound of the case (fdem-tools limit)")]
    ax.legend(handles=h, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_xlabel("control displacement (mm)")
    ax.set_ylabel(f"horizontal load H (kN), averaged over {a.smooth:g} mm")
    ax.set_title(a.title, fontsize=9)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    savefig_stamped(fig, a.out, [os.path.join(a.report_dir, r["case"], "runs", "run") for r in rows], dpi=110)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
