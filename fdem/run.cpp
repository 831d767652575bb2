// fdem/run.cpp: the run driver: the loop over steps and stages, outputs and checkpoints on their intervals, progress
// lines, stops by signal (SIGINT, SIGTERM, SIGUSR1), failures, and run_case (case file -> scene -> Simulation -> run).
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
#include "fdem/scene.hpp"
#include "fdem/sim_detail.hpp"

namespace fdem {

using namespace sim_detail;

// The progress of the run: the stage's fraction (its duration, its until monitor, or its max_duration), the
// stage's time left at the present rate, and the run's: this stage's plus the later stages' durations (their
// max_duration, an upper bound, when only that is known; "?" when a later stage ends by a criterion alone).
std::string Simulation::progress_text(double& frac) {
    const double now = wall_clock();
    const StageSpec& st = spec_.stages[clock_.stage];
    const double ts = clock_.time - clock_.stage_t0;
    frac = -1;
    if (st.duration) frac = ts / *st.duration;
    if (ending_.until_monitor >= 0 && st.until_value != ending_.until_start)
        frac = std::max(frac, (monitor_value(ending_.until_monitor) - ending_.until_start) /
                                  (st.until_value - ending_.until_start));
    if (frac < 0 && st.max_duration) frac = ts / *st.max_duration;
    const double el = now - wall_start_;
    const double rate = std::max(static_cast<double>(clock_.steps) / std::max(el, 1e-9), 1.0);  // steps per wall second
    std::string eta = "?", run_eta = "?";
    if (frac > 0.001) {
        const double stage_left = (1 - std::min(frac, 1.0)) * (ts / std::max(frac, 1e-9)) / clock_.dt / rate;
        eta = human_time(stage_left);
        double later = 0;
        bool known = true, bound = false;
        for (std::size_t k = static_cast<std::size_t>(clock_.stage) + 1; k < spec_.stages.size(); ++k) {
            const StageSpec& sk = spec_.stages[k];
            if (sk.duration) later += *sk.duration;
            else if (sk.max_duration) later += *sk.max_duration, bound = true;
            else known = false;
        }
        if (known) run_eta = (bound ? "at most " : "") + human_time(stage_left + later / clock_.dt / rate);
    }
    char b[320];
    std::snprintf(b, sizeof b, "[stage %d/%zu %s] %5.1f%%  t = %.4g s  %.3g steps/s  stage left %s  run left %s",
                  clock_.stage + 1, spec_.stages.size(), st.name.c_str(), 100 * std::clamp(frac, 0.0, 1.0), clock_.time,
                  rate, eta.c_str(), run_eta.c_str());
    return b;
}

void Simulation::progress_line(bool final) {
    const double now = wall_clock();
    if (!final && now - last_progress_ < 1.0) return;
    last_progress_ = now;
    double frac = 0;
    std::cerr << "\r" << progress_text(frac) << "   " << (final ? "\n" : "") << std::flush;
}

void Simulation::progress_log_line() {
    const double now = wall_clock();
    if (now - last_progress_log_ < opt_.progress_interval) return;
    last_progress_log_ = now;
    double frac = 0;
    log("progress: " + progress_text(frac));
}

void Simulation::fail(const std::string& what) {
    const std::string msg = what + "; stage " + std::to_string(clock_.stage + 1) + " '" +
                            spec_.stages[clock_.stage].name + "', step " + std::to_string(clock_.steps) +
                            ", t = " + sci(clock_.time, 6) + " s (dt = " + sci(clock_.dt) + " s, stable limit " +
                            sci(clock_.dt_limit) + " s)";
    wall_time_ = wall_clock() - wall_start_;
    cpu_time_ = cpu_clock() - cpu_start_;
    log_ += "error: run failed: " + msg + "\n";  // run.log; the terminal gets it once, on stderr from main
    if (!opt_.out_dir.empty()) {
        flush_files();
        write_summary("failed", msg);
    }
    throw RunError(msg);
}

namespace {
// SIGINT/SIGTERM/SIGUSR1: the handler only records the signal; the run loop finishes the step, writes a checkpoint and
// its outputs with status "interrupted", and run_case returns 128 + the signal number (130, 143, 138), the shell's
// convention. SIGUSR1 is what Slurm's --signal=USR1@SECONDS sends before the time limit.
volatile std::sig_atomic_t g_stop_signal = 0;
extern "C" void fdem_stop_handler(int sig) { g_stop_signal = sig; }

struct StopHandlers {
    struct sigaction old_int {}, old_term {}, old_usr1 {};
    StopHandlers() {
        g_stop_signal = 0;
        struct sigaction sa {};
        sa.sa_handler = fdem_stop_handler;
        sigemptyset(&sa.sa_mask);
        sigaction(SIGINT, &sa, &old_int);
        sigaction(SIGTERM, &sa, &old_term);
        sigaction(SIGUSR1, &sa, &old_usr1);
    }
    ~StopHandlers() {
        sigaction(SIGINT, &old_int, nullptr);
        sigaction(SIGTERM, &old_term, nullptr);
        sigaction(SIGUSR1, &old_usr1, nullptr);
    }
    StopHandlers(const StopHandlers&) = delete;
    StopHandlers& operator=(const StopHandlers&) = delete;
};
}  // namespace

// A stop asked for by a signal: the step is finished; a checkpoint, then history row, snapshot, files and summary
// are written (the checkpoint first: it holds the state before the extra row, which a restart truncates away).
void Simulation::interrupt(int sig, const std::string& why) {
    interrupted_signal_ = sig;
    if (!opt_.out_dir.empty()) write_checkpoint();
    wall_time_ = wall_clock() - wall_start_;
    cpu_time_ = cpu_clock() - cpu_start_;
    if (opt_.progress) progress_line(true);
    const std::string by = !why.empty()       ? why
                           : sig == SIGINT    ? "interrupted by SIGINT"
                           : sig == SIGTERM   ? "interrupted by SIGTERM"
                           : sig == SIGUSR1   ? "interrupted by SIGUSR1"
                                              : "interrupted by a signal";
    const std::string msg =
        by + " in stage " + std::to_string(clock_.stage + 1) + " '" + spec_.stages[clock_.stage].name + "' at step " +
        std::to_string(clock_.steps) + ", t = " + sci(clock_.time, 6) + " s" +
        (opt_.out_dir.empty() ? std::string()
                              : "; checkpoint written: continue with fdem run CASE --restart " + opt_.out_dir);
    log(msg);
    if (!opt_.out_dir.empty()) {
        record_dry_joints();
        if (out_.last_row_step != clock_.steps) append_history(history_row(energies()));
        write_snapshot();
        flush_files();
        write_summary("interrupted", msg);
    }
}

void Simulation::run() {
    const StopHandlers stop_handlers;
    log("fdem " FDEM_VERSION ": case '" + spec_.name + "' (" + spec_.file + ")");
    log("mesh: " + std::to_string(model_.n_triangles()) + " triangles, " + std::to_string(model_.n_nodes()) + " nodes");
    std::string by;
    if (limits_.dt_element >= 0) {
        by = "triangle " + std::to_string(limits_.dt_element);
    } else {
        const NodalLimit& L = limits_.nodal;
        const double k = L.k_tri + L.k_joint + L.k_contact;
        auto pct = [k](double x) { return std::to_string(static_cast<int>(std::lround(100 * x / k))) + " %"; };
        by = (L.body >= 0 ? "rigid body '" + limits_.bodies.group[L.body] + "': triangles " : "node " + std::to_string(L.node) + ": triangles ") +
             pct(L.k_tri) + ", joints " + pct(L.k_joint) + ", contact " + pct(L.k_contact) + " of its stiffness";
    }
    log("time step: " + sci(clock_.dt) +
        " s = " + (spec_.dt_override ? std::string("fixed by numerics.dt") : sci(spec_.safety) + " x stable limit") +
        " " + sci(clock_.dt_limit) + " s (set by " + by +
        ((resumed_ ? damping_.local : stage_alpha(0)) > 0
             ? ", at local damping " + sci(resumed_ ? damping_.local : stage_alpha(0))
             : std::string()) +
        ")" +
        (std::isfinite(clock_.dt_springs)
             ? "; the joint and contact springs alone, every face that may touch in contact: " +
                   sci(clock_.dt_springs) + " s"
             : std::string()));
    if (!model_.has_topology && model_.mesh.n_bodies() > 1)
        log("no interface or fracture rules: the " + std::to_string(model_.mesh.n_bodies()) + " bodies of the mesh are tied into one continuum");
    if (inter_.has_joints()) {
        const int ext = inter_.joints()->extrinsic_count();
        log("cohesive elements: " + std::to_string(inter_.joints()->size()) +
            (ext > 0 ? " (" + std::to_string(ext) + " extrinsic: inserted where the traction reaches the strength, the "
                       "unit one continuum until then)" : std::string()));
    }
    if (crush_.active())
        log("crushing (compression softening, fdem/plasticity.hpp): " + std::to_string(crush_.kappa.size()) + " triangles; work booked under D_frac");
    for (const std::string& note : inter_.penalty_notes()) log(note);
    if (inter_.has_dry_joints())
        log("dry joint record: " + std::to_string(inter_.dry_joint_count()) + " segments, recorded in cracks.csv when an end opens by more than " +
            sci(inter_.open_threshold()) + " m or the segment slips by more than " + sci(inter_.slip_threshold()) + " m");
    if (inter_.has_contact())
        log("contact: " + std::to_string(model_.contact_capable.size()) + " contact-capable triangles, buffer " + sci(inter_.contact()->effective_buffer(model_.x.data())) + " m");
    log("threads: " + std::to_string(omp_get_max_threads()));
    if (spec_.mass_scale != 1)
        log("mass scaling: inertial mass x " + sci(spec_.mass_scale) + " (time step x " + sci(std::sqrt(spec_.mass_scale)) +
            "); gravity uses the physical mass");
    if (spec_.per_node_mass)
        log("per-node mass scaling: " + std::to_string(limits_.mass_raised_nodes) + " of " +
            std::to_string(model_.n_nodes()) +
            " nodes made heavier for the triangles' limit to bound their springs too; total inertial mass x " +
            sci(limits_.mass_raised_ratio));
    if (!spec_.dt_override && spec_.safety > 1)
        log("warning: numerics.safety = " + sci(spec_.safety) + " > 1: the time step exceeds the stability limit");
    if (!opt_.out_dir.empty()) write_summary("running", "");
    last_progress_log_ = wall_clock();
    // After restore(), the current stage continues where the checkpoint left it (no begin_stage).
    const std::size_t first = resumed_ ? static_cast<std::size_t>(clock_.stage) : 0;
    for (std::size_t s = first; s < spec_.stages.size(); ++s) {
        if (!(resumed_ && s == first)) begin_stage(static_cast<int>(s));
        while (!stage_finished()) {
            step();
            if (g_stop_signal) return interrupt(g_stop_signal);
            if (opt_.stop_after_steps > 0 && clock_.steps >= opt_.stop_after_steps)
                return interrupt(SIGUSR1,
                                 "stopped after " + std::to_string(clock_.steps) + " steps (--stop-after-steps)");
            checkpoint_if_due();
        }
        if (opt_.progress) progress_line(true);
        const StageResult& r = ending_.results.back();
        std::string how = r.ended_by;
        if (r.ended_by == "max_duration") how = "max_duration reached before its until/equilibrium criterion (warning)";
        log("stage " + std::to_string(s + 1) + " '" + r.name + "' ended by " + how + " at t = " + sci(r.time) + " s after " +
            std::to_string(r.steps) + " steps");
        for (auto& a : supports_.list) {
            const std::string line = a->stage_summary();  // (a servo's statistics of the stage)
            if (!line.empty()) log(line);
        }
        if (!opt_.out_dir.empty()) {
            record_dry_joints();
            write_history_row();
            write_snapshot();
            flush_files();
        }
    }
    wall_time_ = wall_clock() - wall_start_;
    cpu_time_ = cpu_clock() - cpu_start_;
    const double tps = static_cast<double>(clock_.steps) * model_.n_triangles() / std::max(wall_time_, 1e-9);
    if (inter_.has_dry_joints())
        log("dry joint record: " + std::to_string(inter_.dry_open_count()) + " segments opened, " + std::to_string(inter_.dry_slip_count()) +
            " slipped (of " + std::to_string(inter_.dry_joint_count()) + ")");
    if (inter_.has_joints() && inter_.joints()->extrinsic_count() > 0) {
        const auto* J = inter_.joints();
        log("extrinsic insertion: " + std::to_string(J->extrinsic_count() - J->dormant_count()) + " of " +
            std::to_string(J->extrinsic_count()) + " elements inserted; time step " + sci(clock_.dt) +
            " s at the end (" + sci(limits_.dt_initial) + " s at the start)");
    }
    log("done: " + std::to_string(clock_.steps) + " steps in " + human_time(wall_time_) + " (" + sci(tps, 3) +
        " triangle-steps/s; CPU time " + human_time(cpu_time_) + ")");
    if (const contact::ContactSystem* c = inter_.contact()) {
        const auto& st = c->stats();
        log("contact: " + std::to_string(st.detections) + " detections, " + std::to_string(st.candidate_pairs) + " candidate pairs (" +
            std::to_string(st.active_pairs) + " active) at the end, " + sci(st.pair_evaluations / std::max(wall_time_, 1e-9), 3) +
            " pair evaluations/s; " + sci(100 * st.time_detection / std::max(wall_time_, 1e-9), 3) + " % of the run in detection, " +
            sci(100 * st.time_forces / std::max(wall_time_, 1e-9), 3) + " % in contact forces");
    }
    const Energies e = energies();
    log("energy: kinetic " + sci(e.kinetic) + " J, elastic " + sci(e.elastic) + " J, joints " + sci(e.joint) + " J, contact " +
        sci(e.contact) + " J, external work " + sci(e.external) + " J, damping " + sci(e.damping) + " J, viscous " + sci(e.viscous) +
        " J, fracture " + sci(e.fracture) + " J, friction " + sci(e.friction) + " J, balance error " + sci(100 * e.balance_error(), 3) + " %");
    // A large balance error means the bookkeeping and the forces disagree. The known cause is damaged cohesive joints
    // that vibrate: their shear traction follows the slip with a strength c + |sigma| tan(phi) that changes with the
    // compression, which is not derived from a potential, so a joint slipping back while more compressed than when it
    // slipped forward returns more work than it took (measured on a mortared wall: fdem/RESULTS.md, "Energy balance").
    if (const std::string crushed = crushed_broken_note(); !crushed.empty()) log("warning: " + crushed);
    if (e.balance_error() > kBalanceWarning) {
        std::string why =
            e.fracture > 0.0
                ? "damaged cohesive joints with friction that vibrate do this: their Mohr-Coulomb strength follows the "
                  "compression without a potential (stage key local_damping, or materials.NAME.viscous_damping of the "
                  "units; cases/vermeltfoort/RESULTS.md)"
                : "contact, friction and dashpots close their books in the contact tests (within 0.11 %), so look for "
                  "a time step near its stability limit (numerics.safety) or a support doing work the loads do not "
                  "show; history.csv shows which column runs away";
        log("warning: the energy balance error " + sci(100 * e.balance_error(), 3) + " % exceeds " + sci(100 * kBalanceWarning) +
            " %: the dissipation records are not reliable; " + why +
            (spec_.energy_audit ? "" : "; numerics.energy_audit = true shows which part's books do not close"));
    }
    if (!opt_.out_dir.empty()) {
        flush_files();
        write_summary("completed", "");
    }
}

int run_case(const std::string& case_file, const std::vector<std::string>& overrides, const RunOptions& options) {
    CaseSpec spec = load_case(case_file, overrides);
    for (const std::string& w : plausibility_warnings(spec)) std::cerr << "warning: " << w << "\n";
    RunOptions opt = options;
    if (!opt.restart_dir.empty()) {
        if (!opt.out_dir.empty() && std::filesystem::weakly_canonical(opt.out_dir) != std::filesystem::weakly_canonical(opt.restart_dir))
            throw InputError("--restart " + opt.restart_dir + " continues the run in that folder: --out " + opt.out_dir +
                             " names another one (leave --out out)");
        opt.out_dir = opt.restart_dir;
    }
    if (opt.out_dir.empty()) opt.out_dir = (std::filesystem::path("runs") / spec.name).string();
    Model model = build_scene(spec);
    // A fresh run into a folder used before: the previous run's snapshots and run.pvd go first (a restart, which
    // continues a run, must keep them).
    if (opt.restart_dir.empty()) remove_previous_snapshots(opt.out_dir);
    Simulation sim(spec, std::move(model), opt);
    if (!opt.restart_dir.empty()) sim.restore(opt.restart_dir);
    sim.run();
    if (sim.interrupted_signal()) {
        if (!opt.quiet) std::cout << "run folder: " << opt.out_dir << std::endl;
        std::cerr << "run interrupted: outputs written with status \"interrupted\" in " << opt.out_dir << std::endl;
        return 128 + sim.interrupted_signal();
    }
    // The result against the reference, on stdout (summary.json has it too).
    if (spec.reference.present && !opt.quiet) {
        const ReferenceSpec& ref = spec.reference;
        const auto ext = sim.monitor_extrema();
        for (std::size_t i = 0; i < spec.monitors.size(); ++i) {
            if (spec.monitors[i].name != ref.monitor) continue;
            const double got = sim.reference_value(static_cast<int>(i));
            const double err = ref.value != 0 ? (std::abs(got) - std::abs(ref.value)) / std::abs(ref.value) : 0.0;
            // Compared by magnitude: a reaction carries the opposite sign of the load it resists, so a value whose
            // sign differs from the reference's is printed as its magnitude, |H|.
            const bool flip = got * ref.value < 0;
            const std::string name = flip ? "|" + ref.monitor + "|" : ref.monitor;
            char b[512];
            std::snprintf(b, sizeof b, "result: %s %s = %.5g %s; reference %.5g %s (%s); error %+.2f %%; run time %.2f s",
                          ref.quantity.c_str(), name.c_str(), flip ? -got : got, spec.monitors[i].unit().c_str(),
                          ref.value, spec.monitors[i].unit().c_str(), ref.source.c_str(), 100 * err, sim.wall_time());
            std::cout << b << std::endl;
            if (!sim.reference_past_peak(static_cast<int>(i)))
                std::cout << "note: " << ref.monitor << " ended within " << 100 * Simulation::kPastPeakDrop
                          << " % of its largest value (not past the peak): the peak above is the largest value reached, "
                             "a lower bound; run further (a larger until, or [[stages]] past_peak)" << std::endl;
            if (ref.tolerance > 0)
                std::cout << (std::abs(err) <= ref.tolerance ? "within" : "OUTSIDE") << " the stated tolerance of "
                          << 100 * ref.tolerance << " %" << std::endl;
        }
    }
    if (!opt.quiet) std::cout << "run folder: " << opt.out_dir << std::endl;
    return 0;
}

}  // namespace fdem
