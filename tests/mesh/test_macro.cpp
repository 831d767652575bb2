// tests/mesh/test_macro.cpp: the macro-block pier generator (mesh/macro.hpp, issue 29, M-DEM of seeds/000).
//
// CLOSED FORMS (L length, H height, t = tan(phi), w horizontal joint, r = (L - w) / 2)
//   the six blocks tile the pier: total block area L H;
//   diagonal joints (cap, side): 4 r / cos(phi); vertical joint (side, side): H - 2 r t; horizontal joints
//   (key, side): 2 w; key sides (cap, key): 2 w / cos(phi); beam and foundation against the caps: L each.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <utility>

#include "../core/engine_helpers.hpp"
#include "helpers.hpp"
#include "mesh/macro.hpp"
#include "mesh/topology.hpp"

using namespace fdem::mesh;
using namespace fdem::mesh::testing;

namespace {

constexpr double kPi = 3.14159265358979323846;

// The JRC Ispra LW pier (cases/README.md §D): 1.00 x 1.35 m, texture angle 28 deg, 50 mm horizontal joints.
MacroPierSpec lw_pier(double mesh_size = 0.1) {
    MacroPierSpec s;
    s.length = 1.0;
    s.height = 1.35;
    s.texture_angle = 28.0;
    s.horizontal_joint = 0.05;
    s.mesh_size = mesh_size;
    s.beam_height = 0.2;
    s.base_height = 0.3;
    s.base_overhang = 0.2;
    s.mesh_size_beam = 0.1;
    s.mesh_size_base = 0.15;
    return s;
}

TopologyOptions joint_rules() {
    TopologyOptions opt;
    auto rule = [&](const char* a, const char* b, InterfaceKind k) { opt.interfaces.push_back({a, b, k}); };
    rule("cap", "side", InterfaceKind::bonded);   // diagonal joints
    rule("side", "side", InterfaceKind::bonded);  // vertical joint
    rule("key", "side", InterfaceKind::bonded);   // horizontal joints
    rule("cap", "key", InterfaceKind::tied);      // key and cap: one continuum
    rule("beam", "cap", InterfaceKind::bonded);
    rule("base", "cap", InterfaceKind::bonded);
    return opt;
}

// Total length of the edges between two different bodies, per (sorted) region-name pair.
std::map<std::pair<std::string, std::string>, double> joint_lengths(const Topology& topo) {
    std::map<std::pair<std::string, std::string>, double> out;
    const Mesh& m = topo.mesh;
    for (int e = 0; e < topo.n_edges(); ++e) {
        const int ta = topo.edge_tri[2 * e], tb = topo.edge_tri[2 * e + 1];
        if (tb < 0 || m.tri_body[ta] == m.tri_body[tb]) continue;
        std::string a = m.regions[m.tri_region[ta]], b = m.regions[m.tri_region[tb]];
        if (b < a) std::swap(a, b);
        out[{a, b}] += edge_length(topo, e);
    }
    return out;
}

}  // namespace

TEST_CASE("macro pier: six blocks tile the L x H rectangle, beam and base are separate bodies", "[unit][macro]") {
    const MacroPierSpec s = lw_pier();
    const auto outlines = macro_block_outlines(s);
    REQUIRE(outlines.size() == 6);
    const Mesh m = generate_macro_pier(s);
    REQUIRE(m.regions == std::vector<std::string>{"cap", "side", "key", "beam", "base"});
    CHECK(m.n_bodies() == 8);
    double blocks = 0;
    for (const char* r : {"cap", "side", "key"}) blocks += mesh_area(m, m.find_region(r));
    CHECK(std::abs(blocks - s.length * s.height) <= 1e-9 * s.length * s.height);
    CHECK(std::abs(mesh_area(m, m.find_region("beam")) - s.length * s.beam_height) <= 1e-9);
    CHECK(std::abs(mesh_area(m, m.find_region("base")) - (s.length + 2 * s.base_overhang) * s.base_height) <= 1e-9);
    // Each body lies in one region, two bodies per block region.
    std::map<int, std::set<int>> bodies_of_region;
    for (int t = 0; t < m.n_triangles(); ++t) bodies_of_region[m.tri_region[t]].insert(m.tri_body[t]);
    for (const char* r : {"cap", "side", "key"}) CHECK(bodies_of_region[m.find_region(r)].size() == 2);
    for (const char* g : {"pier_bottom", "pier_top", "pier_left", "pier_right", "beam_top", "beam_left",
                          "beam_right", "base_bottom", "base_left", "base_right", "toe_left", "toe_right"})
        REQUIRE(m.find_group(g) != nullptr);
    for (int k : m.find_group("pier_top")->nodes) CHECK(m.xy[2 * k + 1] == Approx(s.height).margin(1e-12));
    for (int k : m.find_group("beam_top")->nodes) CHECK(m.xy[2 * k + 1] == Approx(1.55).margin(1e-12));
    for (int k : m.find_group("base_bottom")->nodes) CHECK(m.xy[2 * k + 1] == Approx(-0.3).margin(1e-12));
}

