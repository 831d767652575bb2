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
