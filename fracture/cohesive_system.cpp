// fracture/cohesive_system.cpp: construction and force loop of the cohesive elements (insertion, damage update and
// records: fracture/cohesive_records.cpp).
//
// DATA LAYOUT ASSUMPTIONS
// - Node arrays (x, f, node_mass) are the engine's: x and f interleaved 2 per node (x0 y0 x1 y1 ...), m 1 per node.
// - Elements are indexed 0..size()-1 in the order the engine gave them; every per-element array below uses that
//   index: law_[e] (AoS struct, read whole by the general loop), length_[e], history_[3e + i] (i = end 0, midpoint,
//   end 1; the damage and what the second-order dissipation needs from the previous step),
//   force_[8e + 2k + {0,1}] (k = a0, a1, b0, b1), energy_[e], dissipated_[e].
// - plain_ (detail::PlainJoint, one 128-byte record per element) and other_ group the intact elements by law, each in
//   active_ order: derived from active_, elems_ and law_ by build_hot(), not saved. The force loop walks plain_ in
//   order, eight, four or two elements at a time where it can (plain_oct, plain_quad, plain_pair), and other_ with the
//   general laws.
// - active_ lists the intact elements in ascending order; broken ones leave it and their force slots are zeroed,
//   so the node gather (CSR over the intact elements, slots in element order) stays valid between rebuilds, which
//   happen once a quarter of its slots belong to broken elements.
//
// Kinematics and forces ([M04] ch. 7, [MAW99]). With N0 = 1 - xi, N1 = xi along the edge, the gap is
//   d(xi) = sum_k N_k (x_Bk - x_Ak),  o = d.n,  s = d.t,
// and the nodal forces are the integral of the traction T = sigma n + tau t over the reference face area h t:
//   f_Bk = - int N_k T dA,  f_Ak = + int N_k T dA   (action = reaction, sum zero),
// discretised by Simpson's rule on xi = 0, 1/2, 1 with weights 1/6, 4/6, 1/6:
//   f_A0 = h t (T_0 / 6 + T_m / 3),  f_A1 = h t (T_1 / 6 + T_m / 3).
// The derivative of the frame (n, t) with respect to x is neglected, as in [M04]: it is of the order of the
// gap over h, which is tiny while the joint carries load.
#include "fracture/cohesive_system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#if defined(__SSE2__)
#include <immintrin.h>
#endif
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace fdem::fracture {

namespace {
using detail::kPi;
using detail::kSimpson;
// Below this many elements a parallel region costs more than it saves (thread wake-up is microseconds, an element
// tens of nanoseconds), and on a loaded machine much more. The result does not depend on it.
constexpr int kMinParallel = 4096;

// An element's frame and opening at positions x (nodes n: edge A a0 a1, edge B b0 b1): the tangent from the mid-line
// of the two edges (a fully collapsed element, of length 0, has none: x), the normal of edge A pointing into side B,
// and the relative displacement B - A at end 0, the midpoint and end 1. The plain path and the general loop share it;
// the vector kernels (SSE2, AVX) do the same arithmetic lane by lane.
struct ElementFrame {
  double tx, ty, nx, ny;
  double dx[3], dy[3];
};
inline ElementFrame element_frame(const double* x, const int* n) {
  const double xa0 = x[2 * n[0]], ya0 = x[2 * n[0] + 1], xa1 = x[2 * n[1]], ya1 = x[2 * n[1] + 1];
  const double xb0 = x[2 * n[2]], yb0 = x[2 * n[2] + 1], xb1 = x[2 * n[3]], yb1 = x[2 * n[3] + 1];
  ElementFrame f;
  f.tx = (xa1 + xb1) - (xa0 + xb0), f.ty = (ya1 + yb1) - (ya0 + yb0);
  const double len = std::sqrt(f.tx * f.tx + f.ty * f.ty);
  if (len > 0.0) {
    f.tx /= len;
    f.ty /= len;
  } else {
    f.tx = 1.0;
    f.ty = 0.0;
  }
  f.nx = f.ty, f.ny = -f.tx;
  const double d0x = xb0 - xa0, d0y = yb0 - ya0, d1x = xb1 - xa1, d1y = yb1 - ya1;
  f.dx[0] = d0x, f.dx[1] = 0.5 * (d0x + d1x), f.dx[2] = d1x;
  f.dy[0] = d0y, f.dy[1] = 0.5 * (d0y + d1y), f.dy[2] = d1y;
  return f;
}

// evaluate_point (law.hpp) for a plain joint (CohesiveSystem::PlainJoint: the [K25] law without keep_friction, cap or
// insertion offset), the same operations in the same order on the constants the record holds. What the general law
// would keep unchanged is left alone: the closure and the slider slip (0 for these joints), and the damage unless it
// grows. L is read only on the rare branch of a compressed point past its shear peak.
// An element's nodal forces from its Simpson-weighted point forces T (N, at xi = 0, 1/2, 1): the midpoint's shared
// half-half by the two ends, a0 and a1 get them, b0 and b1 the opposite (force_'s layout).
inline void store_forces(const double* Tx, const double* Ty, double* fe) {
  const double fa0x = Tx[0] + 0.5 * Tx[1], fa0y = Ty[0] + 0.5 * Ty[1];
  const double fa1x = Tx[2] + 0.5 * Tx[1], fa1y = Ty[2] + 0.5 * Ty[1];
  fe[0] = fa0x;
  fe[1] = fa0y;
  fe[2] = fa1x;
  fe[3] = fa1y;
  fe[4] = -fa0x;
  fe[5] = -fa0y;
  fe[6] = -fa1x;
  fe[7] = -fa1y;
}

struct PlainPoint {
  double sigma, tau, energy, dissipated, damage_I, damage_II, D;
};
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
inline PlainPoint plain_point(const detail::PlainJoint& J, const JointLaw& L, double o, double s,
                              PointHistory& h) {
  PlainPoint r;
  double sigma_c = 0.0, f_s = J.c, s_p = J.s_p0, inv_s_p = J.inv_s_p0;
  if (o < 0.0) {
    sigma_c = J.K_n * o;
    f_s = shear_strength(sigma_c, J.c, J.tan_phi);
    s_p = 2.0 * f_s * J.inv_K_s;
    inv_s_p = 1.0 / s_p;
  }
  const double a_s = s < 0.0 ? -s : s;
  const double o_p = J.o_p;
  const double dI = (o - o_p) * J.inv_o_t;
  const double dII = (o < 0.0 && a_s > s_p) ? (a_s - s_p) / shear_softening_range(L, f_s, s_p)
                                            : (a_s - s_p) * J.inv_s_t0;
  r.damage_I = dI > 0.0 ? dI : 0.0;
  r.damage_II = dII > 0.0 ? dII : 0.0;
  double trial;
  if (dI > 0.0 || dII > 0.0) {
    trial = std::sqrt(r.damage_I * r.damage_I + r.damage_II * r.damage_II);
  } else {
    trial = dI > dII ? dI : dII;
  }
  const double D_old = h.damage;
  const double D = trial >= 1.0 ? 1.0 : (trial > D_old ? trial : D_old);
  double t_n0 = 0.0, e_n0 = 0.0;
  if (o > 0.0) {
    if (o >= o_p) {
      t_n0 = J.f_t;
      e_n0 = J.f_t * (o_p * (2.0 / 3.0) + (o - o_p));
    } else {
      const double x = o * J.inv_o_p;
      t_n0 = prepeak_shape(x) * J.f_t;
      e_n0 = prepeak_energy_shape(x) * J.f_t * o_p;
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
  const double E0 = e_n0 + e_s0;
  const double z = D > 0.0 ? softening(D) : 1.0;
  r.sigma = o < 0.0 ? sigma_c : z * t_n0;
  r.tau = (s < 0.0 ? -z : z) * t_s0;
  r.energy = z * E0 + (o < 0.0 ? 0.5 * sigma_c * o : 0.0);
  r.dissipated = 0.0;
  if (D > D_old) {
    double phi = 0.0;
    if (trial > h.trial) phi = (D_old - h.trial) / (trial - h.trial);
    phi = phi < 0.0 ? 0.0 : (phi > 1.0 ? 1.0 : phi);
    const double E0_a = h.undamaged_energy + phi * (E0 - h.undamaged_energy);
    r.dissipated = (softening(D_old) - z) * 0.5 * (E0_a + E0) + 0.0;  // (+ the cap's crushing, 0)
    h.damage = D;
  }
  h.trial = trial;
  h.undamaged_energy = E0;
  r.D = D;
  return r;
}

#if defined(__SSE2__)
#if defined(__GNUC__) && defined(__x86_64__)
#define FDEM_PLAIN_QUAD 1
// Four plain elements at once with AVX (lane j = element J[j]): the lanes of plain_pair (in CohesiveSystem::add_forces)
// twice as wide, the same operations in the same order (AVX arithmetic is IEEE per lane; no FMA: contraction is
// off, and "avx" does not enable it), for the same common case; otherwise it writes nothing and returns false.
// Compiled for AVX whatever the build's baseline; called only where the CPU has it (avx_available).
__attribute__((target("avx"))) bool plain_quad(const detail::PlainJoint* const J[4], const double* x,
                                               PointHistory* hist, double* force, double* energy_out) {
  PointHistory* h[4] = {hist + 3 * std::size_t(J[0]->e), hist + 3 * std::size_t(J[1]->e),
                        hist + 3 * std::size_t(J[2]->e), hist + 3 * std::size_t(J[3]->e)};
  const __m256d zero = _mm256_setzero_pd();
  __m256d bad = zero;
  for (int i = 0; i < 3; ++i)
    bad = _mm256_or_pd(bad, _mm256_cmp_pd(_mm256_set_pd(h[3][i].damage, h[2][i].damage, h[1][i].damage,
                                                        h[0][i].damage), zero, _CMP_NEQ_UQ));
  if (_mm256_movemask_pd(bad)) return false;
  const __m256d one = _mm256_set1_pd(1.0), two = _mm256_set1_pd(2.0), three = _mm256_set1_pd(3.0),
                half = _mm256_set1_pd(0.5), two_thirds = _mm256_set1_pd(2.0 / 3.0), sign = _mm256_set1_pd(-0.0);
#define sel(m, a, b) _mm256_or_pd(_mm256_and_pd(m, a), _mm256_andnot_pd(m, b))
#define neg(a) _mm256_xor_pd(a, sign)
  // Node k of the four elements as (x_0, x_1, x_2, x_3) and (y_0, ..., y_3).
  __m256d xa0, ya0, xa1, ya1, xb0, yb0, xb1, yb1;
  __m256d* const vx[4] = {&xa0, &xa1, &xb0, &xb1};
  __m256d* const vy[4] = {&ya0, &ya1, &yb0, &yb1};
  for (int k = 0; k < 4; ++k) {
    const __m256d lo = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(x + 2 * J[0]->n[k])),
                                            _mm_loadu_pd(x + 2 * J[2]->n[k]), 1);
    const __m256d hi = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(x + 2 * J[1]->n[k])),
                                            _mm_loadu_pd(x + 2 * J[3]->n[k]), 1);
    *vx[k] = _mm256_unpacklo_pd(lo, hi);
    *vy[k] = _mm256_unpackhi_pd(lo, hi);
  }
  __m256d tx = _mm256_sub_pd(_mm256_add_pd(xa1, xb1), _mm256_add_pd(xa0, xb0));
  __m256d ty = _mm256_sub_pd(_mm256_add_pd(ya1, yb1), _mm256_add_pd(ya0, yb0));
  const __m256d len = _mm256_sqrt_pd(_mm256_add_pd(_mm256_mul_pd(tx, tx), _mm256_mul_pd(ty, ty)));
  const __m256d has_len = _mm256_cmp_pd(len, zero, _CMP_GT_OQ);
  tx = sel(has_len, _mm256_div_pd(tx, len), one);
  ty = sel(has_len, _mm256_div_pd(ty, len), zero);
  const __m256d nx = ty, ny = neg(tx);
  const __m256d d0x = _mm256_sub_pd(xb0, xa0), d0y = _mm256_sub_pd(yb0, ya0);
  const __m256d d1x = _mm256_sub_pd(xb1, xa1), d1y = _mm256_sub_pd(yb1, ya1);
  const __m256d dx[3] = {d0x, _mm256_mul_pd(half, _mm256_add_pd(d0x, d1x)), d1x};
  const __m256d dy[3] = {d0y, _mm256_mul_pd(half, _mm256_add_pd(d0y, d1y)), d1y};
#define FDEM_QUAD(field) _mm256_set_pd(J[3]->field, J[2]->field, J[1]->field, J[0]->field)
  const __m256d K_n = FDEM_QUAD(K_n), inv_K_s = FDEM_QUAD(inv_K_s);
  const __m256d o_p = FDEM_QUAD(o_p), inv_o_p = FDEM_QUAD(inv_o_p), inv_o_t = FDEM_QUAD(inv_o_t);
  const __m256d s_p0 = FDEM_QUAD(s_p0), inv_s_p0 = FDEM_QUAD(inv_s_p0), inv_s_t0 = FDEM_QUAD(inv_s_t0);
  const __m256d f_t = FDEM_QUAD(f_t), c = FDEM_QUAD(c), tan_phi = FDEM_QUAD(tan_phi);
  const __m256d w_end = FDEM_QUAD(w_end), w_mid = FDEM_QUAD(w_mid);
#undef FDEM_QUAD
  __m256d Tx[3], Ty[3], trial[3], E0[3];
  __m256d energy = zero;
#pragma GCC unroll 3
  for (int i = 0; i < 3; ++i) {
    const __m256d o = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx[i], nx), _mm256_mul_pd(dy[i], ny)), zero);
    const __m256d s = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx[i], tx), _mm256_mul_pd(dy[i], ty)), zero);
    const __m256d comp = _mm256_cmp_pd(o, zero, _CMP_LT_OQ);
    const __m256d sc = _mm256_mul_pd(K_n, o);
    const __m256d fs_c =
        _mm256_add_pd(c, _mm256_and_pd(_mm256_cmp_pd(sc, zero, _CMP_LT_OQ), _mm256_mul_pd(neg(sc), tan_phi)));
    const __m256d sp_c = _mm256_mul_pd(_mm256_mul_pd(two, fs_c), inv_K_s);
    const __m256d sigma_c = _mm256_and_pd(comp, sc);
    const __m256d f_s = sel(comp, fs_c, c);
    const __m256d s_p = sel(comp, sp_c, s_p0);
    const __m256d inv_s_p = sel(comp, _mm256_div_pd(one, sp_c), inv_s_p0);
    const __m256d s_neg = _mm256_cmp_pd(s, zero, _CMP_LT_OQ);
    const __m256d a_s = sel(s_neg, neg(s), s);
    const __m256d dI = _mm256_mul_pd(_mm256_sub_pd(o, o_p), inv_o_t);
    const __m256d dII = _mm256_mul_pd(_mm256_sub_pd(a_s, s_p), inv_s_t0);
    bad = _mm256_or_pd(bad, _mm256_or_pd(_mm256_and_pd(comp, _mm256_cmp_pd(a_s, s_p, _CMP_GT_OQ)),
                                         _mm256_or_pd(_mm256_cmp_pd(dI, zero, _CMP_GT_OQ),
                                                      _mm256_cmp_pd(dII, zero, _CMP_GT_OQ))));
    trial[i] = sel(_mm256_cmp_pd(dI, dII, _CMP_GT_OQ), dI, dII);
    const __m256d u = _mm256_mul_pd(o, inv_o_p);
    const __m256d pre_t = _mm256_mul_pd(_mm256_mul_pd(u, _mm256_sub_pd(two, u)), f_t);
    const __m256d pre_e = _mm256_mul_pd(
        _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(u, u), _mm256_sub_pd(one, _mm256_div_pd(u, three))), f_t), o_p);
    const __m256d top_e =
        _mm256_mul_pd(f_t, _mm256_add_pd(_mm256_mul_pd(o_p, two_thirds), _mm256_sub_pd(o, o_p)));
    const __m256d tension = _mm256_cmp_pd(o, zero, _CMP_GT_OQ), top = _mm256_cmp_pd(o, o_p, _CMP_GE_OQ);
    const __m256d t_n0 = _mm256_and_pd(tension, sel(top, f_t, pre_t));
    const __m256d e_n0 = _mm256_and_pd(tension, sel(top, top_e, pre_e));
    const __m256d y = _mm256_mul_pd(a_s, inv_s_p);
    const __m256d pre_ts = _mm256_mul_pd(_mm256_mul_pd(y, _mm256_sub_pd(two, y)), f_s);
    const __m256d pre_es = _mm256_mul_pd(
        _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(y, y), _mm256_sub_pd(one, _mm256_div_pd(y, three))), f_s), s_p);
    const __m256d top_es =
        _mm256_mul_pd(f_s, _mm256_add_pd(_mm256_mul_pd(s_p, two_thirds), _mm256_sub_pd(a_s, s_p)));
    const __m256d top_s = _mm256_cmp_pd(a_s, s_p, _CMP_GE_OQ);
    const __m256d t_s0 = sel(top_s, f_s, pre_ts);
    const __m256d e_s0 = sel(top_s, top_es, pre_es);
    E0[i] = _mm256_add_pd(e_n0, e_s0);
    const __m256d sigma = sel(comp, sigma_c, _mm256_mul_pd(one, t_n0));
    const __m256d tau = _mm256_mul_pd(sel(s_neg, neg(one), one), t_s0);
    const __m256d en =
        _mm256_add_pd(_mm256_mul_pd(one, E0[i]), _mm256_and_pd(comp, _mm256_mul_pd(_mm256_mul_pd(half, sigma_c), o)));
    const __m256d w = i == 1 ? w_mid : w_end;
    Tx[i] = _mm256_mul_pd(w, _mm256_add_pd(_mm256_mul_pd(sigma, nx), _mm256_mul_pd(tau, tx)));
    Ty[i] = _mm256_mul_pd(w, _mm256_add_pd(_mm256_mul_pd(sigma, ny), _mm256_mul_pd(tau, ty)));
    energy = _mm256_add_pd(energy, _mm256_mul_pd(w, en));
  }
  if (_mm256_movemask_pd(bad)) return false;
  const __m256d fa0x = _mm256_add_pd(Tx[0], _mm256_mul_pd(half, Tx[1]));
  const __m256d fa0y = _mm256_add_pd(Ty[0], _mm256_mul_pd(half, Ty[1]));
  const __m256d fa1x = _mm256_add_pd(Tx[2], _mm256_mul_pd(half, Tx[1]));
  const __m256d fa1y = _mm256_add_pd(Ty[2], _mm256_mul_pd(half, Ty[1]));
  // (f_a0x, f_a0y) per element: lanes 0 and 2 in the unpacklo, 1 and 3 in the unpackhi
  const __m256d a0_02 = _mm256_unpacklo_pd(fa0x, fa0y), a0_13 = _mm256_unpackhi_pd(fa0x, fa0y);
  const __m256d a1_02 = _mm256_unpacklo_pd(fa1x, fa1y), a1_13 = _mm256_unpackhi_pd(fa1x, fa1y);
  const __m128d a0[4] = {_mm256_castpd256_pd128(a0_02), _mm256_castpd256_pd128(a0_13), _mm256_extractf128_pd(a0_02, 1),
                         _mm256_extractf128_pd(a0_13, 1)};
  const __m128d a1[4] = {_mm256_castpd256_pd128(a1_02), _mm256_castpd256_pd128(a1_13), _mm256_extractf128_pd(a1_02, 1),
                         _mm256_extractf128_pd(a1_13, 1)};
