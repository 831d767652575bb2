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

#include "fdem/body_step.hpp"
#include "fdem/case.hpp"
#include "fdem/interactions.hpp"
#include "fdem/load.hpp"
#include "fdem/support.hpp"
#include "fdem/node_update.hpp"
#include "fdem/model.hpp"
#include "fdem/output.hpp"
#include "fdem/plasticity.hpp"
#include "fdem/common/state_io.hpp"

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

// Wall time spent in each part of Simulation::step (s, cumulative; not part of the state, not checkpointed). For
// fdem_bench's per-kernel breakdown; the contact module's own split (detection, forces, scatter) is in its stats.
struct StepTimes {
    double triangles = 0;     // triangle forces (and crushing)
    double interactions = 0;  // cohesive elements and contact (detection, forces, scatter)
    double integration = 0;   // rigid groups, node loop, block sums
    double other = 0;         // loads, damage update, outputs, energy checks
};

struct StageResult {
    std::string name;
    std::string ended_by;  // "duration", "until", "equilibrium", "max_duration"
    double time = 0;       // s, at the end of the stage (run time)
    long steps = 0;
};

class Simulation {
public:
    Simulation(CaseSpec spec, Model model, RunOptions options);

    // Runs every stage. Throws RunError on instability (after writing what it has), InputError for a stage
    // that cannot end with the state reached.
    void run();

    // Finer control, for tests: set up stage s (0-based), then step.
    void begin_stage(int s);
    void step();
    bool stage_finished();  // evaluates the termination rule of the current stage
    // |R + L| / |L| at t^n: R the resultant of the reactions of the fixed and driven DOFs (a rigid group is free as a
    // whole and carries none), L that of the applied loads and gravity (N); 0 when nothing is applied.
    double load_imbalance(double* applied = nullptr, double* reactions = nullptr) const;
    double unbalanced_ratio() const { return unbalanced_ratio_; }  // of the last step (history.csv `unbalanced`)

    const Model& model() const { return model_; }
    // (a caller that may write v: the node loop's largest speed is forgotten, ContactSystem::step scans v again)
    Model& model() {
        v2max_ = -1.0;
        return model_;
    }
    // The node loop's largest |v|^2 over the nodes (m^2/s^2) that the next contact step takes; -1: v was set elsewhere
    // since (initial conditions, a restart, model()), and the contact step scans v itself.
    double speed2_of_node_loop() const { return v2max_; }
    double dt() const { return dt_; }
    // The assembled system's stable step (fdem/README.md 'Time step'): 2 / sqrt(max over nodes of k / m), k the node's
    // triangles' share (add_triangle_node_stiffness) plus its joint and contact springs' row sums, m its mass (a tied
    // group's, summed over its copies, with rep). Bounds the highest frequency of triangles and springs together, which
    // the smaller of their separate limits does not.
    struct NodalLimit {
        double dt = std::numeric_limits<double>::infinity();  // s
        int node = -1;                                         // the node that sets it
        double k_tri = 0, k_joint = 0, k_contact = 0;          // N/m, that node's shares (a body's: its nodes' sums)
        int body = -1;  // a rigid body sets it (index in bodies()), the node one of its own
    };
    const RigidBodies& bodies() const { return bodies_; }
    const NodalLimit& nodal_limit() const { return dt_nodal_; }  // at the start of the run
    const CaseSpec& spec() const { return spec_; }
    double time() const { return time_; }
    long steps() const { return steps_; }
    long broken_total() const { return broken_total_; }  // cohesive elements broken since the start
    double monitor_value(int i) const;
    Energies energies() const;  // computes the elastic energy now (contact energy: see energy_every_step)
    // Contact energy is evaluated only on reported steps unless this is on (for tests reading every step).
    void energy_every_step(bool on) { energy_every_step_ = on; }
    const std::vector<StageResult>& stage_results() const { return stage_results_; }
    double wall_time() const { return wall_time_; }
    const StepTimes& step_times() const { return step_times_; }
    // Energy audit (case key numerics.energy_audit): per part (0 triangles, 1 cohesive joints, 2 contact) the work
    // done on it by the nodes since the audit started and the growth of what it holds and dissipated, for energies e
    // (J; inserted elements' starting energy counts as work done on the joints). All zero before the first step.
    struct AuditPart {
        double worked = 0, grew = 0;
    };
    std::array<AuditPart, 3> energy_audit(const Energies& e) const;
    int interrupted_signal() const { return interrupted_signal_; }  // 0, or the signal that stopped run()
    const std::vector<double>& reactions() const { return reaction_; }
    const Interactions& interactions() const { return inter_; }
    const Crushing& crushing() const { return crush_; }  // compression softening of the triangles (plasticity.hpp)
    // Largest |value| and final value of each monitor over the history rows written.
    std::vector<std::array<double, 3>> monitor_extrema() const { return mon_ext_; }  // min, max, final
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
    double rotation_deg(const std::vector<int>& nodes, double lag) const;  // deg, positions x - lag v

