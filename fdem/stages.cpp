// fdem/stages.cpp: the stage logic of Simulation: initial conditions, what a stage sets when it begins (supports,
// loads, protocols, damping, gravity), the time-dependent loads and velocities of every step, the servos and how a
// stage ends (duration, until, equilibrium).
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

double Simulation::protocol_displacement(const ActiveSupport& s, double tau) const {
    if (tau <= s.pt.front()) return s.pu.front();
    if (tau >= s.pt.back()) return s.pu.back();
    const auto it = std::upper_bound(s.pt.begin(), s.pt.end(), tau);
    const std::size_t i = static_cast<std::size_t>(it - s.pt.begin());
    const double w = (tau - s.pt[i - 1]) / (s.pt[i] - s.pt[i - 1]);
    return s.pu[i - 1] + w * (s.pu[i] - s.pu[i - 1]);
}

double Simulation::protocol_integral(const ActiveSupport& s, double tau) const {
    // INT_{pt[0]}^{tau} u dt of the piecewise-linear protocol, u held at its end values outside [pt[0], pt[n-1]].
    if (tau <= s.pt.front()) return (tau - s.pt.front()) * s.pu.front();
    if (tau >= s.pt.back()) return s.pI.back() + (tau - s.pt.back()) * s.pu.back();
    const auto it = std::upper_bound(s.pt.begin(), s.pt.end(), tau);
    const std::size_t i = static_cast<std::size_t>(it - s.pt.begin());
    const double w = (tau - s.pt[i - 1]) / (s.pt[i] - s.pt[i - 1]);
    const double u = s.pu[i - 1] + w * (s.pu[i] - s.pu[i - 1]);  // protocol_displacement(s, tau), same segment
    return s.pI[i - 1] + 0.5 * (tau - s.pt[i - 1]) * (s.pu[i - 1] + u);
}

double Simulation::protocol_position(const ActiveSupport& s, double tau) const {
    // Corner smoothing: with ramp T > 0 the driven position is the protocol averaged over the trailing window
    // [tau - T, tau], u_T(tau) = (I(tau) - I(tau - T)) / T. Its velocity (u(tau) - u(tau - T)) / T is continuous:
    // it starts from 0 at the stage start and changes linearly over T at every corner (largest acceleration
    // |dv| / T), instead of jumping in one step (a reversal of v then asks the driven nodes for a force
    // m 2 v / dt, which the reaction monitor reports and which hits the specimen like an impact). The price: the
    // motion lags the protocol by T / 2 and each corner is cut by |dv| T / 8 (an amplitude a reached at rate v
    // and reversed: a - v T / 4).
    if (!(s.ramp > 0)) return protocol_displacement(s, tau);
    return (protocol_integral(s, tau) - protocol_integral(s, tau - s.ramp)) / s.ramp;
}

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
            for (auto& sp : supports_) sp.v_ref = sp.v_common;
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

