// Bad geometry and meshes through the fdem command: exit code 1 and a message naming the problem.
#include <catch2/catch.hpp>

#include "../core/engine_helpers.hpp"

namespace {

const std::string kWall = R"([case]
name = "wall"
thickness = 0.2

[geometry]
type = "wall"
length = 1.0
height = 1.0
unit_length = 0.2
unit_height = 0.1
beam_height = 0.1
mesh_size = 0.05

[materials.stone]
E = 7.68e8
nu = 0.2
density = 2400.0

[materials.concrete]
E = 3.0e10
nu = 0.2
density = 2400.0

[regions]
units = "stone"
beam = "concrete"

[[interfaces]]
regions = ["units", "units"]
kind = "dry"
friction = 31.8
normal_stiffness = 8.08e12

[[interfaces]]
regions = ["units", "beam"]
kind = "tied"

[[stages]]
duration = 0.001
  [[stages.supports]]
  group = "wall_bottom"
  fix = "xy"
)";

std::string edit(std::string s, const std::string& from, const std::string& to) {
    const auto p = s.find(from);
    REQUIRE(p != std::string::npos);
    return s.replace(p, from.size(), to);
}

}  // namespace

TEST_CASE("fdem mesh writes the mesh and its statistics", "[unit]") {
    const auto dir = testing::tmp_dir("mesh_cli_ok");
    const auto path = testing::write_text(dir / "case.toml", kWall);
    const auto r = testing::run_fdem("mesh \"" + path + "\" --out \"" + (dir / "out").string() + "\"", dir);
    INFO(r.err);
    REQUIRE(r.code == 0);
    CHECK(r.out.find("56 bodies") != std::string::npos);
    CHECK(r.out.find("dry") != std::string::npos);
    CHECK(std::filesystem::exists(dir / "out" / "mesh.vtu"));
    // the rigid-block model for fdem-tools limit (fdem/limit_export.hpp)
    CHECK(std::filesystem::exists(dir / "out" / "limit_model.json"));
    CHECK(r.out.find("limit model written to") != std::string::npos);
}

TEST_CASE("fdem mesh reports the roughened joint faces", "[unit]") {
    const auto dir = testing::tmp_dir("mesh_cli_rough");
    const auto path = testing::write_text(
        dir / "case.toml", edit(kWall, "mesh_size = 0.05", "mesh_size = 0.05\njoint_roughness = 2e-4\nroughness_wavelength = 0.1"));
    const auto r = testing::run_fdem("mesh \"" + path + "\" --out \"" + (dir / "out").string() + "\"", dir);
    INFO(r.out << r.err);
    REQUIRE(r.code == 0);
    CHECK(r.out.find("joint roughness") != std::string::npos);
    CHECK(r.out.find("face points moved inwards") != std::string::npos);
}