TEST_CASE("macro pier: every joint family has its closed-form length and the mesh is conforming", "[unit][macro]") {
    for (double h : {0.1, 0.05}) {
        for (double phi : {28.0, 40.0}) {
            MacroPierSpec s = lw_pier(h);
            s.texture_angle = phi;
            if (phi == 40.0) s.height = 2.0;  // the HW pier; (L - w) tan(40 deg) = 0.80 m fits
            INFO("mesh_size " << h << " m, phi " << phi << " deg");
            const Mesh m = generate_macro_pier(s);
            const Topology topo = build_topology(m, joint_rules());
            CHECK(topo.nonconforming_nodes == 0);
            const double t = std::tan(phi * kPi / 180), c = std::cos(phi * kPi / 180);
            const double w = s.horizontal_joint, r = 0.5 * (s.length - w);
            const auto len = joint_lengths(topo);
            REQUIRE(len.size() == 6);
            CHECK(len.at({"cap", "side"}) == Approx(4 * r / c).epsilon(1e-9));
            CHECK(len.at({"side", "side"}) == Approx(s.height - 2 * r * t).epsilon(1e-9));
            CHECK(len.at({"key", "side"}) == Approx(2 * w).epsilon(1e-9));
            CHECK(len.at({"cap", "key"}) == Approx(2 * w / c).epsilon(1e-9));
            CHECK(len.at({"beam", "cap"}) == Approx(s.length).epsilon(1e-9));
            CHECK(len.at({"base", "cap"}) == Approx(s.length).epsilon(1e-9));
            // Bonded joints carry cohesive elements on both sides of every joint edge (conforming: the same nodes);
            // the tied key sides are interior.
            const double bonded = 4 * r / c + (s.height - 2 * r * t) + 2 * w + 2 * s.length;
            CHECK(class_length(topo, EdgeClass::bonded) == Approx(bonded).epsilon(1e-9));
            CHECK(class_length(topo, EdgeClass::crackable) == 0.0);
        }
    }
}

TEST_CASE("macro pier: bad specs give one-line problems naming the key", "[unit][macro]") {
    MacroPierSpec s = lw_pier();
    CHECK(check(s).empty());
    for (double bad : {0.0, 90.0, -10.0, 120.0}) {
        s.texture_angle = bad;
        const auto problems = check(s);
        REQUIRE(problems.size() == 1);
        CHECK(problems[0].find("geometry.texture_angle") != std::string::npos);
        CHECK(problems[0].find("(0, 90)") != std::string::npos);
    }
    CHECK_THROWS_WITH(generate_macro_pier(s), Catch::Contains("geometry.texture_angle"));
    s = lw_pier();
    s.texture_angle = 60;  // (1 - 0.05) tan 60 = 1.65 m > 1.35 m: the diagonals would cross
    CHECK_THROWS_WITH(generate_macro_pier(s), Catch::Contains("geometry.height") && Catch::Contains("cross"));
    s = lw_pier();
    s.horizontal_joint = 0.5;
    CHECK_THROWS_WITH(generate_macro_pier(s), Catch::Contains("geometry.horizontal_joint"));
    s = lw_pier();
    s.mesh_size = 0;
    CHECK_THROWS_WITH(generate_macro_pier(s), Catch::Contains("geometry.mesh_size"));
}

TEST_CASE("macro pier through the case reader: a bad texture_angle names file, line and key", "[unit][macro]") {
    const std::string good = R"([case]
name = "macro"
thickness = 0.25
[geometry]
type = "macro"
length = 1.0
height = 1.35
texture_angle = 28.0
mesh_size = 0.1
[materials.brick]
E = 1.491e9
nu = 0.25
density = 1800.0
[regions]
cap = "brick"
side = "brick"
key = "brick"
[[stages]]
duration = 0.001
  [[stages.supports]]
  group = "pier_bottom"
  fix = "xy"
)";
    const auto dir = ::testing::tmp_dir("macro_case");
    auto r = ::testing::run_fdem("check \"" + ::testing::write_text(dir / "good.toml", good) + "\"", dir);
    INFO(r.out << r.err);
    CHECK(r.code == 0);
    std::string bad = good;
    bad.replace(bad.find("texture_angle = 28.0"), 20, "texture_angle = 95.0");
    r = ::testing::run_fdem("check \"" + ::testing::write_text(dir / "bad.toml", bad) + "\"", dir);
    CHECK(r.code != 0);
    CHECK(r.err.find("bad.toml:8") != std::string::npos);
    CHECK(r.err.find("geometry.texture_angle") != std::string::npos);
    CHECK(r.err.find("(0, 90) deg") != std::string::npos);
}

TEST_CASE("macro pier: the shipped JRC Ispra LW cyclic case (0.10 m) passes fdem check", "[unit][macro]") {
    const auto dir = ::testing::tmp_dir("macro_lw_check");
    const std::string path = std::string(FDEM_CASES_DIR) + "/jrc_ispra/macro_LW_EL010.toml";
    const auto r = ::testing::run_fdem("check \"" + path + "\"", dir);
    INFO(r.out << r.err);
    CHECK(r.code == 0);
}

