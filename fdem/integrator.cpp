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
    const int* rep = ties_ ? tie_rep_.data() : nullptr;
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
    if (ties_) {
        const int ng = static_cast<int>(tie_start_.size()) - 1;
        for (int g = 0; g < ng; ++g) {
            double M = 0;
            for (int j = tie_start_[g]; j < tie_start_[g + 1]; ++j) {
                M += model_.mass[tie_node_[j]];
                done[tie_node_[j]] = 1;
            }
            const double N = need[tie_node_[tie_start_[g]]];
            if (N > M)
                for (int j = tie_start_[g]; j < tie_start_[g + 1]; ++j) raise(tie_node_[j], N / M);
        }
    }
    for (int k = 0; k < nn; ++k)
        if (!done[k] && need[k] > model_.mass[k]) raise(k, need[k] / model_.mass[k]);
    for (int k = 0; k < nn; ++k) after += model_.mass[k];
    mass_raised_nodes_ = raised;
    mass_raised_ratio_ = before > 0 ? after / before : 1.0;
    if (raised > 0) build_ties();  // the groups' masses and the copies' shares
}

Simulation::NodalLimit Simulation::nodal_step_limit(const double* mass, const int* rep, double xi_contact, double alpha) {
    const int nn = model_.n_nodes();
    if (tri_node_k_.size() != static_cast<std::size_t>(nn) || tri_node_k_alpha_ != alpha) {
        tri_node_k_.assign(nn, 0.0);
        add_triangle_node_stiffness(spec_, model_, nullptr, tri_node_k_.data(), alpha);
        tri_node_k_alpha_ = alpha;
    }
    std::vector<double> kt(nn, 0.0), kj(nn, 0.0), kc(nn, 0.0);
    for (int k = 0; k < nn; ++k) kt[rep ? rep[k] : k] += tri_node_k_[k];
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
    const double* mass = eff_mass_.empty() ? nullptr : eff_mass_.data();
    const int* rep = tie_rep_.empty() ? nullptr : tie_rep_.data();
    dt_triangles_ = lim.dt;
    dt_nodal_ = nodal_step_limit(mass ? mass : model_.mass.data(), rep, xi_max_, alpha);
    if (!set_dt) return;
    dt_limit_ = lim.dt;
    dt_element_ = lim.element;
    if (dt_nodal_.dt < dt_limit_) dt_limit_ = dt_nodal_.dt, dt_element_ = -1;
    dt_ = spec_.dt_override ? *spec_.dt_override : spec_.safety * dt_limit_;
}

void Simulation::compute_dt() {
    // The first stage's local damping alpha: each stage that changes it sets the step again (begin_stage), as the
    // damped limit depends on it (damped_step_factor, fdem/model.hpp).
    const double alpha = stage_alpha(0);
    const StepLimit lim = triangle_step_limit(spec_, model_, alpha);
    dt_limit_ = dt_triangles_ = lim.dt;
    dt_element_ = lim.element;
    const double xi_max = contact_xi_max();
    xi_max_ = xi_max;
    // Tied copies (extrinsic insertion) move as one node of their group's mass.
    const double* mass = eff_mass_.empty() ? nullptr : eff_mass_.data();
    const int* rep = tie_rep_.empty() ? nullptr : tie_rep_.data();
    // The contact dashpots' coefficient beta = xi dt_contact_ comes from the copies' own masses, as without ties: on a
    // tied group (heavier) that is a smaller fraction of critical, and it stays right for the copies an insertion
    // unties. (From the groups' masses beta grew 1.45-fold on the default wall and a roughened wall's dashpots then
    // booked ten times the work they did: the balance was off by 33 %.)
    dt_contact_ = inter_.contact_stable_dt(model_);
    dt_springs_ = inter_.stable_dt(model_, xi_max, mass, rep, alpha);
    // The assembled bound: triangles and springs at each node together. The springs' own limit dt_springs_ (logged)
    // ignores the triangles at the same nodes (alone it can overestimate the limit where both are alike) and counts
    // the faces of intact joints, which cannot touch yet.
    dt_nodal_ = nodal_step_limit(mass ? mass : model_.mass.data(), rep, xi_max, alpha);
    if (dt_nodal_.dt < dt_limit_) dt_limit_ = dt_nodal_.dt, dt_element_ = -1;
    dt_ = spec_.dt_override ? *spec_.dt_override : spec_.safety * dt_limit_;
}

