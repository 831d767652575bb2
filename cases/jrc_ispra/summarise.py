#!/usr/bin/env python3
"""The JRC Ispra piers' table and figure (cases/jrc_ispra/RESULTS.md): for each run folder of a macro_* or micro_*
case, the largest base shear, the elastic stiffness k_el (secant at 10 % of the peak on the first loading branch, as
the test's), the hysteretic energy E_h (the work of H over the cyclic stage: what the cycles dissipate, plus the
little the pier stores at the end), the largest drift, the run's wall time and steps, against the test and the
M-DEM numbers of seeds/000 (cases/README.md §D).

/usr/bin/python3 cases/jrc_ispra/summarise.py RUN [RUN ...] [--out PREFIX]

Writes PREFIX.csv, PREFIX.png (H against the beam's displacement, one panel per pier) and PREFIX_speed.png (CPU time
against the errors of the peak and of k_el, both representations; runs without a CPU time are left out; default PREFIX jrc_ispra_summary in the current
folder) and prints a markdown table.
"""
import argparse
import csv
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "tools"))
sys.path.insert(0, HERE)

from make_cases import read_reference  # noqa: E402  (reference.csv: the test and seeds/000's M-DEM numbers)
from fdemtools.figures import run_stamp, savefig_stamped  # noqa: E402  (the runs' build and case hashes on the figures)

_REF = read_reference()
TEST = {p: dict(peak=float(r["experiment_kN"]), k_el=float(r["k_el_kN_per_mm"]), drift=float(r["drift_pct"]),
                E_h=float(r["E_h_J"]), height=float(r["height_m"])) for p, r in _REF.items()}
# seeds/000, results table (Fig. 3(e)): BS_p kN, k_el kN/mm, E_h J of the M-DEM runs
MDEM = {(p, el): (float(r[f"mdem_{el}_kN"]), float(r[f"mdem_k_el_{el}"]), float(r[f"mdem_E_h_{el}_J"]))
        for p, r in _REF.items() for el in ("EL005", "EL010", "EL020")}


def read(run):
    rows = list(csv.DictReader(open(os.path.join(run, "history.csv"))))
    last_stage = max(int(float(r["stage"])) for r in rows)
    rows = [r for r in rows if int(float(r["stage"])) == last_stage]
    u = np.array([float(r["u_top"]) for r in rows])
    H = np.array([float(r["H"]) for r in rows])
    summary = json.load(open(os.path.join(run, "summary.json")))
    return (u - u[0]) * 1e3, H / 1e3, summary


