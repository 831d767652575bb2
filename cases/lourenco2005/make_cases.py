#!/usr/bin/env python3
"""Writes the case files of cases/lourenco2005/ from reference.csv and the shared settings below.

The case files are committed; this script documents how they were made and keeps the numerical settings identical
across the walls of a family (rerun it after changing a setting: /usr/bin/python3 cases/lourenco2005/make_cases.py).
"""
import csv
import os

HERE = os.path.dirname(os.path.abspath(__file__))
G = 9.81            # m/s^2
RHO = 2400.0        # kg/m^3, stone and concrete (assumed, cases/README.md §A)
T = 0.2             # m, wall thickness
L, H = 1.0, 1.0     # m, wall length and height
BEAM_H = 0.2        # m, beam depth (assumed)
BASE_H = 0.1        # m, base slab depth (assumed)
W_WALL = RHO * G * L * H * T            # N
W_BEAM = RHO * G * L * BEAM_H * T       # N
# Loading (the same for every wall and variant; RESULTS.md §6). cases/README.md §A gives the rigid-block limit of these walls
# as "H = N/2 plus the self-weight share": a lever arm equal to the wall's height (the horizontal load acts at the top
# of the wall, h = 1.0 m) and the self-weight acting on top of N. The same section also says N "includes the wall's and
# beam's self-weight"; the two readings contradict each other. We follow the limit analysis, because the test paper's
# sigma = N / A (0.15 MPa = 30 kN / 0.2 m^2) is the jack's load alone, and because every published model of the 30 kN
# wall (FDEM 17.10, FEM 17.13, DEM 16.14 kN) carries more than N/2 = 15 kN, which no model with the self-weight inside
# N and the load at 1.0 m can (its rigid-block bound is N/2 exactly). Measured on the 30 kN quasi-static wall: load at
# the beam's mid-depth (1.1 m) and self-weight inside N 11.98 kN; load at 1.0 m 14.65 kN; and self-weight on top of N
# 16.92 kN (RESULTS.md §6).
LOAD_HEIGHT = 1.0   # m, the actuator node: the beam's left end at the top of the wall

# Numerical settings shared by every wall of a variant (fdem/README.md 'Mass scaling and damping'). The [K25] time step is fixed so that all
# four walls use the same one: 1.5e-6 s = 0.76 of the joint-spring limit 1.985e-6 s of this mesh (before engine commit
# 0b03ca9 the engine took 0.8 x the triangle limit, 1.5e-5 s, and the wall blew up at step 9).
# Loading rate 0.01 m/s for both variants: a single dry block pushed over its base at 0.1 m/s shows a mean force 38 %
# above mu N with +-50 % oscillations, at 0.01 m/s 4.7 % above (RESULTS.md), and the [K25] walls at 0.1 m/s carry
# 1.7-2.1 times the measured loads. At 0.01 m/s one [K25] wall is ~600,000 steps (about 40 min on 2 cores).
# [K25] family (quasi-static, RESULTS.md §5 and §7): mass scaling 10, contact dashpots at 0.3 of critical (they damp
# the contacts' chatter and the vibrations that made the blocks creep; RESULTS.md §5) and local damping 0.05 in the
# shear stage: pushed at the top of the wall (below the beam's mid-depth) the walls develop a growing 25 Hz vertical
# oscillation that the dashpots do not reach and that lets the joints creep (RESULTS.md §6.2); 0.05 removes it. Local
# damping signed by the absolute velocity carried a load of its own (1.6-7.1 % of the loading work, RESULTS.md §7):
# the oscillation rides on the drive's motion, so the damping force pointed backwards nearly all the time. Since
# RESULTS.md §8 it is signed by the velocity minus its moving mean over ld_filter = 0.1 s (stage key
# local_damping_filter; 2-5 periods of the 20-30 Hz oscillation, a tenth of the 1 s loading).
# QUICK: the setting of the default ./run.sh, see K25_QUICK.
# Since 27 Nov (RESULTS.md §29): the blocks' cohesive elements are inserted where the traction reaches the strength
# (insertion = "extrinsic": a block is one continuum until then, so no penalty compliance and no joint springs in the
# step), the dry joints and crack faces touch with contact_penalty = 1e9 Pa (the joint penalty p_j of the cohesive
# elements stays penalty "auto" with penalty_ref = 1e10 Pa), and the drive starts with a 0.1 s velocity ramp (three
# transits of the shear wave through the mass-scaled wall at mass scaling 100). Same curve as the family setting
# before within the scatter of its slip events, 3-6 times fewer steps (RESULTS.md §29).
# Since 27 Nov (RESULTS.md §33): mass scaling 10 per node (mass_scaling = "per_node"): the triangles' step at
# mass scaling 10, the nodes whose contact springs would need a smaller one made heavier; on the 100 kN wall 24,920
# steps instead of 64,532 for the same curve within 0.3 % of the peak (peak +0.73 / +0.41 %, K_e -2.0 / -2.1 % against
# the converged curve).
# Since 27 Nov (RESULTS.md §34): safety 0.7. The contact springs' bound became a per-node Gershgorin row sum (it had
# counted one face and no other side), which asks 1.7 times the added mass at the default safety 0.8, where the
# springs are made stable at 4/3 of the triangles' step; at 0.7 they are made stable at the triangles' step itself
# (per_node_margin), about the added mass of before at 0.875 of the step.
# Since 28 Nov (issue 50, RESULTS.md §45): per-node mass scaling raises each node until the assembled nodal bound (its
# triangles' share plus its springs' row sums) reaches the triangles' limit, whatever the safety; the step is safety x
# that limit. Safety 0.7 stays for accuracy, not stability: at the default 0.8 (step x 1.14) the default run's curve
# moved +1.05 % at 10 mm against +0.01 % at 0.7 (total inertial mass x 2.69 over x 15 with the new rule, 2.38 before).
# Since 28 Nov (issue 48 §2): the shear stage runs past its peak ([[stages]] past_peak: it ends when the base shear,
# averaged over 0.5 mm of travel, has stayed PAST_PEAK_DROP below its largest average for PAST_PEAK_TRAVEL of travel)
# or to 30 mm (3 % drift), whichever comes first; before, it stopped at 10 mm (K25) or 8 mm (DEC) while still rising.
PAST_PEAK_DROP, PAST_PEAK_TRAVEL, UNTIL_PAST_PEAK = 0.1, 0.002, 0.030
K25 = dict(mesh=0.025, penalty=1.0e10, contact_penalty=1.0e9, rate=0.01, until=UNTIL_PAST_PEAK, past_peak=True,
           damping=0.05, ld_filter=0.1,
           contact_damping=0.3, mass_scale=10, mass_scaling="per_node", safety=0.7, drive_ramp=0.1,
           # precompression: ramps and bound long enough for the mass-scaled wall (vertical period ~0.1 s) to come to rest
           pre_ramp=0.05, pre_max=0.4, snapshots=0.05)
