// fdem/integrator.cpp: the explicit central-difference integrator of Simulation: the time step, the tied groups of
// extrinsic insertion and one step.
//
// One step (central differences with local damping, README "Physics"; [M04] ch. 4, [C79]), with x^n, v^{n-1/2} known:
//   1. loads, gravity and prescribed velocities at time t^n (ramps, protocols, tilting);
//   2. triangle forces f_int(x^n, v^{n-1/2}) in parallel, one 6-double record per triangle;
//   3. node loop in parallel, one unit (a node, or a group of tied copies moving as one node) at a time: gather the
//      triangle records in CSR order, add applied loads and gravity,
//      local damping f_d = -alpha |f| sign(v) on free DOFs ([C79]) and mass-proportional (Rayleigh alpha) damping -a m vbar
//      (Belytschko, Liu & Moran 2000; vbar = (v^{n-1/2} + v^{n+1/2}) / 2, implicit in v, never limits the step), then
//      v^{n+1/2} = ((1 - a dt / 2) v^{n-1/2} + dt (f + f_d) / m) / (1 + a dt / 2), or the prescribed value
//      (reaction = m dv/dt - f),
//      x^{n+1} = x^n + dt v^{n+1/2}.
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
// those bounds: both are Gershgorin row sums per node (counting the other side's nodes; the contact one counted a
// single face and no other side until 27 Nov, and a stack on stiff dry joints went unstable at the default safety
// under it). A tied group (extrinsic insertion) is raised as one: its copies
// keep their shares. Done once, at set-up, on the reference configuration: the masses stay constant in the run (the
// energy books and the restart stay exact), and cracks inserted later may still shrink the step
// (reduce_dt_after_insertion). Gravity keeps the physical mass.
void Simulation::scale_node_masses() {
    if (!spec_.per_node_mass || spec_.dt_override) return;
    const int nn = model_.n_nodes();
    // Each node (a tied group as one: its copies' shares summed at its first node) is made heavy enough that its
    // assembled nodal bound (nodal_step_limit: its triangles' share plus its joint and contact springs' row sums, over
    // its mass) allows the triangles' exact limit dt_t; the step is then safety * dt_t, as in a case without mass
    // scaling whose triangles set the step. (Until 28 Nov the springs alone were made stable at a margin over dt_t
    // and the sum bounded by Weyl's inequality, which asked more mass wherever the springs dominate.)
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
    // ignores the triangles at the same nodes and counts the faces of intact joints, which cannot touch yet; it was
    // taken alone until 28 Nov.
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
                const std::string grp = owner >= 0 ? supports_[owner].group : std::string("?");
                throw InputError(spec_.file + ": stage " + std::to_string(stage_ + 1) + ": the support of group '" + grp +
                                 "' holds only some of the copies of the node at (" + sci(model_.X[2 * k], 6) + ", " +
                                 sci(model_.X[2 * k + 1], 6) + ") m, which move as one node until a crack is inserted "
                                 "there (insertion = \"extrinsic\"); expected a group that takes every copy (a box, "
                                 "or a curve or surface of the whole unit)");
            }
        }
    }
}

