"""Equivalent energy elastic-plastic (EEEP) bilinear curve and ductility. [K25] Eq. 14 (Karakus et al., the EEEP
ductility of the dry-joint stone walls), ASTM E2126 (the EEEP curve, the 0.4 P_peak stiffness and the 0.8 P_peak
failure limit).

Continuous definitions, for a monotonic load-displacement curve P(Delta) starting at the origin:
  K_e      elastic stiffness: least-squares line through the origin fitted to the ascending branch
           for P <= f P_peak (f = 0.7 by default, 0.4 is the ASTM E2126 choice), or the secant at f P_peak;
  Delta_u  ultimate displacement: at the peak (the [K25] choice) or where the load has dropped after the
           peak to 0.8 P_peak (ASTM E2126);
  A        = int_0^Delta_u P dDelta, the area under the curve;
  the EEEP curve (0,0)-(Delta_y,P_y)-(Delta_u,P_y) has the same area A:
           P_y Delta_u - P_y^2 / (2 K_e) = A  =>  P_y = K_e (Delta_u - sqrt(Delta_u^2 - 2 A / K_e))
  Delta_y  = P_y / K_e,  mu = Delta_u / Delta_y.
Discrete form coded here: the sampled curve is taken as piecewise linear between its points, so A is the
trapezoidal rule (exact for the polyline) and the 70 % and 80 % crossings are linear interpolations.
P_y is evaluated as 2 A / (Delta_u + sqrt(Delta_u^2 - 2 A / K_e)), the same value without the cancellation of
the difference form. When Delta_u^2 < 2 A / K_e (the curve holds more energy than any elastic-plastic line
of stiffness K_e can), ASTM E2126 allows P_y = 0.85 P_peak; that fallback is used, flagged (`fallback`), printed
by the command line and drawn in the figure.
Other bilinear idealisations (METHODS, the command's --method): "astm" is the EEEP above with ASTM E2126's rules
(secant at 0.4 P_peak, Delta_u at the post-peak drop to 0.8 P_peak); "tomazevic" the idealisation of Tomazevic
(Earthquake-Resistant Design of Masonry Buildings, 1999) in the form used for masonry shear walls by Frumento,
Magenes, Morandi & Calvi (2009): the effective stiffness as the secant at 0.7 P_peak, Delta_u at the drop to
0.8 P_peak, the resistance P_y by the same equal energy; "ec8" the elasto-perfectly plastic idealisation of
EN 1998-1:2004 Annex B (the N2 method's): the yield force equals the largest load, P_y = P_peak, and the stiffness
follows from the equal area, Delta_y = 2 (Delta_u - A / P_y), K_e = P_y / Delta_y (Delta_u by --ultimate; the
Annex's Delta_m, the displacement at the formation of the mechanism, taken at the drop to 0.8 P_peak by default).
Signs: the displacement is mirrored when its largest excursion is negative; the load takes the tools' one sign rule
(curves.resolve_sign: given, else the case's, else the sign whose loading work is positive), so a softening curve is
never turned and a reaction is.
All quantities are in whatever consistent units the arrays carry (SI from the command line).
Past the peak: the curve has a post-peak branch when its load at the end is at least PAST_PEAK_DROP (5 %) below its
peak (validate's rule). Without one the record stops at (or near) its largest load, the capacity may not be reached
and Delta_u is where the record ends, not where the structure fails: the ductility is then a lower bound
(`past_peak` false, `ductility_is_lower_bound` true).
Reversing records: the fit above is for a monotonic curve. A record whose displacement turns back (it retreats from
its largest excursion, or goes the other way, by more than REVERSAL = 10 % of its largest |displacement|: a cyclic
test, or a pushover unloaded at its end) is refused by `eeep`; `envelope` takes its backbone in one direction (the
rows where the displacement exceeds every earlier one in that direction: the first-cycle loading branches and the
tips of the loops, ASTM E2126's envelope), and the command line fits each direction's envelope apart.
"""
from __future__ import annotations

import numpy as np

from .common import ToolError
from .curves import (PAST_PEAK_DROP, REVERSAL, envelope, interp_x, is_reversing,  # noqa: F401
                     loading_work_sign, mirror_sign, polyline_area, reversal)

