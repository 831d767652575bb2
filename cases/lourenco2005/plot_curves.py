#!/usr/bin/env python3
"""Whole load-displacement curves of several runs of one wall on one figure, with the first millimetres enlarged
(RESULTS.md §33: per-node against uniform mass scaling on the 100 kN wall).

/usr/bin/python3 cases/lourenco2005/plot_curves.py RUN=LABEL [RUN=LABEL ...] [--zoom MM] [--title T] --out FILE.png

LABEL may not contain "=". The first run is drawn black (the reference); each curve is the run's loading curve as `fdem-tools study` reads it
(last stage, the load sign rule).
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools"))
from fdemtools.study import curve_quantities  # noqa: E402
from fdemtools.figures import savefig_stamped  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+", metavar="RUN=LABEL")
    ap.add_argument("--zoom", type=float, default=3.0, help="displacement range of the enlarged panel, mm")
    ap.add_argument("--title", default="")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(12, 4.5))
    top = 0.0
    for i, spec in enumerate(a.runs):
        run, _, label = spec.rpartition("=")  # the last "=": run folders may hold one
        q = curve_quantities(run)
        style = dict(color="k") if i == 0 else {}
        for axis in ax:
            axis.plot(q["x"] * 1e3, q["y"] / 1e3, lw=1, label=label or run, **style)
        zoomed = q["y"][q["x"] * 1e3 <= a.zoom]
        top = max(top, float(zoomed.max()) / 1e3 if len(zoomed) else 0.0)
    ax[1].set_xlim(0, a.zoom)
    ax[1].set_ylim(0, 1.15 * top)
    ax[1].set_title(f"first {a.zoom:g} mm", fontsize=9)
    for axis in ax:
        axis.set_xlabel("control displacement (mm)")
        axis.set_ylabel("load (kN)")
        axis.grid(alpha=0.3)
    ax[0].legend(fontsize=8)
    fig.suptitle(a.title, fontsize=10)
    fig.tight_layout()
    savefig_stamped(fig, a.out, [spec.rpartition("=")[0] for spec in a.runs], dpi=120)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
