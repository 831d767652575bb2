// tests/mesh/test_topology.cpp: edge classes, node splitting, cohesive and contact sets (mesh/README.md 'Topology').
#include <catch2/catch.hpp>

#include <algorithm>
#include <set>

#include "helpers.hpp"
#include "mesh/quality.hpp"
#include "mesh/topology.hpp"
#include "mesh/wall.hpp"

using namespace fdem::mesh;
using namespace fdem::mesh::testing;

namespace {

// The split node of original node `k` in triangle t.
int copy_in(const Topology& topo, int t, int k) {
    for (int i = 0; i < 3; ++i)
        if (topo.node_origin[topo.mesh.tri[3 * t + i]] == k) return topo.mesh.tri[3 * t + i];
    return -1;
}

// The invariants every topology must satisfy, whatever the rules. Returns the number of checks run.
// With crack_tips, a separating edge may keep one end shared (a crack ending inside a tied continuum).
int check_invariants(const Mesh& in, const Topology& topo, bool crack_tips = false) {
    int checks = 0;
    const Mesh& m = topo.mesh;
    REQUIRE(m.n_triangles() == in.n_triangles());
    REQUIRE(static_cast<int>(topo.node_origin.size()) == m.n_nodes());
    // Copies sit where their origin was, and each triangle keeps its reference geometry.
    for (int k = 0; k < m.n_nodes(); ++k) {
        REQUIRE(m.xy[2 * k] == in.xy[2 * topo.node_origin[k]]);
        REQUIRE(m.xy[2 * k + 1] == in.xy[2 * topo.node_origin[k] + 1]);
    }
    for (int c = 0; c < 3 * m.n_triangles(); ++c) REQUIRE(topo.node_origin[m.tri[c]] == in.tri[c]);
    // No node shared across a separating edge; shared across interior ones.
    for (int e = 0; e < topo.n_edges(); ++e) {
        const int ta = topo.edge_tri[2 * e], tb = topo.edge_tri[2 * e + 1];
        const auto cls = topo.edge_class[e];
        REQUIRE((tb < 0) == (cls == EdgeClass::free_boundary));
        if (tb < 0) continue;
        int separated = 0;
        for (int end = 0; end < 2; ++end) {
            const int k = topo.edge_nodes[2 * e + end];
            if (cls == EdgeClass::interior) REQUIRE(copy_in(topo, ta, k) == copy_in(topo, tb, k));
            else if (!crack_tips) REQUIRE(copy_in(topo, ta, k) != copy_in(topo, tb, k));
            separated += copy_in(topo, ta, k) != copy_in(topo, tb, k);
            ++checks;
        }
        if (cls != EdgeClass::interior) REQUIRE(separated >= 1);
    }
    // Node count implied by the classes: around a manifold vertex with T triangles and I interior edges the
    // fans number max(1, T - I) (closed fan: T edges; open fan: T + 1 edges of which 2 free).
    std::vector<int> T(in.n_nodes(), 0), I(in.n_nodes(), 0);
    for (int c = 0; c < 3 * in.n_triangles(); ++c) ++T[in.tri[c]];
    for (int e = 0; e < topo.n_edges(); ++e)
        if (topo.edge_class[e] == EdgeClass::interior) ++I[topo.edge_nodes[2 * e]], ++I[topo.edge_nodes[2 * e + 1]];
    long implied = 0;
    for (int k = 0; k < in.n_nodes(); ++k) implied += std::max(1, T[k] - I[k]);
    REQUIRE(m.n_nodes() == implied);
    ++checks;
    // Cohesive elements: one per crackable/bonded edge; edges coincide; a0->a1 counter-clockwise in tri_a.
    int expected = 0;
    for (auto c : topo.edge_class) expected += (c == EdgeClass::crackable || c == EdgeClass::bonded);
    REQUIRE(static_cast<int>(topo.cohesive.size()) == expected);
    for (const auto& ce : topo.cohesive) {
        for (int s = 0; s < 2; ++s) {
            REQUIRE(m.xy[2 * ce.n[s]] == m.xy[2 * ce.n[2 + s]]);
            REQUIRE(m.xy[2 * ce.n[s] + 1] == m.xy[2 * ce.n[2 + s] + 1]);
        }
        REQUIRE(ce.n[0] != ce.n[1]);
        bool ccw = false;
        for (int i = 0; i < 3; ++i)
            ccw |= m.tri[3 * ce.tri_a + i] == ce.n[0] && m.tri[3 * ce.tri_a + (i + 1) % 3] == ce.n[1];
        REQUIRE(ccw);
        bool cw_b = false;  // side B runs b1->b0 counter-clockwise
        for (int i = 0; i < 3; ++i)
            cw_b |= m.tri[3 * ce.tri_b + i] == ce.n[3] && m.tri[3 * ce.tri_b + (i + 1) % 3] == ce.n[2];
        REQUIRE(cw_b);
        REQUIRE(ce.body_a == m.tri_body[ce.tri_a]);
        REQUIRE(ce.body_b == m.tri_body[ce.tri_b]);
        ++checks;
    }
    // Surface groups hold exactly the nodes of their triangles; curve groups every copy on the bodies their edges
    // border; point groups every copy of their nodes.
    for (std::size_t g = 0; g < in.groups.size(); ++g) {
        std::set<int> want(in.groups[g].nodes.begin(), in.groups[g].nodes.end()), got;
        for (int k : m.groups[g].nodes) got.insert(topo.node_origin[k]);
        REQUIRE(got == want);
        if (in.groups[g].dim == 2 && !in.groups[g].triangles.empty()) {
            std::set<int> own;
            for (int t : m.groups[g].triangles)
                for (int i = 0; i < 3; ++i) own.insert(m.tri[3 * t + i]);
            REQUIRE(std::set<int>(m.groups[g].nodes.begin(), m.groups[g].nodes.end()) == own);
        } else if (in.groups[g].dim == 1 && !m.groups[g].edges.empty()) {
            const std::vector<int>& bodies = m.groups[g].bodies;
            std::set<int> border, expect;
            for (const auto& ed : m.groups[g].edges)
                for (int t = 0; t < m.n_triangles(); ++t) {
                    int hits = 0;
                    for (int i = 0; i < 3; ++i) hits += m.tri[3 * t + i] == ed[0] || m.tri[3 * t + i] == ed[1];
                    if (hits == 2) border.insert(m.tri_body[t]);
                }
            REQUIRE(std::set<int>(bodies.begin(), bodies.end()) == border);
            for (int t = 0; t < m.n_triangles(); ++t)
                if (border.count(m.tri_body[t]))
                    for (int i = 0; i < 3; ++i)
                        if (want.count(topo.node_origin[m.tri[3 * t + i]])) expect.insert(m.tri[3 * t + i]);
            REQUIRE(std::set<int>(m.groups[g].nodes.begin(), m.groups[g].nodes.end()) == expect);
        } else {
            long copies = 0;
            for (int k = 0; k < m.n_nodes(); ++k) copies += want.count(topo.node_origin[k]);
            REQUIRE(static_cast<long>(m.groups[g].nodes.size()) == copies);
        }
        ++checks;
    }
    return checks;
}

TopologyOptions dry_crackable_units() {
    TopologyOptions o;
    o.regions = {{"units", true}};
    o.interfaces = {{"units", "units", InterfaceKind::dry}};
    return o;
}

}  // namespace

