#!/usr/bin/env python3
"""Writes the M-DEM macro-block case files of cases/jrc_ispra/ (issue 29): the JRC Ispra piers LW and HW under the
cyclic displacement history at the three element sizes of seeds/000 (0.05, 0.10, 0.20 m), and a monotonic pushover of
each at 0.10 m (the macro side of the speed-against-error comparison with the micro-models, make_micro.py).

/usr/bin/python3 cases/jrc_ispra/make_cases.py
"""
import csv
import os

HERE = os.path.dirname(os.path.abspath(__file__))


def read_reference():
    """The piers' test data (cases/README.md §D) and seeds/000's M-DEM numbers, by pier: reference.csv beside this
    file, shared with make_micro.py and summarise.py."""
    with open(os.path.join(HERE, "reference.csv"), newline="") as f:
        return {r["pier"]: r for r in csv.DictReader(f)}


REF = read_reference()

RATE = 0.01          # m/s, loading rate (monotonic and every leg of the cycles)
MASS_SCALE = 1       # no mass scaling: the pier's own vibration, excited at every turn of the drive, must stay well
                     # below the loads of the small cycles. LW at 0.10 m, first 1.2 s of the history (cycles at 0.5
                     # and 1 mm): at mass scaling 1 the first leg's secant H / u is 36.7-38.6 kN/mm and H scatters by
                     # 0.58 kN (std about its 0.02 s moving mean); at mass scaling 10 the secant swings over 31-49 kN/mm
                     # and the scatter is 1.17 kN (loop tips 18.9 / 16.6 kN at 0.5 mm against 16.8 / 16.1), and local
                     # damping 0.8 does not remove it (2.45 kN); corners smoothed over 0.05 s instead of 0.01 s cut
                     # the tips to 10.8 kN (RESULTS.md)
CORNER = 0.01        # s, corner smoothing of the protocol: the velocity turns over 0.01 s (tips cut by v T / 4 =
                     # 0.025 mm)
N_TOP = 150000.0     # N, sigma_0 = 0.6 MPa over 1.00 x 0.25 m

PIERS = {
    "LW": dict(height=float(REF["LW"]["height_m"]), peak=round(1e3 * float(REF["LW"]["experiment_kN"]), 6),
               k_el=float(REF["LW"]["k_el_kN_per_mm"]), label="low wall, 1.35 m: diagonal shear",
               # (amplitude m, cycles): two cycles per amplitude, three in the second-to-last phase, then a last
               # cycle at about 8 mm (0.60 % drift), as seeds/000 describes the LW protocol (its figure is lost)
               protocol=[(0.0005, 2), (0.001, 2), (0.002, 2), (0.003, 2), (0.004, 2), (0.005, 2), (0.006, 2),
                         (0.007, 3), (0.008, 1)],
               mono_until=0.008),
    "HW": dict(height=float(REF["HW"]["height_m"]), peak=round(1e3 * float(REF["HW"]["experiment_kN"]), 6),
               k_el=float(REF["HW"]["k_el_kN_per_mm"]), label="high wall, 2.00 m: flexure and rocking",
               # two cycles per amplitude up to about 13 mm (0.65 % drift), seeds/000 (its figure is lost)
               protocol=[(0.0005, 2), (0.001, 2), (0.002, 2), (0.003, 2), (0.004, 2), (0.006, 2), (0.008, 2),
                         (0.010, 2), (0.012, 2), (0.013, 2)],
               mono_until=0.013),
}
SIZES = {"EL005": 0.05, "EL010": 0.10, "EL020": 0.19}  # m; EL020 at 0.19 m: at 0.20 m (and 0.17, 0.21) Gmsh leaves a
                                                     # 7.6-8.4 deg sliver in a side block next to a key's corner


def protocol_points(protocol, rate):
    """[[t, u], ...] of the cycles 0 -> +a -> 0 -> -a -> 0 at the given rate, t from the stage start."""
    t, pts = 0.0, [[0.0, 0.0]]
    for a, n in protocol:
        for _ in range(n):
            for u in (a, 0.0, -a, 0.0):
                t += abs(u - pts[-1][1]) / rate
                pts.append([round(t, 6), u])
    return pts