    void compute_dt();
    // The triangles' and the nodal limits at local damping alpha (dt_triangles_, dt_nodal_); with set_dt also
    // dt_limit_ and the step (begin_stage, when a stage changes the local damping).
    void set_step_limits(double alpha, bool set_dt);
    double stage_alpha(int s) const;  // the local damping in force in stage s (a stage without the key keeps it)
    NodalLimit nodal_step_limit(const double* mass, const int* rep, double xi_contact, double alpha);  // (see NodalLimit)
    // Extrinsic insertion (fracture/cohesive_system.hpp): the copies joined by dormant cohesive elements move as one
    // node. build_ties groups them (union-find over the dormant elements' node pairs; groups in order of their first
    // node, members ascending); check_ties refuses a support that holds only some copies of a group.
    void build_ties();
    void scale_node_masses();  // [numerics] mass_scaling = "per_node" (integrator.cpp)
    double contact_xi_max() const;
    void check_ties() const;
    void apply_time_dependent(double t);
    void fail(const std::string& what);
    void interrupt(int sig, const std::string& why = "");
    void checkpoint_if_due();
    bool resumed_ = false;            // restore() ran: run() continues the current stage
    double next_checkpoint_ = 1e300;  // s, simulated time of the next checkpoint (checkpoint_interval)
    double last_checkpoint_wall_ = 0; // s, wall clock of the last checkpoint (checkpoint_wall_interval)
    long checkpoints_written_ = 0;
    int interrupted_signal_ = 0;
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
    double history_interval() const;   // s, of the current stage (0: every history_every_steps_ steps)
    double snapshot_interval() const;  // s, of the current stage (0: only at stage ends)
    bool history_due(double t, long step) const;
    void write_snapshot();
    // Stages of step() (fdem/integrator.cpp)
    double triangle_stage(double* tri_sigma);
    void observe(double dt);
    void dry_joint_forces(const std::vector<contact::ContactSystem::LoadedEdge>& faces, std::vector<double>& force) const;
    void dry_joint_traction(const int* n, const double* F, double& sigma, double& tau) const;
    std::string contact_snapshot(const std::vector<contact::ContactSystem::LoadedEdge>& faces) const;
    void write_summary(const std::string& status, const std::string& message);
    void log(const std::string& line);
    void progress_line(bool final);
    void progress_log_line();                  // the log's progress line, every opt_.progress_interval seconds
    std::string progress_text(double& frac);   // stage, its fraction, time, steps/s, stage and run time left

    CaseSpec spec_;
    Model model_;
    RunOptions opt_;
    Interactions inter_;
    Crushing crush_;  // per-triangle crushing state of the materials with a crushing table (empty: none)
    int control_monitor_ = -1;  // monitor giving the control displacement of the damage records
    double dt_ = 0;
    double dt_limit_ = 0;
    double dt_springs_ = 0;  // s, bound of joint and contact springs
    double dt_contact_ = 0;  // s, undamped bound of the contact springs alone (+inf without contact)
    double xi_contact_ = 0;  // fraction of critical of the contact dashpots in the current stage
    long broken_total_ = 0;
    int dt_element_ = -1;
    double time_ = 0;
    long steps_ = 0;
    int stage_ = -1;
    double stage_t0_ = 0;
    long stage_steps0_ = 0;