NO_POST_PEAK = "no post-peak branch: ductility is a lower bound"
# The bilinear idealisations: the rules each fixes (None: the caller's) and what the result names as its source.
METHODS = {
    "eeep": {"fraction": None, "stiffness": None, "ultimate": None, "drop": None,
             "source": "EEEP ([K25] Eq. 14)"},
    "astm": {"fraction": 0.4, "stiffness": "secant", "ultimate": "drop", "drop": 0.8,
             "source": "EEEP, ASTM E2126 (secant at 0.4 P_peak, ultimate at 0.8 P_peak after the peak)"},
    "tomazevic": {"fraction": 0.7, "stiffness": "secant", "ultimate": "drop", "drop": 0.8,
                  "source": "Tomazevic 1999 bilinear (secant at 0.7 P_peak, ultimate at 0.8 P_peak after the peak, "
                            "equal energy)"},
    "ec8": {"fraction": None, "stiffness": None, "ultimate": None, "drop": None,
            "defaults": {"ultimate": "drop"},
            "source": "EN 1998-1 Annex B (P_y = P_peak, stiffness by equal energy)"},
}


def method_options(method: str, fraction=None, stiffness=None, ultimate=None, drop=None) -> dict:
    """The eeep() keyword options of a bilinear idealisation of METHODS: its fixed rules, the caller's where it fixes
    none (else the defaults 0.7, regression, peak, 0.8). A caller's rule that contradicts the method is an error."""
    if method not in METHODS:
        raise ToolError(f"bilinear idealisation must be one of {', '.join(METHODS)}, got '{method}'")
    m = METHODS[method]
    given = {"fraction": fraction, "stiffness": stiffness, "ultimate": ultimate, "drop": drop}
    default = {"fraction": 0.7, "stiffness": "regression", "ultimate": "peak", "drop": 0.8, **m.get("defaults", {})}
    opts = {}
    for key, value in given.items():
        fixed = m[key]
        if fixed is not None and value is not None and value != fixed:
            flag = {"fraction": "--limit"}.get(key, "--" + key)
            raise ToolError(f"--method {method} fixes {flag} {fixed}; got {flag} {value} (leave it out, or use "
                            "--method eeep with your rules)")
        opts[key] = fixed if fixed is not None else (value if value is not None else default[key])
    opts["method"] = "ec8" if method == "ec8" else "eeep"
    return opts