TEST_CASE("CASES A wall: dry joint length equals bed plus head joints and splitting invariants hold", "[unit]") {
    const Mesh m = generate_wall(cases_a_wall());
    const Topology topo = build_topology(m, dry_crackable_units());
    CHECK(check_invariants(m, topo) > 100);
    CHECK(topo.nonconforming_nodes == 0);
    // 9 internal bed joints of 1 m; head joints: 5 courses x 4 + 5 courses x 5 = 45 of 0.1 m.
    const double bed = 9 * 1.0, head = 45 * 0.1;
    CHECK(std::abs(class_length(topo, EdgeClass::dry) - (bed + head)) <= 1e-9);
    CHECK(std::abs(class_length(topo, EdgeClass::free_boundary) - 4.0) <= 1e-9);
    CHECK(class_length(topo, EdgeClass::interior) == 0.0);  // crackable units: every inner edge separates
    CHECK(topo.cohesive.size() > 0);
    for (const auto& ce : topo.cohesive) {
        CHECK(ce.kind == EdgeClass::crackable);
        CHECK(ce.body_a == ce.body_b);
    }
    // Every triangle touches a dry or free edge by a node in a 50 mm mesh of 100 mm courses? Not necessarily;
    // but every triangle with a free or dry edge must be in the set.
    std::set<int> capable(topo.contact_capable.begin(), topo.contact_capable.end());
    CHECK(std::is_sorted(topo.contact_capable.begin(), topo.contact_capable.end()));
    for (int e = 0; e < topo.n_edges(); ++e)
        if (topo.edge_class[e] == EdgeClass::dry || topo.edge_class[e] == EdgeClass::free_boundary)
            CHECK(capable.count(topo.edge_tri[2 * e]) == 1);
}

