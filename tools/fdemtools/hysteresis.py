"""Cyclic load-displacement curves: per-cycle peaks, secant stiffness and dissipated energy. FORMULATION §9.

Cycles: the displacement history is cut where it crosses zero upwards (from negative to positive); a cycle
runs from one such crossing to the next (the first starts with the record). A dead band of `deadband` x max|d|
around zero keeps noise at zero displacement from creating cycles. A last cycle that does not return to zero
from the negative side is marked incomplete.
Per cycle i: P+ = max load, d+ its displacement; P- = min load, d- its displacement;
  secant stiffness k_i = (|P+| + |P-|) / (|d+| + |d-|),  degradation k_d = k_i / k_el  (k_el: given, else k_1);
  also, at the cycle's displacement extremes: P(d_max), P(d_min) and k_ext = (|P(d_max)| + |P(d_min)|) / (d_max - d_min).
  For loops with a flat (sliding, perfectly plastic) branch the largest load is reached anywhere along the branch,
  even on the other side of zero, and k_i loses its meaning; k_ext stays the secant through the loop's tips.
  energy of the cycle  W_i = int_cycle P dd  (for a closed loop, the area it encloses, dissipated);
  cumulative energy    E_i = sum_{j<=i} W_j;  normalised E_d = E_i / E_h  (E_h: given, else the final E_i).
Discrete form: the record is a polyline, W_i = sum over its segments of (P_k + P_{k+1})/2 (d_{k+1} - d_k), exact for
piecewise-linear branches.
"""
from __future__ import annotations

import numpy as np

from .common import ToolError


def split_cycles(d, deadband: float = 1e-3) -> list:
    """Index ranges [start, end] (inclusive, consecutive cycles share their boundary point) and completeness."""
    d = np.asarray(d, dtype=float)
    eps = deadband * float(np.max(np.abs(d)))
    state = 0
    last_nonpos = 0  # last index with d <= 0 seen while in the negative state
    cuts = []
    for k, v in enumerate(d):
        if v > eps:
            if state == -1:
                cuts.append(last_nonpos)
            state = 1
        elif v < -eps:
            state = -1
        if v <= 0:
            last_nonpos = k
    bounds = [0] + cuts + [len(d) - 1]
    cycles = []
    for i in range(len(bounds) - 1):
        s, e = bounds[i], bounds[i + 1]
        if e > s:
            # the record's last cycle is complete if it came back to zero from the negative side
            last = i == len(bounds) - 2
            complete = not last or (d[s:e + 1].min() < -eps and abs(d[-1]) <= eps)
            cycles.append((s, e, bool(complete)))
    return cycles