def eeep(d, p, fraction: float = 0.7, ultimate: str = "peak", drop: float = 0.8, stiffness: str = "regression",
         source: str = "curve", load_sign: float | None = None, method: str = "eeep") -> dict:
    """EEEP analysis of the curve (d, p). Returns a dict of results (same units as the input).

    method: "eeep" (the rules below) or "ec8" (P_y = P_peak, K_e from the equal area; fraction and stiffness then
    only give the branch's stiffness for reference, `K_e_branch`). The presets of METHODS are applied by the caller
    (method_options).
    fraction: regression limit as a fraction of the peak load (0 < fraction <= 1).
    ultimate: "peak" ([K25]) or "drop" (ASTM E2126: post-peak drop to `drop` x peak).
    stiffness: "regression" (least squares through the origin) or "secant" (at fraction x peak).
    load_sign: +1 / -1 to take the load as given / turned; None: curves.loading_work_sign.
    """
    if not 0 < fraction <= 1:
        raise ToolError(f"regression limit must be in (0, 1], got {fraction}")
    if not 0 < drop < 1:
        raise ToolError(f"post-peak drop level must be in (0, 1), got {drop}")
    if ultimate not in ("peak", "drop"):
        raise ToolError(f"ultimate displacement rule must be 'peak' or 'drop', got '{ultimate}'")
    if stiffness not in ("regression", "secant"):
        raise ToolError(f"stiffness rule must be 'regression' or 'secant', got '{stiffness}'")
    if method not in ("eeep", "ec8"):
        raise ToolError(f"idealisation must be 'eeep' or 'ec8' here, got '{method}'")
    d = np.asarray(d, dtype=float)
    p = np.asarray(p, dtype=float)
    if d.shape != p.shape or d.ndim != 1:
        raise ToolError(f"{source}: displacement and load must be two columns of equal length")
    if len(d) < 2:
        raise ToolError(f"{source}: the curve needs at least two points")
    if not (np.isfinite(d).all() and np.isfinite(p).all()):
        raise ToolError(f"{source}: the curve contains non-finite values")
    if is_reversing(d):
        raise ToolError(f"{source}: the displacement reverses (it turns back by {100 * reversal(d):.0f} % of its "
                        "largest value: a cyclic record); EEEP applies to a monotonic curve or to the envelope of "
                        "each direction (eeep.envelope; the eeep command reads it)")

    # A curve loaded in the negative direction is analysed as its mirror image (both axes turned); a reaction
    # monitor's sign is turned on top of that by the one load sign rule.
    sign_x = mirror_sign(d)
    s = loading_work_sign(d, p) if load_sign is None else float(load_sign)
    sign_y = sign_x * s
    d, p = sign_x * d, sign_y * p
    # The bilinear idealisation starts at the origin, so the curve must too.
    origin_added = not (d[0] == 0.0 and p[0] == 0.0)
    if origin_added:
        d = np.concatenate(([0.0], d))
        p = np.concatenate(([0.0], p))

    p_peak = float(p.max())
    if p_peak <= 0:
        raise ToolError(f"{source}: the curve has no peak (the load is never positive)")
    # On a plateau the peak is its far end: an elastic-perfectly-plastic curve peaks at its last point.
    i_peak = int(len(p) - 1 - np.argmax(p[::-1] == p_peak))
    d_peak = float(d[i_peak])
    if d_peak <= 0:
        raise ToolError(f"{source}: the curve has no peak at positive displacement")

    past_peak = bool(p[-1] <= (1.0 - PAST_PEAK_DROP) * p_peak)
    # Ultimate displacement.
    ultimate_note = "displacement at peak load ([K25])"
    n_u = i_peak  # last full point before the end of the integration
    d_u, p_u = d_peak, p_peak
    if ultimate == "drop":
        level = drop * p_peak
        below = np.nonzero(p[i_peak + 1:] < level)[0]
        if len(below):
            j = i_peak + 1 + int(below[0])
            d_u = float(interp_x(d[j - 1], p[j - 1], d[j], p[j], level))
            p_u = level
            n_u = j - 1
            ultimate_note = f"post-peak drop to {drop:g} x peak load (ASTM E2126)"
        else:
            n_u = len(d) - 1
            d_u, p_u = float(d[-1]), float(p[-1])
            ultimate_note = f"last point: the load never drops to {drop:g} x peak (ASTM E2126 failure limit not reached)"

    # Area under the polyline up to Delta_u (path integral, so a non-monotonic displacement counts correctly).
    dd = np.concatenate((d[:n_u + 1], [d_u]))
    pp = np.concatenate((p[:n_u + 1], [p_u]))
    area = polyline_area(dd, pp)
    if area <= 0:
        raise ToolError(f"{source}: the area under the curve up to the ultimate displacement is not positive")

    # Elastic stiffness from the ascending branch up to fraction x peak.
    level = fraction * p_peak
    over = np.nonzero(p[:i_peak + 1] > level)[0]
    if len(over):
        k = int(over[0])
        d_lim = float(interp_x(d[k - 1], p[k - 1], d[k], p[k], level))
        bd = np.concatenate((d[:k], [d_lim]))
        bp = np.concatenate((p[:k], [level]))
    else:  # fraction == 1
        d_lim = d_peak
        bd, bp = d[:i_peak + 1], p[:i_peak + 1]
    if stiffness == "secant":
        if d_lim <= 0:
            raise ToolError(f"{source}: the curve reaches {fraction:g} x peak at non-positive displacement")
        k_e = level / d_lim
    else:
        sxx = float(np.dot(bd, bd))
        if sxx <= 0 or np.count_nonzero(bd) < 1:
            raise ToolError(f"{source}: no points on the ascending branch below {fraction:g} x peak for the regression")
        k_e = float(np.dot(bd, bp)) / sxx
    if k_e <= 0:
        raise ToolError(f"{source}: the elastic stiffness from the ascending branch is not positive ({k_e:g})")

    k_branch = k_e
    if method == "ec8":
        # EN 1998-1 Annex B: F_y = F_max; the area under the bilinear equals A: F_y (Delta_u - Delta_y / 2) = A.
        p_y = p_peak
        d_y = 2.0 * (d_u - area / p_y)
        if not d_y > 0:
            raise ToolError(f"{source}: the curve holds the whole area P_peak x Delta_u (rigid-plastic): no EN 1998-1 "
                            "Annex B yield displacement")
        k_e = p_y / d_y
        yield_note = "P_y = P_peak, Delta_y = 2 (Delta_u - A / P_y) (EN 1998-1 Annex B)"
        fallback = False
    else:
        disc = d_u * d_u - 2.0 * area / k_e
        if disc >= 0:
            p_y = 2.0 * area / (d_u + np.sqrt(disc))
            yield_note = "equal energy ([K25] Eq. 14)"
            fallback = False
        else:
            p_y = 0.85 * p_peak
            yield_note = "0.85 x peak load (ASTM E2126 when Delta_u^2 < 2 A / K_e): EEEP area differs from A"
            fallback = True
        d_y = p_y / k_e
    mu = d_u / d_y
    eeep_area = p_y * d_u - 0.5 * p_y * d_y

    return {
        "K_e": k_e,
        "K_e_branch": k_branch,
        "method": method,
        "P_peak": p_peak,
        "Delta_peak": d_peak,
        "Delta_u": d_u,
        "P_u": p_u,
        "area": area,
        "P_y": float(p_y),
        "Delta_y": float(d_y),
        "ductility": float(mu),
        "eeep_area": float(eeep_area),
        "regression_limit": fraction,
        "regression_points": int(len(bd)),
        "stiffness_rule": stiffness,
        "ultimate_rule": ultimate,
        "ultimate_note": ultimate_note,
        "yield_note": yield_note,
        "fallback": fallback,
        "mirrored": bool(sign_x < 0 or sign_y < 0),
        "sign_x": sign_x,
        "sign_y": sign_y,
        "origin_added": origin_added,
        "P_end": float(p[-1]),
        "past_peak": past_peak,
        "ductility_is_lower_bound": not past_peak,
        "post_peak_note": "" if past_peak else NO_POST_PEAK,
        "bilinear": {"x": [0.0, float(d_y), float(d_u)], "y": [0.0, float(p_y), float(p_y)]},
    }


