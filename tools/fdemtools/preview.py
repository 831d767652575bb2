"""`preview`: the set-up of a case drawn before it runs: the meshed regions, the joints between bodies by kind, the
supports, drives and loads of the last stage and gravity, from the engine's own export (`fdem mesh`, the
limit_model.json that `limit` reads), so that what is drawn is what `fdem run` builds.

    fdem-tools preview CASE.toml [--set KEY=VALUE ...] [--out FILE.png]

Regions are filled (light colours, legend); dry joints green, bonded joints blue, other interface segments grey;
fixed degrees of freedom as small wedges at their nodes (pointing along the held direction: '>' x, '^' y); a driven
support (velocity or protocol) as a red arrow at its group's centre, labelled with its velocity; a force or pressure
as a black arrow at the group's centre, labelled with its total; gravity as an arrow in the corner. The last stage's
supports and the loads in force then are drawn (as `limit` takes them); earlier stages are listed in the title.
"""
from __future__ import annotations

import os
import shutil
import tempfile

import numpy as np

from .common import ToolError

REGION_COLOURS = ["#dfe8f1", "#f1e4d0", "#e2efdc", "#efdcec", "#f3f0cf", "#d9eeee", "#e8e8e8"]
JOINT_STYLE = {"dry": ("#2ca02c", 1.0), "bonded": ("#1f77b4", 1.0)}


def _centre(model: dict, nodes: list) -> np.ndarray:
    xy = np.asarray(model["nodes"]["xy"], float)
    return xy[np.asarray(nodes, int)].mean(axis=0) if len(nodes) else np.zeros(2)