# QUICK (the default ./run.sh; until 27 Nov, 2-4 minutes on 2 threads): the family setting with mass scaling 100 instead of 10
# (time step x 3.16). On the 100 kN wall with the filtered local damping of RESULTS.md §8 and the loading of SETUP_NODE:
# 45.58 kN raw against 45.13 kN raw at mass scaling 10 (+1.0 %), 116,405 steps, 123-137 s on 2 threads (RESULTS.md
# §17; before §8: 47.23 against 46.20 kN, RESULTS.md §7.4); with SETUP_PAPER 40.01 kN, 118,692 steps (RESULTS.md §28).
# Since 27 Nov (RESULTS.md §33): mass scaling 15 per node ([numerics] mass_scaling = "per_node": the triangles' step,
# the nodes whose joint penalty would need a smaller one made heavier) instead of 100 uniform: 20,812 steps against
# 21,779, peak +0.81 % and K_e -2.0 % against the converged curve instead of +2.3 % and -7.1 %. Since RESULTS.md §34
# at safety 0.7 (as the family): 23,480 steps. Since RESULTS.md §45 (the nodal bound's masses): 23,769 steps.
K25_QUICK = dict(K25, mass_scale=15, until=0.010, past_peak=False)  # the preview stops at 10 mm, before its peak
# 3DEC family: local damping 0.8 in the shear stage, as 3DEC's default (Itasca's local damping 0.8), signed by the
# velocity minus its moving mean over 0.1 s, and contact dashpots at 0.3 of critical: without the filter the damping
# carried load (the files were quasi-static at 0 of 4 walls, -2.2 to -11 % at half rate), without the dashpots the
# 30 kN wall's first peak at 0.9 mm was dynamic (-20.7 % at half rate; RESULTS.md §8.4-8.5).
DEC = dict(mesh=0.05, rate=0.01, until=UNTIL_PAST_PEAK, past_peak=True, damping=0.8, ld_filter=0.1, contact_damping=0.3, pre_ramp=0.01, pre_max=0.02,
           snapshots=0.01)



