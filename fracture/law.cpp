// fracture/law.cpp: softening function, energy-exact ranges and the point law of FORMULATION §6.
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
  // FORMULATION §6: G = (2/3) f o_p + kappa f o_t  =>  o_t = (G - (2/3) f o_p) / (kappa f).
  return (fracture_energy - (2.0 / 3.0) * strength * elastic_limit) / (softening_integral() * strength);
}

double shear_softening_range(const JointLaw& law, double shear_strength_now, double slip_peak) {
  const double s_t = softening_range(law.shear_energy, shear_strength_now, slip_peak);
  return std::max(s_t, 1e-3 * slip_peak);
}

PointResponse evaluate_point(const JointLaw& law, double o, double s, double damage_old) {
  PointResponse r{};
  const double K_n = law.normal_stiffness;
  const double f_t = law.tensile_strength;
  const double o_p = law.opening_peak;

  // Compression is an undamaged linear penalty: crack faces in contact carry pressure whatever D is.
  const double sigma_c = o < 0.0 ? K_n * o : 0.0;
  const double f_s = shear_strength(sigma_c, law.cohesion, law.tan_friction);
  const double s_p = opening_at_peak(f_s, law.shear_stiffness);
  const double a_s = std::abs(s);

  // Damage components from the current separation; D is the largest value ever reached (irreversible).
  const double D_I = o > o_p ? (o - o_p) / law.opening_range : 0.0;
  const double D_II = a_s > s_p ? (a_s - s_p) / shear_softening_range(law, f_s, s_p) : 0.0;
  double D = damage_old;
  if (D_I > 0.0 || D_II > 0.0) {
    const double D_trial = std::min(1.0, std::sqrt(D_I * D_I + D_II * D_II));
    D = std::max(D, D_trial);
  }
  r.damage = D;
  r.damage_I = D_I;
  r.damage_II = D_II;

  // Undamaged tensile and shear curves; z(D) scales both (FORMULATION §6).
  const double o_pos = o > 0.0 ? o : 0.0;
  const double t_n0 = o > 0.0 ? undamaged_traction(o_pos, o_p, f_t) : 0.0;
  const double t_s0 = undamaged_traction(a_s, s_p, f_s);
  const double z = softening(D);
  r.sigma = o < 0.0 ? sigma_c : z * t_n0;
  r.tau = (s < 0.0 ? -z : z) * t_s0;

  // Recoverable energy: the work given back when unloading to o = s = 0 at frozen D along the same curves.
  const double e_n0 = o > 0.0 ? undamaged_energy(o_pos, o_p, f_t) : 0.0;
  const double e_s0 = undamaged_energy(a_s, s_p, f_s);
  const double e_c = o < 0.0 ? 0.5 * K_n * o * o : 0.0;
  r.energy = z * (e_n0 + e_s0) + e_c;
  // E(o,s,D_old) - E(o,s,D_new): exact bookkeeping of "work done minus recoverable energy" for each increment.
  r.dissipated = D > damage_old ? (softening(damage_old) - z) * (e_n0 + e_s0) : 0.0;
  return r;
}

}  // namespace fdem::fracture
