"""Crack-pattern image of a run at a chosen time: the deformed outline of the units and the broken cohesive
elements coloured by mode (tension I, shear II, mixed), unit-interior and interface cracks told apart.

Sources: cracks.csv (one row per broken element: time, control displacement, reference midpoint, class, mode)
and the .vtu snapshot at or before the chosen time (reference points + displacement). A broken element is drawn
as the mesh edge whose midpoint, in the snapshot nearest in time to the break, is nearest to the recorded
midpoint (the fracture module records it in the current configuration), at its deformed position in the chosen
snapshot; with no snapshot it is drawn as a marker at the recorded midpoint.
Unit outline: the edges of the triangulation that bound a unit, i.e. edges with one triangle only (free
boundary) or whose two triangles differ in the cell array `unit` (if the snapshot has one), else `region`, else
`material`. Edges are matched by their reference coordinates, so duplicated nodes on either side of a joint count
as one edge; an opened joint shows as a gap in the grey deformed mesh drawn underneath.

Dry joints (mortarless, no cohesive element) leave rows of class `interface-dry` instead: mode `open` when the
normal opening at one end of the joint segment first exceeded `output.joint_open` (m), mode `slip` when the mean
tangential slip of its ends first exceeded `output.joint_slip` (m); D_I and D_II are then the largest end opening
and the |slip| divided by those thresholds (-), `element` the joint segment's own index (not a cohesive element's).
A segment can have one row of each mode, and a joint that closes again keeps its row: they are records of events,
not of the present state. Their segment is found
exactly as a broken element's (nearest edge midpoint to the recorded current midpoint), and they are drawn under
the cohesive cracks in their own style (openings thick orange, slips thin green: purple is already mixed mode),
counted apart from the broken elements, never added to them.
"""
from __future__ import annotations

import glob
import os

import numpy as np

from .common import MODE_COLOURS, MODE_NAMES, ToolError, load_run, read_table
from .vtk import read_pvd, read_vtu, triangles

CLASS_STYLE = {"unit": {"ls": "-", "lw": 2.0, "marker": "o"}, "interface": {"ls": (0, (2.0, 1.2)), "lw": 1.6, "marker": "s"}}
CLASS_NAMES = {"unit": "in units", "interface": "at interfaces"}


# Column names of the run-folder contract, and the unit-suffixed names the fracture module writes.
CRACK_COLUMNS = {"time": ("time", "time_s"), "control_displacement": ("control_displacement", "control_displacement_m"),
                 "x": ("x", "x_m"), "y": ("y", "y_m"), "class": ("class",), "mode": ("mode",)}
CLASS_ALIASES = {"unit": "unit", "unit-interior": "unit", "unit_interior": "unit", "interior": "unit",
                 "interface": "interface", "interface-dry": "dry", "interface_dry": "dry"}
# Dry-joint events (class interface-dry), by mode. Drawn under the cohesive cracks (zorder 3), above the outline
# (zorder 2): the thick opening first so that a slip of the same segment stays visible on top of it.
DRY_STYLE = {"open": {"color": "#ff7f0e", "lw": 4.0, "alpha": 0.7, "marker": "D", "ms": 5, "zorder": 2.4,
                      "name": "dry joint opened", "threshold": "open_threshold_m"},
             "slip": {"color": "#2ca02c", "lw": 1.1, "alpha": 1.0, "marker": "x", "ms": 6, "zorder": 2.6,
                      "name": "dry joint slipped", "threshold": "slip_threshold_m"}}
EXPECTED_CLASSES = "unit-interior (or unit), interface, interface-dry"
EXPECTED_MODES = "I, II or mixed for broken elements, open or slip for interface-dry"


