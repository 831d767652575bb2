// fdem/support.hpp: the supports of a run, one type per kind, each in its own file with its reading, its set-up, its
// part of every step and its state (as fdem/load.hpp does for the loads):
//   fixed     fdem/support_fixed.cpp     the DOFs held (velocity 0)
//   velocity  fdem/support_velocity.cpp  a prescribed velocity (smooth ramp-up, time function, servo)
//   protocol  fdem/support_protocol.cpp  a displacement-versus-time history (protocol, cyclic), corner-smoothed
//   rigid     fdem/support_rigid.cpp     one velocity per group and component from the resultant of its forces
//   body      fdem/support_body.cpp      the group one rigid body (translation and rotation), both components
//   free      fdem/support_free.cpp      the DOFs released (no active support)
// A [[stages.supports]] block (SupportSpec) sets a mode per component; each kind reads the keys that select it (a
// block may give several). Each component of a block becomes one Support owning the group's DOFs in that component
// (Simulation::dof_owner_) until a later block takes them over. The node loop (fdem/node_update.cpp) reads only the
// DOF arrays the supports fill: dof_kind_ (0 free, 1 fixed, 2 prescribed velocity) and dof_vel_.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "fdem/case.hpp"
#include "fdem/common/state_io.hpp"
#include "fdem/model.hpp"

namespace fdem {

class SupportKind;
class Support;

namespace case_detail {
struct Ctx;
class Reader;
}  // namespace case_detail

// What a support sees when its stage begins: the model, the time, and the DOF arrays before it takes its DOFs.
struct SupportStart {
    const Model& model;
    double time;                    // s
    const std::uint8_t* dof_kind;   // per DOF: 0 free, 1 fixed, 2 prescribed velocity
    const double* dof_vel;          // m/s
};

// The rigid-groups stage of Simulation::step (step_rigid_groups, fdem/step.cpp) for the rigid supports: the forces on
// their nodes at t^n and the damping parameters; the supports write dof_vel of the DOFs they own and add their
// damping's work to the sums (J).
struct RigidStep {
    const Model& model;
    const double* f_mod;            // N, joint and contact forces
    const double* f_ext;            // N, loads
    const double* tri_forces;       // N, 6 per triangle
    std::array<double, 2> gravity;  // m/s^2, applied
    // local damping, its filter's time constant (s) and one-step weight, mass damping a (1/s), dtv a / 2, the step
    // and the velocity update's span (s)
    double local_damping, filter_tau, wf, mass_damping, hm, dt, dtv;
    double* dof_vel;
    const int* dof_owner;
    double dt_before;  // s, the last step's length (= dt while the step is constant; fdem/node_update.hpp)
    const std::unique_ptr<Support>* supports;  // the active supports, indexed by dof_owner (a body finds its other
    int n_supports;                            // component's support)
    double damp = 0, damp_half = 0, mass = 0, mass_half = 0;  // J: dt F_d v_bar, dt/2 F_d v^{n+1/2}; the same for -a M v
};

// One component of one block, active.
class Support {
public:
    explicit Support(const SupportKind& k) : kind(&k) {}
    virtual ~Support() = default;
    const SupportKind* kind;
    std::vector<int> nodes;  // the group's
    int comp = 0;            // 0 x, 1 y
    std::string group;
    double t0 = 0, ramp = 0;  // s: the stage start; the kind's ramp (velocity: ramp-up; protocol: corner smoothing)

    // The node loop's DOF kind of its DOFs (1 fixed, 2 prescribed velocity) and their velocity at set-up.
    virtual std::uint8_t dof_kind() const { return 2; }
    virtual double start_velocity() const { return 0; }
    // When its ramp-up ends (s): a stage's equilibrium is not checked before (velocity: t0 + ramp).
    virtual double ramp_end() const { return t0; }
    // The velocity prescribed for the update from t to t + dt (false: none, the DOFs keep theirs: fixed, rigid).
    virtual bool prescribe(double /*t*/, double /*dt*/, double& /*v*/) const { return false; }
    // Step 5 (rigid): the common velocity from the resultant; `id` is this support's index (its DOFs' owner).
    virtual void rigid_step(RigidStep& /*s*/, int /*id*/) {}
    // Whether the reactions of its DOFs are support reactions (load_imbalance; rigid: internal, false).
    virtual bool carries_reaction() const { return true; }
    // After each step (servo): the step and the unbalanced-force ratio of the step.
    virtual void after_step(double /*dt*/, double /*unbalanced_ratio*/) {}
    // The filtered local damping was switched on: the moving means start from the current velocities (rigid).
    virtual void filter_started() {}
    // A line for the log at the end of a stage ("" none); resets the stage's statistics (servo).
    virtual std::string stage_summary() { return ""; }
    // Checkpoint (fdem/checkpoint.cpp writes the kind's key first): the common fields and the kind's own.
    virtual void save(StateWriter& w) const = 0;
    virtual void load(StateReader& r, int n_nodes) = 0;

protected:
    template <class IO>
    void io_common(IO& io, int n_nodes);
};

class SupportKind {
public:
    virtual ~SupportKind() = default;
    virtual const char* key() const = 0;  // its name in the checkpoint ("fixed")
    virtual DofMode mode() const = 0;     // the SupportSpec mode it takes
    // Reads the keys of a [[stages.supports]] block that select it (and its own options) into s, setting the
    // components' modes; the block's reader (fdem/case_stages.cpp) has read group and ramp, calls every kind in the
    // registry's order and reports unknown keys after. Errors into ctx (fdem/case_reader.hpp).
    virtual void read(case_detail::Ctx& ctx, case_detail::Reader& r, SupportSpec& s) const = 0;
    // The active support of component c of block s at the stage start (nodes, comp, group, t0, ramp are set by the
    // caller after); null: none (free).
    virtual std::unique_ptr<Support> begin(const SupportSpec& s, int c, const SupportStart& st) const = 0;
    virtual std::unique_ptr<Support> restore() const = 0;
};

// The registered kinds (fdem/support_registry.cpp).
const std::vector<const SupportKind*>& support_kinds();
const SupportKind* find_support_kind(DofMode mode);
const SupportKind* find_support_kind(const std::string& key);

template <class IO>
void Support::io_common(IO& io, int n_nodes) {
    io.vec(nodes);
    if constexpr (IO::loading)
        for (int k : nodes)
            if (k < 0 || k >= n_nodes) throw StateError("support node out of range");
    io.pod(comp);
    if constexpr (IO::loading)
        if (comp != 0 && comp != 1) throw StateError("support component out of range");
    io.str(group);
    io.pod(t0), io.pod(ramp);
}

}  // namespace fdem
