#include <catch2/catch.hpp>

#include "mesh/gmsh_source.hpp"

TEST_CASE("rectangle mesh preserves area and names its sides", "[unit]") {
    const auto m = fdem::mesh::mesh_rectangle(0, 0, 2.0, 1.0, 0.1);
    double area = 0;
    for (int t = 0; t < m.n_triangles(); ++t) {
        const int* n = &m.tri[3 * t];
        const double* p = m.xy.data();
        const double a2 = (p[2 * n[1]] - p[2 * n[0]]) * (p[2 * n[2] + 1] - p[2 * n[0] + 1]) -
                          (p[2 * n[2]] - p[2 * n[0]]) * (p[2 * n[1] + 1] - p[2 * n[0] + 1]);
        REQUIRE(a2 > 0);
        area += 0.5 * a2;
    }
    CHECK(area == Approx(2.0).epsilon(1e-12));
    for (const char* side : {"left", "right", "top", "bottom", "body", "corner_bl", "corner_tr"})
        REQUIRE(m.find_group(side) != nullptr);
    const auto* left = m.find_group("left");
    for (int k : left->nodes) CHECK(m.xy[2 * k] == Approx(0.0).margin(1e-12));
    CHECK(m.find_group("corner_bl")->nodes.size() == 1);
}