def read_cracks(run_dir: str):
    path = os.path.join(run_dir, "cracks.csv")
    if not os.path.isfile(path):
        raise ToolError(f"{run_dir}: no cracks.csv (was fracture on in this run?)")
    t = read_table(path)
    names = {}
    for key, options in CRACK_COLUMNS.items():
        found = [o for o in options if t.has(o)]
        if not found and key != "control_displacement":
            raise ToolError(f"{path}: no column '{options[0]}' (columns: {', '.join(t.names)})")
        names[key] = found[0] if found else None
    n = len(t)
    if n == 0:
        return {"time": np.zeros(0), "x": np.zeros(0), "y": np.zeros(0), "class": np.zeros(0, object),
                "mode": np.zeros(0, object), "control_displacement": np.zeros(0)}
    cls = np.array([CLASS_ALIASES.get(str(v), str(v)) for v in t.col("class")], dtype=object)
    mode = np.array([str(v) for v in t.col("mode")], dtype=object)
    bad = set(cls) - set(CLASS_STYLE) - {"dry"}
    if bad:
        raise ToolError(f"{path}: unknown class {sorted(bad)} (expected {EXPECTED_CLASSES})")
    bad = set(mode) - set(MODE_COLOURS) - set(DRY_STYLE)
    if bad:
        raise ToolError(f"{path}: unknown mode {sorted(bad)} (expected {EXPECTED_MODES})")
    dry = cls == "dry"
    # a known mode on the wrong kind of row would otherwise be silently left out of the image and the counts
    wrong = np.nonzero(dry & ~np.isin(mode, list(DRY_STYLE)) | ~dry & ~np.isin(mode, list(MODE_COLOURS)))[0]
    if len(wrong):
        i = int(wrong[0])
        raw = str(t.col("class")[i])
        raise ToolError(f"{path}: data row {i + 1}: mode '{mode[i]}' does not go with class '{raw}' "
                        f"(expected {EXPECTED_MODES}); {len(wrong)} such row(s)")
    cd = t.numeric(names["control_displacement"]) if names["control_displacement"] else np.full(n, np.nan)
    out = {"time": t.numeric(names["time"]), "x": t.numeric(names["x"]), "y": t.numeric(names["y"]), "class": cls,
           "mode": mode, "control_displacement": cd}
    # the engine also writes the reference midpoint: an exact key to the element's mesh edge
    if t.has("x_ref_m") and t.has("y_ref_m"):
        out["x_ref"], out["y_ref"] = t.numeric("x_ref_m"), t.numeric("y_ref_m")
    return out


def snapshots(run_dir: str) -> list:
    pvd = os.path.join(run_dir, "run.pvd")
    if os.path.isfile(pvd):
        return [(t, f) for t, f in read_pvd(pvd) if os.path.isfile(f)]
    files = sorted(glob.glob(os.path.join(run_dir, "snapshots", "*.vtu")))
    return [(float("nan"), f) for f in files]


def pick_snapshot(snaps: list, time: float | None):
    if not snaps:
        return None
    if time is None or not all(np.isfinite(t) for t, _ in snaps):  # no times known: the last snapshot
        return snaps[-1]
    before = [s for s in snaps if s[0] <= time * (1 + 1e-12) + 1e-300]
    return before[-1] if before else snaps[0]


def _unit_ids(vtu: dict, sel):
    for name in ("unit", "unit_id", "body", "block", "region", "material"):
        a = vtu["cell_data"].get(name)
        if a is not None and a.ndim == 1 and len(a) == len(vtu["types"]):
            return name, a[sel]
    return None, np.zeros(len(sel), np.int64)


