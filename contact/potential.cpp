// contact/potential.cpp: pair kernel of the distributed-potential contact (formulas in potential.hpp).
#include "contact/potential.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace fdem::contact {

namespace {

// Area coordinates of T as affine functions: L_k(P) = g[3k] + g[3k+1] P.x + g[3k+2] P.y.
inline void area_coordinates(const double* T, double* g) {
    const double area2 = (T[2] - T[0]) * (T[5] - T[1]) - (T[4] - T[0]) * (T[3] - T[1]);
    const double inv = 1.0 / area2;
    for (int k = 0; k < 3; ++k) {
        const int i = (k + 1) % 3, j = (k + 2) % 3;
        const double xi = T[2 * i], yi = T[2 * i + 1], xj = T[2 * j], yj = T[2 * j + 1];
        g[3 * k] = (xi * yj - xj * yi) * inv;
        g[3 * k + 1] = (yi - yj) * inv;
        g[3 * k + 2] = (xj - xi) * inv;
    }
}

inline double affine(const double* g, double x, double y) { return g[0] + g[1] * x + g[2] * y; }

// Sutherland-Hodgman clip of a convex polygon by the half-plane g(P) >= 0.
int clip(const double* in, int n, const double* g, double* out) {
    int m = 0;
    for (int i = 0; i < n; ++i) {
        const int j = (i + 1) % n;
        const double xi = in[2 * i], yi = in[2 * i + 1], xj = in[2 * j], yj = in[2 * j + 1];
        const double di = affine(g, xi, yi), dj = affine(g, xj, yj);
        if (di >= 0.0) {
            out[2 * m] = xi;
            out[2 * m + 1] = yi;
            ++m;
        }
        if ((di >= 0.0) != (dj >= 0.0)) {
            const double s = di / (di - dj);
            out[2 * m] = xi + s * (xj - xi);
            out[2 * m + 1] = yi + s * (yj - yi);
            ++m;
        }
    }
    return m;
}

// INT over a convex polygon of an affine function f (exact: fan of triangles, f at each centroid).
double integrate_affine(const double* poly, int n, const double* f) {
    double sum = 0.0;
    for (int i = 1; i + 1 < n; ++i) {
        const double x0 = poly[0], y0 = poly[1], x1 = poly[2 * i], y1 = poly[2 * i + 1], x2 = poly[2 * i + 2],
                     y2 = poly[2 * i + 3];
        const double area = 0.5 * ((x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0));
        sum += area * affine(f, (x0 + x1 + x2) / 3.0, (y0 + y1 + y2) / 3.0);
    }
    return sum;
}

// INT over polygon omega of phi_X = min_k w_k L_k (g: X's area coordinates): split omega where each branch is the
// minimum.
double integrate_potential(const double* omega, int n, const double* g, const double* w) {
    double total = 0.0;
    double buf1[2 * 16], buf2[2 * 16];
    for (int k = 0; k < 3; ++k) {
        const double* src = omega;
        int m = n;
        double* dst = buf1;
        for (int j = 0; j < 3 && m > 0; ++j) {
            if (j == k) continue;
            const double h[3] = {w[j] * g[3 * j] - w[k] * g[3 * k], w[j] * g[3 * j + 1] - w[k] * g[3 * k + 1],
                                 w[j] * g[3 * j + 2] - w[k] * g[3 * k + 2]};
            m = clip(src, m, h, dst);
            src = dst;
            dst = (dst == buf1) ? buf2 : buf1;
        }
        if (m < 3) continue;
        const double f[3] = {w[k] * g[3 * k], w[k] * g[3 * k + 1], w[k] * g[3 * k + 2]};
        total += integrate_affine(src, m, f);
    }
    return total;
}

}  // namespace

double release_slot(double* h) {
    const double energy = 0.5 * h[5] * h[0] * h[0];  // J: the spring's stored energy, k_t delta_s^2 / 2
    for (int i = 0; i < kHistPerEdge; ++i) h[i] = 0.0;
    return energy;
}