#undef sel
#undef neg
  const __m128d sign2 = _mm_set1_pd(-0.0);
  alignas(32) double en_l[4], trial_l[3][4], E0_l[3][4];
  _mm256_store_pd(en_l, energy);
  for (int i = 0; i < 3; ++i) {
    _mm256_store_pd(trial_l[i], trial[i]);
    _mm256_store_pd(E0_l[i], E0[i]);
  }
  for (int j = 0; j < 4; ++j) {
    double* fe = force + 8 * std::size_t(J[j]->e);
    _mm_storeu_pd(fe + 0, a0[j]);
    _mm_storeu_pd(fe + 2, a1[j]);
    _mm_storeu_pd(fe + 4, _mm_xor_pd(a0[j], sign2));
    _mm_storeu_pd(fe + 6, _mm_xor_pd(a1[j], sign2));
    energy_out[J[j]->e] = en_l[j];
    for (int i = 0; i < 3; ++i) {
      h[j][i].trial = trial_l[i][j];
      h[j][i].undamaged_energy = E0_l[i][j];
    }
  }
  return true;
}
bool avx_available() {
  static const bool yes = __builtin_cpu_supports("avx");
  return yes;
}
#define FDEM_PLAIN_OCT 1
// (GCC 12 warns of its own AVX-512 intrinsics' undefined vectors, a false positive: off for this function)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Eight plain elements at once with AVX-512 (lane j = element J[j]): plain_quad's operations in the same order on
// twice the lanes (AVX-512 arithmetic is IEEE per lane; no FMA), for the same common case; otherwise it writes
// nothing and returns false. Compiled for AVX-512 F and DQ whatever the build's baseline; called only where the CPU
// has them (avx512_available).
__attribute__((target("avx512f,avx512dq,avx2"))) bool plain_oct(const detail::PlainJoint* const J[8], const double* x,
                                                              PointHistory* hist, double* force, double* energy_out) {
  PointHistory* h[8];
  for (int j = 0; j < 8; ++j) h[j] = hist + 3 * std::size_t(J[j]->e);
  const __m512d zero = _mm512_setzero_pd();
  __mmask8 bad = 0;
  for (int i = 0; i < 3; ++i)
    bad |= _mm512_cmp_pd_mask(_mm512_set_pd(h[7][i].damage, h[6][i].damage, h[5][i].damage, h[4][i].damage,
                                            h[3][i].damage, h[2][i].damage, h[1][i].damage, h[0][i].damage),
                              zero, _CMP_NEQ_UQ);
  if (bad) return false;
  const __m512d one = _mm512_set1_pd(1.0), two = _mm512_set1_pd(2.0), three = _mm512_set1_pd(3.0),
                half = _mm512_set1_pd(0.5), two_thirds = _mm512_set1_pd(2.0 / 3.0), sign = _mm512_set1_pd(-0.0);
#define sel(m, a, b) _mm512_mask_blend_pd(m, b, a)
#define neg(a) _mm512_xor_pd(a, sign)
  // Node k of the eight elements as (x_0, ..., x_7) and (y_0, ..., y_7).
  __m512d xa0, ya0, xa1, ya1, xb0, yb0, xb1, yb1;
  __m512d* const vx[4] = {&xa0, &xa1, &xb0, &xb1};
  __m512d* const vy[4] = {&ya0, &ya1, &yb0, &yb1};
  for (int k = 0; k < 4; ++k) {
    __m128d p[8];
    for (int j = 0; j < 8; ++j) p[j] = _mm_loadu_pd(x + 2 * J[j]->n[k]);
    const __m512d lo = _mm512_insertf64x4(
        _mm512_castpd256_pd512(_mm256_insertf128_pd(_mm256_castpd128_pd256(p[0]), p[2], 1)),
        _mm256_insertf128_pd(_mm256_castpd128_pd256(p[4]), p[6], 1), 1);
    const __m512d hi = _mm512_insertf64x4(
        _mm512_castpd256_pd512(_mm256_insertf128_pd(_mm256_castpd128_pd256(p[1]), p[3], 1)),
        _mm256_insertf128_pd(_mm256_castpd128_pd256(p[5]), p[7], 1), 1);
    *vx[k] = _mm512_unpacklo_pd(lo, hi);
    *vy[k] = _mm512_unpackhi_pd(lo, hi);
  }
  __m512d tx = _mm512_sub_pd(_mm512_add_pd(xa1, xb1), _mm512_add_pd(xa0, xb0));
  __m512d ty = _mm512_sub_pd(_mm512_add_pd(ya1, yb1), _mm512_add_pd(ya0, yb0));
  const __m512d len = _mm512_sqrt_pd(_mm512_add_pd(_mm512_mul_pd(tx, tx), _mm512_mul_pd(ty, ty)));
  const __mmask8 has_len = _mm512_cmp_pd_mask(len, zero, _CMP_GT_OQ);
  tx = sel(has_len, _mm512_div_pd(tx, len), one);
  ty = sel(has_len, _mm512_div_pd(ty, len), zero);
  const __m512d nx = ty, ny = neg(tx);
  const __m512d d0x = _mm512_sub_pd(xb0, xa0), d0y = _mm512_sub_pd(yb0, ya0);
  const __m512d d1x = _mm512_sub_pd(xb1, xa1), d1y = _mm512_sub_pd(yb1, ya1);
  const __m512d dx[3] = {d0x, _mm512_mul_pd(half, _mm512_add_pd(d0x, d1x)), d1x};
  const __m512d dy[3] = {d0y, _mm512_mul_pd(half, _mm512_add_pd(d0y, d1y)), d1y};
#define FDEM_OCT(field) \
  _mm512_set_pd(J[7]->field, J[6]->field, J[5]->field, J[4]->field, J[3]->field, J[2]->field, J[1]->field, J[0]->field)
  const __m512d K_n = FDEM_OCT(K_n), inv_K_s = FDEM_OCT(inv_K_s);
  const __m512d o_p = FDEM_OCT(o_p), inv_o_p = FDEM_OCT(inv_o_p), inv_o_t = FDEM_OCT(inv_o_t);
  const __m512d s_p0 = FDEM_OCT(s_p0), inv_s_p0 = FDEM_OCT(inv_s_p0), inv_s_t0 = FDEM_OCT(inv_s_t0);
  const __m512d f_t = FDEM_OCT(f_t), c = FDEM_OCT(c), tan_phi = FDEM_OCT(tan_phi);
  const __m512d w_end = FDEM_OCT(w_end), w_mid = FDEM_OCT(w_mid);
#undef FDEM_OCT
  __m512d Tx[3], Ty[3], trial[3], E0[3];
  __m512d energy = zero;
#pragma GCC unroll 3
  for (int i = 0; i < 3; ++i) {
    const __m512d o = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx[i], nx), _mm512_mul_pd(dy[i], ny)), zero);
    const __m512d s = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(dx[i], tx), _mm512_mul_pd(dy[i], ty)), zero);
    const __mmask8 comp = _mm512_cmp_pd_mask(o, zero, _CMP_LT_OQ);
    const __m512d sc = _mm512_mul_pd(K_n, o);
    const __m512d fs_c =
        _mm512_add_pd(c, _mm512_maskz_mov_pd(_mm512_cmp_pd_mask(sc, zero, _CMP_LT_OQ), _mm512_mul_pd(neg(sc), tan_phi)));
    const __m512d sp_c = _mm512_mul_pd(_mm512_mul_pd(two, fs_c), inv_K_s);
    const __m512d sigma_c = _mm512_maskz_mov_pd(comp, sc);
    const __m512d f_s = sel(comp, fs_c, c);
    const __m512d s_p = sel(comp, sp_c, s_p0);
    const __m512d inv_s_p = sel(comp, _mm512_div_pd(one, sp_c), inv_s_p0);
    const __mmask8 s_neg = _mm512_cmp_pd_mask(s, zero, _CMP_LT_OQ);
    const __m512d a_s = sel(s_neg, neg(s), s);
    const __m512d dI = _mm512_mul_pd(_mm512_sub_pd(o, o_p), inv_o_t);
    const __m512d dII = _mm512_mul_pd(_mm512_sub_pd(a_s, s_p), inv_s_t0);
    bad |= (comp & _mm512_cmp_pd_mask(a_s, s_p, _CMP_GT_OQ)) | _mm512_cmp_pd_mask(dI, zero, _CMP_GT_OQ) |
           _mm512_cmp_pd_mask(dII, zero, _CMP_GT_OQ);
    trial[i] = sel(_mm512_cmp_pd_mask(dI, dII, _CMP_GT_OQ), dI, dII);
    const __m512d u = _mm512_mul_pd(o, inv_o_p);
    const __m512d pre_t = _mm512_mul_pd(_mm512_mul_pd(u, _mm512_sub_pd(two, u)), f_t);
    const __m512d pre_e = _mm512_mul_pd(
        _mm512_mul_pd(_mm512_mul_pd(_mm512_mul_pd(u, u), _mm512_sub_pd(one, _mm512_div_pd(u, three))), f_t), o_p);
    const __m512d top_e =
        _mm512_mul_pd(f_t, _mm512_add_pd(_mm512_mul_pd(o_p, two_thirds), _mm512_sub_pd(o, o_p)));
    const __mmask8 tension = _mm512_cmp_pd_mask(o, zero, _CMP_GT_OQ), top = _mm512_cmp_pd_mask(o, o_p, _CMP_GE_OQ);
    const __m512d t_n0 = _mm512_maskz_mov_pd(tension, sel(top, f_t, pre_t));
    const __m512d e_n0 = _mm512_maskz_mov_pd(tension, sel(top, top_e, pre_e));
    const __m512d y = _mm512_mul_pd(a_s, inv_s_p);
    const __m512d pre_ts = _mm512_mul_pd(_mm512_mul_pd(y, _mm512_sub_pd(two, y)), f_s);
    const __m512d pre_es = _mm512_mul_pd(
        _mm512_mul_pd(_mm512_mul_pd(_mm512_mul_pd(y, y), _mm512_sub_pd(one, _mm512_div_pd(y, three))), f_s), s_p);
    const __m512d top_es =
        _mm512_mul_pd(f_s, _mm512_add_pd(_mm512_mul_pd(s_p, two_thirds), _mm512_sub_pd(a_s, s_p)));
    const __mmask8 top_s = _mm512_cmp_pd_mask(a_s, s_p, _CMP_GE_OQ);
    const __m512d t_s0 = sel(top_s, f_s, pre_ts);
    const __m512d e_s0 = sel(top_s, top_es, pre_es);
    E0[i] = _mm512_add_pd(e_n0, e_s0);
    const __m512d sigma = sel(comp, sigma_c, _mm512_mul_pd(one, t_n0));
    const __m512d tau = _mm512_mul_pd(sel(s_neg, neg(one), one), t_s0);
    const __m512d en =
        _mm512_add_pd(_mm512_mul_pd(one, E0[i]), _mm512_maskz_mov_pd(comp, _mm512_mul_pd(_mm512_mul_pd(half, sigma_c), o)));
    const __m512d w = i == 1 ? w_mid : w_end;
    Tx[i] = _mm512_mul_pd(w, _mm512_add_pd(_mm512_mul_pd(sigma, nx), _mm512_mul_pd(tau, tx)));
    Ty[i] = _mm512_mul_pd(w, _mm512_add_pd(_mm512_mul_pd(sigma, ny), _mm512_mul_pd(tau, ty)));
    energy = _mm512_add_pd(energy, _mm512_mul_pd(w, en));
  }
  if (bad) return false;
  const __m512d fa0x = _mm512_add_pd(Tx[0], _mm512_mul_pd(half, Tx[1]));
  const __m512d fa0y = _mm512_add_pd(Ty[0], _mm512_mul_pd(half, Ty[1]));
  const __m512d fa1x = _mm512_add_pd(Tx[2], _mm512_mul_pd(half, Tx[1]));
  const __m512d fa1y = _mm512_add_pd(Ty[2], _mm512_mul_pd(half, Ty[1]));
  // (f_a0x, f_a0y) per element: element 2l in 128-bit lane l of the unpacklo, 2l + 1 in that of the unpackhi
  alignas(64) double a0[2][8], a1[2][8], en_l[8], trial_l[3][8], E0_l[3][8];
  _mm512_store_pd(a0[0], _mm512_unpacklo_pd(fa0x, fa0y));
  _mm512_store_pd(a0[1], _mm512_unpackhi_pd(fa0x, fa0y));
  _mm512_store_pd(a1[0], _mm512_unpacklo_pd(fa1x, fa1y));
  _mm512_store_pd(a1[1], _mm512_unpackhi_pd(fa1x, fa1y));
