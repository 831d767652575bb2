"""The standard views of an fdem run in ParaView: deformed mesh, cracks, joint stresses, contact forces.

Run with ParaView's Python (pvpython ships with ParaView; it is not a Debian dependency of fdem):

    pvpython tools/paraview/fdem_views.py RUN_DIR [--out DIR] [--time T] [--scale S] [--size W H]

writes DIR/view_deformed.png (the mesh warped by S x the displacement, coloured by von Mises stress),
view_cracks.png (the joint and crack cells coloured by damage: cohesive 0 intact .. 1 broken; dry joints by state),
view_joint_stress.png (the joints' normal stress, tension positive) and, when the run wrote contact files,
view_contacts.png (arrows of the contact forces, the force chains and thrust lines), at the snapshot nearest to T
(default: the last). Without --out the pipeline is built in the running ParaView session (Python Shell > Run
Script, with RUN_DIR set in the dialog's arguments) and nothing is written. The arrays read are those of
fdem/README.md, "The run folder".
"""
import argparse
import os
import sys

# The run folder's arrays this script reads (checked against a real run by tools/tests/test_paraview_views.py).
FIELDS = {
    "points": ["displacement"],
    "cells": ["von_mises", "cell_kind", "joint_damage", "joint_state", "joint_normal_stress"],
    "contacts": ["force", "normal_force"],
}
CELL_KIND_TRIANGLE = 0  # cell_kind: 0 triangle, 1 cohesive element, 2 dry joint


def parse(argv):
    p = argparse.ArgumentParser(prog="fdem_views.py", description=__doc__.split("\n\n")[0])
    p.add_argument("run", help="an fdem run folder (with run.pvd)")
    p.add_argument("--out", help="write the PNG views into this folder (default: build the pipeline only)")
    p.add_argument("--time", type=float, help="the snapshot nearest to this time, s (default: the last)")
    p.add_argument("--scale", type=float, default=1.0, help="displacement magnification of the deformed views")
    p.add_argument("--size", type=int, nargs=2, default=[1600, 900], metavar=("W", "H"), help="image size, px")
    a = p.parse_args(argv)
    if not os.path.isfile(os.path.join(a.run, "run.pvd")):
        p.error(f"{a.run}: no run.pvd (not an fdem run folder, or a run that wrote no snapshot)")
    if a.scale <= 0:
        p.error(f"--scale {a.scale}: expected a factor > 0")
    return a


def nearest_time(times, t):
    """The snapshot time nearest to t (the last one when t is None)."""
    if not times:
        return None
    if t is None:
        return times[-1]
    return min(times, key=lambda x: abs(x - t))


def build(pv, a):
    """Builds the views with the paraview.simple module pv; returns [(name, view)] to save."""
    snaps = pv.PVDReader(FileName=os.path.join(a.run, "run.pvd"))
    times = list(getattr(snaps, "TimestepValues", []) or [])
    t = nearest_time(times, a.time)
    warped = pv.WarpByVector(Input=snaps, Vectors=["POINTS", FIELDS["points"][0]], ScaleFactor=a.scale)
    triangles = pv.Threshold(Input=warped, Scalars=["CELLS", "cell_kind"], LowerThreshold=CELL_KIND_TRIANGLE,
                             UpperThreshold=CELL_KIND_TRIANGLE)
    joints = pv.Threshold(Input=warped, Scalars=["CELLS", "cell_kind"], LowerThreshold=CELL_KIND_TRIANGLE + 1,
                          UpperThreshold=2)
    views = []

    def view(name, sources):
        v = pv.CreateRenderView()
        v.ViewSize = list(a.size)
        v.OrientationAxesVisibility = 0
        if t is not None:
            v.ViewTime = t
        shown = []
        for src, array, lines in sources:
            d = pv.Show(src, v)
            if lines:
                d.LineWidth = 3.0
            if array:
                pv.ColorBy(d, array)
                d.SetScalarBarVisibility(v, True)
            else:
                d.DiffuseColor = [0.8, 0.8, 0.8]
            shown.append(d)
        v.InteractionMode = "2D"
        pv.ResetCamera(v)
        views.append((name, v))
        return shown

    view("deformed", [(triangles, ("CELLS", "von_mises"), False)])
    view("cracks", [(triangles, None, False), (joints, ("CELLS", "joint_damage"), True)])
    view("joint_stress", [(triangles, None, False), (joints, ("CELLS", "joint_normal_stress"), True)])
    contacts = os.path.join(a.run, "contacts.pvd")
    if os.path.isfile(contacts):
        forces = pv.PVDReader(FileName=contacts)
        arrows = pv.Glyph(Input=forces, GlyphType="Arrow", OrientationArray=["POINTS", "force"],
                          ScaleArray=["POINTS", "normal_force"], GlyphMode="All Points")
        view("contacts", [(triangles, None, False), (arrows, ("POINTS", "normal_force"), False)])
    return views


def main(argv=None, pv=None):
    a = parse(sys.argv[1:] if argv is None else argv)
    if pv is None:
        try:
            from paraview import simple as pv  # noqa: F811 (ParaView's own Python)
        except ImportError:
            sys.exit("fdem_views.py: run it with ParaView's pvpython (paraview.simple is not importable here)")
    views = build(pv, a)
    if a.out:
        os.makedirs(a.out, exist_ok=True)
        for name, v in views:
            path = os.path.join(a.out, f"view_{name}.png")
            pv.SaveScreenshot(path, v, ImageResolution=list(a.size))
            print(path)
    else:
        pv.Render()
    return views


if __name__ == "__main__":
    main()
