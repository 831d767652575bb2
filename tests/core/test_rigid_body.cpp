// tests/core/test_rigid_body.cpp: a support rigid = "body" (fdem/support_body.cpp).
//
// SCENE. A 0.4 x 0.2 m block (E 1e9 Pa, 2000 kg/m^3, thickness 0.1 m, mesh 0.05 m), no contact, given an initial
// velocity v0 and angular velocity omega0 about its centre ([[initial]]), one stage with rigid = "body" on the block.
// CLOSED FORMS. Free of forces the body keeps its momentum and its angular momentum about its centre of mass, its
// shape (every distance between two nodes) and its kinetic energy; under gravity g its centre follows
// c0 + v0 t + g t^2 / 2 (central differences are exact for a constant acceleration) and it turns at omega0.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "engine_helpers.hpp"

namespace {

std::string body_case(const std::string& gravity, const std::string& extra_support = "") {
    std::ostringstream c;
    c << "[case]\nname = \"body\"\nthickness = 0.1\n[geometry]\ntype = \"rectangle\"\nwidth = 0.4\nheight = 0.2\n"
      << "mesh_size = 0.05\n[materials.m]\nE = 1e9\nnu = 0.2\ndensity = 2000.0\n[regions]\nbody = \"m\"\n"
      << "[[initial]]\ngroup = \"body\"\nvelocity = [0.3, -0.1]\nangular_velocity = 2.0\ncenter = [0.2, 0.1]\n"
      << "[[stages]]\nname = \"fly\"\nduration = 0.05\nlocal_damping = 0.0\ngravity = " << gravity << "\n"
      << "  [[stages.supports]]\n  group = \"body\"\n  rigid = \"body\"\n" << extra_support;
    return c.str();
}

struct BodyState {
    double m = 0, cx = 0, cy = 0, px = 0, py = 0, L = 0, K = 0;
};

BodyState body_state(const fdem::Simulation& sim) {
    const auto& md = sim.model();
    BodyState b;
    for (int k = 0; k < md.n_nodes(); ++k) {
        const double m = md.mass[k];
        b.m += m, b.cx += m * md.x[2 * k], b.cy += m * md.x[2 * k + 1];
        b.px += m * md.v[2 * k], b.py += m * md.v[2 * k + 1];
        b.K += 0.5 * m * (md.v[2 * k] * md.v[2 * k] + md.v[2 * k + 1] * md.v[2 * k + 1]);
    }
    b.cx /= b.m, b.cy /= b.m;
    for (int k = 0; k < md.n_nodes(); ++k)
        b.L += md.mass[k] * ((md.x[2 * k] - b.cx) * md.v[2 * k + 1] - (md.x[2 * k + 1] - b.cy) * md.v[2 * k]);
    return b;
}

double max_distance_change(const fdem::Simulation& sim, const std::vector<double>& x0) {
    const auto& x = sim.model().x;
    const int n = sim.model().n_nodes();
    double worst = 0;
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j) {
            const double d0 = std::hypot(x0[2 * j] - x0[2 * i], x0[2 * j + 1] - x0[2 * i + 1]);
            const double d = std::hypot(x[2 * j] - x[2 * i], x[2 * j + 1] - x[2 * i + 1]);
            worst = std::max(worst, std::fabs(d - d0) / d0);
        }
    return worst;
}

}  // namespace

