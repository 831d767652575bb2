#!/usr/bin/env python3
"""Writes the micro-model cases of the JRC Ispra piers (cases/README.md §D): micro_LW.toml and micro_HW.toml.

The "micro-model" side of the speed-against-error comparison with the macro-block (M-DEM) cases: a simplified
micro-model as the Vermeltfoort walls (cases/vermeltfoort/make_cases.py), monotonic pushover (not cyclic).

/usr/bin/python3 cases/jrc_ispra/make_micro.py
"""
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

# --- test (cases/README.md §D; Anthoine, Magonette, Magenes 1995) ---
LENGTH = 1.00          # m
THICKNESS = 0.25       # m
N = 150.0e3            # N, sigma_0 0.6 MPa x 1.00 x 0.25 m
UNIT_L = 0.25          # m, stretcher length seen in the elevation
UNIT_H = 0.055         # m
sys.path.insert(0, HERE)
from make_cases import read_reference  # noqa: E402  (the piers' test data: reference.csv)

REF = read_reference()
PIERS = {
    # name: height (m), courses, measured peak (N), measured stiffness (kN/mm), failure, end of the pushover (m)
    name: dict(height=float(REF[name]["height_m"]), courses=courses, peak=round(1e3 * float(REF[name]["experiment_kN"]), 6),
               stiffness=float(REF[name]["k_el_kN_per_mm"]), until=until, failure=failure)
    for name, courses, until, failure in (
        ("LW", 21, 0.008, "diagonal shear"),
        ("HW", 31, 0.013, "flexure and rocking (bed joints of the top and bottom courses open)"))
}

# --- masonry (seeds/000 Table 1 as read in macro_LW_EL010.toml) ---
E_M = 1.491e9          # Pa, masonry modulus
G_M = 596e6            # Pa -> nu = E/(2G) - 1 = 0.2508
NU = 0.25
F_C = 6.2e6            # Pa, masonry compressive strength: cap f_m of the joints
G_C = 6200.0           # J/m^2, cap G_c
COHESION = 0.23e6      # Pa, bed joints
TAN_PHI = 0.58
FRICTION = math.degrees(math.atan(TAN_PHI))   # 30.11 deg
F_T = 0.115e6          # Pa, assumed c / 2 (as macro_LW_EL010.toml)

# --- assumed values (see the header) ---
E_U = 2.0 * E_M        # Pa, brick modulus: 2 E_m (assumed)
DENSITY = 1800.0       # kg/m^3
GI = 12.0              # J/m^2, joints (the Vermeltfoort case's values, Pulatsu et al.)
GII = 125.0            # J/m^2
C_S = 9.0              # -, cap shear factor (Lourenco & Rots 1997; the Vermeltfoort cases)
BRICK_FT = 2.0e6       # Pa, brick mid-line crack (the Vermeltfoort case's values)
BRICK_C = 2.8e6        # Pa, 1.4 f_t
BRICK_FRICTION = 45.0  # deg
BRICK_GI = 80.0        # J/m^2
BRICK_GII = 500.0      # J/m^2
BRICK_PENALTY = 10.0 * E_U  # Pa (assumed; the Vermeltfoort cases use 3 E with a 5.6 x stiffer brick)
STEEL_E = 2.1e11       # Pa, as the macro case
CONCRETE_E = 3.0e10    # Pa, as the macro case
BEAM_H = 0.20          # m, as the macro case
BASE_H = 0.30          # m
BASE_OVERHANG = 0.20   # m
MESH = 0.0275          # m, two elements over a brick's height
MESH_BEAM = 0.1        # m
MESH_BASE = 0.15       # m

# --- numerics (as the Vermeltfoort cases) ---
RATE = 0.01            # m/s
DAMPING = 0.8          # precompression
DAMPING_SHEAR = 0.05   # shear, signed against the velocities' moving mean over DAMPING_FILTER
DAMPING_FILTER = 0.1   # s
BRICK_VISCOUS = 0.5    # fraction of critical element damping of the bricks
MASS_SCALE = 10        # inertial mass x 10: time step x 3.2; gravity keeps the physical mass


