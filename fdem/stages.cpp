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
        v2max_ = -1.0;  // (the node loop's speed is not this v's)
        log("initial conditions on '" + in.group + "': " + std::to_string(grp.nodes.size()) + " nodes" +
            (in.rotation != 0 ? ", placement turned by " + sci(in.rotation) + " deg" : std::string()) +
            ", velocity [" + sci(in.velocity[0]) + ", " + sci(in.velocity[1]) + "] m/s" +
            (in.angular_velocity != 0 ? " + " + sci(in.angular_velocity) + " rad/s about the centre" : std::string()));
    }
}

// begin_stage, part 1: the damping (local, its filter, mass, contact dashpots) and gravity (vector, ramp, tilt,
// time function) that the stage sets; the others carry over.
void Simulation::stage_damping_and_gravity(const StageSpec& st) {
    if (st.local_damping && *st.local_damping != alpha_) {
        // The stable step depends on the local damping (damped_step_factor, fdem/model.hpp): a stage that changes it
        // sets the step again from the current model (faces that cracks opened included).
        alpha_ = *st.local_damping;
        if (!spec_.dt_override) {
            const double before = dt_;
            set_step_limits(alpha_, true);
            if (dt_ != before) {
                dt_logged_ = dt_;
                log("time step: " + sci(dt_) + " s = " + sci(spec_.safety) + " x stable limit " + sci(dt_limit_) +
                    " s at local damping " + sci(alpha_) + " (stage '" + st.name + "')");
            }
        }
    }
    if (st.local_damping_filter) {
        // The moving mean starts from the current velocities, so switching the filter on does not kick the motion.
        if (*st.local_damping_filter > 0 && !(tau_ld_ > 0)) {
            v_ref_ = model_.v;
            for (auto& sp : supports_) sp->filter_started();
        }
        tau_ld_ = *st.local_damping_filter;
        if (!(tau_ld_ > 0)) v_ref_.clear();
    }
    if (st.mass_damping) beta_mass_ = *st.mass_damping;
    if (st.contact_damping) {
        xi_contact_ = *st.contact_damping;
        inter_.set_contact_dashpot(std::isfinite(dt_contact_) ? xi_contact_ * dt_contact_ : 0.0);
    }
    if (st.gravity) {
        gravity_start_ = gravity_;
        gravity_target_ = *st.gravity;
        gravity_ramp_ = st.gravity_ramp;
        stage_ramp_end_ = std::max(stage_ramp_end_, time_ + st.gravity_ramp);
    } else {
        gravity_start_ = gravity_target_ = gravity_;
        gravity_ramp_ = 0;
    }
    tilt_rate_ = st.tilt_rate;
    if (st.gravity_function.present()) {
        gravity_fn_ = st.gravity_function;
        gravity_fn_t0_ = time_;
    } else if (st.gravity) {
        gravity_fn_ = TimeFunction{};
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
            std::unique_ptr<Support> a = find_support_kind(sp.mode[c])->begin(sp, c, SupportStart{model_, time_, dof_kind_.data(), dof_vel_.data()});
            if (a) {
                a->nodes = grp.nodes;
                a->comp = c;
                a->group = sp.group;
                a->t0 = time_;
                a->ramp = sp.ramp;
                stage_ramp_end_ = std::max(stage_ramp_end_, a->ramp_end());
            }
            const int id = static_cast<int>(supports_.size());
            for (int k : grp.nodes) {
                const int d = 2 * k + c;
                dof_owner_[d] = a ? id : -1;
                dof_kind_[d] = a ? a->dof_kind() : 0;
                dof_vel_[d] = a ? a->start_velocity() : 0;
                reaction_[d] = 0;
            }
            if (a) supports_.push_back(std::move(a));
        }
    }
    // Drop supports that no longer own any DOF (keeps the per-step loop short).
    {
        std::vector<int> remap(supports_.size(), -1);
        std::vector<std::unique_ptr<Support>> kept;
        std::vector<char> owns(supports_.size(), 0);
        for (int d = 0; d < 2 * nn; ++d)
            if (dof_owner_[d] >= 0) owns[dof_owner_[d]] = 1;
        for (std::size_t i = 0; i < supports_.size(); ++i)
            if (owns[i]) remap[i] = static_cast<int>(kept.size()), kept.push_back(std::move(supports_[i]));
        for (int d = 0; d < 2 * nn; ++d)
            if (dof_owner_[d] >= 0) dof_owner_[d] = remap[dof_owner_[d]];
        supports_ = std::move(kept);
    }
}

