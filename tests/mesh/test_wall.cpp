// tests/mesh/test_wall.cpp: the masonry wall generator (CASES.md §A geometry, A2 mesh sizes, bad inputs).
#include <catch2/catch.hpp>

#include <cmath>
#include <set>

#include "mesh/wall.hpp"

using namespace fdem::mesh;

namespace {
WallSpec cases_a_wall() {
    WallSpec s;  // CASES.md §A: 1000 x 1000 mm, 200 x 100 mm units, running bond, dry
    s.length = 1.0;
    s.height = 1.0;
    s.unit_length = 0.2;
    s.unit_height = 0.1;
    s.bond = "running";
    s.joint = "dry";
    s.mesh_size = 0.05;
    return s;
}

double mesh_area(const Mesh& m, int region = -1) {
    double a = 0;
    for (int t = 0; t < m.n_triangles(); ++t) {
        if (region >= 0 && m.tri_region[t] != region) continue;
        const int* n = &m.tri[3 * t];
        const double* p = m.xy.data();
        a += 0.5 * ((p[2 * n[1]] - p[2 * n[0]]) * (p[2 * n[2] + 1] - p[2 * n[0] + 1]) -
                    (p[2 * n[2]] - p[2 * n[0]]) * (p[2 * n[1] + 1] - p[2 * n[0] + 1]));
    }
    return a;
}
}  // namespace

TEST_CASE("CASES A wall: 55 units, area preserved", "[unit]") {
    const auto outlines = wall_unit_outlines(cases_a_wall());
    CHECK(outlines.size() == 55);
    const Mesh m = generate_wall(cases_a_wall());
    CHECK(m.n_bodies() == 55);
    REQUIRE(m.regions.size() == 1);
    CHECK(m.regions[0] == "units");
    CHECK(std::abs(mesh_area(m) - 1.0) <= 1e-12);
    for (const char* g : {"wall_bottom", "wall_top", "wall_left", "wall_right", "toe_left", "toe_right"})
        CHECK(m.find_group(g) != nullptr);
}