TEST_CASE("non-crackable units: nodes shared inside, split only at joints", "[unit]") {
    const Mesh m = generate_wall(cases_a_wall());
    TopologyOptions o;
    o.interfaces = {{"units", "units", InterfaceKind::dry}};
    const Topology topo = build_topology(m, o);
    check_invariants(m, topo);
    CHECK(topo.cohesive.empty());
    CHECK(std::abs(class_length(topo, EdgeClass::dry) - 13.5) <= 1e-9);
    // Each unit is its own continuum: the split mesh has exactly the nodes of 55 separately meshed units.
    std::vector<std::set<int>> per_body(m.n_bodies());
    for (int c = 0; c < 3 * m.n_triangles(); ++c) per_body[m.tri_body[c / 3]].insert(m.tri[c]);
    long sum = 0;
    for (const auto& s : per_body) sum += static_cast<long>(s.size());
    CHECK(topo.mesh.n_nodes() == sum);
    // Contact by edge is a subset of contact by node.
    o.contact_by_node = false;
    const Topology by_edge = build_topology(m, o);
    CHECK(by_edge.contact_capable.size() < topo.contact_capable.size());
    CHECK(std::includes(topo.contact_capable.begin(), topo.contact_capable.end(), by_edge.contact_capable.begin(),
                        by_edge.contact_capable.end()));
}

TEST_CASE("tied units form one continuum and split_all separates every triangle", "[unit]") {
    const Mesh m = generate_wall(cases_a_wall(0.1));
    TopologyOptions o;
    o.interfaces = {{"units", "units", InterfaceKind::tied}};
    const Topology tied = build_topology(m, o);
    check_invariants(m, tied);
    CHECK(tied.mesh.n_nodes() == m.n_nodes());
    CHECK(tied.contact_capable.size() < static_cast<std::size_t>(m.n_triangles()));
    o.split_all = true;
    const Topology all = build_topology(m, o);
    check_invariants(m, all);
    CHECK(all.mesh.n_nodes() == 3 * m.n_triangles());
    CHECK(class_length(all, EdgeClass::interior) == 0.0);
    // Same with dry joints: joints stay dry, everything else becomes crackable.
    o.interfaces = {{"units", "units", InterfaceKind::dry}};
    const Topology dry_all = build_topology(m, o);
    check_invariants(m, dry_all);
    CHECK(std::abs(class_length(dry_all, EdgeClass::dry) - 13.5) <= 1e-9);
    CHECK(dry_all.mesh.n_nodes() == 3 * m.n_triangles());
}