// begin_stage, part 3: loads (fdem/load.hpp). A block on a group replaces that group's previous load of the same
// kind, ramping from its value.
void Simulation::stage_loads(const StageSpec& st) {
    for (const LoadSpec& ls : st.loads) {
        const LoadKind* kind = find_load_kind(ls.kind);
        if (!kind) throw InputError(spec_.file + ":" + std::to_string(ls.line) + ": no load kind '" + ls.kind + "'");
        auto previous = loads_.end();
        for (auto it = loads_.begin(); it != loads_.end(); ++it)
            if ((*it)->group == ls.group && (*it)->kind == kind) {
                previous = it;
                break;
            }
        std::unique_ptr<Load> l = kind->begin(ls, previous != loads_.end() ? previous->get() : nullptr, LoadStart{model_, spec_.file, time_, dt_});
        l->group = ls.group;
        if (previous != loads_.end()) loads_.erase(previous);
        stage_ramp_end_ = std::max(stage_ramp_end_, time_ + ls.ramp);
        loads_.push_back(std::move(l));
    }
}

// begin_stage, part 4: the termination state (until, past_peak) of stage s.
void Simulation::stage_termination(int s, const StageSpec& st) {
    until_monitor_ = -1;
    if (st.until_monitor) {
        for (std::size_t i = 0; i < spec_.monitors.size(); ++i)
            if (spec_.monitors[i].name == *st.until_monitor) until_monitor_ = static_cast<int>(i);
        until_start_ = monitor_value(until_monitor_);
        // A target behind a driven displacement can never be reached (unless the monitor is already at or beyond it:
        // the stage then ends at once, stage_finished).
        const MonitorSpec& m = spec_.monitors[until_monitor_];
        if (m.type == "displacement" && !until_holds(st.until_value, until_start_))
            for (const auto& sp : st.supports)
                if (sp.group == m.group && sp.mode[m.component] == DofMode::velocity &&
                    (st.until_value - until_start_) * sp.velocity[m.component] <= 0 && !st.max_duration && !st.duration)
                    throw InputError(spec_.file + ":" + std::to_string(st.line) + ": key 'stages." + std::to_string(s + 1) +
                                     ".until': this stage can never end: monitor '" + m.name + "' is at " +
                                     sci(until_start_) + " and the prescribed velocity moves it away from " +
                                     sci(st.until_value));
    }
    peak_load_monitor_ = peak_disp_monitor_ = -1;
    peak_load_ = peak_disp_ = peak_mean_ = 0;
    below_since_ = peak_u_prev_ = std::numeric_limits<double>::quiet_NaN();
    if (st.past_peak) {
        for (std::size_t i = 0; i < spec_.monitors.size(); ++i) {
            if (spec_.monitors[i].name == st.past_peak->load) peak_load_monitor_ = static_cast<int>(i);
            if (spec_.monitors[i].name == st.past_peak->displacement) peak_disp_monitor_ = static_cast<int>(i);
        }
    }
}

void Simulation::begin_stage(int s) {
    const StageSpec& st = spec_.stages[s];
    if (s == 0) apply_initial_conditions();
    stage_ = s;
    stage_t0_ = time_;
    stage_steps0_ = steps_;
    eq_since_ = -1;
    stage_ramp_end_ = time_;
    stage_damping_and_gravity(st);
    stage_supports(st);
    stage_loads(st);
    stage_termination(s, st);
    check_ties();
    const double hi = history_interval();
    next_history_ = hi > 0 ? time_ : 0;
    const double si = snapshot_interval();
    next_snapshot_ = si > 0 ? time_ + si : 1e300;
    log("stage " + std::to_string(s + 1) + "/" + std::to_string(spec_.stages.size()) + " '" + st.name + "' starts at t = " +
        sci(time_) + " s (local damping " + sci(alpha_) +
        (tau_ld_ > 0 ? " against the velocities' moving mean over " + sci(tau_ld_) + " s" : std::string()) +
        (beta_mass_ > 0 ? ", mass damping " + sci(beta_mass_) + " 1/s" : std::string()) +
        (xi_contact_ > 0 ? ", contact damping " + sci(xi_contact_) + " of critical: dashpots c = " + sci(xi_contact_ * dt_contact_) + " s x k" : std::string()) +
        ")");
    if (s == 0) {  // initial velocities and deformation are energy put in, like external work
        const Energies e0 = energies();
        W_ext_ += e0.kinetic + e0.elastic + e0.joint + e0.contact;
    }
    if (s == 0 && !opt_.out_dir.empty()) write_history_row();
}

