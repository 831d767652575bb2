// fdem/step.cpp: one step of Simulation, a fixed sequence of named stages over a StepContext, and the observers
// after it.
//
// step() = advance() + observe(). advance() runs the stages of one explicit step (central differences with local
// damping, fdem/README.md 'Time step'; [M04] ch. 4, [C79]) from x^n, v^{n-1/2}, in this order:
//   step_triangles     triangle forces f_int(x^n, v^{n-1/2}) in parallel, one 6-double record per triangle;
//   step_insertion     extrinsic insertion: dormant edges whose traction reached the strength get their element, the
//                      copies are untied, the step may shrink; then the contact detection, when due, and the step
//                      shrinks if the new candidate pairs need it;
//   step_loads         loads, gravity and prescribed velocities at t^n (ramps, protocols, tilting; after the
//                      insertion, as a prescribed velocity reads the step);
//   step_interactions  joint and contact forces into f_mod (Interactions::add_forces);
//   step_rigid_groups  rigid groups: one velocity per group and component from the resultant of its nodes' forces;
//   step_nodes         the node update (fdem/node_update.hpp: v^{n+1/2}, x^{n+1}, reactions and the books of each
//                      block), then the contact dashpots' second half (Interactions::finish_step);
//   step_books         energy books (block sums in order), the unbalanced-force ratio, servos, the clock to t^{n+1};
//   step_damage        damage of the joints (Interactions::after_step), the step after breaks.
// Each stage's wall time goes to the profile (StepProfile). No stage writes a file or a log line: a stage that
// cannot go on throws a StepFailure, which step() turns into the run's failure (fail, which writes the outputs), and
// a stage's log line waits in StepScratch::notes for observe(). The observers (history row, snapshot, files,
// progress, energy check) run after the step; the run loop (fdem/run.cpp) then checkpoints.
// Determinism: every parallel loop writes per-item results or per-block partial sums over fixed blocks of kBlock
// items; partials are added serially in block order. No result depends on the thread count.
// Energy: with vbar = (v^{n-1/2} + v^{n+1/2}) / 2, the kinetic energy change over a step is exactly sum dt f . vbar,
// so external work and damping are accumulated as dt f . vbar and the balance W_ext = K + E_el + D_damp + D_visc
// holds up to the O(dt^2) error of E_el alone.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "fdem/node_update.hpp"
#include "fdem/sim_detail.hpp"
#include "fdem/simulation.hpp"

