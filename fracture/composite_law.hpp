// fracture/composite_law.hpp: the "composite" joint law (case key law = "composite"), beside the [K25] law of law.hpp.
//
// Source: the contact law of the 3DEC models of Pulatsu et al., "Computational modelling of damage progression in
// unreinforced masonry walls via DEM" [PDEM] §2 and Figure 4 (its Table 1 holds the values of the mortared walls),
// with the compressive cap of Lourenco & Rots (1997) [LR97]. [PDEM] describes the law in words (Figure 4 is a
// drawing); the formulas below are this project's reading of that description, one line per statement of [PDEM] §2:
//   "bilinear stress-displacement behaviour in tension, shear and compression, considering the mode-I, mode-II and
//    compressive fracture energy"                                   -> linear rise, linear softening, areas G_I,
//                                                                      G_II, G_c
//   "a single damage parameter ... to couple tension and shear"     -> one D for f_t and c
//   "one-way coupling ... between shear and compression"            -> the shear stress enters the cap; crushing does
//                                                                      not damage the tension/shear bond
//   "unloading ... returns to the origin" after tension or compression failure -> secant (damage) unloading
//   "tau_0 = c_0 + tan(theta_0) sigma, tau_res = c_res + tan(theta_res) sigma" -> Mohr-Coulomb, c_res = 0
//   "no stiffness degradation ... for shear stiffness"              -> elastic-plastic shear, unloading with k_s
//   "the Cap Model proposed in [31]" (= [LR97])                     -> C_nn sigma^2 + C_ss tau^2 + C_n sigma = f_m^2
//                                                                      with C_nn = 1, C_n = 0, C_ss = C_s
//                                                                      ([LR97], cap f_3)
//
// One integration point sees an opening o (m, > 0 when the faces separate) and a slip s (m); tension positive; stresses
// in Pa, energies in J/m^2. Parameters (SI): k_n, k_s (Pa/m); f_t (Pa), G_I (J/m^2); c_0 (Pa), theta_0, theta_res
// (deg), G_II (J/m^2); f_m (Pa), G_c (J/m^2), C_s (-). The residual cohesion c_res is 0 ([PDEM] Table 1).
//
// Tension (o > 0). Envelope: sigma = k_n o up to f_t at o_p = f_t / k_n, then linear to 0 at o_u = 2 G_I / f_t, so the
// area under the envelope is f_t o_u / 2 = G_I. With the damage D (shared with shear, below) the envelope point is
//   o_D = o_p + D (o_u - o_p),  sigma_D = f_t (1 - D),  secant k_t(D) = sigma_D / o_D,
// and the joint answers sigma = k_t(D) o (unloading to the origin); opening past o_D raises D to (o - o_p)/(o_u - o_p).
//
// Shear. Elastic-plastic with plastic slip s_p: tau = k_s (s - s_p), |tau| <= tau_max with
//   tau_max = max(0, c(D) + sigma_n tan(theta(D))),  c(D) = c_0 (1 - D),
//   tan(theta(D)) = tan(theta_0) + D (tan(theta_res) - tan(theta_0)),  sigma_n = -sigma (compression positive),
// which goes from tau_0 = c_0 + sigma_n tan(theta_0) at D = 0 to tau_res = sigma_n tan(theta_res) at D = 1.
// Plastic slip |d s_p| = d kappa raises the damage by d kappa / kappa_u with kappa_u = 2 G_II / c_0: the cohesion falls
// linearly with the plastic slip and the work of the cohesive part, int c d kappa = c_0 kappa_u / 2, is G_II (the
// friction part sigma_n tan(theta) d kappa is friction, PointResponse::friction_dissipated). The shear stiffness is
// never degraded: unloading follows k_s. The return is closed form (linear softening): with
// h = (c_0 - sigma_n (tan(theta_res) - tan(theta_0))) / kappa_u, d kappa = (|tau_trial| - tau_max(D)) / (k_s - h);
// check() requires k_s > c_0 / kappa_u (no snap-back at the point).
//
// One damage for tension and shear: D = max(D + d kappa / kappa_u, (o - o_p)/(o_u - o_p)) in [0, 1]. Opening past the
// envelope damages the cohesion; plastic slip damages the tensile strength and stiffness. D = 1 at the three points of
// an element breaks it (cohesive_system.hpp); contact then carries compression and residual friction.
//
// Compression (o < 0), optional cap (f_m > 0). The cap f_3 of [LR97] with C_nn = 1, C_n = 0, C_ss = C_s:
//   sigma^2 + C_s tau^2 = f_m^2.
// Equivalent closure u_c = sqrt(o^2 + C_s (tau / k_n)^2), i.e. k_n u_c = sqrt(sigma_el^2 + C_s tau^2) for the elastic
// compression sigma_el = k_n o: compressive damage starts exactly on the cap. Envelope in u_c: k_n u_c up to f_m at
// u_p = f_m / k_n, then linear to 0 at u_u = 2 G_c / f_m (area G_c in pure compression). Compressive damage D_c
// (irreversible) with envelope point u_D = u_p + D_c (u_u - u_p), secant k_c(D_c) = f_m (1 - D_c) / u_D; the normal
// stress is sigma = k_c(D_c) o (unloading to the origin). One-way coupling: the shear stress drives D_c through u_c;
// D_c lowers sigma and with it the friction, but not D. Without a cap sigma = k_n o.
// Order in one evaluation: tension or the compression at the old D_c, then the shear return, then D_c from u_c, then
// (if D_c grew) a second shear return against the lowered friction, so that |tau| <= tau_max holds for the final sigma.
//
// Energy. Recoverable E = sigma o / 2 + tau^2 / (2 k_s) (secant unloading in the normal direction, elastic in shear).
// Per evaluation the work is integrated by the trapezoid rule, W = (sigma_old + sigma)(o - o_old)/2 + (tau_old +
// tau)(s - s_old)/2, and the dissipation is W - (E - E_old) (exact on linear segments, second order in the increment
// across a kink), split into friction (sigma_n tan(theta) d kappa, sigma_n >= 0) and the rest (fracture and crushing).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "fracture/law.hpp"