# Set-up of the loading and supports. "node": the committed set-up until 27 Nov (RESULTS.md §6): one actuator node at the
# beam's left end at the top of the wall (h = 1.0 m), H its reaction; the bottom-left corner node restrained in x only.
# "paper": the [K25] model's set-up (seeds/004 = Karimzadeh et al., Sec. 4, Figure 7b): "the base and bottom-left corner of
# the simulated wall specimens were pinned ... the gridpoints of the element located at the left toe and bottom surface
# were assigned zero displacement"; "no restraints were applied at the top of the RC beam"; "constant gridpoint
# velocities were assigned at the top surface of the loading beam"; "base shear reaction forces were recorded". Read
# here as: every node of the wall's bottom surface fixed in x and y (the toe is one of them; the base slab below is then
# idle), every node of the beam's top surface driven at vx (vertical free, so the beam can still rotate: a uniform
# horizontal velocity along a horizontal line allows a rigid rotation), and H the sum of the horizontal reactions of
# the supports. The other reading, the wall on the slab through its dry joint with only the bottom-left corner node
# pinned (x and y), was run once on the 100 kN wall (RESULTS.md §28: 37.94 kN against 40.01 kN with this one).
# The [K25] family used "paper" from 27 Nov (issue 27 §2) to 28 Nov; since 28 Nov (issue 48 §2) both families use "node":
# the rigid-block bound of the same blocks and friction (`fdem-tools limit`, cases/lourenco2005/RESULTS.md §43) is
# 14.82 / 46.63 kN at N = 30 / 100 kN for "paper" as modelled here and 16.98 / 52.40 kN for "node", and the published
# FDEM peaks, 17.10 / 47.75 kN, cannot lie above the bound of the set-up that produced them (a deformable model with
# non-associative friction stays below the associative rigid-block load of its blocks): they lie 15 % / 2 % above the
# "paper" bound and 0.7 % above / 9 % below the "node" one. SETUP_FAMILY names the set-up both families use.
SETUP_NODE = dict(
    base="""the wall stands on a concrete base slab (fixed at base_bottom) through a dry joint, so it can
#   rock and slide""",
    groups="""[groups.actuator]        # the beam's left end at the top of the wall (h = {load_height} m): one point, so the beam stays
box = [-0.001, {load_low}, 0.001, {load_high}]   # free to rotate; a box takes every node there (the beam's corner and the
                         # tied copies of the top-left stone's corner, which move as one node until a crack is inserted)

[groups.stopper]         # bottom-left corner node of the bottom-left block: restrained against sliding (fix x); one
nearest = [0.0, 0.0]     # node, so that the block can still lift and rotate with the wall (a box of nodes on its left
within = "wall_left"     # face held it upright: a moment restraint the test did not have)

[[monitors]]
name = "u_beam"          # m, horizontal displacement of the loaded point
type = "displacement"
group = "actuator"
component = "x"

[[monitors]]
name = "H"               # N, actuator reaction: the force it applies (positive while pushing in +x)
type = "reaction"
group = "actuator"
component = "x"

[[monitors]]
name = "V_base"          # N, vertical base reaction (= N + self-weight once precompressed)
type = "reaction"
group = "base_bottom"
component = "y"

[[monitors]]
name = "H_stopper"       # N, reaction of the sliding restraint
type = "reaction"
group = "stopper"
component = "x"
""",
    sentence="""Set-up (SETUP_NODE in make_cases.py; since 28 Nov
#   for the [K25] family too: the published FDEM peaks exceed the rigid-block bound of the seeds/004 reading as modelled
#   here, wall bottom fixed and the beam top driven at h = 1.2 m, by 15 % at N = 30 kN; RESULTS.md §43): the actuator
#   is a single node at the beam's left end at the top of the wall (h = {LOAD_HEIGHT} m): horizontal velocity prescribed,
#   vertical free, the beam rotates; the bottom-left corner node is held in x (SETUP_NODE in make_cases.py). N on top of
#   the self-weight follows the rigid-block limit of cases/README.md §A, H = N/2 plus the self-weight share, which the
#   brief's other sentence (cases/README.md §A) ("N includes the self-weight") contradicts: see make_cases.py and
#   RESULTS.md §6 (the other reading: --set stages.1.loads.1.force=[0.0,-(N - {W:.1f})]; the load at the
#   beam's mid-depth: --set groups.actuator.nearest=[0.0,1.1]).""",
    toe="""  [[stages.supports]]
  group = "stopper"
  fix = "x"
""",
    drive="""  [[stages.supports]]
  group = "actuator"
  vx = {rate}              # m/s
  ramp = {ramp}           # s
""")
SETUP_PAPER = dict(
    base="""the wall's bottom surface is fixed (the concrete base slab
#   below it, fixed at base_bottom, stays idle)""",
    groups="""[groups.supports]        # every node from the base slab's bottom to the wall's bottom (a box): the reaction monitors
box = [-0.2, -0.2, 1.2, 0.001]   # sum over its prescribed DOFs, i.e. base_bottom and wall_bottom (xmin, ymin, xmax, ymax; m)

[[monitors]]
name = "u_beam"          # m, horizontal displacement of the beam's top surface (mean over its nodes)
type = "displacement"
group = "beam_top"
component = "x"

[[monitors]]
name = "H"               # N, base shear: horizontal reaction of the supports (the recorded load of seeds/004;
type = "reaction"        # negative while the beam is pushed in +x)
group = "supports"
component = "x"

[[monitors]]
name = "H_drive"         # N, reaction of the driven beam top (positive while pushing in +x; -H plus the inertial and
type = "reaction"        # damping forces of wall and beam)
group = "beam_top"
component = "x"

[[monitors]]
name = "V_base"          # N, vertical reaction of the supports (= N + self-weight once precompressed)
type = "reaction"
group = "supports"
component = "y"
""",
    sentence="""Loading and
#   supports as the [K25] model of seeds/004 (Sec. 4, Figure 7b; SETUP_PAPER in make_cases.py): the wall's bottom surface
#   fixed in x and y (the base slab below is idle; the other reading, the wall on the slab's dry joint with only the
#   bottom-left corner pinned, gave 5 % less on the 100 kN wall, RESULTS.md §28), every node of the beam's top surface
#   (h = 1.2 m) driven horizontally at a constant velocity, vertical free (the beam can rotate); H is the base shear,
#   the horizontal reaction of the supports. N on top of the self-weight as the rigid-block limit of cases/README.md §A
#   reads it (RESULTS.md §6; the other reading: --set stages.1.loads.1.force=[0.0,-(N - {W:.1f})]).""",
    toe="""  [[stages.supports]]
  group = "wall_bottom"   # the wall's bottom surface, pinned (seeds/004 Sec. 4)
  fix = "xy"
""",
    drive="""  [[stages.supports]]
  group = "beam_top"      # every node of the beam's top surface (seeds/004: constant gridpoint velocities)
  vx = {rate}              # m/s
  ramp = {ramp}             # s: velocity ramp (see the header)
""")


