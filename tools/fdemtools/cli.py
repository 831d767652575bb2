"""Command line: `fdem-tools COMMAND ...`, one sub-command per post-processing task.

Errors from bad input end the command with one line on stderr and exit code 1 (2 for a failed batch or study
run), never with a traceback; FDEM_TOOLS_DEBUG=1 shows the traceback of unexpected errors.
"""
from __future__ import annotations

import argparse
import os
import sys

from .common import (DEFAULT_X_UNIT, DEFAULT_Y_UNIT, FORCE_UNITS, LENGTH_UNITS, SIGN_CHOICES, STRESS_UNITS,
                     ToolError, check_finite, is_run_folder, load_curve, load_run, output_prefix, read_table,
                     stage_curve, write_json)
from .curves import resolve_sign

PROG = "fdem-tools"
COMMAND_MODULES = ["plots", "cracks", "batch", "study", "validate", "limit", "preview", "provenance"]  # modules with an add_parser(subparsers) function


def _units_args(p, stage_help="keep only the rows of this stage (1-based; run folders)"):
    p.add_argument("--x", help="displacement column (default: the run's curve; in a CSV the one column named as a "
                               "displacement, d_*, u_*, disp*, else the first of exactly two columns)")
    p.add_argument("--y", help="load column (default: the run's curve; in a CSV the one column named as a load, F_*, "
                               "H*, P_*, load*, else the second of exactly two columns)")
    p.add_argument("--x-unit", choices=list(LENGTH_UNITS),
                   help=f"unit of the CSV displacement column (default: the unit its name ends in, as d_mm or "
                        f"'d [mm]', else {DEFAULT_X_UNIT}; run folders are SI)")
    p.add_argument("--y-unit", choices=list(FORCE_UNITS),
                   help=f"unit of the CSV load column (default: the unit its name ends in, as F_kN, else "
                        f"{DEFAULT_Y_UNIT}; run folders are SI)")
    p.add_argument("--load-sign", choices=SIGN_CHOICES, default="auto",
                   help="sign of the load: auto (default: the case's output.curve.sign, else the sign that makes "
                        "the loading work positive), 1 (as recorded) or -1 (turned)")
    p.add_argument("--report-x-unit", default="mm", choices=list(LENGTH_UNITS), help="displacement unit of the report (default mm)")
    p.add_argument("--report-y-unit", default="kN", choices=list(FORCE_UNITS), help="load unit of the report (default kN)")
    p.add_argument("--stage", type=int, help=stage_help)
    p.add_argument("--zero-start", action="store_true",
                   help="measure displacements from the first point kept (e.g. the start of --stage)")
    p.add_argument("--partial", action="store_true", help="accept a run whose summary is not 'completed'")
    p.add_argument("-o", "--out", help="output prefix: writes PREFIX.json/.png/.svg (default: RUN/post/NAME or CSV_STEM_NAME)")


def _curve(args):
    c = load_curve(args.source, args.x, args.y, args.x_unit, args.y_unit, args.stage, args.partial)
    check_finite(c)
    if args.zero_start:
        c.x = c.x - c.x[0]
    return c


def _stamp(source: str) -> str:
    """The figure stamp (figures.run_stamp) of a run folder; a CSV names nothing."""
    from .common import is_run_folder, read_summary
    from .figures import run_stamp
    return run_stamp([read_summary(source)]) if is_run_folder(source) else ""


def _ru(args):
    return (args.report_x_unit, LENGTH_UNITS[args.report_x_unit]), (args.report_y_unit, FORCE_UNITS[args.report_y_unit])


# ----------------------------------------------------------------------------------------------


def last_stage(source: str, partial: bool) -> int | None:
    """The last stage of a run folder's history (validate's choice: the loading after precompression)."""
    run = load_run(source, allow_unfinished=partial)
    h = run.history
    if h is not None and h.has("stage") and len(h):
        import numpy as np
        return int(np.max(h.numeric("stage")))
    return None


