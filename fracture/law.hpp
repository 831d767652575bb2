// fracture/law.hpp: the cohesive traction-separation law of fracture/README.md as small pure functions.
//
// One integration point of a cohesive element sees an opening `o` (m, positive when the faces separate,
// negative when they overlap) and a slip `s` (m, either sign). Its physical history is the damage `D` in [0, 1],
// the largest value ever reached (irreversible); PointHistory also keeps two numbers of the previous evaluation for
// the energy bookkeeping. Everything here is per unit crack area: stresses in Pa, energies in J/m^2. Tension is
// positive.
//
// Continuous law ([K25] Eqs. 6-13, [MAW99], [M04] ch. 7):
//   sigma(o, D) = K_n o                                  o < 0   (undamaged linear penalty; K_n o == 2 (o/o_p) f_t)
//               = (2 x - x^2) z(D) f_t,  x = o/o_p       0 <= o <= o_p
//               = z(D) f_t                               o > o_p
//   tau(s, D)   = sign(s) (2 y - y^2) z(D) f_s,  y = |s|/s_p  for |s| <= s_p,  sign(s) z(D) f_s beyond,
//   f_s = c + max(0, -sigma) tan(phi),  o_p = 2 f_t / K_n,  s_p = 2 f_s / K_s,
//   D_I = max(0, (o - o_p)/o_t),  D_II = max(0, (|s| - s_p)/s_t),  D = min(1, sqrt(D_I^2 + D_II^2)).
// K_n, K_s (Pa/m) are the initial slopes of the law: p_j / h for a penalty joint (then o_p = 2 h f_t / p_j as in
// fracture/README.md), or the measured k_n, k_s of a zero-thickness interface. Writing the compressive branch as K_n o
// instead of 2 (o/o_p) f_t is the same number and stays defined when it matters least (f_t tiny).
// The shear curve depends on f_s and so on the current compression: like friction, that coupling is not a
// potential, so a cycle of normal stress at fixed slip can move energy between the bookkeeping terms; it is bounded
// by the pre-peak shear energy (2/3) f_s s_p per cycle and vanishes at constant compression. A closed loop below the
// peak takes K_s^2 s^3 / 12 (1/f_s1 - 1/f_s2) (tests/fracture/test_law.cpp); run backwards it gives that out, and
// thousands of joints oscillating under light damping can pump a run up until it fails the energy check
// (`numerics.energy_audit` names the joints: fdem/README.md 'Energy').
//
// Energy-exact ranges: the whole area under sigma(o) in pure mode I is (2/3) f_t o_p + kappa f_t o_t with
// kappa = int_0^1 z(D) dD, so o_t = (G_I - (2/3) f_t o_p) / (kappa f_t) makes it exactly G_I (likewise s_t, G_II).
//
// Option keep_friction (case key shear_softening = "cohesion"; off by default, then the law above is unchanged):
// only the cohesion softens, the frictional part f_f = max(0, -sigma) tan(phi) of f_s is kept, as in the
// Coulomb-slip interfaces with softening cohesion of Lourenco & Rots (1997) [LR97] and of 3DEC's joints. A Coulomb
// slider of stiffness K_s and strength f_f (plastic slip s_f, one more history number) acts in parallel with weight
// 1 - z(D):
//   tau = sign(s) z(D) t_s0(s) + (1 - z(D)) tau_f,   tau_f = clamp(K_s (s - s_f), -f_f, f_f),
// so tau = t_s0 before any damage (the same pre-peak curve) and tends to +-f_f, not 0, as D -> 1 under monotonic
// slip: f_f + z(D) c past the peak. The softening range then belongs to the cohesion,
// s_t = (G_II - (2/3) c s_p) / (kappa c), so the area of the softening branch above the friction line is G_II.
// Energies: recoverable E = z E_0 + (1 - z) tau_f^2 / (2 K_s) (+ the compressive part); friction dissipation
// (1 - z) f_f |ds_f| (PointResponse::friction_dissipated); damage dissipation -dz (E_0 - tau_f^2 / (2 K_s)), which
// is >= 0 because D only grows past s_p, where E_0 >= (4/3) f_s^2 / K_s. Work = dE + both dissipations (tested).
//
// Option compressive cap (case key compressive_strength = f_c, Pa; off by default, then the law above is unchanged):
// the compressive stress is bounded by f_c, as the cap of the interface models of Lourenco & Rots (1997) [LR97] and
// the compressive strength the DEM reproductions give the mortar joints (cases/README.md §B), here perfectly plastic (no
// compressive softening or hardening: no compressive fracture energy is given). Past f_c the joint closes plastically:
// a closure o_c <= 0 (history) is kept, every branch of the law then reads the elastic separation o - o_c, so an
// unloaded crushed joint is open by -o_c at o = 0. Crushing dissipates f_c |d o_c|, booked with the damage
// dissipation (PointResponse::dissipated). When such an element breaks, contact sees the whole overlap -o, the plastic
// part included (fracture/README.md, "Compressive cap").
#pragma once

