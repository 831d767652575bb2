"""fdem-tools limit (issue 49): rigid-block limit analysis against closed forms, through the real `fdem mesh` export.

Closed forms (rigid blocks, Coulomb friction mu = tan(phi), no tension; W = rho g b h t the weight of a block of
width b and height h, thickness t):
- a block on a fixed base pushed horizontally at its top (height h above the joint): rocking about the toe when
  H h = W b / 2, sliding when H = mu W, so H = min(W b / (2 h), mu W);
- the same block on a tilting base: it tips when the weight's line passes the downhill toe, tan(alpha) = b / h, and
  slides when tan(alpha) = mu, so tan(alpha) = min(mu, b / h);
- two blocks, the upper one shifted by d (0 < d < b / 2) towards the push and pushed at its top (y = 2 h): the
  upper joint spans x in [d, b] and its downhill end is x = b; the upper block tips about (b, h) when
  H h = W (b - (d + b / 2)) = W (b / 2 - d), slides when H = mu W; the pair tips about the base toe (b, 0) when
  2 h H = W b / 2 + W (b / 2 - d) = W (b - d), slides on the base when H = 2 mu W. The pair is statically determinate
  and each joint's admissible resultants are a box (|T| <= mu N, resultant inside the joint), so H is the least;
- a squat block bonded to its base (cohesion c, --bonded): sliding at mu W + c b t (its rocking, with or without the
  tension cut-off, is stronger here), and mu W without --bonded.
"""
import json
import math
import os
import subprocess
import sys
import time

import numpy as np
import pytest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _fdem():
    return os.environ.get("FDEM_BIN") or os.path.join(REPO, "build", "fdem", "fdem")


pytestmark = pytest.mark.skipif(not os.access(_fdem(), os.X_OK), reason="no fdem executable (FDEM_BIN or build/fdem/fdem)")

RHO, G, T = 2000.0, 9.81, 0.2


def write_case(path, *, b=0.4, h=0.6, friction=40.0, stones=None, mesh=0.1, tilt=False, bonded=None, E=1.0e9,
               penalty=1.0e9, name="limit_test", extra_stage=""):
    """A wall-generator case: one block (or `stones`) on a fixed base slab, pushed at wall_top or tilted."""
    if stones is None:
        geom = f"length = {b}\ncourses = 1\nunit_length = {b}\nunit_height = {h}\nbond = \"stack\"\n"
    else:
        geom = "stones = " + json.dumps(stones) + "\n"
    if bonded:
        c, ft = bonded
        iface = (f'[[interfaces]]\nregions = ["units", "base"]\nkind = "bonded"\ntensile_strength = {ft}\n'
                 f"cohesion = {c}\nfriction = {friction}\nresidual_friction = {friction}\nGI = 10.0\nGII = 50.0\n"
                 f"penalty = {penalty}\n")
    else:
        iface = (f'[[interfaces]]\nregions = ["units", "base"]\nkind = "dry"\nfriction = {friction}\n'
                 f"normal_penalty = {penalty}\n")
    iface += (f'\n[[interfaces]]\nregions = ["units", "units"]\nkind = "dry"\nfriction = {friction}\n'
              f"normal_penalty = {penalty}\n")
    if tilt:
        stages = ('[[stages]]\nname = "gravity"\nduration = 0.1\ngravity = [0.0, -9.81]\n'
                  '  [[stages.supports]]\n  group = "base_bottom"\n  fix = "xy"\n\n'
                  '[[stages]]\nname = "tilt"\nduration = 8.0\ntilt_rate = 5.0\n')
    else:
        stages = ('[[stages]]\nname = "push"\nduration = 1.0\ngravity = [0.0, -9.81]\n'
                  '  [[stages.supports]]\n  group = "base_bottom"\n  fix = "xy"\n'
                  '  [[stages.supports]]\n  group = "wall_top"\n  vx = 0.01\n')
    text = f"""[case]
name = "{name}"
thickness = {T}

[geometry]
type = "wall"
{geom}joint = "dry"
base = "slab"
base_height = 0.1
base_overhang = 0.1
mesh_size = {mesh}

[materials.stone]
E = {E}
nu = 0.2
density = {RHO}

[regions]
units = "stone"
base = "stone"

{iface}
{stages}{extra_stage}"""
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)
    return str(path)


