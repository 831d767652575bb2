// tests/mesh/test_import.cpp: .geo and .msh (2.2, 4.1) imports give the topology of the generated wall; VTU output.
#include <catch2/catch.hpp>

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "helpers.hpp"
#include "mesh/gmsh_source.hpp"
#include "mesh/topology.hpp"
#include "mesh/vtu.hpp"
#include "mesh/wall.hpp"

using namespace fdem::mesh;
using namespace fdem::mesh::testing;

namespace {

const std::string geo_path = std::string(FDEM_TEST_DATA_DIR) + "/mesh/wall_running_bond.geo";

std::string tmp_dir() {
    const std::string d = std::string(FDEM_TEST_TMP) + "/mesh";
    std::filesystem::create_directories(d);
    return d;
}

TopologyOptions dry_units() {
    TopologyOptions o;
    o.regions = {{"units", true}};
    o.interfaces = {{"units", "units", InterfaceKind::dry}};
    return o;
}

void require_same_layout(const LayoutSignature& a, const LayoutSignature& b) {
    REQUIRE(a.bodies.size() == b.bodies.size());
    for (auto ia = a.bodies.begin(), ib = b.bodies.begin(); ia != a.bodies.end(); ++ia, ++ib) {
        REQUIRE(ia->first == ib->first);
        CHECK(std::abs(ia->second - ib->second) <= 1e-12);
    }
    REQUIRE(a.joints.size() == b.joints.size());
    for (auto ia = a.joints.begin(), ib = b.joints.begin(); ia != a.joints.end(); ++ia, ++ib) {
        REQUIRE(ia->first == ib->first);
        REQUIRE(ia->second.size() == ib->second.size());
        for (const auto& [cls, len] : ia->second) CHECK(std::abs(len - ib->second.at(cls)) <= 1e-9);
    }
    for (int c : {static_cast<int>(EdgeClass::dry), static_cast<int>(EdgeClass::free_boundary)})
        CHECK(std::abs(a.class_lengths.at(c) - b.class_lengths.at(c)) <= 1e-9);
}

}  // namespace

TEST_CASE(".geo with physical groups and its .msh 2.2 / 4.1 exports match the generated wall", "[regression]") {
    const Mesh generated = generate_wall(cases_a_wall());
    const Topology tg = build_topology(generated, dry_units());
    const LayoutSignature sg = signature(tg);
    REQUIRE(sg.bodies.size() == 55);
    // Touching unit pairs: 45 head joints; across each of the 9 bed joints every full unit of the 5-unit course
    // meets 2 units of the 6-piece course (the joints are offset by half a unit): 10 pairs.
    REQUIRE(sg.joints.size() == 45 + 9 * 10);

    const Mesh geo = mesh_geo_file(geo_path);
    REQUIRE(geo.regions == std::vector<std::string>{"units"});
    const Topology tgeo = build_topology(geo, dry_units());
    require_same_layout(signature(tgeo), sg);
    for (const char* g : {"wall_bottom", "wall_top", "wall_left", "wall_right", "toe_left", "toe_right"}) {
        REQUIRE(geo.find_group(g) != nullptr);
        CHECK(geo.find_group(g)->nodes.size() == generated.find_group(g)->nodes.size());
    }

    // Export the .geo's mesh in both formats through the API, then import each.
    const std::string dir = tmp_dir();
    {
        GmshSession session;
        gmsh::open(geo_path);
        gmsh::model::mesh::generate(2);
        gmsh::option::setNumber("Mesh.MshFileVersion", 2.2);
        gmsh::write(dir + "/wall_22.msh");
        gmsh::option::setNumber("Mesh.MshFileVersion", 4.1);
        gmsh::write(dir + "/wall_41.msh");
    }
    for (const char* file : {"/wall_22.msh", "/wall_41.msh"}) {
        CAPTURE(file);
        const Mesh msh = read_msh_file(dir + file);
        // Same mesh as the .geo run: identical counts, and the same layout as the generated wall.
        CHECK(msh.n_triangles() == geo.n_triangles());
        CHECK(msh.n_nodes() == geo.n_nodes());
        CHECK(msh.n_bodies() == 55);
        REQUIRE(msh.regions == std::vector<std::string>{"units"});
        const Topology tm = build_topology(msh, dry_units());
        CHECK(tm.mesh.n_nodes() == tgeo.mesh.n_nodes());
        CHECK(tm.cohesive.size() == tgeo.cohesive.size());
        CHECK(tm.contact_capable.size() == tgeo.contact_capable.size());
        require_same_layout(signature(tm), sg);
        for (const char* g : {"wall_bottom", "wall_top", "wall_left", "wall_right", "toe_left", "toe_right"}) {
            REQUIRE(msh.find_group(g) != nullptr);
            CHECK(msh.find_group(g)->nodes.size() == geo.find_group(g)->nodes.size());
            CHECK(msh.find_group(g)->edges.size() == geo.find_group(g)->edges.size());
        }
    }
}

