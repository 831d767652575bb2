// mesh/macro.hpp: the macro-block pier generator (M-DEM, issue 29; Gmsh C++ API, OpenCASCADE kernel).
//
// The M-DEM paper (seeds/000, "A novel macro-distinct element model (M-DEM) for the in-plane analysis of URM
// structures") cuts a masonry pier into a few deformable macro-blocks along potential failure planes set by the
// masonry texture: diagonal joints at the texture angle phi (the mean slope of the lines joining consecutive head
// joints), a central vertical joint, and two short horizontal joints (50 mm for the JRC Ispra piers) "between the
// diagonal joints and the central vertical joint, to avoid potential stress localizations". The paper's figure is
// missing from the text copy; the layout below is the simplest one consistent with that description.
//
// LAYOUT / COORDINATES (m; the pier occupies x in [0, L], y in [0, H]; t = tan(phi), w = horizontal_joint)
//   Four diagonal joints, one from each pier corner towards the centre line, each of horizontal run r = (L - w) / 2:
//     upper: (0, H) -> (r, y_t) and (L, H) -> (L - r, y_t), y_t = H - r t
//     lower: (0, 0) -> (r, y_b) and (L, 0) -> (L - r, y_b), y_b = r t
//   Two horizontal joints of length w, centred on x = L/2, joining the ends of the two upper diagonals (at y_t)
//   and of the two lower ones (at y_b); the central vertical joint x = L/2 from y_b to y_t (length H - (L - w) t).
//   The rectangle is thereby cut into four blocks: "cap" above the upper diagonals and below the lower ones (the
//   top and bottom blocks), and "side" to the left and right of the vertical joint. So that the horizontal joints
//   are told apart from the diagonals by their region pair (the side blocks border both), the cap blocks' tips above
//   and below the horizontal joints are separate "key" blocks: the triangle over the horizontal joint whose two
//   other sides continue the diagonals' slope (apex at (L/2, y_t + (w/2) t), resp. (L/2, y_b - (w/2) t)).
//   Six macro-blocks in all (two of each region); the case ties key to cap (interface kind "tied") to make the
//   cap and its key one continuum.
//   Needs H > (L - w) t (the upper and lower diagonals do not meet; squat piers need another layout) and
//   0 < w < L/2 (the keys stay inside the pier).
//   With the paper's values (L = 1.00 m, phi = 28 deg, w = 0.05 m) the vertical joint is 1.495 m long for the HW
//   pier (H = 2.00 m) and 0.845 m for LW (H = 1.35 m); the paper quotes 1.0 m and 0.4 m, so its figure draws the
//   diagonals more steeply or longer than this reading (unresolved: the figure is not in the text copy).
//   The top beam sits on y in [H, H + beam_height], x in [-beam_overhang, L + beam_overhang]; the foundation on
//   y in [-base_height, 0], x in [-base_overhang, L + base_overhang]. All blocks, beam and base are fragmented
//   together (OCC boolean fragment), so both sides of every joint carry the same nodes; each is its own body.
//
// PHYSICAL GROUPS
//   2D regions (in this order): "cap" (top and bottom blocks), "side" (left and right blocks), "key" (the two
//   keys), "beam" (if beam_height > 0), "base" (if base_height > 0).
//   Joint families as region pairs (the case's [[interfaces]] rules):
//     diagonal joints     (cap, side)     total length 4 r / cos(phi)
//     vertical joint      (side, side)    H - (L - w) t
//     horizontal joints   (key, side)     2 w
//     key sides           (cap, key)      2 w / cos(phi)   (not a failure plane: tie them)
//     beam / foundation   (beam, cap), (base, cap)   L each (the side blocks touch y = 0 and y = H at one corner only)
//   1D curves: "pier_bottom", "pier_top" (block edges on y = 0 and y = H), "pier_left", "pier_right" (on x = 0,
//   x = L), and as in mesh/wall.hpp "beam_top", "beam_left", "beam_right", "base_bottom", "base_left", "base_right".
//   0D points: "toe_left" (0, 0), "toe_right" (L, 0) as in mesh/wall.hpp.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "mesh/mesh.hpp"

namespace fdem::mesh {

// Field names are the TOML keys under [geometry] (type = "macro").
struct MacroPierSpec {
    double length = 0;             // m, pier length L
    double height = 0;             // m, pier height H
    double texture_angle = 0;      // deg, phi in (0, 90): slope of the diagonal joints
    double horizontal_joint = 0.05;  // m, length w of each short horizontal joint, in (0, L/2)
    double mesh_size = 0;          // m, target triangle size in the blocks (required)
    double beam_height = 0;        // m, top beam depth; 0 = no beam
    double beam_overhang = 0;      // m, beam length beyond each pier end
    double base_height = 0;        // m, foundation depth; 0 = no foundation
    double base_overhang = 0;      // m, foundation length beyond each pier end
    double mesh_size_beam = 0;     // m, in the beam; 0 = mesh_size
    double mesh_size_base = 0;     // m, in the foundation; 0 = mesh_size
};

// User-readable problems with a spec, one line each naming the key ("geometry.texture_angle must be in (0, 90)
// deg, got 95"); empty = fine. generate_macro_pier calls it first.
std::vector<std::string> check(const MacroPierSpec& spec);

// The six block outlines (CCW vertex lists) in region order cap (top, bottom), side (left, right), key (top,
// bottom), for tests. Throws MeshError if check() fails.
std::vector<std::vector<std::array<double, 2>>> macro_block_outlines(const MacroPierSpec& spec);

// The meshed pier (blocks, beam, base). Throws MeshError naming the problem (check()) or a Gmsh failure.
Mesh generate_macro_pier(const MacroPierSpec& spec);

}  // namespace fdem::mesh
