"""fdem's VTU files as ParaView reads them, through VTK's own XML reader (Debian python3-vtk9): stress component
names, von Mises and principal stresses, region and material names in FieldData, one meaning of cell_kind in
mesh.vtu and the snapshots, and a rerun into the same folder that leaves only its own snapshots."""
import math
import os
import re
import subprocess

import numpy as np

import pytest

vtk = pytest.importorskip("vtk")
from vtk.util.numpy_support import vtk_to_numpy  # noqa: E402


def _fdem():
    return os.environ.get("FDEM_BIN") or os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
        os.path.abspath(__file__)))), "build", "fdem", "fdem")


pytestmark = pytest.mark.skipif(not os.access(_fdem(), os.X_OK), reason="no fdem executable (FDEM_BIN or build/fdem/fdem)")

# Two stacked 1 x 1 m blocks of two materials with a dry joint between them (fragmented: conforming nodes).
GEO = """SetFactory("OpenCASCADE");
Rectangle(1) = {0, 0, 0, 1, 1};
Rectangle(2) = {0, 1, 0, 1, 1};
BooleanFragments{ Surface{1, 2}; Delete; }{}
MeshSize{ PointsOf{ Surface{:}; } } = 0.25;
Physical Surface("lower") = {1};
Physical Surface("upper") = {2};
Physical Curve("lower_bottom") = Curve In BoundingBox{-0.01, -0.01, -1, 1.01, 0.01, 1};
Physical Curve("upper_top") = Curve In BoundingBox{-0.01, 1.99, -1, 1.01, 2.01, 1};
"""

CASE = """[case]
name = "two_blocks"
thickness = 0.1
plane = "stress"
[geometry]
type = "gmsh"
file = "blocks.geo"
[materials.stone]
E = 1.0e9
nu = 0.2
density = 2000.0
[materials.brick]
E = 5.0e8
nu = 0.25
density = 1800.0
[regions]
lower = "stone"
upper = "brick"
[[interfaces]]
regions = ["lower", "upper"]
kind = "dry"
friction = 30.0
normal_stiffness = 1e10
[output]
snapshot_interval = {interval}
[[stages]]
name = "press"
duration = 0.005
  [[stages.supports]]
  group = "lower_bottom"
  fix = "xy"
  [[stages.loads]]
  group = "upper_top"
  force = [2000.0, -20000.0]
  ramp = 0.002
"""


def _write_case(d, interval):
    (d / "blocks.geo").write_text(GEO)
    p = d / "case.toml"
    p.write_text(CASE.replace("{interval}", repr(interval)))
    return p


def _fdem_run(*args, cwd):
    r = subprocess.run([_fdem(), *map(str, args)], capture_output=True, text=True, cwd=cwd, timeout=300,
                       env=dict(os.environ, OMP_WAIT_POLICY="passive"))
    assert r.returncode == 0, r.stderr + r.stdout
    return r


def _read(path):
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    grid = reader.GetOutput()
    assert grid.GetNumberOfCells() > 0, path
    return grid


def _strings(grid, name):
    a = grid.GetFieldData().GetAbstractArray(name)
    assert a is not None, f"no FieldData array {name}"
    return [a.GetValue(i) for i in range(a.GetNumberOfValues())]


def _pvd_files(run):
    return re.findall(r'file="([^"]+)"', (run / "run.pvd").read_text())