TEST_CASE("bad geometry and meshes give exit code 1 naming the problem", "[unit]") {
    struct Bad {
        const char* what;
        std::string text;
        std::string needle;  // must appear in the message
    };
    const std::vector<Bad> bad = {
        {"opening outside the wall", edit(kWall, "mesh_size = 0.05", "mesh_size = 0.05\n[[geometry.openings]]\nx = 0.8\ny = 0.3\nwidth = 0.4\nheight = 0.2"),
         "openings"},
        {"overlapping stones", edit(edit(kWall, "unit_length = 0.2\nunit_height = 0.1\n", ""), "mesh_size = 0.05",
                                    "mesh_size = 0.05\nstones = [[[0,0],[0.6,0],[0.6,0.5],[0,0.5]], [[0.5,0],[1.0,0],[1.0,0.5],[0.5,0.5]]]"),
         "overlap"},
        {"touching regions without a rule", edit(kWall, "[[interfaces]]\nregions = [\"units\", \"beam\"]\nkind = \"tied\"\n", ""), "units"},
        {"interface naming a missing region", edit(kWall, "regions = [\"units\", \"beam\"]", "regions = [\"units\", \"slab\"]"), "slab"},
        {"support on a missing group", edit(kWall, "group = \"wall_bottom\"", "group = \"base_bottom\""), "base_bottom"},
        {"sliver limit above the mesh's angles", edit(kWall, "mesh_size = 0.05", "mesh_size = 0.05\nmin_angle = 59.0"), "sliver"},
        {"roughness without its wavelength", edit(kWall, "mesh_size = 0.05", "mesh_size = 0.05\njoint_roughness = 2e-4"),
         "geometry.roughness_wavelength"},
        {"roughness too large for the mesh", edit(kWall, "mesh_size = 0.05", "mesh_size = 0.05\njoint_roughness = 0.02\nroughness_wavelength = 0.1"),
         "smallest altitude"},
        {"negative roughness", edit(kWall, "mesh_size = 0.05", "mesh_size = 0.05\njoint_roughness = -2e-4\nroughness_wavelength = 0.1"),
         "geometry.joint_roughness"},
        {"roughness without a dry joint",
         edit(edit(kWall, "kind = \"dry\"\nfriction = 31.8\nnormal_stiffness = 8.08e12", "kind = \"tied\""), "mesh_size = 0.05",
              "mesh_size = 0.05\njoint_roughness = 2e-4\nroughness_wavelength = 0.1"),
         "no dry joint"},
        {"missing .msh file", edit(kWall, "type = \"wall\"", "type = \"msh\"\nfile = \"nowhere.msh\"\n#"), "nowhere.msh"},
    };
    for (const auto& b : bad) {
        SECTION(b.what) {
            const auto dir = testing::tmp_dir("mesh_cli_bad");
            std::string text = b.text;
            if (std::string(b.what) == "missing .msh file") {
                // the wall keys are not allowed with type = "msh": keep only the file
                text = edit(kWall, "type = \"wall\"\nlength = 1.0\nheight = 1.0\nunit_length = 0.2\nunit_height = 0.1\nbeam_height = 0.1\nmesh_size = 0.05",
                            "type = \"msh\"\nfile = \"nowhere.msh\"");
            }
            const auto path = testing::write_text(dir / "case.toml", text);
            for (const char* cmd : {"mesh", "check", "run"}) {
                const auto r = testing::run_fdem(std::string(cmd) + " \"" + path + "\" --quiet --out \"" + (dir / "out").string() + "\"", dir);
                INFO(b.what << " (" << cmd << "): " << r.err);
                CHECK(r.code == 1);
                CHECK(r.err.find(b.needle) != std::string::npos);
                CHECK(r.err.find("\n", r.err.find("error")) != std::string::npos);
            }
        }
    }
}

TEST_CASE("a .geo script with a syntax error gives exit code 1 naming the file", "[unit]") {
    const auto dir = testing::tmp_dir("mesh_cli_geo");
    testing::write_text(dir / "bad.geo", "Point(1) = {0, 0, 0, 0.1;\n");
    const std::string text = edit(kWall, "type = \"wall\"\nlength = 1.0\nheight = 1.0\nunit_length = 0.2\nunit_height = 0.1\nbeam_height = 0.1\nmesh_size = 0.05",
                                  "type = \"gmsh\"\nfile = \"bad.geo\"");
    const auto path = testing::write_text(dir / "case.toml", text);
    const auto r = testing::run_fdem("check \"" + path + "\"", dir);
    INFO(r.err);
    CHECK(r.code == 1);
    CHECK(r.err.find("bad.geo") != std::string::npos);
}

namespace {
// Two stacked 1 x 1 m blocks in one region, fragmented (they share the node at (0, 1)), with a dry joint; the
// lower block is fixed at its bottom and `support` acts on the named group.
std::string two_block_case(const std::string& support_group) {
    return "[case]\nname = \"two\"\nthickness = 0.1\n[geometry]\ntype = \"gmsh\"\nfile = \"two_blocks.geo\"\n"
           "[materials.m]\nE = 1.0e9\nnu = 0.2\ndensity = 2000.0\n[regions]\nblocks = \"m\"\n"
           "[[interfaces]]\nregions = [\"blocks\", \"blocks\"]\nkind = \"dry\"\nfriction = 30.0\nnormal_stiffness = 1e10\n"
           "[[stages]]\nduration = 0.001\n  [[stages.supports]]\n  group = \"lower_bottom\"\n  fix = \"xy\"\n"
           "  [[stages.supports]]\n  group = \"" + support_group + "\"\n  vx = 0.01\n";
}
}  // namespace

