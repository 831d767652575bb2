// fdem/plasticity.cpp: the crushing model of fdem/plasticity.hpp (formulas and sources there).
#include "fdem/plasticity.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "fdem/case.hpp"
#include "fdem/common/errors.hpp"
#include "fdem/model.hpp"

namespace fdem {

void green_lagrange(const double* F, double* E) {
    // E = (F^T F - I) / 2
    E[0] = 0.5 * (F[0] * F[0] + F[2] * F[2] - 1.0);
    E[1] = 0.5 * (F[1] * F[1] + F[3] * F[3] - 1.0);
    E[2] = 0.5 * (F[0] * F[1] + F[2] * F[3]);
}

double crushing_strength(const CrushingParams& p, double kappa_u, double kappa) {
    return kappa >= kappa_u ? 0.0 : p.fc * (1.0 - kappa / kappa_u);
}

double crushing_dissipation_density(const CrushingParams& p, double kappa_u, double kappa) {
    // INT_0^kappa f_c (1 - k / kappa_u) dk, then f_c kappa_u / 2 = G_c / h once the strength is gone.
    const double k = std::min(kappa, kappa_u);
    return p.fc * (k - 0.5 * k * k / kappa_u);
}

double crushing_energy_density(const CrushingParams& p, const double* E, const double* Ep) {
    const double e0 = E[0] - Ep[0], e1 = E[1] - Ep[1], e2 = E[2] - Ep[2];
    const double tr = e0 + e1;
    return 0.5 * p.lambda * tr * tr + p.mu * (e0 * e0 + e1 * e1 + 2 * e2 * e2);
}

namespace {

void elastic_S(const CrushingParams& p, const double* E, const double* Ep, double* S) {
    const double e0 = E[0] - Ep[0], e1 = E[1] - Ep[1], e2 = E[2] - Ep[2];
    const double ltr = p.lambda * (e0 + e1);
    S[0] = ltr + 2 * p.mu * e0;
    S[1] = ltr + 2 * p.mu * e1;
    S[2] = 2 * p.mu * e2;
}

}  // namespace

bool crushing_update(const CrushingParams& p, double kappa_u, const double* E, double* Ep, double& kappa, double* S) {
    elastic_S(p, E, Ep, S);  // trial stress
    const double m = 0.5 * (S[0] + S[1]), h = 0.5 * (S[0] - S[1]);
    const double r = std::sqrt(h * h + S[2] * S[2]);
    const double s1t = m + r, s2t = m - r;  // principal trial stresses, s1t >= s2t
    const double fc0 = crushing_strength(p, kappa_u, kappa);
    const double f0 = -s2t - fc0;  // yield function f = -s2 - f_c(kappa)
    if (!(f0 > 0)) return false;
    // Principal directions: n1 = (c, s) at theta = atan2(2 S_xy, S_xx - S_yy) / 2, n2 = (-s, c).
    const double th = 0.5 * std::atan2(S[2], h);
    const double c = std::cos(th), s = std::sin(th);
    const double C22 = p.lambda + 2 * p.mu;             // d s2 / d(-Ep along n2): the stiffness of one cap
    const double H = kappa < kappa_u ? p.fc / kappa_u : 0.0;  // softening modulus -d f_c / d kappa, Pa
    // One cap: s2 = s2t + C22 dl = -f_c(kappa + dl), s1 = s1t + lambda dl.
    double dl = f0 / (C22 - H);
    if (H > 0 && kappa + dl > kappa_u) dl = -s2t / C22;  // past kappa_u the strength is 0
    double dl1 = 0, dl2 = dl;
    if (s1t + p.lambda * dl < s2t + C22 * dl) {
        // Both caps (corner): s1 = s1t + C22 dl1 + lambda dl2 = s2 = s2t + lambda dl1 + C22 dl2 = -f_c(kappa + dl1 + dl2).
        // Difference: dl1 - dl2 = -(s1t - s2t) / (2 mu); sum: s1t + s2t + 2 (lambda + mu) Sum = -2 f_c(kappa + Sum).
        const double D = -(s1t - s2t) / (2 * p.mu);
        const double Cc = 2 * (p.lambda + p.mu);
        double sum = -(s1t + s2t + 2 * fc0) / (Cc - 2 * H);
        if (H > 0 && kappa + sum > kappa_u) sum = -(s1t + s2t) / Cc;
        dl1 = std::max(0.0, 0.5 * (sum + D));
        dl2 = sum - dl1;
        dl = sum;
    }
    // dEp = -dl1 n1 n1 - dl2 n2 n2
    const double cc = c * c, ss = s * s, cs = c * s;
    Ep[0] -= dl1 * cc + dl2 * ss;
    Ep[1] -= dl1 * ss + dl2 * cc;
    Ep[2] -= (dl1 - dl2) * cs;
    kappa += dl;
    elastic_S(p, E, Ep, S);
    return true;
}

void Crushing::setup(const CaseSpec& spec, const Model& model) {
    std::vector<int> par_of_mat(spec.materials.size(), -1);
    for (std::size_t i = 0; i < spec.materials.size(); ++i) {
        const Material& m = spec.materials[i];
        if (!m.crushing.present) continue;
        CrushingParams p;
        p.fc = m.crushing.compressive_strength;
        p.Gc = m.crushing.Gc;
        p.mu = model.mat[i].mu;
        p.lambda = model.mat[i].lambda;
        par_of_mat[i] = static_cast<int>(params.size());
        params.push_back(p);
    }
    if (params.empty()) return;
    const int nt = model.n_triangles();
    slot_of_tri.assign(nt, -1);
    std::vector<double> worst(params.size(), 0.0);  // largest h per crushing material, m
    for (int e = 0; e < nt; ++e) {
        const int pi = par_of_mat[model.tri_material[e]];
        if (pi < 0) continue;
        const CrushingParams& p = params[pi];
        const double A0 = model.tris[e].A0t / model.thickness;
        const double h = std::sqrt(2 * A0);  // characteristic length, m (Rots 1988)
        worst[pi] = std::max(worst[pi], h);
        slot_of_tri[e] = static_cast<int>(kappa.size());
        tri_of_slot.push_back(e);
        par.push_back(pi);
        kappa.push_back(0.0);
        kappa_u.push_back(2 * p.Gc / (p.fc * h));  // f_c kappa_u / 2 = G_c / h
        A0t.push_back(model.tris[e].A0t);
        for (int k = 0; k < 3; ++k) Ep.push_back(0.0);
    }
    // No snap-back: H = f_c^2 h / (2 G_c) < lambda + mu, i.e. h < 2 G_c (lambda + mu) / f_c^2.
    std::vector<std::string> errors;
    for (std::size_t i = 0; i < spec.materials.size(); ++i) {
        const int pi = par_of_mat[i];
        if (pi < 0) continue;
        const CrushingParams& p = params[pi];
        const double hmax = 2 * p.Gc * (p.lambda + p.mu) / (p.fc * p.fc);
        if (!(worst[pi] < hmax)) {
            std::ostringstream s;
            s << spec.file << ":" << spec.materials[i].crushing.line << ": key 'materials." << spec.materials[i].name
              << ".crushing.Gc': a triangle of characteristic length sqrt(2 A) = " << worst[pi]
              << " m is too large for G_c = " << p.Gc << " J/m^2 and f_c = " << p.fc
              << " Pa (its softening would snap back); expected triangles up to " << hmax
              << " m (a finer mesh), or G_c >= " << p.fc * p.fc * worst[pi] / (2 * (p.lambda + p.mu)) << " J/m^2";
            errors.push_back(s.str());
        }
    }
    if (!errors.empty()) throw InputError(errors);
}

double Crushing::forces(int s, const TriangleRef& t, const double* x, const double* v, double* f6, double& visc_power) {
    double F[4];
    triangle_F(t, x, F);
    const double J = F[0] * F[3] - F[1] * F[2];
    if (!(J > 0)) {
        for (int k = 0; k < 6; ++k) f6[k] = 0;
        visc_power = 0;
        return J;
    }
    double E[3], S[3];
    green_lagrange(F, E);
    crushing_update(params[par[s]], kappa_u[s], E, &Ep[3 * static_cast<std::size_t>(s)], kappa[s], S);
    // Kirchhoff stress tau = F S F^T (P = F S = tau F^-T).
    const double A00 = F[0] * S[0] + F[1] * S[2], A01 = F[0] * S[2] + F[1] * S[1];
    const double A10 = F[2] * S[0] + F[3] * S[2], A11 = F[2] * S[2] + F[3] * S[1];
    const double tau[3] = {A00 * F[0] + A01 * F[1], A10 * F[2] + A11 * F[3], A00 * F[2] + A01 * F[3]};
    triangle_forces_from_tau(t, F, J, tau, v, f6, visc_power);
    return J;
}

double Crushing::energy(int s, const TriangleRef& t, const double* x) const {
    double F[4], E[3];
    triangle_F(t, x, F);
    green_lagrange(F, E);
    return t.A0t * crushing_energy_density(params[par[s]], E, &Ep[3 * static_cast<std::size_t>(s)]);
}

void Crushing::stress(int s, const TriangleRef& t, const double* x, double* s3) const {
    double F[4], E[3], S[3];
    triangle_F(t, x, F);
    const double J = F[0] * F[3] - F[1] * F[2];
    if (!(J > 0)) {
        s3[0] = s3[1] = s3[2] = std::nan("");
        return;
    }
    green_lagrange(F, E);
    elastic_S(params[par[s]], E, &Ep[3 * static_cast<std::size_t>(s)], S);
    // sigma = F S F^T / J
    const double A00 = F[0] * S[0] + F[1] * S[2], A01 = F[0] * S[2] + F[1] * S[1];
    const double A10 = F[2] * S[0] + F[3] * S[2], A11 = F[2] * S[2] + F[3] * S[1];
    s3[0] = (A00 * F[0] + A01 * F[1]) / J;
    s3[1] = (A10 * F[2] + A11 * F[3]) / J;
    s3[2] = (A00 * F[2] + A01 * F[3]) / J;
}

double Crushing::dissipated() const {
    double d = 0;
    for (std::size_t s = 0; s < kappa.size(); ++s) d += A0t[s] * crushing_dissipation_density(params[par[s]], kappa_u[s], kappa[s]);
    return d;
}

}  // namespace fdem
