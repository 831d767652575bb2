// fdem/triangle.cpp: the triangle forces of a range of elastic triangles (fdem/triangle.hpp, triangle_forces_range).
#include "fdem/triangle.hpp"

#include <cmath>
#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

namespace fdem {

namespace {

#if defined(__GNUC__) && defined(__x86_64__)
#define FDEM_TRIANGLE_QUAD 1
// Four triangles t[0..3] at once with AVX (lane j = triangle j): triangle_forces' operations in the same order (IEEE
// per lane, no contraction; ln J by std::log lane by lane), for triangles without viscous damping (eta = 0) that are
// not inverted (J > 0 in every lane). Otherwise it writes nothing and returns false. f: the four triangles' 24
// consecutive force doubles. Compiled for AVX whatever the build's baseline; called only where the CPU has it.
__attribute__((target("avx"))) bool triangle_quad(const TriangleRef* t, const MaterialConst* mats, const double* x,
                                                  double* f) {
    if (t[0].eta > 0 || t[1].eta > 0 || t[2].eta > 0 || t[3].eta > 0) return false;
    // node k of the four triangles as (x_0, ..., x_3) and (y_0, ..., y_3)
    __m256d X[3], Y[3];
    for (int k = 0; k < 3; ++k) {
        const __m256d lo = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(x + 2 * t[0].n[k])),
                                                _mm_loadu_pd(x + 2 * t[2].n[k]), 1);
        const __m256d hi = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(x + 2 * t[1].n[k])),
                                                _mm_loadu_pd(x + 2 * t[3].n[k]), 1);
        X[k] = _mm256_unpacklo_pd(lo, hi);
        Y[k] = _mm256_unpackhi_pd(lo, hi);
    }
    // D0^-1 = [a b; c d] of the four: a 4 x 4 transpose of the records' Dinv
    const __m256d r0 = _mm256_loadu_pd(t[0].Dinv), r1 = _mm256_loadu_pd(t[1].Dinv);
    const __m256d r2 = _mm256_loadu_pd(t[2].Dinv), r3 = _mm256_loadu_pd(t[3].Dinv);
    const __m256d l01 = _mm256_unpacklo_pd(r0, r1), h01 = _mm256_unpackhi_pd(r0, r1);
    const __m256d l23 = _mm256_unpacklo_pd(r2, r3), h23 = _mm256_unpackhi_pd(r2, r3);
    const __m256d a = _mm256_permute2f128_pd(l01, l23, 0x20), b = _mm256_permute2f128_pd(h01, h23, 0x20);
    const __m256d c = _mm256_permute2f128_pd(l01, l23, 0x31), d = _mm256_permute2f128_pd(h01, h23, 0x31);
    const __m256d A0t = _mm256_set_pd(t[3].A0t, t[2].A0t, t[1].A0t, t[0].A0t);
    const MaterialConst &m0 = mats[t[0].mat], &m1 = mats[t[1].mat], &m2 = mats[t[2].mat], &m3 = mats[t[3].mat];
    const __m256d mu = _mm256_set_pd(m3.mu, m2.mu, m1.mu, m0.mu);
    const __m256d lambda = _mm256_set_pd(m3.lambda, m2.lambda, m1.lambda, m0.lambda);
    const __m256d d00 = _mm256_sub_pd(X[1], X[0]), d10 = _mm256_sub_pd(Y[1], Y[0]);
    const __m256d d01 = _mm256_sub_pd(X[2], X[0]), d11 = _mm256_sub_pd(Y[2], Y[0]);
    const __m256d F00 = _mm256_add_pd(_mm256_mul_pd(d00, a), _mm256_mul_pd(d01, c));
    const __m256d F01 = _mm256_add_pd(_mm256_mul_pd(d00, b), _mm256_mul_pd(d01, d));
    const __m256d F10 = _mm256_add_pd(_mm256_mul_pd(d10, a), _mm256_mul_pd(d11, c));
    const __m256d F11 = _mm256_add_pd(_mm256_mul_pd(d10, b), _mm256_mul_pd(d11, d));
    const __m256d J = _mm256_sub_pd(_mm256_mul_pd(F00, F11), _mm256_mul_pd(F01, F10));
    if (_mm256_movemask_pd(_mm256_cmp_pd(J, _mm256_setzero_pd(), _CMP_GT_OQ)) != 0xF) return false;
    alignas(32) double Jl[4];
    _mm256_store_pd(Jl, J);
    const __m256d lnJ = _mm256_set_pd(std::log(Jl[3]), std::log(Jl[2]), std::log(Jl[1]), std::log(Jl[0]));
    const __m256d one = _mm256_set1_pd(1.0), sign = _mm256_set1_pd(-0.0);
    const __m256d lnl = _mm256_mul_pd(lambda, lnJ);
    const __m256d t00 = _mm256_add_pd(
        _mm256_mul_pd(mu, _mm256_sub_pd(_mm256_add_pd(_mm256_mul_pd(F00, F00), _mm256_mul_pd(F01, F01)), one)), lnl);
    const __m256d t11 = _mm256_add_pd(
        _mm256_mul_pd(mu, _mm256_sub_pd(_mm256_add_pd(_mm256_mul_pd(F10, F10), _mm256_mul_pd(F11, F11)), one)), lnl);
    const __m256d t01 = _mm256_mul_pd(mu, _mm256_add_pd(_mm256_mul_pd(F00, F10), _mm256_mul_pd(F01, F11)));
    const __m256d iJ = _mm256_div_pd(one, J);
    const __m256d G00 = _mm256_mul_pd(F11, iJ), G01 = _mm256_mul_pd(_mm256_xor_pd(F10, sign), iJ);
    const __m256d G10 = _mm256_mul_pd(_mm256_xor_pd(F01, sign), iJ), G11 = _mm256_mul_pd(F00, iJ);
    const __m256d P00 = _mm256_add_pd(_mm256_mul_pd(t00, G00), _mm256_mul_pd(t01, G10));
    const __m256d P01 = _mm256_add_pd(_mm256_mul_pd(t00, G01), _mm256_mul_pd(t01, G11));
    const __m256d P10 = _mm256_add_pd(_mm256_mul_pd(t01, G00), _mm256_mul_pd(t11, G10));
    const __m256d P11 = _mm256_add_pd(_mm256_mul_pd(t01, G01), _mm256_mul_pd(t11, G11));
    const __m256d s = _mm256_xor_pd(A0t, sign);
    const __m256d f1x = _mm256_mul_pd(s, _mm256_add_pd(_mm256_mul_pd(P00, a), _mm256_mul_pd(P01, b)));
    const __m256d f1y = _mm256_mul_pd(s, _mm256_add_pd(_mm256_mul_pd(P10, a), _mm256_mul_pd(P11, b)));
    const __m256d f2x = _mm256_mul_pd(s, _mm256_add_pd(_mm256_mul_pd(P00, c), _mm256_mul_pd(P01, d)));
    const __m256d f2y = _mm256_mul_pd(s, _mm256_add_pd(_mm256_mul_pd(P10, c), _mm256_mul_pd(P11, d)));
    const __m256d f0x = _mm256_xor_pd(_mm256_add_pd(f1x, f2x), sign), f0y = _mm256_xor_pd(_mm256_add_pd(f1y, f2y), sign);
    // (f_kx, f_ky) of triangles 0 and 2 in the unpacklo, of 1 and 3 in the unpackhi
    const __m256d p[3][2] = {{_mm256_unpacklo_pd(f0x, f0y), _mm256_unpackhi_pd(f0x, f0y)},
                             {_mm256_unpacklo_pd(f1x, f1y), _mm256_unpackhi_pd(f1x, f1y)},
                             {_mm256_unpacklo_pd(f2x, f2y), _mm256_unpackhi_pd(f2x, f2y)}};
    for (int k = 0; k < 3; ++k) {
        _mm_storeu_pd(f + 0 + 2 * k, _mm256_castpd256_pd128(p[k][0]));
        _mm_storeu_pd(f + 6 + 2 * k, _mm256_castpd256_pd128(p[k][1]));
        _mm_storeu_pd(f + 12 + 2 * k, _mm256_extractf128_pd(p[k][0], 1));
        _mm_storeu_pd(f + 18 + 2 * k, _mm256_extractf128_pd(p[k][1], 1));
    }
    return true;
}

