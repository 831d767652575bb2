// fracture/properties.hpp: material properties of one class of cohesive elements and their validation.
//
// Classes (issue 7): the unit interior of each material (crackable edges inside a stone or brick) and the bonded
// interface of each pair of materials. A class gives either the joint penalty p_j (Pa; the law's initial slope is
// then p_j / h with h the element length) or, for a zero-thickness interface with measured stiffness, k_n and k_s
// (Pa/m). Unset values are NaN so that check() can tell "missing" from "zero".
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "fracture/law.hpp"

namespace fdem::fracture {

struct CohesiveProps {
  static constexpr double unset = std::numeric_limits<double>::quiet_NaN();
  double tensile_strength = unset;       // f_t, Pa (> 0)
  double cohesion = unset;               // c, Pa (> 0)
  double friction_deg = unset;           // phi, degrees in [0, 90)
  double residual_friction_deg = unset;  // phi_res after breaking (used by contact), degrees in [0, 90)
  double G_I = unset;                    // mode I fracture energy, J/m^2 (> 0)
  double G_II = unset;                   // mode II fracture energy, J/m^2 (> 0)
  double penalty = unset;                // p_j, Pa (> 0); give this OR k_n and k_s
  double k_n = unset;                    // normal stiffness of a zero-thickness interface, Pa/m (> 0)
  double k_s = unset;                    // shear stiffness of a zero-thickness interface, Pa/m (> 0)
  bool keep_friction = false;            // only the cohesion softens, friction is kept (law.hpp; [LR97])
  double compressive_strength = unset;   // f_c, Pa (> 0): compressive cap (law.hpp); unset = no cap
};

// Problems with one class, one line each (empty when fine), for the engine to report against the case file.
// h_max (m): the longest element of this class; the penalty form is "too soft" when G <= (2/3) f o_p with
// o_p = 2 h f / p_j, which is worst for the longest edge (ignored, pass 0, for the k_n/k_s form).
// sigma_c (Pa, >= 0): the largest compression expected on the joints; shear energy exactness needs
// G_II > (2/3) f_s s_p with f_s = c + sigma_c tan(phi). Pass 0 to check at zero normal stress only.
std::vector<std::string> check(const CohesiveProps& props, double h_max, double sigma_c = 0.0);

// The law constants of an element of length h (m) of this class (props must pass check()).
JointLaw make_law(const CohesiveProps& props, double h);

}  // namespace fdem::fracture