#undef sel
#undef neg
  _mm512_store_pd(en_l, energy);
  for (int i = 0; i < 3; ++i) {
    _mm512_store_pd(trial_l[i], trial[i]);
    _mm512_store_pd(E0_l[i], E0[i]);
  }
  const __m128d sign2 = _mm_set1_pd(-0.0);
  for (int j = 0; j < 8; ++j) {
    double* fe = force + 8 * std::size_t(J[j]->e);
    const __m128d p0 = _mm_load_pd(&a0[j & 1][2 * (j >> 1)]), p1 = _mm_load_pd(&a1[j & 1][2 * (j >> 1)]);
    _mm_storeu_pd(fe + 0, p0);
    _mm_storeu_pd(fe + 2, p1);
    _mm_storeu_pd(fe + 4, _mm_xor_pd(p0, sign2));
    _mm_storeu_pd(fe + 6, _mm_xor_pd(p1, sign2));
    energy_out[J[j]->e] = en_l[j];
    for (int i = 0; i < 3; ++i) {
      h[j][i].trial = trial_l[i][j];
      h[j][i].undamaged_energy = E0_l[i][j];
    }
  }
  return true;
}
#pragma GCC diagnostic pop
bool avx512_available() {
  static const bool yes = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq");
  return yes;
}
#else
bool avx_available() { return false; }
bool avx512_available() { return false; }
#endif
#else
bool avx_available() { return false; }
bool avx512_available() { return false; }
#endif  // __SSE2__
}  // namespace