def header(pier, el, cyclic):
    p = PIERS[pier]
    drift = (p["protocol"][-1][0] if cyclic else p["mono_until"]) / p["height"] * 100
    amps = ", ".join(f"{a * 1e3:g} mm x {n}" for a, n in p["protocol"])
    loading = (f"""# Loading: stage 1 puts 150 kN (sigma_0 = 0.6 MPa) on the beam's top and damps the pier to rest; stage 2 drives the whole
#   beam horizontally by the cyclic history and keeps it horizontal (rigid = "y": its nodes share one vertical
#   velocity, so the beam cannot rotate and moves up and down under the constant 150 kN), the "fixed-fixed" set-up of
#   the test. History (our reading: seeds/000 describes it, its Fig. 2(b)(c) with the amplitudes is lost from the text
#   copy), cycles 0 -> +a -> 0 -> -a -> 0 at {RATE} m/s, corners smoothed over {CORNER} s: {amps}
#   (to {drift:.2f} % drift). The other reading (amplitudes doubling: 0.5, 1, 2, 4, 8 ... mm) is in RESULTS.md.
#   Read the loops with: tools/fdem-tools hysteresis RUN --stage 2 --k-el ... (RESULTS.md)""" if cyclic else
               f"""# Loading: stage 1 puts 150 kN (sigma_0 = 0.6 MPa) on the beam's top and damps the pier to rest; stage 2 drives the whole
#   beam horizontally at {RATE} m/s to {p['mono_until'] * 1e3:g} mm ({drift:.2f} % drift) and keeps it horizontal (rigid = "y": its nodes share one
#   vertical velocity, so the beam cannot rotate and moves up and down under the constant 150 kN): the envelope of
#   the cyclic test, for the speed-against-error comparison with micro_{pier}.toml (RESULTS.md).""")
    return f"""# JRC Ispra {p['label']} (cases/README.md §D), as M-DEM macro-blocks (issue 29), element size {SIZES[el]:g} m
#   ({el} of seeds/000), {'cyclic' if cyclic else 'monotonic'}.
# Reproduces: Anthoine, Magonette, Magenes 1995, JRC Ispra piers (cases/README.md §D), modelled as in the M-DEM paper
#   (seeds/000): double-wythe clay brick pier, English bond, 1.00 m long, 0.25 m thick, {p['height']:g} m high, fixed-fixed
#   between a top steel beam and an RC foundation; sigma_0 = 0.6 MPa = 150 kN on the beam. Measured: peak base shear
#   {p['peak'] / 1e3:.2f} kN, k_el {p['k_el']} kN/mm (secant at 10 % of the peak).
# Geometry (mesh/macro.hpp): diagonal joints at the texture angle 28 deg, a central vertical joint and two 50 mm
#   horizontal joints. Region pairs: (cap, side) diagonal, (side, side) vertical, (key, side) horizontal, (cap, key)
#   tied (the key is part of its cap block), (beam, cap) and (base, cap) the bed joints at the top and bottom of the
#   pier. The vertical joint of this layout is longer than the paper's (LW 0.845 m against 0.4 m; mesh/macro.hpp).
# Values, seeds/000 Table 1 as read here (the extraction garbled its header: 14 numbers under 15 units):
#   E_m 1491 MPa, G_m 596 MPa -> nu = E/(2G) - 1 = 0.2508; k_n 14.91, k_s 5.96 printed in "MPa/m", read as GPa/m
#   (= E_m / 0.1 m and G_m / 0.1 m, the element length; MPa/m would be 1000 times softer than the blocks);
#   f_c 6.20 MPa; bed joints: tan(phi) 0.58 (phi 30.11 deg), c 0.23 MPa; diagonal joints: c 0.66 MPa, f_t 0.33 MPa,
#   phi 58.15 deg; vertical joints: c = f_t = 1.32 MPa; G_c 6.20 N/mm = 6200 J/m^2. The joints: Mohr-Coulomb with a
#   tension cut-off, no softening (law = "mohr_coulomb"); the blocks crush by linear softening in compression,
#   regularised by G_c and the element size ([materials.masonry.crushing], fdem/plasticity.hpp).
# Assumed (not legible or not given): the bed joints' f_t = 0.115 MPa (= c / 2, the ratio of the diagonal joints'
#   f_t / c, whose values derive from the bed joints'); the vertical joints' friction = the bed joints' 30.11 deg;
#   masonry density 1800 kg/m^3; steel beam 0.20 m deep, E 210 GPa; RC foundation 0.30 m deep with 0.20 m overhang,
#   E 30 GPa; both elastic.
{loading}
# Numerics: no mass scaling (mass_scale = {MASS_SCALE}: at 10 the pier's vibration, excited at every turn of the drive,
#   scatters H by twice as much in the small cycles, RESULTS.md), local damping 0.8
#   while precompressing, 0.05 while shearing, signed against the velocities' moving mean over 0.1 s (as the
#   other families).
# Run: ./run.sh cases/jrc_ispra/{case_name(pier, el, cyclic)}.toml
# Generated by cases/jrc_ispra/make_cases.py.
"""


