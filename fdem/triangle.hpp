// fdem/triangle.hpp: the deformable constant-strain triangle with finite rotations ([M04] ch. 4).
//
// DATA LAYOUT ASSUMPTIONS
//   x, v: 2 * n_nodes doubles (node k at [2k], [2k+1]); TriangleRef: one 64-byte record per triangle (hot data,
//   read once per step); forces out: 6 doubles per triangle (node 0 x,y, node 1 x,y, node 2 x,y), gathered
//   to nodes afterwards in a fixed order (deterministic for any thread count).
//
// Kinematics: D0 = [X1-X0, X2-X0], D = [x1-x0, x2-x0], F = D D0^-1, J = det F, B = F F^T.
// Compressible neo-Hookean Kirchhoff stress [M04] ch. 4:
//     tau = mu (B - I) + lambda ln(J) I,
// zero under any rigid rotation and equal to linear elasticity at small strain; lambda is the plane-stress
// E nu / (1 - nu^2) or the plane-strain E nu / ((1 + nu)(1 - 2 nu)) Lame constant.
// First Piola stress P = tau F^-T, nodal forces f_a = -t A0 P grad0(N_a) with grad0 N_1, grad0 N_2 the rows
// of D0^-1 and grad0 N_0 = -(grad0 N_1 + grad0 N_2); the three forces sum to zero.
// Stored energy (the potential of that stress): W = mu/2 (tr C - 2) - mu ln J + lambda/2 (ln J)^2 per unit volume.
// Viscous stress sigma_v = eta sym(L), L = Fdot F^-1, eta = xi 2 h sqrt(E rho) ([M04]: xi = 1 is critical);
// in Piola form P_v = J sigma_v F^-T; dissipated power t A0 J eta sym(L):sym(L) >= 0.
#pragma once

#include <cmath>

