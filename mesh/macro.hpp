// mesh/macro.hpp: the macro-block pier and wall generators (M-DEM, issue 29; Gmsh C++ API, OpenCASCADE kernel).
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
//
// TRANSPOSED PANEL (used by the wall below; the single pier is always tall)
//   A squat panel (H <= (L - w) t) gets the same layout with x and y swapped: the tall layout is built in swapped
//   coordinates (x' = y, y' = x: a panel of length H and height L) with slope 1 / t, so that the diagonals keep
//   dy/dx = t in the wall, and swapped back. Its condition, L > (H - w) / t, holds whenever the tall one fails:
//   H <= (L - w) t < L t + w gives (H - w) / t < L. The caps are then the left and right end blocks, the "side"
//   blocks the bottom and top ones, the central joint is horizontal (y = y0 + H/2, length L - (H - w) / t) and the
//   short joints vertical. The keys need w < H/2 (tall: w < L/2).
//
// WALL WITH OPENINGS (type = "macro_wall"; our own equivalent-frame reading: seeds/000 models single piers only)
//   The wall occupies x in [0, length], y in [0, height]; one row of openings [x, x + width] x [y_s, y_l] with the
//   same sill y_s >= 0 and lintel y_l = y_s + height <= wall height H for all. Columns, left to right: piers
//   P_1..P_n (n = openings + 1, each of positive length) and the openings O_1..O_(n-1) between them. Bands: lower
//   [0, y_s] (if y_s > 0), middle [y_s, y_l], upper [y_l, H] (if y_l < H). Cells:
//     pier column x middle band      pier panel: the macro layout above (tall or transposed), regions cap, side, key;
//     opening column x upper / lower spandrel panel: the same, regions spandrel_cap, spandrel_side, spandrel_key;
//     pier column x upper / lower    one plain elastic block, region "node" (the equivalent frame's rigid node:
//                                    here deformable, the case gives it the masonry);
//     opening column x middle band   empty.
//   Every cell edge ends at cell corners (the panels put vertices on their outline at the corners only), so two
//   touching cells share their whole edge (not so with a lintel: LINTELS below); the cells' coordinates are the
//   same doubles (0, the openings' x and x + width, y_s, y_l, length, H), so the fragment merges shared corners
//   exactly.
//   Joint pairs inside a panel: pier (cap, side) diagonal, (side, side) central, (key, side) short, (cap, key) tie;
//   spandrel the same with the spandrel_ names. Between cells, through the blocks on the panel's outline:
//     tall pier panel:         top and bottom edges are cap -> (cap, node), or (beam, cap) if y_l = H,
//                              (base, cap) if y_s = 0; its left and right edges face openings or the wall ends.
//     transposed pier panel:   top and bottom edges are side -> (node, side), (beam, side), (base, side).
//     tall spandrel:           left and right edges are spandrel_side -> (node, spandrel_side); the upper
//                              spandrel's top edge is spandrel_cap -> (beam, spandrel_cap), the lower one's bottom
//                              edge (base, spandrel_cap); the edge on the opening is free.
//     transposed spandrel:     left and right edges are spandrel_cap -> (node, spandrel_cap); top / bottom
//                              (beam, spandrel_side), (base, spandrel_side).
//     node:                    (beam, node) in the upper band, (base, node) in the lower; never node on node
//                              (except under a lintel band, below).
//   The beam and base span x in [-overhang, length + overhang] as for the pier; the beam also meets the pier panels
//   (y_l = H) and the base the pier panels when y_s = 0 (a door).
//   LINTELS (lintel_height h_l > 0, lintel_bearing b >= 0): the band [y_l, y_l + h_l] above the openings becomes a
//   lintel band and the upper band starts at y_u = y_l + h_l (none if y_u = H). Over each opening [x, x + width] a
//   plain elastic block, region "lintel", spans x in [x - b, x + width + b] (it bears b on each pier); the rest of
//   the band over each pier is a node block (region "node", as the nodes above): x from the pier's left end (or
//   the left lintel's x + width + b) to its right end (or the right lintel's x - b). The bearings must leave node
//   material: for each pier, the bearings entering it (one for an end pier, two for an interior one) sum to less
//   than its length; y_u <= H; the shorter upper spandrel takes its own layout (tall or transposed) and must pass
//   the per-panel checks. The bearing ends x - b, x + width + b and y_u are computed once and shared by both
//   neighbours; the T-junctions (a pier panel's top edge meeting a node and a lintel's bearing end, a lintel's top
//   edge meeting a spandrel and the nodes above) are split by the fragment, as the beam and base overhangs are.
//   Pairs that then occur: under the spandrel (lintel, spandrel_cap) if it is tall, (lintel, spandrel_side) if
//   transposed; (lintel, node) at the bearing ends and on the bearings' top; (cap, lintel) (tall pier) or
//   (lintel, side) (transposed pier) where a pier panel's top meets a bearing, the rest of that top meeting the
//   band's node as before, (cap, node) or (node, side); (node, node) between a band node and the node above it
//   (the only node on node: tie it to keep the equivalent-frame node one block); (beam, lintel) and (beam, node)
//   for the band if y_u = H. Without a lintel none of these occur and the mesh is the one before lintels existed.
//   PHYSICAL GROUPS: regions in this order (each only if it has blocks): "cap", "side", "key", "spandrel_cap",
//   "spandrel_side", "spandrel_key", "node", "lintel", "beam", "base"; curves "wall_bottom", "wall_top", "wall_left",
//   "wall_right" (block edges on y = 0, y = H, x = 0, x = length), "beam_*" and "base_*" as above; points
//   "toe_left" (0, 0), "toe_right" (length, 0). Each block its own body.
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