SETUP_FAMILY = SETUP_NODE  # the set-up of both families (see above)


def rows():
    with open(os.path.join(HERE, "reference.csv")) as f:
        return list(csv.DictReader(f))


COMMON_GEOMETRY = """[geometry]
type = "wall"
length = 1.0             # m
courses = 10
unit_length = 0.2        # m, sandstone block 200 x 100 x 200 mm
unit_height = 0.1        # m
bond = "running"         # half blocks at the ends of alternate courses
joint = "dry"
beam_height = 0.2        # m (assumed)
base = "slab"
base_height = 0.1        # m (assumed)
base_overhang = 0.1      # m
mesh_size = {mesh}       # m, in the blocks
mesh_size_beam = 0.1     # m
mesh_size_base = 0.1     # m
"""

COMMON_TAIL = """
[materials.concrete]     # beam and base slab: elastic, no cracking (cases/README.md 'A 3D test as a 2D model')
E = 1.0e9                # Pa (assumed: 1-2x the wall modulus; a stiffer value makes the small beam/base triangles
                         # at the wall corners set a time step several times smaller)
nu = 0.2
density = 2400.0         # kg/m^3

[regions]
units = "stone"
beam = "concrete"
base = "concrete"

{interfaces}
[[interfaces]]           # the beam is bonded to the top course (tied: shared nodes), so it can rotate with the wall
regions = ["units", "beam"]
kind = "tied"

{setup_groups}
[[monitors]]
name = "u_top_right"     # m
type = "displacement"
group = "wall_top_right"
component = "x"

[[monitors]]
name = "v_top_right"     # m, uplift of the top right corner (rocking)
type = "displacement"
group = "wall_top_right"
component = "y"

{numerics}
[output]
history_interval = 0.0005  # s
snapshot_interval = {snapshots}   # s
curve = {{ x = "u_beam", y = "H" }}

[reference]
monitor = "H"
quantity = "peak"
value = {exp_N}          # N, measured peak (average of the tests)
tolerance = 0.25
source = "Lourenco et al. 2005, average of the tests at N = {N} kN"

[[stages]]
name = "precompression"  # gravity and N on the beam, ramped, then damped to rest
equilibrium = 1e-3
max_duration = {pre_max}      # s
local_damping = 0.8
gravity = [0.0, -9.81]   # m/s^2
gravity_ramp = {pre_ramp}      # s
  [[stages.supports]]
  group = "base_bottom"
  fix = "xy"
{toe_support}  [[stages.loads]]
  group = "beam_top"
  force = [0.0, {F_top}]  # N = -N; the base carries N + wall and beam self-weight {W:.1f} N
  ramp = {pre_ramp}            # s

[[stages]]
name = "shear"           # horizontal displacement at constant rate, N held
until = {{ monitor = "u_beam", value = {until} }}{past_peak}
local_damping = {damping}{ldf}{contact}
{drive}"""


def setup_text(setup, s):
    return dict(setup_groups=setup["groups"].format(load_height=LOAD_HEIGHT, load_low=f"{LOAD_HEIGHT - 0.001:g}",
                                                    load_high=f"{LOAD_HEIGHT + 0.001:g}"), toe_support=setup["toe"],
                drive=setup["drive"].format(rate=s["rate"], ramp=s.get("drive_ramp", 0.005)))


def ldf_line(s):
    x = s.get("ld_filter")
    return f"\nlocal_damping_filter = {x}  # s: damping signed by v minus its moving mean (see the header)" if x else ""


def past_peak_line(s):
    if not s.get("past_peak"):
        return ""
    return (f"\npast_peak = {{ load = \"H\", displacement = \"u_beam\", drop = {PAST_PEAK_DROP}, travel = {PAST_PEAK_TRAVEL} }}"
            f"  # ends {PAST_PEAK_DROP * 100:g} % below the peak for {PAST_PEAK_TRAVEL * 1000:g} mm (see the header)")


def contact_line(s):
    x = s.get("contact_damping")
    return f"\ncontact_damping = {x}    # contact dashpots, fraction of critical (see the header)" if x else ""


