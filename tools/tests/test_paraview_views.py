"""tools/paraview/fdem_views.py, the pvpython script of the standard views. ParaView is not a dependency of fdem, so
the script runs here against a stand-in paraview.simple that records the pipeline, on a real run folder: every array
the script reads exists in the run's snapshots and contact files (VTK's own reader), the views are built at the
requested snapshot, and bad arguments are refused."""
import importlib.util
import os
import re
import sys

import pytest

vtk = pytest.importorskip("vtk")

import test_vtu_output as vo  # noqa: E402  (the two-block run of the VTU tests)

SCRIPT = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "paraview", "fdem_views.py")
pytestmark = pytest.mark.skipif(not os.access(vo._fdem(), os.X_OK), reason="no fdem executable")


def _load():
    spec = importlib.util.spec_from_file_location("fdem_views", SCRIPT)
    m = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(m)
    return m


class _Proxy:
    def __init__(self, kind, **kw):
        self.kind, self.kw = kind, kw
        for k, v in kw.items():
            setattr(self, k, v)

    def SetScalarBarVisibility(self, view, on):
        self.bar = on


class FakeParaView:
    """Records what the script asks of paraview.simple."""

    def __init__(self, times):
        self.times, self.calls, self.shots = times, [], []

    def _make(self, kind, **kw):
        p = _Proxy(kind, **kw)
        self.calls.append(p)
        return p

    def PVDReader(self, FileName):
        p = self._make("PVDReader", FileName=FileName)
        p.TimestepValues = self.times
        return p

    def __getattr__(self, name):
        if name in ("WarpByVector", "Threshold", "Glyph", "CreateRenderView", "Show"):
            return lambda *a, **kw: self._make(name, **kw)
        raise AttributeError(name)

    def ColorBy(self, display, array):
        display.colour = array

    def ResetCamera(self, view):
        pass

    def Render(self):
        pass

    def SaveScreenshot(self, path, view, ImageResolution):
        self.shots.append((os.path.basename(path), view.ViewTime, tuple(ImageResolution)))


def _arrays(path):
    g = vo._read(path)
    pd, cd = g.GetPointData(), g.GetCellData()
    return ({pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays())},
            {cd.GetArrayName(i) for i in range(cd.GetNumberOfArrays())})


def test_views_read_only_arrays_the_run_writes_and_save_four_views(tmp_path):
    run = vo._run_blocks(tmp_path, vo.DRY)[0]
    m = _load()
    files = vo._pvd_files(run)
    points, cells = _arrays(run / files[-1])
    for name in m.FIELDS["points"]:
        assert name in points
    for name in m.FIELDS["cells"]:
        assert name in cells
    contact_points, _ = _arrays(run / files[-1].replace("/step_", "/contacts_"))
    for name in m.FIELDS["contacts"]:
        assert name in contact_points
    times = [float(t) for t in re.findall(r'timestep="([^"]+)"', (run / "run.pvd").read_text())]
    pv = FakeParaView(times)
    out = tmp_path / "views"
    m.main([str(run), "--out", str(out), "--time", str(times[0] * 1.01), "--scale", "50", "--size", "800", "600"], pv=pv)
    assert [s[0] for s in pv.shots] == ["view_deformed.png", "view_cracks.png", "view_joint_stress.png",
                                        "view_contacts.png"]
    assert all(s[1] == times[0] and s[2] == (800, 600) for s in pv.shots)
    warp = next(c for c in pv.calls if c.kind == "WarpByVector")
    assert warp.Vectors == ["POINTS", "displacement"] and warp.ScaleFactor == 50
    coloured = [c.colour for c in pv.calls if c.kind == "Show" and hasattr(c, "colour")]
    assert ("CELLS", "von_mises") in coloured and ("CELLS", "joint_damage") in coloured
    assert ("CELLS", "joint_normal_stress") in coloured and ("POINTS", "normal_force") in coloured
    # every array the pipeline names is one the run wrote
    named = set()
    for c in pv.calls:
        for v in c.kw.values():
            if isinstance(v, list) and len(v) == 2 and v[0] in ("POINTS", "CELLS"):
                named.add(v[1])
    named |= {c.colour[1] for c in pv.calls if hasattr(c, "colour")}
    assert named <= points | cells | contact_points


def test_latest_snapshot_by_default_and_bad_arguments(tmp_path, capsys):
    m = _load()
    assert m.nearest_time([0.1, 0.2, 0.3], None) == 0.3
    assert m.nearest_time([0.1, 0.2, 0.3], 0.19) == 0.2
    assert m.nearest_time([], 1.0) is None
    with pytest.raises(SystemExit):
        m.main([str(tmp_path)], pv=FakeParaView([]))  # no run.pvd
    assert "no run.pvd" in capsys.readouterr().err
    (tmp_path / "run.pvd").write_text("<VTKFile/>")
    with pytest.raises(SystemExit):
        m.main([str(tmp_path), "--scale", "0"], pv=FakeParaView([]))
    assert "--scale" in capsys.readouterr().err