CohesiveSystem::CohesiveSystem(std::vector<CohesiveElement> elems, std::vector<CohesiveProps> props,
                               double thickness, const double* x_reference, int num_nodes)
    : elems_(std::move(elems)), props_(std::move(props)), thickness_(thickness), num_nodes_(num_nodes) {
  std::vector<std::string> problems;
  if (!(thickness_ > 0.0) || !std::isfinite(thickness_)) problems.push_back("thickness must be finite and > 0 (m)");
  const int ne = size();
  // Longest edge per class: the penalty form is too soft first there.
  std::vector<double> h_max(props_.size(), 0.0);
  length_.assign(ne, 0.0);
  ref_mid_.assign(2 * std::size_t(ne), 0.0);
  for (int e = 0; e < ne; ++e) {
    const CohesiveElement& el = elems_[e];
    const std::string where = "cohesive element " + std::to_string(e) + ": ";
    bool nodes_ok = true;
    for (int k = 0; k < 4; ++k)
      if (el.n[k] < 0 || el.n[k] >= num_nodes_) nodes_ok = false;
    if (!nodes_ok) {
      problems.push_back(where + "node index out of range");
      continue;
    }
    if (el.props < 0 || el.props >= int(props_.size())) {
      problems.push_back(where + "properties index " + std::to_string(el.props) + " out of range");
      continue;
    }
    const double* X = x_reference;
    const double hx = X[2 * el.n[1]] - X[2 * el.n[0]], hy = X[2 * el.n[1] + 1] - X[2 * el.n[0] + 1];
    const double h = std::sqrt(hx * hx + hy * hy);
    if (!(h > 0.0)) {
      problems.push_back(where + "zero-length edge");
      continue;
    }
    length_[e] = h;
    ref_mid_[2 * e] = 0.5 * (X[2 * el.n[0]] + X[2 * el.n[1]]);
    ref_mid_[2 * e + 1] = 0.5 * (X[2 * el.n[0] + 1] + X[2 * el.n[1] + 1]);
    for (int k = 0; k < 2; ++k) {
      const double dx = X[2 * el.n[2 + k]] - X[2 * el.n[k]], dy = X[2 * el.n[2 + k] + 1] - X[2 * el.n[k] + 1];
      if (std::sqrt(dx * dx + dy * dy) > 1e-9 * h)
        problems.push_back(where + "nodes " + std::to_string(el.n[k]) + " and " + std::to_string(el.n[2 + k]) +
                           " do not coincide in the reference configuration");
    }
    h_max[el.props] = std::max(h_max[el.props], h);
  }
  for (std::size_t p = 0; p < props_.size(); ++p) {
    if (h_max[p] == 0.0) continue;  // class unused
    for (const std::string& msg : check(props_[p], h_max[p]))
      problems.push_back("cohesive properties " + std::to_string(p) + ": " + msg);
  }
  if (!problems.empty()) {
    std::string all = "invalid cohesive elements:";
    const std::size_t shown = std::min<std::size_t>(problems.size(), 20);
    for (std::size_t i = 0; i < shown; ++i) all += "\n  " + problems[i];
    if (shown < problems.size()) all += "\n  ... and " + std::to_string(problems.size() - shown) + " more";
    throw std::invalid_argument(all);
  }

  law_.resize(ne);
  for (int e = 0; e < ne; ++e) {
    law_[e] = make_law(props_[elems_[e].props], length_[e]);
    has_cap_ = has_cap_ || law_[e].compressive_strength > 0.0;
  }
  // law = "composite": its constants and histories beside the [K25] ones.
  composite_index_.assign(ne, -1);
  for (int e = 0; e < ne; ++e)
    if (props_[elems_[e].props].composite) {
      composite_index_[e] = int(composite_law_.size());
      composite_law_.push_back(make_composite_law(props_[elems_[e].props], length_[e]));
    }
  composite_history_.assign(3 * composite_law_.size(), CompositeHistory{});
  history_.resize(3 * std::size_t(ne));
  for (int e = 0; e < ne; ++e)
    for (int i = 0; i < 3; ++i) history_[3 * e + i] = initial_history(law_[e]);
  force_.assign(8 * std::size_t(ne), 0.0);
  energy_.assign(ne, 0.0);
  dissipated_.assign(ne, 0.0);
  friction_.assign(ne, 0.0);
  break_DI_.assign(ne, 0.0);
  break_DII_.assign(ne, 0.0);
  pending_.assign(ne, 0);
  broken_.assign(ne, 0);
  dormant_.assign(ne, 0);
  offset_.assign(2 * std::size_t(ne), 0.0);
  active_.clear();
  for (int e = 0; e < ne; ++e) {
    if (props_[elems_[e].props].extrinsic) {
      dormant_[e] = 1;
      ++dormant_count_;
    } else {
      active_.push_back(e);
    }
  }

  build_gather();
  build_hot();
}

