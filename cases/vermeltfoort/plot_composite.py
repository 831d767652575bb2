#!/usr/bin/env python3
"""H and the vertical force against the top displacement for the three held walls (composite joint law), one figure,
and the table of RESULTS.md (largest H, where, V_base there, first capacity, error against 50 / 120 / 175 kN).

/usr/bin/python3 cases/vermeltfoort/plot_composite.py RUN_030 RUN_121 RUN_212 [--out FIG.png] [--extra LABEL=RUN ...]

RUN_*: run folders of `fdem run cases/vermeltfoort/vermeltfoort_0{30,121,212}.toml` (history.csv with the monitors
u_top, H, V_base of the case files). --extra adds labelled curves (e.g. a sensitivity run) to the figure.
"""
import argparse
import csv
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import sys  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools"))
from fdemtools.figures import savefig_stamped  # noqa: E402  (the runs' build and case hashes on the figure)

WALLS = [("0.30 MPa (J4D/J5D)", 50.0), ("1.21 MPa (J6D)", 120.0), ("2.12 MPa (J7D)", 175.0)]
COLORS = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple"]


def shear_stage(run):
    """u_top (mm), H (kN), V_base (kN) of the shear stage (the last stage of history.csv, numbered from 1), as lists."""
    u, h, v = [], [], []
    with open(os.path.join(run, "history.csv")) as f:
        rows = list(csv.DictReader(f))
        last = max(int(r["stage"]) for r in rows)
        for row in rows:
            if int(row["stage"]) != last:
                continue
            u.append(1e3 * float(row["u_top"]))
            h.append(1e-3 * float(row["H"]))
            v.append(1e-3 * float(row["V_base"]))
    return u, h, v


def first_capacity(u, h, drop=0.05):
    """Largest load before the load first falls `drop` below it (maxima under half the largest load do not count),
    the rule of `fdem-tools validate --peak first`."""
    top = max(h)
    best, at = 0.0, 0.0
    for ui, hi in zip(u, h):
        if hi > best:
            best, at = hi, ui
        elif best >= 0.5 * top and hi < (1.0 - drop) * best:
            return best, at
    return best, at


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs=3)
    ap.add_argument("--out", default="composite_held_walls.png")
    ap.add_argument("--extra", action="append", default=[], help="LABEL=RUN, a further labelled curve")
    a = ap.parse_args()
    fig, (ax_h, ax_v) = plt.subplots(1, 2, figsize=(11, 4.5))
    print("| wall | largest H (kN) | at (mm) | V_base there (kN) | first capacity (kN) at (mm) | test (kN) | error |")
    print("|---|---|---|---|---|---|---|")
    for i, (run, (name, test)) in enumerate(zip(a.runs, WALLS)):
        u, h, v = shear_stage(run)
        k = max(range(len(h)), key=lambda j: h[j])
        fc, fc_at = first_capacity(u, h)
        err = 100.0 * (h[k] - test) / test
        print(f"| {name} | {h[k]:.2f} | {u[k]:.2f} | {v[k]:.1f} | {fc:.2f} at {fc_at:.2f} | {test:g} | {err:+.1f} % |")
        ax_h.plot(u, h, color=COLORS[i], label=f"{name}: computed")
        ax_h.axhspan(0.85 * test, 1.15 * test, color=COLORS[i], alpha=0.12)
        ax_h.axhline(test, color=COLORS[i], lw=0.8, ls=":")
        ax_v.plot(u, v, color=COLORS[i], label=name)
    for j, spec in enumerate(a.extra):
        label, run = spec.split("=", 1)
        u, h, v = shear_stage(run)
        ax_h.plot(u, h, color=COLORS[3 + j % 2], ls="--", label=label)
        ax_v.plot(u, v, color=COLORS[3 + j % 2], ls="--", label=label)
    ax_h.set_xlabel("top displacement u_top (mm)")
    ax_h.set_ylabel("horizontal force H (kN)")
    ax_h.set_title("H; shaded: test +-15 %, dotted: test")
    ax_h.legend(fontsize=7)
    ax_v.set_xlabel("top displacement u_top (mm)")
    ax_v.set_ylabel("vertical force V_base (kN)")
    ax_v.set_title("vertical base reaction (held top beam)")
    ax_v.legend(fontsize=7)
    for ax in (ax_h, ax_v):
        ax.grid(alpha=0.3)
        ax.set_xlim(left=0)
        ax.set_ylim(bottom=0)
    fig.suptitle("Vermeltfoort walls, held top beam, law = \"composite\" (published values, no calibration)")
    fig.tight_layout()
    savefig_stamped(fig, a.out, list(a.runs) + [e.partition("=")[2] for e in a.extra], dpi=120)
    print("wrote", a.out)


if __name__ == "__main__":
    main()