void Simulation::build_ties() {
    node_part_threads_ = 0;  // the node loop's blocks change: the contact scatter is told the new shares
    const fracture::CohesiveSystem* J = inter_.joints();
    ties_ = J && J->dormant_count() > 0;
    const int nn = model_.n_nodes();
    tie_of_.clear(), tie_start_.clear(), tie_node_.clear();
    if (!ties_) {
        tie_w_.clear(), eff_mass_.clear(), tie_rep_.clear();
        unit_start_.clear(), unit_node_.clear(), unit_mass_.clear(), unit_inv_mass_.clear(), unit_block_.clear();
        unit_slot_.clear();
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
    tie_of_.assign(nn, -1);
    std::vector<int> gid(nn, -1);
    int ng = 0;
    for (int k = 0; k < nn; ++k)
        if (parent[k] == k && count[k] > 1) gid[k] = ng++;
    tie_start_.assign(ng + 1, 0);
    for (int k = 0; k < nn; ++k)
        if (gid[find(k)] >= 0) ++tie_start_[gid[find(k)] + 1];
    for (int g = 0; g < ng; ++g) tie_start_[g + 1] += tie_start_[g];
    tie_node_.assign(tie_start_[ng], 0);
    std::vector<int> fill(tie_start_.begin(), tie_start_.end() - 1);
    for (int k = 0; k < nn; ++k) {
        const int g = gid[find(k)];
        if (g < 0) continue;
        tie_of_[k] = g;
        tie_node_[fill[g]++] = k;
    }
    tie_w_.assign(nn, 1.0);
    eff_mass_ = model_.mass;
    tie_rep_.resize(nn);
    for (int k = 0; k < nn; ++k) tie_rep_[k] = k;
    for (int g = 0; g < ng; ++g) {
        double M = 0;
        for (int j = tie_start_[g]; j < tie_start_[g + 1]; ++j) M += model_.mass[tie_node_[j]];
        for (int j = tie_start_[g]; j < tie_start_[g + 1]; ++j) {
            const int k = tie_node_[j];
            tie_w_[k] = model_.mass[k] / M;
            eff_mass_[k] = M;
            tie_rep_[k] = tie_node_[tie_start_[g]];
        }
    }
    // The node loop's units, in order of their first node: a lone node, or a group with its members.
    unit_start_.assign(1, 0), unit_node_.clear(), unit_mass_.clear(), unit_inv_mass_.clear();
    unit_node_.reserve(nn);
    for (int k = 0; k < nn; ++k) {
        const int g = tie_of_[k];
        if (g >= 0 && tie_node_[tie_start_[g]] != k) continue;  // a copy after its group's first
        if (g < 0) {
            unit_node_.push_back(k);
        } else {
            for (int j = tie_start_[g]; j < tie_start_[g + 1]; ++j) unit_node_.push_back(tie_node_[j]);
        }
        unit_start_.push_back(static_cast<int>(unit_node_.size()));
        unit_mass_.push_back(g >= 0 ? eff_mass_[k] : model_.mass[k]);
        unit_inv_mass_.push_back(g >= 0 ? 1.0 / eff_mass_[k] : model_.inv_mass[k]);
    }
    // Each member's triangle-force slot when it has exactly one (a copy, in its one triangle), else -1: the node loop
    // then reads it without the incidence lists.
    unit_slot_.resize(unit_node_.size());
    for (std::size_t j = 0; j < unit_node_.size(); ++j) {
        const int k = unit_node_[j];
        unit_slot_[j] = model_.inc_ptr[k + 1] - model_.inc_ptr[k] == 1 ? model_.inc_idx[model_.inc_ptr[k]] : -1;
    }
    // Blocks of whole units with at least kBlock members each (the last may have fewer): the same work per block
    // whatever the mix of groups and lone nodes, and no more blocks than ceil(nn / kBlock).
    const int nu = static_cast<int>(unit_start_.size()) - 1;
    unit_block_.assign(1, 0);
    for (int u = 0; u < nu; ++u)
        if (unit_start_[u + 1] - unit_start_[unit_block_.back()] >= kBlock || u + 1 == nu) unit_block_.push_back(u + 1);
    if (stage_ >= 0) check_ties();
}

int Simulation::node_block_count() const {
    return ties_ ? static_cast<int>(unit_block_.size()) - 1 : (model_.n_nodes() + kBlock - 1) / kBlock;
}

void Simulation::share_nodes_with_contact(int n_thr) {
    node_part_threads_ = n_thr;
    if (n_thr > 255) return;  // (the scatter then takes its own shares, node k to thread k * T / nn)
    // The node loop's blocks (units of tied copies, or kBlock nodes) and each thread's share of them, as in step().
    const int nn = model_.n_nodes();
    const int nnb = node_block_count();
    std::vector<unsigned char> owner(nn, 0);
    for (int t = 0; t < n_thr; ++t)
        for (int b = share_begin(nnb, n_thr, t); b < share_begin(nnb, n_thr, t + 1); ++b) {
            if (!ties_) {
                for (int k = b * kBlock; k < std::min(nn, (b + 1) * kBlock); ++k) owner[k] = static_cast<unsigned char>(t);
                continue;
            }
            for (int j = unit_start_[unit_block_[b]]; j < unit_start_[unit_block_[b + 1]]; ++j)
                owner[unit_node_[j]] = static_cast<unsigned char>(t);
        }
    inter_.set_node_owner(std::move(owner), n_thr);
}

void Simulation::reduce_dt_after_insertion() {
    if (spec_.dt_override) return;  // numerics.dt: the user's step
    const double* mass = eff_mass_.empty() ? nullptr : eff_mass_.data();
    const int* rep = tie_rep_.empty() ? nullptr : tie_rep_.data();
    // The contact dashpots keep their coefficient beta = xi dt_contact_ of the copies' masses (compute_dt): at most
    // xi of critical on any node, so xi bounds the damped step.
    const double springs = nodal_step_limit(mass ? mass : model_.mass.data(), rep, xi_max_, alpha_).dt;
    const double dt = spec_.safety * std::min(dt_triangles_, springs);
    if (!(dt < dt_)) return;
    dt_ = dt;
    if (springs < dt_limit_) dt_limit_ = springs, dt_springs_ = springs, dt_element_ = -1;
    if (dt_ < 0.9 * dt_logged_) {
        dt_logged_ = dt_;
        log("time step: " + sci(dt_) + " s from t = " + sci(time_) + " s (cracks inserted or joints broken: new faces for contact)");
    }
}

void Simulation::check_ties() const {
    if (!ties_) return;
    const int ng = static_cast<int>(tie_start_.size()) - 1;
    for (int g = 0; g < ng; ++g) {
        const int k0 = tie_node_[tie_start_[g]];
        for (int j = tie_start_[g] + 1; j < tie_start_[g + 1]; ++j) {
            const int k = tie_node_[j];
            for (int c = 0; c < 2; ++c) {
                const int d0 = 2 * k0 + c, d = 2 * k + c;
                if (dof_kind_[d] == dof_kind_[d0] && dof_owner_[d] == dof_owner_[d0]) continue;
                const int owner = dof_owner_[d] >= 0 ? dof_owner_[d] : dof_owner_[d0];
                const std::string grp = owner >= 0 ? supports_[owner]->group : std::string("?");
                throw InputError(spec_.file + ": stage " + std::to_string(stage_ + 1) + ": the support of group '" + grp +
                                 "' holds only some of the copies of the node at (" + sci(model_.X[2 * k], 6) + ", " +
                                 sci(model_.X[2 * k + 1], 6) + ") m, which move as one node until a crack is inserted "
                                 "there (insertion = \"extrinsic\"); expected a group that takes every copy (a box, "
                                 "or a curve or surface of the whole unit)");
            }
        }
    }
}

// The triangles' forces at x^n, v^{n-1/2} into tf_ (6 per triangle), in parallel by blocks, crushing triangles
// through fdem/plasticity.hpp; tsig (extrinsic insertion, else null): their stresses. Returns the viscous power (W)
// summed by blocks in order; stops the run at the first inverted triangle.
double Simulation::triangle_stage(double* tsig) {
    const int nt = model_.n_triangles();
    const TriangleRef* tris = model_.tris.data();
    const MaterialConst* mats = model_.mat.data();
    const double* x = model_.x.data();
    const double* v = model_.v.data();
    double* tf = tf_.data();
    const int ntb = (nt + kBlock - 1) / kBlock;
#pragma omp parallel if (ntb > 1)
    for (int b = block_share_begin(nt, omp_get_num_threads(), omp_get_thread_num());
         b < block_share_begin(nt, omp_get_num_threads(), omp_get_thread_num() + 1); ++b) {
        double pv = 0;
        int bad = -1;
        const int e1 = std::min(nt, (b + 1) * kBlock);
        if (!tsig && !crush_.active()) triangle_forces_range(tris, mats, x, v, tf, b * kBlock, e1, pv, bad);
        else
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
        tri_power_[b] = pv;
        tri_bad_[b] = bad;
    }
    double visc_power = 0;
    for (int b = 0; b < ntb; ++b) {
        visc_power += tri_power_[b];
        if (tri_bad_[b] >= 0) {
            const int e = tri_bad_[b];
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
    if (spec_.energy_audit) audit_step(0, dt_);
    const double dt_before = dt_;
    const int nt = model_.n_triangles(), nn = model_.n_nodes();
    const double* x = model_.x.data();
    const double* v = model_.v.data();
    double* tf = tf_.data();
    // Extrinsic insertion: the triangles' stresses of this step for the check below (ties only).
    if (ties_) tri_sigma_.resize(3 * static_cast<std::size_t>(nt));
    double* tsig = ties_ ? tri_sigma_.data() : nullptr;

    // 1. Triangle forces; per block: viscous power and the first inverted triangle.
    const double w1 = omp_get_wtime();
    const double visc_power = triangle_stage(tsig);
    const double wi = omp_get_wtime();
    // 2-3. Extrinsic insertion: dormant edges whose traction reached the strength get their cohesive element before this
    // step's joint forces, their copies are untied, and the step shrinks if the lighter nodes need it. The velocity
    // update of a step that changed it spans the mean of the two steps (central difference with a variable step,
    // v^{n+1/2} = v^{n-1/2} + (dt^{n-1/2} + dt^{n+1/2}) / 2 a^n; Belytschko, Liu & Moran, Nonlinear Finite Elements
    // for Continua and Structures, 2000, §6.2).
    if (ties_ && inter_.insert_cracks(x, tsig) > 0) {
        build_ties();
        reduce_dt_after_insertion();
    }
    const double dt = dt_;
    const double dtv = 0.5 * (dt_before + dt);
    apply_time_dependent(time_);

    // 4. Joint and contact forces, added to f_mod_ in a fixed order by their modules. The contact energy is only
    // evaluated on the steps whose energies are reported or checked.
    inter_.want_energy(history_due(time_ + dt, steps_ + 1) || (steps_ + 1) % 1000 == 0 || energy_every_step_);
    const double w2 = omp_get_wtime();
    inter_.add_forces(x, v, dt, f_mod_.data(), spec_.energy_audit ? audit_fj_.data() : nullptr, f_mod_.size(), v2max_);
    if (spec_.energy_audit) audit_step(1, dt);
    const double w3 = omp_get_wtime();

    // 5. Rigid groups first: one velocity per group and component from the resultant of its nodes' forces,
    // v^{n+1/2} = v^{n-1/2} + dt (F + F_d) / M with F = sum of the nodal forces, M = sum of the nodal masses and the
    // [C79] local damping F_d = -alpha |F| sign(v) on the resultant. The node loop then treats those DOFs as
    // prescribed: their reactions redistribute the forces inside the group and sum to F_d, which the loop books as
    // work; rigid_damp_ moves that share from work to damping after the loop. Serial, in support and node order.
    // Filtered local damping: each DOF's moving mean vref += wf (v - vref), the exact one-step weight of an
    // exponential mean over tau for a velocity held over the step.
    const double wf = tau_ld_ > 0 ? -std::expm1(-dt / tau_ld_) : 0.0;
    double* vref = tau_ld_ > 0 ? v_ref_.data() : nullptr;
    const double hm = 0.5 * dtv * beta_mass_;
    // (fdem/support_rigid.cpp; the sums, J: dt F_d v_bar and dt/2 F_d v^{n+1/2}, the same for the mass-proportional
    // damping force -a M v_bar)
    RigidStep rs{model_, f_mod_.data(), f_ext_.data(), tf, applied_gravity_, alpha_, tau_ld_, wf, beta_mass_, hm, dt, dtv,
                 dof_vel_.data(), dof_owner_.data(), supports_.data(), static_cast<int>(supports_.size())};
    for (std::size_t id = 0; id < supports_.size(); ++id) supports_[id]->rigid_step(rs, static_cast<int>(id));
    const double rigid_damp = rs.damp, rigid_damp_half = rs.damp_half, rigid_mass = rs.mass, rigid_mass_half = rs.mass_half;

    // 6. Node loop, one unit at a time: a node, or a group of tied copies (extrinsic insertion), which moves as one
    // node of the group's mass M: the resultant F of its members' forces gives every member the same velocity
    // (v^{n+1/2} from F / M, the bits a lone node of mass M takes), and the group's books (work, damping, kinetic
    // energy, unbalanced force) are those of that node. The unbalanced-force scale takes every member's own forces.
    // A prescribed DOF (a support takes every copy, check_ties) has each member's reaction of its mass share
    // w = m / M of F.
    const bool tied = ties_;
    const int nnb = node_block_count();
    NodeUpdate nu_args;
    nu_args.n_units = tied ? static_cast<int>(unit_start_.size()) - 1 : nn;
    nu_args.tied = tied;
    if (tied) {
        nu_args.u_start = unit_start_.data(), nu_args.u_node = unit_node_.data(), nu_args.u_slot = unit_slot_.data();
        nu_args.u_mass = unit_mass_.data(), nu_args.u_inv = unit_inv_mass_.data(), nu_args.tie_w = tie_w_.data();
        nu_args.u_block = unit_block_.data();
    }
    nu_args.tri_forces = tf;
    nu_args.inc_ptr = model_.inc_ptr.data(), nu_args.inc_idx = model_.inc_idx.data();
    nu_args.mass = model_.mass.data(), nu_args.grav_mass = model_.grav_mass.data(), nu_args.inv_mass = model_.inv_mass.data();
    nu_args.f_ext = f_ext_.data(), nu_args.loaded = node_loaded_.data();
    nu_args.f_mod = f_mod_.data();
    nu_args.reset_fmod = inter_.has_joints() || inter_.has_contact();  // the modules that add to f_mod_
    nu_args.dof_kind = dof_kind_.data(), nu_args.dof_velocity = dof_vel_.data(), nu_args.reaction = reaction_.data();
    nu_args.x = model_.x.data(), nu_args.v = model_.v.data(), nu_args.v_ref = vref;
    nu_args.dt = dt, nu_args.dtv = dtv, nu_args.alpha = alpha_, nu_args.beta_mass = beta_mass_, nu_args.hm = hm, nu_args.wf = wf;
    nu_args.gx = applied_gravity_[0], nu_args.gy = applied_gravity_[1];
    // Each thread takes a static share of the blocks (share_begin), the same nodes every step.
    const int n_thr = nnb > 1 ? omp_get_max_threads() : 1;
    if (n_thr != node_part_threads_) share_nodes_with_contact(n_thr);
    node_sums_.resize(static_cast<std::size_t>(nnb));
    update_nodes(nu_args, node_sums_);
    inter_.finish_step(model_.v.data());
    if (spec_.energy_audit) audit_step(2, dt);
    double dW = 0, dD = 0, unb = 0, scale = 0, dM = 0;
    kinetic_n_ = 0, work_half_ = 0, damp_half_ = 0, mass_half_ = 0;
    v2max_ = 0.0;
    for (int b = 0; b < nnb; ++b) {
        const NodeBlockSums& nb = node_sums_[b];
        v2max_ = std::max(v2max_, nb.v2);
        dW += nb.work, dD += nb.damping, unb += nb.unbalanced, scale += nb.scale;
        kinetic_n_ += nb.kinetic, work_half_ += nb.work_half, damp_half_ += nb.damping_half;
        dM += nb.mass, mass_half_ += nb.mass_half;
        if (nb.bad >= 0) {
            const int k = nb.bad;
            fail("node " + std::to_string(k) + " has a non-finite velocity (NaN/inf) near (" + sci(model_.X[2 * k], 6) + ", " +
                 sci(model_.X[2 * k + 1], 6) + ") m");
        }
    }
    dW -= rigid_damp, dD -= rigid_damp;
    work_half_ -= rigid_damp_half, damp_half_ -= rigid_damp_half;
    // The rigid groups' reactions carried their mass damping force too: from work to damping, like F_d.
    dW -= rigid_mass, dM -= rigid_mass;
    work_half_ -= rigid_mass_half, mass_half_ -= rigid_mass_half;
    D_mass_ += dM;
    W_ext_ += dW;
    D_damp_ += dD;
    D_visc_ += dt * visc_power;
    unbalanced_ratio_ = scale > 0 ? unb / scale : 0;
    const double w4 = omp_get_wtime();
    step_times_.triangles += wi - w1;
    step_times_.interactions += w3 - w2;
    step_times_.integration += w4 - w3;
    step_times_.other += (w1 - w0) + (w2 - wi);  // with the insertion check and the loads of the step
    supports_after_step();
    time_ += dt;
    tilt_deg_ += tilt_rate_ * dt;
    ++steps_;
    if (inter_.has_joints()) {
        const int broke = inter_.after_step(time_, control_displacement(), model_.x.data());
        broken_total_ += broke;
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
        if (history_due(time_, steps_)) {
            const double hi = history_interval();
            record_dry_joints();
            write_history_row();
            if (hi > 0) next_history_ += hi * std::max(1.0, std::floor((time_ - next_history_) / hi) + 1);
        }
        if (time_ + 1e-9 * dt >= next_snapshot_) {
            write_snapshot();
            const double si = snapshot_interval();
            next_snapshot_ += si * std::max(1.0, std::floor((time_ - next_snapshot_) / si) + 1);
        }
        if ((steps_ & 255) == 0) {
            const double now = wall_clock();
            if (now - last_flush_ > 5) flush_files();
        }
    }
    if (opt_.progress && (steps_ & 255) == 0) progress_line(false);
    if (opt_.progress_log && (steps_ & 255) == 0) progress_log_line();
    if (steps_ % 1000 == 0) {
        const Energies e = energies();
        if (spec_.energy_audit) log(audit_text(e));
        check_energy(e);
    }
}

}  // namespace fdem
