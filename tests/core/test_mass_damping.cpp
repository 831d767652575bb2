// Stage key mass_damping = a (1/s): mass-proportional (Rayleigh alpha) damping f = -a m vbar on free nodes and rigid
// groups, vbar = (v^{n-1/2} + v^{n+1/2}) / 2, booked under D_visc.
//
// CLOSED FORMS
//   A body in free fall (gravity g, no supports) moves as a rigid translation: every node has the same velocity and
//   the elastic forces stay zero. The update v' = ((1 - h) v + dt g) / (1 + h), h = a dt / 2, has the fixed point
//   v* = g / a (terminal velocity) and v_n - v* = r^n (v_0 - v*), r = (1 - h) / (1 + h), from v_0 = 0: the mean
//   velocity after n steps is v* (1 - r^n) to round-off; r^n = exp(-a t) (1 + O((a dt)^2 a t)), so the continuous
//   v(t) = (g / a)(1 - exp(-a t)) to a relative 1e-6 here. The work of gravity equals the kinetic energy plus the
//   damping's dissipation (energy balance). A top edge rigid in y follows the same closed form (the rigid group is
//   damped on its resultant mass). A mode of angular frequency omega decays at a / 2 per second: ratio a / (2 omega)
//   of critical.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "engine_helpers.hpp"

namespace {

std::string falling_column(double a, const std::string& extra) {
    return testing::column_case_head("falling_column") + R"(
[[stages]]
name = "fall"
duration = 0.5
local_damping = 0.0
mass_damping = )" + std::to_string(a) + R"(
gravity = [0.0, -9.81]
)" + extra;
}

void check_fall(const std::string& extra, const std::string& name) {
    const double a = 4.0, g = 9.81;
    auto sim = testing::make_simulation(falling_column(a, extra), name);
    sim.run();
    const double dt = sim.dt();
    const long n = sim.steps();
    const double h = 0.5 * a * dt, r = (1 - h) / (1 + h);
    const double discrete = -(g / a) * (1 - std::pow(r, static_cast<double>(n)));
    const double t = n * dt;  // v^{n-1/2} belongs to t^{n-1/2}; the discrete form counts whole steps from v_0 = 0
    const double continuous = -(g / a) * (1 - std::exp(-a * t));
    const double v = testing::mean_velocity_y(sim);
    const fdem::Energies e = sim.energies();
    std::printf("[mass damping] %s: %ld steps of %.3e s, mean vy %.12f m/s, discrete closed form %.12f, continuous "
                "%.12f, terminal %.4f; D_visc %.6e J, balance %.2e\n",
                name.c_str(), n, dt, v, discrete, continuous, -g / a, e.viscous, e.balance_error());
    CHECK(v == Approx(discrete).epsilon(1e-9));
    CHECK(v == Approx(continuous).epsilon(1e-6));
    // the velocity is a large share of the terminal one: the damping acted (without it, -g t = -4.9 m/s)
    CHECK(std::abs(v) < 0.9 * g / a);
    CHECK(e.viscous > 0.1 * e.kinetic);
    CHECK(e.balance_error() < 1e-6);
}

}  // namespace

TEST_CASE("mass damping: a falling body tends to the terminal velocity g / a as the closed form says, energy balanced",
          "[unit][damping]") {
    check_fall("", "mass_damping_fall");
}

TEST_CASE("mass damping: a rigid group (top rigid in y) is damped on its resultant mass, same closed form",
          "[unit][damping]") {
    check_fall("  [[stages.supports]]\n  group = \"top\"\n  rigid = \"y\"\n", "mass_damping_fall_rigid");
}

TEST_CASE("mass damping: a negative coefficient is refused, naming the key", "[unit][damping]") {
    const auto dir = testing::tmp_dir("mass_damping_bad");
    const std::string path = testing::write_text(dir / "case.toml", falling_column(-1.0, ""));
    const auto r = testing::run_fdem("check \"" + path + "\"", dir);
    INFO(r.err);
    CHECK(r.code == 1);
    CHECK(r.err.find("mass_damping") != std::string::npos);
    CHECK(r.err.find(">= 0 in 1/s") != std::string::npos);
}