def past_peak_sentence(s):
    if not s.get("past_peak"):
        return ""
    return (f"\n#   or until past the peak (the load H averaged over {PAST_PEAK_TRAVEL / 4 * 1000:g} mm of travel "
            f"{PAST_PEAK_DROP * 100:g} % below its largest average\n#   for {PAST_PEAK_TRAVEL * 1000:g} mm: [[stages]] "
            "past_peak, issue 48; seeds/004 reads the peak at the largest load and the ultimate\n#   displacement there)")


def header(title, r, variant_text, s, fname, setup):
    setup_sentence = setup["sentence"].format(LOAD_HEIGHT=LOAD_HEIGHT, W=W_WALL + W_BEAM)
    setup_base = setup["base"]
    return f"""# {title}
# Reproduces: Lourenco, Oliveira, Roca, Orduna, "Dry joint stone masonry walls subjected to in-plane combined loading",
#   J. Struct. Eng. 131(11) 2005: dry-joint sandstone wall 1000 x 1000 x 200 mm, blocks 200 x 100 x 200 mm, running
#   bond, RC beam on top free to rotate, bottom-left block restrained against sliding; N = {r['N_kN']} kN
#   (sigma = {r['sigma_MPa']} MPa), then horizontal displacement of the beam until well past peak.
#   Measured peak {r['experiment_kN']} kN; published FDEM [K25] {r['fdem_k25_kN']} kN (reference.csv, cases/README.md §A).
# Model (cases/README.md 'A 3D test as a 2D model'): {setup_base}; the beam is tied to the top course; N is a force on beam_top and the self-weight of wall and beam
#   ({W_WALL:.1f} + {W_BEAM:.1f} N, gravity on) acts in addition, so the base carries N + {W_WALL + W_BEAM:.1f} N. {setup_sentence}
{variant_text}
# Assumed values (not published): Poisson 0.2, density 2400 kg/m^3 (cases/README.md §A); beam 200 mm deep and base 100 mm deep,
#   both concrete with E = 1 GPa (elastic, no cracking); loading rate {s['rate']} m/s up to {s['until'] * 1000:g} mm{past_peak_sentence(s)};
#   local damping 0.8 in the precompression stage and {s['damping']} in the shear stage; the numerical settings
#   above are the same for all four walls.
# Run:  ./run.sh cases/lourenco2005/{fname}   or the family: tools/fdem-tools validate cases/lourenco2005
# Generated by cases/lourenco2005/make_cases.py from reference.csv.
"""