namespace fdem {

struct TriangleRef {
    int n[3];        // node indices, counter-clockwise in the reference configuration
    int mat;         // index into the material constants
    double Dinv[4];  // D0^-1, row-major [a b; c d], 1/m
    double A0t;      // reference area times thickness, m^3
    double eta;      // viscous coefficient, Pa s (0: no viscous damping)
};
static_assert(sizeof(TriangleRef) == 64, "TriangleRef is meant to fill one cache line");

struct MaterialConst {
    double mu;      // shear modulus, Pa
    double lambda;  // Lame constant of the plane model, Pa
};

// Nodal forces of one triangle from its deformation gradient F (row-major F00 F01 F10 F11, J = det F > 0) and
// elastic Kirchhoff stress tau (xx, yy, xy): adds the viscous stress, then f_a = -t A0 P grad0(N_a) with
// P = tau F^-T (see the header comment). Shared by the elastic triangle and the crushing model (fdem/plasticity.hpp).
inline void triangle_forces_from_tau(const TriangleRef& t, const double* F, double J, const double* tau, const double* v,
                                     double* f6, double& visc_power) {
    const int i0 = t.n[0], i1 = t.n[1], i2 = t.n[2];
    const double a = t.Dinv[0], b = t.Dinv[1], c = t.Dinv[2], d = t.Dinv[3];
    const double F00 = F[0], F01 = F[1], F10 = F[2], F11 = F[3];
    double t00 = tau[0], t11 = tau[1], t01 = tau[2];
    const double iJ = 1.0 / J;
    // F^-T = (1/J) [F11 -F10; -F01 F00]
    const double G00 = F11 * iJ, G01 = -F10 * iJ, G10 = -F01 * iJ, G11 = F00 * iJ;
    visc_power = 0;
    if (t.eta > 0) {
        const double* vv = v;
        const double w0x = vv[2 * i0], w0y = vv[2 * i0 + 1];
        const double e00 = vv[2 * i1] - w0x, e10 = vv[2 * i1 + 1] - w0y;
        const double e01 = vv[2 * i2] - w0x, e11 = vv[2 * i2 + 1] - w0y;
        const double Fd00 = e00 * a + e01 * c, Fd01 = e00 * b + e01 * d;
        const double Fd10 = e10 * a + e11 * c, Fd11 = e10 * b + e11 * d;
        // L = Fdot F^-1, F^-1 = G^T
        const double L00 = Fd00 * G00 + Fd01 * G01, L01 = Fd00 * G10 + Fd01 * G11;
        const double L10 = Fd10 * G00 + Fd11 * G01, L11 = Fd10 * G10 + Fd11 * G11;
        const double s00 = L00, s11 = L11, s01 = 0.5 * (L01 + L10);
        // Kirchhoff viscous stress J sigma_v
        t00 += J * t.eta * s00;
        t11 += J * t.eta * s11;
        t01 += J * t.eta * s01;
        visc_power = t.A0t * J * t.eta * (s00 * s00 + s11 * s11 + 2 * s01 * s01);
    }
    // P = tau F^-T
    const double P00 = t00 * G00 + t01 * G10, P01 = t00 * G01 + t01 * G11;
    const double P10 = t01 * G00 + t11 * G10, P11 = t01 * G01 + t11 * G11;
    // f_1 = -A0 t P (a, b)^T, f_2 = -A0 t P (c, d)^T, f_0 = -(f_1 + f_2)
    const double s = -t.A0t;
    const double f1x = s * (P00 * a + P01 * b), f1y = s * (P10 * a + P11 * b);
    const double f2x = s * (P00 * c + P01 * d), f2y = s * (P10 * c + P11 * d);
    f6[0] = -(f1x + f2x);
    f6[1] = -(f1y + f2y);
    f6[2] = f1x;
    f6[3] = f1y;
    f6[4] = f2x;
    f6[5] = f2y;
}

// Internal (elastic + viscous) forces of one triangle into f6. Returns J; `visc_power` gets the viscous
// dissipation rate (W). J <= 0 means the triangle is inverted (the caller reports it). sigma3 (optional): the elastic
// Cauchy stress tau / J (xx, yy, xy, Pa), as triangle_stress gives it, for the extrinsic insertion check.
inline double triangle_forces(const TriangleRef& t, const MaterialConst& m, const double* x, const double* v,
                              double* f6, double& visc_power, double* sigma3 = nullptr) {
    const int i0 = t.n[0], i1 = t.n[1], i2 = t.n[2];
    const double x0 = x[2 * i0], y0 = x[2 * i0 + 1];
    const double d00 = x[2 * i1] - x0, d10 = x[2 * i1 + 1] - y0;  // D column 0
    const double d01 = x[2 * i2] - x0, d11 = x[2 * i2 + 1] - y0;  // D column 1
    const double a = t.Dinv[0], b = t.Dinv[1], c = t.Dinv[2], d = t.Dinv[3];
    // F = D D0^-1
    const double F00 = d00 * a + d01 * c, F01 = d00 * b + d01 * d;
    const double F10 = d10 * a + d11 * c, F11 = d10 * b + d11 * d;
    const double J = F00 * F11 - F01 * F10;
    if (!(J > 0)) {
        for (int k = 0; k < 6; ++k) f6[k] = 0;
        visc_power = 0;
        if (sigma3) sigma3[0] = sigma3[1] = sigma3[2] = 0.0;
        return J;
    }
    // tau = mu (B - I) + lambda ln J I
    const double lnJ = std::log(J);
    const double tau[3] = {m.mu * (F00 * F00 + F01 * F01 - 1.0) + m.lambda * lnJ,
                           m.mu * (F10 * F10 + F11 * F11 - 1.0) + m.lambda * lnJ, m.mu * (F00 * F10 + F01 * F11)};
    const double Fm[4] = {F00, F01, F10, F11};
    triangle_forces_from_tau(t, Fm, J, tau, v, f6, visc_power);
    if (sigma3) {
        const double iJ = 1.0 / J;
        sigma3[0] = tau[0] * iJ, sigma3[1] = tau[1] * iJ, sigma3[2] = tau[2] * iJ;
    }
    return J;
}

// triangle_forces for the elastic triangles e0 <= e < e1 of tris, into tf (6 per triangle): each one's viscous power
// added to visc_power in triangle order, and bad set to the first inverted triangle (J <= 0) if bad < 0. Four at a
// time where the CPU has AVX (lanes = 0; 1: one at a time), with the same bits: every lane does triangle_forces'
// operations in the same order (tests/core/test_triangle_range.cpp compares them).
void triangle_forces_range(const TriangleRef* tris, const MaterialConst* mats, const double* x, const double* v,
                           double* tf, int e0, int e1, double& visc_power, int& bad, int lanes = 0);

// Deformation gradient of a triangle (row-major F00 F01 F10 F11).
inline void triangle_F(const TriangleRef& t, const double* x, double* F) {
    const int i0 = t.n[0], i1 = t.n[1], i2 = t.n[2];
    const double d00 = x[2 * i1] - x[2 * i0], d10 = x[2 * i1 + 1] - x[2 * i0 + 1];
    const double d01 = x[2 * i2] - x[2 * i0], d11 = x[2 * i2 + 1] - x[2 * i0 + 1];
    F[0] = d00 * t.Dinv[0] + d01 * t.Dinv[2];
    F[1] = d00 * t.Dinv[1] + d01 * t.Dinv[3];
    F[2] = d10 * t.Dinv[0] + d11 * t.Dinv[2];
    F[3] = d10 * t.Dinv[1] + d11 * t.Dinv[3];
}

// j - ln(1 + j) without cancellation: the series j^2/2 - j^3/3 + ... for |j| < 1e-2 (terms to j^10, the
// truncation below 1e-16 relative), the direct form elsewhere (it loses at most 2 digits there).
inline double j_minus_log1p(double j) {
    if (std::abs(j) < 1e-2) {
        double s = 0;
        for (int k = 10; k >= 2; --k) s = (k % 2 == 0 ? 1.0 : -1.0) / k + j * s;
        return j * j * s;
    }
    return j - std::log1p(j);
}

// Stored elastic energy of a triangle, J (see the header comment), written in the displacement gradient
// H = F - I so that it keeps its digits near F = I (the form mu/2 (tr C - 2) - mu ln J cancels to round-off of
// order mu eps per unit volume, which at E = 1e13 Pa is larger than the energy of a small deformation).
// With j = J - 1 = tr H + det H exactly:
//   tr C - 2 = 2 tr H + |H|^2 and mu/2 (tr C - 2) - mu ln J = mu [1/2 |H|^2 - det H + (j - ln(1 + j))],
//   1/2 |H|^2 - det H = 1/2 (H00 - H11)^2 + 1/2 (H01 + H10)^2 (each term >= 0, zero under a rigid rotation).
inline double triangle_energy(const TriangleRef& t, const MaterialConst& m, const double* x) {
    double F[4];
    triangle_F(t, x, F);
    const double H00 = F[0] - 1.0, H01 = F[1], H10 = F[2], H11 = F[3] - 1.0;
    const double j = H00 + H11 + (H00 * H11 - H01 * H10);
    if (!(j > -1.0)) return 0;
    const double lnJ = std::log1p(j);
    const double dev = 0.5 * (H00 - H11) * (H00 - H11) + 0.5 * (H01 + H10) * (H01 + H10);
    return t.A0t * (m.mu * (dev + j_minus_log1p(j)) + 0.5 * m.lambda * lnJ * lnJ);
}

// Elastic Cauchy stress sigma = tau / J (xx, yy, xy), Pa.
inline void triangle_stress(const TriangleRef& t, const MaterialConst& m, const double* x, double* s3) {
    double F[4];
    triangle_F(t, x, F);
    const double J = F[0] * F[3] - F[1] * F[2];
    if (!(J > 0)) {
        s3[0] = s3[1] = s3[2] = std::nan("");
        return;
    }
    const double lnJ = std::log(J);
    s3[0] = (m.mu * (F[0] * F[0] + F[1] * F[1] - 1.0) + m.lambda * lnJ) / J;
    s3[1] = (m.mu * (F[2] * F[2] + F[3] * F[3] - 1.0) + m.lambda * lnJ) / J;
    s3[2] = m.mu * (F[0] * F[2] + F[1] * F[3]) / J;
}

}  // namespace fdem