def _eeep_fields(res: dict, fx: float, fy: float) -> dict:
    """An eeep result in report units (displacements / fx, loads / fy, stiffness fy/fx), with its rules and flags."""
    return {
        "method": res.get("method_name", "eeep"), "method_source": res.get("method_source", ""),
        "K_e": res["K_e"] * fx / fy, "K_e_branch": res["K_e_branch"] * fx / fy,
        "P_peak": res["P_peak"] / fy, "Delta_peak": res["Delta_peak"] / fx,
        "Delta_u": res["Delta_u"] / fx, "P_u": res["P_u"] / fy,
        "P_y": res["P_y"] / fy, "Delta_y": res["Delta_y"] / fx,
        "ductility": res["ductility"], "P_end": res["P_end"] / fy,
        "past_peak": res["past_peak"], "ductility_is_lower_bound": res["ductility_is_lower_bound"],
        "post_peak_note": res["post_peak_note"],
        "area_J": res["area"], "eeep_area_J": res["eeep_area"],
        "regression_limit": res["regression_limit"], "regression_points": res["regression_points"],
        "stiffness_rule": res["stiffness_rule"], "ultimate_rule": res["ultimate_rule"],
        "ultimate_note": res["ultimate_note"], "yield_note": res["yield_note"],
        "origin_added": res["origin_added"], "fallback": res["fallback"],
        "si": {k: res[k] for k in ("K_e", "P_peak", "Delta_peak", "Delta_u", "P_y", "Delta_y", "area")},
        **{k: res[k] for k in ("drift_height_m", "drift_y_pct", "drift_u_pct") if k in res},
    }


def _eeep_line(name: str, r: dict, xu: str, yu: str) -> str:
    return (f"{name}: " + (f"[{r['method_source']}] " if r.get("method", "eeep") != "eeep" else "") + "K_e = {r['K_e']:.5g} {yu}/{xu}, P_peak = {r['P_peak']:.5g} {yu}, "
            f"P_y = {r['P_y']:.5g} {yu}, Delta_y = {r['Delta_y']:.5g} {xu}, "
            f"Delta_u = {r['Delta_u']:.5g} {xu}, ductility = {r['ductility']:.4g}"
            + (" (lower bound)" if r["ductility_is_lower_bound"] else "")
            + (f"; drift ratios {r['drift_y_pct']:.3g} % at yield, {r['drift_u_pct']:.3g} % at Delta_u "
               f"(H = {r['drift_height_m']:g} m)" if "drift_u_pct" in r else ""))


def _eeep_flags(r: dict, indent: str = "  ", yu: str = "") -> list:
    out = []
    if not r["past_peak"]:
        out.append(f"{indent}NOTE: {r['post_peak_note']} (the load at the end, {r['P_end']:.5g} {yu}, is less than "
                   "5 % below the peak: the record stops before the capacity is shown to be passed)")
    if r["fallback"]:
        out.append(f"{indent}FALLBACK: {r['yield_note']} (no elastic-plastic line of stiffness K_e holds the area "
                   f"{r['area_J']:.4g} J up to Delta_u)")
    return out


