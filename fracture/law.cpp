// fracture/law.cpp: softening function, energy-exact ranges and the point law of fracture/README.md.
// DATA LAYOUT: none (pure scalar functions; the element loop lives in cohesive_system.cpp).
#include "fracture/law.hpp"

#include <algorithm>
#include <cmath>

namespace fdem::fracture {

namespace {
constexpr double kA = 0.63;  // [K25] Eq. 10 constants, dimensionless
constexpr double kB = 1.8;
constexpr double kC = 6.0;
constexpr double kPrefactor = (kA + kB - 1.0) / (kA + kB);
constexpr double kExponent = (kA + kC * kB) / ((kA + kB) * (1.0 - kA - kB));  // negative: exp decays
}  // namespace

double softening(double D) {
  // [K25] Eq. 10. (1-D)^6 by multiplication: pow() is slower and not needed for an integer exponent.
  if (D <= 0.0) return 1.0;
  if (D >= 1.0) return 0.0;
  const double r = 1.0 - D;
  const double r2 = r * r;
  const double r6 = r2 * r2 * r2;
  return (1.0 - kPrefactor * std::exp(D * kExponent)) * (kA * r + kB * r6);
}

double softening_integral() {
  // kappa = int_0^1 z(D) dD. z is smooth on [0, 1], so 64 panels of 5-point Gauss-Legendre give it to rounding.
  static const double kappa = [] {
    const double xg[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640};
    const double wg[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                          0.2369268850561891};
    const int panels = 64;
    double sum = 0.0;
    for (int p = 0; p < panels; ++p) {
      const double lo = double(p) / panels, half = 0.5 / panels;
      for (int q = 0; q < 5; ++q) sum += wg[q] * half * softening(lo + half * (1.0 + xg[q]));
    }
    return sum;
  }();
  return kappa;
}

double softening_range(double fracture_energy, double strength, double elastic_limit) {
  // fracture/README.md: G = (2/3) f o_p + kappa f o_t  =>  o_t = (G - (2/3) f o_p) / (kappa f).
  return (fracture_energy - (2.0 / 3.0) * strength * elastic_limit) / (softening_integral() * strength);
}

double shear_softening_range(const JointLaw& law, double shear_strength_now, double slip_peak) {
  const double s_t = softening_range(law.shear_energy, shear_strength_now, slip_peak);
  return std::max(s_t, 1e-3 * slip_peak);
}

double cohesion_softening_range(const JointLaw& law, double slip_peak) {
  const double s_t = softening_range(law.shear_energy, law.cohesion, slip_peak);
  return std::max(s_t, 1e-3 * slip_peak);
}

PointHistory initial_history(const JointLaw& law) {
  if (law.mohr_coulomb) return PointHistory{0.0, 0.0, 0.0, 0.0, 0.0};  // fracture/mc_law.hpp: nothing happened yet
  const double dI = -law.opening_peak * law.inv_opening_range, dII = -law.slip_peak0 * law.inv_slip_range0;
  return PointHistory{0.0, dI > dII ? dI : dII, 0.0, 0.0, 0.0};
}

JointLaw make_joint_law(double K_n, double K_s, double f_t, double G_I, double cohesion, double tan_friction,
                        double G_II) {
  JointLaw L{};
  L.normal_stiffness = K_n;
  L.shear_stiffness = K_s;
  L.tensile_strength = f_t;
  L.opening_peak = opening_at_peak(f_t, K_n);
  L.opening_range = softening_range(G_I, f_t, L.opening_peak);
  L.cohesion = cohesion;
  L.tan_friction = tan_friction;
  L.shear_energy = G_II;
  L.slip_peak0 = opening_at_peak(cohesion, K_s);
  L.slip_range0 = shear_softening_range(L, cohesion, L.slip_peak0);
  L.inv_opening_peak = 1.0 / L.opening_peak;
  L.inv_opening_range = 1.0 / L.opening_range;
  L.inv_shear_stiffness = 1.0 / K_s;
  L.inv_slip_peak0 = 1.0 / L.slip_peak0;
  L.inv_slip_range0 = 1.0 / L.slip_range0;
  return L;
}

}  // namespace fdem::fracture
