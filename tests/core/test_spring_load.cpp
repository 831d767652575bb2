// Load kind spring: a compliant actuator. A spring of stiffness k pulls a group towards an anchor moving at a
// constant velocity (the loading rig's compliance: actuator and load cell), so a mechanism is driven at a rate
// while the group is loaded by a force, not a prescribed velocity (cases/REFERENCE.md, stages[].loads[].spring).
//
// CLOSED FORM
//   A free body of mass M (no gravity, no support) pulled along x at one edge by a spring k whose anchor moves at v
//   from t = 0 (no ramp): M x'' = k (v t - x), x(0) = x'(0) = 0, so the mass-weighted mean displacement is
//   x(t) = v t - (v / w) sin(w t), w = sqrt(k / M), and the spring force is k (v t - x) = (k v / w) sin(w t).
//   The body is stiff against the spring (largest strain ~ k v / (w E A) = 4e-7), so its loaded edge follows the mean.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <string>

#include "engine_helpers.hpp"
#include "mesh/topology.hpp"

namespace {

std::string spring_case(const std::string& spring) {
    return testing::column_with_left_load_monitor("spring") + R"(
[[stages]]
name = "pull"
duration = 0.1
  [[stages.loads]]
  group = "left"
)" + spring;
}

// Mass-weighted mean x displacement of the body (m).
double mean_ux(const fdem::Simulation& sim) {
    const auto& md = sim.model();
    double p = 0, m = 0;
    for (int k = 0; k < md.n_nodes(); ++k) p += md.mass[k] * (md.x[2 * k] - md.X[2 * k]), m += md.mass[k];
    return p / m;
}

}  // namespace

TEST_CASE("spring load: a free body pulled through a spring follows x = v t - (v / w) sin(w t)", "[unit][spring]") {
    const double k = 4.0e5, v = 0.01;                   // N/m, m/s
    const double M = 0.2 * 1.0 * 0.1 * 2000.0;          // kg (column 0.2 x 1.0 m, t = 0.1 m, 2000 kg/m^3)
    const double w = std::sqrt(k / M);                  // rad/s (100)
    auto sim = testing::make_simulation(
        spring_case("  spring = { component = \"x\", stiffness = 4.0e5, velocity = 0.01 }\n"), "spring_pull");
    sim.begin_stage(0);
    double worst = 0, worst_f = 0;
    while (!sim.stage_finished()) {
        sim.step();
        // Monitors and the mean displacement are at t^n = time - dt (positions lag the step by one dt: use x^n).
        const double t = sim.time();
        const double x = mean_ux(sim);
        const double xs = v * t - v / w * std::sin(w * t);
        worst = std::max(worst, std::abs(x - xs));
        const double tn = t - sim.dt();
        worst_f = std::max(worst_f, std::abs(sim.monitor_value(0) - k * v / w * std::sin(w * tn)));
    }
    std::printf("[spring] %.4g s: mean displacement %.6e m (closed form %.6e), largest error %.3e m of amplitude %.3e m; "
                "spring force error %.3e N of %.3e N; balance error %.3e\n",
                sim.time(), mean_ux(sim), v * sim.time() - v / w * std::sin(w * sim.time()), worst, v / w, worst_f,
                k * v / w, sim.energies().balance_error());
    // The central-difference error of a 100 rad/s oscillation at dt ~ 3e-5 s and the body's elastic lag: 0.5 % of
    // the oscillation's amplitude v / w and of the force amplitude k v / w.
    CHECK(worst < 5e-3 * v / w);
    CHECK(worst_f < 5e-3 * k * v / w);
    CHECK(sim.energies().balance_error() < 1e-3);
}

TEST_CASE("spring load: bad input names the key", "[unit][spring]") {
    CHECK_THROWS_WITH(testing::make_simulation(spring_case("  spring = { component = \"x\", stiffness = -1.0, velocity = 0.01 }\n"),
                                               "spring_bad_k"),
                      Catch::Contains("stiffness") && Catch::Contains("> 0"));
    CHECK_THROWS_WITH(testing::make_simulation(spring_case("  force = [1.0, 0.0]\n  spring = { component = \"x\", stiffness = 1.0, velocity = 0.01 }\n"),
                                               "spring_two_kinds"),
                      Catch::Contains("give one of force, pressure, spring or foundation"));
    CHECK_THROWS_WITH(testing::make_simulation(spring_case("  spring = { component = \"z\", stiffness = 1.0, velocity = 0.01 }\n"),
                                               "spring_bad_component"),
                      Catch::Contains("component"));
}

// The spring's largest frequency on its group, omega^2 = k sum_i w_i^2 / m_i (rank-one stiffness k w w^T), against
// the step: refused above omega^2 dt^2 = 1, accepted below, and stable there for the whole stage.
TEST_CASE("spring load: a spring too stiff for the step is refused at its stage, one just below runs stable", "[unit][spring]") {
    auto probe = testing::make_simulation(spring_case("  spring = { component = \"x\", stiffness = 1.0e3, velocity = 0.0 }\n"),
                                          "spring_probe");
    const auto& md = probe.model();
    double s2 = 0;  // sum w_i^2 / m_i (1/kg)
    for (const auto& [k, w] : fdem::mesh::load_shares(md.group("left"), md.X)) s2 += w * w / md.mass[k];
    const double dt = probe.dt();
    const double k_max = 1.0 / (dt * dt * s2);  // N/m
    std::printf("[spring] step %.4e s, sum w^2/m %.4e 1/kg: the largest stiffness %.4e N/m\n", dt, s2, k_max);
    auto spring = [&](double k) {
        char b[160];
        std::snprintf(b, sizeof b, "  spring = { component = \"x\", stiffness = %.9e, velocity = 0.01 }\n", k);
        return spring_case(b);
    };
    auto stiff = testing::make_simulation(spring(1.02 * k_max), "spring_stiff");
    CHECK_THROWS_WITH(stiff.begin_stage(0), Catch::Contains("key 'spring': too stiff for the time step") &&
                                                Catch::Contains("expected a stiffness below"));
    auto fine = testing::make_simulation(spring(0.98 * k_max), "spring_fine");
    fine.begin_stage(0);
    REQUIRE(fine.dt() == dt);
    while (!fine.stage_finished()) fine.step();
    const auto e = fine.energies();
    std::printf("[spring] 0.98 of it: %ld steps, balance error %.3e\n", fine.steps(), e.balance_error());
    CHECK(std::isfinite(mean_ux(fine)));
    CHECK(std::abs(e.balance_error()) < 1e-3);
}
