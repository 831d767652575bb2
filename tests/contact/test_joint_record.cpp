// tests/contact/test_joint_record.cpp: the dry joint record (Interactions::record_dry_joints, cracks.csv rows of
// class interface-dry). Dry joints have no cohesive element, so this record is what shows a rocking or sliding
// mechanism in cracks.csv.
//
// DATA LAYOUT
//   A 0.4 x 0.2 m dry wall from the generator: stack bond, two 0.2 x 0.1 m units per course, two courses, a base
//   slab; mesh 0.05 m. Its dry joint segments (Model::dry_joints) are the head joints at x = 0.2, the bed joint at
//   y = 0.1 and the base joint at y = 0. Positions x are set directly (no dynamics) from closed-form motions of the
//   upper course; a node belongs to the upper course when a triangle using it has its centroid above y = 0.1.
//
// CLOSED FORMS
//   Upper course lifted by w: every bed-joint segment opens by w, nothing else moves; shifted by u: every bed
//   segment slips by u. A rigid motion of the whole wall opens and slips nothing. The upper course rotated by
//   theta about (0.4, 0.1) (clockwise): a bed point at x opens by (0.4 - x) sin(theta).
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/engine_helpers.hpp"
#include "fdem/interactions.hpp"
#include "fdem/scene.hpp"

namespace {

// A dry wall of two courses of 0.2 x 0.1 m units in stack bond on a base slab; `length` (m) sets the units per course.
std::string wall_case(const std::string& length, const std::string& extra = "") {
    return R"(
[case]
name = "joint_record"
thickness = 0.1
[geometry]
type = "wall"
length = )" + length + R"(
courses = 2
unit_length = 0.2
unit_height = 0.1
bond = "stack"
joint = "dry"
base = "slab"
base_height = 0.1
base_overhang = 0.1
mesh_size = 0.05
mesh_size_base = 0.05
[materials.m]
E = 1.0e9
nu = 0.2
density = 2000.0
[regions]
units = "m"
base = "m"
[[interfaces]]
regions = ["units", "units"]
kind = "dry"
friction = 30.0
normal_stiffness = 5e9
[[interfaces]]
regions = ["units", "base"]
kind = "dry"
friction = 30.0
normal_stiffness = 5e9
)" + extra;
}

struct Scene {
    fdem::CaseSpec spec;
    fdem::Model model;
    std::vector<char> upper;  // per node: belongs to the upper course
};

Scene make_scene(const std::string& name, const std::string& geometry_extra = "") {
    const auto dir = testing::tmp_dir(name);
    std::string text = wall_case("0.4");
    text.insert(text.find("[materials.m]"), geometry_extra);
    const std::string path = testing::write_text(dir / "case.toml", text + R"(
[[stages]]
name = "s"
duration = 0.001
)");
    Scene s{fdem::load_case(path), {}, {}};
    s.model = fdem::build_scene(s.spec);
    const fdem::Model& md = s.model;
    s.upper.assign(md.n_nodes(), 0);
    for (int e = 0; e < md.n_triangles(); ++e) {
        double cy = 0;
        for (int k = 0; k < 3; ++k) cy += md.X[2 * md.tris[e].n[k] + 1] / 3;
        if (cy > 0.1)
            for (int k = 0; k < 3; ++k) s.upper[md.tris[e].n[k]] = 1;
    }
    return s;
}

double ref_mid_y(const fdem::Model& md, const fdem::mesh::CohesiveElement& d) {
    return 0.5 * (md.X[2 * d.n[0] + 1] + md.X[2 * d.n[1] + 1]);
}
bool on_bed_joint(const fdem::Model& md, const fdem::mesh::CohesiveElement& d) {
    return std::abs(ref_mid_y(md, d) - 0.1) < 1e-9 && std::abs(md.X[2 * d.n[0] + 1] - md.X[2 * d.n[1] + 1]) < 1e-9;
}

// cracks.csv rows of the record: (element, mode, D_I, D_II).
struct Row {
    int element;
    std::string cls, mode;
    double D_I, D_II;
};
std::vector<Row> rows_of(const std::string& csv) {
    std::vector<Row> out;
    std::istringstream in(csv);
    std::string line;
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        std::stringstream ls(line);
        std::string c;
        while (std::getline(ls, c, ',')) f.push_back(c);
        REQUIRE(f.size() == 16);
        out.push_back({std::stoi(f[10]), f[4], f[7], std::stod(f[8]), std::stod(f[9])});
    }
    return out;
}

}  // namespace