bool CohesiveSystem::plain_law(int e) const {
  const CohesiveProps& p = props_[elems_[e].props];
  const JointLaw& L = law_[e];
  return !p.extrinsic && !p.composite && !L.mohr_coulomb && !L.keep_friction && !(L.compressive_strength > 0.0) &&
         composite_index_[e] < 0;
}

void CohesiveSystem::build_hot() {
  plain_.clear();
  other_.clear();
  for (int e : active_) {
    if (!plain_law(e)) {
      other_.push_back(e);
      continue;
    }
    const JointLaw& L = law_[e];
    detail::PlainJoint J{};
    for (int k = 0; k < 4; ++k) J.n[k] = elems_[e].n[k];
    J.e = e;
    const double area = length_[e] * thickness_;
    J.w_end = kSimpson[0] * area;
    J.w_mid = kSimpson[1] * area;
    J.K_n = L.normal_stiffness;
    J.inv_K_s = L.inv_shear_stiffness;
    J.o_p = L.opening_peak;
    J.inv_o_p = L.inv_opening_peak;
    J.inv_o_t = L.inv_opening_range;
    J.s_p0 = L.slip_peak0;
    J.inv_s_p0 = L.inv_slip_peak0;
    J.inv_s_t0 = L.inv_slip_range0;
    J.f_t = L.tensile_strength;
    J.c = L.cohesion;
    J.tan_phi = L.tan_friction;
    plain_.push_back(J);
  }
}