namespace {

// One loaded edge: the edge (nodes e, e+1) of triangle O ("owner") lies partly inside triangle Q ("other").
// Normal load c * phi_Q on the owner's edge along -n_O; the reaction on Q through its area coordinates.
// Friction: one tangential spring per edge ([K25] Eqs. 4-5) between two material points, the stick anchors.
// len: the owner's edge length (m), as edge_integrals computed it; its integrals I_k at I[k * stride] (the batch's
// columns, read where they are: copied to a small array, they were stored a double at a time and read back in pairs,
// a stalled store forwarding on every loaded edge). h: the edge's friction state (kHistPerEdge).
// A force (fx, fy) on the owner's edge at s along it (nodes e, e1), its reaction on the other triangle at area
// coordinates l.
inline void spread(double* __restrict fo, double* __restrict fq, int e, int e1, double s, const double* l, double fx,
                   double fy) {
    fo[2 * e] += (1.0 - s) * fx;
    fo[2 * e + 1] += (1.0 - s) * fy;
    fo[2 * e1] += s * fx;
    fo[2 * e1 + 1] += s * fy;
    for (int k = 0; k < 3; ++k) {
        fq[2 * k] -= l[k] * fx;
        fq[2 * k + 1] -= l[k] * fy;
    }
}

// fdo, fdq (optional, with dashpots): the dashpot part of fo, fq is also added there (the books' second half).
void load_edge(const double* __restrict xo, const double* __restrict vo, double* __restrict fo,
               const double* __restrict vq, double* __restrict fq, int e, double len, const double* __restrict In,
               std::size_t stride, const PairParams& p, double* __restrict h, PairResult& r,
               double* __restrict fdo = nullptr, double* __restrict fdq = nullptr, EdgeRecord* rec = nullptr) {
    const double I[6] = {In[0], In[stride], In[2 * stride], In[3 * stride], In[4 * stride], In[5 * stride]};
    const int e1 = (e + 1) % 3;
    const double dx = xo[2 * e1] - xo[2 * e], dy = xo[2 * e1 + 1] - xo[2 * e + 1];
    // (n = (t_y, -t_x): the same bits as dy / len and -dx / len, division rounds symmetrically; two divisions)
    const double tx = dx / len, ty = dy / len;
    const double nx = ty, ny = -tx;
    const double total = I[0] + I[1];
    const double fn = p.c * p.thickness * total;  // N
    // Centre of pressure: along the edge s = I1 / (I0 + I1); in the other triangle the area coordinates
    // I[2 + k] / (I0 + I1) (>= 0, summing to 1). The normal load c t INT N_a phi on the edge's nodes is fn at that
    // point, and so is its reaction on the other triangle; the normal dashpot acts at the same point, so one force
    // vector (gx, gy) on the owner, the opposite on the other, carries both.
    const double inv_total = 1.0 / total;
    const double s = I[1] * inv_total;
    double lq[3];
    for (int k = 0; k < 3; ++k) lq[k] = I[2 + k] * inv_total;
    // Impacts (PairParams::inv_e2): fh >= 0, the part of the elastic push fn the unloading line takes away.
    double fh = 0.0;
    const bool inelastic = p.inv_e2 > 1.0 && I[5] > 0.0;
    double q_max = 0.0;
    if (inelastic) {
        const double q = fn / I[5];  // N/m
        q_max = std::max(h[6], q);
        fh = std::min(fn, (q_max - q) * (p.inv_e2 - 1.0) * I[5]);
    }
    double gx = -(fn - fh) * nx, gy = -(fn - fh) * ny;
    const double k_t = 0.5 * p.k_s * p.thickness * I[5];  // N/m; each of the two faces carries half the contact
    const bool friction = p.mu > 0.0 && k_t > 0.0;
    if (!friction) r.dissipation += release_slot(h);
    if (inelastic) h[6] = q_max;
    if (friction || p.beta > 0.0 || inelastic) {
        const double vox = (1.0 - s) * vo[2 * e] + s * vo[2 * e1], voy = (1.0 - s) * vo[2 * e + 1] + s * vo[2 * e1 + 1];
        const double vqx = lq[0] * vq[0] + lq[1] * vq[2] + lq[2] * vq[4];
        const double vqy = lq[0] * vq[1] + lq[1] * vq[3] + lq[2] * vq[5];
        const double vrx = vox - vqx, vry = voy - vqy;  // owner relative to other, at the centre of pressure
        // Normal dashpot (PairParams::beta) along n_O: > 0 pulls the faces together. It never pulls beyond the
        // elastic push fn, so the faces are pressed together with fn - fdn >= 0, and that whole normal force is
        // what friction reads: a sliding edge carries mu (fn - fdn), so the dashpots change the normal force's
        // history (they damp its chatter) but never the ratio of friction to normal force ([C79] Coulomb slip on
        // the contact force; with the cap on fn alone, the one-sided clamp left chattering contacts a mean net
        // push outside the cap: mu_eff 0.775 for mu 0.8 at contact_damping 0.5, 0.8001 now).
        const double vn = vrx * nx + vry * ny;  // > 0: the owner's edge moves into the other triangle
        const double fdn =
            p.beta > 0.0 ? std::min(-p.beta * 0.5 * p.k_n_area * p.thickness * I[5] * vn, fn - fh) : 0.0;  // N
        gx += fdn * nx;
        gy += fdn * ny;
        double vt = 0.0;
        if (friction) {
            // The stick anchors: the owner's material point at s0 = h[1] along its edge and the other's material
            // point at area coordinates h[2..4], both taken at the centre of pressure when the edge first touches
            // (all zero: not yet) and again whenever it slips. h[0] = delta_s, the elastic tangential displacement
            // of the two anchors (m). [K25] Eq. 4, delta_s += v_rel,t dt, is integrated on the anchors'
            // velocities and the force acts on the anchors, so a sticking edge is a spring between two material
            // points: it stores and returns work, however the pressure moves along the edge. (Taken at the
            // moving centre of pressure, the stuck spring was not conservative: a rocking stack that statics says
            // stands gained energy from its sticking springs, started to slip and crept away.)
            if (h[2] == 0.0 && h[3] == 0.0 && h[4] == 0.0) {
                h[1] = s;
                h[2] = lq[0], h[3] = lq[1], h[4] = lq[2];
                h[5] = k_t;
            }
            // The contact length changed since the last step (h[5] = k_t then): a contact that grows meets the
            // other face with unstretched new length, so the force k_t delta_s stays and delta_s shrinks by
            // k_t,old / k_t; one that shrinks takes the lost length's share of the force with it. Either way the
            // spring's energy falls, and the difference is booked as dissipation (a stretched spring that lets
            // go), so the stored energy k_t delta_s^2 / 2 only changes by work or booked dissipation. (Kept as a
            // stretch with k_t read off the current length, a landing edge gained energy from nothing: a
            // rocking block's books showed 20 % more energy held than worked.)
            // (the spring's force k_t delta_s and energy before this step, for the books below)
            const bool resized = k_t != h[5];
            const double f_old = h[5] * h[0], e_old = 0.5 * h[5] * h[0] * h[0];
            if (resized) {
                if (k_t > h[5]) h[0] *= h[5] / k_t;
                h[5] = k_t;
            }
            const double s0 = h[1];
            const double vax = (1.0 - s0) * vo[2 * e] + s0 * vo[2 * e1], vay = (1.0 - s0) * vo[2 * e + 1] + s0 * vo[2 * e1 + 1];
            const double vbx = h[2] * vq[0] + h[3] * vq[2] + h[4] * vq[4];
            const double vby = h[2] * vq[1] + h[3] * vq[3] + h[4] * vq[5];
            vt = (vax - vbx) * tx + (vay - vby) * ty;
            // [K25] Eq. 5: F_t = min(k_t |delta_s|, mu |F_n|), opposing the slip.
            const double cap = p.mu * (fn - fh - fdn);
            const double trial = h[0] + vt * p.dt;
            double ft = -k_t * trial;  // along t_O on the owner (N)
            double kept = trial;
            const bool sticks = std::fabs(ft) <= cap;
            if (!sticks) {
                kept = (trial > 0.0 ? 1.0 : -1.0) * cap / k_t;
                ft = -k_t * kept;
                // The faces slid: the anchors move to the centre of pressure, keeping the spring's stretch.
                h[1] = s;
                h[2] = lq[0], h[3] = lq[1], h[4] = lq[2];
            }
            // Dissipated this step: the work the spring took, at the mean of its force before and after the step
            // over the step's tangential motion vt dt (the rule by which the engine books every force's work, on the
            // mean velocity of the step, fdem/step.cpp), less the energy it gained. While it sticks at an unchanged
            // length this is 0; when it slips at a steady cap, the cap times the slip. (The cap times the slip alone
            // would miss (cap^{n-1} - cap^n)^2 / (2 k_t) at each change of the cap.)
            const double e_new = 0.5 * k_t * kept * kept;
            // (after a slip the force acts at the new anchors: its half of the work on their motion, vrx, vry at
            // the centre of pressure)
            const double vt_new = sticks ? vt : vrx * tx + vry * ty;
            if (resized || !sticks)
                r.dissipation += 0.5 * (f_old * vt + k_t * kept * vt_new) * p.dt - (e_new - e_old);
            h[0] = kept;
            r.energy_tangential += e_new;
            // The tangential dashpot acts only while the edge sticks and keeps the sum within the Coulomb limit,
            // so a sliding edge carries mu (fn - fdn) whatever the rate.
            const double fdt = (p.beta > 0.0 && sticks) ? std::clamp(-p.beta * k_t * vt, -cap - ft, cap - ft) : 0.0;
            r.damping -= fdt * vt * p.dt;
            const double fx = (ft + fdt) * tx, fy = (ft + fdt) * ty;
            if (rec) rec->ft = ft + fdt, rec->sliding = sticks ? 0 : 1;
            spread(fo, fq, e, e1, h[1], h + 2, fx, fy);
            if (fdo && fdt != 0.0) spread(fdo, fdq, e, e1, h[1], h + 2, fdt * tx, fdt * ty);
        }
        // (the dashpot and the impacts' hysteresis act at the same point along n_O: one force fdn + fh)
        const double fnd = fdn + fh;
        if (p.beta > 0.0 || inelastic) r.damping -= fnd * vn * p.dt;  // (none without dashpots or impacts)
        if (fdo && fnd != 0.0) spread(fdo, fdq, e, e1, s, lq, fnd * nx, fnd * ny);
    }
    spread(fo, fq, e, e1, s, lq, gx, gy);
    if (rec) {
        rec->loaded = true;
        rec->px = (1.0 - s) * xo[2 * e] + s * xo[2 * e1];
        rec->py = (1.0 - s) * xo[2 * e + 1] + s * xo[2 * e1 + 1];
        rec->nx = nx, rec->ny = ny;
        rec->fn = -(gx * nx + gy * ny);  // (gx, gy) = -(fn - fh - fdn) n
        rec->length = I[5];
    }
}

}  // namespace