namespace fdem {

using namespace sim_detail;

namespace {

// Adds the wall time since t to acc and returns the time now.
double lap(double& acc, double t) {
    const double now = omp_get_wtime();
    acc += now - t;
    return now;
}

}  // namespace

void Simulation::step() {
    double dt = 0;
    try {
        dt = advance();
    } catch (const StepFailure& f) {
        write_notes();
        fail(f.what());
    }
    const double t = omp_get_wtime();
    observe(dt);
    lap(profile_.observers, t);
}

double Simulation::advance() {
    StepContext c;
    double t = omp_get_wtime();
    if (spec_.energy_audit) audit_step(0, clock_.dt);
    c.dt_before = clock_.dt_last > 0 ? clock_.dt_last : clock_.dt;
    step_triangles(c);
    t = lap(profile_.triangles, t);
    step_insertion(c);
    t = lap(profile_.insertion, t);
    step_loads(c);
    t = lap(profile_.loads, t);
    step_interactions(c);
    t = lap(profile_.interactions, t);
    step_rigid_groups(c);
    t = lap(profile_.rigid_groups, t);
    step_nodes(c);
    t = lap(profile_.nodes, t);
    step_books(c);
    t = lap(profile_.books, t);
    step_damage(c);
    lap(profile_.damage, t);
    return c.dt;
}

// The triangles' forces at x^n, v^{n-1/2} into StepScratch::tri_forces (6 per triangle), in parallel by blocks,
// crushing triangles through fdem/plasticity.hpp; with ties (extrinsic insertion) also their stresses, for the
// insertion check. The viscous power (W) is summed by blocks in order; the first inverted triangle stops the run.
void Simulation::step_triangles(StepContext& c) {
    const int nt = model_.n_triangles();
    if (units_.active) scratch_.tri_sigma.resize(3 * static_cast<std::size_t>(nt));
    double* tsig = units_.active ? scratch_.tri_sigma.data() : nullptr;
    c.tri_sigma = tsig;
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
        // No crushing and no stresses wanted: the block four at a time where the CPU can (fdem/triangle.hpp).
        if (!tsig && !crush_.active()) triangle_forces_range(tris, mats, x, v, tf, b * kBlock, e1, pv, bad);
        else
        for (int e = b * kBlock; e < e1; ++e) {
            double p;
            const int cs = crush_.slot(e);  // crushing triangles: fdem/plasticity.hpp (state updated per triangle)
            double* sig = tsig ? tsig + 3 * static_cast<std::size_t>(e) : nullptr;
            double* fe = tf + 6 * static_cast<std::size_t>(e);
            const double J = cs < 0 ? triangle_forces(tris[e], mats[tris[e].mat], x, v, fe, p, sig)
                                    : crush_.forces(cs, tris[e], x, v, fe, p);
            if (sig && cs >= 0) triangle_stress(tris[e], mats[tris[e].mat], x, sig);  // elastic stress (not extrinsic)
            if (!(J > 0) && bad < 0) bad = e;
            pv += p;
        }
        scratch_.tri_power[b] = pv;
        scratch_.tri_bad[b] = bad;
    }
    c.visc_power = 0;
    for (int b = 0; b < ntb; ++b) {
        c.visc_power += scratch_.tri_power[b];
        if (scratch_.tri_bad[b] < 0) continue;
        const int e = scratch_.tri_bad[b];
        const TriangleRef& t = tris[e];
        const double cx = (x[2 * t.n[0]] + x[2 * t.n[1]] + x[2 * t.n[2]]) / 3;
        const double cy = (x[2 * t.n[0] + 1] + x[2 * t.n[1] + 1] + x[2 * t.n[2] + 1]) / 3;
        throw StepFailure("triangle " + std::to_string(e) + " (region '" +
                          model_.mesh.regions[model_.mesh.tri_region[e]] + "') inverted (J <= 0) at (" + sci(cx, 6) +
                          ", " + sci(cy, 6) + ") m");
    }
}

// Extrinsic insertion: dormant edges whose traction reached the strength get their cohesive element before this
// step's joint forces, their copies are untied, and the step shrinks if the lighter nodes need it. The velocity
// update of a step that changed it spans the mean of the two steps (central difference with a variable step,
// v^{n+1/2} = v^{n-1/2} + (dt^{n-1/2} + dt^{n+1/2}) / 2 a^n; Belytschko, Liu & Moran, Nonlinear Finite Elements
// for Continua and Structures, 2000, §6.2).
void Simulation::step_insertion(StepContext& c) {
    if (units_.active && inter_.insert_cracks(model_.x.data(), c.tri_sigma) > 0) {
        build_ties();
        reduce_dt_after_insertion("cracks inserted: nodes untied");
    }
    // This step's contact detection (the one step_interactions would run, on the same x^n, dt and speed), before
    // the step is set: the nodal bound counts the faces of the candidate pairs, and a pair not in the list cannot
    // touch before the next detection, so the step shrinks here when a triangle joins the list.
    if (inter_.refresh_contact(model_.x.data(), model_.v.data(), clock_.dt, scratch_.v2max))
        reduce_dt_after_insertion("new contact candidates");
    c.dt = clock_.dt;
    c.dtv = 0.5 * (c.dt_before + c.dt);
}

void Simulation::step_loads(StepContext&) {
    apply_time_dependent(clock_.time);
}

