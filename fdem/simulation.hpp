// fdem/simulation.hpp: stages, loads and supports, the explicit central-difference integrator, monitors,
// energy bookkeeping, failure detection and the run folder.
#pragma once

#include <array>
#include <cstdint>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "fdem/case.hpp"
#include "fdem/common/state_io.hpp"
#include "fdem/interactions.hpp"
#include "fdem/load.hpp"
#include "fdem/model.hpp"
#include "fdem/node_update.hpp"
#include "fdem/output.hpp"
#include "fdem/plasticity.hpp"
#include "fdem/sim_state.hpp"
#include "fdem/support.hpp"

namespace fdem {

struct RunOptions {
    std::string out_dir;     // run folder; empty: no files are written (tests)
    int threads = 0;         // 0: OpenMP's default
    bool quiet = false;      // no log lines on stdout
    bool progress = false;   // progress line on stderr, rewritten in place (a terminal)
    bool progress_log = false;        // progress lines in the log (run.log and stdout unless quiet): batch/cluster logs
    double progress_interval = 10.0;  // s of wall time between two progress lines in the log
    // Testing aid (hidden option --stop-after-steps): after this many steps (0: never), write a checkpoint and stop
    // as a SIGUSR1 does.
    long stop_after_steps = 0;
    // Continue the run in this folder from its checkpoint.bin (fdem run CASE --restart DIR; out_dir is DIR).
    std::string restart_dir;
};

struct Energies {
    double kinetic = 0;     // J
    double elastic = 0;     // J, triangles
    double external = 0;    // J, work of loads, gravity and supports (cumulative), plus the initial kinetic and stored energy
    double damping = 0;     // J, dissipated by local damping (cumulative)
    double viscous = 0;     // J, dissipated by viscous element damping, contact dashpots and mass damping (cumulative)
    double joint = 0;       // J, elastic energy of the intact cohesive elements
    double contact = 0;     // J, contact (penalty) energy
    double fracture = 0;    // J, dissipated by fracture (cumulative)
    double friction = 0;    // J, dissipated by contact friction (cumulative)
    double balance_error() const;  // |W - (K + E + D)| relative to the largest term
};

class Simulation {
public:
    Simulation(CaseSpec spec, Model model, RunOptions options);

    // Runs every stage. Throws RunError on instability (after writing what it has), InputError for a stage
    // that cannot end with the state reached.
    void run();

    // Finer control, for tests: set up stage s (0-based), then step: one step (advance, fdem/step.cpp) and the
    // observers after it (history row, snapshot, files, progress, energy check), as run() takes it.
    void begin_stage(int s);
    void step();
    bool stage_finished();  // evaluates the termination rule of the current stage
    // |R + L| / |L| at t^n: R the resultant of the reactions of the fixed and driven DOFs (a rigid group is free as a
    // whole and carries none), L that of the applied loads and gravity (N); 0 when nothing is applied.
    double load_imbalance(double* applied = nullptr, double* reactions = nullptr) const;
    double unbalanced_ratio() const { return books_.unbalanced_ratio; }  // of the last step (history.csv `unbalanced`)