def geometry(vtu: dict, scale: float = 1.0):
    """Deformed node positions, triangles, outline edges (pairs of node indices) and all edges keyed by their
    reference midpoint, for matching cracks."""
    X = vtu["points"][:, :2].astype(float)
    u = vtu["point_data"].get("displacement")
    x = X + scale * u[:, :2] if u is not None else X.copy()
    sel, tri = triangles(vtu)
    if len(tri) == 0:
        raise ToolError("snapshot has no triangles")
    _, uid = _unit_ids(vtu, sel)
    # geometric edges: key = rounded reference coordinates of both ends (duplicated nodes coincide in X)
    span = float(np.ptp(X, axis=0).max()) or 1.0
    q = np.round(X / (span * 1e-9)).astype(np.int64)
    e_nodes = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    e_tri = np.tile(np.arange(len(tri)), 3)
    ka, kb = q[e_nodes[:, 0]], q[e_nodes[:, 1]]
    swap = (ka[:, 0] > kb[:, 0]) | ((ka[:, 0] == kb[:, 0]) & (ka[:, 1] > kb[:, 1]))
    lo = np.where(swap[:, None], kb, ka)
    hi = np.where(swap[:, None], ka, kb)
    keys = np.concatenate([lo, hi], axis=1)
    _, inv, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    inv = inv.reshape(-1)
    order = np.argsort(inv, kind="stable")
    outline = []
    first = {}
    for k in order:
        g = inv[k]
        if counts[g] == 1:
            outline.append(e_nodes[k])
        elif g in first:
            j = first[g]
            if uid[e_tri[j]] != uid[e_tri[k]]:
                outline.append(e_nodes[k])
                outline.append(e_nodes[j])
        else:
            first[g] = k
    mid_ref = 0.5 * (X[e_nodes[:, 0]] + X[e_nodes[:, 1]])
    joints = None
    cd = vtu["cell_data"]
    if all(k in cd for k in ("cell_kind", "joint_state", "joint_opening", "joint_slip")):
        offs = vtu["offsets"]
        starts = np.concatenate(([0], offs[:-1]))
        lsel = np.nonzero((vtu["types"] == 3) & (offs - starts == 2) & (cd["cell_kind"] == 1))[0]
        conn = vtu["connectivity"]
        joints = {"nodes": np.stack([conn[starts[lsel]], conn[starts[lsel] + 1]], axis=1),
                  "state": np.asarray(cd["joint_state"])[lsel], "opening": np.asarray(cd["joint_opening"], float)[lsel],
                  "slip": np.asarray(cd["joint_slip"], float)[lsel]}
    bc = vtu["cell_data"].get("block_crushing")
    crushing = np.asarray(bc, float)[sel] if bc is not None and bc.ndim == 1 and len(bc) == len(vtu["types"]) else None
    return {"x": x, "X": X, "tri": tri, "outline": np.array(outline).reshape(-1, 2), "edges": e_nodes,
            "edge_mid_ref": mid_ref, "crushing": crushing, "joints": joints}


def match_edges(run_dir: str, geo: dict, pts, times):
    """Index (into geo['edges']) of the mesh edge of each broken element.

    The fracture module records an element's midpoint in the current configuration at breaking, so each crack is
    matched against the edge midpoints of the snapshot nearest in time to its break (same mesh in every snapshot
    of a run); if the snapshots carry no times or differ in size, against the reference midpoints."""
    from scipy.spatial import cKDTree
    snaps = snapshots(run_dir)
    st = np.array([t for t, _ in snaps], dtype=float)
    if not len(snaps) or not np.isfinite(st).all():
        return cKDTree(geo["edge_mid_ref"]).query(pts)[1]
    which = np.argmin(np.abs(st[None, :] - np.asarray(times, float)[:, None]), axis=1)
    idx = np.zeros(len(pts), dtype=np.int64)
    e = geo["edges"]
    for j in np.unique(which):
        v = read_vtu(snaps[j][1])
        X = v["points"][:, :2]
        u = v["point_data"].get("displacement")
        if X.shape != geo["X"].shape or u is None:
            mids = geo["edge_mid_ref"]
        else:
            xj = X + u[:, :2]
            mids = 0.5 * (xj[e[:, 0]] + xj[e[:, 1]])
        sel = which == j
        idx[sel] = cKDTree(mids).query(pts[sel])[1]
    return idx