TEST_CASE("import errors name the file", "[unit]") {
    CHECK_THROWS_WITH(read_msh_file("/nonexistent/wall.msh"), Catch::Contains("/nonexistent/wall.msh"));
    CHECK_THROWS_WITH(mesh_geo_file("/nonexistent/wall.geo"), Catch::Contains("/nonexistent/wall.geo"));
    const std::string bad = tmp_dir() + "/broken.geo";
    {
        std::ofstream f(bad);
        f << "Point(1) = {0, 0, 0};\nThis is not Gmsh;\n";
    }
    CHECK_THROWS_WITH(mesh_geo_file(bad), Catch::Contains("broken.geo"));
}

TEST_CASE("VTU output holds the split mesh and the classified edges", "[unit]") {
    WallSpec s = cases_a_wall(0.1);
    s.beam_height = 0.1;
    const Mesh m = generate_wall(s);
    TopologyOptions o = dry_units();
    o.interfaces.push_back({"units", "beam", InterfaceKind::bonded});
    const Topology topo = build_topology(m, o);
    const std::string path = tmp_dir() + "/wall.vtu";
    std::remove(path.c_str());
    write_topology_vtu(path, topo);
    REQUIRE(std::filesystem::exists(path));
    CHECK_FALSE(std::filesystem::exists(path + ".tmp"));
    std::ifstream f(path);
    std::stringstream buf;
    buf << f.rdbuf();
    const std::string text = buf.str();
    std::ostringstream head;
    head << "NumberOfPoints=\"" << topo.mesh.n_nodes() << "\" NumberOfCells=\""
         << topo.mesh.n_triangles() + topo.n_edges() << "\"";
    CHECK(text.find(head.str()) != std::string::npos);
    for (const char* name : {"\"region\"", "\"body\"", "\"contact_capable\"", "\"edge_class\"", "\"node_origin\"",
                             "\"cell_kind\"", "</VTKFile>"})
        CHECK(text.find(name) != std::string::npos);
    CHECK_THROWS_WITH(write_topology_vtu("/nonexistent/dir/x.vtu", topo), Catch::Contains("/nonexistent/dir/x.vtu"));
}

TEST_CASE("a .geo with overlapping, unfragmented units is rejected by the topology", "[unit]") {
    const std::string path = tmp_dir() + "/overlap.geo";
    {
        std::ofstream f(path);
        f << "SetFactory(\"OpenCASCADE\");\n"
             "Rectangle(1) = {0, 0, 0, 0.2, 0.1};\n"
             "Rectangle(2) = {0.15, 0.05, 0, 0.2, 0.1};\n"
             "MeshSize{ PointsOf{ Surface{:}; } } = 0.02;\n"
             "Physical Surface(\"units\") = {1, 2};\n";
    }
    const Mesh m = mesh_geo_file(path);
    CHECK(m.n_bodies() == 2);
    TopologyOptions o;
    o.interfaces = {{"units", "units", InterfaceKind::dry}};
    CHECK_THROWS_WITH(build_topology(m, o), Catch::Contains("overlap") && Catch::Contains("'units'"));
    // A missing group named by a case.
    CHECK_THROWS_WITH(m.require_group("beam_top"), Catch::Contains("'beam_top'") && Catch::Contains("does not exist"));
    CHECK_THROWS_WITH(m.require_group("units", 1), Catch::Contains("'units' is 2D"));
    CHECK(m.require_group("units", 2).triangles.size() == static_cast<std::size_t>(m.n_triangles()));
    // A Gmsh failure does not leak into the next, valid model.
    CHECK_THROWS(mesh_geo_file(tmp_dir() + "/broken.geo"));
    CHECK_NOTHROW(generate_wall(cases_a_wall(0.1)));
    InterfaceKind k{};
    CHECK(parse_interface_kind("bonded", k));
    CHECK(k == InterfaceKind::bonded);
    CHECK_FALSE(parse_interface_kind("glued", k));
}

