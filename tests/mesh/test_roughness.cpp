// tests/mesh/test_roughness.cpp: uneven bearing at dry joints (mesh/roughness.hpp).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>

#include "helpers.hpp"
#include "mesh/roughness.hpp"
#include "mesh/topology.hpp"
#include "mesh/wall.hpp"

using namespace fdem::mesh;
using namespace fdem::mesh::testing;

namespace {

TopologyOptions dry_joints(bool crackable_units) {
    TopologyOptions o;
    o.regions = {{"units", crackable_units}};
    o.interfaces = {{"units", "units", InterfaceKind::dry}};
    return o;
}

// Signed gap across side A's edge at the joint's two node pairs: (x_B - x_A) . n, n out of side A.
std::array<double, 2> gaps(const Topology& t, const CohesiveElement& d) {
    const double* x = t.mesh.xy.data();
    // The normal from the reference (unmoved) direction is not available here; a bed or head joint keeps its
    // direction to O(amplitude / length), which the tolerances below allow for.
    const double sx = x[2 * d.n[1]] - x[2 * d.n[0]], sy = x[2 * d.n[1] + 1] - x[2 * d.n[0] + 1];
    const double len = std::hypot(sx, sy), nx = sy / len, ny = -sx / len;
    std::array<double, 2> g{};
    for (int j = 0; j < 2; ++j)
        g[j] = (x[2 * d.n[2 + j]] - x[2 * d.n[j]]) * nx + (x[2 * d.n[2 + j] + 1] - x[2 * d.n[j] + 1]) * ny;
    return g;
}

double moved(const Topology& before, const Topology& after, int c) {
    return std::hypot(after.mesh.xy[2 * c] - before.mesh.xy[2 * c], after.mesh.xy[2 * c + 1] - before.mesh.xy[2 * c + 1]);
}

}  // namespace

TEST_CASE("joint roughness opens dry joints by at most twice the amplitude and keeps cracks closed", "[unit]") {
    const double a = 3e-4, wavelength = 0.1;
    const Mesh m = generate_wall(cases_a_wall(0.025));
    const Topology flat = build_topology(m, dry_joints(true));
    Topology rough = flat;
    const RoughnessStats st = roughen_dry_joints(rough, a, wavelength, 7);
    REQUIRE(st.points > 0);
    CHECK(st.largest <= a);
    CHECK(st.largest > 0.8 * a);  // a field of four cosines reaches near its bounds over 55 units
    CHECK(st.mean > 0.3 * a);
    CHECK(st.mean < 0.7 * a);

    // Faces never overlap; the gap is the sum of two offsets in [0, a]; some points still (nearly) touch.
    double smallest_gap = 1, largest_gap = 0;
    for (const auto& d : rough.dry_joints)
        for (double g : gaps(rough, d)) {
            CHECK(g >= -1e-12);
            CHECK(g <= 2 * a + 1e-12);
            smallest_gap = std::min(smallest_gap, g), largest_gap = std::max(largest_gap, g);
        }
    INFO("gaps " << smallest_gap / a << " .. " << largest_gap / a << " x amplitude");
    CHECK(smallest_gap < 0.5 * a);  // mean gap a: the faces are closer in places and farther in others
    CHECK(largest_gap > 1.5 * a);

    // Cohesive elements inside the stones start closed: both copies at each end coincide.
    REQUIRE(!rough.cohesive.empty());
    for (const auto& ce : rough.cohesive)
        for (int j = 0; j < 2; ++j) {
            CHECK(rough.mesh.xy[2 * ce.n[j]] == rough.mesh.xy[2 * ce.n[2 + j]]);
            CHECK(rough.mesh.xy[2 * ce.n[j] + 1] == rough.mesh.xy[2 * ce.n[2 + j] + 1]);
        }

    // Only dry-joint face points move: nothing else, no triangle turns over, and a point inside a bed joint (not at a
    // head joint or the wall's end) moves vertically, the lower block down and the upper block up.
    // (by input node: the copies of a joint point inside a cracking block move with the face copy)
    std::vector<char> on_joint(m.n_nodes(), 0);
    for (const auto& d : rough.dry_joints)
        for (int c : d.n) on_joint[rough.node_origin[c]] = 1;
    int moved_points = 0, vertical_checked = 0;
    for (int c = 0; c < rough.mesh.n_nodes(); ++c) {
        const double dist = moved(flat, rough, c);
        if (!on_joint[rough.node_origin[c]]) {
            CHECK(dist == 0.0);
            continue;
        }
        CHECK(dist <= a * (1 + 1e-12));
        moved_points += dist > 0;
        const double X = flat.mesh.xy[2 * c], Y = flat.mesh.xy[2 * c + 1];
        const double in_course = std::fmod(X + 1e-9, 0.1);
        const bool bed = Y > 0.05 && std::abs(Y / 0.1 - std::round(Y / 0.1)) < 1e-9;
        if (bed && in_course > 0.01 && in_course < 0.09 && X > 0.01 && X < 0.99) {
            CHECK(rough.mesh.xy[2 * c] == Approx(flat.mesh.xy[2 * c]).margin(1e-15));
            ++vertical_checked;
        }
    }
    CHECK(moved_points > 100);
    CHECK(vertical_checked > 100);
    for (int t = 0; t < rough.mesh.n_triangles(); ++t) CHECK(tri_area(rough.mesh, t) > 0);
}

