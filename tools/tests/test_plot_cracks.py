import os

import numpy as np
import pytest

from synth import make_run, two_blocks, write_vtu
from fdemtools import cracks, vtk


def test_vtu_reader_round_trip(tmp_path):
    X, tri, unit = two_blocks()
    disp = np.column_stack((X[:, 1] * 0.01, -X[:, 0] * 0.02))
    p = tmp_path / "a.vtu"
    write_vtu(p, X, tri, disp, {"region": unit})
    v = vtk.read_vtu(str(p))
    assert np.array_equal(v["points"][:, :2], X)
    assert np.array_equal(v["point_data"]["displacement"][:, :2], disp)
    sel, t = vtk.triangles(v)
    assert np.array_equal(t, tri) and np.array_equal(v["cell_data"]["region"], unit)


def test_outline_edges_of_two_blocks(tmp_path):
    X, tri, unit = two_blocks()
    p = tmp_path / "a.vtu"
    write_vtu(p, X, tri, np.zeros_like(X), {"region": unit})
    g = cracks.geometry(vtk.read_vtu(str(p)))
    o = g["outline"]
    # outer boundary: 2*(4+4) edges of 0.05 m = 16 edges (joint excluded), plus the joint drawn from both sides: 2*4
    lengths = np.linalg.norm(X[o[:, 0]] - X[o[:, 1]], axis=1)
    assert len(o) == 16 + 8
    assert np.allclose(lengths, 0.05)


def test_cracks_counts_and_files(tmp_path, cli):
    run = make_run(str(tmp_path / "run"))
    rc, out, err = cli("cracks", run, "--time", "0.65")
    assert rc == 0, err
    for ext in ("png", "svg"):  # named by the moment (issue 51, 13: every map was post/cracks.png)
        assert os.path.getsize(os.path.join(run, "post", f"cracks_t0.65s.{ext}")) > 2000
    rc, out, err = cli("cracks", run, "--displacement", "9.9")
    assert rc == 0, err
    rc, out, err = cli("cracks", run)
    assert rc == 0, err
    for name in ("cracks_t0.65s", "cracks_d9.9mm", "cracks"):  # three maps, none overwritten
        assert os.path.getsize(os.path.join(run, "post", f"{name}.png")) > 2000
    assert "3 broken elements" in open(os.path.join(run, "post", "cracks_t0.65s.svg")).read()
    files, info = cracks.draw(run, str(tmp_path / "c"), time=0.65)
    c = info["counts"]
    assert (c["interface_I"], c["interface_II"], c["unit_mixed"], c["unit_I"], c["unit_II"]) == (1, 1, 1, 0, 0)
    assert info["snapshot"].endswith("snap_0001.vtu")  # last snapshot at or before t = 0.65 s
    files, info = cracks.draw(run, str(tmp_path / "d"), displacement=9.9e-3)
    assert sum(info["counts"].values()) == 5


def test_cracks_without_snapshots_and_bad_input(tmp_path, cli):
    run = make_run(str(tmp_path / "run"), snapshots=False)
    files, info = cracks.draw(run, str(tmp_path / "c"))
    assert info["snapshot"] is None and sum(info["counts"].values()) == 5
    nofrac = make_run(str(tmp_path / "nf"), fracture=False)
    rc, out, err = cli("cracks", nofrac)
    assert rc == 1 and "no cracks.csv" in err and len(err.strip().splitlines()) == 1
    with open(os.path.join(run, "cracks.csv"), "a") as f:
        f.write("1.0,0.01,0.1,0.1,unit,0,0,III\n")
    rc, out, err = cli("cracks", run)
    assert rc == 1 and "unknown mode" in err


def test_plot_all_figures(tmp_path, cli):
    a = make_run(str(tmp_path / "a"), case="wall A")
    b = make_run(str(tmp_path / "b"), peak=50e3, case="wall B")
    exp = tmp_path / "exp.csv"
    u = np.linspace(0, 10, 30)
    exp.write_text("d_mm,H_kN\n" + "".join(f"{x},{40 * np.tanh(x / 2)}\n" for x in u))
    out = tmp_path / "figs"
    rc, o, err = cli("plot", a, b, "--experiment", exp, "--out-dir", out)
    assert rc == 0, err
    for name in ("curves", "energy_wall_A", "energy_wall_B", "damage_wall_A", "damage_wall_B"):
        for ext in ("png", "svg"):
            assert (out / f"{name}.{ext}").stat().st_size > 2000, name
    svg = (out / "curves.svg").read_text()
    assert "control displacement (mm)" in svg and "load (kN)" in svg and "wall B" in svg