def cmd_eeep(args):
    from . import eeep
    from .curves import smooth_curve
    if not args.smooth >= 0:
        raise ToolError(f"--smooth must be a window >= 0 mm, got {args.smooth}")
    if args.drift_height is not None and not args.drift_height > 0:
        raise ToolError(f"--drift-height must be a height > 0 in m, got {args.drift_height}")
    run_folder = is_run_folder(args.source)
    if run_folder and args.stage is None and not args.all_stages:
        # the same curve validate measures: the last stage, displacement from its start, the one load sign rule
        args.stage = last_stage(args.source, args.partial)
        c = load_curve(args.source, args.x, args.y, args.x_unit, args.y_unit, args.stage, args.partial)
        check_finite(c)
        x, y, sign, sign_rule = stage_curve(c, args.load_sign)
        signed_x = c.x - c.x[0]
        stage_note = f"stage {args.stage} (the last), displacement from its start" if args.stage else "all rows"
    else:
        c = _curve(args)
        sign, sign_rule = resolve_sign(c, args.load_sign)
        x, y = c.x, sign * c.y
        signed_x = c.x
        stage_note = f"stage {args.stage}" if args.stage is not None else "all rows"
    (xu, fx), (yu, fy) = _ru(args)
    prefix = output_prefix(args.source, "eeep", args.out)
    opts = dict(eeep.method_options(args.method, args.limit, args.stiffness, args.ultimate, args.drop), load_sign=1.0)
    label = {"eeep": "EEEP", "astm": "EEEP (ASTM E2126)", "tomazevic": "Tomazevic bilinear", "ec8": "EC8 bilinear"}[args.method]

    def fit(xs, ys, source):
        res = eeep.eeep(xs, ys, source=source, **opts)
        res.update(method_name=args.method, method_label=label, method_source=eeep.METHODS[args.method]["source"])
        if args.drift_height:
            res.update(drift_height_m=args.drift_height, drift_y_pct=100 * res["Delta_y"] / args.drift_height,
                       drift_u_pct=100 * res["Delta_u"] / args.drift_height)
        return res

    report = {"source": c.source, "x_column": c.x_name, "y_column": c.y_name,
              "units": {"displacement": xu, "load": yu, "stiffness": f"{yu}/{xu}", "energy": "J"}}
    common = {"columns_rule": c.columns_rule, "load_sign_rule": sign_rule, "curve_rows": stage_note, "smooth_mm": args.smooth,
              "input_units": {"x": c.x_unit, "y": c.y_unit, "rules": list(c.unit_rules)},
              "warnings": list(c.warnings)}
    if eeep.is_reversing(signed_x):
        # a cyclic record: ASTM E2126 fits the envelope of each direction, never the record itself
        fits, per = {}, {}
        for name, s in (("positive", 1.0), ("negative", -1.0)):
            xe, ye = eeep.envelope(signed_x, y, s)
            if args.smooth > 0 and len(xe) > 1:
                ye = smooth_curve(xe, ye, args.smooth * 1e-3)
            if len(xe) < 3:
                per[name] = {"error": "the record does not go this way"}
                continue
            try:
                res = fit(xe, ye, f"{c.source} ({name} envelope)")
            except ToolError as e:
                per[name] = {"error": str(e)}
                fits[name] = (xe, ye, None)
                continue
            fits[name] = (xe, ye, res)
            per[name] = _eeep_fields(res, fx, fy)
        if not any(r is not None for _, _, r in fits.values()):
            raise ToolError(f"{c.source}: a reversing (cyclic) record whose envelope gives no EEEP fit in either "
                            "direction (" + "; ".join(f"{k}: {v['error']}" for k, v in per.items()) + ")")
        report.update({"cyclic": True, "reversal": eeep.reversal(signed_x),
                       "envelope_rule": "ASTM E2126: EEEP of the envelope of each direction (rows where the "
                                        "displacement exceeds every earlier one that way)",
                       "ductility": None, "ductility_note": "cyclic record: see envelope.positive and "
                                                            "envelope.negative",
                       "envelope": per, "sign_y": sign, **common})
        files = [write_json(prefix + ".json", report)]
        if not args.no_plot:
            files += eeep.plot_cyclic(signed_x, y, fits, prefix, c.label, (xu, fx), (yu, fy), stamp=_stamp(args.source),
                                      drift_height=args.drift_height)
        print(f"{c.label}: cyclic record (the displacement reverses by {100 * report['reversal']:.0f} % of its "
              "largest value): EEEP of the envelope of each direction (ASTM E2126)")
        for name, r in per.items():
            if "error" in r:
                print(f"  {name} envelope: no fit ({r['error']})")
                continue
            print("  " + _eeep_line(f"{name} envelope", r, xu, yu))
            for ln in _eeep_flags(r, "    ", yu):
                print(ln)
        print(f"  curve: columns {c.x_name}, {c.y_name} ({c.columns_rule}); {stage_note}; load sign {sign:+g} "
              f"({sign_rule})"
              + (f"; envelope load averaged over {args.smooth:g} mm" if args.smooth > 0 else ""))
        print("wrote " + ", ".join(files))
        return
    if args.smooth > 0:
        y = smooth_curve(abs(x - x[0]), y, args.smooth * 1e-3)
    res = fit(x, y, c.source)
    report.update({"cyclic": False, **_eeep_fields(res, fx, fy), "sign_x": res["sign_x"],
                   "sign_y": res["sign_y"] * sign, **common})
    files = [write_json(prefix + ".json", report)]
    if not args.no_plot:
        files += eeep.plot(x, y, res, prefix, c.label, (xu, fx), (yu, fy), stamp=_stamp(args.source),
                           drift_height=args.drift_height)
    print(_eeep_line(c.label, report, xu, yu))
    print(f"  curve: columns {c.x_name}, {c.y_name} ({c.columns_rule}); {stage_note}; load sign {sign:+g} "
          f"({sign_rule})"
          + (f"; load averaged over {args.smooth:g} mm" if args.smooth > 0 else ""))
    for ln in _eeep_flags(report, yu=yu):
        print(ln)
    print("wrote " + ", ".join(files))