void CohesiveSystem::build_gather() {
  // Counting sort of (node, slot) pairs of the intact elements by node; the slots of a node stay in element order,
  // which fixes the summation order whatever the thread count.
  std::vector<int> start(num_nodes_ + 1, 0);
  for (int e : active_)
    for (int k = 0; k < 4; ++k) ++start[elems_[e].n[k] + 1];
  for (int v = 0; v < num_nodes_; ++v) start[v + 1] += start[v];
  std::vector<int> fill(start.begin(), start.end() - 1);
  std::vector<int> slot(std::size_t(start[num_nodes_]));
  for (int e : active_)
    for (int k = 0; k < 4; ++k) slot[fill[elems_[e].n[k]]++] = 8 * e + 2 * k;
  gather_node_.clear();
  gather_start_.assign(1, 0);
  gather_slot_.clear();
  gather_slot_.reserve(slot.size());
  for (int v = 0; v < num_nodes_; ++v) {
    if (start[v + 1] == start[v]) continue;
    gather_node_.push_back(v);
    gather_slot_.insert(gather_slot_.end(), slot.begin() + start[v], slot.begin() + start[v + 1]);
    gather_start_.push_back(int(gather_slot_.size()));
  }
  stale_slots_ = 0;
}

std::vector<double> CohesiveSystem::node_stiffness(const int* rep) const {
  // Gershgorin bound of one element's stiffness row for a node: the 2x2 block R^T diag(K_n, K_s) R has absolute row
  // sum <= K_max + |K_n - K_s| / 2, and the Simpson-lumped couplings of a node to the 4 nodes sum to h t (1/3 + 1/6 +
  // 1/3 + 1/6) = h t. So omega^2 <= k / m with k = h t (K_max + |K_n - K_s|/2) summed over the node's elements,
  // and central difference is stable for dt <= 2 / omega = 2 sqrt(m / k) (fdem/README.md 'Time step').
  std::vector<double> k_node(num_nodes_, 0.0);
  for (int e : active_) {
    const JointLaw& L = law_[e];
    const double K = std::max(L.normal_stiffness, L.shear_stiffness) +
                     0.5 * std::abs(L.normal_stiffness - L.shear_stiffness);
    const double k = length_[e] * thickness_ * K;
    for (int j = 0; j < 4; ++j) k_node[rep ? rep[elems_[e].n[j]] : elems_[e].n[j]] += k;
  }
  return k_node;
}

double CohesiveSystem::stable_dt(const double* node_mass, const int* rep) const {
  const std::vector<double> k_node = node_stiffness(rep);
  double dt = std::numeric_limits<double>::infinity();
  for (int v = 0; v < num_nodes_; ++v)
    if (k_node[v] > 0.0 && node_mass[v] > 0.0) dt = std::min(dt, 2.0 * std::sqrt(node_mass[v] / k_node[v]));
  return dt;
}