def k25_case(r, quick=False):
    N = float(r["N_kN"]) * 1e3
    E = float(r["E_wall_k25_MPa"]) * 1e6
    s = K25_QUICK if quick else K25
    fname = f"k25_N{r['N_kN']}_quick.toml" if quick else f"k25_N{r['N_kN']}.toml"
    variant = f"""# Variant [K25]: the blocks take the wall modulus calibrated per precompression in [K25] (E = {r['E_wall_k25_MPa']} MPa at
#   this N) and may crack (cohesive elements on every edge inside a block: f_t 3.7 MPa, c 5.2 MPa, G_I 110 N/m,
#   G_II 770 N/m, friction 35 deg, residual 35 deg), inserted where the traction of the block's stress on an edge reaches
#   the strength (insertion = "extrinsic", fracture/README.md: until then the block is one continuum of modulus E);
#   joints between blocks and at the base are dry (f_t = c = 0), friction 31.8 deg, contact penalty
#   p_n = {s['contact_penalty']:g} Pa (assumed; the crack faces' contact_penalty too: with the potential contact the joint's
#   normal stiffness is of order 6 p_n / h = 2.4e11 Pa/m at 25 mm, 30 times the 3DEC k_n of reference.csv; 1e10 Pa gave
#   the same curve with a 3.2 times smaller step, RESULTS.md §29). The joint penalty
#   p_j of the blocks is penalty = "auto" with penalty_ref = {s['penalty']:g} Pa: max(p_ref, 1.5 p_G), p_G the least
#   value the fracture-energy check allows at the longest block edge (fracture/README.md "Mesh-aware penalty"). At
#   the 25 mm mesh (longest edge 34.2 mm, 1.5 p_G = 8.5e9 Pa) that is {s['penalty']:g} Pa, the fixed value these cases
#   had (`fdem check` prints it); coarser meshes of a mesh study get the stiffer joint the check needs (0.05 m:
#   1.54e10 Pa, 0.1 m: 2.49e10 Pa) instead of failing.
# Mesh: {s['mesh'] * 1000:g} mm in the blocks (the [K25] size, from the single-stone study), 100 mm in the beam and base.
{{settings_text}}"""
    if quick:
        settings_text = f"""# QUICK SETTING, for the default ./run.sh (under a minute on 2 threads): the family's settings (k25_N{r['N_kN']}.toml:
#   contact dashpots {s['contact_damping']}, shear-stage local damping {s['damping']}, {s['rate']} m/s to {s['until'] * 1000:g} mm after a
#   {s['drive_ramp']} s ramp) with per-node mass scaling ([numerics] mass_scale = {s['mass_scale']}, mass_scaling = "per_node"; gravity keeps
#   the physical mass): every inertial mass x {s['mass_scale']}, the time step {s['safety']} of the triangles' limit at that, and the
#   nodes whose triangles and contact springs (the joint penalty) together would need a smaller step made heavier until
#   they do not (total inertial mass x 2.69 over x {s['mass_scale']}): 23,769 steps. Against this wall's converged curve with
#   this set-up (uniform mass scaling 10 at half the rate, RESULTS.md §43, §45): peak +0.04 %, K_e +3.0 %, P_y -0.0 %,
#   ductility +2.9 %, whole curve 0-10 mm RMS 0.88 % of the peak (§42: the same measures with the set-up of seeds/004). It stops at {s['until'] * 1000:g} mm, before the wall's peak (about 47.5 kN near 16 mm, k25_N100.toml): the run
#   says so. The family report is the validation; this is its fast preview."""
    else:
        settings_text = f"""# Mass scaling: per node ([numerics] mass_scale = {s['mass_scale']}, mass_scaling = "per_node"; gravity keeps the physical
#   mass): every inertial mass x {s['mass_scale']}, the time step {s['safety']} of the triangles' limit at that (~4e-5 s instead of
#   ~5.4e-6 s unscaled), and the nodes whose triangles and contact springs together would need a smaller step made
#   heavier until they do not
#   (RESULTS.md §33, §34; uniform x 10, the setting before, needed 2.2-2.6 times the steps for the same curve). Shear stage: contact dashpots at {s['contact_damping']} of critical (stage key
#   contact_damping): without them the contacts chatter at the step's frequency and the blocks' vibrations make the
#   joints creep, so the load kept falling as the rate was halved (RESULTS.md §5). And local damping {s['damping']}: the
#   load at the top of the wall excites a 25 Hz vertical oscillation of wall and beam that grows from 4-7 mm on and
#   that the dashpots do not reach (RESULTS.md §6.2); {s['damping']} removes it. Signed by the absolute velocity
#   (-alpha |f| sign v) it carried a load of its own, since the oscillation rides on the drive's motion (RESULTS.md §7);
#   signed by v minus its moving mean over {s['ld_filter']} s (local_damping_filter) it damps the oscillation and leaves
#   the drive's steady motion alone (RESULTS.md §8). Its share of the loading work is in the family report."""
    variant = variant.replace("{settings_text}", settings_text)
    text = header(f"Dry-joint sandstone wall, N = {r['N_kN']} kN, [K25]-style FDEM (block cracking, wall modulus)", r, variant, s, fname,
                  SETUP_FAMILY)
    text += f"""[case]
name = "lourenco2005_k25_N{r['N_kN']}{'_quick' if quick else ''}"
description = "Dry-joint sandstone wall (Lourenco 2005), N = {r['N_kN']} kN, [K25] style: per-wall modulus, cracking blocks{' (QUICK setting: mass scaling ' + str(s['mass_scale']) + ' per node)' if quick else ''}"
thickness = 0.2          # m
plane = "stress"

""" + COMMON_GEOMETRY.format(mesh=s["mesh"]) + f"""
[materials.stone]
E = {E:.4g}              # Pa, [K25] wall modulus at N = {r['N_kN']} kN
nu = 0.2                 # assumed
density = 2400.0         # kg/m^3, assumed
  [materials.stone.fracture]
  tensile_strength = 3.7e6   # Pa
  cohesion = 5.2e6           # Pa
  friction = 35.0            # deg
  residual_friction = 35.0   # deg
  GI = 110.0                 # J/m^2
  GII = 770.0                # J/m^2
  penalty = "auto"           # joint penalty p_j from the element size (see the header)
  penalty_ref = {s['penalty']:g}      # Pa, the least p_j (assumed): p_j at the 25 mm mesh
  insertion = "extrinsic"    # a block is one continuum until an edge reaches the strength (see the header)
  contact_penalty = {s['contact_penalty']:g}   # Pa, the crack faces' contact penalty (assumed, as the dry joints')
"""
    interfaces = f"""[[interfaces]]           # dry joints between blocks
regions = ["units", "units"]
kind = "dry"
friction = 31.8          # deg
normal_penalty = {s['contact_penalty']:g}  # Pa (assumed)

[[interfaces]]           # dry joint between the bottom course and the base
regions = ["units", "base"]
kind = "dry"
friction = 31.8          # deg
normal_penalty = {s['contact_penalty']:g}  # Pa (assumed)
"""
    numerics = f"""[numerics]
mass_scale = {s['mass_scale']}          # inertial mass multiplier, see the header
"""
    if s.get("mass_scaling"):
        numerics += f"""mass_scaling = "{s['mass_scaling']}"   # see the header
"""
    if s.get("safety"):
        numerics += f"""safety = {s['safety']}            # fraction of the stable step, see the header
"""
    W = W_WALL + W_BEAM
    text += COMMON_TAIL.format(**setup_text(SETUP_FAMILY, s), interfaces=interfaces, numerics=numerics, exp_N=float(r["experiment_kN"]) * 1e3,
                               N=r["N_kN"], F_top=f"{-N:.1f}", W=W, until=s["until"], damping=s["damping"], pre_ramp=s["pre_ramp"], pre_max=s["pre_max"], snapshots=s["snapshots"],
                               rate=s["rate"], contact=contact_line(s), ldf=ldf_line(s), past_peak=past_peak_line(s))
    return fname, text


