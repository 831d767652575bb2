"""The curve mathematics of the tools, in one module: the load sign rule, the direction of a record, its
monotonic loading branch and its envelope, interpolation, areas (work) under a polyline, smoothing over a window of
displacement, and the peak rules (largest, first, plateau, past the peak). `eeep`, `hysteresis`, `validate`, `study`,
`plots` and the command line import them from here (issue 52); the names stay importable from the modules they
came from.

Every function takes plain arrays in consistent units (SI from the command line) and returns plain numbers or
arrays; no file is read here.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .errors import ToolError

if TYPE_CHECKING:
    from .common import Curve

REVERSAL = 0.10        # a retreat of the displacement beyond this fraction of its largest |value|: a reversing record
PAST_PEAK_DROP = 0.05  # the load at the end this far below the peak (fraction of it): past the peak
PLATEAU_REACH = 0.75  # a curve with less drop whose largest load lies before this fraction of its travel: a plateau
FIRST_PEAK_DROP = 0.05  # --peak first: the load must fall this far below the largest value so far (fraction)
FIRST_PEAK_FLOOR = 0.5  # --peak first: only a maximum of at least this fraction of the largest load is a peak
PEAK_RULES = ("largest", "first")


# ----------------------------------------------------------------------------------------------
# The load sign rule (one rule for plot, hysteresis, eeep and validate; tools/README.md "Curves, signs and units")


def loading_work_sign(x, y) -> float:
    """+1 or -1: the sign that makes the load do positive work on the loading branches of the curve.

    A loading branch is a segment along which the displacement moves away from its starting value
    (|x - x0| grows). Along it, an applied load does positive work on the structure: W+ = sum over those segments
    of (y_k + y_k+1)/2 (x_k+1 - x_k) > 0; a reaction (the structure pushing back on its support) does negative
    work. So the sign is that of W+ (+1 when W+ = 0). Unlike the covariance of load and displacement, W+ does
    not change sign when the load softens after its peak (a pushover whose load falls from 40 to 10 kN), and it
    reads cyclic loops too (every excursion away from zero is a loading branch)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if len(x) < 2:
        return 1.0
    r = x - x[0]
    dx = np.diff(x)
    away = (r[1:] + r[:-1]) * dx > 0  # the midpoint of the segment and its step have the same sign
    w = float(np.sum(0.5 * (y[1:] + y[:-1])[away] * dx[away]))
    return -1.0 if w < 0 else 1.0


def resolve_sign(curve: "Curve", given: str | float | None = "auto") -> tuple:
    """(sign, rule) of a curve's load: the command line's --load-sign (1 or -1) first, then the sign the case
    states (its [output] curve.sign, through the run folder), else loading_work_sign."""
    if given not in (None, "auto"):
        v = float(given)
        if v not in (1.0, -1.0):
            raise ToolError(f"--load-sign must be auto, 1 or -1, got '{given}'")
        return v, "given (--load-sign)"
    if curve.sign is not None:
        return float(curve.sign), curve.sign_source or "stated by the case"
    return loading_work_sign(curve.x, curve.y), "loading work (the load does positive work as the displacement grows)"


# ----------------------------------------------------------------------------------------------
# Direction, loading branch, envelope, interpolation, area


def mirror_sign(d) -> float:
    """-1.0 when a displacement record's largest excursion is negative (the curve is then read as its mirror image),
    else 1.0."""
    return -1.0 if abs(d.min()) > abs(d.max()) else 1.0


def polyline_area(x, y) -> float:
    """The integral of y dx along the polyline through the points (the trapezoidal rule, exact for the polyline; a
    displacement that goes back counts negatively): the work of a load along its displacement."""
    return float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))


def interp_x(x0, y0, x1, y1, y):
    """x where the segment (x0,y0)-(x1,y1) reaches load y."""
    if y1 == y0:
        return x1
    return x0 + (y - y0) * (x1 - x0) / (y1 - y0)