def model_of(case, tmp_path, sets=None):
    from fdemtools import limit
    model, _ = limit.export_model(str(case), sets, _fdem(), str(tmp_path / "export"))
    return model


def factors(case, tmp_path, bonded=False, sets=None):
    """(static factor, kinematic factor, problem) of a case."""
    from fdemtools import limit
    pr = limit.Problem(model_of(case, tmp_path, sets), bonded=bonded)
    s = limit.solve(pr, nonassoc=False)["assoc"]
    assert s["status"] == 0, s["message"]
    k = limit.kinematic_lp(pr, const_scale=s.get("const_scale", 1.0))
    assert k["status"] == 0, k["message"]
    return s["lam"], k["lam"], pr


def weight(b, h):
    return RHO * G * b * h * T


# ------------------------------------------------------------------------------------------------ export


def test_export_has_the_engine_model(tmp_path):
    case = write_case(tmp_path / "block.toml")
    m = model_of(case, tmp_path)
    assert m["format"] == "fdem-limit-model"
    assert len(m["bodies"]) == 2
    W = weight(0.4, 0.6)
    blk = [b for b in m["bodies"] if b["regions"] == ["units"]][0]
    assert blk["mass"] == pytest.approx(W / G, rel=1e-12)
    assert blk["centroid"] == pytest.approx([0.2, 0.3], abs=1e-12)
    segs = m["interfaces"]
    assert {s["kind"] for s in segs} == {"dry"}
    assert sum(math.hypot(s["p1"][0] - s["p0"][0], s["p1"][1] - s["p0"][1]) for s in segs) == pytest.approx(0.4)
    # every segment runs counter-clockwise around body_a: the normal (s_y, -s_x) points into body_b
    for s in segs:
        a = m["bodies"][s["body_a"]]["centroid"]
        d = np.subtract(s["p1"], s["p0"])
        n = np.array([d[1], -d[0]])
        assert np.dot(n, np.subtract(s["p0"], a)) > 0
    sup = {(s["group"], s["component"]): s for s in m["supports"]}
    assert sup[("wall_top", "x")]["mode"] == "velocity" and sup[("wall_top", "x")]["velocity"] == 0.01
    assert sup[("base_bottom", "y")]["mode"] == "fixed"
    assert m["gravity"]["vector"] == [0.0, -9.81]


def test_export_loads_carry_over_and_are_replaced(tmp_path):
    extra = ('  [[stages.loads]]\n  group = "wall_top"\n  force = [0.0, -100.0]\n\n'
             '[[stages]]\nname = "more"\nduration = 1.0\n'
             '  [[stages.loads]]\n  group = "wall_top"\n  force = [0.0, -300.0]\n'
             '  [[stages.supports]]\n  group = "wall_top"\n  vx = 0.02\n')
    case = write_case(tmp_path / "c.toml", extra_stage=extra)
    m = model_of(case, tmp_path)
    assert len(m["loads"]) == 1 and m["loads"][0]["force"] == [0.0, -300.0]
    assert sum(f[2] for f in m["loads"][0]["node_forces"]) == pytest.approx(-300.0)
    vx = [s for s in m["supports"] if s["group"] == "wall_top"]
    assert len(vx) == 1 and vx[0]["velocity"] == 0.02 and vx[0]["stage"] == 2
    assert any(s["group"] == "base_bottom" for s in m["supports"])  # kept from stage 1


# ------------------------------------------------------------------------------------------------ closed forms