TEST_CASE("joint record: lifting the upper course by 2x the threshold records every bed-joint segment as open, then "
          "a shift records them as slipped, nothing else",
          "[unit][joint_record]") {
    Scene s = make_scene("joint_record_lift");
    const fdem::Model& md = s.model;
    fdem::Interactions inter(s.spec, md);
    REQUIRE(inter.has_dry_joints());
    int n_bed = 0;
    for (const auto& d : inter.dry_joints()) n_bed += on_bed_joint(md, d);
    // 0.4 m of bed joint at 0.05 m: 8 segments; head joints (2 x 2 x 0.1 m) and base joint (0.4 m): 4 + 8 more.
    CHECK(n_bed == 8);
    CHECK(inter.dry_joint_count() == 8 + 4 + 8);

    std::vector<double> x = md.X;
    for (int k = 0; k < md.n_nodes(); ++k)
        if (s.upper[k]) x[2 * k + 1] += 2e-4;
    CHECK(inter.record_dry_joints(0.1, 0.0, x.data()) == n_bed);
    auto rows = rows_of(inter.cracks_csv());
    REQUIRE(rows.size() == static_cast<std::size_t>(n_bed));
    for (const auto& r : rows) {
        CHECK(r.cls == "interface-dry");
        CHECK(r.mode == "open");
        CHECK(on_bed_joint(md, inter.dry_joints()[r.element]));
        CHECK(r.D_I == Approx(2.0).epsilon(1e-9));
        CHECK(r.D_II == Approx(0.0).margin(1e-9));
    }
    // The same state again: a segment is recorded once per mode.
    CHECK(inter.record_dry_joints(0.2, 0.0, x.data()) == 0);
    // Shift by 3x the slip threshold (positive or negative: |slip| counts).
    for (int k = 0; k < md.n_nodes(); ++k)
        if (s.upper[k]) x[2 * k] -= 3e-4;
    CHECK(inter.record_dry_joints(0.3, 0.0, x.data()) == n_bed);
    rows = rows_of(inter.cracks_csv());
    REQUIRE(rows.size() == static_cast<std::size_t>(2 * n_bed));
    for (std::size_t i = n_bed; i < rows.size(); ++i) {
        CHECK(rows[i].mode == "slip");
        CHECK(on_bed_joint(md, inter.dry_joints()[rows[i].element]));
        CHECK(rows[i].D_II == Approx(3.0).epsilon(1e-9));
    }
    CHECK(inter.dry_open_count() == n_bed);
    CHECK(inter.dry_slip_count() == n_bed);
}

TEST_CASE("joint record: with roughened joints (gaps up to 6x the threshold) opening counts from the start",
          "[unit][joint_record]") {
    Scene s = make_scene("joint_record_rough", "joint_roughness = 3e-4\nroughness_wavelength = 0.1\n");
    const fdem::Model& md = s.model;
    fdem::Interactions inter(s.spec, md);
    double largest_gap = 0;
    for (const auto& d : inter.dry_joints()) {
        double o, sl;
        fdem::Interactions::joint_motion(d.n.data(), md.X.data(), o, sl);
        largest_gap = std::max(largest_gap, o);
    }
    CHECK(largest_gap > 2e-4);  // twice the threshold: a record of absolute gaps would call it open
    CHECK(inter.record_dry_joints(0.0, 0.0, md.X.data()) == 0);
    std::vector<double> x = md.X;
    for (int k = 0; k < md.n_nodes(); ++k)
        if (s.upper[k]) x[2 * k + 1] += 2e-4;
    int n_bed = 0;
    for (const auto& d : inter.dry_joints()) n_bed += std::abs(ref_mid_y(md, d) - 0.1) < 1e-3;
    CHECK(n_bed == 8);
    CHECK(inter.record_dry_joints(0.1, 0.0, x.data()) == n_bed);
    for (const auto& r : rows_of(inter.cracks_csv())) {
        CHECK(r.mode == "open");
        CHECK(r.D_I == Approx(2.0).epsilon(0.01));  // the lift over the threshold, to the joints' rotation by the roughness
    }
}

TEST_CASE("joint record: a rigid rotation and translation of the whole wall records nothing", "[unit][joint_record]") {
    Scene s = make_scene("joint_record_rigid");
    const fdem::Model& md = s.model;
    fdem::Interactions inter(s.spec, md);
    for (double deg : {30.0, 90.0, 180.0}) {
        const double c = std::cos(deg * M_PI / 180), sn = std::sin(deg * M_PI / 180);
        std::vector<double> x(md.X.size());
        for (int k = 0; k < md.n_nodes(); ++k) {
            x[2 * k] = 1.0 + c * md.X[2 * k] - sn * md.X[2 * k + 1];
            x[2 * k + 1] = -2.0 + sn * md.X[2 * k] + c * md.X[2 * k + 1];
        }
        CHECK(inter.record_dry_joints(0.1, 0.0, x.data()) == 0);
        for (const auto& d : inter.dry_joints()) {
            double o, sl;
            fdem::Interactions::joint_motion(d.n.data(), x.data(), o, sl);
            CHECK(std::abs(o) < 1e-12);
            CHECK(std::abs(sl) < 1e-12);
        }
    }
}