    const Model& model() const { return model_; }
    // (a caller that may write v: the node loop's largest speed is forgotten, ContactSystem::step scans v again)
    Model& model() {
        scratch_.v2max = -1.0;
        return model_;
    }
    // The node loop's largest |v|^2 over the nodes (m^2/s^2) that the next contact step takes; -1: v was set elsewhere
    // since (initial conditions, a restart, model()), and the contact step scans v itself.
    double speed2_of_node_loop() const { return scratch_.v2max; }
    double dt() const { return clock_.dt; }
    using NodalLimit = fdem::NodalLimit;                             // (fdem/sim_state.hpp)
    const NodalLimit& nodal_limit() const { return limits_.nodal; }  // at the start of the run
    const RigidBodies& bodies() const { return limits_.bodies; }
    const CaseSpec& spec() const { return spec_; }
    double time() const { return clock_.time; }
    long steps() const { return clock_.steps; }
    long broken_total() const { return clock_.broken_total; }  // cohesive elements broken since the start
    double monitor_value(int i) const;
    Energies energies() const;  // computes the elastic energy now (contact energy: see energy_every_step)
    // Contact energy is evaluated only on reported steps unless this is on (for tests reading every step).
    void energy_every_step(bool on) { energy_every_step_ = on; }
    const std::vector<StageResult>& stage_results() const { return ending_.results; }
    double wall_time() const { return wall_time_; }
    const StepProfile& profile() const { return profile_; }  // wall time per stage of step()
    // Energy audit (case key numerics.energy_audit): per part (0 triangles, 1 cohesive joints, 2 contact) the work
    // done on it by the nodes since the audit started and the growth of what it holds and dissipated, for energies e
    // (J; inserted elements' starting energy counts as work done on the joints). All zero before the first step.
    struct AuditPart {
        double worked = 0, grew = 0;
    };
    std::array<AuditPart, 3> energy_audit(const Energies& e) const;
    int interrupted_signal() const { return interrupted_signal_; }  // 0, or the signal that stopped run()
    const std::vector<double>& reactions() const { return supports_.reaction; }
    const Interactions& interactions() const { return inter_; }
    const Crushing& crushing() const { return crush_; }  // compression softening of the triangles (plasticity.hpp)
    // Largest |value| and final value of each monitor over the history rows written.
    std::vector<std::array<double, 3>> monitor_extrema() const { return out_.mon_ext; }  // min, max, final
    double reference_value(int monitor) const;  // the quantity [reference] names, of monitor `monitor`
    // For a "peak" reference: false when the run ended with the monitor still within kPastPeakDrop of its largest
    // magnitude and its last stage did not end by past_peak (the largest value is then a lower bound of the peak);
    // true otherwise
    bool reference_past_peak(int monitor) const;
    static constexpr double kPastPeakDrop = 0.05;

    // Checkpoint and restart (fdem/checkpoint.cpp). save_state/load_state write and read everything that carries from
    // one step to the next (model state, stage, supports and loads, damping filters, energy books, monitors, output
    // counters, and the contact and cohesive modules); write_checkpoint puts it in <run folder>/checkpoint.bin
    // atomically; restore reads it back (refusing a checkpoint of another build or case with an InputError), truncates
    // history.csv to the checkpoint's row, and makes run() continue from there.
    void save_state(StateWriter& w) const;
    void load_state(StateReader& r);
    // The one list of the saved fields behind both (fdem/checkpoint.cpp; IO = StateWriter or StateReader).
    template <class IO>
    void state_io(IO& io);
    void write_checkpoint();
    void restore(const std::string& run_dir);
    std::string checkpoint_path() const;

private:
    void supports_after_step();  // after each step: Support::after_step (the servos' velocity factors from the unbalanced-force ratio)
    void apply_initial_conditions();
    // begin_stage's parts, in its order (fdem/stages.cpp)
    void stage_damping_and_gravity(const StageSpec& st);
    void stage_supports(const StageSpec& st);
    void stage_loads(const StageSpec& st);
    void stage_termination(int s, const StageSpec& st);
    bool past_peak_reached(const StageSpec::PastPeak& pp);  // updates ending_'s past_peak state; true: end the stage
    double rotation_deg(const std::vector<int>& nodes, double lag) const;  // deg, positions x - lag v

