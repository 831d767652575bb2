// fdem/stages.cpp: the stage logic of Simulation: initial conditions, what a stage sets when it begins (supports:
// fdem/support.hpp, loads: fdem/load.hpp, damping, gravity), the time-dependent loads and velocities of every step,
// the supports' updates after it (servos) and how a stage ends (duration, until, equilibrium).
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

#include "fdem/common/errors.hpp"
#include "fdem/sim_detail.hpp"

namespace fdem {

namespace {

// Whether a stage's until condition holds already: the monitor (a quantity measured from its reference, zero at the
// start of the run) at or beyond the target as seen from zero, m / value >= 1 (for value 0: m = 0). Past it, the
// direction rule of stage_finished (towards the target from the start value) would wait for the monitor to come back.
bool until_holds(double value, double m) {
    return value == 0 ? m == 0 : m / value >= 1;
}

}  // namespace

using namespace sim_detail;

// [[initial]]: rigid rotation of the placement about the centre (x only: the triangles turn, stress-free by the
// objectivity of the neo-Hookean law), then v = v0 + omega x (x - c). Blocks apply in order.
void Simulation::apply_initial_conditions() {
    for (const InitialSpec& in : spec_.initial) {
        const auto& grp = model_.group(in.group);
        const double a = in.rotation * kPi / 180, ca = std::cos(a), sa = std::sin(a);
        for (int k : grp.nodes) {
            double* xk = &model_.x[2 * k];
            if (in.rotation != 0) {
                const double rx = xk[0] - in.center[0], ry = xk[1] - in.center[1];
                xk[0] = in.center[0] + ca * rx - sa * ry;
                xk[1] = in.center[1] + sa * rx + ca * ry;
            }
            model_.v[2 * k] = in.velocity[0] - in.angular_velocity * (xk[1] - in.center[1]);
            model_.v[2 * k + 1] = in.velocity[1] + in.angular_velocity * (xk[0] - in.center[0]);
        }
        if (in.rotation != 0) inter_.invalidate_contact();
        scratch_.v2max = -1.0;  // (the node loop's speed is not this v's)
        log("initial conditions on '" + in.group + "': " + std::to_string(grp.nodes.size()) + " nodes" +
            (in.rotation != 0 ? ", placement turned by " + sci(in.rotation) + " deg" : std::string()) +
            ", velocity [" + sci(in.velocity[0]) + ", " + sci(in.velocity[1]) + "] m/s" +
            (in.angular_velocity != 0 ? " + " + sci(in.angular_velocity) + " rad/s about the centre" : std::string()));
    }
    // A turned placement: the contact list of the new positions, and the first step bounded by it.
    if (inter_.refresh_contact(model_.x.data(), model_.v.data(), clock_.dt, -1.0))
        reduce_dt_after_insertion("initial placement: new contact candidates");
}

// begin_stage, part 1: the damping (local, its filter, mass, contact dashpots) and gravity (vector, ramp, tilt,
// time function) that the stage sets; the others carry over.
void Simulation::stage_damping_and_gravity(const StageSpec& st) {
    if (st.local_damping && *st.local_damping != damping_.local) {
        // The stable step depends on the local damping (damped_step_factor, fdem/model.hpp): a stage that changes it
        // sets the step again from the current model (faces that cracks opened included).
        damping_.local = *st.local_damping;
        if (!spec_.dt_override) {
            const double before = clock_.dt;
            set_step_limits(damping_.local, true);
            if (clock_.dt != before) {
                clock_.dt_logged = clock_.dt;
                log("time step: " + sci(clock_.dt) + " s = " + sci(spec_.safety) + " x stable limit " +
                    sci(clock_.dt_limit) + " s at local damping " + sci(damping_.local) + " (stage '" + st.name + "')");
            }
        }
    }
    if (st.local_damping_filter) {
        // The moving mean starts from the current velocities, so switching the filter on does not kick the motion.
        if (*st.local_damping_filter > 0 && !(damping_.filter_tau > 0)) {
            damping_.v_ref = model_.v;
            for (auto& sp : supports_.list) sp->filter_started();
        }
        damping_.filter_tau = *st.local_damping_filter;
        if (!(damping_.filter_tau > 0)) damping_.v_ref.clear();
    }
    if (st.mass_damping) damping_.mass = *st.mass_damping;
    if (st.contact_damping) {
        damping_.contact = *st.contact_damping;
        inter_.set_contact_dashpot(std::isfinite(limits_.dt_contact) ? damping_.contact * limits_.dt_contact : 0.0);
    }
    if (st.gravity) {
        gravity_.start = gravity_.current;
        gravity_.target = *st.gravity;
        gravity_.ramp = st.gravity_ramp;
        ending_.ramp_end = std::max(ending_.ramp_end, clock_.time + st.gravity_ramp);
    } else {
        gravity_.start = gravity_.target = gravity_.current;
        gravity_.ramp = 0;
    }
    gravity_.tilt_rate = st.tilt_rate;
    if (st.gravity_function.present()) {
        gravity_.factor = st.gravity_function;
        gravity_.factor_t0 = clock_.time;
    } else if (st.gravity) {
        gravity_.factor = TimeFunction{};
    }
}

// begin_stage, part 2: supports (fdem/support.hpp). A new block takes over the DOFs it names; the others keep their
// previous support.
void Simulation::stage_supports(const StageSpec& st) {
    const int nn = model_.n_nodes();
    for (const SupportSpec& sp : st.supports) {
        const auto& grp = model_.group(sp.group);
        for (int c = 0; c < 2; ++c) {
            if (sp.mode[c] == DofMode::inherit) continue;
            // (free: no active support)
            std::unique_ptr<Support> a = find_support_kind(sp.mode[c])
                                             ->begin(sp, c,
                                                     SupportStart{model_, clock_.time, supports_.dof_kind.data(),
                                                                  supports_.dof_velocity.data()});
            if (a) {
                a->nodes = grp.nodes;
                a->comp = c;
                a->group = sp.group;
                a->t0 = clock_.time;
                a->ramp = sp.ramp;
                ending_.ramp_end = std::max(ending_.ramp_end, a->ramp_end());
            }
            const int id = static_cast<int>(supports_.list.size());
            for (int k : grp.nodes) {
                const int d = 2 * k + c;
                supports_.dof_owner[d] = a ? id : -1;
                supports_.dof_kind[d] = a ? a->dof_kind() : 0;
                supports_.dof_velocity[d] = a ? a->start_velocity() : 0;
                supports_.reaction[d] = 0;
            }
            if (a) supports_.list.push_back(std::move(a));
        }
    }
    // Drop supports that no longer own any DOF (keeps the per-step loop short).
    {
        std::vector<int> remap(supports_.list.size(), -1);
        std::vector<std::unique_ptr<Support>> kept;
        std::vector<char> owns(supports_.list.size(), 0);
        for (int d = 0; d < 2 * nn; ++d)
            if (supports_.dof_owner[d] >= 0) owns[supports_.dof_owner[d]] = 1;
        for (std::size_t i = 0; i < supports_.list.size(); ++i)
            if (owns[i]) remap[i] = static_cast<int>(kept.size()), kept.push_back(std::move(supports_.list[i]));
        for (int d = 0; d < 2 * nn; ++d)
            if (supports_.dof_owner[d] >= 0) supports_.dof_owner[d] = remap[supports_.dof_owner[d]];
        supports_.list = std::move(kept);
    }
}

// begin_stage, part 3: loads (fdem/load.hpp). A block on a group replaces that group's previous load of the same
// kind, ramping from its value.
void Simulation::stage_loads(const StageSpec& st) {
    for (const LoadSpec& ls : st.loads) {
        const LoadKind* kind = find_load_kind(ls.kind);
        if (!kind) throw InputError(spec_.file + ":" + std::to_string(ls.line) + ": no load kind '" + ls.kind + "'");
        auto previous = loads_.list.end();
        for (auto it = loads_.list.begin(); it != loads_.list.end(); ++it)
            if ((*it)->group == ls.group && (*it)->kind == kind) {
                previous = it;
                break;
            }
        std::unique_ptr<Load> l = kind->begin(ls, previous != loads_.list.end() ? previous->get() : nullptr,
                                              LoadStart{model_, spec_.file, clock_.time, clock_.dt});
        l->group = ls.group;
        if (previous != loads_.list.end()) loads_.list.erase(previous);
        ending_.ramp_end = std::max(ending_.ramp_end, clock_.time + ls.ramp);
        loads_.list.push_back(std::move(l));
    }
}

// begin_stage, part 4: the termination state (until, past_peak) of stage s.
void Simulation::stage_termination(int s, const StageSpec& st) {
    ending_.until_monitor = -1;
    if (st.until_monitor) {
        for (std::size_t i = 0; i < spec_.monitors.size(); ++i)
            if (spec_.monitors[i].name == *st.until_monitor) ending_.until_monitor = static_cast<int>(i);
        ending_.until_start = monitor_value(ending_.until_monitor);
        // A target behind a driven displacement can never be reached (unless the monitor is already at or beyond it:
        // the stage then ends at once, stage_finished).
        const MonitorSpec& m = spec_.monitors[ending_.until_monitor];
        if (m.type == "displacement" && !until_holds(st.until_value, ending_.until_start))
            for (const auto& sp : st.supports)
                if (sp.group == m.group && sp.mode[m.component] == DofMode::velocity &&
                    (st.until_value - ending_.until_start) * sp.velocity[m.component] <= 0 && !st.max_duration &&
                    !st.duration)
                    throw InputError(spec_.file + ":" + std::to_string(st.line) + ": key 'stages." +
                                     std::to_string(s + 1) + ".until': this stage can never end: monitor '" + m.name +
                                     "' is at " + sci(ending_.until_start) +
                                     " and the prescribed velocity moves it away from " + sci(st.until_value));
    }
    ending_.peak_load_monitor = ending_.peak_disp_monitor = -1;
    ending_.peak_load = ending_.peak_disp = ending_.peak_mean = 0;
    ending_.below_since = ending_.peak_u_prev = std::numeric_limits<double>::quiet_NaN();
    if (st.past_peak) {
        for (std::size_t i = 0; i < spec_.monitors.size(); ++i) {
            if (spec_.monitors[i].name == st.past_peak->load) ending_.peak_load_monitor = static_cast<int>(i);
            if (spec_.monitors[i].name == st.past_peak->displacement) ending_.peak_disp_monitor = static_cast<int>(i);
        }
    }
}

void Simulation::begin_stage(int s) {
    const StageSpec& st = spec_.stages[s];
    if (s == 0) apply_initial_conditions();
    clock_.stage = s;
    clock_.stage_t0 = clock_.time;
    clock_.stage_steps0 = clock_.steps;
    clock_.eq_since = -1;
    ending_.ramp_end = clock_.time;
    stage_damping_and_gravity(st);
    stage_supports(st);
    stage_loads(st);
    stage_termination(s, st);
    check_ties();
    const double hi = history_interval();
    out_.next_history = hi > 0 ? clock_.time : 0;
    const double si = snapshot_interval();
    out_.next_snapshot = si > 0 ? clock_.time + si : 1e300;
    log("stage " + std::to_string(s + 1) + "/" + std::to_string(spec_.stages.size()) + " '" + st.name +
        "' starts at t = " + sci(clock_.time) + " s (local damping " + sci(damping_.local) +
        (damping_.filter_tau > 0 ? " against the velocities' moving mean over " + sci(damping_.filter_tau) + " s"
                                 : std::string()) +
        (damping_.mass > 0 ? ", mass damping " + sci(damping_.mass) + " 1/s" : std::string()) +
        (damping_.contact > 0 ? ", contact damping " + sci(damping_.contact) + " of critical: dashpots c = " +
                                    sci(damping_.contact * limits_.dt_contact) + " s x k"
                              : std::string()) +
        ")");
    if (s == 0) {  // initial velocities and deformation are energy put in, like external work
        const Energies e0 = energies();
        books_.W_ext += e0.kinetic + e0.elastic + e0.joint + e0.contact;
    }
    if (s == 0 && !opt_.out_dir.empty()) write_history_row();
}

void Simulation::apply_time_dependent(double t) {
    // Gravity: ramp, then the tilt rotation (counter-clockwise, deg).
    {
        const double w = gravity_.ramp > 0 ? std::min(1.0, (t - clock_.stage_t0) / gravity_.ramp) : 1.0;
        gravity_.current = {gravity_.start[0] + w * (gravity_.target[0] - gravity_.start[0]),
                            gravity_.start[1] + w * (gravity_.target[1] - gravity_.start[1])};
        const double a = gravity_.tilt_deg * kPi / 180;
        const double gf = gravity_.factor.present() ? gravity_.factor(t - gravity_.factor_t0) : 1.0;
        gravity_.applied = {gf * (std::cos(a) * gravity_.current[0] - std::sin(a) * gravity_.current[1]),
                            gf * (std::sin(a) * gravity_.current[0] + std::cos(a) * gravity_.current[1])};
    }
    // Loads.
    for (int d : loads_.loaded_dofs) loads_.f_ext[d] = 0, scratch_.node_loaded[d / 2] = 0;
    loads_.loaded_dofs.clear();
    const LoadStep step{model_, t, loads_.f_ext.data(), loads_.loaded_dofs};
    for (const auto& l : loads_.list) l->add_forces(step);
    for (int d : loads_.loaded_dofs) scratch_.node_loaded[d / 2] = 1;  // the node loop reads f_ext of these nodes only
    // Prescribed velocities for the update to t + dt (driven, protocol; fixed and rigid: none, rigid set in step()).
    for (std::size_t id = 0; id < supports_.list.size(); ++id) {
        double v = 0;
        if (!supports_.list[id]->prescribe(t, clock_.dt, v)) continue;
        const Support& s = *supports_.list[id];
        for (int k : s.nodes) {
            const int d = 2 * k + s.comp;
            if (supports_.dof_owner[d] == static_cast<int>(id)) supports_.dof_velocity[d] = v;
        }
    }
}

// After each step: the supports' own updates (the servos' velocity factors, fdem/support_velocity.cpp).
void Simulation::supports_after_step() {
    for (auto& s : supports_.list) s->after_step(clock_.dt, books_.unbalanced_ratio);
}

double Simulation::load_imbalance(double* applied, double* reactions) const {
    double L[2] = {0, 0}, R[2] = {0, 0};
    const int nn = model_.n_nodes();
    for (int k = 0; k < nn; ++k)
        for (int c = 0; c < 2; ++c) {
            const int d = 2 * k + c;
            L[c] += loads_.f_ext[d] + model_.grav_mass[k] * gravity_.applied[c];
            if (supports_.dof_kind[d] != 0 && supports_.dof_owner[d] >= 0 &&
                supports_.list[supports_.dof_owner[d]]->carries_reaction())
                R[c] += supports_.reaction[d];
        }
    // Loads that hold the body as a support does (an elastic foundation, Load::reacts): with the reactions.
    std::array<double, 2> r;
    for (const auto& l : loads_.list)
        if (l->reacts(r))
            for (int c = 0; c < 2; ++c) L[c] -= r[c], R[c] += r[c];
    if (applied) applied[0] = L[0], applied[1] = L[1];
    if (reactions) reactions[0] = R[0], reactions[1] = R[1];
    const double l = std::hypot(L[0], L[1]);
    return l > 0 ? std::hypot(L[0] + R[0], L[1] + R[1]) / l : 0.0;
}

bool Simulation::stage_finished() {
    const StageSpec& st = spec_.stages[clock_.stage];
    const double ts = clock_.time - clock_.stage_t0;
    auto finish = [&](const char* why) {
        ending_.results.push_back({st.name, why, clock_.time, clock_.steps - clock_.stage_steps0});
        return true;
    };
    if (st.duration && ts + 0.5 * clock_.dt >= *st.duration) return finish("duration");
    if (ending_.until_monitor >= 0) {
        const double m = monitor_value(ending_.until_monitor);
        if (clock_.steps == clock_.stage_steps0 && until_holds(st.until_value, m)) {
            log("stage " + std::to_string(clock_.stage + 1) + " '" + st.name +
                "': its until condition already holds at its start (" + *st.until_monitor + " = " + sci(m) +
                ", at or beyond " + sci(st.until_value) + "): it ends at once");
            return finish("until");
        }
        const double dir = st.until_value >= ending_.until_start ? 1.0 : -1.0;
        if (dir * (m - st.until_value) >= 0) return finish("until");
    }
    if (st.past_peak && past_peak_reached(*st.past_peak)) return finish("past_peak");
    // Equilibrium: the unbalanced-force ratio at most `equilibrium` and the reactions carrying the applied loads
    // within `equilibrium_reactions`, both without a break for a quarter of the stage's time up to when they first
    // held (at least 10 steps): a whole-body oscillation passes through zero imbalance twice a period, so one step
    // within the bounds says nothing; by the time the ratio is small the stage has lasted several of its periods.
    if (st.equilibrium && clock_.time >= ending_.ramp_end && clock_.steps - clock_.stage_steps0 > 10) {
        double L[2], R[2];
        const double imbalance = books_.unbalanced_ratio <= *st.equilibrium ? load_imbalance(L, R) : 1.0;
        if (books_.unbalanced_ratio <= *st.equilibrium && imbalance <= st.equilibrium_reactions) {
            if (!(clock_.eq_since >= 0)) clock_.eq_since = clock_.time;
            if (clock_.time - clock_.eq_since + 0.5 * clock_.dt >=
                std::max(10 * clock_.dt, 0.25 * (clock_.eq_since - clock_.stage_t0))) {
                log("stage " + std::to_string(clock_.stage + 1) + " '" + st.name + "': equilibrium since t = " +
                    sci(clock_.eq_since) + " s: unbalanced-force ratio " + sci(books_.unbalanced_ratio) +
                    ", the reactions (" + sci(R[0]) + ", " + sci(R[1]) + ") N carry the applied loads (" + sci(L[0]) +
                    ", " + sci(L[1]) + ") N within " + sci(100 * imbalance) + " %");
                return finish("equilibrium");
            }
        } else {
            clock_.eq_since = -1;
        }
    }
    if (st.max_duration && ts + 0.5 * clock_.dt >= *st.max_duration) return finish("max_duration");
    return false;
}

// The past-peak end of a pushover stage (StageSpec::PastPeak). The load magnitude |F| is averaged over displacement
// by a running mean, Fbar += w (|F| - Fbar) with w = min(1, |du| / smooth) (explicit runs carry oscillations of the
// whole wall on top of the quasi-static load, of a few per cent of it: a raw crest is not the peak); the largest
// Fbar of the stage is the peak, and u_b is the displacement at which Fbar last fell below (1 - drop) of it. The
// stage ends when Fbar has stayed below since u_b and |u - u_b| >= travel. Read every step at the monitors' time t^n
// (monitor_value).
bool Simulation::past_peak_reached(const StageSpec::PastPeak& pp) {
    if (ending_.peak_load_monitor < 0 || ending_.peak_disp_monitor < 0) return false;
    const double f = std::abs(monitor_value(ending_.peak_load_monitor));
    const double u = monitor_value(ending_.peak_disp_monitor);
    if (std::isnan(ending_.peak_u_prev)) {
        ending_.peak_mean = f, ending_.peak_u_prev = u;
    } else {
        const double w = std::min(1.0, std::abs(u - ending_.peak_u_prev) / pp.smooth);
        ending_.peak_mean += w * (f - ending_.peak_mean);
        ending_.peak_u_prev = u;
    }
    if (ending_.peak_mean > ending_.peak_load) ending_.peak_load = ending_.peak_mean, ending_.peak_disp = u;
    if (!(ending_.peak_mean < (1.0 - pp.drop) * ending_.peak_load)) {
        ending_.below_since = std::numeric_limits<double>::quiet_NaN();
        return false;
    }
    if (std::isnan(ending_.below_since)) ending_.below_since = u;
    if (std::abs(u - ending_.below_since) < pp.travel) return false;
    log("stage " + std::to_string(clock_.stage + 1) + ": past its peak: |" + pp.load + "| averaged over " +
        sci(pp.smooth) + " of " + pp.displacement + " has stayed below " + sci(1.0 - pp.drop, 3) +
        " of its largest value " + sci(ending_.peak_load) + " (at " + pp.displacement + " = " + sci(ending_.peak_disp) +
        ") over " + sci(std::abs(u - ending_.below_since)) + " of " + pp.displacement);
    return true;
}

}  // namespace fdem