#include <cmath>

namespace fdem::fracture {

// Softening function z(D) of [K25] Eq. 10 with its published constants a = 0.63, b = 1.8, c = 6.0:
//   z(D) = [1 - (a+b-1)/(a+b) exp(D (a + c b) / ((a+b)(1-a-b)))] [a (1-D) + b (1-D)^c],  z(0) = 1, z(1) = 0.
double softening(double D);

// kappa = int_0^1 z(D) dD (dimensionless), about 0.38631; computed once by composite Gauss-Legendre quadrature
// to machine precision so that the energy-exact ranges below are exact to rounding, not to 5 digits.
double softening_integral();

// Elastic limit (m): opening or slip at peak stress, o_p = 2 f / K (fracture/README.md; K in Pa/m, f in Pa).
inline double opening_at_peak(double strength, double stiffness) { return 2.0 * strength / stiffness; }

// Energy-exact softening range (m): o_t = (G - (2/3) f o_p) / (kappa f). G in J/m^2, f in Pa, o_p in m.
// Non-positive when the joint is too compliant for its fracture energy (an input error, see check()).
double softening_range(double fracture_energy, double strength, double elastic_limit);

// Pre-peak shape (2 x - x^2) of the traction for x = o/o_p in [0, 1], and its integral x^2 - x^3/3 (times f o_p).
inline double prepeak_shape(double x) { return x * (2.0 - x); }
inline double prepeak_energy_shape(double x) { return x * x * (1.0 - x / 3.0); }

// Undamaged (z = 1) tensile/shear traction magnitude (Pa) for a separation u >= 0 with limit u_p and strength f.
inline double undamaged_traction(double u, double u_p, double f) {
  return u >= u_p ? f : prepeak_shape(u / u_p) * f;
}
// Undamaged energy (J/m^2) stored along that curve from 0 to u (the recoverable energy at D = 0; scale by z(D)).
inline double undamaged_energy(double u, double u_p, double f) {
  return u >= u_p ? f * (u_p * (2.0 / 3.0) + (u - u_p)) : prepeak_energy_shape(u / u_p) * f * u_p;
}

// Shear strength (Pa), Mohr-Coulomb with tension positive: f_s = c + max(0, -sigma) tan(phi).
inline double shear_strength(double sigma, double cohesion, double tan_friction) {
  return cohesion + (sigma < 0.0 ? -sigma * tan_friction : 0.0);
}

// Whether the traction (sigma, tau) (Pa, tension positive) has reached the law's peak surface: sigma >= f_t or
// |tau| >= f_s(sigma). Where the intrinsic law starts to soften, and where an extrinsic element is inserted.
inline bool reaches_peak_surface(double sigma, double tau, double tensile_strength, double cohesion, double tan_friction) {
  return sigma >= tensile_strength || std::abs(tau) >= shear_strength(sigma, cohesion, tan_friction);
}

// Whether a stress (xx, yy, xy; Pa) is far from the peak surface on every plane: p + R < f_t and R < c, with p the
// mean normal stress and R the radius of Mohr's circle, so that sigma_n <= p + R < f_t and |tau| <= R < c <= f_s on
// any plane (tan(phi) >= 0; pass c = -inf otherwise, and the answer is false). p + R and R are convex in the stress,
// so the mean of two far stresses is far too. The slack (1e-9 of the stress's size) covers the rounding of this test
// and of the traction that reaches_peak_surface would be given: for an edge whose triangles are both far,
// reaches_peak_surface on their mean stress is false (Interactions::insert_cracks; tests/fracture/test_law.cpp).
// False for a NaN stress.
inline bool far_from_peak_surface(const double* s, double tensile_strength, double cohesion) {
  const double p = 0.5 * (s[0] + s[1]), d = 0.5 * (s[0] - s[1]);
  const double R2 = d * d + s[2] * s[2];
  const double slack = 1e-9 * (std::abs(s[0]) + std::abs(s[1]) + std::abs(s[2]));
  const double ht = tensile_strength - p - slack, hs = cohesion - slack;
  return ht > 0.0 && hs > 0.0 && R2 < ht * ht && R2 < hs * hs;
}

// Constants of one element's law (all derived once from CohesiveProps and the edge length by make_joint_law;
// reciprocals are stored because the kernel runs three points per element per step and divisions dominate it).
struct JointLaw {
  double normal_stiffness;     // K_n, Pa/m: initial slope of sigma(o), also the compressive penalty
  double shear_stiffness;      // K_s, Pa/m: initial slope of tau(s)
  double tensile_strength;     // f_t, Pa
  double opening_peak;         // o_p = 2 f_t / K_n, m
  double opening_range;        // o_t, m (energy-exact, > 0)
  double cohesion;             // c, Pa
  double tan_friction;         // tan(phi), -
  double shear_energy;         // G_II, J/m^2
  double slip_peak0;           // s_p at zero normal stress, 2 c / K_s, m
  double slip_range0;          // s_t at zero normal stress, m
  double inv_opening_peak;     // 1/o_p, 1/m
  double inv_opening_range;    // 1/o_t, 1/m
  double inv_shear_stiffness;  // 1/K_s, m/Pa
  double inv_slip_peak0;       // 1/s_p at zero normal stress, 1/m
  double inv_slip_range0;      // 1/s_t at zero normal stress, 1/m
  bool keep_friction = false;  // only the cohesion softens (see the header); set by make_law from CohesiveProps
  double compressive_strength = 0.0;  // f_c, Pa: compressive cap (see the header); 0 = none; set by make_law
  bool mohr_coulomb = false;  // law = "mohr_coulomb": evaluate_point defers to fracture/mc_law.hpp
};

// Law constants from stiffnesses K_n, K_s (Pa/m), strengths f_t, c (Pa), tan(phi) and fracture energies (J/m^2).
JointLaw make_joint_law(double K_n, double K_s, double f_t, double G_I, double cohesion, double tan_friction,
                        double G_II);

// History of one integration point. Only `damage` is physics; the other two remember the previous evaluation so that
// the dissipation of a damage increment can be integrated at second order along the step (see evaluate_point).
struct PointHistory {
  double damage;            // D in [0, 1], the largest value reached (irreversible)
  double trial;             // signed trial damage at the last evaluation (< 0 below both thresholds), -
  double undamaged_energy;  // E_0 = e_n0 + e_s0 at the last evaluation (minus the slider's energy with keep_friction), J/m^2
  double slip_friction;     // s_f, plastic slip of the friction slider (keep_friction only; else 0), m
  double closure;           // o_c <= 0, plastic closure of the compressive cap (compressive_strength only; else 0), m
};

// History of an untouched point (o = s = 0): the signed trial damage there is max(-o_p/o_t, -s_p/s_t).
PointHistory initial_history(const JointLaw& law);

// Result of evaluating one integration point.
struct PointResponse {
  double sigma;          // normal stress, Pa (tension positive)
  double tau;            // shear stress, Pa (same sign as the slip)
  double damage_I;       // D_I at this state (>= 0)
  double damage_II;      // D_II at this state (>= 0)
  double energy;         // recoverable elastic energy at the new state, J/m^2
  double dissipated;     // energy dissipated by the damage increment (and the cap's crushing) of this evaluation, J/m^2 (>= 0)
  double friction_dissipated;  // keep_friction: work of the friction slider's slip in this evaluation, J/m^2 (>= 0)
  PointHistory history;  // new history; history.damage >= the old damage
};

// keep_friction: softening range of the cohesion alone, (G_II - (2/3) c s_p) / (kappa c), floored like the one below.
double cohesion_softening_range(const JointLaw& law, double slip_peak);

// Softening range in shear for the current shear strength f_s (Pa) and slip at peak s_p (m). Compression raises
// f_s and s_p = 2 f_s / K_s and can push (2/3) f_s s_p up to G_II; the range is then floored at 1e-3 s_p (the joint
// breaks just after its peak and dissipates (2/3) f_s s_p > G_II: the least wrong answer; check() can warn for an
// expected compression).
double shear_softening_range(const JointLaw& law, double shear_strength_now, double slip_peak);

// The law at one point: (opening o (m), slip s (m), history) -> stresses, energies, new history.
// Dissipation. The recoverable energy is E = z(D) E_0(o, s) (+ the compressive part, undamaged), so at fixed
// separation a damage increment releases dE = -z'(D) E_0 dD. Along a step from the previous evaluation to this one
// the code integrates it with the trapezoid rule between the state where D_old was reached (E_0 interpolated
// linearly in the trial damage between the two evaluations) and the new state:
//   dissipated = (z(D_old) - z(D_new)) (E_0,a + E_0,new) / 2.
// For a monotonic mode I path the sum is (2/3) f_t o_p + kappa f_t o_t = G_I to second order in the increment
// (tested), so the engine's energy balance closes even when a joint breaks in a few tens of steps.
// law = "mohr_coulomb" (fracture/mc_law.hpp): the point law of the M-DEM spring layers.
PointResponse evaluate_mc_point(const JointLaw& L, double o, double s, const PointHistory& old);

inline PointResponse evaluate_point(const JointLaw& L, double o_geo, double s, const PointHistory& old) {
  if (L.mohr_coulomb) return evaluate_mc_point(L, o_geo, s, old);
  PointResponse r;
  // Elastic normal separation: the geometric one less the cap's plastic closure (0 without a cap: o == o_geo).
  double closure = old.closure;
  double o = o_geo - closure;
  double crushing = 0.0;  // J/m^2 dissipated by the cap in this evaluation
  // Compression is an undamaged linear penalty: crack faces in contact carry pressure whatever D is, and it raises
  // the shear strength (Mohr-Coulomb), hence s_p and s_t.
  double sigma_c = 0.0, f_s = L.cohesion, s_p = L.slip_peak0, inv_s_p = L.inv_slip_peak0;
  if (o < 0.0) {
    sigma_c = L.normal_stiffness * o;
    if (L.compressive_strength > 0.0 && sigma_c < -L.compressive_strength) {
      // Crushing: sigma stays at -f_c and the closure takes the rest of the compression (perfectly plastic).
      const double f_c = L.compressive_strength;
      const double new_closure = o_geo + f_c / L.normal_stiffness;
      crushing = f_c * (closure - new_closure);
      closure = new_closure;
      o = o_geo - closure;
      sigma_c = -f_c;
    }
    f_s = shear_strength(sigma_c, L.cohesion, L.tan_friction);
    s_p = 2.0 * f_s * L.inv_shear_stiffness;
    inv_s_p = 1.0 / s_p;
  }
  const double a_s = s < 0.0 ? -s : s;
  const double o_p = L.opening_peak;

  // Damage components (signed: negative below the elastic limit), D_trial = |(D_I, D_II)^+|.
  const double dI = (o - o_p) * L.inv_opening_range;
  // Below the limit only the sign and rough size of dII matter (onset interpolation), so the zero-compression range
  // serves there and spares the compressed joints of a precompressed wall a division per point.
  // (keep_friction: the range belongs to the cohesion alone, see the header.)
  const double dII = (o < 0.0 && a_s > s_p)
                         ? (a_s - s_p) / (L.keep_friction ? cohesion_softening_range(L, s_p)
                                                          : shear_softening_range(L, f_s, s_p))
                         : (a_s - s_p) * L.inv_slip_range0;
  r.damage_I = dI > 0.0 ? dI : 0.0;
  r.damage_II = dII > 0.0 ? dII : 0.0;
  double trial;
  if (dI > 0.0 || dII > 0.0) {
    trial = std::sqrt(r.damage_I * r.damage_I + r.damage_II * r.damage_II);
  } else {
    trial = dI > dII ? dI : dII;  // distance to the nearer threshold, continuous with the branch above
  }
  const double D_old = old.damage;
  const double D = trial >= 1.0 ? 1.0 : (trial > D_old ? trial : D_old);

  // Undamaged tensile and shear curves and their energies; z(D) scales both (fracture/README.md).
  double t_n0 = 0.0, e_n0 = 0.0;
  if (o > 0.0) {
    if (o >= o_p) {
      t_n0 = L.tensile_strength;
      e_n0 = L.tensile_strength * (o_p * (2.0 / 3.0) + (o - o_p));
    } else {
      const double x = o * L.inv_opening_peak;
      t_n0 = prepeak_shape(x) * L.tensile_strength;
      e_n0 = prepeak_energy_shape(x) * L.tensile_strength * o_p;
    }
  }
  double t_s0, e_s0;
  if (a_s >= s_p) {
    t_s0 = f_s;
    e_s0 = f_s * (s_p * (2.0 / 3.0) + (a_s - s_p));
  } else {
    const double y = a_s * inv_s_p;
    t_s0 = prepeak_shape(y) * f_s;
    e_s0 = prepeak_energy_shape(y) * f_s * s_p;
  }
  double E0 = e_n0 + e_s0;
  const double z = D > 0.0 ? softening(D) : 1.0;
  r.sigma = o < 0.0 ? sigma_c : z * t_n0;
  r.tau = (s < 0.0 ? -z : z) * t_s0;
  // Recoverable energy: the work given back when unloading to o = s = 0 at frozen D along the same curves.
  r.energy = z * E0 + (o < 0.0 ? 0.5 * sigma_c * o : 0.0);
  r.dissipated = 0.0;
  r.friction_dissipated = 0.0;
  double s_f = 0.0;
  if (L.keep_friction) {
    // Coulomb slider in parallel, weight 1 - z: strength f_f = f_s - c under compression, none in tension.
    const double f_f = o < 0.0 ? f_s - L.cohesion : 0.0;
    s_f = old.slip_friction;
    double tau_f = L.shear_stiffness * (s - s_f);
    if (tau_f > f_f) {
      tau_f = f_f;
      s_f = s - f_f * L.inv_shear_stiffness;
    } else if (tau_f < -f_f) {
      tau_f = -f_f;
      s_f = s + f_f * L.inv_shear_stiffness;
    }
    const double e_f = 0.5 * tau_f * tau_f * L.inv_shear_stiffness;
    r.tau += (1.0 - z) * tau_f;
    r.energy += (1.0 - z) * e_f;
    // Weight 1 - z at the middle of the step (trapezoid in z): second order like the damage dissipation.
    const double ds_f = s_f - old.slip_friction;
    const double z_mid = D > D_old ? 0.5 * (z + (D_old > 0.0 ? softening(D_old) : 1.0)) : z;
    r.friction_dissipated = (1.0 - z_mid) * f_f * (ds_f < 0.0 ? -ds_f : ds_f);
    E0 -= e_f;  // damage releases z's share of E_0 less the slider's energy, which (1 - z) takes over
  }
  if (D > D_old) {
    double phi = 0.0;  // fraction of the step at which the trial damage passed D_old
    if (trial > old.trial) phi = (D_old - old.trial) / (trial - old.trial);
    phi = phi < 0.0 ? 0.0 : (phi > 1.0 ? 1.0 : phi);
    const double E0_a = old.undamaged_energy + phi * (E0 - old.undamaged_energy);
    r.dissipated = (softening(D_old) - z) * 0.5 * (E0_a + E0);
  }
  r.dissipated += crushing;
  r.history = PointHistory{D, trial, E0, s_f, closure};
  return r;
}

}  // namespace fdem::fracture
