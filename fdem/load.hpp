// fdem/load.hpp: the loads of a stage ([[stages.loads]] blocks), one type per kind. Each kind keeps in its own file
// what the engine does with it, behind fixed hooks (as LAMMPS keeps each fix in one class):
//   reading       LoadKind::read       the block's keys into a LoadSpec (errors named by key, file and line)
//   set-up        LoadKind::begin      at the start of the stage that sets the block: an active Load
//   application   Load::add_forces     at every step, its forces into f_ext (t^n, positions x^n)
//   state         Load::save / load    what carries from step to step, in the checkpoint's byte stream
// and registers itself under the TOML key that selects it in fdem/load_registry.cpp. The kinds: fdem/load_force.cpp
// (force), fdem/load_pressure.cpp (pressure), fdem/load_spring.cpp (spring), fdem/load_foundation.cpp (foundation).
//
// Adding a kind: write fdem/load_NAME.cpp with a LoadKind (its key, its reading, its begin) and a Load (its forces
// and state), add its line to fdem/load_registry.cpp, its rows to cases/REFERENCE.md, and a test.
//
// What the engine does for every kind (fdem/stages.cpp, fdem/step.cpp, fdem/checkpoint.cpp): a block on a
// group replaces that group's previous load of the same kind (begin gets it, to ramp from its value); the forces of
// all loads are summed into f_ext in the order the loads began, and f_ext's work is booked as external work
// (W_ext, the node loop: dt f . v_bar); a "load" monitor on a group reads f_ext.
#pragma once

#include <algorithm>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "fdem/case.hpp"
#include "fdem/common/state_io.hpp"
#include "fdem/model.hpp"

namespace fdem {

namespace case_detail {
struct Ctx;
class Reader;
}  // namespace case_detail

class LoadKind;

// What a load sees when its stage begins.
struct LoadStart {
    const Model& model;       // positions x at the stage start, the reference X, groups, triangles, thickness
    const std::string& file;  // the case file (for errors: FILE:LINE)
    double time;              // s, the stage's start
    double dt;                // s, the run's time step (the stage's local damping set)
};

// What a load sees at each step: t^n, the positions x^n (model.x), and where its forces go.
struct LoadStep {
    const Model& model;
    double t;                  // s
    double* f_ext;             // N, 2 per node (whole thickness): add the load's forces
    std::vector<int>& loaded;  // every DOF of f_ext written: push it (the node loop reads f_ext on these nodes only)
};

// An active load: one block in force since the start of the stage that set it.
class Load {
public:
    explicit Load(const LoadKind& k) : kind(&k) {}
    virtual ~Load() = default;
    const LoadKind* kind;
    std::string group;
    // Adds the load's forces at t^n into s.f_ext (pushing each DOF written into s.loaded).
    virtual void add_forces(const LoadStep& s) = 0;
    // The value a later block of the same kind on the same group ramps from, at time t (force N, pressure Pa);
    // kinds without a ramped value: zero.
    virtual std::array<double, 2> value_at(double /*t*/) const { return {0, 0}; }
    // A load that holds the body as a support does (an elastic foundation): its resultant, as of the last
    // add_forces (N), counts with the supports' reactions in the equilibrium check (Simulation::load_imbalance),
    // not with the applied loads. Others: false.
    virtual bool reacts(std::array<double, 2>& /*resultant*/) const { return false; }
    // Checkpoint (fdem/checkpoint.cpp writes the kind's key and the group before): the fields that carry over.
    virtual void save(StateWriter& w) const = 0;
    virtual void load(StateReader& r, int n_nodes) = 0;
};

// A kind of load: registered once (fdem/load_registry.cpp), stateless.
class LoadKind {
public:
    virtual ~LoadKind() = default;
    // The TOML key that selects the kind in a [[stages.loads]] block ("force"); a block gives exactly one.
    virtual const char* key() const = 0;
    // How to give it, for the "missing; expected ..." message ("force = [Fx, Fy] (N)").
    virtual const char* expect() const = 0;
    // Reads the block's keys the kind takes (its own key and the common ones it uses: ramp, function) into l; the
    // caller has read group and set l.kind, and reports unknown keys after. Errors into ctx (case_reader.hpp).
    virtual void read(case_detail::Ctx& ctx, case_detail::Reader& r, LoadSpec& l) const = 0;
    // The group must be a curve (a 1D physical group: the kind needs its edges); check_against_mesh checks it.
    virtual bool needs_edges() const { return false; }
    // The active load of block l at the stage start; previous: the load of the same kind on the same group that
    // it replaces (null: none).
    virtual std::unique_ptr<Load> begin(const LoadSpec& l, const Load* previous, const LoadStart& s) const = 0;
    // An empty load of this kind, for a restart to fill (Load::load).
    virtual std::unique_ptr<Load> restore() const = 0;
};

// The registered kinds, in the order the reader tries them and lists them in its messages (fdem/load_registry.cpp).
const std::vector<const LoadKind*>& load_kinds();
const LoadKind* find_load_kind(const std::string& key);  // null: no kind of that key

// A value ramped linearly from `start` to `target` over `ramp` from t0, times a time function of t - t0 (the force
// and pressure kinds).
struct RampedValue {
    std::array<double, 2> start{0, 0}, target{0, 0};
    double ramp = 0, t0 = 0;
    TimeFunction fn;
    double weight(double t) const { return ramp > 0 ? std::min(1.0, (t - t0) / ramp) : 1.0; }
    // start + w (target - start), without the time function: what a replacing block ramps from.
    std::array<double, 2> ramped(double t) const {
        const double w = weight(t);
        return {start[0] + w * (target[0] - start[0]), start[1] + w * (target[1] - start[1])};
    }
    // The applied value at t: the time function's factor times the ramped value.
    std::array<double, 2> operator()(double t) const {
        const double w = weight(t);
        const double fac = fn.present() ? fn(t - t0) : 1.0;
        return {fac * (start[0] + w * (target[0] - start[0])), fac * (start[1] + w * (target[1] - start[1]))};
    }
    template <class IO>
    void io(IO& io);
};

template <class IO>
void io_time_function(IO& io, TimeFunction& f) {
    io.str(f.type);
    io.pod(f.amplitude), io.pod(f.omega), io.pod(f.phase), io.pod(f.offset);
    io.vec(f.t), io.vec(f.f);
}

template <class IO>
void RampedValue::io(IO& io) {
    io.pod(start), io.pod(target), io.pod(ramp), io.pod(t0);
    io_time_function(io, fn);
}

// The edges of block l's group, each oriented as it runs counter-clockwise around its triangle (the body on its
// left, the outward normal on its right); InputError (FILE:LINE) for an edge on no triangle. fdem/load_pressure.cpp.
std::vector<std::array<int, 2>> oriented_edges(const Model& model, const LoadSpec& l, const std::string& file);

// A node index read from a checkpoint: in [0, n) (StateError otherwise).
void check_load_node(int k, int n, const char* what);

}  // namespace fdem