@pytest.mark.parametrize("b,h,phi", [(0.4, 0.6, 40.0), (0.4, 0.6, 20.0), (0.3, 0.9, 45.0)])
def test_single_block_pushed_at_the_top(tmp_path, b, h, phi):
    case = write_case(tmp_path / "b.toml", b=b, h=h, friction=phi)
    lam, kin, pr = factors(case, tmp_path)
    W = weight(b, h)
    expected = min(W * b / (2 * h), math.tan(math.radians(phi)) * W)
    assert lam == pytest.approx(expected, rel=1e-9)
    assert kin == pytest.approx(lam, rel=1e-9)


@pytest.mark.parametrize("phi", [40.0, 30.0])
def test_single_block_tilting(tmp_path, phi):
    b, h = 0.4, 0.6
    case = write_case(tmp_path / "t.toml", b=b, h=h, friction=phi, tilt=True)
    lam, kin, pr = factors(case, tmp_path)
    assert pr.mode == "tilt"
    expected = min(math.tan(math.radians(phi)), b / h)
    assert lam == pytest.approx(expected, rel=1e-9)
    assert kin == pytest.approx(lam, rel=1e-9)


def stack_stones(b, h, d):
    return [[[0, 0], [b, 0], [b, h], [0, h]], [[d, h], [d + b, h], [d + b, 2 * h], [d, 2 * h]]]


def stack_closed_form(b, h, d, mu):
    W = weight(b, h)
    return min(W * (b / 2 - d) / h, mu * W, W * (b - d) / (2 * h), 2 * mu * W)


@pytest.mark.parametrize("d,phi", [(0.1, 35.0), (0.05, 20.0), (0.0, 35.0)])
def test_two_block_stack_with_offset(tmp_path, d, phi):
    b, h = 0.4, 0.2
    case = write_case(tmp_path / "s.toml", stones=stack_stones(b, h, d), friction=phi, mesh=0.1)
    lam, kin, pr = factors(case, tmp_path)
    assert pr.nb == 3 and pr.fixed.sum() == 1
    assert lam == pytest.approx(stack_closed_form(b, h, d, math.tan(math.radians(phi))), rel=1e-9)
    assert kin == pytest.approx(lam, rel=1e-9)


def test_bonded_joint_cohesion(tmp_path):
    b, h, phi, c, ft = 0.4, 0.1, 30.0, 2000.0, 1000.0
    case = write_case(tmp_path / "bd.toml", b=b, h=h, friction=phi, bonded=(c, ft), mesh=0.05)
    W, mu = weight(b, h), math.tan(math.radians(30.0))
    lam, kin, pr = factors(case, tmp_path, bonded=True)
    assert lam == pytest.approx(mu * W + c * b * T, rel=1e-9)
    assert kin == pytest.approx(lam, rel=1e-9)
    lam_dry, kin_dry, _ = factors(case, tmp_path, bonded=False)
    assert lam_dry == pytest.approx(mu * W, rel=1e-9)
    assert kin_dry == pytest.approx(lam_dry, rel=1e-9)


def test_mesh_size_does_not_change_the_factor(tmp_path):
    b, h, d = 0.4, 0.2, 0.1
    case = write_case(tmp_path / "m.toml", stones=stack_stones(b, h, d), friction=35.0, mesh=0.1)
    coarse, _, p1 = factors(case, tmp_path)
    fine, _, p2 = factors(case, tmp_path, sets=["geometry.mesh_size=0.03"])
    assert p2.np > p1.np  # more contact points, the same bodies
    assert fine == pytest.approx(coarse, rel=1e-9)


# ------------------------------------------------------------------------------------------------ the command


