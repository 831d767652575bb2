// fdem/sim_state.cpp: the io of each state struct of fdem/sim_state.hpp: its fields once, in the checkpoint's
// order, for StateWriter (save) and StateReader (load) alike; what only a load does (check lengths and indices,
// resize) under IO::loading. The sections around them, the model, the crushing state, the modules and what a load
// derives from the state are in Simulation::state_io (fdem/checkpoint.cpp).
//
// Next to each io, its struct's field count: a field added to a state struct fails the build here until it is added
// to the io and the count raised, or it moves to a cache (not saved).
#include "fdem/sim_state.hpp"

#include <string>

#include "fdem/common/field_count.hpp"
#include "fdem/common/state_io.hpp"

namespace fdem {

namespace {

void check_index(int i, int n, const char* what) {
    if (i < -1 || i >= n) throw StateError(std::string(what) + " out of range");
}

// A list of polymorphic items (supports, loads): the count, then per item its kind's key and what body(item) does
// (the item's own io). A load restores each item from its kind (find(key), kind->restore()) before body reads it.
template <class IO, class Ptr, class Find, class Body>
void kind_list_io(IO& io, std::vector<Ptr>& list, const char* what, Find find, Body body) {
    std::uint64_t n = list.size();
    io.pod(n);
    if constexpr (IO::loading) {
        if (n > io.remaining()) throw StateError(std::string(what) + " count out of range");
        list.clear();
        list.resize(static_cast<std::size_t>(n));
    }
    for (auto& a : list) {
        std::string key;
        if constexpr (IO::loading) {
            io.str(key);
            const auto* kind = find(key);
            if (!kind) throw StateError("a " + std::string(what) + " of an unknown kind '" + key.substr(0, 64) + "'");
            a = kind->restore();
        } else {
            key = a->kind->key();
            io.str(key);
        }
        body(*a);
    }
}

}  // namespace

static_assert(field_count<StepClock>() == 12, "StepClock changed: update StepClock::io and this count");
template <class IO>
void StepClock::io(IO& io, const StateShape& shape) {
    io.pod(dt), io.pod(dt_limit), io.pod(dt_springs), io.pod(dt_logged), io.pod(dt_last);
    io.pod(time), io.pod(steps), io.pod(stage), io.pod(stage_t0), io.pod(stage_steps0), io.pod(broken_total),
        io.pod(eq_since);
    if constexpr (IO::loading)
        if (stage < 0 || stage >= shape.stages) throw StateError("stage index out of range");
}

// Per support: its kind's key, then what the kind saves (fdem/support.hpp).
static_assert(field_count<Supports>() == 5, "Supports changed: update Supports::io and this count");
template <class IO>
void Supports::io(IO& io, const StateShape& shape) {
    const std::size_t nd = 2 * static_cast<std::size_t>(shape.nodes);
    io.vec_sized(dof_kind, nd, "DOF kinds");
    io.vec_sized(dof_owner, nd, "DOF owners");
    io.vec_sized(dof_velocity, nd, "prescribed velocities");
    io.vec_sized(reaction, nd, "reactions");
    kind_list_io(io, list, "support", [](const std::string& k) { return find_support_kind(k); }, [&](Support& a) {
        if constexpr (IO::loading) a.load(io, shape.nodes);
        else a.save(io);
    });
    if constexpr (IO::loading)
        for (int o : dof_owner) check_index(o, static_cast<int>(list.size()), "DOF owner");
}

// Per load: its kind's key, its group, then what the kind saves (fdem/load.hpp).
static_assert(field_count<Loads>() == 3, "Loads changed: update Loads::io and this count");
template <class IO>
void Loads::io(IO& io, const StateShape& shape) {
    const std::size_t nd = 2 * static_cast<std::size_t>(shape.nodes);
    kind_list_io(io, list, "load", find_load_kind, [&](Load& l) {
        io.str(l.group);
        if constexpr (IO::loading) l.load(io, shape.nodes);
        else l.save(io);
    });
    io.vec_sized(f_ext, nd, "applied loads");
    io.vec(loaded_dofs);
    if constexpr (IO::loading)
        for (int d : loaded_dofs) check_index(d, static_cast<int>(nd), "loaded DOF");
}

static_assert(field_count<Gravity>() == 9, "Gravity changed: update Gravity::io and this count");
template <class IO>
void Gravity::io(IO& io, const StateShape&) {
    io.pod(current), io.pod(start), io.pod(target), io.pod(applied);
    io.pod(ramp), io.pod(tilt_rate), io.pod(tilt_deg);
    io_time_function(io, factor);
    io.pod(factor_t0);
}

static_assert(field_count<Damping>() == 5, "Damping changed: update Damping::io and this count");
template <class IO>
void Damping::io(IO& io, const StateShape& shape) {
    const std::size_t nd = 2 * static_cast<std::size_t>(shape.nodes);
    io.pod(local), io.pod(filter_tau), io.vec(v_ref), io.pod(mass), io.pod(contact);
    if constexpr (IO::loading) {
        if (!v_ref.empty() && v_ref.size() != nd) throw StateError("velocity filter of another mesh");
        if (filter_tau > 0 && v_ref.size() != nd) throw StateError("velocity filter missing");
    }
}

static_assert(field_count<EnergyBooks>() == 9, "EnergyBooks changed: update EnergyBooks::io and this count");
template <class IO>
void EnergyBooks::io(IO& io, const StateShape&) {
    io.pod(kinetic_n), io.pod(work_half), io.pod(damp_half), io.pod(mass_half), io.pod(unbalanced_ratio);
    io.pod(W_ext), io.pod(D_damp), io.pod(D_visc), io.pod(D_mass);
}

static_assert(field_count<StageEnding>() == 11, "StageEnding changed: update StageEnding::io and this count");
template <class IO>
void StageEnding::io(IO& io, const StateShape& shape) {
    io.pod(until_start), io.pod(until_monitor), io.pod(ramp_end);
    io.pod(peak_load_monitor), io.pod(peak_disp_monitor), io.pod(peak_mean), io.pod(peak_u_prev), io.pod(peak_load),
        io.pod(peak_disp), io.pod(below_since);
    if constexpr (IO::loading) {
        check_index(until_monitor, shape.monitors, "until monitor");
        check_index(peak_load_monitor, shape.monitors, "past_peak load monitor");
        check_index(peak_disp_monitor, shape.monitors, "past_peak displacement monitor");
    }
    io_count(io, results);
    for (StageResult& r : results) {
        io.str(r.name), io.str(r.ended_by);
        io.pod(r.time), io.pod(r.steps);
    }
}

static_assert(field_count<Outputs>() == 9, "Outputs changed: update Outputs::io and this count");
template <class IO>
void Outputs::io(IO& io, const StateShape& shape) {
    const std::size_t nm = static_cast<std::size_t>(shape.monitors);
    io.pod(last_row_step);
    io.vec_sized(mon_ext, nm, "monitor extrema");
    io.pod(mon_ext_init);
    io.vec_sized(mon_first_peak, nm, "monitor first peaks");
    io.pod(next_history), io.pod(next_snapshot), io.pod(history_every_steps), io.pod(next_checkpoint);
    io_count(io, snapshots);
    for (auto& [t, name] : snapshots) io.pod(t), io.str(name);
}

#define FDEM_STATE_IO(T)                                               \
    template void T::io<StateWriter>(StateWriter&, const StateShape&); \
    template void T::io<StateReader>(StateReader&, const StateShape&);
FDEM_STATE_IO(StepClock)
FDEM_STATE_IO(Supports)
FDEM_STATE_IO(Loads)
FDEM_STATE_IO(Gravity)
FDEM_STATE_IO(Damping)
FDEM_STATE_IO(EnergyBooks)
FDEM_STATE_IO(StageEnding)
FDEM_STATE_IO(Outputs)
#undef FDEM_STATE_IO

}  // namespace fdem