namespace fdem::fracture {

// Constants of one element's composite law (from CohesiveProps by make_composite_law).
struct CompositeLaw {
    double k_n;       // normal stiffness, Pa/m
    double k_s;       // shear stiffness, Pa/m
    double f_t;       // tensile strength, Pa
    double o_peak;    // o_p = f_t / k_n, m
    double o_ult;     // o_u = 2 G_I / f_t, m
    double cohesion;  // c_0, Pa
    double tan0;      // tan(theta_0), -
    double tan_res;   // tan(theta_res), -
    double slip_ult;  // kappa_u = 2 G_II / c_0: plastic slip at which the cohesion is gone, m
    double f_m;       // compressive strength of the cap, Pa; 0 = no cap (linear compression)
    double c_peak;    // u_p = f_m / k_n, m
    double c_ult;     // u_u = 2 G_c / f_m, m
    double C_s;       // shear factor of the cap, -
};

// k_n, k_s in Pa/m; f_t, c_0, f_m in Pa; angles in degrees; G_I, G_II, G_c in J/m^2; C_s dimensionless.
// f_m = 0 (then G_c and C_s are ignored): no cap.
CompositeLaw make_composite_law(double k_n, double k_s, double f_t, double G_I, double c_0, double theta0_deg,
                                double theta_res_deg, double G_II, double f_m, double G_c, double C_s);

// History of one integration point.
struct CompositeHistory {
    double damage = 0.0;            // D in [0, 1], tension-shear damage (irreversible)
    double plastic_slip = 0.0;      // s_p, m
    double crush = 0.0;             // D_c in [0, 1], compressive damage (irreversible)
    double damage_I = 0.0;          // part of D raised by opening (for the mode of a break), -
    double damage_II = 0.0;         // part of D raised by plastic slip, -
    double o = 0.0, s = 0.0;        // opening and slip at the last evaluation, m
    double sigma = 0.0, tau = 0.0;  // stresses at the last evaluation, Pa
};

// The law at one point: (o, s) and the history -> stresses, energies; h is updated in place. The PointResponse's
// history carries only `damage` (= D, what CohesiveSystem reads for breaking and output); damage_I / damage_II are the
// parts of D raised by opening and by slip.
PointResponse evaluate_composite(const CompositeLaw& L, double o, double s, CompositeHistory& h);

}  // namespace fdem::fracture