def test_command_writes_its_outputs(tmp_path, cli):
    case = write_case(tmp_path / "blk.toml", b=0.4, h=0.6, friction=40.0)
    out = tmp_path / "out"
    rc, so, se = cli("limit", case, "--out", out, "--fdem", _fdem())
    assert rc == 0, se
    rep = json.loads((out / "limit.json").read_text())
    W = weight(0.4, 0.6)
    assert rep["collapse_load_N"] == pytest.approx(W * 0.4 / 1.2, rel=1e-9)
    assert rep["collapse_load_nonassoc_N"] == pytest.approx(W * 0.4 / 1.2, rel=1e-6)
    assert rep["bodies"] == 2 and rep["joints"] == 1 and rep["solver_status"] == 0
    assert rep["mechanism"]["moving_bodies"] == 1 and rep["mechanism"]["opening_segments"] >= 1
    assert rep["mechanism"]["sliding_segments"] == 0
    for f in ("mechanism.png", "mechanism.vtu", "limit_model.json"):
        assert (out / f).stat().st_size > 0
    vtu = (out / "mechanism.vtu").read_text()
    assert 'Name="mechanism_velocity"' in vtu and 'Name="joint_opening"' in vtu and 'Name="body"' in vtu
    assert "collapse load" in so and "N" in so


def test_command_tilt_and_nonassociative_sliding(tmp_path, cli):
    # sliding block on a tilting base: associative and non-associative agree (no dilatancy work in pure sliding)
    case = write_case(tmp_path / "tl.toml", b=0.4, h=0.3, friction=30.0, tilt=True)
    out = tmp_path / "o"
    rc, so, se = cli("limit", case, "--out", out, "--fdem", _fdem(), "--no-plot")
    assert rc == 0, se
    rep = json.loads((out / "limit.json").read_text())
    assert rep["critical_tilt_deg"] == pytest.approx(30.0, rel=1e-9)
    assert rep["critical_tilt_nonassoc_deg"] == pytest.approx(30.0, rel=1e-6)
    assert "estimate" in rep["nonassoc"]["label"]


def test_settlement_is_refused(tmp_path, cli):
    extra = ('\n[[stages]]\nname = "settle"\nduration = 1.0\n'
             '  [[stages.supports]]\n  group = "base_bottom"\n  vy = -0.01\n')
    case = write_case(tmp_path / "st.toml", extra_stage=extra)
    rc, so, se = cli("limit", case, "--out", tmp_path / "o", "--fdem", _fdem())
    assert rc == 1
    assert "settlement" in se
    assert "settlement" in json.loads((tmp_path / "o" / "limit.json").read_text())["refused"]


def test_nonassociative_estimate_below_the_bound_on_a_stack(tmp_path):
    from fdemtools import limit
    case = write_case(tmp_path / "na.toml", stones=stack_stones(0.4, 0.2, 0.05), friction=20.0)
    pr = limit.Problem(model_of(case, tmp_path))
    sol = limit.solve(pr)
    assert sol["nonassoc"]["converged"]
    assert sol["nonassoc"]["lam"] <= sol["assoc"]["lam"] * (1 + 1e-9)


# ------------------------------------------------------------------------------------------------ engine consistency

ENGINE_STAGES = """
[groups.pusher]          # one node at the upper block's top-left corner: a drive on the whole top edge would hold
nearest = [0.1, 0.4]     # the edge's nodes at one x velocity and stiffen the block against rocking once it turns
within = "wall_top"

[[monitors]]
name = "u"
type = "displacement"
group = "pusher"
component = "x"

[[monitors]]
name = "H"
type = "reaction"
group = "pusher"
component = "x"

[output]
history_interval = 0.001
curve = { x = "u", y = "H" }

[[stages]]
name = "gravity"
equilibrium = 1e-5
max_duration = 0.5
local_damping = 0.8
gravity = [0.0, -9.81]
gravity_ramp = 0.2
  [[stages.supports]]
  group = "base_bottom"
  fix = "xy"

[[stages]]
name = "push"
until = { monitor = "u", value = 0.0015 }
local_damping = 0.0
contact_damping = 0.3
  [[stages.supports]]
  group = "pusher"
  vx = 0.002
  ramp = 0.2
"""