TEST_CASE("mortared wall with beam and base: bonded joints, named boundaries", "[unit]") {
    WallSpec s;
    s.length = 0.99;  // cases/README.md §B geometry, shortened to 6 courses
    s.courses = 6;
    s.unit_length = 0.21;
    s.unit_height = 0.052;
    s.joint = "mortar";
    s.joint_thickness = 0.01;
    s.beam_height = 0.1;
    s.beam_overhang = 0.05;
    s.base = "slab";
    s.base_height = 0.1;
    s.mesh_size = 0.031;
    s.mesh_size_beam = 0.06;
    s.mesh_size_base = 0.06;
    const Mesh m = generate_wall(s);
    REQUIRE(m.regions == std::vector<std::string>{"units", "beam", "base"});
    const double H = 6 * 0.062;
    CHECK(std::abs(mesh_area(m, 0) - 0.99 * H) <= 1e-12 * 0.99 * H);
    CHECK(std::abs(mesh_area(m, 1) - 1.09 * 0.1) <= 1e-12);
    CHECK(std::abs(mesh_area(m, 2) - 0.99 * 0.1) <= 1e-12);
    for (const char* g : {"beam_top", "beam_left", "beam_right", "base_bottom", "base_left", "base_right", "wall_bottom",
                          "wall_top", "toe_left", "toe_right"})
        CHECK(m.find_group(g) != nullptr);
    for (int k : m.find_group("beam_top")->nodes) CHECK(m.xy[2 * k + 1] == Approx(H + 0.1).margin(1e-12));
    for (int k : m.find_group("base_bottom")->nodes) CHECK(m.xy[2 * k + 1] == Approx(-0.1).margin(1e-12));
    CHECK(m.find_group("toe_right")->nodes.size() == 1);

    TopologyOptions o;
    o.regions = {{"units", true}, {"beam", false}, {"base", false}};
    o.interfaces = {{"units", "units", InterfaceKind::bonded},
                    {"units", "beam", InterfaceKind::bonded},
                    {"base", "units", InterfaceKind::bonded}};
    const Topology topo = build_topology(m, o);
    check_invariants(m, topo);
    // Running bond of 0.22 m pitch over 0.99 m: 4.5 units per course -> 4 head joints per course; 5 inner bed
    // joints, wall-beam and wall-base joints, all 0.99 m.
    CHECK(std::abs(class_length(topo, EdgeClass::bonded) - (6 * 4 * 0.062 + 7 * 0.99)) <= 1e-9);
    int bonded = 0;
    for (const auto& ce : topo.cohesive) bonded += ce.kind == EdgeClass::bonded;
    CHECK(bonded > 0);
    // The beam edge group keeps one copy per edge (beam not crackable, top is a free boundary).
    const auto& in_top = *m.find_group("beam_top");
    CHECK(topo.mesh.find_group("beam_top")->edges.size() == in_top.edges.size());
    // wall_bottom lies on the bonded base joint: each of its edges appears from both sides.
    CHECK(topo.mesh.find_group("wall_bottom")->edges.size() == 2 * m.find_group("wall_bottom")->edges.size());
}

TEST_CASE("topology errors name the regions", "[unit]") {
    WallSpec s = cases_a_wall(0.1);
    s.beam_height = 0.1;
    const Mesh m = generate_wall(s);
    TopologyOptions o;
    o.interfaces = {{"units", "units", InterfaceKind::dry}};
    try {
        build_topology(m, o);
        FAIL("a missing interface rule must throw");
    } catch (const MeshError& e) {
        const std::string msg = e.what();
        CHECK(msg.find("no interface rule") != std::string::npos);
        CHECK(msg.find("'units'") != std::string::npos);
        CHECK(msg.find("'beam'") != std::string::npos);
    }
    o.interfaces.push_back({"units", "slab", InterfaceKind::dry});
    CHECK_THROWS_WITH(build_topology(m, o), Catch::Contains("'slab'") && Catch::Contains("does not exist"));
    o.interfaces.back() = {"beam", "units", InterfaceKind::dry};
    o.interfaces.push_back({"units", "beam", InterfaceKind::bonded});
    CHECK_THROWS_WITH(build_topology(m, o), Catch::Contains("conflicting"));
    o.interfaces.pop_back();
    o.regions = {{"bricks", true}};
    CHECK_THROWS_WITH(build_topology(m, o), Catch::Contains("'bricks'") && Catch::Contains("does not exist"));
    o.regions.clear();
    CHECK_NOTHROW(build_topology(m, o));

    // Hand-made meshes: an inverted triangle and two triangles folded onto the same side of an edge.
    Mesh h;
    h.xy = {0, 0, 1, 0, 0, 1, 1, 1};
    h.tri = {0, 1, 2, 1, 2, 3};  // second is clockwise
    h.tri_region = {0, 0};
    h.tri_body = {0, 0};
    h.regions = {"body"};
    CHECK_THROWS_WITH(build_topology(h, {}), Catch::Contains("inverted") && Catch::Contains("'body'"));
    h.xy = {0, 0, 1, 0, 0, 1, 0.5, 0.2};
    h.tri = {0, 1, 2, 0, 1, 3};  // both counter-clockwise, both left of 0->1: overlap
    CHECK_THROWS_WITH(build_topology(h, {}), Catch::Contains("same side"));
}