// Recorded on commit 0e27abe (before the outline and Gmsh code was shared with type = "macro_wall"): the LW pier at
// 0.1 m must keep its triangles, its node coordinates and its connectivity.
TEST_CASE("macro pier: the LW pier mesh is the one recorded before the macro_wall refactor", "[regression][macro]") {
    const Mesh m = generate_macro_pier(lw_pier());
    REQUIRE(m.n_triangles() == 522);
    REQUIRE(m.n_nodes() == 292);
    double sx = 0, sy = 0, sr = 0;
    for (int k = 0; k < m.n_nodes(); ++k) {
        sx += m.xy[2 * k];
        sy += m.xy[2 * k + 1];
        sr += m.xy[2 * k] * m.xy[2 * k] + m.xy[2 * k + 1] * m.xy[2 * k + 1];
    }
    CHECK(sx == Approx(145.95608973691591).epsilon(1e-12));
    CHECK(sy == Approx(181.84670932548138).epsilon(1e-12));
    CHECK(sr == Approx(302.42518381679918).epsilon(1e-12));
    const std::map<int, std::pair<double, double>> nodes = {{0, {0.76249999999999951, 1.2237190099803987}},
                                                            {97, {0.18472268940857622, 0.62628993913910758}},
                                                            {146, {0.24461689592367603, 0.95168156235272527}},
                                                            {291, {-0.089897955821496067, 0.0}}};
    for (const auto& [k, p] : nodes) {
        CHECK(m.xy[2 * k] == Approx(p.first).margin(1e-12));
        CHECK(m.xy[2 * k + 1] == Approx(p.second).margin(1e-12));
    }
    long long weighted = 0;  // connectivity fingerprint: sum of (position in tri mod 7 + 1) * node index
    for (std::size_t i = 0; i < m.tri.size(); ++i) weighted += static_cast<long long>(i % 7 + 1) * m.tri[i];
    CHECK(weighted == 863643);
}

// ---- type = "macro_wall" (mesh/macro.hpp "WALL WITH OPENINGS") ----

namespace {

// Two JRC-Ispra-like piers 1.0 m long either side of a 1.0 m wide door 1.35 m high in a 3.0 x 2.0 m wall: a
// spandrel 1.0 x 0.65 m, tall at 28 deg ((1.0 - 0.05) tan 28 = 0.505 m < 0.65 m).
MacroWallSpec door_wall(double door_height = 1.35) {
    MacroWallSpec s;
    s.length = 3.0;
    s.height = 2.0;
    s.openings = {{1.0, 0.0, 1.0, door_height}};
    s.texture_angle = 28.0;
    s.horizontal_joint = 0.05;
    s.mesh_size = 0.1;
    s.beam_height = 0.2;
    s.base_height = 0.3;
    s.base_overhang = 0.2;
    return s;
}

TopologyOptions wall_rules() {
    TopologyOptions opt;
    const char* masonry[] = {"cap", "side", "key", "spandrel_cap", "spandrel_side", "spandrel_key", "node", "beam", "base"};
    for (const char* a : masonry)
        for (const char* b : masonry)
            if (std::string(a) <= std::string(b))
                opt.interfaces.push_back({a, b, std::string(a) == "cap" && std::string(b) == "key" ? InterfaceKind::tied
                                                                                                 : InterfaceKind::bonded});
    return opt;
}

std::map<std::string, int> bodies_per_region(const Mesh& m) {
    std::map<int, std::set<int>> bodies;
    for (int t = 0; t < m.n_triangles(); ++t) bodies[m.tri_region[t]].insert(m.tri_body[t]);
    std::map<std::string, int> out;
    for (const auto& [r, b] : bodies) out[m.regions[r]] = static_cast<int>(b.size());
    return out;
}

// The y (or x) of every edge end between two bodies of the given region pair, as a set rounded to 1 nm.
std::set<long long> joint_coordinate(const Topology& topo, const std::string& ra, const std::string& rb, int axis) {
    std::set<long long> out;
    const Mesh& m = topo.mesh;
    for (int e = 0; e < topo.n_edges(); ++e) {
        const int ta = topo.edge_tri[2 * e], tb = topo.edge_tri[2 * e + 1];
        if (tb < 0 || m.tri_body[ta] == m.tri_body[tb]) continue;
        const std::string a = m.regions[m.tri_region[ta]], b = m.regions[m.tri_region[tb]];
        if (!((a == ra && b == rb) || (a == rb && b == ra))) continue;
        for (int i = 0; i < 3; ++i) {
            const int c = m.tri[3 * ta + i];
            const int o = topo.node_origin[c];
            if (o == topo.edge_nodes[2 * e] || o == topo.edge_nodes[2 * e + 1])
                out.insert(std::llround(m.xy[2 * c + axis] * 1e9));
        }
    }
    return out;
}

}  // namespace

