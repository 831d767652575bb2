// mesh/wall.hpp: the masonry wall generator (Gmsh C++ API, OpenCASCADE kernel).
//
// DATA LAYOUT / COORDINATES
//   The wall occupies x in [0, length], y in [0, height] (m). The beam sits on top, y in [height, height +
//   beam_height], x in [-beam_overhang, length + beam_overhang]; the base slab below, y in [-base_height, 0],
//   x in [-base_overhang, length + base_overhang]. Course 0 is the bottom course.
//   Units are fragmented together with the beam and base (OCC boolean fragment), so both sides of every joint
//   carry the same nodes in the returned Mesh; every unit, the beam and the base are separate bodies
//   (Mesh::tri_body), which is what lets mesh/topology.hpp tell a joint from a crack.
//
// PHYSICAL GROUPS (names a case file can use for materials, loads and supports)
//   2D regions:  "units"  every masonry unit (generated or stone);  "beam" (if beam_height > 0);
//                "base" (if base == "slab").
//   1D curves:   "wall_bottom"  bottom edges of the units on y = 0 (the wall's foot; the fixed edge when
//                               base == "fixed" or "none", the unit side of the base joint when base == "slab");
//                "wall_top"     top edges of the units on y = height;
//                "wall_left", "wall_right"  unit edges on x = 0 and x = length;
//                "beam_top", "beam_left", "beam_right"  outer edges of the beam;
//                "base_bottom", "base_left", "base_right"  outer edges of the base slab.
//   0D points:   "toe_left" (0, 0) and "toe_right" (length, 0): the wall foot corners;
//                "wall_top_left" (0, height) and "wall_top_right" (length, height).
//   A group is created only if its entity exists (no beam -> no beam_*; an opening may remove a corner).
//
// Mortar joints follow the simplified micro-model: each unit is expanded by half the joint thickness on every
// side, so the course pitch is unit_height + joint_thickness and the unit pitch unit_length + joint_thickness;
// the joint itself becomes a zero-thickness interface between expanded units (bonded, by the case's rules).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "mesh/mesh.hpp"

namespace fdem::mesh {

// A rectangular opening (window, door) cut out of the units. Lower-left corner (x, y) in m, size in m.
struct WallOpening {
    double x = 0, y = 0;           // m
    double width = 0, height = 0;  // m
};

// A rectangle where the mesh is refined to `size` (m) (a Gmsh Box field; the smaller size wins).
struct WallRefinement {
    double x = 0, y = 0;           // m, lower-left corner
    double width = 0, height = 0;  // m
    double size = 0;               // m
};

// Field names are the TOML keys under [geometry] (type = "wall").
struct WallSpec {
    double length = 0;        // m, wall length (required unless stones are given: then their bounding box)
    double height = 0;        // m, wall height; 0 = courses * (unit_height + joint_thickness)
    int courses = 0;          // number of courses; 0 = height / (unit_height + joint_thickness), must be whole
    double unit_length = 0;   // m, unit (brick, block) length without mortar; required for generated bonds
    double unit_height = 0;   // m, unit height without mortar; required for generated bonds
    std::string bond = "running";  // "running" (half units at the ends of odd courses), "stack", "offsets"
    std::vector<double> offsets;   // m, bond = "offsets": head-joint shift of course i is offsets[i % size]
                                   // (running bond = {0, pitch/2}); pieces cut by the wall ends become part units
    // Irregular stone layout: each polygon a list of (x, y) vertices (m), either orientation, no repeated
    // closing vertex. When non-empty the stones replace the generated courses (bond, courses, unit sizes ignored).
    std::vector<std::vector<std::array<double, 2>>> stones;
    std::string joint = "dry";     // "dry" (units meet face to face) or "mortar" (units expanded by half a joint)
    double joint_thickness = 0;    // m, mortar joint thickness (joint = "mortar" only)
    double beam_height = 0;        // m, top beam depth; 0 = no beam
    double beam_overhang = 0;      // m, beam length beyond each wall end
    std::string base = "none";     // "none" or "fixed" (no base body: support the wall by "wall_bottom"),
                                   // "slab" (a base body of base_height below the wall)
    double base_height = 0;        // m, base slab depth (base = "slab")
    double base_overhang = 0;      // m, base length beyond each wall end
    std::vector<WallOpening> openings;
    double mesh_size = 0;          // m, target triangle size in the units (required)
    double mesh_size_beam = 0;     // m, in the beam; 0 = mesh_size
    double mesh_size_base = 0;     // m, in the base; 0 = mesh_size
    std::vector<WallRefinement> refine;
    // Where a crackable unit may crack: "anywhere" (every interior edge, the default) or "middle": one vertical
    // potential crack at mid-length of every whole unit (the simplified micro-models of Lourenco & Rots 1997 and the
    // DEM reproductions of the Vermeltfoort walls). The unit is meshed as two halves that stay one body; the mid
    // lines form the 1D group "unit_cracks", which the topology then takes as the only crackable unit edges.
    // Generated bonds only; half units at the wall ends (shorter than 3/4 of the longest unit) are not split.
    std::string unit_cracks = "anywhere";
};

// User-readable problems with a spec, one line each ("geometry.openings[1]: the opening reaches x = 1.2 m,
// outside the wall [0, 1] m"); empty = fine. generate_wall calls it first.
std::vector<std::string> check(const WallSpec& spec);

// The generated, meshed wall. Throws MeshError naming the problem: the joined problems of check(), overlapping
// stones (naming both), or a Gmsh failure.
Mesh generate_wall(const WallSpec& spec);

// The unit outlines that generate_wall builds before openings are cut (rectangles as 4 CCW vertices, stones as
// given), for tests and for the CLI's statistics: count, joint lengths. Throws MeshError if check() fails.
std::vector<std::vector<std::array<double, 2>>> wall_unit_outlines(const WallSpec& spec);

// Expected triangle count before meshing (the case reader's size guard, [geometry] max_triangles): area /
// (sqrt(3)/4 h^2) for each part meshed at size h, and at least 2 triangles per unit; 0 when the sizes are not set.
double expected_triangles(const WallSpec& spec);

}  // namespace fdem::mesh