def quantities(u, H):
    """peak (kN, largest |H|), k_el (kN/mm), E_h (J), largest |u| (mm). k_el is the secant where the first loading
    branch (from the start to the first turn of the drive, or the whole curve when it never turns) last rises
    through 10 % of the peak before its own largest load: the start of a drive rings for a few hundredths of a
    millimetre, and the first crossing could fall in that ringing."""
    peak = float(np.max(np.abs(H)))
    s = np.sign(u[np.argmax(np.abs(u) > 1e-6)]) or 1.0  # direction of the first leg
    turn = np.nonzero(s * np.diff(u) < -1e-9)[0]
    end = int(turn[0]) + 1 if len(turn) else len(u)
    a = s * H[:end]
    top = int(np.argmax(a))
    below = np.nonzero(a[:top + 1] < 0.1 * peak)[0]
    k_el = float("nan")
    if len(below) and a[top] >= 0.1 * peak:
        i = int(below[-1])
        f = (0.1 * peak - a[i]) / (a[i + 1] - a[i])
        uu = abs(u[i] + f * (u[i + 1] - u[i]))
        k_el = 0.1 * peak / uu if uu > 0 else float("nan")
    E_h = float(np.sum(0.5 * (H[1:] + H[:-1]) * np.diff(u)))  # kN mm = J
    return peak, k_el, E_h, float(np.max(np.abs(u)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--out", default="jrc_ispra_summary")
    a = ap.parse_args()
    table, curves, summaries = [], [], []
    for run in a.runs:
        u, H, s = read(run)
        summaries.append(s)
        name = s.get("case", os.path.basename(run)).replace("jrc_ispra_", "")
        pier = "LW" if "_LW" in name else "HW"
        el = next((e for e in ("EL005", "EL010", "EL020") if e in name), "")
        peak, k_el, E_h, umax = quantities(u, H)
        t = TEST[pier]
        m = MDEM.get((pier, el))
        table.append(dict(run=name, pier=pier, peak=peak, peak_err=100 * (peak / t["peak"] - 1), k_el=k_el,
                          k_el_err=100 * (k_el / t["k_el"] - 1), E_h=E_h, drift=100 * umax / 1e3 / t["height"],
                          mdem_peak=m[0] if m else "", mdem_k_el=m[1] if m else "", mdem_E_h=m[2] if m else "",
                          wall_time_s=s.get("wall_time_s"), cpu_time_s=s.get("cpu_time_s", float("nan")),
                          steps=s.get("steps"), triangles=s.get("n_triangles")))
        curves.append((name, pier, u, H))
    with open(a.out + ".csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(table[0]))
        w.writeheader()
        w.writerows(table)
    print("| run | triangles | peak (kN) | vs test | k_el (kN/mm) | vs test | E_h (J) | largest drift (%) | "
          "M-DEM peak / k_el / E_h | steps | wall time (s) | CPU time (s) |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|")
    for r in table:
        md = f"{r['mdem_peak']} / {r['mdem_k_el']} / {r['mdem_E_h']}" if r["mdem_peak"] != "" else "-"
        print(f"| {r['run']} | {r['triangles']} | {r['peak']:.2f} | {r['peak_err']:+.1f} % | {r['k_el']:.1f} | "
              f"{r['k_el_err']:+.1f} % | {r['E_h']:.0f} | {r['drift']:.2f} | {md} | {r['steps']} | "
              f"{r['wall_time_s']:.0f} | " + (f"{r['cpu_time_s']:.0f}" if r["cpu_time_s"] == r["cpu_time_s"] else "-")
              + " |")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    piers = [p for p in ("LW", "HW") if any(c[1] == p for c in curves)]
    fig, axes = plt.subplots(1, len(piers), figsize=(6.5 * len(piers), 5), squeeze=False)
    for ax, p in zip(axes[0], piers):
        for name, pier, u, H in curves:
            if pier == p:
                ax.plot(u, H, lw=0.8, label=name)
        t = TEST[p]
        ax.axhline(t["peak"], color="k", ls=":", lw=0.8)
        ax.axhline(-t["peak"], color="k", ls=":", lw=0.8, label=f"test peak {t['peak']} kN")
        ax.set_xlabel("beam displacement (mm)")
        ax.set_ylabel("base shear H (kN)")
        ax.set_title(f"JRC Ispra {p}", fontsize=10)
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.tight_layout()
    # the corner's stamp names four cases and "and N more"; the files' metadata, which `fdem-tools provenance` checks,
    # names every run's case and hash
    meta = {"Source": run_stamp(summaries, limit=None)}
    savefig_stamped(fig, a.out + ".png", a.runs, dpi=130, metadata=meta)
    # run time against error: the CPU time against |peak error| and |k_el error|
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for ax, key, name in ((axes[0], "peak_err", "|peak base shear - test| (% of the test)"),
                          (axes[1], "k_el_err", "|k_el - test| (% of the test)")):
        for r in table:
            t = r["cpu_time_s"]
            if t != t:  # no cpu_time_s (a build before it): its wall time would not compare; left out
                continue
            marker = ("s" if r["run"].startswith("micro") else "o") if "mono" in r["run"] or r["run"].startswith(
                "micro") else "^"
            colour = "C0" if r["pier"] == "LW" else "C3"
            ax.plot(t, abs(r[key]), marker, color=colour, ms=7, mfc="none" if marker == "^" else colour)
            ax.annotate(r["run"].replace("macro_", "M ").replace("micro_", "micro "), (t, abs(r[key])),
                        textcoords="offset points", xytext=(5, 3), fontsize=7)
        ax.set_xscale("log")
        ax.set_xlabel("CPU time, 1 thread (s)")
        ax.set_ylabel(name, fontsize=8)
        ax.grid(alpha=0.3, which="both")
    axes[0].set_title("macro-blocks (M): circles monotonic, triangles cyclic; micro-models: squares; "
                      "blue LW, red HW", fontsize=8)
    fig.tight_layout()
    savefig_stamped(fig, a.out + "_speed.png", a.runs, dpi=130, metadata=meta)
    print(f"wrote {a.out}.csv, {a.out}.png, {a.out}_speed.png")


if __name__ == "__main__":
    main()