double smallest_altitude(const double* T) {
    const double area2 = std::fabs((T[2] - T[0]) * (T[5] - T[1]) - (T[4] - T[0]) * (T[3] - T[1]));
    double lmax = 0.0;
    for (int k = 0; k < 3; ++k) {
        const int j = (k + 1) % 3;
        const double ex = T[2 * j] - T[2 * k], ey = T[2 * j + 1] - T[2 * k + 1];
        lmax = std::max(lmax, ex * ex + ey * ey);
    }
    return area2 / std::sqrt(lmax);
}

void potential_weights(const double* x, bool distance_potential, double* w) {
    if (!distance_potential) {
        w[0] = w[1] = w[2] = 3.0;
        return;
    }
    const double area2 = std::fabs((x[2] - x[0]) * (x[5] - x[1]) - (x[4] - x[0]) * (x[3] - x[1]));
    for (int k = 0; k < 3; ++k) {
        const int i = (k + 1) % 3, j = (k + 2) % 3;
        const double ex = x[2 * j] - x[2 * i], ey = x[2 * j + 1] - x[2 * i + 1];
        w[k] = area2 / std::sqrt(ex * ex + ey * ey);  // altitude from vertex k onto the opposite edge (m)
    }
}

namespace {

// Columns of PairBatch::soa_, one queued edge a row: inputs La[3], Lb[3] (area coordinates of the edge's ends p0, p1
// in the other triangle), p0, p1 (m), the other's potential weights w[3]; results I[6] (as edge_in_triangle's out)
// and the edge's length (m).
enum : int { kLa = 0, kLb = 3, kP0x = 6, kP0y = 7, kP1x = 8, kP1y = 9, kW = 10, kI = 13, kLen = 19, kEdgeColumns = 20 };

// (GCC's note that a 4-double vector is passed differently without AVX: such vectors are used only inside
// edge_batch_avx2, where every function taking them is inlined)
#pragma GCC diagnostic ignored "-Wpsabi"
template <int W>
struct Lanes {
    typedef double d __attribute__((vector_size(8 * W)));
    typedef long long m __attribute__((vector_size(8 * W)));
};

template <int W>
inline __attribute__((always_inline)) typename Lanes<W>::d load_lanes(const double* p) {
    typename Lanes<W>::d r;
    std::memcpy(&r, p, sizeof r);
    return r;
}
template <int W>
inline __attribute__((always_inline)) void store_lanes(double* p, typename Lanes<W>::d v) {
    std::memcpy(p, &v, sizeof v);
}
// x >= 0 (a squared length): the square root of each lane, one instruction (the lanes' std::sqrt become one packed
// square root in the AVX2 function: this file is compiled without errno for the math functions,
// contact/CMakeLists.txt).
template <int W>
inline __attribute__((always_inline)) typename Lanes<W>::d sqrt_lanes(typename Lanes<W>::d x) {
#if defined(__SSE2__)
    if constexpr (W == 2) return __builtin_ia32_sqrtpd(x);
#endif
    for (int l = 0; l < W; ++l) x[l] = std::sqrt(x[l]);
    return x;
}

// The part of each edge inside the other triangle and its integrals, W edges (rows i0 .. i0 + W - 1 of the columns
// col[c] = &soa[c * cap]) side by side. Per edge, segment p0-p1 with L_k(s) = a_k + b_k s (a = La, b = Lb - La) in
// the other triangle, whose potential is phi = min_k w_k L_k:
//   inside where every L_k >= 0: s in [lo, hi] (both ends outside one edge line: no part inside);
//   phi is linear between its breakpoints, where two branches w_j L_j, w_k L_k are equal, inside (lo, hi);
//   with P0 = INT phi ds and P1 = INT s phi ds over the inside part (N0 = 1 - s, N1 = s),
//     I0 = INT N0 phi dG = len (P0 - P1),  I1 = INT N1 phi dG = len P1,
//     I(2+k) = INT L_k phi dG = len (a_k P0 + b_k P1),
//   and on a piece [s0, s1] with end values f0, f1 (trapezoid rule exact for linear, Simpson for the quadratic):
//     INT phi ds = h (f0 + f1) / 2,  INT s phi ds = h (s0 (2 f0 + f1) + s1 (f0 + 2 f1)) / 6,  h = s1 - s0;
//   I5 = (hi - lo) len, the length inside. loaded[i] = 1 when the edge enters with P0 > 0.
// No branch on the data: every edge takes every operation; an edge's results are the same bits in any lane and at
// any width (IEEE operations lane by lane; the selections are written as the scalar std::min / std::max they
// replace: std::max(x, y) = x < y ? y : x, std::min(x, y) = y < x ? y : x, so that signed zeros come out the same).
template <int W>
inline __attribute__((always_inline)) void edge_rows(double* const* col, int i0, unsigned char* loaded) {
    using vd = typename Lanes<W>::d;
    using vm = typename Lanes<W>::m;
    const vd zero = vd{}, one = zero + 1.0;
    vd a[3], b[3], w[3];
    vm out = vm{};  // lanes whose segment misses the triangle: both ends outside one edge line
    for (int k = 0; k < 3; ++k) {
        const vd La = load_lanes<W>(col[kLa + k] + i0), Lb = load_lanes<W>(col[kLb + k] + i0);
        out |= ((La < 0.0) & (Lb <= 0.0)) | ((La <= 0.0) & (Lb < 0.0));
        a[k] = La;
        b[k] = Lb - La;
        w[k] = load_lanes<W>(col[kW + k] + i0);
    }
    // L_k(s) >= 0 for all k: s >= -a_k / b_k where b_k > 0, s <= -a_k / b_k where b_k < 0 (b_k = 0 with a_k < 0 is
    // an edge outside, taken above).
    vd lo = zero, hi = one;
    for (int k = 0; k < 3; ++k) {
        const vd q = -a[k] / (b[k] != 0.0 ? b[k] : one);
        lo = b[k] > 0.0 ? (lo < q ? q : lo) : lo;
        hi = b[k] < 0.0 ? (q < hi ? q : hi) : hi;
    }
    const vd dx = load_lanes<W>(col[kP1x] + i0) - load_lanes<W>(col[kP0x] + i0);
    const vd dy = load_lanes<W>(col[kP1y] + i0) - load_lanes<W>(col[kP0y] + i0);
    const vd len = sqrt_lanes<W>(dx * dx + dy * dy);
    // Breakpoints of min_k w_k L_k(s), branch pairs (0,1), (0,2), (1,2); one outside (lo, hi) is put at hi, where
    // it makes a piece of no length, which is skipped.
    vd c[3];
    {
        static constexpr int kJ[3] = {0, 0, 1}, kK[3] = {1, 2, 2};
        for (int i = 0; i < 3; ++i) {
            const int j = kJ[i], k = kK[i];
            const vd den = w[j] * b[j] - w[k] * b[k];
            const vd num = w[j] * a[j] - w[k] * a[k];
            const vd sb = -num / (den != 0.0 ? den : one);
            c[i] = ((den != 0.0) & (sb > lo) & (sb < hi)) ? sb : hi;
        }
    }
    auto order = [](vd& x, vd& y) __attribute__((always_inline)) {
        const vm swap = y < x;
        const vd mn = swap ? y : x, mx = swap ? x : y;
        x = mn, y = mx;
    };
    order(c[0], c[1]), order(c[1], c[2]), order(c[0], c[1]);
    // phi clamped at 0 against rounding
    auto phi = [&](vd s) __attribute__((always_inline)) {
        vd m = w[0] * (a[0] + b[0] * s);
        vd t = w[1] * (a[1] + b[1] * s);
        m = t < m ? t : m;
        t = w[2] * (a[2] + b[2] * s);
        m = t < m ? t : m;
        return 0.0 < m ? m : zero;
    };
    const vd br[4] = {c[0], c[1], c[2], hi};
    vd P0 = zero, P1 = zero, s0 = lo, f0 = phi(lo);
    for (int i = 0; i < 4; ++i) {
        const vd s1 = br[i];
        const vm piece = s1 > s0;
        const vd f1 = phi(s1), h = s1 - s0;
        P0 = piece ? P0 + 0.5 * h * (f0 + f1) : P0;
        P1 = piece ? P1 + h * (s0 * (2.0 * f0 + f1) + s1 * (f0 + 2.0 * f1)) * (1.0 / 6.0) : P1;
        s0 = piece ? s1 : s0;
        f0 = piece ? f1 : f0;
    }
    store_lanes<W>(col[kI] + i0, len * (P0 - P1));
    store_lanes<W>(col[kI + 1] + i0, len * P1);
    for (int k = 0; k < 3; ++k) store_lanes<W>(col[kI + 2 + k] + i0, len * (a[k] * P0 + b[k] * P1));
    store_lanes<W>(col[kI + 5] + i0, (hi - lo) * len);
    store_lanes<W>(col[kLen] + i0, len);
    const vm in = ~out & (hi > lo) & (P0 > 0.0);
    for (int l = 0; l < W; ++l) loaded[i0 + l] = in[l] != 0 ? 1 : 0;
}

template <int W>
void edge_batch(double* const* col, int n, unsigned char* loaded) {
    for (int i0 = 0; i0 < n; i0 += W) edge_rows<W>(col, i0, loaded);
}
#if defined(__x86_64__) && defined(__GNUC__)
__attribute__((target("avx2"))) void edge_batch_avx2(double* const* col, int n, unsigned char* loaded) {
    for (int i0 = 0; i0 < n; i0 += 4) edge_rows<4>(col, i0, loaded);
}
int default_lanes() { return __builtin_cpu_supports("avx2") ? 4 : 2; }
#else
void edge_batch_avx2(double* const* col, int n, unsigned char* loaded) { edge_batch<4>(col, n, loaded); }
int default_lanes() { return 2; }
#endif
int g_lanes = default_lanes();

void run_edge_batch(double* const* col, int n, unsigned char* loaded) {
    if (g_lanes == 4) edge_batch_avx2(col, n, loaded);
    else if (g_lanes == 2) edge_batch<2>(col, n, loaded);
    else edge_batch<1>(col, n, loaded);
}

// Area coordinates in T (affine coefficients g) of the three vertices of X: L[3 v + k] = L_k(x_v).
inline void vertex_coordinates(const double* g, const double* X, double* L) {
    for (int v = 0; v < 3; ++v)
        for (int k = 0; k < 3; ++k) L[3 * v + k] = affine(g + 3 * k, X[2 * v], X[2 * v + 1]);
}

// Separating axis test on the six edge lines: some edge of one triangle has all of the other on its outside.
inline bool separated(const double* L) {
    for (int k = 0; k < 3; ++k)
        if (L[k] <= 0.0 && L[3 + k] <= 0.0 && L[6 + k] <= 0.0) return true;
    return false;
}

}  // namespace