TEST_CASE("a crackable edge ending inside a tied continuum keeps its tip node shared", "[unit]") {
    // Unit square split in four triangles around its centre (node 4): bottom and right triangles "hard", top and
    // left "soft" (crackable), tied together. The only crackable edge runs from corner 3 (0, 1) to the centre.
    Mesh h;
    h.xy = {0, 0, 1, 0, 1, 1, 0, 1, 0.5, 0.5};
    h.tri = {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
    h.tri_region = {1, 1, 0, 0};
    h.tri_body = {1, 1, 0, 0};
    h.regions = {"soft", "hard"};
    TopologyOptions o;
    o.regions = {{"soft", true}};
    o.interfaces = {{"soft", "hard", InterfaceKind::tied}};
    const Topology topo = build_topology(h, o);
    check_invariants(h, topo, true);
    REQUIRE(topo.cohesive.size() == 1);  // edge 3-4 between triangles 2 and 3
    const auto& ce = topo.cohesive[0];
    CHECK(((ce.n[0] == ce.n[2]) != (ce.n[1] == ce.n[3])));  // one end (the centre) is shared: the crack tip
    CHECK(topo.mesh.n_nodes() == 6);                         // only corner 3 is split
}

TEST_CASE("stats and quality check", "[unit]") {
    const Mesh m = generate_wall(cases_a_wall(0.025));
    const Topology topo = build_topology(m, dry_crackable_units());
    const MeshStats s = mesh_stats(topo);
    CHECK(s.triangles == m.n_triangles());
    CHECK(s.nodes_before == m.n_nodes());
    CHECK(s.nodes_after == topo.mesh.n_nodes());
    CHECK(s.bodies == 55);
    CHECK(s.cohesive_crackable == static_cast<int>(topo.cohesive.size()));
    CHECK(std::abs(s.length_per_class[static_cast<int>(EdgeClass::dry)] - 13.5) <= 1e-9);
    int hist = 0;
    for (int n : s.aspect_histogram) hist += n;
    CHECK(hist == s.triangles);
    CHECK(s.min_angle_deg > 25.0);  // Frontal-Delaunay on rectangles
    CHECK(s.min_angle_deg <= 60.0);
    CHECK(s.min_altitude > 0.25 * 0.025);
    CHECK(s.max_aspect >= 1.0);
    CHECK(std::abs(s.area_per_region[0] - 1.0) <= 1e-12);
    const std::string text = format_stats(s);
    for (const char* word : {"triangles", "after splitting", "crackable", "contact-capable", "minimum angle",
                             "minimum altitude", "aspect"})
        CHECK(text.find(word) != std::string::npos);
    CHECK_NOTHROW(check_quality(m));

    // Closed-form qualities: equilateral triangle and a right isosceles one.
    const double e0[2] = {0, 0}, e1[2] = {1, 0}, e2[2] = {0.5, std::sqrt(3.0) / 2};
    const auto q = triangle_quality(e0, e1, e2);
    CHECK(q.min_angle_deg == Approx(60.0).epsilon(1e-12));
    CHECK(q.aspect == Approx(1.0).epsilon(1e-12));
    CHECK(q.altitude == Approx(std::sqrt(3.0) / 2).epsilon(1e-12));
    const double r2[2] = {0, 1};
    const auto qr = triangle_quality(e0, e1, r2);
    CHECK(qr.min_angle_deg == Approx(45.0).epsilon(1e-12));
    CHECK(qr.altitude == Approx(std::sqrt(0.5)).epsilon(1e-12));
    CHECK(qr.aspect == Approx((1.0 + std::sqrt(2.0)) / 2).epsilon(1e-12));  // R = sqrt2/2, r = (2-sqrt2)/2

    Mesh sliver;
    sliver.xy = {0, 0, 1, 0, 0.5, 0.02};
    sliver.tri = {0, 1, 2};
    sliver.tri_region = {0};
    sliver.regions = {"units"};
    CHECK_THROWS_WITH(check_quality(sliver), Catch::Contains("sliver") && Catch::Contains("'units'"));
    CHECK_NOTHROW(check_quality(sliver, 2.0));
}
