// fdem/node_update.hpp: the node update of one explicit step, the kernel of Simulation::step's node stage, callable
// alone (fdem_bench, tests) on plain arrays.
//
// One unit at a time (a node, or a group of tied copies of extrinsic insertion that moves as one node of the group's
// mass M): the resultant f of its internal forces (triangles, joints, contact: f_mod) and external forces (loads,
// gravity), the [C79] local damping f_d = -alpha |f| sign(v^{n-1/2}) (or sign(v - v_ref) with the filter), the
// optional mass-proportional damping -a m vbar (implicit in v), then
//   v^{n+1/2} = ((1 - a dtv / 2) v^{n-1/2} + dtv (f + f_d) / M) / (1 + a dtv / 2),   x^{n+1} = x^n + dt v^{n+1/2},
// or the prescribed velocity and its reaction R = m (v^{n+1/2} - v^{n-1/2}) / dtv - f on a held DOF. Per block of
// units the books of the step on vbar = (v^{n-1/2} + v^{n+1/2}) / 2: work dt (f_ext + R) . vbar, local and mass
// damping, K^n = 1/2 M v^{n-1/2} . v^{n+1/2}, the halves on v^{n+1/2} that run ahead of t^n, the unbalanced force
// and its scale, the largest |v|^2, and the first unit with a non-finite velocity. dtv = (dt^{n-1/2} + dt^{n+1/2}) / 2
// (a step that changed the step size; Belytschko, Liu & Moran 2000, §6.2). On such a step the work takes f^n over
// (x^{n+1} - x^{n-1}) / 2 = (dt^{n-1/2} v^{n-1/2} + dt^{n+1/2} v^{n+1/2}) / 2, which is dt vbar only while the step
// is constant: the sum of these over the steps is the trapezoidal work of the positions, the one the potential
// energies and K^n agree with (dt vbar at a change books f^n . v^{n-1/2} (dt^{n-1/2} - dt^{n+1/2}) / 2 too many).
// Such a step runs the scalar code.
//
// DATA CONTRACT. Node k's DOFs at 2k, 2k + 1. Units (tied only): members u_node[u_start[u] .. u_start[u + 1]), the
// unit's mass u_mass[u] and its inverse; a member j with u_slot[j] >= 0 reads its triangle forces from that slot
// of tri_forces (2 per slot), the others through the incidence lists inc_ptr / inc_idx (2 per incidence, the
// triangles' 6-double records). Blocks: kBlock nodes, or the tied units' blocks u_block. dof_kind 0 free, 1 fixed,
// 2 prescribed velocity dof_velocity. f_mod is read and, when reset_fmod, zeroed for the next step. Each block writes
// only its own units' x, v, v_ref, reactions and its NodeBlockSums: any thread may take any block, the result is
// the same bits. Plain nodes go two at a time where the CPU has AVX (lanes): each lane does the scalar operations in
// the same order and each book takes its terms in unit order, so the width does not change the bits
// (tests/core/test_node_update.cpp compares them).
#pragma once

#include <cstdint>
#include <vector>

namespace fdem {

struct NodeUpdate {
    int n_units = 0;           // nodes, or tied units
    bool tied = false;         // units of tied copies (the u_* arrays below), else plain nodes
    const int* u_start = nullptr;
    const int* u_node = nullptr;
    const int* u_slot = nullptr;
    const double* u_mass = nullptr;
    const double* u_inv = nullptr;
    const double* tie_w = nullptr;  // per node: its share m / M of its unit's mass
    const int* u_block = nullptr;   // tied: first unit of each block
    const double* tri_forces = nullptr;
    const int* inc_ptr = nullptr;
    const int* inc_idx = nullptr;
    const double* mass = nullptr;
    const double* grav_mass = nullptr;
    const double* inv_mass = nullptr;
    const double* f_ext = nullptr;
    const unsigned char* loaded = nullptr;  // per node: f_ext is nonzero there
    double* f_mod = nullptr;
    bool reset_fmod = false;
    const std::uint8_t* dof_kind = nullptr;
    const double* dof_velocity = nullptr;
    double* reaction = nullptr;
    double* x = nullptr;
    double* v = nullptr;
    double* v_ref = nullptr;  // the filter's moving means, or null (no filter)
    double dt = 0, dtv = 0;   // s
    double dt_before = 0;     // s, the last step's length when it differs from dt (0: the same)
    double local_damping = 0; // [C79] local damping alpha
    double mass_damping = 0;  // mass-proportional (Rayleigh) damping a (1/s)
    double hm = 0;            // dtv a / 2
    double wf = 0;            // the filter's one-step weight
    double gx = 0, gy = 0;    // gravity (m/s^2)
    int lanes = 0;            // 0: plain nodes two at a time where the CPU has AVX; 1: one at a time (the same bits)
};

// One block's books (J, N, m^2/s^2) and its first unit's node with a non-finite velocity (-1: none).
struct NodeBlockSums {
    double work = 0, damping = 0, unbalanced = 0, scale = 0, kinetic = 0, work_half = 0, damping_half = 0, mass = 0,
           mass_half = 0, v2 = 0;
    int bad = -1;
};

// Updates every block, threads taking static shares (share_begin), and writes each block's sums to sums[b]; sums is
// sized by the caller to the number of blocks (kBlock nodes, or the tied units' blocks).
void update_nodes(const NodeUpdate& a, std::vector<NodeBlockSums>& sums);

}  // namespace fdem