def _draw_fit(ax, res: dict, sx: float, sy: float, x_unit, y_unit, direction: float = 1.0, colour="#d62728",
              name: str | None = None) -> None:
    """The bilinear EEEP line of res, its yield point, the peak and Delta_u on ax (direction -1: drawn turned, in
    the negative quadrant)."""
    s = direction
    if name is None:
        name = res.get("method_label", "EEEP")
    bx = s * np.array(res["bilinear"]["x"]) * sx
    by = s * np.array(res["bilinear"]["y"]) * sy
    ax.plot(bx, by, color=colour, lw=1.8, ls="--",
            label=f"{name}: $K_e$={res['K_e'] * sy / sx:.4g} {y_unit[0]}/{x_unit[0]}, "
                  f"$P_y$={res['P_y'] * sy:.4g} {y_unit[0]}, $\\mu$={res['ductility']:.3g}"
                  + (" (lower bound)" if res.get("ductility_is_lower_bound") else ""))
    ax.plot([s * res["Delta_y"] * sx], [s * res["P_y"] * sy], "o", color=colour, ms=5)
    ax.plot([s * res["Delta_peak"] * sx], [s * res["P_peak"] * sy], "^", color="0.2", ms=6,
            label=f"peak {res['P_peak'] * sy:.4g} {y_unit[0]} at {res['Delta_peak'] * sx:.4g} {x_unit[0]}")
    if res.get("fallback"):  # drawn, not only flagged in the JSON
        ax.axhline(s * res["P_y"] * sy, color="#ff7f0e", lw=1.0, ls="-.",
                   label="ASTM E2126 fallback $P_y$ = 0.85 $P_{peak}$ (no equal-energy line: "
                         r"$\Delta_u^2 < 2A/K_e$)")
    ax.axvline(s * res["Delta_u"] * sx, color="0.5", lw=0.8, ls=":", label=r"$\Delta_u$" + (
        f" ({name})" if name != "EEEP" else "") + f" = {res['Delta_u'] * sx:.4g} {x_unit[0]}")


def _notes(results: list) -> list:
    """The figure's warnings: the fallback and the missing post-peak branch, per fit."""
    out = []
    for name, res in results:
        pre = f"{name}: " if name else ""
        if res.get("fallback"):
            out.append(pre + "FALLBACK: P_y = 0.85 P_peak, EEEP area differs from the curve's")
        if res.get("ductility_is_lower_bound"):
            out.append(pre + NO_POST_PEAK)
    return out