def joint(regions, comment, kn, ks):
    return f"""[[interfaces]]           # {comment}
regions = {regions}
kind = "bonded"
law = "composite"        # fracture/composite_law.hpp (see the header)
tensile_strength = {F_T:g}    # Pa (assumed: c / 2)
cohesion = {COHESION:g}          # Pa, c_0 of the bed joints (c_res = 0)
friction = {FRICTION:.2f}         # deg, tan(phi) = {TAN_PHI}, theta_0 = theta_res
GI = {GI:g}                # J/m^2 (assumed)
GII = {GII:g}               # J/m^2 (assumed)
compressive_strength = {F_C:g}  # Pa, f_m of the cap = masonry f_c
compressive_energy = {G_C:g}   # J/m^2, G_c
cap_shear_factor = {C_S:g}       # C_s (assumed)
normal_stiffness = {kn:.4g}  # Pa/m (homogenisation, see the header)
shear_stiffness = {ks:.4g}   # Pa/m
"""


def case(name, p):
    courses = p["courses"]
    pitch = p["height"] / courses                 # course pitch = unit height + joint
    tj = pitch - UNIT_H                           # joint thickness that makes the course count whole
    angle = math.degrees(math.atan(pitch / ((UNIT_L + tj) / 2)))
    kn = E_U * E_M / (pitch * (E_U - E_M))        # Pa/m, so that bricks + joints in series give E_m over a course
    ks = kn / (2 * (1 + NU))
    kn_tj = E_U * E_M / (tj * (E_U - E_M))        # the same formula over the joint thickness (not used)
    beam_w = 9.81 * 7850.0 * LENGTH * BEAM_H * THICKNESS
    wall_w = 9.81 * DENSITY * LENGTH * p["height"] * THICKNESS
    f_top = -(N - beam_w)
    stiff_k = 1.0 / (p["height"] ** 3 / (E_M * THICKNESS * LENGTH ** 3) + 1.2 * p["height"] / (G_M * THICKNESS * LENGTH))
    stem = f"micro_{name}"
    joints = "\n".join(joint(reg, c, kn, ks) for reg, c in (
        ('["units", "units"]', "unit-mortar joints (bed and head)"),
        ('["units", "base"]', "bed joint on the foundation"),
        ('["units", "beam"]', "bed joint under the steel beam")))
    return stem, f"""# JRC Ispra pier {name} as a simplified micro-model (bricks + bonded mortar joints), monotonic pushover.
# Reproduces: Anthoine, Magonette, Magenes 1995, cases/README.md §D: double-wythe solid clay brick pier, English bond,
#   units 250 x 120 x 55 mm, 10 mm joints, {LENGTH:.2f} m long, {THICKNESS} m thick, {p['height']:.2f} m high, fixed-fixed between a steel
#   top beam (kept horizontal) and an RC foundation; sigma_0 = 0.6 MPa = 150 kN. Measured (cyclic test): peak base
#   shear {p['peak'] / 1e3:.2f} kN, elastic stiffness {p['stiffness']} kN/mm (secant at 10 % of the peak); fails by {p['failure']}.
#   The micro-model side of the speed-against-error comparison with the macro-block cases (macro_{name}_mono.toml and macro_{name}_EL0*.toml):
#   a MONOTONIC pushover to {p['until'] * 1e3:g} mm (the test was cyclic; its envelope is the comparison).
# Geometry: English bond idealised in 2D: the elevation shows 250 mm stretchers; modelled as a running bond of
#   250 x 55 mm units (texture angle atan(65/130) = 26.6 deg with 10 mm joints; the paper's is 28 deg). The course
#   count must be whole ({p['height']:.2f} m / 0.065 m = {p['height'] / 0.065:.2f}): the height is kept and the joints are thinner,
#   {courses} courses of pitch {pitch * 1e3:.2f} mm, joint thickness {tj * 1e3:.2f} mm (head joints too), texture angle {angle:.1f} deg.
#   Simplified micro-model: bricks expanded by half a joint, zero-thickness bonded interfaces; one potential vertical
#   crack at mid-length of every whole brick (unit_cracks = "middle", as Lourenco & Rots 1997); the rest of the
#   brick elastic. Steel beam {BEAM_H} m deep, RC base {BASE_H} m deep with {BASE_OVERHANG} m overhang, both elastic (as the macro case).
# Values from the source (seeds/000 Table 1 as read in macro_LW_EL010.toml): E_m 1491 MPa, G_m 596 MPa (nu 0.25),
#   f_c 6.2 MPa (the joints' cap f_m), G_c 6200 J/m^2 (the cap's), bed joints c 0.23 MPa, tan(phi) 0.58 ({FRICTION:.2f} deg).
# Assumed values (the sources give none):
#   - joints' tensile strength f_t 0.115 MPa = c / 2 (as the macro case header);
#   - brick E_u = 2 E_m = {E_U / 1e9:.3f} GPa, nu 0.25 (the masonry's, so G_u = E_u / 2.5 keeps G_m below);
#   - joint stiffnesses by the homogenisation of Lourenco (1996) k_n = E_u E_m / (h (E_u - E_m)) = {kn:.4g} Pa/m,
#     k_s = k_n / (2 (1 + nu)) = {ks:.4g} Pa/m, with h = the course pitch {pitch * 1e3:.2f} mm, not the joint thickness: E_m here
#     is the MASONRY modulus (the source gives no mortar modulus), and a course of brick (E_u) and joint (k_n) in
#     series then has exactly E_m = 1491 MPa and G_m = 596 MPa, the macro model's moduli (with h = t_j, k_n would be
#     {kn_tj:.3g} Pa/m and the pier {E_U * pitch / (pitch + E_U / kn_tj) / E_M:.2f} x stiffer vertically than E_m). Elastic stiffness of the fixed-fixed
#     pier with E_m, G_m (bending + shear, 1.2 h / (G A)): {stiff_k / 1e6:.1f} kN/mm against the measured {p['stiffness']};
#   - joints' G_I 12 J/m^2, G_II 125 J/m^2 and cap C_s 9: the Vermeltfoort case's values (Pulatsu et al.);
#   - brick mid-line crack: f_t 2.0 MPa, c 2.8 MPa, friction 45 deg, G_I 80 J/m^2, G_II 500 J/m^2 (the Vermeltfoort
#     case's values), no cap, penalty 10 E_u = {BRICK_PENALTY:.3g} Pa;
#   - density 1800 kg/m^3; steel beam E 210 GPa, RC foundation E 30 GPa (as the macro case).
# Boundary conditions: stage 1, N on beam_top minus the steel beam's weight ({beam_w / 1e3:.2f} kN), gravity on (the wall's own
#   weight, {wall_w / 1e3:.2f} kN, is left on top of N), damped to equilibrium. Stage 2: the whole beam driven horizontally
#   (vx = {RATE} m/s) with rigid = "y": kept horizontal (no rotation), free to move up and down, N constant; until the beam has
#   moved {p['until'] * 1e3:g} mm. Monitors: u_top, H (reaction of the beam, x), V_base, v_top.
# Numerics (as the Vermeltfoort cases): mesh {MESH * 1e3:g} mm in the units (two elements over a brick's height), local damping
#   {DAMPING} (precompression) and {DAMPING_SHEAR} against the velocities' {DAMPING_FILTER} s moving mean (shear), brick element viscous
#   damping {BRICK_VISCOUS} of critical, mass scaling x {MASS_SCALE} (gravity keeps the physical mass). No value calibrated.
# Run:  ./run.sh cases/jrc_ispra/{stem}.toml   (fdem run cases/jrc_ispra/{stem}.toml --out DIR --threads 1)
# Generated by cases/jrc_ispra/make_micro.py.
[case]
name = "jrc_ispra_{stem}"
description = "JRC Ispra {name} pier as a simplified brick micro-model, monotonic pushover"
thickness = {THICKNESS}         # m
plane = "stress"

[geometry]
type = "wall"
length = {LENGTH}             # m
courses = {courses}             # {p['height']:.2f} m with {tj * 1e3:.2f} mm joints (see the header)
unit_length = {UNIT_L}       # m
unit_height = {UNIT_H}      # m
bond = "running"         # English bond idealised in 2D (see the header)
joint = "mortar"
joint_thickness = {tj:.6f}   # m
beam_height = {BEAM_H}       # m (assumed, as the macro case)
base = "slab"
base_height = {BASE_H}       # m (assumed, as the macro case)
base_overhang = {BASE_OVERHANG}     # m (assumed, as the macro case)
mesh_size = {MESH}        # m
mesh_size_beam = {MESH_BEAM}     # m
mesh_size_base = {MESH_BASE}    # m
unit_cracks = "middle"   # one vertical potential crack per whole brick (see the header)

[materials.brick]
E = {E_U:.4g}            # Pa (assumed: 2 E_m)
nu = {NU}
density = {DENSITY}         # kg/m^3 (assumed)
viscous_damping = {BRICK_VISCOUS}    # fraction of critical element damping
  [materials.brick.fracture]
  law = "composite"          # (no cap)
  tensile_strength = {BRICK_FT:g}   # Pa (assumed)
  cohesion = {BRICK_C:g}           # Pa, 1.4 f_t (c_res = 0)
  friction = {BRICK_FRICTION}            # deg, theta_0 = theta_res
  GI = {BRICK_GI}                  # J/m^2 (assumed)
  GII = {BRICK_GII}                # J/m^2 (assumed)
  penalty = {BRICK_PENALTY:.4g}        # Pa (assumed: 10 E_u)

[materials.steel]
E = {STEEL_E:g}               # Pa (assumed)
nu = 0.3
density = 7850.0         # kg/m^3

[materials.concrete]
E = {CONCRETE_E:g}               # Pa (assumed)
nu = 0.2
density = 2400.0         # kg/m^3

[regions]
units = "brick"
beam = "steel"
base = "concrete"

{joints}
[[monitors]]
name = "u_top"           # m, horizontal displacement of the beam
type = "displacement"
group = "beam"
component = "x"

[[monitors]]
name = "H"               # N, horizontal reaction of the driven beam (base shear)
type = "reaction"
group = "beam"
component = "x"

[[monitors]]
name = "V_base"          # N
type = "reaction"
group = "base_bottom"
component = "y"

[[monitors]]
name = "v_top"           # m, vertical displacement of the beam (free in the pushover)
type = "displacement"
group = "beam"
component = "y"

[numerics]
mass_scale = {MASS_SCALE}          # inertial mass multiplier (quasi-static density scaling)

[output]
history_interval = 0.0005  # s
snapshot_interval = 0.1    # s
curve = {{ x = "u_top", y = "H" }}

[reference]
monitor = "H"
quantity = "peak"
value = {p['peak']:g}          # N
tolerance = 0.15
source = "Anthoine, Magonette, Magenes 1995, JRC Ispra {name} pier, peak base shear of the cyclic test (cases/README.md §D)"

[[stages]]
name = "precompression"  # 150 kN on the pier's top, damped to rest
equilibrium = 1e-3
max_duration = 0.4       # s
local_damping = {DAMPING}
gravity = [0.0, -9.81]   # m/s^2
gravity_ramp = 0.05      # s
  [[stages.supports]]
  group = "base_bottom"
  fix = "xy"
  [[stages.loads]]
  group = "beam_top"
  force = [0.0, {f_top:.1f}]  # N
  ramp = 0.05            # s

[[stages]]
name = "pushover"
until = {{ monitor = "u_top", value = {p['until']} }}
local_damping = {DAMPING_SHEAR}
local_damping_filter = {DAMPING_FILTER}  # s: damping signed by v minus its moving mean
  [[stages.supports]]
  group = "beam"         # driven horizontally, kept horizontal, free to move vertically (N constant)
  vx = {RATE}              # m/s
  rigid = "y"
  ramp = 0.5             # s: velocity ramp. The mass-scaled beam and wall (11.5 t) pushed to v over the ramp put
                         # M v / ramp into H: with 0.005 s up to 16.5 kN in the first 0.05 mm, with 0.05 s 2.3 kN (k_el
                         # 61.0 kN/mm against 49.4), with 0.5 s 0.23 kN, 2.5 % of the 10 % of the peak where k_el is read
"""


def main():
    for name, p in PIERS.items():
        stem, text = case(name, p)
        with open(os.path.join(HERE, stem + ".toml"), "w") as f:
            f.write(text)
        print("wrote", stem + ".toml")


if __name__ == "__main__":
    main()