def _eeep_points(specs):
    """--point SIGMA=EEEP_JSON: the ductility of an `eeep` result at an axial stress."""
    import json
    import numpy as np
    xs, ys = [], []
    for spec in specs:
        if "=" not in spec:
            raise ToolError(f"--point '{spec}': expected SIGMA=EEEP_JSON")
        a, path = spec.split("=", 1)
        try:
            xs.append(float(a))
        except ValueError:
            raise ToolError(f"--point '{spec}': '{a}' is not a number") from None
        try:
            with open(path, encoding="utf-8") as f:
                res = json.load(f)
            if res.get("cyclic"):
                raise ToolError(f"{path}: the eeep result of a cyclic record has a ductility per direction "
                                "(envelope.positive, envelope.negative), not one")
            ys.append(float(res["ductility"]))
        except OSError:
            raise ToolError(f"{path}: cannot read") from None
        except (ValueError, KeyError, TypeError):
            raise ToolError(f"{path}: not an eeep result (no 'ductility')") from None
    return np.array(xs), np.array(ys)


def cmd_ductility_fit(args):
    from . import ductility
    if args.source and args.point:
        raise ToolError("give either a CSV or --point values, not both")
    if args.point:
        x, y = _eeep_points(args.point)
        xn, yn, src = "axial stress", "ductility", "eeep results"
        prefix = args.out or "ductility_fit"
    elif args.source:
        tab = read_table(args.source)
        xn = args.x or tab.names[0]
        yn = args.y or (tab.names[1] if len(tab.names) > 1 else None)
        if yn is None:
            raise ToolError(f"{args.source}: needs two columns (axial stress, ductility)")
        x, y = tab.numeric(xn), tab.numeric(yn)
        src = args.source
        prefix = args.out or os.path.splitext(args.source)[0] + "_fit"
    else:
        raise ToolError("no data: give a CSV or --point SIGMA=EEEP_JSON (repeated)")
    res = ductility.fit(x, y, level=args.level, source=src)
    res.update({"source": src, "x_column": xn, "y_column": yn, "x_unit": args.x_unit,
                "note": f"b and d are per {args.x_unit}", "x": x.tolist(), "y": y.tolist()})
    files = [write_json(prefix + ".json", res)]
    if not args.no_plot:
        files += ductility.plot(x, y, res, prefix, f"axial stress ({args.x_unit})", "ductility $\\mu$ (-)")
    b = res["bounds"]
    def fmt(k):
        return f"{k} = {res[k]:.6g}" + (f" [{b[k][0]:.4g}, {b[k][1]:.4g}]" if b else "")
    print(", ".join(fmt(k) for k in "abcd") + (f"; R^2 = {res['r2']:.4f}" if res["r2"] is not None else ""))
    if not b:
        print(res["bounds_note"])
    print("wrote " + ", ".join(files))