def case_name(pier, el, cyclic):
    return f"macro_{pier}_{el}" if cyclic else f"macro_{pier}_mono"


def mc(comment, ft, c, phi):
    return f"""[[interfaces]]           # {comment}
regions = {{regions}}
kind = "bonded"
law = "mohr_coulomb"
tensile_strength = {ft:g}  # Pa
cohesion = {c:g}          # Pa
friction = {phi}           # deg
normal_stiffness = 1.491e10  # Pa/m
shear_stiffness = 5.96e9     # Pa/m
"""


def interfaces():
    out = []
    for regions, comment, ft, c, phi in [
            ('["cap", "side"]', "diagonal joints", 0.33e6, 0.66e6, 58.15),
            ('["side", "side"]', "central vertical joint (friction assumed: the bed joints')", 1.32e6, 1.32e6, 30.11),
            ('["key", "side"]', "the two short horizontal joints (bed joint values; f_t assumed)", 0.115e6, 0.23e6,
             30.11),
            ('["beam", "cap"]', "bed joint under the beam (top course; f_t assumed)", 0.115e6, 0.23e6, 30.11),
            ('["base", "cap"]', "bed joint on the foundation (bottom course; f_t assumed)", 0.115e6, 0.23e6, 30.11)]:
        out.append(mc(comment, ft, c, phi).replace("{regions}", regions))
        if regions == '["key", "side"]':
            out.append('[[interfaces]]           # each key is part of its cap block\n'
                       'regions = ["cap", "key"]\nkind = "tied"\n')
    return "\n".join(out)


def stage2(pier, cyclic):
    p = PIERS[pier]
    if cyclic:
        pts = protocol_points(p["protocol"], RATE)
        duration = pts[-1][0] + 2 * CORNER
        rows = ",\n      ".join(", ".join(f"[{t:g}, {u:g}]" for t, u in pts[i:i + 4]) for i in range(0, len(pts), 4))
        return f"""[[stages]]
name = "cyclic"          # the displacement history of the header
duration = {duration:.4f}       # s: the protocol's time + the corner lag
local_damping = 0.05
local_damping_filter = 0.1  # s: damping signed by v minus its moving mean
  [[stages.supports]]
  group = "beam"         # driven horizontally, kept horizontal (rigid in y), free to move vertically under N
  rigid = "y"
  protocol = {{ component = "x", points = [
      {rows}] }}
  ramp = {CORNER}            # s, corner smoothing (see the header)
"""
    return f"""[[stages]]
name = "shear"           # monotonic pushover
until = {{ monitor = "u_top", value = {p['mono_until']} }}
local_damping = 0.05
local_damping_filter = 0.1  # s: damping signed by v minus its moving mean
  [[stages.supports]]
  group = "beam"         # driven horizontally, kept horizontal (rigid in y), free to move vertically under N
  vx = {RATE}              # m/s
  rigid = "y"
  ramp = 0.05            # s
"""


