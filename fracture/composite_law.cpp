// fracture/composite_law.cpp: the "composite" joint law ([PDEM] §2, Fig. 4; cap of [LR97]); formulas in the header.
// DATA LAYOUT: none (pure scalar functions; CohesiveSystem keeps one CompositeHistory per point of a composite
// element).
#include "fracture/composite_law.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "fracture/properties.hpp"
#include "fracture/value_checks.hpp"

namespace fdem::fracture {

namespace {
constexpr double kPi = 3.14159265358979323846;

// Secant normal stiffness in tension at damage D (Pa/m): f_t (1 - D) / (o_p + D (o_u - o_p)); 0 when broken.
double tension_secant(const CompositeLaw& L, double D) {
    if (D >= 1.0) return 0.0;
    return L.f_t * (1.0 - D) / (L.o_peak + D * (L.o_ult - L.o_peak));
}

// Secant normal stiffness in compression at compressive damage D_c (Pa/m): k_n at D_c = 0, 0 at D_c = 1.
double compression_secant(const CompositeLaw& L, double Dc) {
    if (Dc >= 1.0) return 0.0;
    return L.f_m * (1.0 - Dc) / (L.c_peak + Dc * (L.c_ult - L.c_peak));
}

// Mohr-Coulomb strength at damage D under the compression sigma_n (Pa, compression positive), floored at 0:
// tau_max = c_0 (1 - D) + sigma_n tan(theta(D)) ([PDEM] §2: tau_0 = c_0 + tan(theta_0) sigma, tau_res with c_res = 0).
double unfloored_strength(const CompositeLaw& L, double D, double sigma_n) {
    return L.cohesion * (1.0 - D) + sigma_n * (L.tan0 + D * (L.tan_res - L.tan0));
}

struct ShearStep {
    double tau;     // Pa, after the return
    double dkappa;  // plastic slip magnitude of this return, m (>= 0)
};

// Closed-form return of the elastic-plastic shear with linear cohesion softening (header). D is raised in place.
ShearStep shear_return(const CompositeLaw& L, double tau_trial, double sigma_n, double& D) {
    const double a = std::abs(tau_trial);
    const double sgn = tau_trial < 0.0 ? -1.0 : 1.0;
    const double t0 = unfloored_strength(L, D, sigma_n);
    if (a <= std::max(t0, 0.0)) return {tau_trial, 0.0};
    if (D >= 1.0) {  // residual: perfectly plastic on tau_res
        const double dk = (a - std::max(t0, 0.0)) / L.k_s;
        return {sgn * (a - L.k_s * dk), dk};
    }
    // Softening modulus of tau_max in the plastic slip (Pa/m): d tau_max / d kappa = -h.
    const double h = (L.cohesion - sigma_n * (L.tan_res - L.tan0)) / L.slip_ult;
    if (t0 > 0.0) {
        const double dk = (a - t0) / (L.k_s - h);
        const double D_new = D + dk / L.slip_ult;
        const double t_new = t0 - h * dk;
        if (D_new < 1.0 && t_new >= 0.0) {
            D = D_new;
            return {sgn * t_new, dk};
        }
        if (D_new >= 1.0) {  // the cohesion runs out within this return: the rest slides on tau_res
            D = 1.0;
            const double t_res = std::max(unfloored_strength(L, 1.0, sigma_n), 0.0);
            const double dk1 = (a - t_res) / L.k_s;
            return {sgn * t_res, dk1};
        }
    }
    // No strength left under this tension (c(D) + sigma_n tan(theta) <= 0): the slip is plastic, the cohesion softens.
    const double dk = a / L.k_s;
    D = std::min(1.0, D + dk / L.slip_ult);
    return {0.0, dk};
}

}  // namespace

CompositeLaw make_composite_law(double k_n, double k_s, double f_t, double G_I, double c_0, double theta0_deg,
                                double theta_res_deg, double G_II, double f_m, double G_c, double C_s) {
    CompositeLaw L{};
    L.k_n = k_n;
    L.k_s = k_s;
    L.f_t = f_t;
    L.o_peak = f_t / k_n;
    L.o_ult = 2.0 * G_I / f_t;  // area f_t o_u / 2 = G_I
    L.cohesion = c_0;
    L.tan0 = std::tan(theta0_deg * kPi / 180.0);
    L.tan_res = std::tan(theta_res_deg * kPi / 180.0);
    L.slip_ult = 2.0 * G_II / c_0;  // int_0^kappa_u c_0 (1 - kappa / kappa_u) d kappa = G_II
    L.f_m = f_m > 0.0 ? f_m : 0.0;
    L.c_peak = L.f_m > 0.0 ? L.f_m / k_n : 0.0;
    L.c_ult = L.f_m > 0.0 ? 2.0 * G_c / L.f_m : 0.0;  // area f_m u_u / 2 = G_c
    L.C_s = L.f_m > 0.0 ? C_s : 0.0;
    return L;
}

PointResponse evaluate_composite(const CompositeLaw& L, double o, double s, CompositeHistory& h) {
    const CompositeHistory old = h;
    double D = h.damage, Dc = h.crush;
    double dI = h.damage_I;

    // Normal stress at the damage reached so far (tension may raise D first).
    double sigma;
    if (o > 0.0) {
        const double Dt = (o - L.o_peak) / (L.o_ult - L.o_peak);
        if (Dt > D) {
            const double D_new = Dt < 1.0 ? Dt : 1.0;
            dI += D_new - D;
            D = D_new;
        }
        sigma = tension_secant(L, D) * o;
    } else if (L.f_m > 0.0) {
        sigma = compression_secant(L, Dc) * o;
    } else {
        sigma = L.k_n * o;
    }

    // Shear: elastic trial from the plastic slip, closed-form return.
    const double D_before_shear = D;
    const double tau_trial = L.k_s * (s - h.plastic_slip);
    const double sgn = tau_trial < 0.0 ? -1.0 : 1.0;
    ShearStep st = shear_return(L, tau_trial, -sigma, D);
    double tau = st.tau;
    double dkappa = st.dkappa;

    // Cap: compressive damage from the equivalent closure u_c = sqrt(o^2 + C_s (tau / k_n)^2) ([LR97] cap, C_nn = 1).
    if (o < 0.0 && L.f_m > 0.0) {
        const double t = tau / L.k_n;
        const double u_c = std::sqrt(o * o + L.C_s * t * t);
        const double Dct = (u_c - L.c_peak) / (L.c_ult - L.c_peak);
        if (Dct > Dc) {
            Dc = Dct < 1.0 ? Dct : 1.0;
            sigma = compression_secant(L, Dc) * o;
            // Lower compression, lower friction: return again so that |tau| <= tau_max(sigma) at the end.
            const ShearStep st2 = shear_return(L, tau, -sigma, D);
            tau = st2.tau;
            dkappa += st2.dkappa;
        }
    }
    // An open joint whose D grew by slip unloads towards the origin along the new secant.
    if (o > 0.0 && D > D_before_shear) sigma = tension_secant(L, D) * o;

    h.damage = D;
    h.plastic_slip += sgn * dkappa;
    h.crush = Dc;
    h.damage_I = dI;
    h.damage_II = old.damage_II + (D - D_before_shear);
    h.o = o;
    h.s = s;
    h.sigma = sigma;
    h.tau = tau;

    PointResponse r{};
    r.sigma = sigma;
    r.tau = tau;
    r.damage_I = h.damage_I;
    r.damage_II = h.damage_II;
    const double inv_ks = 1.0 / L.k_s;
    r.energy = 0.5 * sigma * o + 0.5 * tau * tau * inv_ks;
    const double E_old = 0.5 * old.sigma * old.o + 0.5 * old.tau * old.tau * inv_ks;
    const double work = 0.5 * (old.sigma + sigma) * (o - old.o) + 0.5 * (old.tau + tau) * (s - old.s);
    const double total = work - (r.energy - E_old);
    // Friction part of the plastic slip's work: sigma_n tan(theta) d kappa at the step's mean damage, compression only.
    const double sigma_n = -sigma;
    const double D_mid = 0.5 * (old.damage + D);
    r.friction_dissipated = sigma_n > 0.0 ? sigma_n * (L.tan0 + D_mid * (L.tan_res - L.tan0)) * dkappa : 0.0;
    r.dissipated = total - r.friction_dissipated;
    r.history = PointHistory{D, 0.0, 0.0, 0.0, 0.0};
    return r;
}

// ---- properties (declared in properties.hpp, "law = composite" block) ----

std::vector<std::string> check_composite(const CohesiveProps& p, double h_max) {
    std::vector<std::string> out;
    need_positive(out, "tensile strength f_t", "Pa", p.tensile_strength);
    need_positive(out, "cohesion c_0", "Pa", p.cohesion);
    need_angle(out, "friction angle theta_0", p.friction_deg);
    need_angle(out, "residual friction angle theta_res", p.residual_friction_deg);
    need_positive(out, "mode I fracture energy G_I", "J/m^2", p.G_I);
    need_positive(out, "mode II fracture energy G_II", "J/m^2", p.G_II);
    if (p.keep_friction)
        out.push_back("shear_softening applies to the [K25] law only: the composite law always keeps the friction");
    const bool has_fm = !std::isnan(p.compressive_strength), has_gc = !std::isnan(p.compressive_energy),
               has_cs = !std::isnan(p.cap_shear_factor);
    if (has_fm || has_gc || has_cs) {  // the cap: all three or none
        need_positive(out, "compressive strength f_m (cap)", "Pa", p.compressive_strength);
        need_positive(out, "compressive fracture energy G_c (cap)", "J/m^2", p.compressive_energy);
        need_positive(out, "cap shear factor C_s", "-", p.cap_shear_factor);
    }
    const bool has_penalty = !std::isnan(p.penalty), has_kn = !std::isnan(p.k_n), has_ks = !std::isnan(p.k_s);
    if (has_penalty && (has_kn || has_ks)) {
        out.push_back("give either the joint penalty p_j (Pa) or the interface stiffnesses k_n, k_s (Pa/m), not both");
    } else if (has_penalty) {
        need_positive(out, "joint penalty p_j", "Pa", p.penalty);
        if (!(h_max > 0.0) || !std::isfinite(h_max))
            out.push_back("element length h = " + fmt(h_max) + " m is not physical: it must be finite and > 0");
    } else if (has_kn || has_ks) {
        need_positive(out, "normal stiffness k_n", "Pa/m", p.k_n);
        need_positive(out, "shear stiffness k_s", "Pa/m", p.k_s);
    } else {
        out.push_back(
            "stiffness is missing: give the joint penalty p_j (Pa) or the interface stiffnesses k_n, k_s (Pa/m)");
    }
    if (!out.empty()) return out;
    // Bilinear branches need their softening to start after the peak (no snap-back at a point): the elastic work at the
    // peak, f^2 / (2 k), below G. Worst for the softest element (the longest, with a penalty).
    const double K_n = has_penalty ? p.penalty / h_max : p.k_n, K_s = has_penalty ? p.penalty / h_max : p.k_s;
    const char* where = has_penalty ? " (k = p_j / h at the longest element)" : "";
    const double f_t = p.tensile_strength, c = p.cohesion;
    if (p.G_I <= f_t * f_t / (2.0 * K_n))
        out.push_back("joint too soft for its mode I fracture energy: G_I = " + fmt(p.G_I) +
                      " J/m^2 <= f_t^2 / (2 k_n) = " + fmt(f_t * f_t / (2.0 * K_n)) + " J/m^2" + where);
    if (p.G_II <= c * c / (2.0 * K_s))
        out.push_back("joint too soft for its mode II fracture energy: G_II = " + fmt(p.G_II) +
                      " J/m^2 <= c_0^2 / (2 k_s) = " + fmt(c * c / (2.0 * K_s)) + " J/m^2" + where);
    if (has_fm && p.compressive_energy <= p.compressive_strength * p.compressive_strength / (2.0 * K_n))
        out.push_back("joint too soft for its compressive fracture energy: G_c = " + fmt(p.compressive_energy) +
                      " J/m^2 <= f_m^2 / (2 k_n) = " +
                      fmt(p.compressive_strength * p.compressive_strength / (2.0 * K_n)) + " J/m^2" + where);
    return out;
}

CompositeLaw make_composite_law(const CohesiveProps& p, double h) {
    const bool has_penalty = !std::isnan(p.penalty);
    const double K_n = has_penalty ? p.penalty / h : p.k_n, K_s = has_penalty ? p.penalty / h : p.k_s;
    const bool cap = !std::isnan(p.compressive_strength);
    return make_composite_law(K_n, K_s, p.tensile_strength, p.G_I, p.cohesion, p.friction_deg, p.residual_friction_deg,
                              p.G_II, cap ? p.compressive_strength : 0.0, cap ? p.compressive_energy : 0.0,
                              cap ? p.cap_shear_factor : 0.0);
}

}  // namespace fdem::fracture
