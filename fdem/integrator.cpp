// fdem/integrator.cpp: the explicit central-difference integrator of Simulation: the time step, the tied groups of
// extrinsic insertion and one step.
//
// One step (central differences with local damping, fdem/README.md 'Time step'; [M04] ch. 4, [C79]), with x^n, v^{n-1/2}
// known, in the order step() runs its stages:
//   1. triangle forces f_int(x^n, v^{n-1/2}) in parallel, one 6-double record per triangle (triangle_stage);
//   2. extrinsic insertion: dormant edges whose traction reached the strength get their element, the step may shrink;
//   3. loads, gravity and prescribed velocities at t^n (ramps, protocols, tilting: apply_time_dependent);
//   4. joint and contact forces into f_mod (Interactions::add_forces);
//   5. rigid groups: one velocity per group and component from the resultant of its nodes' forces;
//   6. node update (fdem/node_update.hpp): v^{n+1/2}, x^{n+1}, reactions and the books of each block; then the
//      contact dashpots' second half (Interactions::finish_step);
//   7. energy books (block sums in order), servos, time, damage of the joints (Interactions::after_step);
//   8. observers (observe): history, snapshot, files, progress, energy check.
// Determinism: every parallel loop writes per-item results or per-block partial sums over fixed blocks of
// kBlock items; partials are added serially in block order. No result depends on the thread count.
// Energy: with vbar = (v^{n-1/2} + v^{n+1/2}) / 2, the kinetic energy change over a step is exactly
// sum dt f . vbar, so external work and damping are accumulated as dt f . vbar and the balance
// W_ext = K + E_el + D_damp + D_visc holds up to the O(dt^2) error of E_el alone.
#include "fdem/simulation.hpp"

#include <omp.h>
#include <unistd.h>

#include <csignal>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <type_traits>

#include "fdem/common/errors.hpp"
#include "fdem/node_update.hpp"
#include "fdem/sim_detail.hpp"