def case(pier, el, cyclic):
    p = PIERS[pier]
    size = SIZES[el]
    name = case_name(pier, el, cyclic)
    snap = 0.1  # s: 1 mm of drive between snapshots
    return header(pier, el, cyclic) + f"""[case]
name = "jrc_ispra_{name}"
description = "JRC Ispra {pier} pier as M-DEM macro-blocks, {size:g} m elements, {'cyclic' if cyclic else 'monotonic'}"
thickness = 0.25         # m
plane = "stress"

[geometry]
type = "macro"
length = 1.0             # m
height = {p['height']:g}            # m
texture_angle = 28.0     # deg (seeds/000)
horizontal_joint = 0.05  # m (seeds/000: 50 mm)
mesh_size = {size:g}          # m ({el})
beam_height = 0.2        # m (assumed)
base_height = 0.3        # m (assumed)
base_overhang = 0.2      # m (assumed)
mesh_size_beam = {max(size, 0.1):g}     # m
mesh_size_base = {max(size, 0.15):g}    # m

[materials.masonry]
E = 1.491e9              # Pa, E_m
nu = 0.2508              # from G_m = 596 MPa
density = 1800.0         # kg/m^3, assumed
  [materials.masonry.crushing]
  compressive_strength = 6.2e6   # Pa, f_c
  Gc = 6200.0                    # J/m^2, G_c

[materials.steel]
E = 2.1e11               # Pa, assumed
nu = 0.3
density = 7850.0         # kg/m^3

[materials.concrete]
E = 3.0e10               # Pa, assumed
nu = 0.2
density = 2400.0         # kg/m^3

[regions]
cap = "masonry"
side = "masonry"
key = "masonry"
beam = "steel"
base = "concrete"

{interfaces()}
[[monitors]]
name = "u_top"           # m, horizontal displacement of the beam
type = "displacement"
group = "beam"
component = "x"

[[monitors]]
name = "H"               # N, horizontal reaction of the driven beam: the base shear
type = "reaction"
group = "beam"
component = "x"

[[monitors]]
name = "V_base"          # N, vertical reaction of the foundation
type = "reaction"
group = "base_bottom"
component = "y"

[[monitors]]
name = "v_top"           # m, vertical displacement of the beam
type = "displacement"
group = "beam"
component = "y"

[numerics]
mass_scale = {MASS_SCALE}          # inertial mass multiplier (see the header)

[output]
history_interval = 0.002   # s
snapshot_interval = {snap}    # s
curve = {{ x = "u_top", y = "H" }}

[reference]
monitor = "H"
quantity = "peak"
value = {p['peak']:g}          # N
tolerance = 0.10
source = "Anthoine, Magonette, Magenes 1995, pier {pier} (the M-DEM paper's results table, cases/README.md §D)"

[[stages]]
name = "precompression"  # 150 kN on the beam, damped to rest
max_duration = 0.3       # s
equilibrium = 1e-3
local_damping = 0.8
gravity = [0.0, -9.81]   # m/s^2
gravity_ramp = 0.05      # s
  [[stages.supports]]
  group = "base_bottom"
  fix = "xy"
  [[stages.loads]]
  group = "beam_top"
  force = [0.0, -{N_TOP:g}]  # N
  ramp = 0.05            # s

{stage2(pier, cyclic)}"""


def main():
    written = []
    for pier in PIERS:
        for el in SIZES:
            written.append((case_name(pier, el, True), case(pier, el, True)))
        written.append((case_name(pier, "EL010", False), case(pier, "EL010", False)))
    for name, text in written:
        with open(os.path.join(HERE, name + ".toml"), "w") as f:
            f.write(text)
        print("wrote", name + ".toml")


if __name__ == "__main__":
    main()