bool edge_in_triangle(const double* p0, const double* p1, const double* T, const double* w, double* out) {
    double g[9], row[kEdgeColumns];
    double* col[kEdgeColumns];
    for (int c = 0; c < kEdgeColumns; ++c) col[c] = row + c;
    area_coordinates(T, g);
    for (int k = 0; k < 3; ++k) {
        row[kLa + k] = affine(g + 3 * k, p0[0], p0[1]);
        row[kLb + k] = affine(g + 3 * k, p1[0], p1[1]);
        row[kW + k] = w[k];
    }
    row[kP0x] = p0[0], row[kP0y] = p0[1], row[kP1x] = p1[0], row[kP1y] = p1[1];
    unsigned char in = 0;
    edge_rows<1>(col, 0, &in);
    if (!in) return false;
    for (int i = 0; i < 6; ++i) out[i] = row[kI + i];
    return true;
}

namespace {

// pair_energy on the triangles' geometry (area coordinates, altitudes), computed once per step by the caller.
double pair_energy(const TriangleGeometry& A, const TriangleGeometry& B, const PairParams& p) {
    double buf1[2 * 16], buf2[2 * 16];
    int n = 3;
    for (int i = 0; i < 6; ++i) buf1[i] = A.x[i];
    double* src = buf1;
    double* dst = buf2;
    for (int k = 0; k < 3 && n > 0; ++k) {
        n = clip(src, n, B.g + 3 * k, dst);
        std::swap(src, dst);
    }
    if (n < 3) return 0.0;
    static constexpr double kThree[3] = {3.0, 3.0, 3.0};
    const double ia = integrate_potential(src, n, A.g, p.distance_potential ? A.h : kThree);
    const double ib = integrate_potential(src, n, B.g, p.distance_potential ? B.h : kThree);
    return p.thickness * p.c * (ia + ib);
}

}  // namespace