def run_range(run, cr) -> dict:
    """What the run covers: time (s) from the history (else the snapshots, else summary.json's end time and
    cracks.csv) and the largest |control displacement| (m) of the curve's x (else cracks.csv); None where unknown."""
    out = {"t0": None, "t1": None, "d_max": None}
    h = run.history
    if h is not None and h.has("time") and len(h):
        t = h.numeric("time")
        out["t0"], out["t1"] = float(t.min()), float(t.max())
    else:
        ts = [t for t, _ in snapshots(run.path) if np.isfinite(t)]
        ends = ts + ([float(run.summary["time"])] if isinstance(run.summary.get("time"), (int, float)) else [])
        ends += [float(v) for v in cr["time"]] if len(cr["time"]) else []
        if ends:
            out["t0"], out["t1"] = 0.0, max(ends)
    try:
        if h is not None:
            cx, _ = run.curve_columns()
            out["d_max"] = float(np.max(np.abs(h.numeric(cx))))
    except ToolError:
        pass
    if out["d_max"] is None and np.isfinite(cr["control_displacement"]).any():
        out["d_max"] = float(np.nanmax(np.abs(cr["control_displacement"])))
    return out


def check_range(run, cr, time: float | None, displacement: float | None) -> None:
    """--time / --displacement outside what the run covers: a ToolError naming the range (exit 1), not the last
    snapshot drawn under a title it never reached."""
    r = run_range(run, cr)
    if time is not None and r["t1"] is not None:
        if time > r["t1"] * (1 + 1e-9) + 1e-300 or time < r["t0"] - 1e-12:
            raise ToolError(f"{run.path}: --time {time:g} s is outside the run, which covers {r['t0']:g} to "
                            f"{r['t1']:g} s")
    if displacement is not None and r["d_max"] is not None:
        if abs(displacement) > r["d_max"] * (1 + 1e-9):
            raise ToolError(f"{run.path}: --displacement {abs(displacement) * 1e3:g} mm is beyond the run, whose "
                            f"control displacement reaches {r['d_max'] * 1e3:.4g} mm (|x| from 0 to that)")