def test_plot_bad_input(tmp_path, cli):
    a = make_run(str(tmp_path / "a"), status="running")
    rc, o, err = cli("plot", a)
    assert rc == 1 and "not 'completed'" in err and len(err.strip().splitlines()) == 1
    rc, o, err = cli("plot", a, "--partial", "--figures", "damage", "--out-dir", tmp_path / "o")
    assert rc == 0, err
    nf = make_run(str(tmp_path / "nf"), fracture=False)
    rc, o, err = cli("plot", nf, "--figures", "damage")
    assert rc == 1 and "fracture off" in err
    rc, o, err = cli("plot", nf)  # default set: the damage figure is skipped with a note
    assert rc == 0 and "no damage figure" in o


def test_run_curve_stage_selection_and_extra_columns(tmp_path):
    from fdemtools.common import load_curve
    run = make_run(str(tmp_path / "r"))  # has an unknown extra column, which must be tolerated
    c_all = load_curve(run)
    c2 = load_curve(run, stage=2)
    assert len(c2.x) < len(c_all.x) and c2.x[0] >= 1e-3 - 1e-15  # stage 2 starts at t = 0.1 s, u = 1 mm
    with pytest.raises(Exception, match="no rows of stage 5"):
        load_curve(run, stage=5)


def test_cracks_csv_of_the_fracture_module(tmp_path):
    """The fracture module writes unit-suffixed names and 'unit-interior'; both spellings are read."""
    run = make_run(str(tmp_path / "run"))
    with open(os.path.join(run, "cracks.csv"), "w") as f:
        f.write("time_s,control_displacement_m,x_m,y_m,class,unit_a,unit_b,mode,D_I,D_II,element,tri_a,tri_b\n")
        f.write("0.3,0.003,0.075,0.1,interface,0,1,I,1,0,5,1,9\n")
        f.write("0.6,0.006,0.075,0.05,unit-interior,0,0,mixed,0.7,1,2,3,4\n")
    cr = cracks.read_cracks(run)
    assert list(cr["class"]) == ["interface", "unit"] and list(cr["time"]) == [0.3, 0.6]
    files, info = cracks.draw(run, str(tmp_path / "c"))
    assert info["counts"]["interface_I"] == 1 and info["counts"]["unit_mixed"] == 1


def test_cracks_matched_in_the_deformed_configuration(tmp_path):
    """The upper block moves by a whole edge length (0.05 m): a crack recorded at its current midpoint at t = 1 s
    must be matched to the edge that is there at that time, not to the edge whose reference midpoint is there."""
    import json as _json
    run = tmp_path / "run"
    os.makedirs(run / "snapshots")
    X, tri, unit = two_blocks()
    for k, tk in enumerate((0.0, 1.0)):
        disp = np.zeros_like(X)
        disp[:, 0] = 0.05 * tk * (unit_nodes(X, tri, unit) == 1)
        write_vtu(str(run / "snapshots" / f"s{k}.vtu"), X, tri, disp, {"region": unit})
    (run / "run.pvd").write_text('<VTKFile type="Collection"><Collection>'
                                 '<DataSet timestep="0" file="snapshots/s0.vtu"/>'
                                 '<DataSet timestep="1" file="snapshots/s1.vtu"/></Collection></VTKFile>')
    (run / "summary.json").write_text(_json.dumps({"status": "completed", "case": "moved"}))
    (run / "cracks.csv").write_text("time,control_displacement,x,y,class,unit_a,unit_b,mode\n"
                                    "1.0,0.05,0.15,0.175,unit,1,1,I\n"    # vertical edge x = 0.1 (ref), moved to 0.15
                                    "0.0,0.0,0.1,0.025,unit,0,0,II\n")    # lower block, never moves
    files, info = cracks.draw(str(run), str(tmp_path / "c"))
    m = info["matched_reference_midpoints"]
    assert np.allclose(m[0], [0.1, 0.175]) and np.allclose(m[1], [0.1, 0.025])


def unit_nodes(X, tri, unit):
    """Unit of each node (nodes are not shared between the two blocks)."""
    u = np.zeros(len(X), int)
    for t, b in zip(tri, unit):
        u[t] = b
    return u


# ---- dry-joint rows (class interface-dry, modes open / slip) ---------------------------------------------------