    // boundary conditions, per DOF
    std::vector<uint8_t> dof_kind_;  // 0 free, 1 fixed, 2 prescribed velocity
    std::vector<int> dof_owner_;     // index into supports_, -1 none
    std::vector<double> dof_vel_;    // m/s
    std::vector<double> reaction_;   // N, force the supports exert on each constrained DOF (last step)
    std::vector<std::unique_ptr<Support>> supports_;  // indexed by dof_owner_ (fdem/support.hpp)
    std::vector<std::unique_ptr<Load>> loads_;  // in the order they began (fdem/load.hpp)
    std::vector<double> f_ext_;      // N, applied loads (no gravity), 2 per node
    std::vector<int> loaded_dofs_;   // DOFs with a nonzero f_ext_ entry
    std::vector<unsigned char> node_loaded_;  // per node: 1 when a DOF of it is in loaded_dofs_ (derived, not saved)
    std::array<double, 2> gravity_{0, 0}, gravity_start_{0, 0}, gravity_target_{0, 0};
    std::array<double, 2> applied_gravity_{0, 0};  // m/s^2, after the tilt rotation
    double gravity_ramp_ = 0, tilt_rate_ = 0, tilt_deg_ = 0;
    TimeFunction gravity_fn_;    // factor on the applied gravity, of t - gravity_fn_t0_
    double gravity_fn_t0_ = 0;   // s
    double alpha_ = 0;  // local damping
    double tau_ld_ = 0;  // s, local damping filter time constant (0: sign of the absolute velocity)
    std::vector<double> v_ref_;  // m/s, per DOF: moving mean of the velocity over tau_ld_ (empty while tau_ld_ = 0)
    double beta_mass_ = 0;  // 1/s, mass-proportional damping

    // tied copies (derived from the cohesive system's dormant elements; rebuilt, not checkpointed)
    bool ties_ = false;
    std::vector<int> tie_of_;                // per node: its group, -1 when untied
    std::vector<int> tie_start_, tie_node_;  // CSR: members of group g are tie_node_[tie_start_[g] .. tie_start_[g+1])
    std::vector<double> tie_w_;              // -, per node: its mass over its group's mass
    std::vector<int> unit_start_, unit_node_;  // CSR: the node loop's units (a lone node or a group), by first node
    std::vector<int> unit_block_;              // the node loop's blocks: first unit of each, then the end
    std::vector<int> unit_slot_;               // per entry of unit_node_: its one triangle-force slot, or -1
    std::vector<double> unit_mass_, unit_inv_mass_;  // kg, 1/kg: per unit
    int node_part_threads_ = 0;              // the thread count the contact scatter was told the shares for (0: none)
    std::vector<double> tri_sigma_;          // Pa, per triangle: Cauchy stress xx, yy, xy of the step (ties only)
    std::vector<double> eff_mass_;           // kg, per node: its group's mass (tied) or its own (empty: no ties)
    std::vector<int> tie_rep_;               // per node: its group's first node, or itself (empty: no ties)
    double dt_triangles_ = 0;                // s, the triangles' stable limit (does not change with the ties)
    NodalLimit dt_nodal_;                    // the assembled bound at the start (for the log)
    std::vector<double> tri_node_k_;         // N/m, per node: the triangles' share of the nodal bound (set-up, not saved)
    double tri_node_k_alpha_ = 0;            // the local damping tri_node_k_ was folded with
    RigidBodies bodies_;                     // groups one rigid body all run long (compute_dt; not saved)
    bool bodies_off_ = false;                // compute_dt found nothing left to bound without them
    const std::vector<char>* rigid_tri() const { return bodies_.empty() ? nullptr : &bodies_.tri; }
    double xi_max_ = 0;                      // largest contact dashpot fraction of any stage
    int mass_raised_nodes_ = 0;              // per-node mass scaling: nodes made heavier, and the total inertial
    double mass_raised_ratio_ = 1;           // mass after it over the total before
    double dt_initial_ = 0;                  // s, the step at the start (the restart check compares it)
    double dt_logged_ = 0;                   // s, the last step reported in the log
    void reduce_dt_after_insertion();        // the step after nodes were untied: never larger, smaller if needed
    void share_nodes_with_contact(int n_thr);  // tells the contact which thread integrates each node
    int node_block_count() const;              // the node loop's blocks: units of tied copies, or kBlock nodes