TEST_CASE("macro wall: a door wall has 2 pier panels, 1 spandrel, 2 nodes, tiling the wall less the door", "[unit][macro]") {
    const MacroWallSpec s = door_wall();
    REQUIRE(check(s).empty());
    std::map<std::string, int> blocks;
    for (const auto& b : macro_wall_blocks(s)) {
        ++blocks[b.region];
        CHECK_FALSE(b.transposed);  // the piers (1.0 x 1.35 m) and the spandrel (1.0 x 0.65 m) are tall at 28 deg
    }
    CHECK(blocks == std::map<std::string, int>{{"cap", 4}, {"side", 4}, {"key", 4}, {"spandrel_cap", 2},
                                               {"spandrel_side", 2}, {"spandrel_key", 2}, {"node", 2}});
    const Mesh m = generate_macro_wall(s);
    REQUIRE(m.regions == std::vector<std::string>{"cap", "side", "key", "spandrel_cap", "spandrel_side",
                                                  "spandrel_key", "node", "beam", "base"});
    CHECK(bodies_per_region(m) == std::map<std::string, int>{{"cap", 4}, {"side", 4}, {"key", 4}, {"spandrel_cap", 2},
                                                             {"spandrel_side", 2}, {"spandrel_key", 2}, {"node", 2},
                                                             {"beam", 1}, {"base", 1}});
    double area = 0;
    for (int r = 0; r < 7; ++r) area += mesh_area(m, r);
    const double expected = s.length * s.height - 1.0 * 1.35;
    CHECK(std::abs(area - expected) <= 1e-9 * expected);
    for (int t = 0; t < m.n_triangles(); ++t) CHECK(tri_area(m, t) > 0);
    for (const char* g : {"wall_bottom", "wall_top", "wall_left", "wall_right", "beam_top", "beam_left", "beam_right",
                          "base_bottom", "base_left", "base_right", "toe_left", "toe_right"})
        REQUIRE(m.find_group(g) != nullptr);
    for (int k : m.find_group("wall_top")->nodes) CHECK(m.xy[2 * k + 1] == Approx(2.0).margin(1e-12));
    for (int k : m.find_group("wall_bottom")->nodes) {
        CHECK(m.xy[2 * k + 1] == Approx(0.0).margin(1e-12));
        CHECK((m.xy[2 * k] <= 1.0 + 1e-12 || m.xy[2 * k] >= 2.0 - 1e-12));  // not under the door
    }
    for (int k : m.find_group("wall_right")->nodes) CHECK(m.xy[2 * k] == Approx(3.0).margin(1e-12));
    // The documented joint pairs and their lengths (tall panels): nothing else touches.
    const Topology topo = build_topology(m, wall_rules());
    CHECK(topo.nonconforming_nodes == 0);
    const auto len = joint_lengths(topo);
    std::set<std::pair<std::string, std::string>> pairs;
    for (const auto& [p, l] : len) pairs.insert(p);
    CHECK(pairs == std::set<std::pair<std::string, std::string>>{
                       {"cap", "side"}, {"side", "side"}, {"key", "side"}, {"cap", "key"},
                       {"spandrel_cap", "spandrel_side"}, {"spandrel_side", "spandrel_side"},
                       {"spandrel_key", "spandrel_side"}, {"spandrel_cap", "spandrel_key"},
                       {"cap", "node"}, {"node", "spandrel_side"}, {"beam", "spandrel_cap"}, {"beam", "node"},
                       {"base", "cap"}});
    CHECK(len.at({"cap", "node"}) == Approx(2.0).epsilon(1e-9));
    CHECK(len.at({"node", "spandrel_side"}) == Approx(2 * 0.65).epsilon(1e-9));
    CHECK(len.at({"beam", "spandrel_cap"}) == Approx(1.0).epsilon(1e-9));
    CHECK(len.at({"beam", "node"}) == Approx(2.0).epsilon(1e-9));
    CHECK(len.at({"base", "cap"}) == Approx(2.0).epsilon(1e-9));
    // The tall spandrel's central joint is vertical, at the door's mid-length.
    CHECK(joint_coordinate(topo, "spandrel_side", "spandrel_side", 0) == std::set<long long>{1500000000});
}

TEST_CASE("macro wall: a window with a sill gives 2 spandrels and 4 nodes", "[unit][macro]") {
    MacroWallSpec s = door_wall();
    // Lower spandrel 1.0 x 0.5 m: transposed (0.5 <= (1.0 - 0.05) tan 28 = 0.505 m); upper 1.0 x 0.6 m: tall;
    // piers 1.0 x 0.9 m: tall.
    s.openings = {{1.0, 0.5, 1.0, 0.9}};
    const Mesh m = generate_macro_wall(s);
    CHECK(bodies_per_region(m) == std::map<std::string, int>{{"cap", 4}, {"side", 4}, {"key", 4}, {"spandrel_cap", 4},
                                                             {"spandrel_side", 4}, {"spandrel_key", 4}, {"node", 4},
                                                             {"beam", 1}, {"base", 1}});
    double area = 0;
    for (int r = 0; r < 7; ++r) area += mesh_area(m, r);
    const double expected = s.length * s.height - 1.0 * 0.9;
    CHECK(std::abs(area - expected) <= 1e-9 * expected);
    for (int t = 0; t < m.n_triangles(); ++t) CHECK(tri_area(m, t) > 0);
    const Topology topo = build_topology(m, wall_rules());
    CHECK(topo.nonconforming_nodes == 0);
    const auto len = joint_lengths(topo);
    CHECK(len.at({"base", "node"}) == Approx(2.0).epsilon(1e-9));
    CHECK(len.at({"base", "spandrel_side"}) == Approx(1.0).epsilon(1e-9));  // transposed: "side" blocks at the bottom
    CHECK(len.at({"beam", "spandrel_cap"}) == Approx(1.0).epsilon(1e-9));   // tall: cap at the top
    CHECK(len.at({"cap", "node"}) == Approx(4.0).epsilon(1e-9));            // piers under and over nodes
    CHECK(len.count({"base", "cap"}) == 0);
    CHECK(len.count({"base", "spandrel_cap"}) == 0);
}

