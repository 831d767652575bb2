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
  bool penalty_auto = false;             // p_j = auto_penalty(props, h_max) (resolve before check/make_law)
  double penalty_ref = unset;            // Pa (> 0): the auto penalty where the mesh allows it
  double k_n = unset;                    // normal stiffness of a zero-thickness interface, Pa/m (> 0)
  double k_s = unset;                    // shear stiffness of a zero-thickness interface, Pa/m (> 0)
  bool keep_friction = false;            // only the cohesion softens, friction is kept (law.hpp; [LR97])
  bool mohr_coulomb = false;             // law = "mohr_coulomb" (mc_law.hpp): no softening, G_I and G_II unused
  double compressive_strength = unset;   // f_c, Pa (> 0): compressive cap (law.hpp); unset = no cap
  // law = "composite" (fracture/composite_law.hpp; [PDEM] §2): compressive_strength is then the cap's f_m.
  bool composite = false;                // the composite law instead of the [K25] law
  double compressive_energy = unset;     // G_c, J/m^2 (> 0): compressive fracture energy of the cap (composite only)
  double cap_shear_factor = unset;       // C_s, - (> 0): cap sigma^2 + C_s tau^2 = f_m^2 (composite only)
  bool extrinsic = false;                // inserted when the traction reaches the strength (cohesive_system.hpp)
};

// Problems with one class, one line each (empty when fine), for the engine to report against the case file.
// h_max (m): the longest element of this class; the penalty form is "too soft" when G <= (2/3) f o_p with
// o_p = 2 h f / p_j, which is worst for the longest edge (ignored, pass 0, for the k_n/k_s form).
// sigma_c (Pa, >= 0): the largest compression expected on the joints; shear energy exactness needs
// G_II > (2/3) f_s s_p with f_s = c + sigma_c tan(phi). Pass 0 to check at zero normal stress only.
std::vector<std::string> check(const CohesiveProps& props, double h_max, double sigma_c = 0.0);

// penalty = "auto" (fracture/README.md, "Mesh-aware penalty"): the joint penalty of a class whose longest element
// is h_max (m), p_j = max(p_ref, kAutoPenaltyMargin * p_G) with p_G = 4 h_max max(f_t^2 / G_I, c^2 / G_II) / 3 (Pa),
// the penalty at which the pre-peak work (2/3) f o_p of the longest element equals G (o_p = 2 h f / p_j, law.hpp). With the margin 1.5 the pre-peak work is at most 2/3 of G, a third is left for the softening branch.
// p_ref: props.penalty_ref (Pa), which the engine sets to 10 E when the case gives none.
inline constexpr double kAutoPenaltyMargin = 1.5;
double auto_penalty(const CohesiveProps& props, double h_max);

// The law constants of an element of length h (m) of this class (props must pass check()). For a composite class
// only the stiffnesses are set (stable_dt reads them); the law itself is make_composite_law below.
JointLaw make_law(const CohesiveProps& props, double h);

// law = "composite" (fracture/composite_law.hpp, implemented in composite_law.cpp): the problems of a composite class
// (check() forwards to it) and the constants of one of its elements of length h (m).
struct CompositeLaw;
std::vector<std::string> check_composite(const CohesiveProps& props, double h_max);
CompositeLaw make_composite_law(const CohesiveProps& props, double h);

}  // namespace fdem::fracture