FRACTURE_HEADER = "time_s,control_displacement_m,x_m,y_m,class,unit_a,unit_b,mode,D_I,D_II,element,tri_a,tri_b," \
                  "length_m,x_ref_m,y_ref_m\n"
# The joint of two_blocks() lies at y = 0.1 m with segments of 0.05 m; the upper block of make_run() moves in x by
# 2 mm per second, so a joint's current midpoint (mean of both sides) is about 1 mm per second right of reference.
DRY_ROWS = [  # the columns of FRACTURE_HEADER; element = the joint segment's index
    (0.2, 2e-3, 0.0252, 0.1, "interface-dry", 0, 1, "open", 1.3, 0.2, 0, 14, 16, 0.05, 0.025, 0.1),
    (0.4, 4e-3, 0.1754, 0.1, "interface-dry", 0, 1, "open", 1.1, 0.4, 3, 20, 22, 0.05, 0.175, 0.1),
    (0.45, 4.5e-3, 0.1754, 0.1, "interface-dry", 0, 1, "slip", 0.9, 1.2, 3, 20, 22, 0.05, 0.175, 0.1),
    (0.8, 8e-3, 0.1258, 0.1, "interface-dry", 0, 1, "slip", 0.1, 2.5, 2, 18, 20, 0.05, 0.125, 0.1),
]
COHESIVE_ROWS = [  # the cracks of make_run(), written as the fracture module does
    (0.3, 3e-3, 0.075, 0.1, "interface", 0, 1, "I", 1, 0, 5, 1, 9, 0.05, 0.075, 0.1),
    (0.5, 5e-3, 0.125, 0.1, "interface", 0, 1, "II", 0, 1, 6, 3, 11, 0.05, 0.125, 0.1),
    (0.6, 6e-3, 0.075, 0.05, "unit-interior", 0, 0, "mixed", 0.7, 1, 2, 3, 4, 0.05, 0.075, 0.05),
    (0.7, 7e-3, 0.1, 0.025, "unit-interior", 0, 0, "I", 1, 0, 3, 5, 6, 0.05, 0.1, 0.025),
    (0.95, 9.5e-3, 0.1, 0.175, "unit-interior", 1, 1, "II", 0, 1, 4, 21, 22, 0.05, 0.1, 0.175),
]


def write_fracture_csv(run, rows, joint_record=True):
    with open(os.path.join(run, "cracks.csv"), "w") as f:
        f.write(FRACTURE_HEADER + "".join(",".join(map(str, r)) + "\n" for r in rows))
    if joint_record:
        import json as _json
        p = os.path.join(run, "summary.json")
        with open(p) as f:
            s = _json.load(f)
        s["joint_record"] = {"open_threshold_m": 1e-4, "slip_threshold_m": 2e-4, "segments": 4}
        with open(p, "w") as f:
            _json.dump(s, f)


def counts_from_stdout(out):
    line = out.splitlines()[0]
    return {k: int(v) for k, v in (item.split() for item in line.split(": ", 1)[1].split(", "))}


def test_dry_joint_rows_drawn_and_counted_apart(tmp_path, cli):
    run = make_run(str(tmp_path / "run"))
    write_fracture_csv(run, COHESIVE_ROWS + DRY_ROWS)
    rc, out, err = cli("cracks", run, "--time", "0.65")
    assert rc == 0, err
    c = counts_from_stdout(out)
    assert c == {"unit_I": 0, "unit_II": 0, "unit_mixed": 1, "interface_I": 1, "interface_II": 1,
                 "interface_mixed": 0, "dry_open": 2, "dry_slip": 1}
    for ext in ("png", "svg"):
        assert os.path.getsize(os.path.join(run, "post", f"cracks_t0.65s.{ext}")) > 2000
    svg = open(os.path.join(run, "post", "cracks_t0.65s.svg")).read()
    assert "3 broken elements" in svg and "dry joints opened: 2, slipped: 1" in svg
    assert "dry joint opened &gt; 0.1 mm (2)" in svg and "dry joint slipped &gt; 0.2 mm (1)" in svg
    assert "#ff7f0e" in svg and "#2ca02c" in svg and "dry-joint events" in svg
    # every row at the end; each dry event on the joint segment it names (both sides share the reference midpoint)
    files, info = cracks.draw(run, str(tmp_path / "c"))
    assert info["counts"]["dry_open"] == 2 and info["counts"]["dry_slip"] == 2
    assert sum(v for k, v in info["counts"].items() if not k.startswith("dry_")) == 5
    m = info["matched_reference_midpoints"]
    assert np.allclose(m[5:], [[r[14], r[15]] for r in DRY_ROWS])
    assert np.allclose(m[:5], [[r[14], r[15]] for r in COHESIVE_ROWS])