TEST_CASE("macro wall: a squat spandrel takes the transposed layout, its central joint horizontal", "[unit][macro]") {
    const MacroWallSpec s = door_wall(1.6);  // spandrel 1.0 x 0.4 m: 0.4 <= (1.0 - 0.05) tan 28 = 0.505 m
    int transposed = 0;
    for (const auto& b : macro_wall_blocks(s)) {
        CHECK(b.transposed == (b.region.rfind("spandrel_", 0) == 0));
        transposed += b.transposed;
    }
    CHECK(transposed == 6);
    const Mesh m = generate_macro_wall(s);
    for (int t = 0; t < m.n_triangles(); ++t) CHECK(tri_area(m, t) > 0);
    double area = 0;
    for (int r = 0; r < 7; ++r) area += mesh_area(m, r);
    CHECK(std::abs(area - (6.0 - 1.6)) <= 1e-9 * (6.0 - 1.6));
    const Topology topo = build_topology(m, wall_rules());
    CHECK(topo.nonconforming_nodes == 0);
    // Central joint at mid-height of the spandrel, y = 1.6 + 0.2; length L - (H - w) / t.
    CHECK(joint_coordinate(topo, "spandrel_side", "spandrel_side", 1) == std::set<long long>{1800000000});
    const double t = std::tan(28.0 * kPi / 180);
    const auto len = joint_lengths(topo);
    CHECK(len.at({"spandrel_side", "spandrel_side"}) == Approx(1.0 - (0.4 - 0.05) / t).epsilon(1e-9));
    // Diagonals keep dy/dx = tan 28: each runs (0.4 - 0.05) / 2 in y, so its length is that / sin(phi).
    CHECK(len.at({"spandrel_cap", "spandrel_side"}) == Approx(4 * 0.5 * (0.4 - 0.05) / std::sin(28.0 * kPi / 180)).epsilon(1e-9));
    // The caps are the end blocks, against the nodes; the "side" blocks against the beam.
    CHECK(len.at({"node", "spandrel_cap"}) == Approx(2 * 0.4).epsilon(1e-9));
    CHECK(len.at({"beam", "spandrel_side"}) == Approx(1.0).epsilon(1e-9));
    CHECK(len.count({"node", "spandrel_side"}) == 0);
}

TEST_CASE("macro wall: bad openings give one-line problems naming the opening and the values", "[unit][macro]") {
    auto problem = [](const MacroWallSpec& s) {
        const auto p = check(s);
        REQUIRE(p.size() == 1);
        CHECK_THROWS_WITH(generate_macro_wall(s), Catch::Contains(p[0]));
        return p[0];
    };
    using Catch::Contains;
    MacroWallSpec s = door_wall();
    s.length = 5.0;
    s.openings = {{1.0, 0.0, 1.0, 1.35}, {3.0, 0.2, 1.0, 1.35}};  // not aligned: y differs
    CHECK_THAT(problem(s), Contains("geometry.openings[2].y = 0.2 m") && Contains("one row of openings"));
    s.openings = {{1.0, 0.0, 1.0, 1.35}, {3.0, 0.0, 1.0, 1.2}};  // not aligned: height differs
    CHECK_THAT(problem(s), Contains("geometry.openings[2].height = 1.2 m") && Contains("one row of openings"));
    s.openings = {{2.5, 0.0, 1.0, 1.35}, {1.0, 0.0, 2.0, 1.35}};  // overlapping (given out of x order)
    CHECK_THAT(problem(s), Contains("geometry.openings[2] (x in [1, 3] m) and geometry.openings[1] (x in [2.5, 3.5] m)") &&
                               Contains("overlap"));
    s.openings = {{1.0, 0.0, 1.0, 1.35}, {2.0, 0.0, 1.0, 1.35}};  // touching: no pier between
    CHECK_THAT(problem(s), Contains("overlap or touch"));
    s = door_wall();
    s.openings = {{0.0, 0.0, 1.0, 1.35}};  // at the left end
    CHECK_THAT(problem(s), Contains("geometry.openings[1].x = 0 m") && Contains("left end"));
    s.openings = {{2.0, 0.0, 1.0, 1.35}};  // reaching the right end
    CHECK_THAT(problem(s), Contains("geometry.openings[1]: x + width = 3 m") && Contains("right end"));
    s.openings = {{1.0, 0.8, 1.0, 1.35}};  // lintel 2.15 m above the 2.0 m wall
    CHECK_THAT(problem(s), Contains("lintel y + height = 2.15 m") && Contains("geometry.height = 2 m"));
    s.openings = {{1.0, -0.1, 1.0, 1.35}};
    CHECK_THAT(problem(s), Contains("geometry.openings[1].y (the sill) must be >= 0"));
    s.openings.clear();
    CHECK_THAT(problem(s), Contains("geometry.openings") && Contains("at least one opening"));
    s = door_wall();
    s.openings = {{0.2, 0.0, 1.0, 1.35}};  // a 0.2 m pier: the 0.15 m joints do not fit (0.15 >= 0.1)
    s.horizontal_joint = 0.15;
    CHECK_THAT(problem(s), Contains("geometry.horizontal_joint = 0.15 m does not fit the pier panel 1"));
}

// The case text of the door wall (3.0 x 2.0 m, a 1.0 x 1.35 m door at x = 1.0) for the reader tests; with a lintel
// 0.15 m high with 0.2 m bearings, of an RC material.
static std::string door_wall_case(bool lintel) {
    const std::string geometry_extra = lintel ? "lintel_height = 0.15\nlintel_bearing = 0.2\n" : "";
    const std::string material_extra = lintel ? "[materials.rc]\nE = 3.0e10\nnu = 0.2\ndensity = 2400.0\n" : "";
    const std::string region_extra = lintel ? "lintel = \"rc\"\n" : "";
    return std::string(R"([case]
name = ")") + (lintel ? "macro_wall_lintel" : "macro_wall") + R"("
thickness = 0.25
[geometry]
type = "macro_wall"
length = 3.0
height = 2.0
texture_angle = 28.0
mesh_size = 0.1
)" + geometry_extra + R"(  [[geometry.openings]]
  x = 1.0
  y = 0.0
  width = 1.0
  height = 1.35
[materials.brick]
E = 1.491e9
nu = 0.25
density = 1800.0
)" + material_extra + R"([regions]
cap = "brick"
side = "brick"
key = "brick"
spandrel_cap = "brick"
spandrel_side = "brick"
spandrel_key = "brick"
node = "brick"
)" + region_extra + R"([[stages]]
duration = 0.001
  [[stages.supports]]
  group = "wall_bottom"
  fix = "xy"
)";
}