void Simulation::step() {
    const double w0 = omp_get_wtime();
    if (spec_.energy_audit) audit_step(0, dt_);
    const double dt_before = dt_;
    const int nt = model_.n_triangles(), nn = model_.n_nodes();
    const TriangleRef* tris = model_.tris.data();
    const MaterialConst* mats = model_.mat.data();
    const double* x = model_.x.data();
    const double* v = model_.v.data();
    double* tf = tf_.data();
    // Extrinsic insertion: the triangles' stresses of this step for the check below (ties only).
    if (ties_) tri_sigma_.resize(3 * static_cast<std::size_t>(nt));
    double* tsig = ties_ ? tri_sigma_.data() : nullptr;

    // 2. Triangle forces; per block: viscous power and the first inverted triangle.
    const double w1 = omp_get_wtime();
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
        block_a_[b] = pv;
        block_bad_[b] = bad;
    }
    double visc_power = 0;
    for (int b = 0; b < ntb; ++b) {
        visc_power += block_a_[b];
        if (block_bad_[b] >= 0) {
            const int e = block_bad_[b];
            const TriangleRef& t = tris[e];
            const double cx = (x[2 * t.n[0]] + x[2 * t.n[1]] + x[2 * t.n[2]]) / 3, cy = (x[2 * t.n[0] + 1] + x[2 * t.n[1] + 1] + x[2 * t.n[2] + 1]) / 3;
            fail("triangle " + std::to_string(e) + " (region '" + model_.mesh.regions[model_.mesh.tri_region[e]] +
                 "') inverted (J <= 0) at (" + sci(cx, 6) + ", " + sci(cy, 6) + ") m");
        }
    }

    const double wi = omp_get_wtime();
    // Extrinsic insertion: dormant edges whose traction reached the strength get their cohesive element before this
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

    // Joint and contact forces, added to f_mod_ in a fixed order by their modules. The contact energy is only
    // evaluated on the steps whose energies are reported or checked.
    inter_.want_energy(history_due(time_ + dt, steps_ + 1) || (steps_ + 1) % 1000 == 0 || energy_every_step_);
    const double w2 = omp_get_wtime();
    inter_.add_forces(x, v, dt, f_mod_.data(), spec_.energy_audit ? audit_fj_.data() : nullptr, f_mod_.size(), v2max_);
    if (spec_.energy_audit) audit_step(1, dt);
    const double w3 = omp_get_wtime();

    // Rigid groups first: one velocity per group and component from the resultant of its nodes' forces,
    // v^{n+1/2} = v^{n-1/2} + dt (F + F_d) / M with F = sum of the nodal forces, M = sum of the nodal masses and the
    // [C79] local damping F_d = -alpha |F| sign(v) on the resultant. The node loop then treats those DOFs as
    // prescribed: their reactions redistribute the forces inside the group and sum to F_d, which the loop books as
    // work; rigid_damp_ moves that share from work to damping after the loop. Serial, in support and node order.
    double rigid_damp = 0, rigid_damp_half = 0;  // J: dt F_d v_bar and dt/2 F_d v^{n+1/2}
    double rigid_mass = 0, rigid_mass_half = 0;  // J: the same for the mass-proportional damping force -a M v_bar
    // Filtered local damping: each DOF's moving mean vref += wf (v - vref), the exact one-step weight of an
    // exponential mean over tau for a velocity held over the step.
    const double wf = tau_ld_ > 0 ? -std::expm1(-dt / tau_ld_) : 0.0;
    double* vref = tau_ld_ > 0 ? v_ref_.data() : nullptr;
    const double hm = 0.5 * dtv * beta_mass_;
    for (std::size_t id = 0; id < supports_.size(); ++id) {
        ActiveSupport& s = supports_[id];
        if (s.mode != DofMode::rigid) continue;
        const int c = s.comp;
        double F = 0, M = 0;
        for (int k : s.nodes) {
            const int d = 2 * k + c;
            if (dof_owner_[d] != static_cast<int>(id)) continue;
            double f = f_mod_[d] + f_ext_[d] + model_.grav_mass[k] * applied_gravity_[c];
            for (int j = model_.inc_ptr[k]; j < model_.inc_ptr[k + 1]; ++j) f += tf[2 * static_cast<std::size_t>(model_.inc_idx[j]) + c];
            F += f, M += model_.mass[k];
        }
        if (!(M > 0)) continue;
        const double vold = s.v_common;
        const double vrel = tau_ld_ > 0 ? vold - s.v_ref : vold;
        const double Fd = vrel > 0 ? -alpha_ * std::abs(F) : vrel < 0 ? alpha_ * std::abs(F) : 0.0;
        const double vnew = ((1 - hm) * vold + dtv * (F + Fd) / M) / (1 + hm);
        const double Fm = -beta_mass_ * M * 0.5 * (vold + vnew);
        rigid_damp += dt * Fd * 0.5 * (vold + vnew);
        rigid_damp_half += 0.5 * dt * Fd * vnew;
        rigid_mass += dt * Fm * 0.5 * (vold + vnew);
        rigid_mass_half += 0.5 * dt * Fm * vnew;
        s.v_common = vnew;
        if (tau_ld_ > 0) s.v_ref += wf * (vnew - s.v_ref);
        for (int k : s.nodes)
            if (dof_owner_[2 * k + c] == static_cast<int>(id)) dof_vel_[2 * k + c] = vnew;
    }

    // 3. Node loop, one unit at a time: a node, or a group of tied copies (extrinsic insertion), which moves as one
    // node of the group's mass M: the resultant F of its members' forces gives every member the same velocity
    // (v^{n+1/2} from F / M, the bits a lone node of mass M takes), and the group's books (work, damping, kinetic
    // energy, unbalanced force) are those of that node. The unbalanced-force scale takes every member's own forces.
    // A prescribed DOF (a support takes every copy, check_ties) has each member's reaction of its mass share
    // w = m / M of F.
    const bool tied = ties_;  // (node_block below has it as the constant kTied)
    const int nu = tied ? static_cast<int>(unit_start_.size()) - 1 : nn;
    const int* u_start = tied ? unit_start_.data() : nullptr;
    const int* u_node = tied ? unit_node_.data() : nullptr;
    const int* u_slot = tied ? unit_slot_.data() : nullptr;
    const double* u_mass = tied ? unit_mass_.data() : nullptr;
    const double* u_inv = tied ? unit_inv_mass_.data() : nullptr;
    const double* tie_w = tied ? tie_w_.data() : nullptr;
    // blocks of units: kBlock nodes (tied: whole units of at least kBlock members, unit_block_)
    const int nnb = node_block_count();
    const int* u_block = tied ? unit_block_.data() : nullptr;
    const double alpha = alpha_;
    const double beta_mass = beta_mass_;
    const double gx = applied_gravity_[0], gy = applied_gravity_[1];
    const int* inc_ptr = model_.inc_ptr.data();
    const int* inc_idx = model_.inc_idx.data();
    const double* mass = model_.mass.data();
    const double* gmass = model_.grav_mass.data();
    const double* inv_mass = model_.inv_mass.data();
    double* xw = model_.x.data();
    double* vw = model_.v.data();
    const double* fext = f_ext_.data();
    const unsigned char* loaded = node_loaded_.data();
    double* fmod = f_mod_.data();
    const bool reset_fmod = inter_.has_joints() || inter_.has_contact();  // the modules that add to f_mod_
    const uint8_t* kind = dof_kind_.data();
    const double* vpres = dof_vel_.data();
    double* reac = reaction_.data();
    // One block; compiled for each combination of three compile-time constants, so that each model runs only the
    // parts it has: kTied (units of tied copies, else plain nodes without the units' indirections), kFilter (the
    // filtered local damping's moving means, vref) and kMass (mass-proportional damping, hm > 0).
    auto node_block = [&](auto tied_const, auto filter_const, auto mass_const, int b) {
        constexpr bool kTied = decltype(tied_const)::value;
        constexpr bool kFilter = decltype(filter_const)::value;
        constexpr bool kMass = decltype(mass_const)::value;
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
        block_a_[b] = dW, block_b_[b] = dD, block_c_[b] = unb, block_d_[b] = scale;
        block_e_[b] = K, block_f_[b] = cW, block_g_[b] = cD, block_h_[b] = dM, block_i_[b] = cM;
        block_v2_[b] = v2;
        // The first unit (in loop order) with a non-finite velocity, looked for only when there is one.
        int bad = -1;
        if (!(nonfinite == 0))
            for (int u = u0; u < u1 && bad < 0; ++u) {
                const int k0 = kTied ? u_node[u_start[u]] : u;
                if (!std::isfinite(vw[2 * k0]) || !std::isfinite(vw[2 * k0 + 1])) bad = k0;
            }
        block_bad_[b] = bad;
    };
    // Each thread takes a static share of the blocks (share_begin), the same nodes every step.
    const int n_thr = nnb > 1 ? omp_get_max_threads() : 1;
    if (n_thr != node_part_threads_) share_nodes_with_contact(n_thr);
    auto run_blocks = [&](auto t, auto fl, auto m) {
#pragma omp parallel if (nnb > 1)
        {
            const int T = omp_get_num_threads(), me = omp_get_thread_num();
            for (int b = share_begin(nnb, T, me); b < share_begin(nnb, T, me + 1); ++b) node_block(t, fl, m, b);
        }
    };
    auto with_mass = [&](auto t, auto fl) {
        if (hm > 0) run_blocks(t, fl, std::true_type{});
        else run_blocks(t, fl, std::false_type{});
    };
    auto with_filter = [&](auto t) {
        if (vref) with_mass(t, std::true_type{});
        else with_mass(t, std::false_type{});
    };
    if (tied) with_filter(std::true_type{});
    else with_filter(std::false_type{});
    inter_.finish_step(model_.v.data());
    if (spec_.energy_audit) audit_step(2, dt);
    double dW = 0, dD = 0, unb = 0, scale = 0, dM = 0;
    kinetic_n_ = 0, work_half_ = 0, damp_half_ = 0, mass_half_ = 0;
    v2max_ = 0.0;
    for (int b = 0; b < nnb; ++b) {
        v2max_ = std::max(v2max_, block_v2_[b]);
        dW += block_a_[b], dD += block_b_[b], unb += block_c_[b], scale += block_d_[b];
        kinetic_n_ += block_e_[b], work_half_ += block_f_[b], damp_half_ += block_g_[b];
        dM += block_h_[b], mass_half_ += block_i_[b];
        if (block_bad_[b] >= 0) {
            const int k = block_bad_[b];
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
    update_servos();
    time_ += dt;
    tilt_deg_ += tilt_rate_ * dt;
    ++steps_;
    if (inter_.has_joints()) {
        const int broke = inter_.after_step(time_, control_displacement(), model_.x.data());
        broken_total_ += broke;
        if (broke > 0) reduce_dt_after_insertion();  // broken elements' faces join the contact count
    }

    // Outputs.
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
    step_times_.other += omp_get_wtime() - w4;
}

}  // namespace fdem