def loading_branch(x, y):
    """The rows of a curve where x exceeds every earlier x (the monotonic loading branch; a pause or a step back of
    the control displacement is dropped), as two arrays."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if len(x) == 0:
        return x, y
    prev = np.maximum.accumulate(np.concatenate(([-np.inf], x[:-1])))
    keep = x > prev
    return x[keep], y[keep]


def reversal(d) -> float:
    """How far the displacement turns back, as a fraction of its largest |value|: the larger of its largest retreat
    from the running extreme in the direction of its largest excursion and its largest excursion the other way."""
    d = np.asarray(d, dtype=float)
    if len(d) < 2:
        return 0.0
    s = mirror_sign(d)
    x = s * (d - d[0])
    top = float(np.max(np.abs(x)))
    if top <= 0:
        return 0.0
    back = float(np.max(np.maximum.accumulate(x) - x))
    other = float(max(0.0, -x.min()))
    return max(back, other) / top


def is_reversing(d, tol: float = REVERSAL) -> bool:
    return reversal(d) > tol


def envelope(d, p, direction: float = 1.0) -> tuple:
    """The backbone of a (cyclic) record in one direction (+1 or -1), in that direction's coordinates (x = direction
    x d, y = direction x p, so both are positive on the envelope): the rows where x exceeds every earlier x, with x > 0,
    the origin first. Empty arrays when the record never goes that way."""
    d = np.asarray(d, dtype=float) * direction
    p = np.asarray(p, dtype=float) * direction
    xb, yb = loading_branch(d, p)
    keep = xb > 0
    return np.concatenate(([0.0], xb[keep])), np.concatenate(([0.0], yb[keep]))


# ----------------------------------------------------------------------------------------------
# Smoothing and the peak rules (validate --smooth, --peak, --peak-up-to; the half-rate check)


def smooth_curve(x: np.ndarray, y: np.ndarray, window: float) -> np.ndarray:
    """y averaged over the rows whose x lies within window / 2 of each row's x (x in the same unit as window; x is
    the control displacement, made non-decreasing first so that a stalled or jittering actuator does not break the
    search). Near the ends the window is cut (one-sided mean). window <= 0 returns y unchanged."""
    y = np.asarray(y, float)
    if window <= 0 or len(y) == 0:
        return y
    xm = np.maximum.accumulate(np.asarray(x, float))
    cs = np.concatenate(([0.0], np.cumsum(y)))
    lo = np.searchsorted(xm, xm - 0.5 * window, side="left")
    hi = np.searchsorted(xm, xm + 0.5 * window, side="right")
    return (cs[hi] - cs[lo]) / (hi - lo)


def peak_index(y: np.ndarray, rule: str = "largest") -> tuple:
    """(index of the peak, whether the curve fell past it) by --peak's rule. largest: the first row of the largest
    value, past when the last row is PAST_PEAK_DROP below it. first: the running maximum at the first row that lies
    FIRST_PEAK_DROP below it, counting only maxima of at least FIRST_PEAK_FLOOR times the curve's largest value (so
    the inertia spike when an actuator starts is not a peak); then past by construction. A curve that never falls
    that far gives its largest value and past = False (None when that value is not positive)."""
    y = np.asarray(y, float)
    if rule == "first" and len(y):
        floor = FIRST_PEAK_FLOOR * float(np.max(y))
        best = 0
        for k in range(1, len(y)):
            if y[k] > y[best]:
                best = k
            elif y[best] >= floor and y[k] <= (1.0 - FIRST_PEAK_DROP) * y[best]:
                return best, True
        rule = "largest"
    if rule != "largest":
        raise ToolError(f"--peak must be one of {', '.join(PEAK_RULES)}, got '{rule}'")
    i = int(np.argmax(y))
    return i, (None if not y[i] > 0 else bool((y[i] - y[-1]) / y[i] >= PAST_PEAK_DROP))


def plateau_or(past, x: np.ndarray, y: np.ndarray, i: int):
    """"plateau" for a curve not past its peak (past False) whose largest load y[i] lies well inside the run (at or
    before PLATEAU_REACH of its travel) and that ends below it, by less than PAST_PEAK_DROP: an inner maximum followed
    by a slow fall (a rigid mechanism losing load to the P-delta of its weights); otherwise `past` unchanged."""
    if past is False and len(x) and float(x[i]) <= PLATEAU_REACH * float(np.max(x)) and float(y[-1]) < float(y[i]):
        return "plateau"
    return past


def cut_at(x: np.ndarray, d: float) -> int:
    """Number of rows of a curve up to and including the first row whose control displacement reaches d (m)."""
    hit = np.nonzero(np.asarray(x) >= d * (1 - 1e-12))[0]
    return int(hit[0]) + 1 if len(hit) else len(x)


def oscillation(x: np.ndarray, raw: np.ndarray, smooth: np.ndarray, window: float) -> float:
    """Largest |raw - smoothed| (N) over the rows whose window is whole (x - window / 2 >= 0 and x + window / 2 <=
    the largest x): the one-sided means at the two ends of the curve would count the curve's own slope there."""
    if window <= 0:
        return 0.0
    whole = (x - 0.5 * window >= 0) & (x + 0.5 * window <= np.max(x))
    return float(np.max(np.abs(raw - smooth)[whole])) if np.any(whole) else float("nan")


def peak_up_to(m: dict, d: float) -> float:
    """The peak (N) of a run's curve, by the run's --peak rule, up to the first row where the control displacement
    reaches d (m)."""
    x, y = m["x"], m["y"]
    y = y[: cut_at(x, d)]
    return float(y[peak_index(y, m.get("rule", "largest"))[0]])