def test_dry_joint_rows_only_and_without_snapshots(tmp_path, cli):
    """A dry-stone wall: no broken elements at all, only joint events; without snapshots they are markers."""
    run = make_run(str(tmp_path / "run"), snapshots=False)
    write_fracture_csv(run, DRY_ROWS, joint_record=False)
    cr = cracks.read_cracks(run)
    assert list(cr["class"]) == ["dry"] * 4 and list(cr["mode"]) == ["open", "open", "slip", "slip"]
    rc, out, err = cli("cracks", run, "--time", "0.5")
    assert rc == 0, err
    c = counts_from_stdout(out)
    assert c["dry_open"] == 2 and c["dry_slip"] == 1 and sum(c.values()) == 3
    assert "none (markers" in out
    svg = open(os.path.join(run, "post", "cracks_t0.5s.svg")).read()
    assert "dry joints opened: 2, slipped: 1" in svg and "broken elements</text>" not in svg  # no "0 broken"
    assert "dry joint opened (2)" in svg  # no joint_record in summary.json: no threshold in the label
    rc, out, err = cli("cracks", run, "--time", "0.1")  # before the first event
    assert rc == 0 and sum(counts_from_stdout(out).values()) == 0


def test_cohesive_only_file_unchanged_by_dry_support(tmp_path, cli):
    """The broken elements of a file are counted and matched the same with or without dry rows next to them, and
    a file of broken elements only reports no dry-joint events."""
    run = make_run(str(tmp_path / "run"))
    rc, out, err = cli("cracks", run)
    assert rc == 0, err
    assert out.splitlines()[0].endswith(", dry_open 0, dry_slip 0")
    _, before = cracks.draw(run, str(tmp_path / "a"))
    with open(os.path.join(run, "cracks.csv"), "a") as f:  # the contract spelling: first eight columns only
        for r in DRY_ROWS:
            f.write(",".join(map(str, r[:8])) + "\n")
    _, after = cracks.draw(run, str(tmp_path / "b"))
    coh = [k for k in before["counts"] if not k.startswith("dry_")]
    assert [before["counts"][k] for k in coh] == [after["counts"][k] for k in coh]
    assert np.array_equal(before["matched_reference_midpoints"], after["matched_reference_midpoints"][:5])
    assert (after["counts"]["dry_open"], after["counts"]["dry_slip"]) == (2, 2)


@pytest.mark.parametrize("row, message", [
    ("interface-dry,0,1,close", ["unknown mode ['close']", "open or slip for interface-dry"]),
    ("interface-dry,0,1,I", ["mode 'I' does not go with class 'interface-dry'", "data row 2"]),
    ("unit-interior,0,0,slip", ["mode 'slip' does not go with class 'unit-interior'"]),
    ("interface-wet,0,1,open", ["unknown class ['interface-wet']", "interface-dry"]),
])
def test_dry_joint_bad_rows_fail_clearly(tmp_path, cli, row, message):
    run = make_run(str(tmp_path / "run"))
    write_fracture_csv(run, DRY_ROWS[:1])
    with open(os.path.join(run, "cracks.csv"), "a") as f:
        f.write(f"0.5,0.005,0.075,0.1,{row},1,1,7,1,2,0.05,0.075,0.1\n")
    rc, out, err = cli("cracks", run)
    assert rc == 1 and len(err.strip().splitlines()) == 1, err
    for m in message:
        assert m in err, err


def test_cracks_outside_the_run_exit_1_with_the_range(tmp_path, cli):
    """--displacement 50 on a run that reached 10 mm (and --time beyond its end) drew the last snapshot under a title
    it never reached, exit 0; now exit 1 naming what the run covers."""
    run = make_run(str(tmp_path / "run"))  # u = 10 mm x t, t from 0 to 1 s
    rc, out, err = cli("cracks", run, "--displacement", "50")
    assert rc == 1 and "reaches 10 mm" in err and len(err.strip().splitlines()) == 1
    rc, out, err = cli("cracks", run, "--time", "99")
    assert rc == 1 and "covers 0 to 1 s" in err
    rc, out, err = cli("cracks", run, "--time", "-1")
    assert rc == 1 and "outside the run" in err
    rc, out, err = cli("cracks", run, "--displacement", "10")  # the end of the run itself is inside
    assert rc == 0, err