void Simulation::apply_time_dependent(double t) {
    // Gravity: ramp, then the tilt rotation (counter-clockwise, deg).
    {
        const double w = gravity_ramp_ > 0 ? std::min(1.0, (t - stage_t0_) / gravity_ramp_) : 1.0;
        gravity_ = {gravity_start_[0] + w * (gravity_target_[0] - gravity_start_[0]),
                    gravity_start_[1] + w * (gravity_target_[1] - gravity_start_[1])};
        const double a = tilt_deg_ * kPi / 180;
        const double gf = gravity_fn_.present() ? gravity_fn_(t - gravity_fn_t0_) : 1.0;
        applied_gravity_ = {gf * (std::cos(a) * gravity_[0] - std::sin(a) * gravity_[1]),
                            gf * (std::sin(a) * gravity_[0] + std::cos(a) * gravity_[1])};
    }
    // Loads.
    for (int d : loaded_dofs_) f_ext_[d] = 0, node_loaded_[d / 2] = 0;
    loaded_dofs_.clear();
    const LoadStep step{model_, t, f_ext_.data(), loaded_dofs_};
    for (const auto& l : loads_) l->add_forces(step);
    for (int d : loaded_dofs_) node_loaded_[d / 2] = 1;  // the node loop reads f_ext_ of these nodes only
    // Prescribed velocities for the update to t + dt (driven, protocol; fixed and rigid: none, rigid set in step()).
    for (std::size_t id = 0; id < supports_.size(); ++id) {
        double v = 0;
        if (!supports_[id]->prescribe(t, dt_, v)) continue;
        const Support& s = *supports_[id];
        for (int k : s.nodes) {
            const int d = 2 * k + s.comp;
            if (dof_owner_[d] == static_cast<int>(id)) dof_vel_[d] = v;
        }
    }
}

// After each step: the supports' own updates (the servos' velocity factors, fdem/support_velocity.cpp).
void Simulation::supports_after_step() {
    for (auto& s : supports_) s->after_step(dt_, unbalanced_ratio_);
}

double Simulation::load_imbalance(double* applied, double* reactions) const {
    double L[2] = {0, 0}, R[2] = {0, 0};
    const int nn = model_.n_nodes();
    for (int k = 0; k < nn; ++k)
        for (int c = 0; c < 2; ++c) {
            const int d = 2 * k + c;
            L[c] += f_ext_[d] + model_.grav_mass[k] * applied_gravity_[c];
            if (dof_kind_[d] != 0 && dof_owner_[d] >= 0 && supports_[dof_owner_[d]]->carries_reaction()) R[c] += reaction_[d];
        }
    // Loads that hold the body as a support does (an elastic foundation, Load::reacts): with the reactions.
    std::array<double, 2> r;
    for (const auto& l : loads_)
        if (l->reacts(r))
            for (int c = 0; c < 2; ++c) L[c] -= r[c], R[c] += r[c];
    if (applied) applied[0] = L[0], applied[1] = L[1];
    if (reactions) reactions[0] = R[0], reactions[1] = R[1];
    const double l = std::hypot(L[0], L[1]);
    return l > 0 ? std::hypot(L[0] + R[0], L[1] + R[1]) / l : 0.0;
}