TEST_CASE("units touching without shared nodes: counted for dry pairs, an error for bonded or unruled ones", "[unit]") {
    const std::string path = tmp_dir() + "/unfragmented.geo";
    {
        std::ofstream f(path);
        f << "SetFactory(\"OpenCASCADE\");\n"
             "Rectangle(1) = {0, 0, 0, 0.2, 0.1};\n"
             "Rectangle(2) = {0.2, 0, 0, 0.2, 0.1};\n"
             "MeshSize{ PointsOf{ Surface{1}; } } = 0.02;\n"
             "MeshSize{ PointsOf{ Surface{2}; } } = 0.03;\n"
             "Physical Surface(\"units\") = {1, 2};\n";
    }
    const Mesh m = mesh_geo_file(path);
    REQUIRE(m.n_bodies() == 2);
    TopologyOptions o;
    o.interfaces = {{"units", "units", InterfaceKind::dry}};
    const Topology topo = build_topology(m, o);
    CHECK(topo.nonconforming_nodes >= 2 * 4);  // both sides' nodes along the 0.1 m face (5 and 4 segments)
    CHECK(class_length(topo, EdgeClass::dry) == 0.0);
    o.interfaces = {{"units", "units", InterfaceKind::bonded}};
    CHECK_THROWS_WITH(build_topology(m, o), Catch::Contains("without sharing nodes") && Catch::Contains("bonded"));
    o.interfaces.clear();
    CHECK_THROWS_WITH(build_topology(m, o), Catch::Contains("without sharing nodes") && Catch::Contains("no interface rule"));
}

namespace {
std::string write_geo(const std::string& name, const std::string& extra) {
    const std::string path = tmp_dir() + "/" + name;
    std::ofstream f(path);
    f << "Point(1) = {0, 0, 0, 0.5};\nPoint(2) = {1, 0, 0, 0.5};\nPoint(3) = {1, 1, 0, 0.5};\nPoint(4) = {0, 1, 0, 0.5};\n"
         "Point(5) = {0, 2, 0, 0.5};\nPoint(6) = {1, 2, 0, 0.5};\n"
         "Line(1) = {1, 2};\nLine(2) = {2, 3};\nLine(3) = {3, 4};\nLine(4) = {4, 1};\n"
         "Line(5) = {3, 6};\nLine(6) = {6, 5};\nLine(7) = {5, 4};\n"
         "Curve Loop(1) = {1, 2, 3, 4};\nPlane Surface(1) = {1};\nCurve Loop(2) = {-3, 5, 6, 7};\nPlane Surface(2) = {2};\n"
      << extra;
    return path;
}
}  // namespace

TEST_CASE("elements other than 3-node triangles and surfaces outside every group are refused, not dropped", "[unit]") {
    // Quadrangles of a recombined surface: refused with the surface and the element name.
    const std::string quads = write_geo("quads.geo", "Recombine Surface{2};\nPhysical Surface(\"all\") = {1, 2};\n");
    CHECK_THROWS_WITH(mesh_geo_file(quads), Catch::Contains("quads.geo") && Catch::Contains("surface 2") &&
                                                Catch::Contains("Quadrilateral"));
    // Second-order triangles.
    const std::string p2 = write_geo("p2.geo", "Mesh.ElementOrder = 2;\nPhysical Surface(\"all\") = {1, 2};\n");
    CHECK_THROWS_WITH(mesh_geo_file(p2), Catch::Contains("p2.geo") && Catch::Contains("6 nodes"));
    // Surface 2 meshed but in no physical group, while surface 1 is.
    const std::string orphan = write_geo("orphan.geo", "Physical Surface(\"lower\") = {1};\n");
    CHECK_THROWS_WITH(mesh_geo_file(orphan), Catch::Contains("orphan.geo") && Catch::Contains("surface(s) 2"));
    // The same model with both surfaces grouped reads.
    const std::string ok = write_geo("ok.geo", "Physical Surface(\"all\") = {1, 2};\n");
    CHECK(mesh_geo_file(ok).n_triangles() > 0);
}