double pair_energy(const double* xa, const double* xb, const PairParams& p) {
    TriangleGeometry a, b;
    triangle_geometry(xa, a);
    triangle_geometry(xb, b);
    return pair_energy(a, b, p);
}

void triangle_geometry(const double* x, TriangleGeometry& t, bool altitudes) {
    for (int i = 0; i < 6; ++i) t.x[i] = x[i];
    area_coordinates(x, t.g);
    // smallest_altitude(x) = area2 / sqrt(longest edge^2) = min_k h_k exactly: the same rounded squares (each edge
    // taken in the same direction), and sqrt and the division by it are monotone.
    if (altitudes) {
        potential_weights(x, true, t.h);
        t.inv_h_min = 1.0 / std::min(t.h[0], std::min(t.h[1], t.h[2]));
    } else {
        t.h[0] = t.h[1] = t.h[2] = std::numeric_limits<double>::quiet_NaN();
        t.inv_h_min = 1.0 / smallest_altitude(x);
    }
    t.faces = 7;
}

bool pair_contact(const double* xa, const double* xb, const double* va, const double* vb, const PairParams& params,
                  bool want_energy, double* hist, PairResult& r) {
    TriangleGeometry a, b;
    triangle_geometry(xa, a);
    triangle_geometry(xb, b);
    return pair_contact(a, b, va, vb, params, want_energy, hist, r);
}

