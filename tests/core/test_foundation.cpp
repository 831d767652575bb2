// Load kind foundation (fdem/load_foundation.cpp; cases/REFERENCE.md, stages[].loads[].foundation): an elastic
// (Winkler) foundation of normal and shear stiffness k_n, k_s (Pa/m) under a curve group.
//
// CLOSED FORM
//   A free block (1.0 m x 0.5 m, t = 0.1 m, 2000 kg/m^3: m = 100 kg) on a foundation along its bottom edge
//   (L = 1.0 m). At rest the foundation's springs carry what is applied: under the weight m g the settlement of the
//   bottom, weighted by its nodes' tributary lengths (the springs' shares), is m g / (k_n L t); under a horizontal
//   force F (on the top edge: the moment F h only tilts the block, it moves the straight bottom vertically) the
//   bottom slides by F / (k_s L t). Both are the exact static answers of the lumped springs, whatever the block's
//   own deformation; the runs settle under local damping to the stage's equilibrium (unbalanced-force ratio 1e-4,
//   the foundation counted with the reactions), and the energy balance closes (the springs' energy is booked as the
//   negative work of their forces).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "engine_helpers.hpp"
#include "mesh/topology.hpp"

namespace {

constexpr double kN = 1.0e7, kS = 5.0e6;  // Pa/m
constexpr double kL = 1.0, kT = 0.1;       // m: foundation length, thickness

std::string block_case(const std::string& name, const std::string& stage) {
    return "\n[case]\nname = \"" + name + R"("
thickness = 0.1
plane = "stress"
[geometry]
type = "rectangle"
width = 1.0
height = 0.5
mesh_size = 0.1
[materials.m]
E = 1.0e9
nu = 0.2
density = 2000.0
[regions]
body = "m"
[[monitors]]
name = "Fy"
type = "load"
group = "bottom"
component = "y"
)" + stage;
}

std::string settle_stage(const std::string& gravity, const std::string& extra_load, const std::string& foundation) {
    return R"(
[[stages]]
name = "settle"
equilibrium = 1e-4
max_duration = 3.0
local_damping = 0.8
gravity = )" + gravity + R"(
  [[stages.loads]]
  group = "bottom"
  foundation = )" + foundation + "\n" + extra_load;
}

// Mean displacement of the group's nodes in component c, weighted by their tributary lengths (m).
double weighted_u(const fdem::Simulation& sim, const std::string& group, int c) {
    const auto& md = sim.model();
    double u = 0, w = 0;
    for (const auto& [k, s] : fdem::mesh::load_shares(md.group(group), md.X)) u += s * (md.x[2 * k + c] - md.X[2 * k + c]), w += s;
    return u / w;
}

void run_stage(fdem::Simulation& sim) {
    sim.begin_stage(0);
    while (!sim.stage_finished()) sim.step();
}

}  // namespace

TEST_CASE("foundation: a block on an elastic foundation settles under its weight to m g over k_n L t", "[unit][foundation]") {
    auto sim = testing::make_simulation(
        block_case("foundation_settle", settle_stage("[0.0, -9.81]", "", "{ normal = 1.0e7, shear = 5.0e6 }")), "foundation_settle");
    run_stage(sim);
    double m = 0;
    for (double mk : sim.model().grav_mass) m += mk;
    const double expected = -m * 9.81 / (kN * kL * kT);
    const double uy = weighted_u(sim, "bottom", 1), ux = weighted_u(sim, "bottom", 0);
    const auto e = sim.energies();
    std::printf("[foundation] settled after %.4g s (%s): bottom u_y %.6e m, closed form %.6e m (%.3f %%), u_x %.3e m, "
                "foundation force %.6e N of weight %.6e N, balance error %.3e\n",
                sim.time(), sim.stage_results().back().ended_by.c_str(), uy, expected, 100 * (uy / expected - 1), ux,
                sim.monitor_value(0), m * 9.81, e.balance_error());
    CHECK(m == Approx(100.0).epsilon(1e-9));
    CHECK(sim.stage_results().back().ended_by == "equilibrium");  // the foundation counts as a support
    CHECK(std::abs(uy / expected - 1) < 0.01);
    CHECK(std::abs(ux) < 1e-3 * std::abs(expected));
    CHECK(sim.monitor_value(0) == Approx(m * 9.81).epsilon(0.01));  // a load monitor reads the foundation's force
    CHECK(e.balance_error() < 0.005);
}

