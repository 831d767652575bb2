// fdem/node_update.cpp: the node update kernel (fdem/node_update.hpp).
#include "fdem/node_update.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "fdem/sim_detail.hpp"

namespace fdem {

using sim_detail::kBlock;
using sim_detail::share_begin;

namespace {

// One block; compiled for each combination of three compile-time constants, so that each model runs only the parts
// it has: kTied (units of tied copies, else plain nodes without the units' indirections), kFilter (the filtered
// local damping's moving means, vref) and kMass (mass-proportional damping, hm > 0).
template <bool kTied, bool kFilter, bool kMass>
void node_block(const NodeUpdate& a, int b, NodeBlockSums& out) {
    const int nu = a.n_units;
    const int* u_start = a.u_start;
    const int* u_node = a.u_node;
    const int* u_slot = a.u_slot;
    const double* u_mass = a.u_mass;
    const double* u_inv = a.u_inv;
    const double* tie_w = a.tie_w;
    const int* u_block = a.u_block;
    const double* tf = a.tri_forces;
    const int* inc_ptr = a.inc_ptr;
    const int* inc_idx = a.inc_idx;
    const double* mass = a.mass;
    const double* gmass = a.grav_mass;
    const double* inv_mass = a.inv_mass;
    const double* fext = a.f_ext;
    const unsigned char* loaded = a.loaded;
    double* fmod = a.f_mod;
    const bool reset_fmod = a.reset_fmod;
    const std::uint8_t* kind = a.dof_kind;
    const double* vpres = a.dof_velocity;
    double* reac = a.reaction;
    double* xw = a.x;
    double* vw = a.v;
    double* vref = a.v_ref;
    const double dt = a.dt, dtv = a.dtv, alpha = a.alpha, beta_mass = a.beta_mass, hm = a.hm, wf = a.wf;
    const double gx = a.gx, gy = a.gy;
    double dW = 0, dD = 0, unb = 0, scale = 0, K = 0, cW = 0, cD = 0, dM = 0, cM = 0;
    double nonfinite = 0;  // v - v summed: 0 while every new velocity is finite, NaN after an inf or a NaN
    double v2 = 0;  // the largest |v|^2 of the block's units (a NaN passed over, as std::max(v2, NaN) = v2)
    const int u0 = kTied ? u_block[b] : b * kBlock, u1 = kTied ? u_block[b + 1] : std::min(nu, (b + 1) * kBlock);
    for (int u = u0; u < u1; ++u) {
        const int j0 = kTied ? u_start[u] : u, j1 = kTied ? u_start[u + 1] : u + 1;
        // the resultant: internal (joints, contact, triangles) and external (loads, gravity) sums
        double S[4] = {0, 0, 0, 0};
        for (int j = j0; j < j1; ++j) {
            const int k = kTied ? u_node[j] : j;
            double fi0 = fmod[2 * k], fi1 = fmod[2 * k + 1];
            // (without joints and contact no node gets a module force, and the lines are not written; with
            // them every one is reset: a test of which had one was a branch that a third of the nodes
            // mispredicted. The sums never make a -0.0, so the reset keeps the bits of one that tests.)
            if (reset_fmod) fmod[2 * k] = 0, fmod[2 * k + 1] = 0;
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
            const double fe0 = (ld ? fext[2 * k] : 0.0) + gmass[k] * gx, fe1 = (ld ? fext[2 * k + 1] : 0.0) + gmass[k] * gy;
            scale += std::abs(fi0) + std::abs(fe0);
            scale += std::abs(fi1) + std::abs(fe1);
            S[0] += fi0, S[1] += fi1, S[2] += fe0, S[3] += fe1;
        }
        const int k0 = kTied ? u_node[j0] : j0;
        const double M = kTied ? u_mass[u] : mass[k0];
        const double im = kTied ? u_inv[u] : inv_mass[k0];
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
                dW += dt * fe * vbar;
                dD -= dt * fd * vbar;
                cW += 0.5 * dt * fe * vnew;
                cD -= 0.5 * dt * fd * vnew;
                if (kMass) {  // -a m vbar: work dt (-a m vbar) vbar, and its share up to t^n
                    const double fm = -beta_mass * M * vbar;
                    dM -= dt * fm * vbar;
                    cM -= 0.5 * dt * fm * vnew;
                }
                unb += std::abs(f);
            } else {
                vnew = kind[d0] == 1 ? 0.0 : vpres[d0];
                for (int j = j0; j < j1; ++j) {
                    const int k = kTied ? u_node[j] : j;
                    const double w = kTied ? tie_w[k] : 1.0;
                    const double R = mass[k] * (vnew - vold) / dtv - w * f;
                    reac[2 * k + c] = R;
                    dW += dt * (w * fe + R) * 0.5 * (vold + vnew);
                    cW += 0.5 * dt * (w * fe + R) * vnew;
                }
            }
            K += 0.5 * M * vold * vnew;
            nonfinite += vnew - vnew;
            vn[c] = vnew;
            xn[c] = xw[d0] + dt * vnew;  // the members' positions are the same bits
            vr[c] = kFilter ? vref[d0] + wf * (vnew - vref[d0]) : 0.0;
        }
        v2 = std::max(v2, vn[0] * vn[0] + vn[1] * vn[1]);  // (every member's |v|^2, the bits of v written below)
        for (int j = j0; j < j1; ++j) {
            const int d = 2 * (kTied ? u_node[j] : j);
            vw[d] = vn[0], vw[d + 1] = vn[1];
            xw[d] = xn[0], xw[d + 1] = xn[1];
            if (kFilter) vref[d] = vr[0], vref[d + 1] = vr[1];
        }
    }
    out.work = dW, out.damping = dD, out.unbalanced = unb, out.scale = scale;
    out.kinetic = K, out.work_half = cW, out.damping_half = cD, out.mass = dM, out.mass_half = cM;
    out.v2 = v2;
    // The first unit (in loop order) with a non-finite velocity, looked for only when there is one.
    int bad = -1;
    if (!(nonfinite == 0))
        for (int u = u0; u < u1 && bad < 0; ++u) {
            const int k0 = kTied ? u_node[u_start[u]] : u;
            if (!std::isfinite(vw[2 * k0]) || !std::isfinite(vw[2 * k0 + 1])) bad = k0;
        }
    out.bad = bad;
}

template <bool kTied, bool kFilter, bool kMass>
void run_blocks(const NodeUpdate& a, std::vector<NodeBlockSums>& sums) {
    const int nnb = static_cast<int>(sums.size());
#pragma omp parallel if (nnb > 1)
    {
        const int T = omp_get_num_threads(), me = omp_get_thread_num();
        for (int b = share_begin(nnb, T, me); b < share_begin(nnb, T, me + 1); ++b)
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