def test_engine_run_reaches_the_bound_and_stays_below_it(tmp_path):
    """A two-block stack (upper block shifted 0.1 m towards the push, phi 35 deg: the upper block rocks about the
    lower block's corner at H = W (b/2 - d) / h = 0.5 W) run by fdem with stiff blocks and joints (E and the contact
    penalty x 20 of the cases above: 2e10 Pa) at 2 mm/s, to 1.5 mm. The drive's reaction, averaged over 0.1 mm of
    travel (the contacts' chatter makes single rows scatter by a few per cent), reaches at least 95 % of the
    associative bound and never exceeds it by more than 2 %. About 4 s on one thread."""
    import csv
    case = write_case(tmp_path / "eng.toml", stones=stack_stones(0.4, 0.2, 0.1), friction=35.0, mesh=0.1, E=2.0e10,
                      penalty=2.0e10, tilt=False)
    text = open(case).read()
    text = text[:text.index("[[stages]]")] + ENGINE_STAGES
    with open(case, "w") as f:
        f.write(text)
    lam, kin, pr = factors(case, tmp_path)
    assert lam == pytest.approx(0.5 * weight(0.4, 0.2), rel=1e-9)
    run = tmp_path / "run"
    r = subprocess.run([_fdem(), "run", case, "--out", str(run), "--threads", "1", "--quiet"], capture_output=True,
                       text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    with open(run / "history.csv") as f:
        rows = [x for x in csv.DictReader(f) if x["stage"] == "2"]
    u = np.array([float(x["u"]) for x in rows])
    H = np.array([float(x["H"]) for x in rows])
    Hs = np.array([H[np.abs(u - uu) <= 0.5e-4].mean() for uu in u])
    assert Hs.max() >= 0.95 * lam
    assert Hs.max() <= 1.02 * lam


def test_validate_tabulates_the_bound_and_flags_a_peak_above_it(tmp_path):
    """validate's rigid-block column: the single block pushed at its top (b 0.4 m, h 0.6 m, 40 deg) has the bound
    W b / (2 h) (rocking, below mu W); a peak 1 % above it is tabulated as its ratio, 3 % above is flagged."""
    from fdemtools import validate
    case = write_case(tmp_path / "b.toml", b=0.4, h=0.6, friction=40.0)
    got = validate.rigid_block_bound(case, [], _fdem(), str(tmp_path / "lim"))
    W = weight(0.4, 0.6)
    assert got["bound_N"] == pytest.approx(W * 0.4 / (2 * 0.6), rel=1e-9)
    assert validate.bound_ratio({"peak_over_bound": 1.01}) == "1.010"
    assert validate.bound_ratio({"peak_over_bound": 1.03}).endswith("ABOVE THE BOUND")
    # a case with no load to multiply (a settlement: a support moving along gravity) has a note, not a number
    settle = write_case(tmp_path / "s.toml", extra_stage="")
    text = open(settle).read().replace('group = "wall_top"\n  vx = 0.01', 'group = "base_bottom"\n  vy = -0.01')
    open(settle, "w").write(text)
    got = validate.rigid_block_bound(settle, [], _fdem(), str(tmp_path / "lim2"))
    assert "bound_N" not in got and got["note"]


def test_preview_draws_the_set_up_the_engine_builds(tmp_path, cli):
    """fdem-tools preview on the single block of these tests: a PNG with the regions, the dry joint under the block,
    the fixed base, the drive at wall_top (vx = 0.01 m/s) and gravity, all read from the engine's export."""
    from fdemtools import preview
    case = write_case(tmp_path / "b.toml", b=0.4, h=0.6, friction=40.0)
    out = tmp_path / "p.png"
    rc, o, err = cli("preview", case, "--out", out)
    assert rc == 0, err
    assert out.stat().st_size > 10000
    texts = preview.draw(model_of(case, tmp_path), str(tmp_path / "q.png"))
    joined = "\n".join(texts)
    assert "region units" in joined and "region base" in joined
    assert "dry joint segments" in joined
    assert "wall_top: vx = 0.01 m/s" in joined
    assert "base_bottom: x fixed" in joined and "base_bottom: y fixed" in joined
    assert "g = 9.81 m/s^2" in joined