def dec_case(r):
    N = float(r["N_kN"]) * 1e3
    s = DEC
    kn = float(r["kn_3dec_N_per_mm3"]) * 1e9   # N/mm^3 -> Pa/m
    ks = float(r["ks_3dec_N_per_mm3"]) * 1e9
    fname = f"dec_N{r['N_kN']}.toml"
    variant = f"""# Variant 3DEC style (Bui et al. 2017): elastic blocks with the stone modulus E = 15.5 GPa, no block cracking, and
#   the joint compliance in measured joint stiffnesses k_n = E_b E_m / ((E_b - E_m) h_b) = {r['kn_3dec_N_per_mm3']} N/mm^3,
#   k_s = k_n / (2 (1 + nu)) = {r['ks_3dec_N_per_mm3']} N/mm^3 (h_b = 100 mm, E_m = {r['E_wall_k25_MPa']} MPa), friction 32 deg,
#   on the joints between blocks and at the base.
# Mesh: {s['mesh'] * 1000:g} mm in the blocks (elastic blocks need no crack resolution), 100 mm in the beam and base.
# Shear stage: local damping {s['damping']} signed by v minus its moving mean over {s['ld_filter']} s (local_damping_filter), so that
#   it damps vibrations and not the drive's steady motion, and contact dashpots at {s['contact_damping']} of critical
#   (contact_damping); without them the 30 kN wall's first peak was dynamic (RESULTS.md §8.5)."""
    text = header(f"Dry-joint sandstone wall, N = {r['N_kN']} kN, 3DEC-style model (stone modulus, joint stiffness)", r, variant, s, fname,
                  SETUP_FAMILY)
    text += f"""[case]
name = "lourenco2005_dec_N{r['N_kN']}"
description = "Dry-joint sandstone wall (Lourenco 2005), N = {r['N_kN']} kN, 3DEC style: E 15.5 GPa, joint k_n/k_s"
thickness = 0.2          # m
plane = "stress"

""" + COMMON_GEOMETRY.format(mesh=s["mesh"]) + """
[materials.stone]
E = 1.55e10              # Pa, Bui et al. 2017
nu = 0.2
density = 2400.0         # kg/m^3, assumed
"""
    interfaces = f"""[[interfaces]]           # dry joints between blocks
regions = ["units", "units"]
kind = "dry"
friction = 32.0          # deg
normal_stiffness = {kn:.4g}   # Pa/m ({r['kn_3dec_N_per_mm3']} N/mm^3)
shear_stiffness = {ks:.4g}    # Pa/m ({r['ks_3dec_N_per_mm3']} N/mm^3)

[[interfaces]]           # dry joint between the bottom course and the base
regions = ["units", "base"]
kind = "dry"
friction = 32.0          # deg
normal_stiffness = {kn:.4g}   # Pa/m
shear_stiffness = {ks:.4g}    # Pa/m
"""
    W = W_WALL + W_BEAM
    text += COMMON_TAIL.format(**setup_text(SETUP_FAMILY, s), interfaces=interfaces, numerics="", exp_N=float(r["experiment_kN"]) * 1e3,
                               N=r["N_kN"], F_top=f"{-N:.1f}", W=W, until=s["until"], damping=s["damping"], pre_ramp=s["pre_ramp"], pre_max=s["pre_max"], snapshots=s["snapshots"],
                               rate=s["rate"], contact=contact_line(s), ldf=ldf_line(s), past_peak=past_peak_line(s))
    return fname, text


# Single stone in tension (cases/README.md §A2): the joint penalty must satisfy the fracture-energy check at the coarsest
# mesh (100 mm: p_j > 4 h f_t^2 / (3 G_I) = 2.3e10 Pa for its 141 mm diagonal edges), so the study uses 3e10 Pa at
# every size. The time step is the automatic one at the default safety (0.8 x the stable limit of each mesh, which
# scales with h: node mass ~ h^2, spring p_j t). Until 28 Nov each case fixed numerics.dt = 0.7 x an estimate of its
# own mesh's limit, which a mesh study (--set geometry.mesh_size) then kept at the finer sizes, beyond their limit
# (issue 51); then safety 0.7 of the separate limits, and since the assembled nodal bound (issue 50) the default: the
# peaks moved by less than 0.001 % at all four sizes, with 30-38 % fewer steps (RESULTS.md §45).
# Local damping 0.8 in the pull: the bar stores f_t^2 V / (2E) = 35.6 J at peak, 16 x G_I A, and a displacement-driven
# bar this much longer than its characteristic length snaps back; undamped, the released energy shattered it (many
# broken elements, the 10 mm mesh inverting a triangle; RESULTS.md E4). Damped, one crack forms and the damping takes
# the released elastic energy (RESULTS.md §10).
STONE = dict(penalty=3.0e10, rate=0.01, until=0.0015, damping=0.8)
STONE_SIZES = [(0.1, "100mm"), (0.05, "50mm"), (0.025, "25mm"), (0.01, "10mm")]


