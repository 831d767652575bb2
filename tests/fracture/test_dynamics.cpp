// The joint forces under the engine's integrator (central difference / leap-frog, fdem/README.md 'Time step'), on one element
// with lumped node masses: the stable step is right, and kinetic + elastic + dissipated energy is conserved through
// softening and breaking.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "fracture/cohesive_system.hpp"
#include "test_grid.hpp"

using namespace fdem::fracture;
using fracture_test::OneElement;

namespace {
CohesiveProps stone() { return fracture_test::sandstone(2e10); }  // cases/README.md §A sandstone

struct LeapFrog {
  CohesiveSystem sys;
  std::vector<double> x, v, m;  // m per node (kg); m = 0 marks a fixed node
  std::size_t breaks = 0;
  LeapFrog(const CohesiveProps& p, double h, double t, std::vector<double> mass)
      : sys(OneElement::element(), {p}, t, OneElement::reference(h).data(), 4),
        x(OneElement::reference(h)),
        v(8, 0.0),
        m(std::move(mass)) {}
  // One step: v += dt f(x) / m, x += dt v. Returns the force at the start of the step.
  std::vector<double> step(double dt) {
    std::vector<double> f(8, 0.0);
    sys.add_forces(x.data(), f.data());
    breaks += sys.update_damage(0.0, 0.0, x.data()).size();
    for (int i = 0; i < 8; ++i) {
      if (m[i / 2] == 0.0) continue;
      v[i] += dt * f[i] / m[i / 2];
      x[i] += dt * v[i];
    }
    return f;
  }
  double gap_y() const { return 0.5 * ((x[5] - x[1]) + (x[7] - x[3])); }  // mean y gap of B relative to A
};
}  // namespace

TEST_CASE("leap-frog with the joint alone: stable just below stable_dt, unstable just above", "[unit]") {
  // Four free nodes of equal mass: the highest mode (A against B, uniform gap) has omega^2 = h t K (2/m) / 2, so the
  // Gershgorin bound of stable_dt is attained and the limit is sharp.
  const double h = 0.025, t = 0.2, m = 0.05;
  const CohesiveProps p = stone();
  for (double factor : {0.98, 1.02}) {
    CAPTURE(factor);
    LeapFrog lf(p, h, t, {m, m, m, m});
    const double dt = factor * lf.sys.stable_dt(lf.m.data());
    const double amp0 = 1e-6 * lf.sys.law(0).opening_peak;  // tiny: linear regime, no damage
    lf.x[1] -= 0.5 * amp0;  // A down, B up: overlap, o = -amp0
    lf.x[3] -= 0.5 * amp0;
    lf.x[5] += 0.5 * amp0;
    lf.x[7] += 0.5 * amp0;
    // Stop at 1e3 amp0, far below o_p = 1e6 amp0, so that the test stays in the linear, undamaged regime.
    double amp = 0.0;
    for (int n = 0; n < 3000 && amp < 1e3 * amp0; ++n) {
      lf.step(dt);
      amp = std::max(amp, std::abs(lf.gap_y()));
    }
    if (factor < 1.0) {
      // Starting from rest at the half step, the leap-frog amplitude is amp0 / sqrt(1 - (omega dt / 2)^2) = 5 amp0
      // at omega dt = 1.96: bounded.
      CHECK(amp < 6.0 * amp0);
    } else {
      CHECK(amp >= 1e3 * amp0);
    }
    CHECK(lf.sys.damage(0) == 0.0);
  }
}

TEST_CASE("leap-frog through softening and breaking: kinetic + elastic + dissipated energy is conserved",
          "[convergence]") {
  // Side A fixed, side B (two nodes of mass m) launched with the kinetic energy 1.5 G A, in mode I or obliquely.
  // The balance error (leap-frog plus the dissipation bookkeeping) is second order in dt: check it shrinks with dt.
  const double h = 0.025, t = 0.2, m = 0.1;
  const CohesiveProps p = stone();
  const double A = h * t, KE0 = 1.5 * p.G_I * A;
  for (double angle : {0.0, 0.6}) {
    double err_prev = 0.0;
    for (double fraction : {0.2, 0.02}) {
      CAPTURE(angle, fraction);
      LeapFrog lf(p, h, t, {0.0, 0.0, m, m});
      const std::vector<double> lumped(4, m);  // the step as if A were free too (the engine passes real masses)
      const double dt = fraction * lf.sys.stable_dt(lumped.data());
      const double v0 = std::sqrt(KE0 / m);  // 2 nodes: KE = m v0^2
      // Opening is B moving along n = (0, -1); slip along t = (1, 0).
      for (int k = 2; k < 4; ++k) {
        lf.v[2 * k] = v0 * std::sin(angle);
        lf.v[2 * k + 1] = -v0 * std::cos(angle);
      }
      // Start the staggered velocity at -dt/2 with the (zero) initial force: v^{-1/2} = v0.
      std::vector<double> v_half_old = lf.v;
      double worst = 0.0;
      int n = 0;
      while (lf.breaks == 0 && n < 2000000) {
        lf.step(dt);
        // KE at integer step n: mean of the two half-step velocities around it.
        double ke = 0.0;
        for (int i = 4; i < 8; ++i) {
          const double vn = 0.5 * (v_half_old[i] + lf.v[i]);
          ke += 0.5 * m * vn * vn;
        }
        v_half_old = lf.v;
        worst = std::max(worst, std::abs(ke + lf.sys.elastic_energy() + lf.sys.dissipated_energy() - KE0));
        ++n;
      }
      REQUIRE(lf.breaks == 1);
      double ke_final = 0.0;
      for (int i = 4; i < 8; ++i) ke_final += 0.5 * m * lf.v[i] * lf.v[i];
      const double err = worst / KE0;
      WARN("angle " << angle << " rad, dt = " << fraction << " dt_stable: " << n << " steps, balance error "
                    << err << " KE0, dissipated " << lf.sys.dissipated_energy() / A << " J/m^2, final KE "
                    << ke_final / KE0 << " KE0");
      if (angle == 0.0) CHECK(lf.sys.dissipated_energy() == Approx(p.G_I * A).epsilon(0.02));
      CHECK(err < 0.02);
      if (fraction < 0.1) CHECK(err < 0.02 * err_prev);  // 10x smaller dt: 100x smaller error
      err_prev = err;
    }
  }
}
