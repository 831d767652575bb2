// fracture/mc_law.cpp: see mc_law.hpp.
#include "fracture/mc_law.hpp"

#include <cmath>

namespace fdem::fracture {

McResponse evaluate_mc(const McLaw& L, double o, double s, const McHistory& old) {
  McResponse r{};
  r.history = old;
  // Tension cut-off: the point cracks the first time sigma reaches f_t.
  if (!old.cracked && L.normal_stiffness * o >= L.tensile_strength) {
    r.history.cracked = true;
    const double o_t = L.tensile_strength / L.normal_stiffness;
    r.dissipated = 0.5 * L.normal_stiffness * o_t * o_t;
  }
  const bool cracked = r.history.cracked;
  const double o_e = cracked ? (o < 0.0 ? o : 0.0) : o;
  r.sigma = L.normal_stiffness * o_e;
  // Mohr-Coulomb: f_s = max(0, c_eff - sigma tan(phi)) (tension positive), perfectly plastic slip.
  const double c_eff = cracked ? 0.0 : L.cohesion;
  double f_s = c_eff - r.sigma * L.tan_friction;
  if (f_s < 0.0) f_s = 0.0;
  double s_p = old.slip_plastic;
  double tau = L.shear_stiffness * (s - s_p);
  if (tau > f_s) {
    tau = f_s;
    s_p = s - f_s / L.shear_stiffness;
  } else if (tau < -f_s) {
    tau = -f_s;
    s_p = s + f_s / L.shear_stiffness;
  }
  const double ds = s_p - old.slip_plastic;
  r.friction_dissipated = f_s * (ds < 0.0 ? -ds : ds);
  r.history.slip_plastic = s_p;
  r.tau = tau;
  r.energy = 0.5 * L.normal_stiffness * o_e * o_e + 0.5 * tau * tau / L.shear_stiffness;
  return r;
}

}  // namespace fdem::fracture

namespace fdem::fracture {

JointLaw make_mc_joint_law(double K_n, double K_s, double f_t, double cohesion, double tan_friction) {
  JointLaw L{};
  L.normal_stiffness = K_n;
  L.shear_stiffness = K_s;
  L.tensile_strength = f_t;
  L.cohesion = cohesion;
  L.tan_friction = tan_friction;
  L.inv_shear_stiffness = 1.0 / K_s;
  L.mohr_coulomb = true;
  return L;
}

PointResponse evaluate_mc_point(const JointLaw& L, double o, double s, const PointHistory& old) {
  const McLaw m{L.normal_stiffness, L.shear_stiffness, L.tensile_strength, L.cohesion, L.tan_friction};
  McHistory h;
  h.slip_plastic = old.slip_friction;
  h.cracked = old.trial > 0.5;
  const McResponse q = evaluate_mc(m, o, s, h);
  PointResponse r{};
  r.sigma = q.sigma;
  r.tau = q.tau;
  r.damage_I = 0.0;
  r.damage_II = 0.0;
  r.energy = q.energy;
  r.dissipated = q.dissipated;
  r.friction_dissipated = q.friction_dissipated;
  r.history = PointHistory{0.0, q.history.cracked ? 1.0 : 0.0, 0.0, q.history.slip_plastic, 0.0};
  return r;
}

}  // namespace fdem::fracture