TEST_CASE("macro wall through the case reader: unknown keys are rejected, bad openings name file and key", "[unit][macro]") {
    const std::string good = door_wall_case(false);
    const auto dir = ::testing::tmp_dir("macro_wall_case");
    auto r = ::testing::run_fdem("check \"" + ::testing::write_text(dir / "good.toml", good) + "\"", dir);
    INFO(r.out << r.err);
    CHECK(r.code == 0);
    std::string bad = good;
    bad.replace(bad.find("mesh_size = 0.1"), 15, "mesh_size = 0.1\ncourses = 3");
    r = ::testing::run_fdem("check \"" + ::testing::write_text(dir / "unknown.toml", bad) + "\"", dir);
    CHECK(r.code != 0);
    CHECK(r.err.find("geometry.courses") != std::string::npos);
    bad = good;
    bad.replace(bad.find("  height = 1.35"), 15, "  height = 2.35");
    r = ::testing::run_fdem("check \"" + ::testing::write_text(dir / "lintel.toml", bad) + "\"", dir);
    CHECK(r.code != 0);
    CHECK(r.err.find("lintel.toml:4") != std::string::npos);
    CHECK(r.err.find("geometry.openings[1]: the lintel y + height = 2.35 m") != std::string::npos);
}

namespace {

// A mesh's fingerprint for the recorded-mesh test below: counts, coordinate sums, connectivity, regions, bodies.
struct MeshPrint {
    int triangles = 0, nodes = 0;
    double sx = 0, sy = 0, sr = 0;
    long long weighted = 0, regions = 0, bodies = 0;
};

MeshPrint print_of(const Mesh& m) {
    MeshPrint p;
    p.triangles = m.n_triangles();
    p.nodes = m.n_nodes();
    for (int k = 0; k < m.n_nodes(); ++k) {
        p.sx += m.xy[2 * k];
        p.sy += m.xy[2 * k + 1];
        p.sr += m.xy[2 * k] * m.xy[2 * k] + m.xy[2 * k + 1] * m.xy[2 * k + 1];
    }
    for (std::size_t i = 0; i < m.tri.size(); ++i) p.weighted += static_cast<long long>(i % 7 + 1) * m.tri[i];
    for (int t = 0; t < m.n_triangles(); ++t) {
        p.regions += static_cast<long long>(t % 5 + 1) * m.tri_region[t];
        p.bodies += static_cast<long long>(t % 5 + 1) * m.tri_body[t];
    }
    return p;
}

}  // namespace

// Recorded on commit fc933ff (before lintels): the door wall, the window wall and the squat-spandrel wall at 0.1 m
// must keep their triangles, node coordinates, connectivity, regions and bodies when no lintel is given.
TEST_CASE("macro wall: the meshes without a lintel are the ones recorded before lintels existed", "[regression][macro]") {
    MacroWallSpec window = door_wall();
    window.openings = {{1.0, 0.5, 1.0, 0.9}};
    const MacroWallSpec specs[] = {door_wall(), window, door_wall(1.6)};
    const MeshPrint recorded[] = {
        {1766, 967, 1451.6357517664935, 924.1800533088275, 4549.3282802151343, 9964199, 19642, 65094},
        {1864, 1010, 1515.4603975070927, 913.65145943266521, 4579.6999365163274, 11024626, 24242, 102747},
        {1658, 914, 1370.0973907796094, 867.19113332286622, 4335.906876470669, 8793245, 16846, 56541}};
    for (int i = 0; i < 3; ++i) {
        INFO("wall " << i);
        const MeshPrint p = print_of(generate_macro_wall(specs[i]));
        const MeshPrint& r = recorded[i];
        REQUIRE(p.triangles == r.triangles);
        REQUIRE(p.nodes == r.nodes);
        CHECK(p.sx == Approx(r.sx).epsilon(1e-12));
        CHECK(p.sy == Approx(r.sy).epsilon(1e-12));
        CHECK(p.sr == Approx(r.sr).epsilon(1e-12));
        CHECK(p.weighted == r.weighted);
        CHECK(p.regions == r.regions);
        CHECK(p.bodies == r.bodies);
    }
}

// ---- lintels (mesh/macro.hpp "LINTELS") ----

namespace {

// The door wall with a lintel 0.15 m deep bearing 0.2 m on each pier: lintel [0.8, 2.2] x [1.35, 1.5], band nodes
// [0, 0.8] and [2.2, 3.0] x [1.35, 1.5], spandrel 1.0 x 0.5 m from y = 1.5, transposed at 28 deg (0.5 <= (1.0 -
// 0.05) tan 28 = 0.505 m), nodes [0, 1] and [2, 3] x [1.5, 2.0] above.
MacroWallSpec lintel_wall() {
    MacroWallSpec s = door_wall();
    s.lintel_height = 0.15;
    s.lintel_bearing = 0.2;
    return s;
}

// A bonded rule for every pair of the mesh's regions (cap-key tied).
TopologyOptions lintel_rules(const Mesh& m) {
    TopologyOptions opt;
    for (const std::string& a : m.regions)
        for (const std::string& b : m.regions)
            if (a <= b) opt.interfaces.push_back({a, b, a == "cap" && b == "key" ? InterfaceKind::tied : InterfaceKind::bonded});
    return opt;
}

double outline_area(const std::vector<std::array<double, 2>>& p) {
    double a = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const auto& u = p[i];
        const auto& v = p[(i + 1) % p.size()];
        a += u[0] * v[1] - v[0] * u[1];
    }
    return 0.5 * a;
}

}  // namespace