// begin_stage, part 2: supports. A new block takes over the DOFs it names; the others keep their previous support.
void Simulation::stage_supports(const StageSpec& st) {
    const int nn = model_.n_nodes();
    for (const SupportSpec& sp : st.supports) {
        const auto& grp = model_.group(sp.group);
        for (int c = 0; c < 2; ++c) {
            if (sp.mode[c] == DofMode::inherit) continue;
            ActiveSupport a;
            a.nodes = grp.nodes;
            a.comp = c;
            a.mode = sp.mode[c];
            a.group = sp.group;
            a.t0 = time_;
            a.ramp = sp.ramp;
            if (sp.mode[c] == DofMode::velocity) {
                a.fn = sp.function;
                a.servo_ratio = sp.servo_ratio, a.servo_time = sp.servo_time, a.servo_min = sp.servo_min;
                a.servo_rbar = sp.servo_ratio;
            }
            if (a.mode == DofMode::velocity) {
                // Smooth ramp from the group's current prescribed velocity (0 if it was fixed or free).
                const int d0 = 2 * a.nodes.front() + c;
                a.v_start = dof_kind_[d0] == 2 ? dof_vel_[d0] : 0.0;
                a.v_target = sp.velocity[c];
                stage_ramp_end_ = std::max(stage_ramp_end_, time_ + sp.ramp);
            }
            if (a.mode == DofMode::protocol) {
                a.pt = sp.protocol_t, a.pu = sp.protocol_u;
                a.pI.assign(a.pt.size(), 0.0);
                for (std::size_t i = 1; i < a.pt.size(); ++i)
                    a.pI[i] = a.pI[i - 1] + 0.5 * (a.pt[i] - a.pt[i - 1]) * (a.pu[i] + a.pu[i - 1]);
            }
            if (a.mode == DofMode::rigid) {
                // Starts from the group's momentum: the mass-weighted mean velocity.
                double p = 0, m = 0;
                for (int k : a.nodes) p += model_.mass[k] * model_.v[2 * k + c], m += model_.mass[k];
                a.v_common = m > 0 ? p / m : 0.0;
                a.v_ref = a.v_common;  // the filtered local damping's mean starts there (no kick)
            }
            const int id = static_cast<int>(supports_.size());
            for (int k : a.nodes) {
                const int d = 2 * k + c;
                dof_owner_[d] = a.mode == DofMode::free ? -1 : id;
                dof_kind_[d] = a.mode == DofMode::free ? 0 : a.mode == DofMode::fixed ? 1 : 2;
                dof_vel_[d] = a.mode == DofMode::rigid ? a.v_common : 0;
                reaction_[d] = 0;
            }
            supports_.push_back(std::move(a));
        }
    }
    // Drop supports that no longer own any DOF (keeps the per-step loop short).
    {
        std::vector<int> remap(supports_.size(), -1);
        std::vector<ActiveSupport> kept;
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
    // Prescribed velocities for the update to t + dt (evaluated at the half step).
    const double th = t + 0.5 * dt_;
    for (std::size_t id = 0; id < supports_.size(); ++id) {
        const ActiveSupport& s = supports_[id];
        if (s.mode == DofMode::fixed || s.mode == DofMode::rigid) continue;  // rigid: set in step() from the forces
        double v = 0;
        if (s.mode == DofMode::velocity) {
            const double tau = th - s.t0;
            v = s.ramp > 0 && tau < s.ramp ? s.v_start + (s.v_target - s.v_start) * 0.5 * (1 - std::cos(kPi * tau / s.ramp)) : s.v_target;
            if (s.fn.present()) v *= s.fn(tau);
            if (s.servo_ratio > 0) v *= s.servo_factor;
        } else {
            // Displacement protocol: the velocity that lands exactly on u(t + dt) from u(t) (corner-smoothed
            // when the support has a ramp).
            v = (protocol_position(s, t + dt_ - s.t0) - protocol_position(s, t - s.t0)) / dt_;
        }
        for (int k : s.nodes) {
            const int d = 2 * k + s.comp;
            if (dof_owner_[d] == static_cast<int>(id)) dof_vel_[d] = v;
        }
    }
}

// Servo-controlled loading rate (the Itasca codes' practice of driving a quasi-static test by its unbalanced-force
// ratio, Itasca 3DEC manual; Lourenco, Oliveira, Roca, Orduna 2005 run their 3DEC walls so). R's mean over the
// response time T follows rbar += w (R - rbar), w = dt / T; the factor follows
// f <- clamp(f exp(w clamp(ln(R* / rbar), -2, 2)), f_min, 1): while the mean ratio is above the target the actuator
// slows down (by up to e^-2 per T), below it speeds back up, never beyond the prescribed velocity.
void Simulation::update_servos() {
    for (ActiveSupport& s : supports_) {
        if (s.servo_ratio <= 0 || s.mode != DofMode::velocity) continue;
        const double w = std::min(1.0, dt_ / s.servo_time);
        s.servo_rbar += w * (unbalanced_ratio_ - s.servo_rbar);
        const double g = std::log(s.servo_ratio / std::max(s.servo_rbar, 1e-300));
        s.servo_factor = std::clamp(s.servo_factor * std::exp(w * std::clamp(g, -2.0, 2.0)), s.servo_min, 1.0);
        s.servo_t += dt_;
        s.servo_r_int += dt_ * s.servo_rbar;
        s.servo_f_int += dt_ * s.servo_factor;
        s.servo_r_max = std::max(s.servo_r_max, s.servo_rbar);
        s.servo_f_min = std::min(s.servo_f_min, s.servo_factor);
    }
}

double Simulation::load_imbalance(double* applied, double* reactions) const {
    double L[2] = {0, 0}, R[2] = {0, 0};
    const int nn = model_.n_nodes();
    for (int k = 0; k < nn; ++k)
        for (int c = 0; c < 2; ++c) {
            const int d = 2 * k + c;
            L[c] += f_ext_[d] + model_.grav_mass[k] * applied_gravity_[c];
            if (dof_kind_[d] != 0 && dof_owner_[d] >= 0 && supports_[dof_owner_[d]].mode != DofMode::rigid) R[c] += reaction_[d];
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