def cmd_hysteresis(args):
    from . import hysteresis
    from .common import write_csv
    c = _curve(args)
    (xu, fx), (yu, fy) = _ru(args)
    sign, sign_rule = resolve_sign(c, args.load_sign)
    k_el = args.k_el * fy / fx if args.k_el is not None else None
    res = hysteresis.analyse(c.x, c.y, k_el=k_el, e_h=args.e_h, deadband=args.deadband, source=c.source,
                             load_sign=sign, tip_band=args.tip_band)
    prefix = output_prefix(args.source, "hysteresis", args.out)
    rows = []
    for cy in res["cycles"]:
        rows.append([cy["cycle"], int(cy["complete"]), cy["d_plus"] / fx, cy["P_plus"] / fy, cy["d_minus"] / fx,
                     cy["P_minus"] / fy, cy["k_i"] * fx / fy, cy["k_d"], cy["W_i"], cy["E_i"], cy["E_d"],
                     int(cy["W_negative"]), cy["P_largest_plus"] / fy, cy["d_at_P_largest_plus"] / fx,
                     cy["P_largest_minus"] / fy, cy["d_at_P_largest_minus"] / fx])
    header = ["cycle", "complete", f"d_plus_{xu}", f"P_plus_{yu}", f"d_minus_{xu}", f"P_minus_{yu}",
              f"k_i_{yu}_per_{xu}", "k_d", "W_i_J", "E_i_J", "E_d", "W_negative", f"P_largest_plus_{yu}",
              f"d_at_P_largest_plus_{xu}", f"P_largest_minus_{yu}", f"d_at_P_largest_minus_{xu}"]
    report = {"source": c.source, "units": {"displacement": xu, "load": yu, "stiffness": f"{yu}/{xu}", "energy": "J"},
              "k_el": res["k_el"] * fx / fy, "k_el_rule": res["k_el_rule"], "E_h_J": res["E_h"],
              "E_h_rule": res["E_h_rule"], "E_total_J": res["E_total"], "n_cycles": res["n_cycles"],
              "peak_rule": res["peak_rule"], "sign_y": res["sign_y"], "load_sign_rule": sign_rule,
              "warnings": list(c.warnings) + res["warnings"], "columns": header, "cycles": rows,
              "partial_cycles": [{"cycle": q["cycle"], "d_plus": q["d_plus"] / fx, "P_plus": q["P_plus"] / fy,
                                  "d_minus": q["d_minus"] / fx, "P_minus": q["P_minus"] / fy, "W_J": q["W_i"],
                                  "d_end": q["d_end"] / fx} for q in res["partial"]],
              "partial_note": "partial cycles (the record ends inside them) are kept out of the cycle table, k_el, "
                              "k_d, E_i, E_d and E_h"}
    files = [write_json(prefix + ".json", report), write_csv(prefix + ".csv", header, rows)]
    if not args.no_plot:
        files += hysteresis.plot(c.x, c.y, res, prefix, c.label, (xu, fx), (yu, fy), stamp=_stamp(args.source))
    print(f"{c.label}: {res['n_cycles']} complete cycles"
          + (f" (+ {res['n_partial']} partial, not counted)" if res["n_partial"] else "")
          + f", k_el = {report['k_el']:.5g} {yu}/{xu}, E_total = {res['E_total']:.5g} J; load sign {sign:+g} "
            f"({sign_rule}); peaks at the loop tips")
    for r in rows:
        print("  cycle {:3d}: d+ {:8.4g} P+ {:9.4g}  d- {:8.4g} P- {:9.4g} {}  k_i {:9.4g}  k_d {:6.3f}  "
              "W_i {:9.4g} J{} E_i {:9.4g} J  E_d {:6.3f}".format(r[0], r[2], r[3], r[4], r[5],
                                                                 yu, r[6], r[7], r[8], " (NEGATIVE)" if r[11] else "",
                                                                 r[9], r[10]))
    for q in report["partial_cycles"]:
        print("  cycle {:3d}*: d+ {:8.4g} P+ {:9.4g}  d- {:8.4g} P- {:9.4g} {}  W {:9.4g} J, ends at d = {:.4g} {}"
              .format(q["cycle"], q["d_plus"], q["P_plus"], q["d_minus"], q["P_minus"], yu, q["W_J"], q["d_end"], xu))
    if report["partial_cycles"]:
        print("  * partial cycle: the record ends before the cycle returns to zero from the negative side; its "
              "tips are where the record stopped, so it is kept out of the table, k_el, k_d, E_i, E_d and E_h")
    print("wrote " + ", ".join(files))