def analyse(d, p, k_el: float | None = None, e_h: float | None = None, deadband: float = 1e-3,
            source: str = "curve") -> dict:
    d = np.asarray(d, dtype=float)
    p = np.asarray(p, dtype=float)
    if d.shape != p.shape or d.ndim != 1 or len(d) < 3:
        raise ToolError(f"{source}: a cyclic curve needs two columns of equal length with at least 3 points")
    if not (np.isfinite(d).all() and np.isfinite(p).all()):
        raise ToolError(f"{source}: the curve contains non-finite values")
    if not (d.max() > 0 and d.min() < 0):
        raise ToolError(f"{source}: not a cyclic curve (the displacement never changes sign)")
    # A load that falls as the displacement grows is a reaction (opposite sign convention): turn it.
    sign_y = -1.0 if float(np.dot(d - d.mean(), p - p.mean())) < 0 else 1.0
    p = sign_y * p
    cycles = []
    e_cum = 0.0
    for s, e, complete in split_cycles(d, deadband):
        cd, cp = d[s:e + 1], p[s:e + 1]
        ip, im = int(np.argmax(cp)), int(np.argmin(cp))
        jx, jn = int(np.argmax(cd)), int(np.argmin(cd))  # the cycle's displacement extremes (its tips)
        w = float(np.sum(0.5 * (cp[1:] + cp[:-1]) * np.diff(cd)))
        e_cum += w
        has_both = cp[ip] > 0 and cp[im] < 0 and cd[jx] > 0 and cd[jn] < 0
        den = abs(cd[ip]) + abs(cd[im])
        k = (abs(cp[ip]) + abs(cp[im])) / den if has_both and den > 0 else float("nan")
        k_ext = (abs(cp[jx]) + abs(cp[jn])) / (cd[jx] - cd[jn]) if cd[jx] > 0 and cd[jn] < 0 else float("nan")
        cycles.append({
            "cycle": len(cycles) + 1,
            "start": s, "end": e, "complete": bool(complete),
            "d_plus": float(cd[ip]), "P_plus": float(cp[ip]),
            "d_minus": float(cd[im]), "P_minus": float(cp[im]),
            "d_max": float(cd[jx]), "d_min": float(cd[jn]),
            "k_i": float(k), "W_i": w, "E_i": e_cum,
            "P_at_d_max": float(cp[jx]), "P_at_d_min": float(cp[jn]), "k_ext": float(k_ext),
        })
    finite_k = [c["k_i"] for c in cycles if np.isfinite(c["k_i"])]
    if not finite_k:
        raise ToolError(f"{source}: no cycle has both a positive and a negative peak")
    k_ref = k_el if k_el is not None else finite_k[0]
    e_ref = e_h if e_h is not None else e_cum
    if k_ref <= 0:
        raise ToolError(f"{source}: reference stiffness k_el must be positive")
    for c in cycles:
        c["k_d"] = c["k_i"] / k_ref
        c["E_d"] = c["E_i"] / e_ref if e_ref != 0 else float("nan")
    return {
        "n_cycles": len(cycles),
        "sign_y": sign_y,
        "k_el": k_ref, "k_el_rule": "given" if k_el is not None else "secant stiffness of the first cycle",
        "E_h": e_ref, "E_h_rule": "given" if e_h is not None else "cumulative energy at the end of the record",
        "E_total": e_cum,
        "cycles": cycles,
    }


def plot(d, p, res: dict, prefix: str, label: str, x_unit=("mm", 1e-3), y_unit=("kN", 1e3)) -> list:
    from .figures import new_figure, save
    sx, sy = 1.0 / x_unit[1], 1.0 / y_unit[1]
    fig, axs = new_figure(1, 2, figsize=(11, 4.4))
    ax = axs[0]
    ax.plot(np.asarray(d) * sx, res["sign_y"] * np.asarray(p) * sy, color="0.3", lw=1.0, label=label)
    cyc = res["cycles"]
    ax.plot([c["d_plus"] * sx for c in cyc] + [c["d_minus"] * sx for c in cyc],
            [c["P_plus"] * sy for c in cyc] + [c["P_minus"] * sy for c in cyc], "o", color="#d62728", ms=4,
            label="cycle peaks")
    ax.set_xlabel(f"displacement ({x_unit[0]})")
    ax.set_ylabel(f"load ({y_unit[0]})" + (" [sign reversed]" if res["sign_y"] < 0 else ""))
    ax.legend(fontsize=8)
    ax = axs[1]
    n = [c["cycle"] for c in cyc]
    ax.plot(n, [c["k_d"] for c in cyc], "o-", color="#1f77b4", label=r"$k_d = k_i / k_{el}$")
    ax.plot(n, [c["E_d"] for c in cyc], "s-", color="#ff7f0e", label=r"$E_d = E_i / E_h$")
    from matplotlib.ticker import MaxNLocator
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlabel("cycle")
    ax.set_ylabel("normalised stiffness and energy (-)")
    ax.set_title(f"$k_{{el}}$ = {res['k_el'] * sy / sx:.4g} {y_unit[0]}/{x_unit[0]}, $E_h$ = {res['E_h']:.4g} J",
                 fontsize=9)
    ax.legend(fontsize=8)
    return save(fig, prefix)