def _finish(fig, ax, title: str, notes: list):
    """Title with the notes under it, legend below the axes (outside them: it never covers the curve or a label)."""
    ax.set_title(title + "".join("\n" + n for n in notes), fontsize=9,
                 color="#b22222" if notes else "black")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), fontsize=8, ncol=1)


def figure(curve_d, curve_p, res: dict, label: str, x_unit=("mm", 1e-3), y_unit=("kN", 1e3),
           drift_height: float | None = None):
    """The figure of a monotonic fit (matplotlib figure and axes, not saved); drift_height (m): a drift-ratio axis."""
    from .figures import add_drift_axis, new_figure
    sx, sy = 1.0 / x_unit[1], 1.0 / y_unit[1]
    fig, ax = new_figure(figsize=(6.4, 6.2))
    ax.plot(res["sign_x"] * np.asarray(curve_d) * sx, res["sign_y"] * np.asarray(curve_p) * sy, color="0.2", lw=1.4,
            label=label)
    _draw_fit(ax, res, sx, sy, x_unit, y_unit)
    ax.set_xlabel(f"displacement ({x_unit[0]})" + (" [sign reversed]" if res["sign_x"] < 0 else ""))
    ax.set_ylabel(f"load ({y_unit[0]})" + (" [sign reversed]" if res["sign_y"] < 0 else ""))
    ax.set_xlim(left=0)
    ax.set_ylim(bottom=0)
    _finish(fig, ax, f"{res.get('method_label', 'EEEP')} idealisation, ultimate: {res['ultimate_rule']}, "
                     + ("P_y = P_peak" if res.get("method") == "ec8" else
                        f"{res['stiffness_rule']} to {res['regression_limit']:g} P_peak"), _notes([("", res)]))
    if drift_height:
        add_drift_axis(ax, x_unit[1], drift_height)
    return fig, ax


def plot(curve_d, curve_p, res: dict, prefix: str, label: str, x_unit=("mm", 1e-3), y_unit=("kN", 1e3),
         stamp: str = "", drift_height: float | None = None) -> list:
    """The curve, its EEEP bilinear idealisation and the markers of yield, peak and ultimate points."""
    from .figures import save
    fig, _ = figure(curve_d, curve_p, res, label, x_unit, y_unit, drift_height)
    return save(fig, prefix, stamp)


def figure_cyclic(d, p, fits: dict, label: str, x_unit=("mm", 1e-3), y_unit=("kN", 1e3),
                  drift_height: float | None = None):
    """A reversing record (d signed, p with its load sign) in grey, the envelope of each direction and its EEEP fit
    (fits: {"positive": (x_env, y_env, res or None), "negative": ...})."""
    from .figures import new_figure
    sx, sy = 1.0 / x_unit[1], 1.0 / y_unit[1]
    fig, ax = new_figure(figsize=(7.0, 6.6))
    ax.plot(np.asarray(d) * sx, np.asarray(p) * sy, color="0.7", lw=0.8, label=f"{label} (record)")
    colours = {"positive": "#d62728", "negative": "#1f77b4"}
    done = []
    for name, (xe, ye, res) in fits.items():
        s = 1.0 if name == "positive" else -1.0
        ax.plot(s * np.asarray(xe) * sx, s * np.asarray(ye) * sy, color="0.15", lw=1.4,
                label=f"{name} envelope" if name == "positive" else f"{name} envelope (drawn with its sign)")
        if res is not None:
            _draw_fit(ax, res, sx, sy, x_unit, y_unit, s, colours[name], f"{res.get('method_label', 'EEEP')} {name}")
            done.append((name, res))
    ax.axhline(0, color="0.4", lw=0.6)
    ax.axvline(0, color="0.4", lw=0.6)
    ax.set_xlabel(f"displacement ({x_unit[0]})")
    ax.set_ylabel(f"load ({y_unit[0]})")
    _finish(fig, ax, "EEEP of the envelope of each direction (ASTM E2126), cyclic record", _notes(done))
    if drift_height:
        from .figures import add_drift_axis
        add_drift_axis(ax, x_unit[1], drift_height)
    return fig, ax


def plot_cyclic(d, p, fits: dict, prefix: str, label: str, x_unit=("mm", 1e-3), y_unit=("kN", 1e3),
         stamp: str = "", drift_height: float | None = None) -> list:
    from .figures import save
    fig, _ = figure_cyclic(d, p, fits, label, x_unit, y_unit, drift_height)
    return save(fig, prefix, stamp)
