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