TEST_CASE("foundation: a horizontal force F on the block slides its bottom by F over k_s L t", "[unit][foundation]") {
    const double F = 500.0;  // N
    const std::string push = "  [[stages.loads]]\n  group = \"top\"\n  force = [500.0, 0.0]\n";
    auto sim = testing::make_simulation(
        block_case("foundation_push", settle_stage("[0.0, 0.0]", push, "{ normal = 1.0e7, shear = 5.0e6 }")), "foundation_push");
    run_stage(sim);
    const double expected = F / (kS * kL * kT);
    const double ux = weighted_u(sim, "bottom", 0), uy = weighted_u(sim, "bottom", 1);
    const auto e = sim.energies();
    std::printf("[foundation] pushed, at rest after %.4g s (%s): bottom u_x %.6e m, closed form %.6e m (%.3f %%), mean u_y %.3e m, "
                "balance error %.3e\n",
                sim.time(), sim.stage_results().back().ended_by.c_str(), ux, expected, 100 * (ux / expected - 1), uy,
                e.balance_error());
    CHECK(sim.stage_results().back().ended_by == "equilibrium");
    CHECK(std::abs(ux / expected - 1) < 0.01);
    CHECK(std::abs(uy) < 0.01 * expected);  // the moment tilts the block about the middle of its bottom
    CHECK(e.balance_error() < 0.005);
}

TEST_CASE("foundation: the state after a save and load runs on to the same bits", "[unit][foundation]") {
    const std::string text = block_case("foundation_state", settle_stage("[0.0, -9.81]", "", "{ normal = 1.0e7, shear = 5.0e6 }"));
    auto state_of = [](const fdem::Simulation& s) {
        fdem::StateWriter w;
        s.save_state(w);
        return w.data();
    };
    auto a = testing::make_simulation(text, "foundation_state_a");
    a.begin_stage(0);
    for (int i = 0; i < 400; ++i) a.step();
    const std::string mid = state_of(a);
    for (int i = 0; i < 400; ++i) a.step();
    auto b = testing::make_simulation(text, "foundation_state_b");
    fdem::StateReader r(mid.data(), mid.size());
    b.load_state(r);
    CHECK(state_of(b) == mid);
    for (int i = 0; i < 400; ++i) b.step();
    CHECK(state_of(b) == state_of(a));
}

TEST_CASE("foundation: bad input names the key, the file and the line", "[unit][foundation]") {
    auto line_of = [](const std::string& text, const std::string& what) {
        const auto p = text.find(what);
        return std::to_string(1 + std::count(text.begin(), text.begin() + static_cast<long>(p), '\n'));
    };
    struct Bad {
        std::string foundation, extra, key, message;
    };
    const std::vector<Bad> bad{
        {"{ shear = 1.0e6 }", "", "'stages.1.loads.1.foundation.normal'", "missing"},
        {"{ normal = 1.0e7 }", "", "'stages.1.loads.1.foundation.shear'", "missing"},
        {"{ normal = -1.0e7, shear = 1.0e6 }", "", "'stages.1.loads.1.foundation.normal'", ">= 0 in Pa/m, got -1e+07"},
        {"{ normal = 1.0e7, shear = -5.0 }", "", "'stages.1.loads.1.foundation.shear'", ">= 0 in Pa/m, got -5"},
        {"{ normal = 0.0, shear = 0.0 }", "", "'stages.1.loads.1.foundation'", "got both 0"},
        {"{ normal = 1.0e7, shear = 1.0e6, damping = 0.1 }", "", "'stages.1.loads.1.foundation.damping'", "unknown key"},
        {"{ normal = 1.0e7, shear = 1.0e6 }", "  ramp = 0.1\n", "'stages.1.loads.1.ramp'", "unknown key"},
    };
    for (const auto& b : bad) {
        const std::string text = block_case("foundation_bad", settle_stage("[0.0, -9.81]", b.extra, b.foundation));
        const auto dir = testing::tmp_dir("foundation_bad");
        const std::string path = testing::write_text(dir / "case.toml", text);
        INFO(b.foundation << " " << b.extra);
        const std::string where = path + ":" + line_of(text, b.extra.empty() ? "foundation =" : "ramp =") + ":";
        CHECK_THROWS_WITH(fdem::load_case(path), Catch::Contains(where + " key " + b.key) || Catch::Contains(where + " unknown key " + b.key));
        CHECK_THROWS_WITH(fdem::load_case(path), Catch::Contains(b.message));
    }
    // A region (no edges): refused against the mesh; a foundation far stiffer than the body: refused at its stage.
    std::string region = block_case("foundation_region", settle_stage("[0.0, -9.81]", "", "{ normal = 1.0e7, shear = 1.0e6 }"));
    region.replace(region.find("group = \"bottom\"\n  foundation"), 16, "group = \"body\"");
    CHECK_THROWS_WITH(testing::make_simulation(region, "foundation_region"),
                      Catch::Contains("loads.1.foundation': group 'body' is not a curve") && Catch::Contains("a foundation needs edges"));
    auto stiff = testing::make_simulation(
        block_case("foundation_stiff", settle_stage("[0.0, -9.81]", "", "{ normal = 1.0e16, shear = 1.0e6 }")), "foundation_stiff");
    CHECK_THROWS_WITH(stiff.begin_stage(0), Catch::Contains("too stiff for the time step"));
}