TEST_CASE("rigid body: a free spinning body keeps its shape, momentum, angular momentum and kinetic energy",
          "[engine][regression]") {
    fdem::Simulation sim = testing::make_simulation(body_case("[0.0, 0.0]"), "rigid_body_free", {}, 1);
    sim.begin_stage(0);
    sim.step();  // the first step sets the chord velocities of the rotation
    const std::vector<double> x0 = sim.model().x;
    const BodyState b0 = body_state(sim);
    long steps = 0;
    while (!sim.stage_finished()) sim.step(), ++steps;
    const BodyState b = body_state(sim);
    std::printf("[rigid body free] %ld steps: distances %.2e, momentum %.2e / %.2e, L %.2e, K %.2e (relative), "
                "elastic %.2e J\n", steps, max_distance_change(sim, x0), std::fabs(b.px - b0.px) / std::fabs(b0.px),
                std::fabs(b.py - b0.py) / std::fabs(b0.py), std::fabs(b.L - b0.L) / b0.L, std::fabs(b.K - b0.K) / b0.K,
                sim.energies().elastic);
    CHECK(steps > 1000);
    CHECK(max_distance_change(sim, x0) < 1e-12);
    CHECK(b.px == Approx(b0.px).epsilon(1e-12));
    CHECK(b.py == Approx(b0.py).epsilon(1e-12));
    CHECK(b.L == Approx(b0.L).epsilon(1e-10));
    CHECK(b.K == Approx(b0.K).epsilon(1e-10));
    // It turned at omega0 = 2 rad/s: I omega0 about the centre of mass.
    double I = 0;
    const auto& md = sim.model();
    for (int k = 0; k < md.n_nodes(); ++k)
        I += md.mass[k] * ((md.x[2 * k] - b.cx) * (md.x[2 * k] - b.cx) + (md.x[2 * k + 1] - b.cy) * (md.x[2 * k + 1] - b.cy));
    CHECK(b.L / I == Approx(2.0).epsilon(1e-6));
    CHECK(sim.energies().elastic < 1e-12 * b.K);
    CHECK(std::fabs(sim.energies().balance_error()) < 1e-9);
}

TEST_CASE("rigid body: under gravity the centre falls as c0 + v0 t + g t^2 / 2 while the body turns", "[engine][regression]") {
    fdem::Simulation sim = testing::make_simulation(body_case("[0.0, -9.81]"), "rigid_body_fall", {}, 1);
    sim.begin_stage(0);  // applies the initial conditions
    const BodyState b0 = body_state(sim);
    const double dt = sim.dt();
    long n = 0;
    while (!sim.stage_finished()) sim.step(), ++n;
    const BodyState b = body_state(sim);
    // Central differences from v^{-1/2} = v0: x_n = x_0 + n dt v0 + g dt^2 n (n + 1) / 2 (the continuous
    // c0 + v0 t + g t^2 / 2 plus g t dt / 2).
    const double t = n * dt, ey = b0.cy - 0.1 * t - 0.5 * 9.81 * dt * dt * n * (n + 1);
    std::printf("[rigid body fall] %ld steps, t %.5f s: centre (%.12f, %.12f) against (%.12f, %.12f); L %.9f -> %.9f\n",
                n, t, b.cx, b.cy, b0.cx + 0.3 * t, ey, b0.L, b.L);
    CHECK(b.cx == Approx(b0.cx + 0.3 * t).margin(1e-12));
    CHECK(b.cy == Approx(ey).margin(1e-12));
    CHECK(b0.L != 0.0);
    CHECK(b.L == Approx(b0.L).epsilon(1e-10));
}

TEST_CASE("rigid body: rigid = \"body\" with another support of the same component in the block is refused, naming the key",
          "[engine][regression]") {
    const auto dir = testing::tmp_dir("rigid_body_error");
    const std::string text = body_case("[0.0, 0.0]", "") ;
    std::string bad = text;
    bad.replace(bad.find("  rigid = \"body\"\n"), 17, "  fix = \"x\"\n  rigid = \"body\"\n");
    const std::string path = testing::write_text(dir / "case.toml", bad);
    const auto r = testing::run_fdem("check \"" + path + "\"", dir);
    CHECK(r.code == 1);
    CHECK(r.err.find("stages.1.supports.1.rigid") != std::string::npos);
    CHECK(r.err.find("already has a support") != std::string::npos);
    const std::string path2 = testing::write_text(dir / "case2.toml", text.substr(0, text.find("rigid = \"body\"")) + "rigid = \"bodies\"\n");
    const auto r2 = testing::run_fdem("check \"" + path2 + "\"", dir);
    CHECK(r2.code == 1);
    CHECK(r2.err.find("\"body\"") != std::string::npos);
}