def test_snapshot_fields_names_and_cell_kind(tmp_path):
    case = _write_case(tmp_path, 0.001)
    run = tmp_path / "run"
    _fdem_run("run", case, "--quiet", "--threads", "1", "--out", run, cwd=tmp_path)
    files = _pvd_files(run)
    assert len(files) >= 4
    grid = _read(run / files[-1])
    cd = grid.GetCellData()

    # stress: three named components, so ParaView shows sxx / syy / sxy instead of X / Y / Z.
    stress = cd.GetArray("stress")
    assert stress.GetNumberOfComponents() == 3
    assert [stress.GetComponentName(i) for i in range(3)] == ["sxx", "syy", "sxy"]
    assert [grid.GetPointData().GetArray("displacement").GetComponentName(i) for i in range(2)] == ["ux", "uy"]
    principal = cd.GetArray("principal_stress")
    assert principal.GetNumberOfComponents() == 2
    assert [principal.GetComponentName(i) for i in range(2)] == ["s1", "s2"]

    # Von Mises and principal stresses against the stress tensor, cell by cell (plane stress: s_zz = 0).
    kind = vtk_to_numpy(cd.GetArray("cell_kind"))
    s = vtk_to_numpy(stress)
    vm = vtk_to_numpy(cd.GetArray("von_mises"))
    p = vtk_to_numpy(principal)
    tri = kind == 0
    assert tri.sum() > 0
    loaded = 0
    for (sxx, syy, sxy), v, (s1, s2) in zip(s[tri], vm[tri], p[tri]):
        scale = abs(sxx) + abs(syy) + abs(sxy)
        loaded += scale > 1e3
        assert v == pytest.approx(math.sqrt(sxx * sxx - sxx * syy + syy * syy + 3 * sxy * sxy), rel=1e-12, abs=1e-9 * scale)
        assert s1 >= s2
        assert s1 + s2 == pytest.approx(sxx + syy, rel=1e-12, abs=1e-9 * scale)
        assert s1 * s2 == pytest.approx(sxx * syy - sxy * sxy, rel=1e-9, abs=1e-9 * scale * scale)
    assert loaded > 0.5 * tri.sum()  # the load reached most triangles: the checks above compared real stresses

    # Region and material names: the ids of the cell arrays index them.
    regions = _strings(grid, "region_names")
    materials = _strings(grid, "material_names")
    assert sorted(regions) == ["lower", "upper"] and sorted(materials) == ["brick", "stone"]
    region = vtk_to_numpy(cd.GetArray("region"))
    material = vtk_to_numpy(cd.GetArray("material"))
    assert set(region[tri]) == {0, 1}
    # Through the names, every triangle's region has the case's material: lower = stone, upper = brick.
    case_material = {"lower": "stone", "upper": "brick"}
    for r, m in zip(region[tri], material[tri]):
        assert materials[m] == case_material[regions[r]]

    # cell_kind in the snapshot: triangles 0, dry joint segments 2 (no cohesive elements in this case).
    assert set(kind) == {0, 2}
    n_dry = int((kind == 2).sum())
    assert n_dry >= 4  # the 1 m joint at mesh size 0.25 m

    # The same codes in mesh.vtu: the same triangles and the same dry joint segments; other edges are 3.
    _fdem_run("mesh", case, "--out", tmp_path / "mesh", cwd=tmp_path)
    mesh = _read(tmp_path / "mesh" / "mesh.vtu")
    mkind = vtk_to_numpy(mesh.GetCellData().GetArray("cell_kind"))
    assert set(mkind) == {0, 2, 3}
    assert int((mkind == 0).sum()) == int(tri.sum())
    assert int((mkind == 2).sum()) == n_dry
    assert _strings(mesh, "region_names") == regions
    assert _strings(mesh, "cell_kind_names") == ["triangle", "cohesive element", "dry joint", "other edge"]
    assert _strings(mesh, "edge_class_names") == ["interior", "crackable", "bonded", "dry", "free_boundary"]


def test_rerun_into_the_same_folder_keeps_only_its_own_snapshots(tmp_path):
    run = tmp_path / "run"
    _fdem_run("run", _write_case(tmp_path, 0.0005), "--quiet", "--threads", "1", "--out", run, cwd=tmp_path)
    first = _pvd_files(run)
    assert len(first) >= 8
    (run / "snapshots" / "my_notes.txt").write_text("kept")  # not a snapshot: left alone
    _fdem_run("run", _write_case(tmp_path, 0.002), "--quiet", "--threads", "1", "--out", run, cwd=tmp_path)
    second = _pvd_files(run)
    assert 2 <= len(second) < len(first)
    on_disk = sorted("snapshots/" + f for f in os.listdir(run / "snapshots") if f.startswith("step_") and f.endswith(".vtu"))
    assert on_disk == sorted(second)
    # the contact files beside them: one per snapshot, listed in contacts.pvd, none of the first run's left
    contacts = sorted("snapshots/" + f for f in os.listdir(run / "snapshots") if f.startswith("contacts_"))
    assert contacts == sorted(f.replace("/step_", "/contacts_") for f in second)
    assert sorted(re.findall(r'file="([^"]+)"', (run / "contacts.pvd").read_text())) == contacts
    assert (run / "snapshots" / "my_notes.txt").read_text() == "kept"