def draw(run_dir: str, prefix: str, time: float | None = None, displacement: float | None = None,
         scale: float = 1.0, partial: bool = False, joint_width: float | None = None) -> tuple:
    run = load_run(run_dir, allow_unfinished=partial, need_history=False)
    cr = read_cracks(run_dir)
    check_range(run, cr, time, displacement)
    if displacement is not None:
        h = run.history
        if h is not None and h.has("time"):
            try:
                cx, _ = run.curve_columns()
                hx = h.numeric(cx)
                reach = np.nonzero(np.abs(hx) >= abs(displacement))[0]
                time = float(h.numeric("time")[reach[0]]) if len(reach) else None
            except ToolError:
                time = None
        if time is None:
            if not np.isfinite(cr["control_displacement"]).any():
                raise ToolError(f"{run_dir}: neither the history's curve nor cracks.csv's control_displacement "
                                "to select by displacement")
            reach = np.nonzero(np.abs(cr["control_displacement"]) <= abs(displacement))[0]
            time = float(cr["time"][reach].max()) if len(reach) else 0.0
    snap = pick_snapshot(snapshots(run_dir), time)
    if time is None:
        time = snap[0] if snap and np.isfinite(snap[0]) else (float(cr["time"].max()) if len(cr["time"]) else 0.0)
    keep = cr["time"] <= time * (1 + 1e-12) + 1e-300
    from .figures import new_figure, save
    fig, ax = new_figure(figsize=(7.5, 6.5))
    geo = None
    crushed_patches = []
    joint_counts = {}
    if snap is not None:
        geo = geometry(read_vtu(snap[1]), scale)
        x = geo["x"]
        ax.tripcolor(x[:, 0], x[:, 1], geo["tri"], facecolors=np.ones(len(geo["tri"])), cmap="Greys", vmin=0, vmax=8,
                     edgecolors="none", alpha=0.6)
        crushed_patches = _draw_crushing(ax, geo)
        if joint_width is not None:
            joint_counts = _draw_joint_widths(ax, geo, joint_width)
        o = geo["outline"]
        if len(o):
            from matplotlib.collections import LineCollection
            ax.add_collection(LineCollection(x[o], colors="0.15", linewidths=0.7, zorder=2))
    counts = {}
    if keep.any():
        from matplotlib.collections import LineCollection
        pts = np.column_stack((cr["x"][keep], cr["y"][keep]))
        cls, mode = cr["class"][keep], cr["mode"][keep]
        segs = None
        matched = None
        if geo is not None and "x_ref" in cr and np.isfinite(cr["x_ref"][keep]).all():
            # Reference midpoints are exact (both copies of a split edge share them); the current midpoint can lie
            # nearer another edge once the blocks have moved by more than an element.
            from scipy.spatial import cKDTree
            ref = np.column_stack((cr["x_ref"][keep], cr["y_ref"][keep]))
            idx = cKDTree(geo["edge_mid_ref"]).query(ref)[1]
        elif geo is not None:
            idx = match_edges(run_dir, geo, pts, cr["time"][keep])
        if geo is not None:
            ends = geo["edges"][idx]
            segs = geo["x"][ends]  # (k, 2, 2) deformed
            matched = geo["edge_mid_ref"][idx]
        for c in CLASS_STYLE:
            for m in MODE_COLOURS:
                s = (cls == c) & (mode == m)
                n = int(s.sum())
                counts[f"{c}_{m}"] = n
                if not n:
                    continue
                lab = f"{MODE_NAMES[m]} {CLASS_NAMES[c]} ({n})"
                if segs is not None:
                    ax.add_collection(LineCollection(segs[s], colors=MODE_COLOURS[m], linewidths=CLASS_STYLE[c]["lw"],
                                                     linestyles=[CLASS_STYLE[c]["ls"]], zorder=3, label=lab))
                else:
                    ax.plot(pts[s, 0], pts[s, 1], CLASS_STYLE[c]["marker"], color=MODE_COLOURS[m], ms=4, ls="none",
                            label=lab, zorder=3)
        # added after the cracks so that the legend lists them last; zorder puts them underneath
        for m, st in DRY_STYLE.items():
            s = (cls == "dry") & (mode == m)
            n = int(s.sum())
            counts[f"dry_{m}"] = n
            if not n:
                continue
            lab = f"{st['name']}{_threshold_text(run, st['threshold'])} ({n})"
            if segs is not None:
                ax.add_collection(LineCollection(segs[s], colors=st["color"], linewidths=st["lw"], alpha=st["alpha"],
                                                 capstyle="butt", zorder=st["zorder"], label=lab))
            else:
                ax.plot(pts[s, 0], pts[s, 1], st["marker"], color=st["color"], ms=st["ms"], ls="none", label=lab,
                        zorder=st["zorder"])
    else:
        for c in CLASS_STYLE:
            for m in MODE_COLOURS:
                counts[f"{c}_{m}"] = 0
        for m in DRY_STYLE:
            counts[f"dry_{m}"] = 0
    counts.update(joint_counts)
    if geo is not None and geo["crushing"] is not None:
        c = geo["crushing"]
        counts["crushing"] = int(np.sum(c > CRUSH_STARTED))
        counts["crushed"] = int(np.sum(c >= 1.0))
    if geo is None and keep.any():
        ax.autoscale_view()
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(False)
    has_dry = bool((cr["class"] == "dry").any()) or isinstance(run.summary.get("joint_record"), dict)
    what = "broken elements and dry-joint events" if has_dry else "broken elements"
    title = f"{run.name}: {what} at t = {time:.4g} s"
    if displacement is not None:
        title += f" (control displacement {displacement * 1e3:.3g} mm)"
    if scale != 1.0 and geo is not None:
        title += f", displacements x{scale:g}"
    ax.set_title(title, fontsize=9)
    n_broken = sum(v for k, v in counts.items() if k.startswith(("unit_", "interface_")))
    n_open, n_slip = counts["dry_open"], counts["dry_slip"]
    heading = ([f"{n_broken} broken elements"] if n_broken else []) + \
              ([f"dry joints opened: {n_open}, slipped: {n_slip}"] if n_open + n_slip else [])
    if joint_counts.get("joint_open", 0) + joint_counts.get("joint_slip", 0):
        heading.append(f"unbroken joints wider than {joint_width * 1e3:.3g} mm at this time")
    handles, _ = ax.get_legend_handles_labels()
    if geo is not None and crushed_patches:
        handles += crushed_patches
        heading.append(f"crushing blocks: {counts['crushing']} triangles softening, {counts['crushed']} crushed")
    if heading:
        ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, title="\n".join(heading),
                  title_fontsize=8)
    else:
        ax.text(0.5, 0.02, f"no {what.replace(' and ', ' or ')} at this time", transform=ax.transAxes, ha="center",
                fontsize=9)
    from .figures import run_stamp
    files = save(fig, prefix, run_stamp([run.summary]))
    return files, {"time": time, "snapshot": snap[1] if snap else None, "counts": counts,
                   "matched_reference_midpoints": matched if keep.any() else None}


