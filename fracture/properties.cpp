// fracture/properties.cpp: validation of cohesive properties and their conversion to per-element law constants.
// DATA LAYOUT: none (cold data, one CohesiveProps per class).
#include "fracture/properties.hpp"
#include "fracture/value_checks.hpp"

#include "fracture/mc_law.hpp"

#include <cmath>
#include <sstream>

namespace fdem::fracture {

namespace {
constexpr double kPi = 3.14159265358979323846;

// Initial slopes (Pa/m) of the law for an element of length h: p_j / h or the measured k_n, k_s.
void stiffnesses(const CohesiveProps& p, double h, double& K_n, double& K_s) {
  if (!std::isnan(p.penalty)) {
    K_n = p.penalty / h;
    K_s = p.penalty / h;
  } else {
    K_n = p.k_n;
    K_s = p.k_s;
  }
}
}  // namespace

std::vector<std::string> check(const CohesiveProps& p, double h_max, double sigma_c) {
  if (p.composite) return check_composite(p, h_max);  // law = "composite": its own checks (composite_law.cpp)
  std::vector<std::string> out;
  need_positive(out, "tensile strength f_t", "Pa", p.tensile_strength);
  need_positive(out, "cohesion c", "Pa", p.cohesion);
  need_angle(out, "friction angle", p.friction_deg);
  need_angle(out, "residual friction angle", p.residual_friction_deg);
  if (!p.mohr_coulomb) {
    need_positive(out, "mode I fracture energy G_I", "J/m^2", p.G_I);
    need_positive(out, "mode II fracture energy G_II", "J/m^2", p.G_II);
  }
  if (!std::isnan(p.compressive_strength)) need_positive(out, "compressive strength f_c", "Pa", p.compressive_strength);

  const bool has_penalty = !std::isnan(p.penalty);
  const bool has_kn = !std::isnan(p.k_n), has_ks = !std::isnan(p.k_s);
  if (has_penalty && (has_kn || has_ks)) {
    out.push_back("give either the joint penalty p_j (Pa) or the interface stiffnesses k_n, k_s (Pa/m), not both");
  } else if (has_penalty) {
    need_positive(out, "joint penalty p_j", "Pa", p.penalty);
    if (!(h_max > 0.0) || !std::isfinite(h_max)) {
      out.push_back("element length h = " + fmt(h_max) + " m is not physical: it must be finite and > 0");
    }
  } else if (has_kn || has_ks) {
    need_positive(out, "normal stiffness k_n", "Pa/m", p.k_n);
    need_positive(out, "shear stiffness k_s", "Pa/m", p.k_s);
  } else {
    out.push_back("stiffness is missing: give the joint penalty p_j (Pa) or the interface stiffnesses k_n, k_s (Pa/m)");
  }
  if (!(sigma_c >= 0.0) || !std::isfinite(sigma_c)) {
    out.push_back("expected compression sigma_c = " + fmt(sigma_c) + " Pa must be finite and >= 0");
  } else if (p.compressive_strength > 0.0 && sigma_c >= p.compressive_strength) {
    out.push_back("expected compression sigma_c = " + fmt(sigma_c) + " Pa reaches the compressive strength f_c = " +
                  fmt(p.compressive_strength) + " Pa: the joints would crush under the load alone");
  }
  if (!out.empty() || p.mohr_coulomb) return out;  // the energy checks need every value above (none without softening)

  // Too-compliant joints: the pre-peak work alone would exceed G (fracture/README.md).
  double K_n = 0.0, K_s = 0.0;
  stiffnesses(p, h_max, K_n, K_s);
  const double f_t = p.tensile_strength;
  const double o_p = opening_at_peak(f_t, K_n);
  if (p.G_I <= (2.0 / 3.0) * f_t * o_p) {
    std::string need = has_penalty ? "p_j > 4 h f_t^2 / (3 G_I) = " + fmt(4.0 * h_max * f_t * f_t / (3.0 * p.G_I)) + " Pa"
                                   : "k_n > 4 f_t^2 / (3 G_I) = " + fmt(4.0 * f_t * f_t / (3.0 * p.G_I)) + " Pa/m";
    out.push_back("joint too soft for its mode I fracture energy: G_I = " + fmt(p.G_I) +
                  " J/m^2 <= (2/3) f_t o_p = " + fmt((2.0 / 3.0) * f_t * o_p) + " J/m^2" +
                  (has_penalty ? " at h = " + fmt(h_max) + " m" : std::string()) + "; need " + need);
  }
  const double f_s = p.cohesion + sigma_c * std::tan(p.friction_deg * kPi / 180.0);
  const double s_p = opening_at_peak(f_s, K_s);
  // keep_friction: G_II pays for the softening of the cohesion only, (2/3) c s_p before the peak.
  if (p.G_II <= (2.0 / 3.0) * (p.keep_friction ? p.cohesion : f_s) * s_p) {
    std::string need = has_penalty ? "p_j > 4 h f_s^2 / (3 G_II) = " + fmt(4.0 * h_max * f_s * f_s / (3.0 * p.G_II)) + " Pa"
                                   : "k_s > 4 f_s^2 / (3 G_II) = " + fmt(4.0 * f_s * f_s / (3.0 * p.G_II)) + " Pa/m";
    out.push_back("joint too soft for its mode II fracture energy: G_II = " + fmt(p.G_II) +
                  " J/m^2 <= (2/3) f_s s_p = " + fmt((2.0 / 3.0) * f_s * s_p) + " J/m^2 (f_s = " + fmt(f_s) +
                  " Pa)" + (has_penalty ? " at h = " + fmt(h_max) + " m" : std::string()) + "; need " + need);
  }
  return out;
}

double auto_penalty(const CohesiveProps& p, double h_max) {
  const double f_t = p.tensile_strength, c = p.cohesion;
  // The fracture-energy conditions of check() (mode I; mode II at zero normal stress) solved for p_j.
  const double p_G = 4.0 * h_max * std::max(f_t * f_t / p.G_I, c * c / p.G_II) / 3.0;
  return std::max(p.penalty_ref, kAutoPenaltyMargin * p_G);
}

JointLaw make_law(const CohesiveProps& p, double h) {
  double K_n = 0.0, K_s = 0.0;
  stiffnesses(p, h, K_n, K_s);
  if (p.composite) {  // law = "composite": the stiffnesses only (composite_law.hpp holds the law)
    JointLaw L{};
    L.normal_stiffness = K_n;
    L.shear_stiffness = K_s;
    return L;
  }
  if (p.mohr_coulomb) return make_mc_joint_law(K_n, K_s, p.tensile_strength, p.cohesion, std::tan(p.friction_deg * kPi / 180.0));
  JointLaw L = make_joint_law(K_n, K_s, p.tensile_strength, p.G_I, p.cohesion,
                              std::tan(p.friction_deg * kPi / 180.0), p.G_II);
  L.keep_friction = p.keep_friction;
  L.compressive_strength = std::isnan(p.compressive_strength) ? 0.0 : p.compressive_strength;
  return L;
}

}  // namespace fdem::fracture