void CohesiveSystem::add_forces(const double* x, double* f) {
  const int na = int(active_.size());
  const int np = int(plain_.size()), no = int(other_.size());
  const int rows = int(gather_node_.size());
  int pending = 0, pending_plain = 0;
  const int lanes = lanes_ >= 8 && avx512_available() ? 8 : (lanes_ >= 4 && avx_available() ? 4 : std::min(lanes_, 2));
  (void)lanes;  // (read only where the build has SSE2 or the AVX kernel)
  // One plain element (the same arithmetic as the general loop below with evaluate_point; see plain_point). Returns
  // whether it is pending. An element that was pending is still fully damaged (damage never decreases), so pending_
  // is read only for those.
  auto plain_element = [&](const detail::PlainJoint& J) -> int {
    const int e = J.e;
    const int* n = J.n;
    const ElementFrame fr = element_frame(x, n);
    const double tx = fr.tx, ty = fr.ty, nx = fr.nx, ny = fr.ny;
    const double* dx = fr.dx;
    const double* dy = fr.dy;
    PointHistory* h = &history_[3 * std::size_t(e)];
    double Tx[3], Ty[3];
    double energy = 0.0, dissipated = 0.0, DI = 0.0, DII = 0.0;
    bool all_broken = true, damaged = false;
    for (int i = 0; i < 3; ++i) {
      // (+ 0.0: the insertion offset of the general loop, 0 for an intrinsic element)
      const double o = dx[i] * nx + dy[i] * ny + 0.0;
      const double s = dx[i] * tx + dy[i] * ty + 0.0;
      const double D_old = h[i].damage;
      const PlainPoint r = plain_point(J, law_[e], o, s, h[i]);
      const double w = i == 1 ? J.w_mid : J.w_end;
      Tx[i] = w * (r.sigma * nx + r.tau * tx);
      Ty[i] = w * (r.sigma * ny + r.tau * ty);
      energy += w * r.energy;
      dissipated += w * r.dissipated;
      DI += r.damage_I;
      DII += r.damage_II;
      all_broken = all_broken && r.D >= 1.0;
      damaged = damaged || r.D > D_old;
    }
    store_forces(Tx, Ty, &force_[8 * std::size_t(e)]);
    energy_[e] = energy;
    // Without a damage increment every point dissipated +0.0 (and the element's friction is +0.0 at every step):
    // adding them would leave the sums as they are.
    if (damaged) dissipated_[e] += dissipated;
    if (!all_broken) return 0;
    if (!pending_[e]) {
      pending_[e] = 1;
      break_DI_[e] = DI / 3.0;
      break_DII_[e] = DII / 3.0;
    }
    return 1;
  };

#if defined(__SSE2__)
  // Two plain elements at once, lane 0 = A, lane 1 = B, each lane the operations of plain_element in the same order
  // (SSE2 arithmetic is IEEE per lane, as the scalar one), with the branches as selects. It covers the common case
  // only: every point of both elements undamaged and staying so (trial damage <= 0, so z = 1 and nothing is
  // dissipated) and not a compressed point past its shear peak. Otherwise it writes nothing and returns false, and
  // the caller evaluates both elements with plain_element.
  auto plain_pair = [&](const detail::PlainJoint& A, const detail::PlainJoint& B) -> bool {
    PointHistory* hA = &history_[3 * std::size_t(A.e)];
    PointHistory* hB = &history_[3 * std::size_t(B.e)];
    const __m128d zero = _mm_setzero_pd();
    __m128d bad = _mm_or_pd(_mm_or_pd(_mm_cmpneq_pd(_mm_set_pd(hB[0].damage, hA[0].damage), zero),
                                      _mm_cmpneq_pd(_mm_set_pd(hB[1].damage, hA[1].damage), zero)),
                            _mm_cmpneq_pd(_mm_set_pd(hB[2].damage, hA[2].damage), zero));
    if (_mm_movemask_pd(bad)) return false;
    const __m128d one = _mm_set1_pd(1.0), two = _mm_set1_pd(2.0), three = _mm_set1_pd(3.0), half = _mm_set1_pd(0.5),
                  two_thirds = _mm_set1_pd(2.0 / 3.0), sign = _mm_set1_pd(-0.0);
    auto sel = [](__m128d m, __m128d a, __m128d b) { return _mm_or_pd(_mm_and_pd(m, a), _mm_andnot_pd(m, b)); };
    auto neg = [sign](__m128d a) { return _mm_xor_pd(a, sign); };
    // Node k of A and of B as (x_A, x_B) and (y_A, y_B).
    auto node = [&](int k, __m128d& vx, __m128d& vy) {
      const __m128d pa = _mm_loadu_pd(x + 2 * A.n[k]), pb = _mm_loadu_pd(x + 2 * B.n[k]);
      vx = _mm_unpacklo_pd(pa, pb);
      vy = _mm_unpackhi_pd(pa, pb);
    };
    __m128d xa0, ya0, xa1, ya1, xb0, yb0, xb1, yb1;
    node(0, xa0, ya0);
    node(1, xa1, ya1);
    node(2, xb0, yb0);
    node(3, xb1, yb1);
    __m128d tx = _mm_sub_pd(_mm_add_pd(xa1, xb1), _mm_add_pd(xa0, xb0));
    __m128d ty = _mm_sub_pd(_mm_add_pd(ya1, yb1), _mm_add_pd(ya0, yb0));
    const __m128d len = _mm_sqrt_pd(_mm_add_pd(_mm_mul_pd(tx, tx), _mm_mul_pd(ty, ty)));
    const __m128d has_len = _mm_cmpgt_pd(len, zero);
    tx = sel(has_len, _mm_div_pd(tx, len), one);
    ty = sel(has_len, _mm_div_pd(ty, len), zero);
    const __m128d nx = ty, ny = neg(tx);
    const __m128d d0x = _mm_sub_pd(xb0, xa0), d0y = _mm_sub_pd(yb0, ya0);
    const __m128d d1x = _mm_sub_pd(xb1, xa1), d1y = _mm_sub_pd(yb1, ya1);
    const __m128d dx[3] = {d0x, _mm_mul_pd(half, _mm_add_pd(d0x, d1x)), d1x};
    const __m128d dy[3] = {d0y, _mm_mul_pd(half, _mm_add_pd(d0y, d1y)), d1y};
    auto pair_of = [](double a, double b) { return _mm_set_pd(b, a); };
    const __m128d K_n = pair_of(A.K_n, B.K_n), inv_K_s = pair_of(A.inv_K_s, B.inv_K_s);
    const __m128d o_p = pair_of(A.o_p, B.o_p), inv_o_p = pair_of(A.inv_o_p, B.inv_o_p);
    const __m128d inv_o_t = pair_of(A.inv_o_t, B.inv_o_t);
    const __m128d s_p0 = pair_of(A.s_p0, B.s_p0), inv_s_p0 = pair_of(A.inv_s_p0, B.inv_s_p0);
    const __m128d inv_s_t0 = pair_of(A.inv_s_t0, B.inv_s_t0);
    const __m128d f_t = pair_of(A.f_t, B.f_t), c = pair_of(A.c, B.c), tan_phi = pair_of(A.tan_phi, B.tan_phi);
    const __m128d w_end = pair_of(A.w_end, B.w_end), w_mid = pair_of(A.w_mid, B.w_mid);
    __m128d Tx[3], Ty[3], trial[3], E0[3];
    __m128d energy = zero;
#pragma GCC unroll 3
    for (int i = 0; i < 3; ++i) {
      const __m128d o = _mm_add_pd(_mm_add_pd(_mm_mul_pd(dx[i], nx), _mm_mul_pd(dy[i], ny)), zero);
      const __m128d s = _mm_add_pd(_mm_add_pd(_mm_mul_pd(dx[i], tx), _mm_mul_pd(dy[i], ty)), zero);
      // compression: the penalty, Mohr-Coulomb f_s and the slip at peak
      const __m128d comp = _mm_cmplt_pd(o, zero);
      const __m128d sc = _mm_mul_pd(K_n, o);
      const __m128d fs_c = _mm_add_pd(c, _mm_and_pd(_mm_cmplt_pd(sc, zero), _mm_mul_pd(neg(sc), tan_phi)));
      const __m128d sp_c = _mm_mul_pd(_mm_mul_pd(two, fs_c), inv_K_s);
      const __m128d sigma_c = _mm_and_pd(comp, sc);
      const __m128d f_s = sel(comp, fs_c, c);
      const __m128d s_p = sel(comp, sp_c, s_p0);
      const __m128d inv_s_p = sel(comp, _mm_div_pd(one, sp_c), inv_s_p0);
      const __m128d s_neg = _mm_cmplt_pd(s, zero);
      const __m128d a_s = sel(s_neg, neg(s), s);
      const __m128d dI = _mm_mul_pd(_mm_sub_pd(o, o_p), inv_o_t);
      const __m128d dII = _mm_mul_pd(_mm_sub_pd(a_s, s_p), inv_s_t0);
      bad = _mm_or_pd(bad, _mm_or_pd(_mm_and_pd(comp, _mm_cmpgt_pd(a_s, s_p)),
                                     _mm_or_pd(_mm_cmpgt_pd(dI, zero), _mm_cmpgt_pd(dII, zero))));
      trial[i] = sel(_mm_cmpgt_pd(dI, dII), dI, dII);
      // tension: pre-peak curve or plateau
      const __m128d u = _mm_mul_pd(o, inv_o_p);
      const __m128d pre_t = _mm_mul_pd(_mm_mul_pd(u, _mm_sub_pd(two, u)), f_t);
      const __m128d pre_e = _mm_mul_pd(
          _mm_mul_pd(_mm_mul_pd(_mm_mul_pd(u, u), _mm_sub_pd(one, _mm_div_pd(u, three))), f_t), o_p);
      const __m128d top_e = _mm_mul_pd(f_t, _mm_add_pd(_mm_mul_pd(o_p, two_thirds), _mm_sub_pd(o, o_p)));
      const __m128d tension = _mm_cmpgt_pd(o, zero), top = _mm_cmpge_pd(o, o_p);
      const __m128d t_n0 = _mm_and_pd(tension, sel(top, f_t, pre_t));
      const __m128d e_n0 = _mm_and_pd(tension, sel(top, top_e, pre_e));
      // shear: pre-peak curve or plateau
      const __m128d y = _mm_mul_pd(a_s, inv_s_p);
      const __m128d pre_ts = _mm_mul_pd(_mm_mul_pd(y, _mm_sub_pd(two, y)), f_s);
      const __m128d pre_es = _mm_mul_pd(
          _mm_mul_pd(_mm_mul_pd(_mm_mul_pd(y, y), _mm_sub_pd(one, _mm_div_pd(y, three))), f_s), s_p);
      const __m128d top_es = _mm_mul_pd(f_s, _mm_add_pd(_mm_mul_pd(s_p, two_thirds), _mm_sub_pd(a_s, s_p)));
      const __m128d top_s = _mm_cmpge_pd(a_s, s_p);
      const __m128d t_s0 = sel(top_s, f_s, pre_ts);
      const __m128d e_s0 = sel(top_s, top_es, pre_es);
      E0[i] = _mm_add_pd(e_n0, e_s0);
      // z = 1 (undamaged)
      const __m128d sigma = sel(comp, sigma_c, _mm_mul_pd(one, t_n0));
      const __m128d tau = _mm_mul_pd(sel(s_neg, neg(one), one), t_s0);
      const __m128d en = _mm_add_pd(_mm_mul_pd(one, E0[i]), _mm_and_pd(comp, _mm_mul_pd(_mm_mul_pd(half, sigma_c), o)));
      const __m128d w = i == 1 ? w_mid : w_end;
      Tx[i] = _mm_mul_pd(w, _mm_add_pd(_mm_mul_pd(sigma, nx), _mm_mul_pd(tau, tx)));
      Ty[i] = _mm_mul_pd(w, _mm_add_pd(_mm_mul_pd(sigma, ny), _mm_mul_pd(tau, ty)));
      energy = _mm_add_pd(energy, _mm_mul_pd(w, en));
    }
    if (_mm_movemask_pd(bad)) return false;
    const __m128d fa0x = _mm_add_pd(Tx[0], _mm_mul_pd(half, Tx[1])), fa0y = _mm_add_pd(Ty[0], _mm_mul_pd(half, Ty[1]));
    const __m128d fa1x = _mm_add_pd(Tx[2], _mm_mul_pd(half, Tx[1])), fa1y = _mm_add_pd(Ty[2], _mm_mul_pd(half, Ty[1]));
    double* fA = &force_[8 * std::size_t(A.e)];
    double* fB = &force_[8 * std::size_t(B.e)];
    // (f_a0x, f_a0y), (f_a1x, f_a1y) and their negatives for the B side, one element per lane
    const __m128d a0A = _mm_unpacklo_pd(fa0x, fa0y), a0B = _mm_unpackhi_pd(fa0x, fa0y);
    const __m128d a1A = _mm_unpacklo_pd(fa1x, fa1y), a1B = _mm_unpackhi_pd(fa1x, fa1y);
    _mm_storeu_pd(fA + 0, a0A);
    _mm_storeu_pd(fA + 2, a1A);
    _mm_storeu_pd(fA + 4, neg(a0A));
    _mm_storeu_pd(fA + 6, neg(a1A));
    _mm_storeu_pd(fB + 0, a0B);
    _mm_storeu_pd(fB + 2, a1B);
    _mm_storeu_pd(fB + 4, neg(a0B));
    _mm_storeu_pd(fB + 6, neg(a1B));
    _mm_storel_pd(&energy_[A.e], energy);
    _mm_storeh_pd(&energy_[B.e], energy);
    for (int i = 0; i < 3; ++i) {
      _mm_storel_pd(&hA[i].trial, trial[i]);
      _mm_storeh_pd(&hB[i].trial, trial[i]);
      _mm_storel_pd(&hA[i].undamaged_energy, E0[i]);
      _mm_storeh_pd(&hB[i].undamaged_energy, E0[i]);
    }
    return true;
  };
#endif

  // One parallel region for all loops: on a shared machine every fork/join can cost a scheduler time slice.
#pragma omp parallel if (na >= kMinParallel)
  {
  // Plain group, in quads (lanes_ == 4), pairs (2) or one by one (1): the same bits whichever evaluates an element.
  // Integer reductions: exact, so the count does not depend on the thread count.
  // (in groups of eight: a quad or a pair that cannot go falls back as before, so the groups do not change the bits)
  const int octs = (np + 7) / 8;
#pragma omp for schedule(static) reduction(+ : pending_plain) nowait
  for (int q = 0; q < octs; ++q) {
    const int g0 = 8 * q, g1 = std::min(g0 + 8, np);
    // ask for the records four groups ahead and the point histories of the elements two groups ahead
    if (g0 + 40 <= np)
      for (int j = 0; j < 8; ++j) {
        const char* rec = reinterpret_cast<const char*>(&plain_[g0 + 32 + j]);
        __builtin_prefetch(rec), __builtin_prefetch(rec + 64);
        const char* hp = reinterpret_cast<const char*>(&history_[3 * std::size_t(plain_[g0 + 16 + j].e)]);
        __builtin_prefetch(hp), __builtin_prefetch(hp + 64), __builtin_prefetch(hp + 119);
      }
#if defined(FDEM_PLAIN_OCT)
    if (lanes >= 8 && g1 - g0 == 8) {
      const detail::PlainJoint* const J[8] = {&plain_[g0],     &plain_[g0 + 1], &plain_[g0 + 2], &plain_[g0 + 3],
                                              &plain_[g0 + 4], &plain_[g0 + 5], &plain_[g0 + 6], &plain_[g0 + 7]};
      if (plain_oct(J, x, history_.data(), force_.data(), energy_.data())) continue;
    }
#endif
    for (int k0 = g0; k0 < g1; k0 += 4) {
    const int k1 = std::min(k0 + 4, g1);
#if defined(FDEM_PLAIN_QUAD)
    if (lanes >= 4 && k1 - k0 == 4) {
      const detail::PlainJoint* const J[4] = {&plain_[k0], &plain_[k0 + 1], &plain_[k0 + 2], &plain_[k0 + 3]};
      if (plain_quad(J, x, history_.data(), force_.data(), energy_.data())) continue;
    }
#endif
    for (int k = k0; k < k1; k += 2) {
      if (k + 1 < k1) {
#if defined(__SSE2__)
        if (lanes >= 2 && plain_pair(plain_[k], plain_[k + 1])) continue;
#endif
        pending_plain += plain_element(plain_[k]) + plain_element(plain_[k + 1]);
      } else {
        pending_plain += plain_element(plain_[k]);
      }
    }
    }
  }

  // The other laws.
#pragma omp for schedule(static) reduction(+ : pending)
  for (int k = 0; k < no; ++k) {
    const int e = other_[k];
    const int* n = elems_[e].n;
    const ElementFrame fr = element_frame(x, n);
    const double tx = fr.tx, ty = fr.ty, nx = fr.nx, ny = fr.ny;
    const double* dx = fr.dx;
    const double* dy = fr.dy;

    const JointLaw& L = law_[e];
    const int ci = composite_index_[e];  // law = "composite" when >= 0
    const double area = length_[e] * thickness_;
    double Tx[3], Ty[3];
    double energy = 0.0, dissipated = 0.0, friction = 0.0, DI = 0.0, DII = 0.0;
    bool all_broken = true;
    for (int i = 0; i < 3; ++i) {
      const double o = dx[i] * nx + dy[i] * ny + offset_[2 * std::size_t(e)];
      const double s = dx[i] * tx + dy[i] * ty + offset_[2 * std::size_t(e) + 1];
      const PointResponse r =
          ci < 0 ? evaluate_point(L, o, s, history_[3 * e + i])
                 : evaluate_composite(composite_law_[ci], o, s, composite_history_[3 * std::size_t(ci) + i]);
      history_[3 * e + i] = r.history;
      const double w = kSimpson[i] * area;
      Tx[i] = w * (r.sigma * nx + r.tau * tx);
      Ty[i] = w * (r.sigma * ny + r.tau * ty);
      energy += w * r.energy;
      dissipated += w * r.dissipated;
      friction += w * r.friction_dissipated;
      DI += r.damage_I;
      DII += r.damage_II;
      all_broken = all_broken && r.history.damage >= 1.0;
    }
    store_forces(Tx, Ty, &force_[8 * std::size_t(e)]);
    energy_[e] = energy;
    dissipated_[e] += dissipated;
    friction_[e] += friction;
    if (all_broken && !pending_[e]) {
      pending_[e] = 1;
      break_DI_[e] = DI / 3.0;
      break_DII_[e] = DII / 3.0;
    }
    pending += pending_[e];
  }
  // (implicit barrier: every element's forces are in force_ before any node gathers them)

  // Gather: each node sums its element contributions in element order; nodes are independent.
  // The slots of a node lie anywhere in force_ (element order): each one is asked for kAhead slots before it is read.
  const int last_slot = int(gather_slot_.size()) - 1;
  constexpr int kAhead = 24;
#pragma omp for schedule(static)
  for (int r = 0; r < rows; ++r) {
    double sx = 0.0, sy = 0.0;
    for (int k = gather_start_[r]; k < gather_start_[r + 1]; ++k) {
      __builtin_prefetch(&force_[gather_slot_[std::min(k + kAhead, last_slot)]]);
      sx += force_[gather_slot_[k]];
      sy += force_[gather_slot_[k] + 1];
    }
    const int v = gather_node_[r];
    f[2 * v] += sx;
    f[2 * v + 1] += sy;
  }
  }  // omp parallel
  pending_count_ = pending + pending_plain;
}

}  // namespace fdem::fracture
