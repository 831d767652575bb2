// fdem/sim_state.hpp: what a Simulation holds, split by what a checkpoint does with it (fdem/checkpoint.cpp).
//
// The state: the structs of the first part, each with one io (IO = StateWriter or StateReader, fdem/common/
// state_io.hpp) that lists its fields once, in the checkpoint's order, for save and load alike. With the Model's
// positions, velocities and masses, the crushing state and the contact and cohesive modules (which save their own)
// it is everything that carries from one step to the next. Next to each io (fdem/sim_state.cpp) a static_assert
// holds its struct's field count (fdem/common/field_count.hpp): a field added to a state struct fails the build
// until its author adds it to the io and raises the count (or moves it to a cache).
//
// The caches: the structs of the second part, rebuilt from the case and the state (at set-up, by build_ties, by each
// step) and never saved. A field of Simulation itself outside these is the case, the run's options or the
// observers' own bookkeeping of this process (log, open files, wall clocks), none of it saved either.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "fdem/body_step.hpp"
#include "fdem/case.hpp"
#include "fdem/load.hpp"
#include "fdem/node_update.hpp"
#include "fdem/support.hpp"

namespace fdem {

struct StageResult {
    std::string name;
    std::string ended_by;  // "duration", "until", "equilibrium", "max_duration", "past_peak"
    double time = 0;       // s, at the end of the stage (run time)
    long steps = 0;
};

// The sizes a loaded state must agree with (the case and mesh the checkpoint is read into).
struct StateShape {
    int nodes = 0;
    int monitors = 0;
    int stages = 0;
};

// ---- The state (saved) ----

// The clock: the step and its limits (smaller than at the start after insertions), time, step count, the current
// stage and where it began, the cohesive elements broken since the start, and since when the stage's equilibrium
// conditions hold without a break (s; -1: they do not).
struct StepClock {
    double dt = 0, dt_limit = 0;  // s, the step and the stable limit it is a fraction of
    double dt_springs = 0;        // s, bound of joint and contact springs alone, every face in contact (the log)
    double dt_logged = 0;         // s, the last step reported in the log
    double dt_last = 0;           // s, the length of the last step taken (0 before the first)
    double time = 0;              // s
    long steps = 0;
    int stage = -1;
    double stage_t0 = 0;  // s
    long stage_steps0 = 0;
    long broken_total = 0;
    double eq_since = -1;  // s
    template <class IO>
    void io(IO& io, const StateShape& shape);
};

// Supports (fdem/support.hpp), per DOF and as the list of the active ones.
struct Supports {
    std::vector<uint8_t> dof_kind;     // 0 free, 1 fixed, 2 prescribed velocity
    std::vector<int> dof_owner;        // index into list, -1 none
    std::vector<double> dof_velocity;  // m/s
    std::vector<double> reaction;      // N, force the supports exert on each constrained DOF (last step)
    std::vector<std::unique_ptr<Support>> list;
    template <class IO>
    void io(IO& io, const StateShape& shape);
};

// Loads (fdem/load.hpp) in the order they began, and their nodal forces of the last step.
struct Loads {
    std::vector<std::unique_ptr<Load>> list;
    std::vector<double> f_ext;     // N, applied loads (no gravity), 2 per node
    std::vector<int> loaded_dofs;  // DOFs with a nonzero f_ext entry
    template <class IO>
    void io(IO& io, const StateShape& shape);
};

// Gravity: the stage's vector ramped from start to target, turned by the tilt and scaled by the time function
// (applied, what the nodes feel).
struct Gravity {
    std::array<double, 2> current{0, 0}, start{0, 0}, target{0, 0};  // m/s^2
    std::array<double, 2> applied{0, 0};                             // m/s^2, after the tilt and the factor
    double ramp = 0;                                                 // s
    double tilt_rate = 0, tilt_deg = 0;                              // deg/s, deg
    TimeFunction factor;                                             // of t - factor_t0
    double factor_t0 = 0;                                            // s
    template <class IO>
    void io(IO& io, const StateShape& shape);
};

// The damping in force (set by the stages; a stage without a key keeps the previous value).
struct Damping {
    double local = 0;           // local damping alpha ([C79])
    double filter_tau = 0;      // s, the local damping filter's time constant (0: sign of the velocity itself)
    std::vector<double> v_ref;  // m/s, per DOF: moving mean of the velocity over filter_tau (empty while it is 0)
    double mass = 0;            // 1/s, mass-proportional (Rayleigh alpha) damping a
    double contact = 0;         // fraction of critical of the contact dashpots
    template <class IO>
    void io(IO& io, const StateShape& shape);
};

// The energy books (J): the cumulative sums and the last step's halves past t^n (fdem/README.md 'Energy').
struct EnergyBooks {
    double kinetic_n = 0;         // K^n = 1/2 m v^{n-1/2} . v^{n+1/2} of the last step
    double work_half = 0;         // dt/2 (f_ext + R)^n . v^{n+1/2}: the half step W_ext runs ahead of t^n
    double damp_half = 0;         // the same for local damping
    double mass_half = 0;         // the same for mass-proportional damping
    double unbalanced_ratio = 1;  // - , of the last step (history.csv `unbalanced`)
    double W_ext = 0, D_damp = 0, D_visc = 0, D_mass = 0;
    template <class IO>
    void io(IO& io, const StateShape& shape);
};

// How the current stage ends (until, past_peak, ramps) and how the finished ones ended. past_peak
// (StageSpec::PastPeak): the monitors, the load magnitude's running mean over displacement and the displacement of
// its last update (NaN before the first), the mean's largest value and where it was reached, and the displacement
// at which the mean last fell below (1 - drop) of it (NaN while it is above).
struct StageEnding {
    double until_start = 0;
    int until_monitor = -1;
    double ramp_end = 0;  // s, when the stage's last ramp ends (equilibrium is not checked before)
    int peak_load_monitor = -1, peak_disp_monitor = -1;
    double peak_mean = 0, peak_u_prev = std::numeric_limits<double>::quiet_NaN();
    double peak_load = 0, peak_disp = 0, below_since = std::numeric_limits<double>::quiet_NaN();
    std::vector<StageResult> results;
    template <class IO>
    void io(IO& io, const StateShape& shape);
};

// The outputs' schedule and what they carry over: the last history row's step, the monitors' extrema (min, max,
// final) and first peaks, the next history row, snapshot and checkpoint, and the snapshots written (time, file).
struct Outputs {
    long last_row_step = -1;
    std::vector<std::array<double, 3>> mon_ext;
    bool mon_ext_init = false;
    std::vector<double> mon_first_peak;  // largest |value| (signed) before the first cohesive break
    double next_history = 0, next_snapshot = 0;
    long history_every_steps = 100;
    double next_checkpoint = 1e300;  // s, simulated time of the next checkpoint (checkpoint_interval)
    std::vector<std::pair<double, std::string>> snapshots;
    template <class IO>
    void io(IO& io, const StateShape& shape);
};

// ---- The caches (rebuilt, never saved) ----

// The assembled system's stable step (fdem/README.md 'Time step'): 2 / sqrt(max over nodes of k / m), k the node's
// triangles' share (add_triangle_node_stiffness) plus its joint and contact springs' row sums, m its mass (a tied
// group's, summed over its copies, with rep). Bounds the highest frequency of triangles and springs together, which
// the smaller of their separate limits does not.
struct NodalLimit {
    double dt = std::numeric_limits<double>::infinity();  // s
    int node = -1;                                        // the node that sets it
    double k_tri = 0, k_joint = 0, k_contact = 0;         // N/m, that node's shares (a body's: its nodes' sums)
    int body = -1;  // a rigid body sets it (index in StepLimits::bodies), the node one of its own
};

// The step's limits and what set them (set-up and stage changes; a restart computes them again).
struct StepLimits {
    double dt_initial = 0;           // s, the step at the start (the restart check compares it)
    double dt_triangles = 0;         // s, the triangles' stable limit (does not change with the ties)
    int dt_element = -1;             // the triangle that sets the limit, -1: a node (nodal)
    NodalLimit nodal;                // the assembled bound at the start (for the log)
    double dt_contact = 0;           // s, undamped bound of the contact springs alone (+inf without contact)
    double xi_max = 0;               // largest contact dashpot fraction of any stage
    std::vector<double> tri_node_k;  // N/m, per node: the triangles' share of the nodal bound
    double tri_node_k_alpha = 0;     // the local damping tri_node_k was folded with
    int mass_raised_nodes = 0;       // per-node mass scaling: nodes made heavier, and the total inertial
    double mass_raised_ratio = 1;    // mass after it over the total before
    RigidBodies bodies;              // groups one rigid body all run long (fdem/body_step.hpp)
    bool bodies_off = false;         // compute_dt found nothing left to bound without them
};

// Tied copies of extrinsic insertion (derived from the cohesive system's dormant elements by build_ties) and the
// node loop's units and blocks over them.
struct TiedUnits {
    bool active = false;                   // some copies are tied
    std::vector<int> tie_of;               // per node: its group, -1 when untied
    std::vector<int> tie_start, tie_node;  // CSR: members of group g are tie_node[tie_start[g] .. tie_start[g+1])
    std::vector<double> tie_w;             // -, per node: its mass over its group's mass
    std::vector<double> eff_mass;          // kg, per node: its group's mass (tied) or its own (empty: no ties)
    std::vector<int> rep;                  // per node: its group's first node, or itself (empty: no ties)
    std::vector<int> start, node;          // CSR: the node loop's units (a lone node or a group), by first node
    std::vector<int> block;                // the node loop's blocks: first unit of each, then the end
    std::vector<int> slot;                 // per entry of node: its one triangle-force slot, or -1
    std::vector<double> mass, inv_mass;    // kg, 1/kg: per unit
    int shared_threads = 0;                // the thread count the contact scatter was told the shares for (0: none)
};

// Per-step scratch: written by a step and read within it (or by the observers after it).
struct StepScratch {
    std::vector<double> tri_forces;  // N, 6 per triangle
    std::vector<double> f_mod;  // N, joint and contact forces, 2 per node (the node update reads and clears them: zero
                                // between steps, where a checkpoint is taken)
    std::vector<double> tri_sigma;   // Pa, per triangle: Cauchy stress xx, yy, xy of the step (ties only)
    std::vector<double> tri_power;   // W, per block of triangles: the viscous power
    std::vector<int> tri_bad;        // per block of triangles: the first inverted triangle (-1: none)
    std::vector<NodeBlockSums> node_sums;    // per block of the node update (fdem/node_update.hpp)
    std::vector<unsigned char> node_loaded;  // per node: 1 when a DOF of it has a load (from Loads::loaded_dofs)
    // The node loop's largest |v|^2 over the nodes, for the contact's detection schedule (ContactSystem::step's
    // v2max, a scan of every node less); -1 when v was set elsewhere since (initial conditions, a restart, model()).
    double v2max = -1.0;
    std::vector<std::string> notes;  // log lines of the step, written by the observers after it
};

// The energy audit (CaseSpec::energy_audit): per part (0 triangles, 1 cohesive joints, 2 contact) the work its
// forces did on the nodes, sum of dt f . v_bar as the external work is booked (J), the last step's share past t^n,
// and what the part held and had dissipated when the audit started (at the first step of this process: a restart
// starts over).
struct EnergyAudit {
    std::vector<double> fj, f, v;  // N, N, m/s per DOF: the joints' forces, the modules' forces, v^{n-1/2}
    std::array<double, 3> w{0, 0, 0}, half{0, 0, 0}, base{0, 0, 0};  // J
    double t0 = -1;                                                  // s; < 0: not started
};

// ---- The step ----

// Wall time of each stage of Simulation::step (s, cumulative over this process; not saved): fdem_bench's per-kernel
// breakdown. The contact module's own split (detection, forces, scatter) is in its stats.
struct StepProfile {
    double triangles = 0;     // triangle forces and crushing (with the step's set-up)
    double insertion = 0;     // extrinsic insertion: the check, untying, the step after it
    double loads = 0;         // loads, gravity and prescribed velocities at t^n
    double interactions = 0;  // cohesive elements and contact (detection, forces, scatter)
    double rigid_groups = 0;  // rigid groups' velocities
    double nodes = 0;         // the node update and the contact dashpots' second half
    double books = 0;         // energy books, servos, the clock
    double damage = 0;        // the joints' damage, the step after breaks
    double observers = 0;     // history rows, snapshots, files, progress, energy checks
    double integration() const { return rigid_groups + nodes + books; }
    double other() const { return insertion + loads + damage + observers; }
};

// What the stages of one step hand on to the next ones (fdem/step.cpp).
struct StepContext {
    double dt_before = 0;         // s, the length of the previous step (this one's at the first)
    double dt = 0;                // s, this step (insertion may have made it smaller)
    double dtv = 0;               // s, the velocity update's span (dt_before + dt) / 2
    double* tri_sigma = nullptr;  // the triangles' stresses for the insertion check (ties only), else null
    double visc_power = 0;        // W, the triangles' viscous power
    double wf = 0;                // the local damping filter's one-step weight
    double hm = 0;                // dtv a / 2 of the mass damping a
    double rigid_damp = 0, rigid_damp_half = 0, rigid_mass = 0, rigid_mass_half = 0;  // J (RigidStep)
};

// A step that cannot go on (an inverted triangle, a non-finite velocity): thrown by a stage, turned into the run's
// failure (Simulation::fail, which writes the outputs) by Simulation::step.
struct StepFailure : std::runtime_error {
    using std::runtime_error::runtime_error;
};

}  // namespace fdem