    void compute_dt();
    // The triangles' and the nodal limits at local damping alpha (limits_); with set_dt also the stable limit and
    // the step (clock_; begin_stage, when a stage changes the local damping).
    void set_step_limits(double alpha, bool set_dt);
    double stage_alpha(int s) const;  // the local damping in force in stage s (a stage without the key keeps it)
    // (see NodalLimit) every_face: the contact springs of every face that may touch, not only those near a
    // candidate pair (Interactions::add_node_stiffness)
    NodalLimit nodal_step_limit(const double* mass, const int* rep, double xi_contact, double alpha,
                                bool every_face = false);
    // Extrinsic insertion (fracture/cohesive_system.hpp): the copies joined by dormant cohesive elements move as one
    // node. build_ties groups them (units_: union-find over the dormant elements' node pairs; groups in order of
    // their first node, members ascending); check_ties refuses a support that holds only some copies of a group.
    void build_ties();
    void scale_node_masses();  // [numerics] mass_scaling = "per_node" (integrator.cpp)
    double contact_xi_max() const;
    void check_ties() const;
    // The step after nodes were untied, joints broke or the contact candidates grew (cause, for the log): never
    // larger, smaller if the nodal bound of the current springs needs it.
    void reduce_dt_after_insertion(const char* cause);
    void share_nodes_with_contact(int n_thr);  // tells the contact which thread integrates each node
    int node_block_count() const;              // the node loop's blocks: units of tied copies, or kBlock nodes
    void apply_time_dependent(double t);
    void fail(const std::string& what);
    void interrupt(int sig, const std::string& why = "");
    void checkpoint_if_due();
    void check_energy(const Energies& e);
    std::string crushed_broken_note() const;  // "" or why contact may push crushed, broken joints apart
    // Energy audit (CaseSpec::energy_audit): audit_step's sums, and their report for energies e.
    void audit_step(int phase, double dt);
    std::string audit_text(const Energies& e) const;
    bool joints_made_it(const Energies& e) const;
    void audit_parts(const Energies& e, double* held) const;
    void write_history_row();
    void append_history(const std::string& row);  // append to history.csv and flush (header on first call)
    std::string history_row(const Energies& e);
    void open_history();  // create history.csv with its header (once)
    double control_displacement() const;  // m (or the control monitor's unit): the curve's x monitor, 0 without one
    void record_dry_joints();
    void flush_files();
    double history_interval() const;   // s, of the current stage (0: every Outputs::history_every_steps steps)
    double snapshot_interval() const;  // s, of the current stage (0: only at stage ends)
    bool history_due(double t, long step) const;
    void write_snapshot();
    // The step (fdem/step.cpp): advance() runs the stages in this order and returns the step's dt; observe(dt) runs
    // the observers after it.
    double advance();
    void step_triangles(StepContext& c);
    void step_insertion(StepContext& c);
    void step_loads(StepContext& c);
    void step_interactions(StepContext& c);
    void step_rigid_groups(StepContext& c);
    void step_nodes(StepContext& c);
    void step_books(StepContext& c);
    void step_damage(StepContext& c);
    void observe(double dt);
    void write_notes();  // the stages' log lines (StepScratch::notes)
    void dry_joint_forces(const std::vector<contact::ContactSystem::LoadedEdge>& faces, std::vector<double>& force) const;
    void dry_joint_traction(const int* n, const double* F, double& sigma, double& tau) const;
    std::string contact_snapshot(const std::vector<contact::ContactSystem::LoadedEdge>& faces) const;
    void write_summary(const std::string& status, const std::string& message);
    void log(const std::string& line);
    void progress_line(bool final);
    void progress_log_line();                  // the log's progress line, every opt_.progress_interval seconds
    std::string progress_text(double& frac);   // stage, its fraction, time, steps/s, stage and run time left

    // The case and the model (the model's positions, velocities and masses are state: fdem/checkpoint.cpp).
    CaseSpec spec_;
    Model model_;
    RunOptions opt_;
    Interactions inter_;        // cohesive elements and contact, with their own state
    Crushing crush_;            // per-triangle crushing state of the materials with a crushing table (empty: none)
    int control_monitor_ = -1;  // monitor giving the control displacement of the damage records

    // The state (fdem/sim_state.hpp: each with its io, fdem/sim_state.cpp).
    StepClock clock_;
    Supports supports_;
    Loads loads_;
    Gravity gravity_;
    Damping damping_;
    EnergyBooks books_;
    StageEnding ending_;
    Outputs out_;

    // The caches (fdem/sim_state.hpp: rebuilt, never saved).
    StepLimits limits_;
    const std::vector<char>* rigid_tri() const { return limits_.bodies.empty() ? nullptr : &limits_.bodies.tri; }
    TiedUnits units_;
    StepScratch scratch_;
    EnergyAudit audit_;

    // The run's own bookkeeping in this process (not saved).
    bool resumed_ = false;  // restore() ran: run() continues the current stage
    int interrupted_signal_ = 0;
    bool energy_every_step_ = false;  // tests that read energies after every step
    std::string history_;             // header, until append_history writes it
    std::ofstream history_out_;       // history.csv, opened by the first append_history
    std::string log_;
    double last_checkpoint_wall_ = 0;      // s, wall clock of the last checkpoint (checkpoint_wall_interval)
    double cpu_start_ = 0, cpu_time_ = 0;  // s, process CPU time (cpu_clock), summary.json cpu_time_s
    double wall_start_ = 0, wall_time_ = 0, last_flush_ = 0, last_progress_ = 0, last_progress_log_ = 0;
    StepProfile profile_;
};

// Run a case file end to end (the `fdem run` command). Returns the exit code.
int run_case(const std::string& case_file, const std::vector<std::string>& overrides, const RunOptions& options);

}  // namespace fdem