    // per-step scratch
    std::vector<double> tf_;  // 6 per triangle
    std::vector<double> f_mod_;  // module forces (contact, joints), 2 per node
    // per block of triangles: the viscous power and the first inverted triangle (-1: none)
    std::vector<double> tri_power_;
    std::vector<int> tri_bad_;
    // per block of the node update: its books, largest |v|^2 (for the contact's detection schedule: ContactSystem::
    // step's v2max, a scan of every node less) and first non-finite node (fdem/node_update.hpp)
    std::vector<NodeBlockSums> node_sums_;
    double kinetic_n_ = 0;   // J, K^n = 1/2 m v^{n-1/2} . v^{n+1/2} of the last step
    double work_half_ = 0;   // J, dt/2 (f_ext + R)^n . v^{n+1/2}: the half step W_ext_ runs ahead of t^n
    double damp_half_ = 0;   // J, the same for local damping
    double mass_half_ = 0;   // J, the same for mass-proportional damping
    double v2max_ = -1.0;  // the largest |v|^2 over the nodes of the last update; -1 when v was set elsewhere since
    double unbalanced_ratio_ = 1;
    double eq_since_ = -1;  // s: since when the stage's equilibrium conditions hold without a break (-1: they do not)
    bool energy_every_step_ = false;  // tests that read energies after every step
    // Energy audit: per part (0 triangles, 1 cohesive joints, 2 contact) the work its forces did on the nodes, sum of
    // dt f . v_bar as the external work is booked (J), the last step's share past t^n, and what the part held and had
    // dissipated when the audit started (at the first step of this process: not checkpointed, a restart starts over).
    std::vector<double> audit_fj_, audit_f_, audit_v_;
    double audit_w_[3] = {0, 0, 0}, audit_half_[3] = {0, 0, 0}, audit_base_[3] = {0, 0, 0};
    double audit_t0_ = -1;  // s; < 0: not started

    // energies (cumulative)
    double W_ext_ = 0, D_damp_ = 0, D_visc_ = 0, D_mass_ = 0;

    // stage termination state
    double until_start_ = 0;
    int until_monitor_ = -1;
    double stage_ramp_end_ = 0;
    bool past_peak_reached(const StageSpec::PastPeak& pp);  // updates the state below; true: end the stage
    // past_peak (StageSpec::PastPeak): the monitors, the load magnitude's running mean over displacement and the
    // displacement of its last update (NaN before the first), the mean's largest value and where it was reached,
    // and the displacement at which the mean last fell below (1 - drop) of it (NaN while it is above)
    int peak_load_monitor_ = -1, peak_disp_monitor_ = -1;
    double peak_mean_ = 0, peak_u_prev_ = std::numeric_limits<double>::quiet_NaN();
    double peak_load_ = 0, peak_disp_ = 0, below_since_ = std::numeric_limits<double>::quiet_NaN();

    // outputs
    std::string history_;          // header, until append_history writes it
    std::ofstream history_out_;    // history.csv, opened by the first append_history
    long last_row_step_ = -1;      // step of the last row written
    std::vector<std::array<double, 3>> mon_ext_;
    bool mon_ext_init_ = false;
    std::vector<double> mon_first_peak_;  // largest |value| (signed) before the first cohesive break
    double next_history_ = 0, next_snapshot_ = 0;
    long history_every_steps_ = 100;
    std::vector<std::pair<double, std::string>> snapshots_;
    std::vector<StageResult> stage_results_;
    std::string log_;
    double cpu_start_ = 0, cpu_time_ = 0;  // s, process CPU time (cpu_clock), summary.json cpu_time_s; not checkpointed
    double wall_start_ = 0, wall_time_ = 0, last_flush_ = 0, last_progress_ = 0, last_progress_log_ = 0;
    double dt_report_triangles_ = 0;
    StepTimes step_times_;
};

// Run a case file end to end (the `fdem run` command). Returns the exit code.
int run_case(const std::string& case_file, const std::vector<std::string>& overrides, const RunOptions& options);

}  // namespace fdem