bool avx_available() {
    static const bool yes = __builtin_cpu_supports("avx");
    return yes;
}
#endif

}  // namespace

void triangle_forces_range(const TriangleRef* tris, const MaterialConst* mats, const double* x, const double* v,
                           double* tf, int e0, int e1, double& visc_power, int& bad, int lanes) {
#if defined(FDEM_TRIANGLE_QUAD)
    const bool quads = lanes != 1 && avx_available();
#else
    const bool quads = false;
    (void)lanes;
#endif
    for (int e = e0; e < e1;) {
        const int e4 = e + 4 <= e1 ? e + 4 : e1;
#if defined(FDEM_TRIANGLE_QUAD)
        if (quads && e4 == e + 4 && triangle_quad(tris + e, mats, x, tf + 6 * static_cast<std::size_t>(e))) {
            for (int j = 0; j < 4; ++j) visc_power += 0.0;  // (each triangle's viscous power, 0 without eta)
            e = e4;
            continue;
        }
#endif
        for (; e < e4; ++e) {
            double p;
            const double J = triangle_forces(tris[e], mats[tris[e].mat], x, v, tf + 6 * static_cast<std::size_t>(e), p);
            if (!(J > 0) && bad < 0) bad = e;
            visc_power += p;
        }
    }
}

}  // namespace fdem