# Crushing of the triangles of a [materials.NAME.crushing] table (the VTU cell array block_crushing = kappa / kappa_u,
# fdem/plasticity.hpp): triangles past the peak of the compressive law shaded light red, those with no strength left
# dark red (the M-DEM paper's way of showing crushed regions, seeds/000 Fig. 3).
CRUSH_STARTED = 1e-9
CRUSH_COLOURS = {"softening": "#f4a6a6", "crushed": "#b01818"}


def _draw_crushing(ax, geo) -> list:
    """Shades the crushing triangles; returns legend patches (empty when none crush)."""
    c = geo["crushing"]
    if c is None:
        return []
    from matplotlib.patches import Patch
    x = geo["x"]
    patches = []
    for name, sel in (("softening", (c > CRUSH_STARTED) & (c < 1.0)), ("crushed", c >= 1.0)):
        n = int(np.sum(sel))
        if not n:
            continue
        from matplotlib.collections import PolyCollection
        ax.add_collection(PolyCollection(x[geo["tri"][sel]], facecolors=CRUSH_COLOURS[name], edgecolors="none",
                                         zorder=1.5))
        label = ("crushing (past the compressive peak)" if name == "softening" else "crushed (no strength left)")
        patches.append(Patch(facecolor=CRUSH_COLOURS[name], label=f"{label} ({n})"))
    return patches


# Joints that do not break (the Mohr-Coulomb layers of law = "mohr_coulomb" never hand over to contact) show their
# cracks as the opening and slip of their line cells in the snapshot: with --joint-width W the cohesive elements that
# are not broken and open or slip by more than W are drawn (in the colours of modes I and II), the M-DEM paper's way
# of showing cracks (seeds/000 Fig. 3: widths > 0.5 mm). Opened wins where both hold.
JOINT_WIDTH_STYLE = {"joint_slip": {"color": MODE_COLOURS["II"], "lw": 2.2, "name": "joint slipped"},
                     "joint_open": {"color": MODE_COLOURS["I"], "lw": 2.2, "name": "joint opened"}}


def _draw_joint_widths(ax, geo, width: float) -> dict:
    j = geo["joints"]
    counts = {"joint_open": 0, "joint_slip": 0}
    if j is None:
        return counts
    from matplotlib.collections import LineCollection
    intact = j["state"] != 2
    opened = intact & (np.nan_to_num(j["opening"]) > width)
    slipped = intact & (np.abs(np.nan_to_num(j["slip"])) > width) & ~opened
    for key, sel in (("joint_open", opened), ("joint_slip", slipped)):
        n = int(np.sum(sel))
        counts[key] = n
        if n:
            st = JOINT_WIDTH_STYLE[key]
            ax.add_collection(LineCollection(geo["x"][j["nodes"][sel]], colors=st["color"], linewidths=st["lw"],
                                             zorder=2.8, label=f"{st['name']} > {width * 1e3:.3g} mm ({n})"))
    return counts