def test_crushing_blocks_and_joint_widths_drawn_and_counted(tmp_path, cli):
    # The macro-block model's damage (issue 29): crushing triangles (block_crushing = kappa / kappa_u) shaded, and
    # joints that never break (law = "mohr_coulomb") drawn where they open or slip by more than --joint-width.
    run = make_run(str(tmp_path / "run"))
    X, tri, unit = two_blocks()
    nt = len(tri)
    lines = [(10, 11), (11, 12), (12, 13), (13, 14)]  # the joint at y = 0.1 m, on the lower block's nodes
    nan = float("nan")
    cells = {"region": np.concatenate((unit, -np.ones(4, int))),
             "cell_kind": np.concatenate((np.zeros(nt, int), np.ones(4, int))),
             "joint_state": np.concatenate((-np.ones(nt, int), [0, 0, 2, 0])),
             "joint_opening": np.concatenate((np.full(nt, nan), [1e-3, 0.1e-3, 2e-3, 0.0])),
             "joint_slip": np.concatenate((np.full(nt, nan), [0.0, 0.8e-3, 0.0, -0.7e-3])),
             "block_crushing": np.concatenate(([0.5, 1.0, 1.2], np.zeros(nt - 3), np.full(4, nan)))}
    write_vtu(os.path.join(run, "snapshots", "snap_0002.vtu"), X, tri, np.zeros_like(X), cells, lines=lines)
    files, info = cracks.draw(run, str(tmp_path / "c"), joint_width=0.5e-3)
    c = info["counts"]
    # opened: line 1 (1 mm); line 3 is broken (drawn by cracks.csv, not here); slipped: lines 2 and 4 (|0.8|, |-0.7| mm)
    assert (c["joint_open"], c["joint_slip"]) == (1, 2)
    assert (c["crushing"], c["crushed"]) == (3, 2)
    files, info = cracks.draw(run, str(tmp_path / "d"), joint_width=0.9e-3)
    assert (info["counts"]["joint_open"], info["counts"]["joint_slip"]) == (1, 0)
    files, info = cracks.draw(run, str(tmp_path / "e"))  # no --joint-width: the joints are not drawn or counted
    assert "joint_open" not in info["counts"] and info["counts"]["crushed"] == 2
    rc, out, err = cli("cracks", run, "--joint-width", "0")
    assert rc == 1 and "--joint-width" in err and "> 0" in err


def test_damage_figure_counts_the_dry_joint_record(tmp_path, cli):
    """A dry-joint run (no broken-element columns): the damage figure draws the dry-joint record of cracks.csv (3
    segments opened at 2, 4, 6 mm and 2 slipped at 5, 7 mm: the step counts 3 and 2) instead of failing 'fracture
    off?'; a fracture run keeps its broken-element lines and adds the record."""
    from fdemtools import plots
    run = make_run(str(tmp_path / "dry"), fracture=False)
    with open(os.path.join(run, "cracks.csv"), "w") as f:
        f.write("time,control_displacement,x,y,class,unit_a,unit_b,mode\n")
        for d, m in ((2e-3, "open"), (4e-3, "open"), (5e-3, "slip"), (6e-3, "open"), (7e-3, "slip")):
            f.write(f"{d * 100},{d},0.1,0.1,interface-dry,0,1,{m}\n")
    rec = plots.dry_joint_record(run)
    assert sorted(rec["open"]) == pytest.approx([2e-3, 4e-3, 6e-3]) and sorted(rec["slip"]) == pytest.approx([5e-3, 7e-3])
    rc, o, err = cli("plot", run, "--figures", "damage", "--out", tmp_path / "p")
    assert rc == 0, err
    svg = (tmp_path / "p" / "damage.svg").read_text()
    assert "dry joint segments opened (final 3)" in svg and "dry joint segments slipped (final 2)" in svg
    assert "broken in units" not in svg
    # a run with neither: a clear error
    bare = make_run(str(tmp_path / "bare"), fracture=False)
    if os.path.exists(os.path.join(bare, "cracks.csv")):
        os.remove(os.path.join(bare, "cracks.csv"))
    with pytest.raises(Exception, match="no dry-joint record"):
        plots.plot_damage(plots.load_run(bare), "bare", str(tmp_path / "bare_damage"))
