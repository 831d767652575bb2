// Support mode rigid: the nodes of a group share one velocity component, free as a whole (a loading beam kept
// horizontal but free to move vertically, as in the Vermeltfoort shear walls).
//
// CLOSED FORMS
//   Column B x H, thickness t, on rollers (bottom fix y, one corner fix x), top edge rigid in y, a force P at ONE top
//   corner: the rigid top spreads it, so the state is uniform uniaxial stress sigma = P / (B t) and the top settles (small strain: P / (B t) = 50 kPa)
//   by P H / (E B t) everywhere (plane stress, lateral expansion free); constant-strain triangles reproduce a
//   uniform state exactly, so only the equilibrium tolerance remains. Without the constraint the loaded corner
//   settles much more than the other one.
//   Free fall of the same body with its top rigid in y: the mass-weighted mean vertical velocity is -g t exactly
//   (the rigid group receives the resultant of its nodes' forces, momentum is kept), and the energy balances.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "engine_helpers.hpp"

namespace {

std::string column_case(const std::string& top_support, const std::string& stage_extra) {
    return testing::column_case_head("column") + stage_extra + top_support;
}

const char* kPressed = R"(
[[stages]]
name = "press"
equilibrium = 1e-9
max_duration = 5.0
local_damping = 0.8
  [[stages.supports]]
  group = "bottom"
  fix = "y"
  [[stages.supports]]
  group = "corner_bl"
  fix = "x"
  [[stages.loads]]
  group = "corner_tr"
  force = [0.0, -1.0e3]
  ramp = 0.01
)";

// Vertical displacement of the top nodes: min and max (m).
std::pair<double, double> top_settlement(const fdem::Simulation& sim) {
    const auto& md = sim.model();
    double lo = 1e300, hi = -1e300;
    for (int k : md.group("top").nodes) {
        const double u = md.x[2 * k + 1] - md.X[2 * k + 1];
        lo = std::min(lo, u), hi = std::max(hi, u);
    }
    return {lo, hi};
}

}  // namespace

TEST_CASE("rigid support: a corner force on a column whose top is rigid in y gives the uniform settlement P H / (E B t)",
          "[unit][rigid]") {
    const double P = 1.0e3, H = 1.0, E = 1.0e9, B = 0.2, t = 0.1;
    const double expected = -P * H / (E * B * t);  // m
    auto sim = testing::make_simulation(column_case("  [[stages.supports]]\n  group = \"top\"\n  rigid = \"y\"\n", kPressed),
                                        "rigid_column");
    sim.run();
    const auto [lo, hi] = top_settlement(sim);
    std::printf("[rigid] top settlement %.6e .. %.6e m, closed form %.6e m\n", lo, hi, expected);
    CHECK(hi - lo < 1e-12);
    CHECK(lo == Approx(expected).epsilon(1e-4));
    CHECK(sim.energies().balance_error() < 1e-3);

    // The same without the constraint: the loaded corner goes down much further than the other (the test above
    // could fail).
    auto free_sim = testing::make_simulation(column_case("", kPressed), "rigid_column_free");
    free_sim.run();
    const auto [flo, fhi] = top_settlement(free_sim);
    std::printf("[rigid] without the constraint: top settlement %.6e .. %.6e m\n", flo, fhi);
    CHECK(fhi - flo > 0.5 * std::abs(expected));
}

TEST_CASE("rigid support: a body falling with its top rigid in y keeps its momentum (mean velocity -g t) and energy",
          "[unit][rigid]") {
    auto sim = testing::make_simulation(column_case("  [[stages.supports]]\n  group = \"top\"\n  rigid = \"y\"\n", R"(
[[stages]]
name = "fall"
duration = 0.05
local_damping = 0.0
gravity = [0.0, -9.81]
)"),
                                        "rigid_fall");
    sim.run();
    const auto& md = sim.model();
    const double vy = testing::mean_velocity_y(sim);
    // Leap-frog started from rest with v^{-1/2} = 0: after n steps v^{n-1/2} = -g n dt = -g t exactly.
    const double t_half = sim.time();
    std::printf("[rigid] fall: mean vy %.12f m/s, -g t %.12f m/s\n", vy, -9.81 * t_half);
    CHECK(vy == Approx(-9.81 * t_half).epsilon(1e-9));
    double vmin = 1e300, vmax = -1e300;
    for (int k : md.group("top").nodes) vmin = std::min(vmin, md.v[2 * k + 1]), vmax = std::max(vmax, md.v[2 * k + 1]);
    CHECK(vmax - vmin == 0.0);
    CHECK(sim.energies().balance_error() < 1e-6);
}

TEST_CASE("rigid support: case errors name the key", "[unit][rigid]") {
    const auto dir = testing::tmp_dir("rigid_bad");
    const std::string text = column_case("  [[stages.supports]]\n  group = \"top\"\n  rigid = \"y\"\n  fix = \"y\"\n", kPressed);
    const auto path = testing::write_text(dir / "case.toml", text);
    const auto r = testing::run_fdem("check \"" + path + "\"", dir);
    INFO(r.err);
    CHECK(r.code == 1);
    CHECK(r.err.find("already has a support in this block") != std::string::npos);
    const auto path2 = testing::write_text(dir / "case2.toml", column_case("  [[stages.supports]]\n  group = \"top\"\n  rigid = \"z\"\n", kPressed));
    const auto r2 = testing::run_fdem("check \"" + path2 + "\"", dir);
    INFO(r2.err);
    CHECK(r2.code == 1);
    CHECK(r2.err.find("rigid") != std::string::npos);
}