// The six block outlines of one panel [x0, x1] x [y0, y1] (CCW), in the order of macro_block_outlines: tall layout
// (transposed = false) or the transposed one (caps at the left and right ends). The corners are passed rather than
// a length and height so that every outline vertex on the panel's edge is exactly x0, x1, y0 or y1 (shared with the
// neighbouring cells); for x0 = y0 = 0 it computes the same doubles as the single pier. No checks.
std::vector<std::vector<std::array<double, 2>>> panel_outlines(double x0, double y0, double x1, double y1,
                                                               double tan_phi, double w, bool transposed);

// Field names are the TOML keys under [geometry] (type = "macro_wall").
struct MacroWallOpening {
    double x = 0, y = 0;           // m, lower-left corner in wall coordinates
    double width = 0, height = 0;  // m
};

struct MacroWallSpec {
    double length = 0;             // m, whole wall
    double height = 0;             // m, wall top (below the beam)
    std::vector<MacroWallOpening> openings;  // one row: the same y and height for all
    double texture_angle = 0;      // deg, phi in (0, 90)
    double horizontal_joint = 0.05;  // m, w: below half of every panel's length (tall) or height (transposed)
    double mesh_size = 0;          // m, in the blocks (required)
    double beam_height = 0;        // m, 0 = no beam
    double beam_overhang = 0;      // m
    double base_height = 0;        // m, 0 = no foundation
    double base_overhang = 0;      // m
    double mesh_size_beam = 0;     // m, 0 = mesh_size
    double mesh_size_base = 0;     // m, 0 = mesh_size
    double lintel_height = 0;      // m, depth of the lintel band over the openings; 0 = no lintel
    double lintel_bearing = 0;     // m, how far each lintel reaches into the piers on each side (needs a lintel)
};

// One block of the wall: its outline (CCW), region name, and whether its panel uses the transposed layout.
struct MacroWallBlock {
    std::vector<std::array<double, 2>> outline;
    std::string region;  // "cap", "side", "key", "spandrel_cap", "spandrel_side", "spandrel_key", "node" or "lintel"
    bool transposed = false;
};

// Problems of a wall spec, one line each naming the key; openings are numbered from 1 in input order
// ("geometry.openings[2].y ..."). Empty = fine.
std::vector<std::string> check(const MacroWallSpec& spec);

// The wall's blocks: pier panels left to right, then spandrels (per opening, upper then lower), then nodes (per
// pier, upper then lower), then with a lintel the lintels (per opening) and the lintel band's nodes (per pier), all
// left to right. Throws MeshError if check() fails.
std::vector<MacroWallBlock> macro_wall_blocks(const MacroWallSpec& spec);

// The meshed wall (blocks, beam, base). Throws MeshError naming the problem (check()) or a Gmsh failure.
Mesh generate_macro_wall(const MacroWallSpec& spec);

// Expected triangle counts before meshing (the case reader's size guard, as for a wall: mesh/wall.hpp).
double expected_triangles(const MacroPierSpec& spec);
double expected_triangles(const MacroWallSpec& spec);

}  // namespace fdem::mesh
