// The Mohr-Coulomb interface law of the M-DEM spring layers (fracture/mc_law.hpp).
//
// CLOSED FORMS (K_n, K_s in Pa/m; tension positive)
//   Tension: sigma = K_n o up to f_t at o_t = f_t / K_n, then 0 for any opening, and again K_n o when closed;
//   the cracking releases K_n o_t^2 / 2.
//   Shear at a fixed compression sigma_n: tau = K_s s up to c + sigma_n tan(phi), then held at that value for any
//   slip (no softening); unloading from the plateau at slope K_s, reversed slip plateau at -(c + sigma_n tan(phi));
//   the slip work equals f_s times the plastic slip; after cracking the cohesion is gone.
#include <catch2/catch.hpp>

#include <cmath>

#include "fracture/mc_law.hpp"

using namespace fdem::fracture;

namespace {
McLaw layer() {  // bed joints of the Ispra piers (JRC Ispra, M-DEM paper Table 1): c 0.23 MPa, tan(phi) 0.58; stiffnesses ours
  return McLaw{1.0e10, 4.0e9, 0.1e6, 0.23e6, 0.58};
}
}  // namespace

TEST_CASE("mc law: tension cut-off at f_t, then no tension, compression kept", "[unit][mc]") {
  const McLaw L = layer();
  McHistory h;
  const double o_t = L.tensile_strength / L.normal_stiffness;
  auto r = evaluate_mc(L, 0.5 * o_t, 0.0, h);
  CHECK(r.sigma == Approx(0.5 * L.tensile_strength));
  CHECK(!r.history.cracked);
  CHECK(r.dissipated == 0.0);
  h = r.history;
  r = evaluate_mc(L, o_t * (1 + 1e-9), 0.0, h);
  CHECK(r.history.cracked);
  CHECK(r.sigma == 0.0);
  CHECK(r.dissipated == Approx(0.5 * L.tensile_strength * o_t));
  h = r.history;
  for (double o : {2 * o_t, 100 * o_t, 0.5 * o_t}) {
    r = evaluate_mc(L, o, 0.0, h);
    CHECK(r.sigma == 0.0);
    CHECK(r.dissipated == 0.0);
    CHECK(r.energy == 0.0);
  }
  r = evaluate_mc(L, -o_t, 0.0, h);  // closed again: compression as before
  CHECK(r.sigma == Approx(-L.tensile_strength));
  CHECK(r.energy == Approx(0.5 * L.normal_stiffness * o_t * o_t));
}

TEST_CASE("mc law: shear strength c + sigma tan(phi) held without softening, unloading at K_s", "[unit][mc]") {
  const McLaw L = layer();
  const double sigma_n = 0.6e6;                   // compression, Pa
  const double o = -sigma_n / L.normal_stiffness;  // closes the joint to sigma = -sigma_n
  const double f_s = L.cohesion + sigma_n * L.tan_friction;
  const double s_y = f_s / L.shear_stiffness;
  McHistory h;
  double work = 0, tau_prev = 0, s_prev = 0, fric = 0;
  const int n = 4000;
  const double s_end = 50 * s_y;
  for (int i = 1; i <= n; ++i) {
    const double s = s_end * i / n;
    const auto r = evaluate_mc(L, o, s, h);
    CHECK(r.sigma == Approx(-sigma_n));
    if (s <= s_y) CHECK(r.tau == Approx(L.shear_stiffness * s));
    else CHECK(r.tau == Approx(f_s).epsilon(1e-12));  // no softening at 50 times the elastic slip
    work += 0.5 * (r.tau + tau_prev) * (s - s_prev);
    fric += r.friction_dissipated;
    tau_prev = r.tau, s_prev = s;
    h = r.history;
  }
  CHECK(h.slip_plastic == Approx(s_end - s_y));
  // Work = stored + slip work (the trapezoid overshoots by the one corner increment: within 1e-3).
  const double stored = 0.5 * f_s * f_s / L.shear_stiffness;
  CHECK(fric == Approx(f_s * (s_end - s_y)).epsilon(1e-12));
  CHECK(work == Approx(stored + fric).epsilon(1e-3));
  // Unloading: slope K_s from the plateau, elastic until -f_s.
  const double s1 = s_end - 0.5 * s_y;
  auto r = evaluate_mc(L, o, s1, h);
  CHECK(r.tau == Approx(f_s - L.shear_stiffness * 0.5 * s_y));
  CHECK(r.friction_dissipated == 0.0);
  CHECK(r.history.slip_plastic == h.slip_plastic);
  r = evaluate_mc(L, o, s_end - 3 * s_y, h);  // reversed past -f_s: plateau at -f_s
  CHECK(r.tau == Approx(-f_s));
  CHECK(r.history.slip_plastic == Approx(s_end - 3 * s_y + s_y));
  // Cohesion-free after a tensile crack: the shear limit is sigma_n tan(phi).
  McHistory cr;
  cr.cracked = true;
  r = evaluate_mc(L, o, 10 * s_y, cr);
  CHECK(r.tau == Approx(sigma_n * L.tan_friction));
}

TEST_CASE("mc law: in tension below the cut-off the shear limit is c - sigma tan(phi)", "[unit][mc]") {
  const McLaw L = layer();
  const double sigma = 0.05e6;
  const auto r = evaluate_mc(L, sigma / L.normal_stiffness, 1.0, McHistory{});
  CHECK(r.sigma == Approx(sigma));
  CHECK(r.tau == Approx(L.cohesion - sigma * L.tan_friction));
}
