// fdem/node_update.cpp: the node update kernel (fdem/node_update.hpp).
#include "fdem/node_update.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>
#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

#include "fdem/sim_detail.hpp"

namespace fdem {

using sim_detail::kBlock;
using sim_detail::share_begin;

namespace {

// A block's running books (J, N, m^2/s^2), each summed in unit order.
struct Books {
    double work = 0, damping = 0, unbalanced = 0, scale = 0, kinetic = 0, work_half = 0, damping_half = 0, mass = 0,
           mass_half = 0;
    double nonfinite = 0;  // v - v summed: 0 while every new velocity is finite, NaN after an inf or a NaN
    double v2 = 0;  // the largest |v|^2 of the block's units (a NaN passed over, as std::max(v2, NaN) = v2)
};

// One unit u; compiled for each combination of three compile-time constants, so that each model runs only the parts
// it has: kTied (units of tied copies, else plain nodes without the units' indirections), kFilter (the filtered
// local damping's moving means, vref) and kMass (mass-proportional damping, hm > 0).
template <bool kTied, bool kFilter, bool kMass>
inline void unit_update(const NodeUpdate& a, int u, Books& s) {
    const int* u_start = a.u_start;
    const int* u_node = a.u_node;
    const int* u_slot = a.u_slot;
    const double* tf = a.tri_forces;
    const int* inc_ptr = a.inc_ptr;
    const int* inc_idx = a.inc_idx;
    const double* mass = a.mass;
    const double* gmass = a.grav_mass;
    const double* fext = a.f_ext;
    const unsigned char* loaded = a.loaded;
    double* fmod = a.f_mod;
    const std::uint8_t* kind = a.dof_kind;
    double* reac = a.reaction;
    double* xw = a.x;
    double* vw = a.v;
    double* vref = a.v_ref;
    const double dt = a.dt, dtv = a.dtv, alpha = a.local_damping, mass_damp = a.mass_damping, hm = a.hm, wf = a.wf;
    const bool change = a.dt_before != 0 && a.dt_before != dt;  // (the same for every unit of the step)
    const int j0 = kTied ? u_start[u] : u, j1 = kTied ? u_start[u + 1] : u + 1;
    // the resultant: internal (joints, contact, triangles) and external (loads, gravity) sums
    double S[4] = {0, 0, 0, 0};
    for (int j = j0; j < j1; ++j) {
        const int k = kTied ? u_node[j] : j;
        double fi0 = fmod[2 * k], fi1 = fmod[2 * k + 1];
        // (without joints and contact no node gets a module force, and the lines are not written; with
        // them every one is reset: a test of which had one was a branch that a third of the nodes
        // mispredicted. The sums never make a -0.0, so the reset keeps the bits of one that tests.)
        if (a.reset_fmod) fmod[2 * k] = 0, fmod[2 * k + 1] = 0;
        if (kTied && u_slot[j] >= 0) {
            const double* r = tf + 2 * static_cast<std::size_t>(u_slot[j]);
            fi0 += r[0], fi1 += r[1];
        } else {
            for (int i = inc_ptr[k]; i < inc_ptr[k + 1]; ++i) {
                const double* r = tf + 2 * static_cast<std::size_t>(inc_idx[i]);
                fi0 += r[0], fi1 += r[1];
            }
        }
        // (f_ext_ is +0.0 off the loaded nodes, so 0.0 + m g is the same sum without reading it)
        const bool ld = loaded[k] != 0;
        const double fe0 = (ld ? fext[2 * k] : 0.0) + gmass[k] * a.gx, fe1 = (ld ? fext[2 * k + 1] : 0.0) + gmass[k] * a.gy;
        s.scale += std::abs(fi0) + std::abs(fe0);
        s.scale += std::abs(fi1) + std::abs(fe1);
        S[0] += fi0, S[1] += fi1, S[2] += fe0, S[3] += fe1;
    }
    const int k0 = kTied ? u_node[j0] : j0;
    const double M = kTied ? a.u_mass[u] : mass[k0];
    const double im = kTied ? a.u_inv[u] : a.inv_mass[k0];
    double vn[2], xn[2], vr[2];  // the unit's new velocity, position and filter mean, written to its members below
    // (unrolled: vn, xn and vr stay in registers; a loop over c stored them one double at a time and read them
    // back as pairs below, a stalled store forwarding on every unit)
#pragma GCC unroll 2
    for (int c = 0; c < 2; ++c) {
        const int d0 = 2 * k0 + c;
        const double f = S[c] + S[2 + c], fe = S[2 + c];
        const double vold = vw[d0];
        double vnew;
        if (kind[d0] == 0) {
            // [C79] local damping: -alpha |f| sign(v), or sign(v - vref) with the filter. (Two selects,
            // which the compiler makes without branches: the sign of v is a coin toss on a chattering wall.)
            const double vrel = kFilter ? vold - vref[d0] : vold;
            const double af = alpha * std::abs(f);
            const double fd_pos = vrel > 0 ? -af : 0.0;
            const double fd = vrel < 0 ? af : fd_pos;
            // (without mass damping the same bits without the division: (1 - 0) v = v, x / 1 = x)
            vnew = kMass ? ((1 - hm) * vold + dtv * (f + fd) * im) / (1 + hm) : vold + dtv * (f + fd) * im;
            const double vbar = 0.5 * (vold + vnew);
            // (a change of step: f over (x^{n+1} - x^{n-1}) / 2, node_update.hpp)
            const double span = change ? 0.5 * (a.dt_before * vold + dt * vnew) : 0.0;
            s.work += change ? fe * span : dt * fe * vbar;
            s.damping -= change ? fd * span : dt * fd * vbar;
            s.work_half += 0.5 * dt * fe * vnew;
            s.damping_half -= 0.5 * dt * fd * vnew;
            if (kMass) {  // -a m vbar: work dt (-a m vbar) vbar, and its share up to t^n
                const double fm = -mass_damp * M * vbar;
                s.mass -= change ? fm * span : dt * fm * vbar;
                s.mass_half -= 0.5 * dt * fm * vnew;
            }
            s.unbalanced += std::abs(f);
        } else {
            vnew = kind[d0] == 1 ? 0.0 : a.dof_velocity[d0];
            for (int j = j0; j < j1; ++j) {
                const int k = kTied ? u_node[j] : j;
                const double w = kTied ? a.tie_w[k] : 1.0;
                const double R = mass[k] * (vnew - vold) / dtv - w * f;
                reac[2 * k + c] = R;
                s.work += change ? (w * fe + R) * (0.5 * (a.dt_before * vold + dt * vnew))
                                 : dt * (w * fe + R) * 0.5 * (vold + vnew);
                s.work_half += 0.5 * dt * (w * fe + R) * vnew;
            }
        }
        s.kinetic += 0.5 * M * vold * vnew;
        s.nonfinite += vnew - vnew;
        vn[c] = vnew;
        xn[c] = xw[d0] + dt * vnew;  // the members' positions are the same bits
        vr[c] = kFilter ? vref[d0] + wf * (vnew - vref[d0]) : 0.0;
    }
    s.v2 = std::max(s.v2, vn[0] * vn[0] + vn[1] * vn[1]);  // (every member's |v|^2, the bits of v written below)
    for (int j = j0; j < j1; ++j) {
        const int d = 2 * (kTied ? u_node[j] : j);
        vw[d] = vn[0], vw[d + 1] = vn[1];
        xw[d] = xn[0], xw[d + 1] = xn[1];
        if (kFilter) vref[d] = vr[0], vref[d + 1] = vr[1];
    }
}

// The first unit of [u0, u1) (in loop order) with a non-finite velocity, looked for only when there is one.
template <bool kTied>
int first_bad(const NodeUpdate& a, int u0, int u1, double nonfinite) {
    int bad = -1;
    if (!(nonfinite == 0))
        for (int u = u0; u < u1 && bad < 0; ++u) {
            const int k0 = kTied ? a.u_node[a.u_start[u]] : u;
            if (!std::isfinite(a.v[2 * k0]) || !std::isfinite(a.v[2 * k0 + 1])) bad = k0;
        }
    return bad;
}

// One block, unit by unit.
template <bool kTied, bool kFilter, bool kMass>
void node_block(const NodeUpdate& a, int b, NodeBlockSums& out) {
    const int u0 = kTied ? a.u_block[b] : b * kBlock, u1 = kTied ? a.u_block[b + 1] : std::min(a.n_units, (b + 1) * kBlock);
    Books s;
    for (int u = u0; u < u1; ++u) unit_update<kTied, kFilter, kMass>(a, u, s);
    out.work = s.work, out.damping = s.damping, out.unbalanced = s.unbalanced, out.scale = s.scale;
    out.kinetic = s.kinetic, out.work_half = s.work_half, out.damping_half = s.damping_half, out.mass = s.mass,
    out.mass_half = s.mass_half;
    out.v2 = s.v2;
    out.bad = first_bad<kTied>(a, u0, u1, s.nonfinite);
}

#if defined(__GNUC__) && defined(__x86_64__)
#define FDEM_NODE_AVX 1
// A plain node between the pairs of plain_node_block: unit_update's scalar code on the books that block keeps packed,
// g[0..9] = work, work_half, damping, damping_half, unbalanced, kinetic, scale, nonfinite, mass, mass_half.
template <bool kFilter, bool kMass>
void scalar_node(const NodeUpdate& a, int k, double* g, double& v2) {
    Books s;
    s.work = g[0], s.work_half = g[1], s.damping = g[2], s.damping_half = g[3], s.unbalanced = g[4], s.kinetic = g[5];
    s.scale = g[6], s.nonfinite = g[7], s.mass = g[8], s.mass_half = g[9], s.v2 = v2;
    unit_update<false, kFilter, kMass>(a, k, s);
    g[0] = s.work, g[1] = s.work_half, g[2] = s.damping, g[3] = s.damping_half, g[4] = s.unbalanced, g[5] = s.kinetic;
    g[6] = s.scale, g[7] = s.nonfinite, g[8] = s.mass, g[9] = s.mass_half, v2 = s.v2;
}

// acc_j = (((acc_j + t_j[0]) + t_j[1]) + t_j[2]) + t_j[3] for the four books j of acc: the terms of two nodes (lanes
// x, y of the first node, x, y of the second), each book summed in unit_update's order.
__attribute__((target("avx"), always_inline)) inline void add_terms(__m256d& acc, __m256d t0, __m256d t1, __m256d t2,
                                                                     __m256d t3) {
    const __m256d lo01 = _mm256_unpacklo_pd(t0, t1), hi01 = _mm256_unpackhi_pd(t0, t1);
    const __m256d lo23 = _mm256_unpacklo_pd(t2, t3), hi23 = _mm256_unpackhi_pd(t2, t3);
    acc = _mm256_add_pd(acc, _mm256_permute2f128_pd(lo01, lo23, 0x20));
    acc = _mm256_add_pd(acc, _mm256_permute2f128_pd(hi01, hi23, 0x20));
    acc = _mm256_add_pd(acc, _mm256_permute2f128_pd(lo01, lo23, 0x31));
    acc = _mm256_add_pd(acc, _mm256_permute2f128_pd(hi01, hi23, 0x31));
}

// (p[0], p[0], p[1], p[1])
__attribute__((target("avx"), always_inline)) inline __m256d pairs(const double* p) {
    return _mm256_permute_pd(_mm256_broadcast_pd(reinterpret_cast<const __m128d*>(p)), 0xC);
}

// node_block for plain nodes (no tied units), two nodes at a time with AVX, lanes (x, y) of one node and (x, y) of
// the next: every lane does unit_update's scalar operations in the same order (IEEE per lane, no contraction; a book
// that unit_update subtracts from adds the negated term, the same bits), and each book takes its terms in
// unit_update's order (add_terms), so the results are the same bits. A pair with a fixed or prescribed DOF, and a
// block's odd last node, go through unit_update (scalar_node). Compiled for AVX whatever the build's baseline;
// called only where the CPU has it.
template <bool kFilter, bool kMass>
__attribute__((target("avx"))) void plain_node_block(const NodeUpdate& a, int b, NodeBlockSums& out) {
    const int u0 = b * kBlock, u1 = std::min(a.n_units, (b + 1) * kBlock);
    const double* tf = a.tri_forces;
    const int* inc_ptr = a.inc_ptr;
    const int* inc_idx = a.inc_idx;
    const double* fext = a.f_ext;
    const unsigned char* loaded = a.loaded;
    const std::uint8_t* kind = a.dof_kind;
    const double* mass = a.mass;
    const double* gmass = a.grav_mass;
    const double* inv_mass = a.inv_mass;
    double* fmod = a.f_mod;
    const bool reset_fmod = a.reset_fmod;
    double* xw = a.x;
    double* vw = a.v;
    double* vref = a.v_ref;
    const __m256d zero = _mm256_setzero_pd(), sign = _mm256_set1_pd(-0.0), half = _mm256_set1_pd(0.5);
    const __m256d dt = _mm256_set1_pd(a.dt), dtv = _mm256_set1_pd(a.dtv), alpha = _mm256_set1_pd(a.local_damping);
    const __m256d hdt = _mm256_set1_pd(0.5 * a.dt), g = _mm256_set_pd(a.gy, a.gx, a.gy, a.gx);
    const __m256d one_m_hm = _mm256_set1_pd(1 - a.hm), one_p_hm = _mm256_set1_pd(1 + a.hm), wf = _mm256_set1_pd(a.wf);
    const __m256d neg_mass_damp = _mm256_set1_pd(-a.mass_damping);
    // the books, four to a register: (work, work_half, damping, damping_half), (unbalanced, kinetic, scale,
    // nonfinite), (mass, mass_half, -, -)
    alignas(32) double gb[12];
    __m256d b1 = zero, b2 = zero, b3 = zero;
    __m128d v2 = _mm_setzero_pd();  // lane 0: the largest |v|^2
    int k = u0;
    for (; k < u1; k += 2) {
        std::uint32_t kinds = 1;  // the four DOFs' kinds
        if (k + 1 < u1) std::memcpy(&kinds, kind + 2 * k, sizeof kinds);
        if (kinds != 0) {  // a held DOF, or the block's odd last node
            _mm256_store_pd(gb, b1), _mm256_store_pd(gb + 4, b2), _mm256_store_pd(gb + 8, b3);
            double vv = _mm_cvtsd_f64(v2);
            scalar_node<kFilter, kMass>(a, k, gb, vv);
            if (k + 1 < u1) scalar_node<kFilter, kMass>(a, k + 1, gb, vv);
            b1 = _mm256_load_pd(gb), b2 = _mm256_load_pd(gb + 4), b3 = _mm256_load_pd(gb + 8);
            v2 = _mm_set_sd(vv);
            continue;
        }
        double* fm = fmod + 2 * k;
        __m128d fi0 = _mm_loadu_pd(fm), fi1 = _mm_loadu_pd(fm + 2);
        if (reset_fmod) _mm256_storeu_pd(fm, zero);
        const int i0 = inc_ptr[k], i1 = inc_ptr[k + 1], i2 = inc_ptr[k + 2];
        if (i1 - i0 == 1 && i2 - i1 == 1) {  // one triangle each (every node of a mesh split at every edge)
            fi0 = _mm_add_pd(fi0, _mm_loadu_pd(tf + 2 * static_cast<std::size_t>(inc_idx[i0])));
            fi1 = _mm_add_pd(fi1, _mm_loadu_pd(tf + 2 * static_cast<std::size_t>(inc_idx[i1])));
        } else {
            for (int i = i0; i < i1; ++i) fi0 = _mm_add_pd(fi0, _mm_loadu_pd(tf + 2 * static_cast<std::size_t>(inc_idx[i])));
            for (int i = i1; i < i2; ++i) fi1 = _mm_add_pd(fi1, _mm_loadu_pd(tf + 2 * static_cast<std::size_t>(inc_idx[i])));
        }
        const __m256d fi = _mm256_insertf128_pd(_mm256_castpd128_pd256(fi0), fi1, 1);
        __m256d base = zero;
        if (loaded[k] | loaded[k + 1]) {
            const __m128d z = _mm_setzero_pd();
            base = _mm256_insertf128_pd(_mm256_castpd128_pd256(loaded[k] ? _mm_loadu_pd(fext + 2 * k) : z),
                                        loaded[k + 1] ? _mm_loadu_pd(fext + 2 * k + 2) : z, 1);
        }
        const __m256d fe = _mm256_add_pd(base, _mm256_mul_pd(pairs(gmass + k), g));
        const __m256d sc = _mm256_add_pd(_mm256_andnot_pd(sign, fi), _mm256_andnot_pd(sign, fe));
        const __m256d f = _mm256_add_pd(_mm256_add_pd(zero, fi), _mm256_add_pd(zero, fe));
        const __m256d M = pairs(mass + k), im = pairs(inv_mass + k);
        const __m256d vold = _mm256_loadu_pd(vw + 2 * k);
        const __m256d vrel = kFilter ? _mm256_sub_pd(vold, _mm256_loadu_pd(vref + 2 * k)) : vold;
        const __m256d abs_f = _mm256_andnot_pd(sign, f);
        const __m256d af = _mm256_mul_pd(alpha, abs_f);
        const __m256d fd_pos = _mm256_and_pd(_mm256_cmp_pd(vrel, zero, _CMP_GT_OQ), _mm256_xor_pd(af, sign));
        const __m256d lt = _mm256_cmp_pd(vrel, zero, _CMP_LT_OQ);
        const __m256d fd = _mm256_or_pd(_mm256_and_pd(lt, af), _mm256_andnot_pd(lt, fd_pos));
        const __m256d step = _mm256_mul_pd(_mm256_mul_pd(dtv, _mm256_add_pd(f, fd)), im);
        const __m256d vnew = kMass ? _mm256_div_pd(_mm256_add_pd(_mm256_mul_pd(one_m_hm, vold), step), one_p_hm)
                                   : _mm256_add_pd(vold, step);
        const __m256d vbar = _mm256_mul_pd(half, _mm256_add_pd(vold, vnew));
        const __m256d nfd = _mm256_xor_pd(fd, sign);
        add_terms(b1, _mm256_mul_pd(_mm256_mul_pd(dt, fe), vbar), _mm256_mul_pd(_mm256_mul_pd(hdt, fe), vnew),
                  _mm256_mul_pd(_mm256_mul_pd(dt, nfd), vbar), _mm256_mul_pd(_mm256_mul_pd(hdt, nfd), vnew));
        add_terms(b2, abs_f, _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(half, M), vold), vnew), sc,
                  _mm256_sub_pd(vnew, vnew));
        if (kMass) {  // the negated mass damping force -(-a m vbar)
            const __m256d nfm = _mm256_xor_pd(_mm256_mul_pd(_mm256_mul_pd(neg_mass_damp, M), vbar), sign);
            add_terms(b3, _mm256_mul_pd(_mm256_mul_pd(dt, nfm), vbar), _mm256_mul_pd(_mm256_mul_pd(hdt, nfm), vnew),
                      zero, zero);
        }
        const __m256d sq = _mm256_mul_pd(vnew, vnew);
        const __m256d h = _mm256_hadd_pd(sq, sq);  // |v|^2 of the first node in lane 0, of the second in lane 2
        v2 = _mm_max_sd(_mm256_castpd256_pd128(h), v2);
        v2 = _mm_max_sd(_mm256_extractf128_pd(h, 1), v2);
        _mm256_storeu_pd(vw + 2 * k, vnew);
        _mm256_storeu_pd(xw + 2 * k, _mm256_add_pd(_mm256_loadu_pd(xw + 2 * k), _mm256_mul_pd(dt, vnew)));
        if (kFilter) {
            const __m256d vr = _mm256_loadu_pd(vref + 2 * k);
            _mm256_storeu_pd(vref + 2 * k, _mm256_add_pd(vr, _mm256_mul_pd(wf, _mm256_sub_pd(vnew, vr))));
        }
    }
    _mm256_store_pd(gb, b1), _mm256_store_pd(gb + 4, b2), _mm256_store_pd(gb + 8, b3);
    out.work = gb[0], out.work_half = gb[1], out.damping = gb[2], out.damping_half = gb[3];
    out.unbalanced = gb[4], out.kinetic = gb[5], out.scale = gb[6];
    out.mass = gb[8], out.mass_half = gb[9];
    out.v2 = _mm_cvtsd_f64(v2);
    out.bad = first_bad<false>(a, u0, u1, gb[7]);
}