TEST_CASE("joint roughness is seeded, independent of the mesh, and refused where it would invert triangles", "[unit]") {
    const double a = 2e-4, wavelength = 0.08;
    auto rough_of = [&](double h, std::uint64_t seed, Topology* flat_out = nullptr) {
        const Topology flat = build_topology(generate_wall(cases_a_wall(h)), dry_joints(false));
        Topology t = flat;
        roughen_dry_joints(t, a, wavelength, seed);
        if (flat_out) *flat_out = flat;
        return t;
    };
    Topology flat50, flat25;
    const Topology r1 = rough_of(0.05, 3, &flat50), r1again = rough_of(0.05, 3), r2 = rough_of(0.05, 4);
    const Topology fine = rough_of(0.025, 3, &flat25);
    CHECK(r1.mesh.xy == r1again.mesh.xy);
    CHECK(r1.mesh.xy != r2.mesh.xy);

    // The offset is a field of the reference position: block corners (in both meshes) move by the same amount in
    // the 50 mm and the 25 mm mesh. Key: body and reference position rounded to 1 um.
    auto corner_moves = [](const Topology& flat, const Topology& rough) {
        std::map<std::array<long, 3>, double> out;
        for (int c = 0; c < flat.mesh.n_nodes(); ++c) {
            const double X = flat.mesh.xy[2 * c], Y = flat.mesh.xy[2 * c + 1];
            if (std::abs(X / 0.1 - std::round(X / 0.1)) > 1e-9 || std::abs(Y / 0.1 - std::round(Y / 0.1)) > 1e-9) continue;
            int body = -1;
            for (int t = 0; t < flat.mesh.n_triangles() && body < 0; ++t)
                for (int k = 0; k < 3; ++k)
                    if (flat.mesh.tri[3 * t + k] == c) body = flat.mesh.tri_body[t];
            out[{body, std::lround(X * 1e6), std::lround(Y * 1e6)}] = moved(flat, rough, c);
        }
        return out;
    };
    const auto coarse_corners = corner_moves(flat50, r1), fine_corners = corner_moves(flat25, fine);
    REQUIRE(coarse_corners.size() > 100);
    int compared = 0;
    for (const auto& [k, v] : coarse_corners) {
        auto it = fine_corners.find(k);
        if (it == fine_corners.end()) continue;
        ++compared;
        CHECK(it->second == Approx(v).margin(1e-12));
    }
    CHECK(compared == static_cast<int>(coarse_corners.size()));

    // A 50 mm mesh has altitudes of about 40 mm: 10 mm of roughness could turn triangles over.
    Topology t = build_topology(generate_wall(cases_a_wall(0.05)), dry_joints(false));
    try {
        roughen_dry_joints(t, 0.01, wavelength, 1);
        FAIL("expected a MeshError");
    } catch (const MeshError& e) {
        CHECK(std::string(e.what()).find("more than a fifth of the smallest altitude") != std::string::npos);
    }
    CHECK_THROWS_AS(roughen_dry_joints(t, 1e-4, 0.0, 1), MeshError);
    CHECK_THROWS_AS(roughen_dry_joints(t, -1e-4, 0.1, 1), MeshError);
}

TEST_CASE("joint roughness leaves bonded joints closed", "[unit]") {
    WallSpec s;  // a short mortared wall on a dry base: bonded unit joints, dry base joint
    s.length = 0.66;
    s.courses = 3;
    s.unit_length = 0.21;
    s.unit_height = 0.052;
    s.joint = "mortar";
    s.joint_thickness = 0.01;
    s.base = "slab";
    s.base_height = 0.1;
    s.mesh_size = 0.031;
    TopologyOptions o;
    o.regions = {{"units", false}, {"base", false}};
    o.interfaces = {{"units", "units", InterfaceKind::bonded}, {"base", "units", InterfaceKind::dry}};
    const Topology flat = build_topology(generate_wall(s), o);
    Topology t = flat;
    const RoughnessStats st = roughen_dry_joints(t, 1e-4, 0.05, 1);
    CHECK(st.points > 0);
    REQUIRE(!t.cohesive.empty());
    for (const auto& ce : t.cohesive) {
        REQUIRE(ce.kind == EdgeClass::bonded);
        for (int j = 0; j < 2; ++j) {
            CHECK(t.mesh.xy[2 * ce.n[j]] == t.mesh.xy[2 * ce.n[2 + j]]);
            CHECK(t.mesh.xy[2 * ce.n[j] + 1] == t.mesh.xy[2 * ce.n[2 + j] + 1]);
        }
    }
    // The base joint opened (the foot's points that are not also on a bonded head joint moved).
    double largest_gap = 0;
    for (const auto& d : t.dry_joints)
        for (double g : gaps(t, d)) largest_gap = std::max(largest_gap, g);
    CHECK(largest_gap > 0.5e-4);
}

TEST_CASE("joint roughness does not move points shared with a tied beam and keeps the stones' cracks closed there", "[unit]") {
    WallSpec s = cases_a_wall(0.025);  // the [K25] walls: crackable stones, dry joints, beam tied to the top course
    s.beam_height = 0.2;
    const Mesh m = generate_wall(s);
    TopologyOptions o;
    o.regions = {{"units", true}, {"beam", false}};
    o.interfaces = {{"units", "units", InterfaceKind::dry}, {"units", "beam", InterfaceKind::tied}};
    const Topology flat = build_topology(m, o);
    Topology t = flat;
    CHECK(roughen_dry_joints(t, 3e-4, 0.1, 1).points > 0);
    for (const auto& ce : t.cohesive)
        for (int j = 0; j < 2; ++j) {
            CHECK(t.mesh.xy[2 * ce.n[j]] == t.mesh.xy[2 * ce.n[2 + j]]);
            CHECK(t.mesh.xy[2 * ce.n[j] + 1] == t.mesh.xy[2 * ce.n[2 + j] + 1]);
        }
    const double top = 1.0;
    for (int c = 0; c < t.mesh.n_nodes(); ++c)
        if (flat.mesh.xy[2 * c + 1] >= top - 1e-9) CHECK(moved(flat, t, c) == 0.0);
}