// Joint and contact forces, added to StepScratch::f_mod in a fixed order by their modules. The contact energy is
// only evaluated on the steps whose energies are reported or checked.
void Simulation::step_interactions(StepContext& c) {
    inter_.want_energy(history_due(clock_.time + c.dt, clock_.steps + 1) || (clock_.steps + 1) % 1000 == 0 ||
                       energy_every_step_);
    inter_.add_forces(model_.x.data(), model_.v.data(), c.dt, scratch_.f_mod.data(),
                      spec_.energy_audit ? audit_.fj.data() : nullptr, scratch_.f_mod.size(), scratch_.v2max);
    if (spec_.energy_audit) audit_step(1, c.dt);
}

// Rigid groups first: one velocity per group and component from the resultant of its nodes' forces,
// v^{n+1/2} = v^{n-1/2} + dt (F + F_d) / M with F = sum of the nodal forces, M = sum of the nodal masses and the
// [C79] local damping F_d = -alpha |F| sign(v) on the resultant. The node loop then treats those DOFs as prescribed:
// their reactions redistribute the forces inside the group and sum to F_d, which the loop books as work; step_books
// moves that share from work to damping. Serial, in support and node order (fdem/support_rigid.cpp; the sums, J:
// dt F_d v_bar and dt/2 F_d v^{n+1/2}, the same for the mass-proportional damping force -a M v_bar).
// Filtered local damping: each DOF's moving mean vref += wf (v - vref), the exact one-step weight of an exponential
// mean over tau for a velocity held over the step; wf and the mass damping's hm serve the node update too.
void Simulation::step_rigid_groups(StepContext& c) {
    c.wf = damping_.filter_tau > 0 ? -std::expm1(-c.dt / damping_.filter_tau) : 0.0;
    c.hm = 0.5 * c.dtv * damping_.mass;
    RigidStep rs{model_,
                 scratch_.f_mod.data(),
                 loads_.f_ext.data(),
                 scratch_.tri_forces.data(),
                 gravity_.applied,
                 damping_.local,
                 damping_.filter_tau,
                 c.wf,
                 damping_.mass,
                 c.hm,
                 c.dt,
                 c.dtv,
                 supports_.dof_velocity.data(),
                 supports_.dof_owner.data(),
                 c.dt_before,
                 supports_.list.data(),
                 static_cast<int>(supports_.list.size())};
    for (std::size_t id = 0; id < supports_.list.size(); ++id) supports_.list[id]->rigid_step(rs, static_cast<int>(id));
    c.rigid_damp = rs.damp, c.rigid_damp_half = rs.damp_half;
    c.rigid_mass = rs.mass, c.rigid_mass_half = rs.mass_half;
}

// The node update, one unit at a time: a node, or a group of tied copies (extrinsic insertion), which moves as one
// node of the group's mass M: the resultant F of its members' forces gives every member the same velocity
// (v^{n+1/2} from F / M, the bits a lone node of mass M takes), and the group's books (work, damping, kinetic energy,
// unbalanced force) are those of that node. The unbalanced-force scale takes every member's own forces. A prescribed
// DOF (a support takes every copy, check_ties) has each member's reaction of its mass share w = m / M of F. Each
// thread takes a static share of the blocks (share_begin), the same nodes every step.
void Simulation::step_nodes(StepContext& c) {
    const bool tied = units_.active;
    NodeUpdate u;
    u.n_units = tied ? static_cast<int>(units_.start.size()) - 1 : model_.n_nodes();
    u.tied = tied;
    if (tied) {
        u.u_start = units_.start.data(), u.u_node = units_.node.data(), u.u_slot = units_.slot.data();
        u.u_mass = units_.mass.data(), u.u_inv = units_.inv_mass.data(), u.tie_w = units_.tie_w.data();
        u.u_block = units_.block.data();
    }
    u.tri_forces = scratch_.tri_forces.data();
    u.inc_ptr = model_.inc_ptr.data(), u.inc_idx = model_.inc_idx.data();
    u.mass = model_.mass.data(), u.grav_mass = model_.grav_mass.data(), u.inv_mass = model_.inv_mass.data();
    u.f_ext = loads_.f_ext.data(), u.loaded = scratch_.node_loaded.data();
    u.f_mod = scratch_.f_mod.data();
    u.reset_fmod = inter_.has_joints() || inter_.has_contact();  // the modules that add to f_mod
    u.dof_kind = supports_.dof_kind.data(), u.dof_velocity = supports_.dof_velocity.data();
    u.reaction = supports_.reaction.data();
    u.x = model_.x.data(), u.v = model_.v.data();
    u.v_ref = damping_.filter_tau > 0 ? damping_.v_ref.data() : nullptr;
    u.dt = c.dt, u.dtv = c.dtv, u.dt_before = c.dt_before;
    u.local_damping = damping_.local, u.mass_damping = damping_.mass, u.hm = c.hm, u.wf = c.wf;
    u.gx = gravity_.applied[0], u.gy = gravity_.applied[1];
    const int nnb = node_block_count();
    const int n_thr = nnb > 1 ? omp_get_max_threads() : 1;
    if (n_thr != units_.shared_threads) share_nodes_with_contact(n_thr);
    scratch_.node_sums.resize(static_cast<std::size_t>(nnb));
    update_nodes(u, scratch_.node_sums);
    inter_.finish_step(model_.v.data());
    if (spec_.energy_audit) audit_step(2, c.dt);
}