TEST_CASE("macro wall lintel: the door wall's lintel band, the shorter spandrel and the documented pairs", "[unit][macro]") {
    const MacroWallSpec s = lintel_wall();
    REQUIRE(check(s).empty());
    std::map<std::string, int> blocks;
    double block_area = 0;
    for (const auto& b : macro_wall_blocks(s)) {
        ++blocks[b.region];
        block_area += outline_area(b.outline);
        CHECK(b.transposed == (b.region.rfind("spandrel_", 0) == 0));  // the 0.5 m spandrel is squat now
        if (b.region == "lintel") CHECK(outline_area(b.outline) == Approx((1.0 + 2 * 0.2) * 0.15).epsilon(1e-12));
        if (b.region.rfind("spandrel_", 0) == 0)
            for (const auto& v : b.outline) {
                CHECK(v[1] >= 1.35 + 0.15);
                CHECK(v[1] <= 2.0);
            }
    }
    CHECK(blocks == std::map<std::string, int>{{"cap", 4}, {"side", 4}, {"key", 4}, {"spandrel_cap", 2},
                                               {"spandrel_side", 2}, {"spandrel_key", 2}, {"node", 4}, {"lintel", 1}});
    const double expected = s.length * s.height - 1.0 * 1.35;
    CHECK(std::abs(block_area - expected) <= 1e-9 * expected);

    const Mesh m = generate_macro_wall(s);
    REQUIRE(m.regions == std::vector<std::string>{"cap", "side", "key", "spandrel_cap", "spandrel_side",
                                                  "spandrel_key", "node", "lintel", "beam", "base"});
    CHECK(bodies_per_region(m) == std::map<std::string, int>{{"cap", 4}, {"side", 4}, {"key", 4}, {"spandrel_cap", 2},
                                                             {"spandrel_side", 2}, {"spandrel_key", 2}, {"node", 4},
                                                             {"lintel", 1}, {"beam", 1}, {"base", 1}});
    double area = 0;
    for (int r = 0; r < 8; ++r) area += mesh_area(m, r);
    CHECK(std::abs(area - expected) <= 1e-9 * expected);
    CHECK(mesh_area(m, 7) == Approx(1.4 * 0.15).epsilon(1e-9));
    for (int t = 0; t < m.n_triangles(); ++t) CHECK(tri_area(m, t) > 0);
    // The spandrel's triangles lie in [1.5, 2.0]: the spandrel panel starts on the lintel.
    for (int t = 0; t < m.n_triangles(); ++t)
        if (m.regions[m.tri_region[t]].rfind("spandrel_", 0) == 0)
            for (int i = 0; i < 3; ++i) {
                const double y = m.xy[2 * m.tri[3 * t + i] + 1];
                CHECK((y >= 1.5 - 1e-12 && y <= 2.0 + 1e-12));
            }
    // The touching pairs are the documented ones (macro.hpp "LINTELS", transposed spandrel, tall piers).
    const Topology topo = build_topology(m, lintel_rules(m));
    CHECK(topo.nonconforming_nodes == 0);  // the T-junctions at the bearing ends are conforming
    const auto len = joint_lengths(topo);
    std::set<std::pair<std::string, std::string>> pairs;
    for (const auto& [p, l] : len) pairs.insert(p);
    CHECK(pairs == std::set<std::pair<std::string, std::string>>{
                       {"cap", "side"}, {"side", "side"}, {"key", "side"}, {"cap", "key"},
                       {"spandrel_cap", "spandrel_side"}, {"spandrel_side", "spandrel_side"},
                       {"spandrel_key", "spandrel_side"}, {"spandrel_cap", "spandrel_key"},
                       {"cap", "node"}, {"cap", "lintel"}, {"lintel", "node"}, {"lintel", "spandrel_side"},
                       {"node", "node"}, {"node", "spandrel_cap"}, {"beam", "spandrel_side"}, {"beam", "node"},
                       {"base", "cap"}});
    CHECK(len.at({"cap", "lintel"}) == Approx(2 * 0.2).epsilon(1e-9));            // the two bearings
    CHECK(len.at({"cap", "node"}) == Approx(2 * 0.8).epsilon(1e-9));              // the piers' tops beside them
    CHECK(len.at({"lintel", "node"}) == Approx(2 * 0.15 + 2 * 0.2).epsilon(1e-9));  // bearing ends and tops
    CHECK(len.at({"lintel", "spandrel_side"}) == Approx(1.0).epsilon(1e-9));
    CHECK(len.at({"node", "node"}) == Approx(2 * 0.8).epsilon(1e-9));             // band node under the node above
    CHECK(len.at({"node", "spandrel_cap"}) == Approx(2 * 0.5).epsilon(1e-9));
    CHECK(len.at({"beam", "spandrel_side"}) == Approx(1.0).epsilon(1e-9));
    CHECK(len.at({"beam", "node"}) == Approx(2.0).epsilon(1e-9));
    // The bearings are the piers' tops in x in [0.8, 1.0] and [2.0, 2.2], ends included.
    const auto bearing_x = joint_coordinate(topo, "cap", "lintel", 0);
    for (long long x : {800000000LL, 1000000000LL, 2000000000LL, 2200000000LL}) CHECK(bearing_x.count(x) == 1);
    for (long long x : bearing_x) CHECK(((x >= 800000000 && x <= 1000000000) || (x >= 2000000000 && x <= 2200000000)));
}

