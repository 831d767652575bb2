"""Cyclic load-displacement curves: per-cycle peaks, secant stiffness and dissipated energy.

Definitions (the stiffness-degradation and energy indices of the M-DEM paper, "A novel macro-distinct element
model (M-DEM) for the in-plane analysis of URM structures", Eqs. 6-8, after Faella et al.): the secant stiffness of
cycle i is k_i = (|P+_i| + |P-_i|) / (|d+_i| + |d-_i|), where P+_i, P-_i are the cycle's peak loads in the positive
and negative direction and d+_i, d-_i the displacements at which they occur; k_d = k_i / k_el (Eq. 6) and
E_d = E_i / E_h (Eq. 7), E_i the energy dissipated up to the end of cycle i, E_h a reference energy.
What a "peak" is here: the excursion's tip. d+_i = max d over the cycle (its positive excursion) and P+_i the
largest load while the displacement is within `tip_band` (default 5 %) of d+_i, i.e. over the rows with
d >= (1 - tip_band) d+_i; likewise d-_i = min d and P-_i the most negative load over d <= (1 - tip_band) d-_i.
With tip_band = 0 it is the load at the extreme row; the band keeps the ringing of a sampled record at the turning
point (a few per cent from one row to the next) from deciding the peak. k_i is then the secant through the loop's
two tips. Taking the largest load of the cycle wherever it occurs instead breaks on
sliding (rectangular) loops, whose largest load can lie anywhere on the flat branch, even at the other side of zero
(k_i of 705 kN/mm for a loop whose tip secant is 25 kN/mm). The largest load of each excursion and where it occurs
are reported beside the peaks (P_largest_plus/minus) for information.

Cycles: the displacement history is cut where it crosses zero upwards (from negative to positive); a cycle
runs from one such crossing to the next (the first starts with the record). A dead band of `deadband` x max|d|
around zero keeps noise at zero displacement from creating cycles. A last cycle that does not return to zero
from the negative side is partial (the record ends inside it): it is kept apart, in `partial`, never in `cycles`,
k_el, k_d, E_i, E_d or E_h, because its "peaks" are wherever the record stopped (a partial excursion of 0.2 mm gave
k_d = 7.13 and a loop peak at d = 0). Its own energy is reported as `W_partial`.
Energy of a cycle W_i = int_cycle P dd (for a closed loop, the area it encloses: dissipated; an applied load goes
round the loop clockwise in the (d, P) plane); cumulative E_i = sum_{j<=i} W_j; E_h defaults to the final E_i.
Discrete form: the record is a polyline, W_i = sum over its segments of (P_k + P_{k+1})/2 (d_{k+1} - d_k), exact for
piecewise-linear branches. A negative W_i (a loop run anticlockwise: energy returned, which a passive structure
cannot do; noise, an unclosed loop or a wrong load sign) is flagged in the cycle's row and printed as a warning.
Load sign: the tools' one rule (curves.resolve_sign; tools/README.md "Curves, signs and units").
"""
from __future__ import annotations

import numpy as np