def draw(model: dict, out_png: str, title: str = "") -> list:
    """Draws the set-up of an exported model (limit_model.json as a dict) to out_png; returns the texts drawn (the
    legend's labels and the annotations), for the caller and the tests."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    xy = np.asarray(model["nodes"]["xy"], float)
    tri = np.asarray(model["triangles"]["nodes"], int)
    reg = list(model["triangles"]["region"])
    names = list(model.get("regions") or sorted(set(reg)))
    fig, ax = plt.subplots(figsize=(9.0, 6.5))
    handles = []
    for i, name in enumerate(names):
        sel = [k for k, r in enumerate(reg) if r == name or r == i]
        if not sel:
            continue
        col = REGION_COLOURS[i % len(REGION_COLOURS)]
        ax.add_collection(PolyCollection(xy[tri[sel]], facecolors=col, edgecolors="0.8", linewidths=0.2, zorder=1))
        handles.append(Patch(facecolor=col, edgecolor="0.6", label=f"region {name} ({len(sel)} triangles)"))
    segs = {}
    for s in model.get("interfaces", []):
        segs.setdefault(s["kind"], []).append([s["p0"], s["p1"]])
    for kind, lines in segs.items():
        col, lw = JOINT_STYLE.get(kind, ("0.5", 0.8))
        ax.add_collection(LineCollection(lines, colors=col, linewidths=lw, zorder=2))
        handles.append(Line2D([], [], color=col, lw=lw, label=f"{kind} joint segments ({len(lines)})"))
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    span = float(max(hi - lo)) or 1.0
    arrow = 0.12 * span
    fixed_done = set()
    for s in model.get("supports", []):
        nodes = s.get("nodes") or []
        c = _centre(model, nodes)
        if s["mode"] == "fixed":
            m = ">" if s["component"] == "x" else "^"
            if (s["group"], s["component"]) in fixed_done:
                continue
            fixed_done.add((s["group"], s["component"]))
            p = xy[np.asarray(nodes, int)] if nodes else np.zeros((0, 2))
            ax.plot(p[:, 0], p[:, 1], m, color="#7f3f00", ms=5, ls="none", zorder=4)
            ax.annotate(f"{s['group']}: {s['component']} fixed", c, fontsize=7, color="#7f3f00",
                        xytext=(4, -10 if s["component"] == "y" else 4), textcoords="offset points", zorder=6)
        elif s["mode"] in ("velocity", "protocol"):
            d = np.array([1.0, 0.0]) if s["component"] == "x" else np.array([0.0, 1.0])
            sgn = np.sign(s.get("velocity") or s.get("protocol_first_displacement") or 1.0)
            ax.annotate("", xy=c + sgn * arrow * d, xytext=c, zorder=6,
                        arrowprops=dict(arrowstyle="-|>", color="tab:red", lw=2.0))
            what = (f"v{s['component']} = {s['velocity']:g} m/s" if s["mode"] == "velocity" else
                    f"protocol in {s['component']}")
            ax.annotate(f"{s['group']}: {what} (stage {s['stage']})", c + sgn * arrow * d, fontsize=7,
                        color="tab:red", xytext=(3, 3), textcoords="offset points", zorder=6)
        else:
            ax.annotate(f"{s['group']}: {s['mode']} in {s['component']}", c, fontsize=7, color="0.3", zorder=6)
    for ld in model.get("loads", []):
        nf = ld.get("node_forces") or []
        if not nf:
            continue
        F = np.array([sum(r[1] for r in nf), sum(r[2] for r in nf)])
        c = _centre(model, [r[0] for r in nf])
        n = float(np.hypot(*F))
        if n <= 0:
            continue
        d = F / n
        ax.annotate("", xy=c, xytext=c - arrow * d, zorder=6,
                    arrowprops=dict(arrowstyle="-|>", color="k", lw=2.0))
        ax.annotate(f"{ld['group']}: {ld['kind']} {n / 1e3:.4g} kN (stage {ld['stage']})", c - arrow * d, fontsize=7,
                    xytext=(3, 3), textcoords="offset points", zorder=6)
    g = (model.get("gravity") or {}).get("vector")
    if g and np.hypot(*g) > 0:
        gd = np.asarray(g, float) / np.hypot(*g)
        o = np.array([hi[0] + 0.05 * span, hi[1]])
        ax.annotate("", xy=o + 0.5 * arrow * gd, xytext=o, arrowprops=dict(arrowstyle="-|>", color="0.4", lw=1.5))
        ax.annotate(f"g = {np.hypot(*g):g} m/s^2" + (f", tilting {model['gravity'].get('tilt_rate_deg_s'):g} deg/s"
                                                      if model["gravity"].get("tilt_rate_deg_s") else ""),
                    o, fontsize=7, color="0.4", xytext=(3, 3), textcoords="offset points")
    handles += [Line2D([], [], marker=">", color="#7f3f00", ls="none", label="fixed x at a node"),
                Line2D([], [], marker="^", color="#7f3f00", ls="none", label="fixed y at a node"),
                Line2D([], [], color="tab:red", lw=2, label="driven support (velocity / protocol)"),
                Line2D([], [], color="k", lw=2, label="force or pressure (total)")]
    ax.set_xlim(lo[0] - 0.1 * span, hi[0] + 0.3 * span)
    ax.set_ylim(lo[1] - 0.1 * span, hi[1] + 0.15 * span)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    stages = model.get("stages") or []
    ax.set_title((title or model.get("case", {}).get("name", "")) + "\nsupports and drives of the last stage"
                 + (f" ('{stages[-1]}')" if stages else "") + "; loads in force then", fontsize=9)
    ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    fig.savefig(out_png, dpi=120)
    texts = [h.get_label() for h in handles] + [t.get_text() for t in ax.texts]
    plt.close(fig)
    return texts


def cmd_preview(args):
    from .limit import export_model
    tmp = tempfile.mkdtemp(prefix="fdem_preview_")
    try:
        model, _ = export_model(args.case, args.set, args.fdem, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    out = args.out or os.path.join("runs", model["case"]["name"], "preview.png")
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    if not out.endswith(".png"):
        raise ToolError(f"--out {out}: expected a .png file name")
    draw(model, out)
    print(f"wrote {out}")
    return 0


def add_parser(sub):
    p = sub.add_parser("preview", help="the case's set-up as a picture before it runs: regions, joints, supports, "
                                       "drives, loads, gravity",
                       description=__doc__.split("\n\n")[0] + " " + __doc__.split("\n\n")[2].replace("\n", " "))
    p.add_argument("case", metavar="CASE.toml", help="case file")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help="override a case value (as fdem --set)")
    p.add_argument("--out", help="PNG file (default runs/<case name>/preview.png)")
    p.add_argument("--fdem", help="fdem executable (default: $FDEM_BIN, else build/fdem/fdem)")
    p.set_defaults(func=cmd_preview)