// The node update's block sums in block order into the books (a non-finite velocity stops the run), the rigid
// groups' damping moved from work to damping, the unbalanced-force ratio, the servos (which read it) and the clock.
void Simulation::step_books(StepContext& c) {
    double dW = 0, dD = 0, unb = 0, scale = 0, dM = 0;
    books_.kinetic_n = 0, books_.work_half = 0, books_.damp_half = 0, books_.mass_half = 0;
    scratch_.v2max = 0.0;
    for (const NodeBlockSums& nb : scratch_.node_sums) {
        scratch_.v2max = std::max(scratch_.v2max, nb.v2);
        dW += nb.work, dD += nb.damping, unb += nb.unbalanced, scale += nb.scale;
        books_.kinetic_n += nb.kinetic, books_.work_half += nb.work_half, books_.damp_half += nb.damping_half;
        dM += nb.mass, books_.mass_half += nb.mass_half;
        if (nb.bad >= 0) {
            const int k = nb.bad;
            throw StepFailure("node " + std::to_string(k) + " has a non-finite velocity (NaN/inf) near (" +
                              sci(model_.X[2 * k], 6) + ", " + sci(model_.X[2 * k + 1], 6) + ") m");
        }
    }
    dW -= c.rigid_damp, dD -= c.rigid_damp;
    books_.work_half -= c.rigid_damp_half, books_.damp_half -= c.rigid_damp_half;
    // The rigid groups' reactions carried their mass damping force too: from work to damping, like F_d.
    dW -= c.rigid_mass, dM -= c.rigid_mass;
    books_.work_half -= c.rigid_mass_half, books_.mass_half -= c.rigid_mass_half;
    books_.D_mass += dM;
    books_.W_ext += dW;
    books_.D_damp += dD;
    books_.D_visc += c.dt * c.visc_power;
    books_.unbalanced_ratio = scale > 0 ? unb / scale : 0;
    supports_after_step();
    clock_.time += c.dt;
    clock_.dt_last = c.dt;
    gravity_.tilt_deg += gravity_.tilt_rate * c.dt;
    ++clock_.steps;
}

// The joints' damage at t^{n+1}; broken elements' faces join the contact count, which may shrink the step.
void Simulation::step_damage(StepContext&) {
    if (!inter_.has_joints()) return;
    const int broke = inter_.after_step(clock_.time, control_displacement(), model_.x.data());
    clock_.broken_total += broke;
    if (broke > 0) reduce_dt_after_insertion("joints broken: new faces for contact");
}

// The log lines the stages left (StepScratch::notes), in their order.
void Simulation::write_notes() {
    for (const std::string& line : scratch_.notes) log(line);
    scratch_.notes.clear();
}

// After a step of length dt (the observers): the step's log lines, the history row with the dry joints' record, the
// snapshot, the periodic flush of the files, progress, and every 1000 steps the energy check (which may stop the
// run). Nothing here changes what the next step computes.
void Simulation::observe(double dt) {
    write_notes();
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