from .common import ToolError, warn
from .curves import loading_work_sign, polyline_area


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
            source: str = "curve", load_sign: float | None = None, tip_band: float = 0.05) -> dict:
    """Per-cycle peaks at the excursions' extreme displacements, k_i, W_i, E_i, k_d, E_d (module docstring).
    load_sign: +1 / -1 (given or stated by the case), None: curves.loading_work_sign."""
    d = np.asarray(d, dtype=float)
    p = np.asarray(p, dtype=float)
    if d.shape != p.shape or d.ndim != 1 or len(d) < 3:
        raise ToolError(f"{source}: a cyclic curve needs two columns of equal length with at least 3 points")
    if not (np.isfinite(d).all() and np.isfinite(p).all()):
        raise ToolError(f"{source}: the curve contains non-finite values")
    if not 0 <= tip_band < 1:
        raise ToolError(f"tip band must be in [0, 1), got {tip_band}")
    if not (d.max() > 0 and d.min() < 0):
        raise ToolError(f"{source}: not a cyclic curve (the displacement never changes sign)")
    sign_y = loading_work_sign(d, p) if load_sign is None else float(load_sign)
    p = sign_y * p
    cycles = []
    partial = []
    warnings = []
    e_cum = 0.0
    for s, e, complete in split_cycles(d, deadband):
        cd, cp = d[s:e + 1], p[s:e + 1]
        jx, jn = int(np.argmax(cd)), int(np.argmin(cd))  # the excursions' extreme displacements (the loop's tips)
        if cd[jx] > 0:  # the largest load near the tip (within tip_band of it), at the tip's displacement
            near = np.flatnonzero(cd >= (1.0 - tip_band) * cd[jx])
            px = float(cp[near[np.argmax(cp[near])]])
        else:
            px = float(cp[jx])
        if cd[jn] < 0:
            near = np.flatnonzero(cd <= (1.0 - tip_band) * cd[jn])
            pn = float(cp[near[np.argmin(cp[near])]])
        else:
            pn = float(cp[jn])
        w = polyline_area(cd, cp)
        has_both = cd[jx] > 0 and cd[jn] < 0
        k = (abs(px) + abs(pn)) / (cd[jx] - cd[jn]) if has_both else float("nan")  # M-DEM paper Eq. 8
        pos, neg = cd > 0, cd < 0
        ipl = int(np.flatnonzero(pos)[np.argmax(cp[pos])]) if pos.any() else jx
        iml = int(np.flatnonzero(neg)[np.argmin(cp[neg])]) if neg.any() else jn
        n = len(cycles) + 1
        if not complete:  # the record ends inside this cycle: kept apart, out of every index
            partial.append({"cycle": n, "start": s, "end": e, "complete": False, "d_plus": float(cd[jx]),
                            "P_plus": px, "d_minus": float(cd[jn]), "P_minus": pn, "W_i": w,
                            "d_end": float(cd[-1])})
            continue
        e_cum += w
        if w < 0:
            warnings.append(f"{source}: cycle {n} has a negative dissipated energy W_i = {w:.4g} J (a loop run "
                            "anticlockwise returns energy: noise, an unclosed loop or a wrong load sign)")
        cycles.append({
            "cycle": n,
            "start": s, "end": e, "complete": bool(complete),
            "d_plus": float(cd[jx]), "P_plus": px,
            "d_minus": float(cd[jn]), "P_minus": pn,
            "k_i": float(k), "W_i": w, "E_i": e_cum, "W_negative": bool(w < 0),
            "P_largest_plus": float(cp[ipl]), "d_at_P_largest_plus": float(cd[ipl]),
            "P_largest_minus": float(cp[iml]), "d_at_P_largest_minus": float(cd[iml]),
        })
    finite_k = [c["k_i"] for c in cycles if np.isfinite(c["k_i"])]
    if not finite_k:
        raise ToolError(f"{source}: no complete cycle goes both to positive and to negative displacement"
                        + (f" ({len(partial)} partial cycle(s) at the end of the record are not counted)"
                           if partial else ""))
    k_ref = k_el if k_el is not None else finite_k[0]
    e_ref = e_h if e_h is not None else e_cum
    if k_ref <= 0:
        raise ToolError(f"{source}: reference stiffness k_el must be positive")
    if e_ref < 0:
        warnings.append(f"{source}: the reference energy E_h = {e_ref:.4g} J is negative")
    for c in cycles:
        c["k_d"] = c["k_i"] / k_ref
        c["E_d"] = c["E_i"] / e_ref if e_ref != 0 else float("nan")
    for msg in warnings:
        warn(msg)
    return {
        "n_cycles": len(cycles),
        "n_partial": len(partial),
        "partial": partial,
        "W_partial": float(sum(c["W_i"] for c in partial)),
        "sign_y": sign_y,
        "k_el": k_ref, "k_el_rule": "given" if k_el is not None else "secant stiffness of the first cycle",
        "E_h": e_ref, "E_h_rule": "given" if e_h is not None else "cumulative energy at the end of the last complete "
                                                                    "cycle",
        "E_total": e_cum,
        "peak_rule": f"largest load within {100 * tip_band:g} % of the excursion's extreme displacement (M-DEM "
                     "paper Eqs. 6-8)",
        "warnings": warnings,
        "cycles": cycles,
    }


def plot(d, p, res: dict, prefix: str, label: str, x_unit=("mm", 1e-3), y_unit=("kN", 1e3),
         stamp: str = "") -> list:
    from .figures import new_figure, save
    sx, sy = 1.0 / x_unit[1], 1.0 / y_unit[1]
    fig, axs = new_figure(1, 2, figsize=(11, 4.4))
    ax = axs[0]
    ax.plot(np.asarray(d) * sx, res["sign_y"] * np.asarray(p) * sy, color="0.3", lw=1.0, label=label)
    cyc = res["cycles"]
    ax.plot([c["d_plus"] * sx for c in cyc] + [c["d_minus"] * sx for c in cyc],
            [c["P_plus"] * sy for c in cyc] + [c["P_minus"] * sy for c in cyc], "o", color="#d62728", ms=4,
            label="cycle peaks (loads at the loop tips)")
    for c in res.get("partial", []):  # where the record ends inside a cycle: drawn apart, not as loop peaks
        d0, d1 = c["start"], c["end"] + 1
        ax.plot(np.asarray(d)[d0:d1] * sx, res["sign_y"] * np.asarray(p)[d0:d1] * sy, color="#ff7f0e", lw=1.2,
                ls="--", label=f"partial cycle {c['cycle']} (the record ends inside it; not in the metrics)")
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
    return save(fig, prefix, stamp)