namespace fdem {

using namespace sim_detail;

double Simulation::contact_xi_max() const {
    // Contact dashpots lower the contact springs' stable step (damped central difference); the largest fraction
    // any stage asks for sets it for the whole run, so that dt stays the same from stage to stage.
    double xi_max = 0;
    for (const StageSpec& st : spec_.stages)
        if (st.contact_damping) xi_max = std::max(xi_max, *st.contact_damping);
    return xi_max;
}

// Per-node mass scaling ([numerics] mass_scaling = "per_node"). Uniform density scaling (mass_scale) lengthens every
// period alike, so the stiffest springs in the model, the contact and joint penalties on the nodes along the joints,
// keep setting the step while the wall's own sway, which sets how fast it can be loaded quasi-statically, grows with
// the whole mass. Here the step is the triangles' limit at mass_scale, and only the nodes whose springs are not
// stable at `margin` (below) times it are made heavier, each just enough (m = k dt^2 / 4 with the bounds of
// stable_dt), as the Itasca codes scale each gridpoint's mass for its own stiffness. The result is only as safe as
// those bounds: both are Gershgorin row sums per node, counting the other side's nodes and every face at the node
// (a bound that counts a single face and not the other side is not safe: a stack on stiff dry joints goes unstable
// at the default safety under it). A tied group (extrinsic insertion) is raised as one: its copies
// keep their shares. Done once, at set-up, on the reference configuration: the masses stay constant in the run (the
// energy books and the restart stay exact), and cracks inserted later may still shrink the step
// (reduce_dt_after_insertion). Gravity keeps the physical mass.
void Simulation::scale_node_masses() {
    if (!spec_.per_node_mass || spec_.dt_override) return;
    const int nn = model_.n_nodes();
    // Each node (a tied group as one: its copies' shares summed at its first node) is made heavy enough that its
    // assembled nodal bound (nodal_step_limit: its triangles' share plus its joint and contact springs' row sums, over
    // its mass) allows the triangles' exact limit dt_t; the step is then safety * dt_t, as in a case without mass
    // scaling whose triangles set the step. (Making the springs alone stable at a margin over dt_t and bounding the
    // sum by Weyl's inequality asks more mass wherever the springs dominate.)
    const double dt = triangle_step_limit(spec_, model_).dt;
    const int* rep = units_.active ? units_.rep.data() : nullptr;
    // The shares of nodal_step_limit, the triangles' summed per triangle into the groups (nodal_step_limit sums its
    // per-node cache instead: the same values up to rounding, and each order is the one the committed results hold).
    std::vector<double> kt(nn, 0.0), kj(nn, 0.0), kc(nn, 0.0);
    add_triangle_node_stiffness(spec_, model_, rep, kt.data());
    inter_.add_node_stiffness(model_, contact_xi_max(), 0.0, rep, kj.data(), kc.data());
    // m >= k dt^2 / 4, with a relative margin of 1e-12 so that rounding leaves the nodal bound at or above dt_t.
    const double q = 0.25 * dt * dt * (1 + 1e-12);
    std::vector<double> need(nn, 0.0);
    for (int k = 0; k < nn; ++k) need[k] = (kt[k] + kj[k] + kc[k]) * q;
    double before = 0, after = 0;
    for (int k = 0; k < nn; ++k) before += model_.mass[k];
    int raised = 0;
    auto raise = [&](int k, double f) {
        model_.mass[k] *= f;
        model_.inv_mass[k] = 1.0 / model_.mass[k];
        ++raised;
    };
    std::vector<char> done(nn, 0);
    if (units_.active) {
        const int ng = static_cast<int>(units_.tie_start.size()) - 1;
        for (int g = 0; g < ng; ++g) {
            double M = 0;
            for (int j = units_.tie_start[g]; j < units_.tie_start[g + 1]; ++j) {
                M += model_.mass[units_.tie_node[j]];
                done[units_.tie_node[j]] = 1;
            }
            const double N = need[units_.tie_node[units_.tie_start[g]]];
            if (N > M)
                for (int j = units_.tie_start[g]; j < units_.tie_start[g + 1]; ++j) raise(units_.tie_node[j], N / M);
        }
    }
    for (int k = 0; k < nn; ++k)
        if (!done[k] && need[k] > model_.mass[k]) raise(k, need[k] / model_.mass[k]);
    for (int k = 0; k < nn; ++k) after += model_.mass[k];
    limits_.mass_raised_nodes = raised;
    limits_.mass_raised_ratio = before > 0 ? after / before : 1.0;
    if (raised > 0) build_ties();  // the groups' masses and the copies' shares
}

Simulation::NodalLimit Simulation::nodal_step_limit(const double* mass, const int* rep, double xi_contact, double alpha) {
    const int nn = model_.n_nodes();
    if (limits_.tri_node_k.size() != static_cast<std::size_t>(nn) || limits_.tri_node_k_alpha != alpha) {
        limits_.tri_node_k.assign(nn, 0.0);
        add_triangle_node_stiffness(spec_, model_, nullptr, limits_.tri_node_k.data(), alpha);
        limits_.tri_node_k_alpha = alpha;
    }
    std::vector<double> kt(nn, 0.0), kj(nn, 0.0), kc(nn, 0.0);
    for (int k = 0; k < nn; ++k) kt[rep ? rep[k] : k] += limits_.tri_node_k[k];
    inter_.add_node_stiffness(model_, xi_contact, alpha, rep, kj.data(), kc.data());
    NodalLimit lim;
    double w2max = 0;  // 1/s^2
    for (int k = 0; k < nn; ++k) {
        if (rep && rep[k] != k) continue;  // a copy: its group is counted at its first node
        const double w2 = (kt[k] + kj[k] + kc[k]) / mass[k];
        if (w2 > w2max) w2max = w2, lim.node = k, lim.k_tri = kt[k], lim.k_joint = kj[k], lim.k_contact = kc[k];
    }
    if (w2max > 0) lim.dt = 2.0 / std::sqrt(w2max);
    return lim;
}

double Simulation::stage_alpha(int s) const {
    double alpha = 0;  // a stage without local_damping keeps the one before it
    for (int i = 0; i <= s && i < static_cast<int>(spec_.stages.size()); ++i)
        if (spec_.stages[i].local_damping) alpha = *spec_.stages[i].local_damping;
    return alpha;
}

void Simulation::set_step_limits(double alpha, bool set_dt) {
    const StepLimit lim = triangle_step_limit(spec_, model_, alpha);
    const double* mass = units_.eff_mass.empty() ? nullptr : units_.eff_mass.data();
    const int* rep = units_.rep.empty() ? nullptr : units_.rep.data();
    limits_.dt_triangles = lim.dt;
    limits_.nodal = nodal_step_limit(mass ? mass : model_.mass.data(), rep, limits_.xi_max, alpha);
    if (!set_dt) return;
    clock_.dt_limit = lim.dt;
    limits_.dt_element = lim.element;
    if (limits_.nodal.dt < clock_.dt_limit) clock_.dt_limit = limits_.nodal.dt, limits_.dt_element = -1;
    clock_.dt = spec_.dt_override ? *spec_.dt_override : spec_.safety * clock_.dt_limit;
}

void Simulation::compute_dt() {
    // The first stage's local damping alpha: each stage that changes it sets the step again (begin_stage), as the
    // damped limit depends on it (damped_step_factor, fdem/model.hpp).
    const double alpha = stage_alpha(0);
    const StepLimit lim = triangle_step_limit(spec_, model_, alpha);
    clock_.dt_limit = limits_.dt_triangles = lim.dt;
    limits_.dt_element = lim.element;
    const double xi_max = contact_xi_max();
    limits_.xi_max = xi_max;
    // Tied copies (extrinsic insertion) move as one node of their group's mass.
    const double* mass = units_.eff_mass.empty() ? nullptr : units_.eff_mass.data();
    const int* rep = units_.rep.empty() ? nullptr : units_.rep.data();
    // The contact dashpots' coefficient beta = xi dt_contact comes from the copies' own masses, as without ties: on a
    // tied group (heavier) that is a smaller fraction of critical, and it stays right for the copies an insertion
    // unties. (From the groups' masses beta grew 1.45-fold on the default wall and a roughened wall's dashpots then
    // booked ten times the work they did: the balance was off by 33 %.)
    limits_.dt_contact = inter_.contact_stable_dt(model_);
    clock_.dt_springs = inter_.stable_dt(model_, xi_max, mass, rep, alpha);
    // The assembled bound: triangles and springs at each node together. The springs' own limit dt_springs (logged)
    // ignores the triangles at the same nodes (alone it can overestimate the limit where both are alike) and counts
    // the faces of intact joints, which cannot touch yet.
    limits_.nodal = nodal_step_limit(mass ? mass : model_.mass.data(), rep, xi_max, alpha);
    if (limits_.nodal.dt < clock_.dt_limit) clock_.dt_limit = limits_.nodal.dt, limits_.dt_element = -1;
    clock_.dt = spec_.dt_override ? *spec_.dt_override : spec_.safety * clock_.dt_limit;
}

void Simulation::build_ties() {
    units_.shared_threads = 0;  // the node loop's blocks change: the contact scatter is told the new shares
    const fracture::CohesiveSystem* J = inter_.joints();
    units_.active = J && J->dormant_count() > 0;
    const int nn = model_.n_nodes();
    units_.tie_of.clear(), units_.tie_start.clear(), units_.tie_node.clear();
    if (!units_.active) {
        units_.tie_w.clear(), units_.eff_mass.clear(), units_.rep.clear();
        units_.start.clear(), units_.node.clear(), units_.mass.clear(), units_.inv_mass.clear(), units_.block.clear();
        units_.slot.clear();
        return;
    }
    std::vector<int> parent(nn);
    for (int k = 0; k < nn; ++k) parent[k] = k;
    auto find = [&parent](int k) {
        while (parent[k] != k) k = parent[k] = parent[parent[k]];
        return k;
    };
    for (int e = 0; e < J->size(); ++e) {
        if (!J->dormant(e)) continue;
        const int* n = J->element(e).n;
        for (int k = 0; k < 2; ++k) {
            const int a = find(n[k]), b = find(n[2 + k]);
            if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the root is the smallest member
        }
    }
    // Groups of two or more, in order of their smallest member (the root), members ascending.
    std::vector<int> count(nn, 0);
    for (int k = 0; k < nn; ++k) ++count[find(k)];
    units_.tie_of.assign(nn, -1);
    std::vector<int> gid(nn, -1);
    int ng = 0;
    for (int k = 0; k < nn; ++k)
        if (parent[k] == k && count[k] > 1) gid[k] = ng++;
    units_.tie_start.assign(ng + 1, 0);
    for (int k = 0; k < nn; ++k)
        if (gid[find(k)] >= 0) ++units_.tie_start[gid[find(k)] + 1];
    for (int g = 0; g < ng; ++g) units_.tie_start[g + 1] += units_.tie_start[g];
    units_.tie_node.assign(units_.tie_start[ng], 0);
    std::vector<int> fill(units_.tie_start.begin(), units_.tie_start.end() - 1);
    for (int k = 0; k < nn; ++k) {
        const int g = gid[find(k)];
        if (g < 0) continue;
        units_.tie_of[k] = g;
        units_.tie_node[fill[g]++] = k;
    }
    units_.tie_w.assign(nn, 1.0);
    units_.eff_mass = model_.mass;
    units_.rep.resize(nn);
    for (int k = 0; k < nn; ++k) units_.rep[k] = k;
    for (int g = 0; g < ng; ++g) {
        double M = 0;
        for (int j = units_.tie_start[g]; j < units_.tie_start[g + 1]; ++j) M += model_.mass[units_.tie_node[j]];
        for (int j = units_.tie_start[g]; j < units_.tie_start[g + 1]; ++j) {
            const int k = units_.tie_node[j];
            units_.tie_w[k] = model_.mass[k] / M;
            units_.eff_mass[k] = M;
            units_.rep[k] = units_.tie_node[units_.tie_start[g]];
        }
    }
    // The node loop's units, in order of their first node: a lone node, or a group with its members.
    units_.start.assign(1, 0), units_.node.clear(), units_.mass.clear(), units_.inv_mass.clear();
    units_.node.reserve(nn);
    for (int k = 0; k < nn; ++k) {
        const int g = units_.tie_of[k];
        if (g >= 0 && units_.tie_node[units_.tie_start[g]] != k) continue;  // a copy after its group's first
        if (g < 0) {
            units_.node.push_back(k);
        } else {
            for (int j = units_.tie_start[g]; j < units_.tie_start[g + 1]; ++j)
                units_.node.push_back(units_.tie_node[j]);
        }
        units_.start.push_back(static_cast<int>(units_.node.size()));
        units_.mass.push_back(g >= 0 ? units_.eff_mass[k] : model_.mass[k]);
        units_.inv_mass.push_back(g >= 0 ? 1.0 / units_.eff_mass[k] : model_.inv_mass[k]);
    }
    // Each member's triangle-force slot when it has exactly one (a copy, in its one triangle), else -1: the node loop
    // then reads it without the incidence lists.
    units_.slot.resize(units_.node.size());
    for (std::size_t j = 0; j < units_.node.size(); ++j) {
        const int k = units_.node[j];
        units_.slot[j] = model_.inc_ptr[k + 1] - model_.inc_ptr[k] == 1 ? model_.inc_idx[model_.inc_ptr[k]] : -1;
    }
    // Blocks of whole units with at least kBlock members each (the last may have fewer): the same work per block
    // whatever the mix of groups and lone nodes, and no more blocks than ceil(nn / kBlock).
    const int n_units = static_cast<int>(units_.start.size()) - 1;
    units_.block.assign(1, 0);
    for (int u = 0; u < n_units; ++u)
        if (units_.start[u + 1] - units_.start[units_.block.back()] >= kBlock || u + 1 == n_units)
            units_.block.push_back(u + 1);
    if (clock_.stage >= 0) check_ties();
}

int Simulation::node_block_count() const {
    return units_.active ? static_cast<int>(units_.block.size()) - 1 : (model_.n_nodes() + kBlock - 1) / kBlock;
}

void Simulation::share_nodes_with_contact(int n_thr) {
    units_.shared_threads = n_thr;
    if (n_thr > 255) return;  // (the scatter then takes its own shares, node k to thread k * T / nn)
    // The node loop's blocks (units of tied copies, or kBlock nodes) and each thread's share of them, as in step().
    const int nn = model_.n_nodes();
    const int nnb = node_block_count();
    std::vector<unsigned char> owner(nn, 0);
    for (int t = 0; t < n_thr; ++t)
        for (int b = share_begin(nnb, n_thr, t); b < share_begin(nnb, n_thr, t + 1); ++b) {
            if (!units_.active) {
                for (int k = b * kBlock; k < std::min(nn, (b + 1) * kBlock); ++k) owner[k] = static_cast<unsigned char>(t);
                continue;
            }
            for (int j = units_.start[units_.block[b]]; j < units_.start[units_.block[b + 1]]; ++j)
                owner[units_.node[j]] = static_cast<unsigned char>(t);
        }
    inter_.set_node_owner(std::move(owner), n_thr);
}

void Simulation::reduce_dt_after_insertion() {
    if (spec_.dt_override) return;  // numerics.dt: the user's step
    const double* mass = units_.eff_mass.empty() ? nullptr : units_.eff_mass.data();
    const int* rep = units_.rep.empty() ? nullptr : units_.rep.data();
    // The contact dashpots keep their coefficient beta = xi dt_contact of the copies' masses (compute_dt): at most
    // xi of critical on any node, so xi bounds the damped step.
    const double springs = nodal_step_limit(mass ? mass : model_.mass.data(), rep, limits_.xi_max, damping_.local).dt;
    const double dt = spec_.safety * std::min(limits_.dt_triangles, springs);
    if (!(dt < clock_.dt)) return;
    clock_.dt = dt;
    if (springs < clock_.dt_limit) clock_.dt_limit = springs, clock_.dt_springs = springs, limits_.dt_element = -1;
    if (clock_.dt < 0.9 * clock_.dt_logged) {
        clock_.dt_logged = clock_.dt;
        log("time step: " + sci(clock_.dt) + " s from t = " + sci(clock_.time) +
            " s (cracks inserted or joints broken: new faces for contact)");
    }
}

void Simulation::check_ties() const {
    if (!units_.active) return;
    const int ng = static_cast<int>(units_.tie_start.size()) - 1;
    for (int g = 0; g < ng; ++g) {
        const int k0 = units_.tie_node[units_.tie_start[g]];
        for (int j = units_.tie_start[g] + 1; j < units_.tie_start[g + 1]; ++j) {
            const int k = units_.tie_node[j];
            for (int c = 0; c < 2; ++c) {
                const int d0 = 2 * k0 + c, d = 2 * k + c;
                if (supports_.dof_kind[d] == supports_.dof_kind[d0] &&
                    supports_.dof_owner[d] == supports_.dof_owner[d0])
                    continue;
                const int owner = supports_.dof_owner[d] >= 0 ? supports_.dof_owner[d] : supports_.dof_owner[d0];
                const std::string grp = owner >= 0 ? supports_.list[owner]->group : std::string("?");
                throw InputError(spec_.file + ": stage " + std::to_string(clock_.stage + 1) +
                                 ": the support of group '" + grp + "' holds only some of the copies of the node at (" +
                                 sci(model_.X[2 * k], 6) + ", " + sci(model_.X[2 * k + 1], 6) +
                                 ") m, which move as one node until a crack is inserted "
                                 "there (insertion = \"extrinsic\"); expected a group that takes every copy (a box, "
                                 "or a curve or surface of the whole unit)");
            }
        }
    }
}

// The triangles' forces at x^n, v^{n-1/2} into scratch_.tri_forces (6 per triangle), in parallel by blocks, crushing
// triangles through fdem/plasticity.hpp; tsig (extrinsic insertion, else null): their stresses. Returns the viscous
// power (W) summed by blocks in order; stops the run at the first inverted triangle.
double Simulation::triangle_stage(double* tsig) {
    const int nt = model_.n_triangles();
    const TriangleRef* tris = model_.tris.data();
    const MaterialConst* mats = model_.mat.data();
    const double* x = model_.x.data();
    const double* v = model_.v.data();
    double* tf = scratch_.tri_forces.data();
    const int ntb = (nt + kBlock - 1) / kBlock;
#pragma omp parallel if (ntb > 1)
    for (int b = block_share_begin(nt, omp_get_num_threads(), omp_get_thread_num());
         b < block_share_begin(nt, omp_get_num_threads(), omp_get_thread_num() + 1); ++b) {
        double pv = 0;
        int bad = -1;
        const int e1 = std::min(nt, (b + 1) * kBlock);
        for (int e = b * kBlock; e < e1; ++e) {
            double p;
            const int cs = crush_.slot(e);  // crushing triangles: fdem/plasticity.hpp (state updated per triangle)
            double* sig = tsig ? tsig + 3 * static_cast<std::size_t>(e) : nullptr;
            const double J = cs < 0 ? triangle_forces(tris[e], mats[tris[e].mat], x, v, tf + 6 * static_cast<std::size_t>(e), p, sig)
                                    : crush_.forces(cs, tris[e], x, v, tf + 6 * static_cast<std::size_t>(e), p);
            if (sig && cs >= 0) triangle_stress(tris[e], mats[tris[e].mat], x, sig);  // elastic stress (not extrinsic)
            if (!(J > 0) && bad < 0) bad = e;
            pv += p;
        }
        scratch_.tri_power[b] = pv;
        scratch_.tri_bad[b] = bad;
    }
    double visc_power = 0;
    for (int b = 0; b < ntb; ++b) {
        visc_power += scratch_.tri_power[b];
        if (scratch_.tri_bad[b] >= 0) {
            const int e = scratch_.tri_bad[b];
            const TriangleRef& t = tris[e];
            const double cx = (x[2 * t.n[0]] + x[2 * t.n[1]] + x[2 * t.n[2]]) / 3, cy = (x[2 * t.n[0] + 1] + x[2 * t.n[1] + 1] + x[2 * t.n[2] + 1]) / 3;
            fail("triangle " + std::to_string(e) + " (region '" + model_.mesh.regions[model_.mesh.tri_region[e]] +
                 "') inverted (J <= 0) at (" + sci(cx, 6) + ", " + sci(cy, 6) + ") m");
        }
    }

    return visc_power;
}

void Simulation::step() {
    const double w0 = omp_get_wtime();
    if (spec_.energy_audit) audit_step(0, clock_.dt);
    const double dt_before = clock_.dt;
    const int nt = model_.n_triangles(), nn = model_.n_nodes();
    const double* x = model_.x.data();
    const double* v = model_.v.data();
    double* tf = scratch_.tri_forces.data();
    // Extrinsic insertion: the triangles' stresses of this step for the check below (ties only).
    if (units_.active) scratch_.tri_sigma.resize(3 * static_cast<std::size_t>(nt));
    double* tsig = units_.active ? scratch_.tri_sigma.data() : nullptr;

    // 1. Triangle forces; per block: viscous power and the first inverted triangle.
    const double w1 = omp_get_wtime();
    const double visc_power = triangle_stage(tsig);
    const double wi = omp_get_wtime();
    // 2-3. Extrinsic insertion: dormant edges whose traction reached the strength get their cohesive element before this
    // step's joint forces, their copies are untied, and the step shrinks if the lighter nodes need it. The velocity
    // update of a step that changed it spans the mean of the two steps (central difference with a variable step,
    // v^{n+1/2} = v^{n-1/2} + (dt^{n-1/2} + dt^{n+1/2}) / 2 a^n; Belytschko, Liu & Moran, Nonlinear Finite Elements
    // for Continua and Structures, 2000, §6.2).
    if (units_.active && inter_.insert_cracks(x, tsig) > 0) {
        build_ties();
        reduce_dt_after_insertion();
    }
    const double dt = clock_.dt;
    const double dtv = 0.5 * (dt_before + dt);
    apply_time_dependent(clock_.time);

    // 4. Joint and contact forces, added to scratch_.f_mod in a fixed order by their modules. The contact energy is
    // only evaluated on the steps whose energies are reported or checked.
    inter_.want_energy(history_due(clock_.time + dt, clock_.steps + 1) || (clock_.steps + 1) % 1000 == 0 ||
                       energy_every_step_);
    const double w2 = omp_get_wtime();
    inter_.add_forces(x, v, dt, scratch_.f_mod.data(), spec_.energy_audit ? audit_.fj.data() : nullptr,
                      scratch_.f_mod.size(), scratch_.v2max);
    if (spec_.energy_audit) audit_step(1, dt);
    const double w3 = omp_get_wtime();

    // 5. Rigid groups first: one velocity per group and component from the resultant of its nodes' forces,
    // v^{n+1/2} = v^{n-1/2} + dt (F + F_d) / M with F = sum of the nodal forces, M = sum of the nodal masses and the
    // [C79] local damping F_d = -alpha |F| sign(v) on the resultant. The node loop then treats those DOFs as
    // prescribed: their reactions redistribute the forces inside the group and sum to F_d, which the loop books as
    // work; rigid_damp_ moves that share from work to damping after the loop. Serial, in support and node order.
    // Filtered local damping: each DOF's moving mean vref += wf (v - vref), the exact one-step weight of an
    // exponential mean over tau for a velocity held over the step.
    const double wf = damping_.filter_tau > 0 ? -std::expm1(-dt / damping_.filter_tau) : 0.0;
    double* vref = damping_.filter_tau > 0 ? damping_.v_ref.data() : nullptr;
    const double hm = 0.5 * dtv * damping_.mass;
    // (fdem/support_rigid.cpp; the sums, J: dt F_d v_bar and dt/2 F_d v^{n+1/2}, the same for the mass-proportional
    // damping force -a M v_bar)
    RigidStep rs{model_,
                 scratch_.f_mod.data(),
                 loads_.f_ext.data(),
                 tf,
                 gravity_.applied,
                 damping_.local,
                 damping_.filter_tau,
                 wf,
                 damping_.mass,
                 hm,
                 dt,
                 dtv,
                 supports_.dof_velocity.data(),
                 supports_.dof_owner.data(),
                 supports_.list.data(),
                 static_cast<int>(supports_.list.size())};
    for (std::size_t id = 0; id < supports_.list.size(); ++id) supports_.list[id]->rigid_step(rs, static_cast<int>(id));
    const double rigid_damp = rs.damp, rigid_damp_half = rs.damp_half, rigid_mass = rs.mass, rigid_mass_half = rs.mass_half;

    // 6. Node loop, one unit at a time: a node, or a group of tied copies (extrinsic insertion), which moves as one
    // node of the group's mass M: the resultant F of its members' forces gives every member the same velocity
    // (v^{n+1/2} from F / M, the bits a lone node of mass M takes), and the group's books (work, damping, kinetic
    // energy, unbalanced force) are those of that node. The unbalanced-force scale takes every member's own forces.
    // A prescribed DOF (a support takes every copy, check_ties) has each member's reaction of its mass share
    // w = m / M of F.
    const bool tied = units_.active;
    const int nnb = node_block_count();
    NodeUpdate nu_args;
    nu_args.n_units = tied ? static_cast<int>(units_.start.size()) - 1 : nn;
    nu_args.tied = tied;
    if (tied) {
        nu_args.u_start = units_.start.data(), nu_args.u_node = units_.node.data(), nu_args.u_slot = units_.slot.data();
        nu_args.u_mass = units_.mass.data(), nu_args.u_inv = units_.inv_mass.data(),
        nu_args.tie_w = units_.tie_w.data();
        nu_args.u_block = units_.block.data();
    }
    nu_args.tri_forces = tf;
    nu_args.inc_ptr = model_.inc_ptr.data(), nu_args.inc_idx = model_.inc_idx.data();
    nu_args.mass = model_.mass.data(), nu_args.grav_mass = model_.grav_mass.data(), nu_args.inv_mass = model_.inv_mass.data();
    nu_args.f_ext = loads_.f_ext.data(), nu_args.loaded = scratch_.node_loaded.data();
    nu_args.f_mod = scratch_.f_mod.data();
    nu_args.reset_fmod = inter_.has_joints() || inter_.has_contact();  // the modules that add to scratch_.f_mod
    nu_args.dof_kind = supports_.dof_kind.data(), nu_args.dof_velocity = supports_.dof_velocity.data(),
    nu_args.reaction = supports_.reaction.data();
    nu_args.x = model_.x.data(), nu_args.v = model_.v.data(), nu_args.v_ref = vref;
    nu_args.dt = dt, nu_args.dtv = dtv, nu_args.alpha = damping_.local, nu_args.beta_mass = damping_.mass,
    nu_args.hm = hm, nu_args.wf = wf;
    nu_args.gx = gravity_.applied[0], nu_args.gy = gravity_.applied[1];
    // Each thread takes a static share of the blocks (share_begin), the same nodes every step.
    const int n_thr = nnb > 1 ? omp_get_max_threads() : 1;
    if (n_thr != units_.shared_threads) share_nodes_with_contact(n_thr);
    scratch_.node_sums.resize(static_cast<std::size_t>(nnb));
    update_nodes(nu_args, scratch_.node_sums);
    inter_.finish_step(model_.v.data());
    if (spec_.energy_audit) audit_step(2, dt);
    double dW = 0, dD = 0, unb = 0, scale = 0, dM = 0;
    books_.kinetic_n = 0, books_.work_half = 0, books_.damp_half = 0, books_.mass_half = 0;
    scratch_.v2max = 0.0;
    for (int b = 0; b < nnb; ++b) {
        const NodeBlockSums& nb = scratch_.node_sums[b];
        scratch_.v2max = std::max(scratch_.v2max, nb.v2);
        dW += nb.work, dD += nb.damping, unb += nb.unbalanced, scale += nb.scale;
        books_.kinetic_n += nb.kinetic, books_.work_half += nb.work_half, books_.damp_half += nb.damping_half;
        dM += nb.mass, books_.mass_half += nb.mass_half;
        if (nb.bad >= 0) {
            const int k = nb.bad;
            fail("node " + std::to_string(k) + " has a non-finite velocity (NaN/inf) near (" + sci(model_.X[2 * k], 6) + ", " +
                 sci(model_.X[2 * k + 1], 6) + ") m");
        }
    }
    dW -= rigid_damp, dD -= rigid_damp;
    books_.work_half -= rigid_damp_half, books_.damp_half -= rigid_damp_half;
    // The rigid groups' reactions carried their mass damping force too: from work to damping, like F_d.
    dW -= rigid_mass, dM -= rigid_mass;
    books_.work_half -= rigid_mass_half, books_.mass_half -= rigid_mass_half;
    books_.D_mass += dM;
    books_.W_ext += dW;
    books_.D_damp += dD;
    books_.D_visc += dt * visc_power;
    books_.unbalanced_ratio = scale > 0 ? unb / scale : 0;
    const double w4 = omp_get_wtime();
    step_times_.triangles += wi - w1;
    step_times_.interactions += w3 - w2;
    step_times_.integration += w4 - w3;
    step_times_.other += (w1 - w0) + (w2 - wi);  // with the insertion check and the loads of the step
    supports_after_step();
    clock_.time += dt;
    gravity_.tilt_deg += gravity_.tilt_rate * dt;
    ++clock_.steps;
    if (inter_.has_joints()) {
        const int broke = inter_.after_step(clock_.time, control_displacement(), model_.x.data());
        clock_.broken_total += broke;
        if (broke > 0) reduce_dt_after_insertion();  // broken elements' faces join the contact count
    }

    observe(dt);
    step_times_.other += omp_get_wtime() - w4;
}

// After a step of length dt (the observers): the history row with the dry joints' record, the snapshot, the periodic
// flush of the files, progress, and every 1000 steps the energy check (which may stop the run). Nothing here
// changes what the next step computes.
void Simulation::observe(double dt) {
    if (!opt_.out_dir.empty()) {
        if (history_due(clock_.time, clock_.steps)) {
            const double hi = history_interval();
            record_dry_joints();
            write_history_row();
            if (hi > 0) out_.next_history += hi * std::max(1.0, std::floor((clock_.time - out_.next_history) / hi) + 1);
        }
        if (clock_.time + 1e-9 * dt >= out_.next_snapshot) {
            write_snapshot();
            const double si = snapshot_interval();
            out_.next_snapshot += si * std::max(1.0, std::floor((clock_.time - out_.next_snapshot) / si) + 1);
        }
        if ((clock_.steps & 255) == 0) {
            const double now = wall_clock();
            if (now - last_flush_ > 5) flush_files();
        }
    }
    if (opt_.progress && (clock_.steps & 255) == 0) progress_line(false);
    if (opt_.progress_log && (clock_.steps & 255) == 0) progress_log_line();
    if (clock_.steps % 1000 == 0) {
        const Energies e = energies();
        if (spec_.energy_audit) log(audit_text(e));
        check_energy(e);
    }
}

}  // namespace fdem
