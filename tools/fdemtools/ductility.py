"""Ductility against axial stress: f(x) = a e^{b x} + c e^{d x} with 95 % confidence bounds ([K25] Eq. 15).

Fit: nonlinear least squares, min sum_i (f(x_i) - y_i)^2 over (a, b, c, d).
A sum of two exponentials has many poor local minima, so the start is found by variable projection: for fixed
rates (b, d) the amplitudes (a, c) are a linear least-squares problem, solved exactly on a grid of rate pairs;
the best few pairs then start a Levenberg-Marquardt refinement of all four parameters. Terms are reported with
b <= d (the model is symmetric under swapping the terms).
Bounds: parameter p_k +- t_{0.975, n-4} sqrt(C_kk) with C = s^2 (J^T J)^-1, s^2 = SSE / (n - 4) (the usual
linearised bounds, as curve-fitting toolboxes report); the curve's confidence band is
f(x) +- t_{0.975, n-4} sqrt(g(x)^T C g(x)) with g = df/dp. With n = 4 points the fit is exact and no bounds exist.
"""
from __future__ import annotations

import numpy as np
from scipy import optimize, stats

from .common import ToolError


def model(x, a, b, c, d):
    x = np.asarray(x, dtype=float)
    return a * np.exp(b * x) + c * np.exp(d * x)


def _jac(x, p):
    a, b, c, d = p
    eb, ed = np.exp(b * x), np.exp(d * x)
    return np.column_stack((eb, a * x * eb, ed, c * x * ed))


def _amplitudes(x, y, b, d):
    m = np.column_stack((np.exp(b * x), np.exp(d * x)))
    coef, *_ = np.linalg.lstsq(m, y, rcond=None)
    r = m @ coef - y
    return coef, float(r @ r)


def fit(x, y, level: float = 0.95, source: str = "data") -> dict:
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.shape != y.shape or x.ndim != 1:
        raise ToolError(f"{source}: x and y must be two columns of equal length")
    if not (np.isfinite(x).all() and np.isfinite(y).all()):
        raise ToolError(f"{source}: non-finite values in the data")
    n = len(x)
    if n < 4:
        raise ToolError(f"{source}: the two-exponential model has 4 parameters and needs at least 4 points, got {n}")
    if len(np.unique(x)) < 4:
        raise ToolError(f"{source}: needs at least 4 distinct x values")

    span = float(x.max() - x.min())
    grid = np.linspace(-12.0, 12.0, 49) / span
    cands = []
    for i, b in enumerate(grid):
        for d in grid[i + 1:]:
            coef, sse = _amplitudes(x, y, b, d)
            if np.isfinite(sse):
                cands.append((sse, (coef[0], b, coef[1], d)))
    cands.sort(key=lambda c: c[0])
    yscale = max(float(np.max(np.abs(y))), 1e-300)

    best = None
    for _, p0 in cands[:8]:
        try:
            r = optimize.least_squares(lambda p: model(x, *p) - y, np.array(p0), jac=lambda p: _jac(x, p),
                                       method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=20000)
        except (ValueError, FloatingPointError):
            continue
        sse = float(r.fun @ r.fun)
        if np.isfinite(sse) and (best is None or sse < best[0]):
            best = (sse, r.x)
    if best is None:
        raise ToolError(f"{source}: the fit did not converge")
    sse, p = best
    a, b, c, d = p
    if b > d:
        a, b, c, d = c, d, a, b
    p = np.array([a, b, c, d])

    dof = n - 4
    sst = float(np.sum((y - y.mean()) ** 2))
    out = {
        "model": "f(x) = a exp(b x) + c exp(d x)",
        "a": a, "b": b, "c": c, "d": d,
        "n": n, "dof": dof, "sse": sse,
        "rmse": float(np.sqrt(sse / dof)) if dof > 0 else 0.0,
        "r2": 1.0 - sse / sst if sst > 0 else None,
        "confidence": level,
        "bounds": None,
        "bounds_note": "",
        "relative_residual": float(np.sqrt(sse) / (yscale * np.sqrt(n))),
    }
    if dof > 0:
        jac = _jac(x, p)
        s2 = sse / dof
        cov = s2 * np.linalg.pinv(jac.T @ jac)
        tq = float(stats.t.ppf(0.5 + level / 2.0, dof))
        half = tq * np.sqrt(np.maximum(np.diag(cov), 0.0))
        out["bounds"] = {k: [float(v - h), float(v + h)] for k, v, h in zip("abcd", p, half)}
        out["t_quantile"] = tq
        out["covariance"] = cov.tolist()
    else:
        out["bounds_note"] = "n = 4 points: exact fit, no degrees of freedom left for confidence bounds"
    return out


def band(res: dict, xs):
    """Fitted curve and its confidence band at xs (None for the band when there are no bounds)."""
    xs = np.asarray(xs, dtype=float)
    p = np.array([res["a"], res["b"], res["c"], res["d"]])
    f = model(xs, *p)
    if res.get("covariance") is None:
        return f, None, None
    g = _jac(xs, p)
    var = np.einsum("ij,jk,ik->i", g, np.array(res["covariance"]), g)
    h = res["t_quantile"] * np.sqrt(np.maximum(var, 0.0))
    return f, f - h, f + h


def plot(x, y, res: dict, prefix: str, x_label: str, y_label: str, x_scale: float = 1.0) -> list:
    from .figures import new_figure, save
    fig, ax = new_figure()
    lo, hi = float(np.min(x)), float(np.max(x))
    pad = 0.05 * (hi - lo)
    xs = np.linspace(lo - pad, hi + pad, 300)
    f, flo, fhi = band(res, xs)
    if flo is not None:
        ax.fill_between(xs / x_scale, flo, fhi, color="#1f77b4", alpha=0.2,
                        label=f"{100 * res['confidence']:.0f} % confidence band")
    ax.plot(xs / x_scale, f, color="#1f77b4", lw=1.8,
            label=f"$f = {res['a']:.4g}\\,e^{{{res['b']:.4g}x}} + {res['c']:.4g}\\,e^{{{res['d']:.4g}x}}$")
    ax.plot(np.asarray(x) / x_scale, y, "o", color="0.15", ms=5, label="data")
    ax.set_xlabel(x_label)
    ax.set_ylabel(y_label)
    ax.legend(fontsize=8)
    return save(fig, prefix)