bool Simulation::stage_finished() {
    const StageSpec& st = spec_.stages[stage_];
    const double ts = time_ - stage_t0_;
    auto finish = [&](const char* why) {
        stage_results_.push_back({st.name, why, time_, steps_ - stage_steps0_});
        return true;
    };
    if (st.duration && ts + 0.5 * dt_ >= *st.duration) return finish("duration");
    if (until_monitor_ >= 0) {
        const double m = monitor_value(until_monitor_);
        if (steps_ == stage_steps0_ && until_holds(st.until_value, m)) {
            log("stage " + std::to_string(stage_ + 1) + " '" + st.name + "': its until condition already holds at its start (" +
                *st.until_monitor + " = " + sci(m) + ", at or beyond " + sci(st.until_value) + "): it ends at once");
            return finish("until");
        }
        const double dir = st.until_value >= until_start_ ? 1.0 : -1.0;
        if (dir * (m - st.until_value) >= 0) return finish("until");
    }
    if (st.past_peak && past_peak_reached(*st.past_peak)) return finish("past_peak");
    // Equilibrium: the unbalanced-force ratio at most `equilibrium` and the reactions carrying the applied loads
    // within `equilibrium_reactions`, both without a break for a quarter of the stage's time up to when they first
    // held (at least 10 steps): a whole-body oscillation passes through zero imbalance twice a period, so one step
    // within the bounds says nothing; by the time the ratio is small the stage has lasted several of its periods.
    if (st.equilibrium && time_ >= stage_ramp_end_ && steps_ - stage_steps0_ > 10) {
        double L[2], R[2];
        const double imbalance = unbalanced_ratio_ <= *st.equilibrium ? load_imbalance(L, R) : 1.0;
        if (unbalanced_ratio_ <= *st.equilibrium && imbalance <= st.equilibrium_reactions) {
            if (!(eq_since_ >= 0)) eq_since_ = time_;
            if (time_ - eq_since_ + 0.5 * dt_ >= std::max(10 * dt_, 0.25 * (eq_since_ - stage_t0_))) {
                log("stage " + std::to_string(stage_ + 1) + " '" + st.name + "': equilibrium since t = " + sci(eq_since_) +
                    " s: unbalanced-force ratio " + sci(unbalanced_ratio_) + ", the reactions (" + sci(R[0]) + ", " +
                    sci(R[1]) + ") N carry the applied loads (" + sci(L[0]) + ", " + sci(L[1]) + ") N within " +
                    sci(100 * imbalance) + " %");
                return finish("equilibrium");
            }
        } else {
            eq_since_ = -1;
        }
    }
    if (st.max_duration && ts + 0.5 * dt_ >= *st.max_duration) return finish("max_duration");
    return false;
}

// The past-peak end of a pushover stage (StageSpec::PastPeak). The load magnitude |F| is averaged over displacement
// by a running mean, Fbar += w (|F| - Fbar) with w = min(1, |du| / smooth) (explicit runs carry oscillations of the
// whole wall on top of the quasi-static load, of a few per cent of it: a raw crest is not the peak); the largest
// Fbar of the stage is the peak, and u_b is the displacement at which Fbar last fell below (1 - drop) of it. The
// stage ends when Fbar has stayed below since u_b and |u - u_b| >= travel. Read every step at the monitors' time t^n
// (monitor_value).
bool Simulation::past_peak_reached(const StageSpec::PastPeak& pp) {
    if (peak_load_monitor_ < 0 || peak_disp_monitor_ < 0) return false;
    const double f = std::abs(monitor_value(peak_load_monitor_));
    const double u = monitor_value(peak_disp_monitor_);
    if (std::isnan(peak_u_prev_)) {
        peak_mean_ = f, peak_u_prev_ = u;
    } else {
        const double w = std::min(1.0, std::abs(u - peak_u_prev_) / pp.smooth);
        peak_mean_ += w * (f - peak_mean_);
        peak_u_prev_ = u;
    }
    if (peak_mean_ > peak_load_) peak_load_ = peak_mean_, peak_disp_ = u;
    if (!(peak_mean_ < (1.0 - pp.drop) * peak_load_)) {
        below_since_ = std::numeric_limits<double>::quiet_NaN();
        return false;
    }
    if (std::isnan(below_since_)) below_since_ = u;
    if (std::abs(u - below_since_) < pp.travel) return false;
    log("stage " + std::to_string(stage_ + 1) + ": past its peak: |" + pp.load + "| averaged over " + sci(pp.smooth) +
        " of " + pp.displacement + " has stayed below " + sci(1.0 - pp.drop, 3) + " of its largest value " +
        sci(peak_load_) + " (at " + pp.displacement + " = " + sci(peak_disp_) + ") over " +
        sci(std::abs(u - below_since_)) + " of " + pp.displacement);
    return true;
}

}  // namespace fdem