def test_snapshots_carry_their_time(tmp_path):
    """Each snapshot holds its time as FieldData TimeValue (ParaView's dataset time), equal to run.pvd's timestep."""
    case = _write_case(tmp_path, 0.001)
    run = tmp_path / "run"
    _fdem_run("run", case, "--quiet", "--threads", "1", "--out", run, cwd=tmp_path)
    pvd = (run / "run.pvd").read_text()
    pairs = re.findall(r'timestep="([^"]+)"[^>]*file="([^"]+)"', pvd)
    assert len(pairs) >= 4
    for t, f in pairs:
        grid = _read(run / f)
        a = grid.GetFieldData().GetArray("TimeValue")
        assert a is not None and a.GetNumberOfTuples() == 1, f
        assert a.GetValue(0) == pytest.approx(float(t), rel=1e-12, abs=1e-15)
    # the reader reports it as the dataset's time too
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(run / pairs[-1][1]))
    reader.UpdateInformation()
    reader.Update()
    assert reader.GetOutput().GetFieldData().GetArray("TimeValue").GetValue(0) > 0


BONDED_JOINT = """kind = "bonded"
tensile_strength = 1.0e7
cohesion = 1.0e7
friction = 30.0
residual_friction = 30.0
GI = 1000.0
GII = 1000.0
penalty = 1.0e11"""

BONDED = """[case]
name = "bonded_blocks"
thickness = 0.1
plane = "stress"
[geometry]
type = "gmsh"
file = "blocks.geo"
[materials.stone]
E = 1.0e9
nu = 0.2
density = 2000.0
[regions]
lower = "stone"
upper = "stone"
[[interfaces]]
regions = ["lower", "upper"]
{joint}
[output]
snapshot_interval = 10.0
[[stages]]
name = "press"
equilibrium = 1e-5
max_duration = 2.0
local_damping = 0.8
  [[stages.supports]]
  group = "lower_bottom"
  fix = "xy"
  [[stages.loads]]
  group = "upper_top"
  force = [2000.0, -20000.0]
  ramp = 0.002
""".replace("{joint}", BONDED_JOINT)


def _run_blocks(tmp_path, case_text):
    """Runs the two blocks with this case: the run folder, its snapshots, the last one's grid and its cell_kind,
    joint_normal_stress and joint_shear_stress."""
    (tmp_path / "blocks.geo").write_text(GEO)
    case = tmp_path / "case.toml"
    case.write_text(case_text)
    run = tmp_path / "run"
    _fdem_run("run", case, "--quiet", "--threads", "1", "--out", run, cwd=tmp_path)
    files = _pvd_files(run)
    grid = _read(run / files[-1])
    cd = grid.GetCellData()
    return (run, files, grid, vtk_to_numpy(cd.GetArray("cell_kind")), vtk_to_numpy(cd.GetArray("joint_normal_stress")),
            vtk_to_numpy(cd.GetArray("joint_shear_stress")))


def _joint_forces(grid, cells, sn, ss, thickness=0.1):
    """The normal and shear force (N) of the line cells selected: their stresses times their current length and
    the thickness, summed."""
    cur = vtk_to_numpy(grid.GetPoints().GetData()) + vtk_to_numpy(grid.GetPointData().GetArray("displacement"))
    N = T = 0.0
    for c in np.nonzero(cells)[0]:
        ids = grid.GetCell(int(c)).GetPointIds()
        a, b = cur[ids.GetId(0)], cur[ids.GetId(1)]
        length = float(np.hypot(*(b - a)[:2]))
        N += sn[c] * length * thickness
        T += ss[c] * length * thickness
    return N, T