bool pair_contact(const TriangleGeometry& A, const TriangleGeometry& B, const double* va, const double* vb,
                  const PairParams& params, bool want_energy, double* hist, PairResult& r, unsigned held,
                  double* f12) {
    thread_local PairBatch batch;
    batch.clear(1);
    if (!batch.begin(A, B, params, want_energy, hist, r, held)) return false;
    batch.integrate();
    return batch.end(A, B, va, vb, params, want_energy, hist, r, held, f12);
}

namespace {
// A pair's result before its edges: no force (on fa, fb: r's own or the caller's slots), no energy, no edge.
void clear_result(PairResult& r, double* fa, double* fb) {
    for (int i = 0; i < 6; ++i) fa[i] = fb[i] = 0.0;
    r.energy_normal = r.energy_tangential = r.dissipation = r.damping = 0.0;
    r.active_edges = 0;
    r.held = 0;
}
}  // namespace

int PairBatch::lanes() { return g_lanes; }

int PairBatch::set_lanes(int w) {
    const int old = g_lanes;
    if (w == 1 || w == 2 || (w == 4 && default_lanes() == 4)) g_lanes = w;
    return old;
}

void PairBatch::clear(int max_pairs) {
    static_assert(kColumns == kEdgeColumns, "PairBatch::kColumns");
    n_edges_ = 0, n_pending_ = 0, next_pending_ = 0, next_edge_ = 0;
    if (static_cast<int>(tested_.size()) < max_pairs) tested_.resize(max_pairs);
    const int cap = (6 * max_pairs + 3) / 4 * 4;  // whole vectors of 4 lanes
    if (cap > cap_) {
        soa_.assign(static_cast<std::size_t>(kEdgeColumns) * cap, 0.0);
        loaded_.assign(cap, 0);
        cap_ = cap;
    }
    for (int c = 0; c < kEdgeColumns; ++c) col_[c] = soa_.data() + static_cast<std::size_t>(c) * cap_;
}