# ----------------------------------------------------------------------------------------------


class PercentFormatter(argparse.HelpFormatter):
    """argparse %-formats help strings, so they write a percent sign as %%, but shows descriptions as written (only
    one that holds %(prog) is formatted), which then showed a literal %%. Here every text is written the one way,
    %% for %, and shown with one %."""

    def _format_text(self, text):
        if "%" in text and "%(prog)" not in text:
            text = text.replace("%%", "%")
        return super()._format_text(text)


class OneLineParser(argparse.ArgumentParser):
    """Usage errors as one line too (the usage itself is one --help away); help texts through PercentFormatter
    (sub-commands too: they are made with this class)."""

    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", PercentFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message):
        self.exit(1, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser():
    ap = OneLineParser(prog=PROG, description="Post-processing of fdem run folders and measured curves.")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND")

    p = sub.add_parser("eeep", help="EEEP bilinear curve and ductility ([K25] Eq. 14, ASTM E2126)",
                       description="EEEP bilinear idealisation and ductility of a monotonic load-displacement curve "
                                   "([K25] Eq. 14, ASTM E2126; tools/README.md 'eeep'). SOURCE is an fdem run folder "
                                   "(by default its last stage, displacement from the stage's start, as validate) or "
                                   "a CSV.")
    p.add_argument("source", metavar="SOURCE", help="run folder or CSV file")
    _units_args(p, stage_help="keep only the rows of this stage (1-based; run folders; default: the last stage, "
                              "displacements from its start, as validate)")
    p.add_argument("--all-stages", action="store_true",
                   help="run folders: read every row (precompression too) instead of the last stage")
    p.add_argument("--smooth", type=float, default=0.0, metavar="MM",
                   help="take the curve on the load averaged over MM mm of control displacement centred on each row, "
                        "as validate --smooth (default 0: raw)")
    p.add_argument("--method", choices=["eeep", "astm", "tomazevic", "ec8"], default="eeep",
                   help="bilinear idealisation: eeep (default: the rules below), astm (ASTM E2126: secant at 0.4 "
                        "peak, ultimate at the drop to 0.8 peak), tomazevic (secant at 0.7 peak, ultimate at the drop "
                        "to 0.8 peak, equal energy), ec8 (EN 1998-1 Annex B: yield force = peak, stiffness from the "
                        "equal area; ultimate at the drop to 0.8 peak unless --ultimate is given)")
    p.add_argument("--limit", type=float, default=None,
                   help="regression limit: fit K_e to the ascending branch up to this fraction of the peak (default 0.7)")
    p.add_argument("--stiffness", choices=["regression", "secant"], default=None,
                   help="K_e by least squares through the origin (default) or as the secant at LIMIT x peak")
    p.add_argument("--ultimate", choices=["peak", "drop"], default=None,
                   help="ultimate displacement: at peak load ([K25], default) or at the post-peak drop (ASTM E2126)")
    p.add_argument("--drop", type=float, default=None, help="post-peak load level for --ultimate drop (default 0.8)")
    p.add_argument("--drift-height", type=float, metavar="H",
                   help="height H in m over which the drift is taken: drift ratios of Delta_y and Delta_u in the JSON "
                        "and the output, a drift-ratio axis on the figure")
    p.add_argument("--no-plot", action="store_true", help="write the JSON only")
    p.set_defaults(func=cmd_eeep)

    p = sub.add_parser("ductility-fit", help="fit a e^{bx} + c e^{dx} to (axial stress, ductility) with 95 %% bounds",
                       description="Fits f(x) = a exp(b x) + c exp(d x) to (axial stress, ductility) points "
                                   "([K25] Eq. 15) and reports 95 %% confidence bounds (needs >= 5 points for bounds).")
    p.add_argument("source", metavar="CSV", nargs="?", help="CSV with the axial stress and ductility columns")
    p.add_argument("--point", action="append", metavar="SIGMA=EEEP_JSON",
                   help="instead of a CSV: axial stress (in --x-unit) and the JSON written by `eeep` (repeatable)")
    p.add_argument("--x", help="axial stress column (default: first)")
    p.add_argument("--y", help="ductility column (default: second)")
    p.add_argument("--x-unit", default="MPa", choices=list(STRESS_UNITS),
                   help="unit of the stress column, used for labels; b and d are per this unit (default MPa)")
    p.add_argument("--level", type=float, default=0.95, help="confidence level (default 0.95)")
    p.add_argument("-o", "--out", help="output prefix (default: CSV_STEM_fit, or ductility_fit with --point)")
    p.add_argument("--no-plot", action="store_true", help="write the JSON only")
    p.set_defaults(func=cmd_ductility_fit)

    p = sub.add_parser("hysteresis", help="per-cycle peaks, secant stiffness and dissipated energy of a cyclic curve",
                       description="Per-cycle peaks, secant stiffness k_i, k_d = k_i / k_el, cumulative dissipated "
                                   "energy E_i and E_d = E_i / E_h of a cyclic load-displacement curve (the indices of "
                                   "the M-DEM paper's Eqs. 6-8, tools/README.md 'hysteresis'): each cycle's peaks are "
                                   "the loads at its extreme displacements.")
    p.add_argument("source", metavar="SOURCE", help="run folder or CSV file")
    _units_args(p)
    p.add_argument("--k-el", type=float, help="reference elastic stiffness in report units (default: k of the first cycle)")
    p.add_argument("--e-h", type=float, help="reference energy E_h in J (default: the total at the end)")
    p.add_argument("--deadband", type=float, default=1e-3,
                   help="zero band for cycle detection, fraction of the largest displacement (default 1e-3)")
    p.add_argument("--tip-band", type=float, default=0.05,
                   help="a cycle's peak is the largest load while the displacement is within this fraction of the "
                        "excursion's extreme (default 0.05; 0: the load at the extreme row)")
    p.add_argument("--no-plot", action="store_true", help="write the JSON and CSV only")
    p.set_defaults(func=cmd_hysteresis)

    import importlib
    for name in COMMAND_MODULES:  # each adds its own sub-command(s)
        importlib.import_module(f".{name}", __package__).add_parser(sub)
    return ap


def main(argv=None) -> int:
    ap = build_parser()
    args = ap.parse_args(argv)
    if not getattr(args, "func", None):
        ap.print_help()
        return 1
    try:
        rc = args.func(args)
        return int(rc or 0)
    except ToolError as e:
        print(f"{PROG} {args.command}: error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{PROG} {args.command}: interrupted", file=sys.stderr)
        return 130
    except Exception as e:  # a bug or an unforeseen input: still one line unless debugging
        if os.environ.get("FDEM_TOOLS_DEBUG"):
            raise
        print(f"{PROG} {args.command}: error: {type(e).__name__}: {e} (FDEM_TOOLS_DEBUG=1 shows the traceback)",
              file=sys.stderr)
        return 3