def stone_case(h, tag):
    fname = f"stone_tension_{tag}.toml"
    text = f"""# Single sandstone unit in uniaxial tension, mesh {h * 1000:g} mm (mesh sensitivity, cases/README.md §A2)
# Reproduces: the single-stone study of [K25] that chose the 25 mm mesh of the walls (sizes 100, 50, 25, 10 mm: 1, 2,
#   4 and 10 triangles across the 100 mm edge). Closed-form checks (cases/README.md §C): peak force f_t A = 3.7e6 x 0.1 x 0.2
#   = 74.0 kN; energy dissipated at full separation G_I A = 110 x 0.02 = 2.2 J; characteristic length
#   E G_I / f_t^2 = {7.68e8 * 110 / 3.7e6 ** 2 * 1000:.2f} mm.
# Model: one block 200 x 100 mm (thickness 200 mm), cohesive elements on every inner edge (f_t 3.7 MPa, c 5.2 MPa,
#   G_I 110 N/m, G_II 770 N/m, friction 35 deg), left edge fixed, right edge pulled at {STONE['rate']} m/s to
#   {STONE['until'] * 1000:g} mm (the elastic elongation at peak is f_t L / E = 0.96 mm).
# Assumed values: E = 768 MPa (the [K25] modulus of the 100 kN wall), Poisson 0.2, density 2400 kg/m^3, joint penalty
#   p_j = {STONE['penalty']:g} Pa at every size (see make_cases.py), the automatic time step, local damping {STONE['damping']}: the bar
#   stores f_t^2 V / (2E) = 35.6 J at peak, 16 x G_I A, and snaps back after the peak; the damping takes that energy
#   so that one crack forms (undamped, the release shattered the bar: RESULTS.md E4 and §10).
# Report per size: peak of R_left (N), D_frac at the end (J, history.csv), run time (measured: RESULTS.md §10;
#   the 50 mm mesh peaks 5.1 % above f_t A, just outside the 5 % tolerance below: a mesh study, not a failure).
# Run:  ./run.sh cases/lourenco2005/{fname}
# Generated by cases/lourenco2005/make_cases.py.
[case]
name = "stone_tension_{tag}"
description = "Single sandstone unit in tension, mesh {h * 1000:g} mm"
thickness = 0.2          # m
plane = "stress"

[geometry]
type = "rectangle"
width = 0.2              # m
height = 0.1             # m
mesh_size = {h}          # m

[materials.stone]
E = 7.68e8               # Pa
nu = 0.2
density = 2400.0         # kg/m^3
  [materials.stone.fracture]
  tensile_strength = 3.7e6   # Pa
  cohesion = 5.2e6           # Pa
  friction = 35.0            # deg
  residual_friction = 35.0   # deg
  GI = 110.0                 # J/m^2
  GII = 770.0                # J/m^2
  penalty = {STONE['penalty']:g}         # Pa

[regions]
body = "stone"

[[monitors]]
name = "u_right"         # m
type = "displacement"
group = "right"
component = "x"

[[monitors]]
name = "R_left"          # N
type = "reaction"
group = "left"
component = "x"

[output]
history_interval = 0.0005  # s
curve = {{ x = "u_right", y = "R_left" }}

[reference]
monitor = "R_left"
quantity = "first_peak"      # the tensile strength: the peak before the first cohesive break, not the ringing after it
value = 74.0e3           # N, f_t A
tolerance = 0.05
source = "closed form f_t A (cases/README.md §C)"

[[stages]]
name = "pull"
until = {{ monitor = "u_right", value = {STONE['until']} }}
local_damping = {STONE['damping']}     # takes the elastic energy released after the peak (see the header)
  [[stages.supports]]
  group = "left"
  fix = "xy"
  [[stages.supports]]
  group = "right"
  vx = {STONE['rate']}            # m/s
  ramp = 0.005           # s
"""
    return fname, text


def main():
    for r in rows():
        for make in (k25_case, dec_case):
            fname, text = make(r)
            with open(os.path.join(HERE, fname), "w") as f:
                f.write(text)
            print("wrote", fname)
        if r["N_kN"] == "100":  # the default ./run.sh case
            fname, text = k25_case(r, quick=True)
            with open(os.path.join(HERE, fname), "w") as f:
                f.write(text)
            print("wrote", fname)
    for h, tag in STONE_SIZES:
        fname, text = stone_case(h, tag)
        with open(os.path.join(HERE, fname), "w") as f:
            f.write(text)
        print("wrote", fname)


if __name__ == "__main__":
    main()