def _threshold_text(run, key: str) -> str:
    """' > 0.1 mm' from summary.json's joint_record, or '' when the run does not state its threshold."""
    rec = run.summary.get("joint_record")
    v = rec.get(key) if isinstance(rec, dict) else None
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v) or v <= 0:
        return ""
    return f" > {v * 1e3:.3g} mm"


def default_name(time: float | None, displacement_mm: float | None) -> str:
    """RUN/post/<name> of a crack map: cracks_t<T>s at a time, cracks_d<D>mm at a displacement, cracks at the end of
    the run, so maps at different moments do not overwrite each other."""
    if time is not None:
        return f"cracks_t{time:g}s"
    if displacement_mm is not None:
        return f"cracks_d{displacement_mm:g}mm"
    return "cracks"


def cmd_cracks(args):
    prefix = args.out or os.path.join(args.run, "post", default_name(args.time, args.displacement))
    disp = args.displacement * 1e-3 if args.displacement is not None else None
    if args.joint_width is not None and not (args.joint_width > 0):
        raise ToolError(f"--joint-width: expected a width > 0 in mm, got {args.joint_width:g}")
    width = args.joint_width * 1e-3 if args.joint_width is not None else None
    files, info = draw(args.run, prefix, time=args.time, displacement=disp, scale=args.scale, partial=args.partial,
                       joint_width=width)
    c = info["counts"]
    print(f"t = {info['time']:.6g} s, snapshot {info['snapshot'] or 'none (markers at reference midpoints)'}: "
          + ", ".join(f"{k} {v}" for k, v in c.items()))
    print("wrote " + ", ".join(files))


def add_parser(sub):
    p = sub.add_parser("cracks", help="crack-pattern image at a chosen time",
                       description="Crack-pattern image: deformed unit outlines and broken cohesive elements coloured "
                                   "by mode (tension, shear, mixed); unit-interior cracks solid, interface cracks "
                                   "dashed. Dry-joint events (class interface-dry) are drawn underneath: openings "
                                   "beyond output.joint_open thick orange, slips beyond output.joint_slip thin green, "
                                   "counted apart. Uses cracks.csv and the .vtu snapshot at or before the chosen time. "
                                   "Prints the counts: unit_I ... interface_mixed (broken elements), dry_open, "
                                   "dry_slip (dry-joint segments); with --joint-width, joint_open and joint_slip "
                                   "(unbroken cohesive elements wider than it); with crushing blocks, crushing and "
                                   "crushed (triangles past the compressive peak, and with no strength left: shaded "
                                   "light and dark red).")
    p.add_argument("run", metavar="RUN", help="fdem run folder")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--time", type=float, help="time in s (default: the last snapshot)")
    g.add_argument("--displacement", type=float, help="control displacement in mm (the first time it is reached)")
    p.add_argument("--scale", type=float, default=1.0, help="displacement magnification of the drawing (default 1)")
    p.add_argument("--partial", action="store_true", help="accept a run whose summary is not 'completed'")
    p.add_argument("--joint-width", type=float, metavar="MM",
                   help="also draw the cohesive elements that are not broken but open (the colour of mode I) or slip (of "
                        "mode II) by more than MM mm in the snapshot: the cracks of joints that never break (law = \"mohr_coulomb\"; "
                        "the M-DEM paper draws widths > 0.5 mm)")
    p.add_argument("-o", "--out", help="output prefix: writes PREFIX.png and PREFIX.svg (default RUN/post/cracks_tTs "
                                       "with --time T, RUN/post/cracks_dDmm with --displacement D, else "
                                       "RUN/post/cracks: maps at different moments do not overwrite each other)")
    p.set_defaults(func=cmd_cracks)