bool PairBatch::begin(const TriangleGeometry& A, const TriangleGeometry& B, const PairParams& p, bool want_energy,
                      double* hist, PairResult& r, unsigned held) {
    const double* xa = A.x;
    const double* xb = B.x;
    // Area coordinates of each triangle's vertices in the other, for the edges that are faces (a triangle without
    // faces needs none), and the separating-axis test on them.
    double a_in_b[9], b_in_a[9];
    bool apart = false;
    if (A.faces) {
        vertex_coordinates(B.g, xa, a_in_b);
        apart = separated(a_in_b);
    }
    if (!apart && B.faces) {
        vertex_coordinates(A.g, xb, b_in_a);
        apart = separated(b_in_a);
    }
    if (apart || (A.faces | B.faces) == 0) {
        clear_result(r, r.fa, r.fb);
        // A slot that may hold state lets its spring go (the others are all zero already).
        for (int s = 0; s < 6; ++s)
            if ((held >> s) & 1u) r.dissipation += release_slot(hist + kHistPerEdge * s);
        // Triangles with no face (inside their bodies) that overlap still hold energy: the loads of their edges
        // went to the faces of their neighbours, whose pairs carry them. (pair_energy is 0 when they are apart.)
        if (!apart && want_energy) r.energy_normal = pair_energy(A, B, p);
        return false;
    }
    // Queue the faces' edges in slot order (edge e of A, then edge e of B, e = 0, 1, 2): end() loads them in it.
    static constexpr double kThree[3] = {3.0, 3.0, 3.0};
    const double* wa = p.distance_potential ? A.h : kThree;
    const double* wb = p.distance_potential ? B.h : kThree;
    unsigned tested = 0;
    double* const* col = col_;
    auto queue = [&](const double* L, const double* X, const double* w, int e) {
        const int e1 = (e + 1) % 3;
        const int i = n_edges_++;
        for (int k = 0; k < 3; ++k) {
            col[kLa + k][i] = L[3 * e + k];
            col[kLb + k][i] = L[3 * e1 + k];
            col[kW + k][i] = w[k];
        }
        col[kP0x][i] = X[2 * e], col[kP0y][i] = X[2 * e + 1];
        col[kP1x][i] = X[2 * e1], col[kP1y][i] = X[2 * e1 + 1];
    };
    for (int e = 0; e < 3; ++e) {
        if ((A.faces >> e) & 1) queue(a_in_b, xa, wb, e), tested |= 1u << e;
        if ((B.faces >> e) & 1) queue(b_in_a, xb, wa, e), tested |= 1u << (3 + e);
    }
    tested_[n_pending_++] = static_cast<unsigned char>(tested);
    return true;
}

