// fdem/integrator.cpp: the time step of Simulation and the tied groups of extrinsic insertion: the stable limits
// (triangles, nodes with their springs, damping), per-node mass scaling, the ties and the node loop's units and
// blocks over them, and the step after an insertion or a break. The step itself is in fdem/step.cpp.
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

#include "fdem/body_step.hpp"
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
    // (the masses stay for the whole run: every face that may touch counts, not only the candidates of the moment)
    inter_.add_node_stiffness(model_, contact_xi_max(), 0.0, rep, kj.data(), kc.data(), true);
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

Simulation::NodalLimit Simulation::nodal_step_limit(const double* mass, const int* rep, double xi_contact, double alpha,
                                                    bool every_face) {
    const int nn = model_.n_nodes();
    if (limits_.tri_node_k.size() != static_cast<std::size_t>(nn) || limits_.tri_node_k_alpha != alpha) {
        limits_.tri_node_k.assign(nn, 0.0);
        add_triangle_node_stiffness(spec_, model_, nullptr, limits_.tri_node_k.data(), alpha, rigid_tri());
        limits_.tri_node_k_alpha = alpha;
    }
    std::vector<double> kt(nn, 0.0), kj(nn, 0.0), kc(nn, 0.0);
    for (int k = 0; k < nn; ++k) kt[rep ? rep[k] : k] += limits_.tri_node_k[k];
    // The contact springs of the edges near a candidate pair (Interactions::add_node_stiffness): the step follows
    // the list (reduce_dt_after_insertion when it grows). A fixed step (numerics.dt) cannot: its limit counts every
    // face that may touch.
    inter_.add_node_stiffness(model_, xi_contact, alpha, rep, kj.data(), kc.data(),
                              every_face || spec_.dt_override.has_value());
    NodalLimit lim;
    double w2max = 0;  // 1/s^2
    for (int k = 0; k < nn; ++k) {
        if (rep && rep[k] != k) continue;  // a copy: its group is counted at its first node
        // (a rigid body's node: the body's bound below; a held node has no dynamics)
        if (!limits_.bodies.empty() && (limits_.bodies.node_body[k] >= 0 || limits_.bodies.held[k])) continue;
        const double w2 = (kt[k] + kj[k] + kc[k]) / mass[k];
        if (w2 > w2max) w2max = w2, lim.node = k, lim.k_tri = kt[k], lim.k_joint = kj[k], lim.k_contact = kc[k];
    }
    // Rigid bodies (fdem/body_step.hpp): their mass and inertia against the springs at their nodes. A body counts
    // every face that may touch, candidate or not: its contact is all its deformation, and the step of its candidate
    // springs alone resolves an impact by two or three steps, where its restitution needs about ten (fdem/README.md
    // 'Time step'; tests/contact/test_rocking.cpp).
    std::vector<double> k;  // N/m, per node: the three shares summed (read at the bodies' nodes only)
    if (!limits_.bodies.nodes.empty()) {
        if (!every_face && !spec_.dt_override.has_value()) {
            std::fill(kj.begin(), kj.end(), 0.0), std::fill(kc.begin(), kc.end(), 0.0);
            inter_.add_node_stiffness(model_, xi_contact, alpha, rep, kj.data(), kc.data(), true);
        }
        k.resize(nn);
        for (int j = 0; j < nn; ++j) k[j] = kt[j] + kj[j] + kc[j];
    }
    for (std::size_t b = 0; b < limits_.bodies.nodes.size(); ++b) {
        double st = 0, sj = 0, sc = 0;
        for (int j : limits_.bodies.nodes[b]) st += kt[j], sj += kj[j], sc += kc[j];
        const double w2 = body_omega2(limits_.bodies.nodes[b], model_.x.data(), mass, k.data());
        if (w2 > w2max)
            w2max = w2, lim.node = limits_.bodies.nodes[b].front(), lim.body = static_cast<int>(b), lim.k_tri = st,
            lim.k_joint = sj, lim.k_contact = sc;
    }
    if (w2max > 0) lim.dt = 2.0 / std::sqrt(w2max);
    // Nothing bounded (rigid bodies and held nodes only, no spring near a candidate: a body in free flight): the
    // bound of every face, which a contact would shrink the step to, keeps the step finite.
    if (!every_face && !(lim.dt < 1e299)) return nodal_step_limit(mass, rep, xi_contact, alpha, true);
    return lim;
}

double Simulation::stage_alpha(int s) const {
    double alpha = 0;  // a stage without local_damping keeps the one before it
    for (int i = 0; i <= s && i < static_cast<int>(spec_.stages.size()); ++i)
        if (spec_.stages[i].local_damping) alpha = *spec_.stages[i].local_damping;
    return alpha;
}

void Simulation::set_step_limits(double alpha, bool set_dt) {
    const StepLimit lim = triangle_step_limit(spec_, model_, alpha, rigid_tri());
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
    // Groups that are one rigid body all run long take the step of their mass and inertia (fdem/body_step.hpp); not
    // with tied copies or per-node mass scaling, whose masses are not the lumped ones the body moves with.
    limits_.bodies = (spec_.per_node_mass || units_.active || limits_.bodies_off) ? RigidBodies{}
                                                                                   : whole_run_bodies(spec_, model_);
    limits_.tri_node_k.clear();
    const StepLimit lim = triangle_step_limit(spec_, model_, alpha, rigid_tri());
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
    // Nothing left that moves (every node held or in a body without springs): the bound of every triangle and node.
    if (!limits_.bodies.empty() && !(clock_.dt_limit < 1e299)) {
        limits_.bodies = RigidBodies{};
        limits_.tri_node_k.clear();
        limits_.bodies_off = true;
        compute_dt();
    }
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

void Simulation::reduce_dt_after_insertion(const char* cause) {
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
    if (clock_.dt < 0.9 * clock_.dt_logged) {  // (a note of the step: the observers log it)
        clock_.dt_logged = clock_.dt;
        scratch_.notes.push_back("time step: " + sci(clock_.dt) + " s from t = " + sci(clock_.time) +
                                 " s (" + cause + ")");
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

}  // namespace fdem