def test_joint_tractions_and_principal_directions(tmp_path):
    """A bonded joint carries the load on the block above it: the sum of joint_normal_stress x length x thickness over
    its elements is the applied vertical load, that of joint_shear_stress the horizontal one (1 %); each triangle's
    principal_direction is the unit vector at atan2(2 sxy, sxx - syy) / 2, and an eigenvector of its stress."""
    run, files, grid, kind, sn, ss = _run_blocks(tmp_path, BONDED)
    cd = grid.GetCellData()
    joint = kind == 1
    assert joint.sum() >= 4
    assert np.isnan(sn[kind == 0]).all() and np.isnan(ss[kind == 0]).all()
    N, T = _joint_forces(grid, joint, sn, ss)
    assert N == pytest.approx(-20000.0, rel=0.01)   # compression: the load on the block above
    assert abs(T) == pytest.approx(2000.0, rel=0.01)  # the horizontal load, along the joint
    s = vtk_to_numpy(cd.GetArray("stress"))
    pdir = vtk_to_numpy(cd.GetArray("principal_direction"))
    p = vtk_to_numpy(cd.GetArray("principal_stress"))
    assert np.isnan(pdir[joint]).all()
    for (sxx, syy, sxy), (nx, ny, nz), (s1, _) in zip(s[kind == 0], pdir[kind == 0], p[kind == 0]):
        assert nx * nx + ny * ny == pytest.approx(1.0, rel=1e-12) and nz == 0
        scale = abs(sxx) + abs(syy) + abs(sxy)
        # (sigma - s1 I) n = 0
        assert (sxx - s1) * nx + sxy * ny == pytest.approx(0.0, abs=1e-9 * scale)
        assert sxy * nx + (syy - s1) * ny == pytest.approx(0.0, abs=1e-9 * scale)


DRY = BONDED.replace(BONDED_JOINT, """kind = "dry"
friction = 30.0
normal_stiffness = 1.0e10""").replace('name = "bonded_blocks"', 'name = "dry_blocks"')


def test_dry_joint_stresses_and_contact_forces(tmp_path):
    """A dry joint at rest under the load of the block above: its segments' joint_normal_stress x length x thickness
    sum to the applied vertical load and joint_shear_stress to the horizontal one (1 %; the joint sticks: 2 kN is
    below tan 30 deg x 20 kN). The contact file beside the snapshot (contacts_N.vtu, one point per loaded face at its
    centre of pressure): the forces of the faces between the blocks add up to the force the lower block exerts on the
    upper one, the reaction to the load (1 %); each face's force is -normal_force n + shear_force t, its
    normal_stress -normal_force / (length thickness); the file carries the snapshot's time."""
    run, files, grid, kind, sn, ss = _run_blocks(tmp_path, DRY)
    cd = grid.GetCellData()
    dry = kind == 2
    assert dry.sum() >= 4
    assert np.isnan(sn[kind == 0]).all()
    N, T = _joint_forces(grid, dry, sn, ss)
    assert N == pytest.approx(-20000.0, rel=0.01)
    assert abs(T) == pytest.approx(2000.0, rel=0.01)

    contacts = files[-1].replace("/step_", "/contacts_")
    assert re.findall(r'file="([^"]+)"', (run / "contacts.pvd").read_text())[-1] == contacts
    faces = _read(run / contacts)
    pd = faces.GetPointData()
    get = lambda name: vtk_to_numpy(pd.GetArray(name))  # noqa: E731
    force, normal, fn, ft = get("force"), get("normal"), get("normal_force"), get("shear_force")
    unit, other = get("unit"), get("other_unit")
    tangent = np.stack([-normal[:, 1], normal[:, 0]], axis=1)
    assert np.allclose(force[:, :2], -fn[:, None] * normal[:, :2] + ft[:, None] * tangent, rtol=0, atol=1e-9 * abs(fn).max())
    assert np.allclose(get("normal_stress"), -fn / (get("length") * 0.1), rtol=1e-12)
    assert (fn >= 0).all()
    # every face between the blocks has unit != other_unit; the upper block's unit from the snapshot's cells
    between = unit != other
    assert between.sum() >= 4
    names = _strings(grid, "region_names")
    assert names.index("upper") >= 0
    region = vtk_to_numpy(cd.GetArray("region"))
    body = vtk_to_numpy(cd.GetArray("unit"))
    upper = int(body[(kind == 0) & (region == names.index("upper"))][0])
    on_upper = force[between & (unit == upper), :2].sum(axis=0) - force[between & (other == upper), :2].sum(axis=0)
    assert on_upper[1] == pytest.approx(20000.0, rel=0.01)
    assert on_upper[0] == pytest.approx(-2000.0, rel=0.01)
    assert faces.GetFieldData().GetArray("TimeValue").GetValue(0) == pytest.approx(
        grid.GetFieldData().GetArray("TimeValue").GetValue(0), rel=1e-12)