void PairBatch::integrate() {
    run_edge_batch(col_, n_edges_, loaded_.data());
}

bool PairBatch::end(const TriangleGeometry& A, const TriangleGeometry& B, const double* va, const double* vb,
                    const PairParams& params, bool want_energy, double* hist, PairResult& r, unsigned held,
                    double* f12, double* fd12, EdgeRecord* records) {
    const unsigned tested = tested_[next_pending_++];
    if (records)
        for (int k = 0; k < 6; ++k) records[k] = EdgeRecord{};
    double* fa = f12 ? f12 : r.fa;
    double* fb = f12 ? f12 + 6 : r.fb;
    clear_result(r, fa, fb);
    if (params.beta <= 0.0 && params.inv_e2 <= 1.0) fd12 = nullptr;
    double* fda = fd12;
    double* fdb = fd12 ? fd12 + 6 : nullptr;
    if (fd12)
        for (int i = 0; i < 12; ++i) fd12[i] = 0.0;
    PairParams p = params;
    if (p.p_t > 0.0 || (p.beta > 0.0 && p.p_n > 0.0)) {
        const double inv_h = A.inv_h_min + B.inv_h_min;  // 1/m
        if (p.p_t > 0.0) p.k_s = 3.0 * p.p_t * inv_h;
        if (p.beta > 0.0 && p.p_n > 0.0) p.k_n_area = 3.0 * p.p_n * inv_h;
    }
    double* const* col = col_;
    // Slots in order (A's edge e, then B's edge e): a loaded edge carries its load, any other slot that may hold
    // state lets its spring go (a pair's six slots are 288 bytes, most of them idle: not read, not dirtied).
    for (int e = 0; e < 3; ++e)
        for (int side = 0; side < 2; ++side) {
            const int s = 3 * side + e;
            bool on = false;
            if ((tested >> s) & 1u) {
                const int i = next_edge_++;
                if (loaded_[i]) {
                    const double* I = col[kI] + i;  // I_k at I[k cap_] (clear: the columns cap_ apart)
                    const double len = col[kLen][i];
                    EdgeRecord* rec = records ? records + s : nullptr;
                    if (side == 0) load_edge(A.x, va, fa, vb, fb, e, len, I, cap_, p, hist + kHistPerEdge * s, r, fda, fdb, rec);
                    else load_edge(B.x, vb, fb, va, fa, e, len, I, cap_, p, hist + kHistPerEdge * s, r, fdb, fda, rec);
                    ++r.active_edges;
                    r.held |= 1u << s;
                    on = true;
                }
            }
            if (!on && ((held >> s) & 1u)) r.dissipation += release_slot(hist + kHistPerEdge * s);
        }
    if (want_energy) r.energy_normal = pair_energy(A, B, p);
    return r.active_edges > 0;
}

}  // namespace fdem::contact