TEST_CASE("joint record: the upper course rocking about its right corner opens the bed joint where (0.4 - x) sin(theta) "
          "exceeds the threshold",
          "[unit][joint_record]") {
    Scene s = make_scene("joint_record_rock");
    const fdem::Model& md = s.model;
    fdem::Interactions inter(s.spec, md);
    const double theta = 1.1e-3;  // rad, clockwise
    const double c = std::cos(theta), sn = std::sin(theta);
    std::vector<double> x = md.X;
    for (int k = 0; k < md.n_nodes(); ++k)
        if (s.upper[k]) {
            const double dx = md.X[2 * k] - 0.4, dy = md.X[2 * k + 1] - 0.1;
            x[2 * k] = 0.4 + c * dx + sn * dy;
            x[2 * k + 1] = 0.1 - sn * dx + c * dy;
        }
    inter.record_dry_joints(0.1, 0.0, x.data());
    std::set<int> opened;
    for (const auto& r : rows_of(inter.cracks_csv())) {
        CHECK(r.mode == "open");
        opened.insert(r.element);
    }
    int expected_open = 0;
    for (int e = 0; e < inter.dry_joint_count(); ++e) {
        const auto& d = inter.dry_joints()[e];
        if (!on_bed_joint(md, d)) {
            CHECK(opened.count(e) == 0);
            continue;
        }
        const double x_left = std::min(md.X[2 * d.n[0]], md.X[2 * d.n[1]]);
        const double predicted = (0.4 - x_left) * sn / 1e-4;  // largest end opening / threshold
        double o, sl;
        fdem::Interactions::joint_motion(d.n.data(), x.data(), o, sl);
        CHECK(o / 1e-4 == Approx(predicted).epsilon(1e-3));
        if (predicted > 1.05) {
            CHECK(opened.count(e) == 1);
            ++expected_open;
        }
        if (predicted < 0.95) CHECK(opened.count(e) == 0);
    }
    CHECK(expected_open == 7);  // left ends at x = 0 ... 0.30 m
}

TEST_CASE("joint record through fdem run: pushing the upper unit of a two-unit stack 2 mm writes slip rows for its bed "
          "joint only, and summary.json counts them",
          "[engine][regression][joint_record]") {
    const auto dir = testing::tmp_dir("joint_record_run");
    const std::string text = wall_case("0.2", R"(
[groups.pusher]
box = [-0.001, 0.149, 0.201, 0.201]
[output]
history_interval = 0.001
[[stages]]
name = "settle"
duration = 0.05
local_damping = 0.8
gravity = [0.0, -9.81]
  [[stages.supports]]
  group = "base_bottom"
  fix = "xy"
[[stages]]
name = "push"
duration = 0.2
local_damping = 0.8
  [[stages.supports]]
  group = "pusher"
  vx = 0.01
)");
    const std::string path = testing::write_text(dir / "case.toml", text);
    const auto r = testing::run_fdem("run \"" + path + "\" --quiet --threads 1 --out \"" + (dir / "out").string() + "\"", dir);
    INFO(r.err);
    REQUIRE(r.code == 0);
    const std::string csv = testing::read_text(dir / "out" / "cracks.csv");
    std::istringstream in(csv);
    std::string line;
    std::getline(in, line);  // header
    int slip = 0, open = 0, other = 0;
    while (std::getline(in, line)) {
        std::vector<std::string> f;
        std::stringstream ls(line);
        std::string c;
        while (std::getline(ls, c, ',')) f.push_back(c);
        REQUIRE(f.size() == 16);
        const double y_ref = std::stod(f[15]);
        if (f[7] == "slip" && std::abs(y_ref - 0.1) < 1e-9) ++slip;
        else if (f[7] == "open") ++open;
        else ++other;
    }
    // The upper unit slides 2 mm on the 0.2 m bed joint (4 segments); the lower unit, pressed by both weights, holds
    // on the base joint (friction mu 2 W against mu W pushing it); no joint opens by 0.1 mm.
    CHECK(slip == 4);
    CHECK(open == 0);
    CHECK(other == 0);
    const std::string summary = testing::read_text(dir / "out" / "summary.json");
    CHECK(summary.find("\"joint_record\"") != std::string::npos);
    CHECK(summary.find("\"slipped\": 4") != std::string::npos);
}
