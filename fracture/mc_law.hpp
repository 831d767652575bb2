// fracture/mc_law.hpp: the Mohr-Coulomb interface law of the M-DEM spring layers (seeds/000, issue 29): elastic
// springs K_n, K_s (Pa/m) with a Mohr-Coulomb shear limit that does not soften (residual = peak) and a tension
// cut-off. Per unit joint area, tension positive, like fracture/law.hpp.
//
// Law at one point (opening o, slip s, m; history: plastic slip s_p (m) and a cracked flag):
//   sigma = K_n o                          uncracked (o < o_t = f_t / K_n)
//         = K_n min(o, 0)                  cracked: no tension ever again
//   the point cracks the first time o >= o_t (tension cut-off, brittle: the tensile strength and the cohesion of
//   that point are lost, as in the Coulomb slip joint of 3DEC that seeds/000 uses); the stored K_n o_t^2 / 2 is
//   dissipated then;
//   tau   = K_s (s - s_p),  |tau| <= f_s = max(0, c_eff - sigma tan(phi)),  c_eff = c (uncracked) or 0 (cracked);
//   past f_s the slip is plastic (s_p moves, perfectly plastic: no shear softening), and its work f_s |d s_p| is
//   dissipated (booked as friction dissipation).
// Stored energy: K_n o_e^2 / 2 + tau^2 / (2 K_s) with o_e the sigma-carrying opening. The damage of the point
// stays 0: the element never breaks and never hands over to contact (the layers stay in place; cracks show as
// joint_opening and joint_slip in the snapshots).
#pragma once

namespace fdem::fracture {

struct McLaw {
  double normal_stiffness;  // K_n, Pa/m
  double shear_stiffness;   // K_s, Pa/m
  double tensile_strength;  // f_t, Pa (>= 0)
  double cohesion;          // c, Pa (>= 0)
  double tan_friction;      // tan(phi), -
};

struct McHistory {
  double slip_plastic = 0.0;  // s_p, m
  bool cracked = false;       // tension cut-off reached once
};

struct McResponse {
  double sigma;                 // Pa, tension positive
  double tau;                   // Pa
  double energy;                // J/m^2 stored at the new state
  double dissipated;            // J/m^2 released by cracking in this evaluation
  double friction_dissipated;   // J/m^2 work of the plastic slip in this evaluation (>= 0)
  McHistory history;
};

McResponse evaluate_mc(const McLaw& L, double o, double s, const McHistory& old);

}  // namespace fdem::fracture

#include "fracture/law.hpp"

namespace fdem::fracture {

// law = "mohr_coulomb" in the cohesive system: a JointLaw whose evaluate_point defers to evaluate_mc. The element's
// PointHistory carries the state: slip_friction = s_p, trial = 1 once cracked (0 before); damage stays 0.
JointLaw make_mc_joint_law(double K_n, double K_s, double f_t, double cohesion, double tan_friction);

}  // namespace fdem::fracture