TEST_CASE("a group at a corner two blocks share: a curve drives its own block, a point is refused", "[unit]") {
    const auto dir = testing::tmp_dir("mesh_cli_shared_corner");
    testing::write_text(dir / "two_blocks.geo",
                        "SetFactory(\"OpenCASCADE\");\nRectangle(1) = {0, 0, 0, 1, 1};\nRectangle(2) = {0, 1, 0, 1, 1};\n"
                        "BooleanFragments{ Surface{1, 2}; Delete; }{}\nMeshSize{ PointsOf{ Surface{:}; } } = 0.25;\n"
                        "Physical Surface(\"blocks\") = {1, 2};\n"
                        "Physical Curve(\"lower_bottom\") = Curve In BoundingBox{-0.01, -0.01, -1, 1.01, 0.01, 1};\n"
                        "Physical Curve(\"upper_left\") = Curve In BoundingBox{-0.01, 0.99, -1, 0.01, 2.01, 1};\n"
                        "Physical Point(\"corner\") = Point In BoundingBox{-0.01, 0.99, -1, 0.01, 1.01, 1};\n");
    // The upper block's left edge ends at the lower block's corner: it is driven on the upper block only, and the
    // check says so.
    auto path = testing::write_text(dir / "curve.toml", two_block_case("upper_left"));
    auto r = testing::run_fdem("check \"" + path + "\"", dir);
    INFO(r.err);
    CHECK(r.code == 0);
    CHECK(r.err.find("warning") != std::string::npos);
    CHECK(r.err.find("'upper_left'") != std::string::npos);
    CHECK(r.err.find("stages.1.supports.2.group") != std::string::npos);
    CHECK(r.err.find("not part of it") != std::string::npos);
    // The physical point at that corner cannot say which block it means: exit 1 naming the key, group and bodies.
    path = testing::write_text(dir / "point.toml", two_block_case("corner"));
    r = testing::run_fdem("check \"" + path + "\"", dir);
    INFO(r.err);
    CHECK(r.code == 1);
    CHECK(r.err.find("point.toml") != std::string::npos);
    CHECK(r.err.find("stages.1.supports.2.group") != std::string::npos);
    CHECK(r.err.find("'corner'") != std::string::npos);
    CHECK(r.err.find("bodies 0 (region 'blocks'), 1 (region 'blocks')") != std::string::npos);
    // A case group with `within` the upper block's edge takes the upper block's copy only: no error.
    path = testing::write_text(dir / "within.toml", two_block_case("pusher") +
                                                        "[groups.pusher]\nnearest = [0.0, 1.0]\nwithin = \"upper_left\"\n");
    r = testing::run_fdem("check \"" + path + "\"", dir);
    INFO(r.err);
    CHECK(r.code == 0);
}

TEST_CASE("a .msh that cannot be read names the file and the cause", "[unit]") {
    const auto dir = testing::tmp_dir("mesh_cli_msh_errors");
    const std::string head = "[case]\nname = \"m\"\nthickness = 0.1\n[geometry]\ntype = \"msh\"\nfile = \"";
    const std::string tail = "\"\n[materials.m]\nE = 1.0e9\nnu = 0.2\ndensity = 2000.0\n[regions]\nbody = \"m\"\n"
                             "[[stages]]\nduration = 0.001\n";
    // Only 2-node lines, in a physical curve: the message lists what the file holds and its groups.
    testing::write_text(dir / "lines.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n1 1 \"bar\"\n"
                                           "$EndPhysicalNames\n$Nodes\n2\n1 0 0 0\n2 1 0 0\n$EndNodes\n$Elements\n1\n"
                                           "1 1 2 1 1 1 2\n$EndElements\n");
    testing::write_text(dir / "garbage.msh", "this is not a mesh\n");
    // Cut off inside $Elements: Gmsh says only "Error loading"; the section structure says where.
    testing::write_text(dir / "cut.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n3\n1 0 0 0\n2 1 0 0\n3 0 1 0\n"
                                         "$EndNodes\n$Elements\n1\n1 2 2 1 1 1 2\n");
    testing::write_text(dir / "empty.msh", "");
    std::filesystem::create_directories(dir / "folder.msh");
    struct Bad {
        std::string file;
        std::vector<std::string> needles;
    };
    const std::vector<Bad> bad = {
        {"lines.msh", {"lines.msh", "no 3-node triangles", "1 'Line 2' (1D)", "'bar' (1D)"}},
        {"garbage.msh", {"garbage.msh", "Gmsh: ", "not a Gmsh .msh file"}},
        {"cut.msh", {"cut.msh", "Gmsh: ", "ends inside section $Elements", "truncated"}},
        {"empty.msh", {"empty.msh", "empty"}},
        {"folder.msh", {"folder.msh", "directory"}},
    };
    for (const Bad& b : bad) {
        const auto path = testing::write_text(dir / "case.toml", head + b.file + tail);
        const auto r = testing::run_fdem("check \"" + path + "\"", dir);
        INFO(b.file << ": " << r.err);
        CHECK(r.code == 1);
        CHECK(r.err.find("case.toml") != std::string::npos);
        for (const auto& n : b.needles) CHECK(r.err.find(n) != std::string::npos);
    }
}