TEST_CASE("a curve group of the upper block that ends at the lower block's corner holds the upper block's copies only",
          "[unit]") {
    // Two stacked 1 x 1 m blocks (surface 1 below, surface 2 above) share line 3 (y = 1). Line 7 is the upper
    // block's left edge, from (0, 2) down to point 4 at (0, 1): the lower block's top-left corner.
    const std::string path = write_geo("two_blocks.geo", "Physical Surface(\"blocks\") = {1, 2};\n"
                                                         "Physical Curve(\"upper_left\") = {7};\n"
                                                         "Physical Curve(\"joint\") = {3};\n"
                                                         "Physical Point(\"corner\") = {4};\n");
    const Mesh m = mesh_geo_file(path);
    REQUIRE(m.n_bodies() == 2);
    TopologyOptions o;
    o.interfaces = {{"blocks", "blocks", InterfaceKind::dry}};
    const Topology topo = build_topology(m, o);
    const Mesh& s = topo.mesh;
    // Bodies by position: the upper block's triangles have centroids above y = 1.
    auto centroid_y = [&](int t) { return (s.xy[2 * s.tri[3 * t] + 1] + s.xy[2 * s.tri[3 * t + 1] + 1] + s.xy[2 * s.tri[3 * t + 2] + 1]) / 3; };
    int upper = -1, lower = -1;
    for (int t = 0; t < s.n_triangles(); ++t) (centroid_y(t) > 1 ? upper : lower) = s.tri_body[t];
    REQUIRE(upper >= 0);
    REQUIRE(lower >= 0);
    REQUIRE(upper != lower);
    auto bodies_of_copy = [&](int c) {
        std::set<int> b;
        for (int t = 0; t < s.n_triangles(); ++t)
            for (int i = 0; i < 3; ++i)
                if (s.tri[3 * t + i] == c) b.insert(s.tri_body[t]);
        return b;
    };
    std::vector<int> corner_copies;  // the copies of the node at (0, 1)
    for (int c = 0; c < s.n_nodes(); ++c)
        if (std::abs(s.xy[2 * c]) < 1e-12 && std::abs(s.xy[2 * c + 1] - 1) < 1e-12) corner_copies.push_back(c);
    REQUIRE(corner_copies.size() == 2);  // split by the dry joint

    const PhysicalGroup& g = *s.find_group("upper_left");
    CHECK(g.bodies == std::vector<int>{upper});
    CHECK(g.left_out_bodies == std::vector<int>{lower});
    CHECK(g.split_bodies.empty());
    for (int c : g.nodes) CHECK(bodies_of_copy(c) == std::set<int>{upper});
    int corner_in_group = 0;
    for (int c : corner_copies) corner_in_group += std::count(g.nodes.begin(), g.nodes.end(), c) > 0;
    CHECK(corner_in_group == 1);  // before: both copies, so a support on the edge dragged the lower block's corner
    // Every node of line 7 is in it, one copy each: 1 m at the points' mesh size 0.5 m gives 3 nodes.
    CHECK(g.nodes.size() == 3);

    // A curve along the joint borders both blocks and keeps both copies.
    const PhysicalGroup& j = *s.find_group("joint");
    CHECK(j.bodies.size() == 2);
    CHECK(j.left_out_bodies.empty());
    for (int c : corner_copies) CHECK(std::count(j.nodes.begin(), j.nodes.end(), c) == 1);
    // The point group cannot say which block it means: both copies, recorded as split between the two bodies.
    const PhysicalGroup& p = *s.find_group("corner");
    CHECK(p.nodes == corner_copies);
    CHECK(p.split_bodies == std::vector<int>{std::min(upper, lower), std::max(upper, lower)});
    REQUIRE(p.split_node >= 0);
    CHECK(std::abs(s.xy[2 * p.split_node + 1] - 1) < 1e-12);

    // Tied blocks share the node: one copy, nothing left out, nothing split.
    o.interfaces = {{"blocks", "blocks", InterfaceKind::tied}};
    const Topology tied = build_topology(m, o);
    CHECK(tied.mesh.find_group("corner")->split_bodies.empty());
    CHECK(tied.mesh.find_group("corner")->nodes.size() == 1);
    CHECK(tied.mesh.find_group("upper_left")->left_out_bodies.empty());
}

// Gmsh 4.8's MSH 2.2 reader crashed (SIGSEGV) on these one-line defects, found by the issue-26 fuzzer; fdem checks the
// file's structure first and names the file and the line.
TEST_CASE("malformed MSH 2.2 node and element lines are refused with the line, before Gmsh reads them", "[unit]") {
    const std::string good =
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 1 \"body\"\n$EndPhysicalNames\n"
        "$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n$EndNodes\n"
        "$Elements\n2\n1 2 2 1 5 1 2 3\n2 2 2 1 5 1 3 4\n$EndElements\n";
    auto write = [](const std::string& name, const std::string& text) {
        const std::string path = tmp_dir() + "/" + name;
        std::ofstream(path) << text;
        return path;
    };
    auto replace_line = [](std::string text, int line, const std::string& with) {
        std::size_t b = 0;
        for (int k = 1; k < line; ++k) b = text.find('\n', b) + 1;
        return text.replace(b, text.find('\n', b) - b, with);
    };
    CHECK(read_msh_file(write("good2.msh", good)).n_triangles() == 2);
    const struct {
        int line;
        const char* text;
        const char* why;
    } cases[] = {{11, "2 1 0", "a tag and three coordinates"},
                 {12, "0 1 1 0", "positive tag"},
                 {12, "3 1 nan 0", "not a finite number"},
                 {13, "2 0 1 0", "appears twice"},
                 {17, "1 2 2 1 5 1 2", "needs 8 numbers"},
                 {18, "2 2 2 1 5 1 3 9", "node 9 is not in $Nodes"},
                 {9, "5", "expected $EndNodes"}};
    for (const auto& c : cases) {
        const std::string path = write("bad2.msh", replace_line(good, c.line, c.text));
        INFO("line " << c.line << " -> '" << c.text << "'");
        CHECK_THROWS_WITH(read_msh_file(path), Catch::Contains("bad2.msh") && Catch::Contains("line ") && Catch::Contains(c.why));
    }
}