bool avx_available() {
    static const bool yes = __builtin_cpu_supports("avx");
    return yes;
}
#endif

template <bool kTied, bool kFilter, bool kMass>
void run_blocks(const NodeUpdate& a, std::vector<NodeBlockSums>& sums) {
    const int nnb = static_cast<int>(sums.size());
#if defined(FDEM_NODE_AVX)
    const bool avx = a.lanes != 1 && avx_available() && (a.dt_before == 0 || a.dt_before == a.dt);
#endif
#pragma omp parallel if (nnb > 1)
    {
        const int T = omp_get_num_threads(), me = omp_get_thread_num();
        for (int b = share_begin(nnb, T, me); b < share_begin(nnb, T, me + 1); ++b)
#if defined(FDEM_NODE_AVX)
            if (!kTied && avx) plain_node_block<kFilter, kMass>(a, b, sums[b]);
            else
#endif
                node_block<kTied, kFilter, kMass>(a, b, sums[b]);
    }
}

template <bool kTied, bool kFilter>
void with_mass(const NodeUpdate& a, std::vector<NodeBlockSums>& sums) {
    if (a.hm > 0) run_blocks<kTied, kFilter, true>(a, sums);
    else run_blocks<kTied, kFilter, false>(a, sums);
}

template <bool kTied>
void with_filter(const NodeUpdate& a, std::vector<NodeBlockSums>& sums) {
    if (a.v_ref) with_mass<kTied, true>(a, sums);
    else with_mass<kTied, false>(a, sums);
}

}  // namespace

void update_nodes(const NodeUpdate& a, std::vector<NodeBlockSums>& sums) {
    if (a.tied) with_filter<true>(a, sums);
    else with_filter<false>(a, sums);
}

}  // namespace fdem