TEST_CASE("macro wall lintel: a lintel up to the wall top leaves no upper band and meets the beam", "[unit][macro]") {
    MacroWallSpec s = lintel_wall();
    s.lintel_height = 2.0 - 1.35;  // y_l + lintel_height = 2.0 = height
    REQUIRE(check(s).empty());
    const Mesh m = generate_macro_wall(s);
    CHECK(bodies_per_region(m) == std::map<std::string, int>{{"cap", 4}, {"side", 4}, {"key", 4}, {"node", 2},
                                                             {"lintel", 1}, {"beam", 1}, {"base", 1}});
    double area = 0;
    for (int r = 0; r < static_cast<int>(m.regions.size()); ++r)
        if (m.regions[r] != "beam" && m.regions[r] != "base") area += mesh_area(m, r);
    CHECK(std::abs(area - (6.0 - 1.35)) <= 1e-9 * (6.0 - 1.35));
    const Topology topo = build_topology(m, lintel_rules(m));
    CHECK(topo.nonconforming_nodes == 0);
    const auto len = joint_lengths(topo);
    CHECK(len.at({"beam", "lintel"}) == Approx(1.4).epsilon(1e-9));
    CHECK(len.at({"beam", "node"}) == Approx(1.6).epsilon(1e-9));
    CHECK(len.at({"lintel", "node"}) == Approx(2 * (2.0 - 1.35)).epsilon(1e-9));
    CHECK(len.count({"node", "node"}) == 0);
}

TEST_CASE("macro wall lintel: bad lintel keys give one-line problems naming the key and the values", "[unit][macro]") {
    auto problem = [](const MacroWallSpec& s) {
        const auto p = check(s);
        REQUIRE(p.size() == 1);
        CHECK_THROWS_WITH(generate_macro_wall(s), Catch::Contains(p[0]));
        return p[0];
    };
    using Catch::Contains;
    MacroWallSpec s = lintel_wall();
    s.openings = {{0.5, 0.0, 1.0, 1.35}};  // end piers 0.5 and 1.5 m: a 0.6 m bearing leaves nothing of pier 1
    s.lintel_bearing = 0.6;
    CHECK_THAT(problem(s), Contains("geometry.lintel_bearing = 0.6 m leaves no node between the lintels on pier 1 "
                                    "(x in [0, 0.5] m): its bearing (0.6 m) must be shorter than its length 0.5 m"));
    s = lintel_wall();
    s.length = 5.0;
    s.openings = {{1.0, 0.0, 1.0, 1.35}, {2.8, 0.0, 1.0, 1.35}};  // interior pier 0.8 m: two 0.45 m bearings
    s.lintel_bearing = 0.45;
    CHECK_THAT(problem(s), Contains("geometry.lintel_bearing = 0.45 m leaves no node between the lintels on pier 2 "
                                    "(x in [2, 2.8] m): its 2 bearings (0.9 m) must be shorter than its length 0.8 m"));
    s.lintel_bearing = 0.39;  // 0.78 m < 0.8 m: fine
    CHECK(check(s).empty());
    s = lintel_wall();
    s.lintel_height = 0.7;  // 1.35 + 0.7 = 2.05 m > 2.0 m
    CHECK_THAT(problem(s), Contains("geometry.lintel_height = 0.7 m puts the lintels' top (y + height + "
                                    "lintel_height = 2.05 m) above the wall's geometry.height = 2 m"));
    s = lintel_wall();
    s.lintel_height = 0;
    CHECK_THAT(problem(s), Contains("geometry.lintel_bearing = 0.2 m needs a lintel: geometry.lintel_height must be "
                                    "> 0 with it, got 0 m"));
    s = lintel_wall();
    s.lintel_height = -0.1;
    s.lintel_bearing = 0;
    CHECK_THAT(problem(s), Contains("geometry.lintel_height must be >= 0 (m), got -0.1"));
    s = lintel_wall();
    s.lintel_bearing = -0.1;
    CHECK_THAT(problem(s), Contains("geometry.lintel_bearing must be >= 0 (m), got -0.1"));
    s = lintel_wall();
    s.lintel_height = 0.6;  // the spandrel above is 0.05 m high (transposed): its 0.05 m joints do not fit
    CHECK_THAT(problem(s), Contains("geometry.horizontal_joint = 0.05 m does not fit the spandrel above opening 1") &&
                               Contains("y in [1.95, 2] m, transposed layout"));
}

TEST_CASE("macro wall lintel through the case reader: the keys are read, a bearing without a lintel names the key", "[unit][macro]") {
    const std::string good = door_wall_case(true);
    const auto dir = ::testing::tmp_dir("macro_wall_lintel_case");
    auto r = ::testing::run_fdem("check \"" + ::testing::write_text(dir / "good.toml", good) + "\"", dir);
    INFO(r.out << r.err);
    CHECK(r.code == 0);
    std::string bad = good;
    bad.replace(bad.find("lintel = \"rc\""), 13, "");  // the lintel region needs a material: it was read
    r = ::testing::run_fdem("check \"" + ::testing::write_text(dir / "no_material.toml", bad) + "\"", dir);
    CHECK(r.code != 0);
    CHECK(r.err.find("lintel") != std::string::npos);
    bad = good;
    bad.replace(bad.find("lintel_height = 0.15"), 20, "lintel_height = 0.0");
    r = ::testing::run_fdem("check \"" + ::testing::write_text(dir / "bearing.toml", bad) + "\"", dir);
    CHECK(r.code != 0);
    CHECK(r.err.find("geometry.lintel_bearing = 0.2 m needs a lintel") != std::string::npos);
}
