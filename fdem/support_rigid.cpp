// fdem/support_rigid.cpp: support kind `rigid` (rigid = "x" | "y" | "xy" in a [[stages.supports]] block): the group's
// nodes share one velocity in the component, free as a whole (e.g. rigid = "y" with vx on a loading beam: the beam
// stays horizontal, moves up and down freely and cannot rotate). Each step (Simulation::step_rigid_groups) the common
// velocity follows the resultant of the group's nodal forces, v^{n+1/2} = v^{n-1/2} + dt (F + F_d) / M with
// M = sum of the nodal masses and the [C79] local damping F_d = -alpha |F| sign(v) on the resultant (and the
// mass-proportional damping -a M v_bar). The node loop then treats the DOFs as prescribed: their reactions
// redistribute the forces inside the group and sum to the damping forces, which the loop books as work; the step
// moves that share from work to damping (RigidStep's sums). Its reactions are internal: not support reactions.
#include <cmath>

#include "fdem/case_reader.hpp"
#include "fdem/support.hpp"

namespace fdem {

namespace {

class RigidSupport final : public Support {
public:
    using Support::Support;
    double v_common = 0;  // m/s, the group's common velocity at the last half step
    double v_ref = 0;     // m/s, its moving mean for the filtered local damping

    double start_velocity() const override { return v_common; }
    bool carries_reaction() const override { return false; }
    void filter_started() override { v_ref = v_common; }
    void rigid_step(RigidStep& s, int id) override {
        const Model& m = s.model;
        const int c = comp;
        double F = 0, M = 0;
        for (int k : nodes) {
            const int d = 2 * k + c;
            if (s.dof_owner[d] != id) continue;
            double f = s.f_mod[d] + s.f_ext[d] + m.grav_mass[k] * s.gravity[c];
            for (int j = m.inc_ptr[k]; j < m.inc_ptr[k + 1]; ++j) f += s.tri_forces[2 * static_cast<std::size_t>(m.inc_idx[j]) + c];
            F += f, M += m.mass[k];
        }
        if (!(M > 0)) return;
        const double vold = v_common;
        const double vrel = s.filter_tau > 0 ? vold - v_ref : vold;
        const double Fd = vrel > 0 ? -s.local_damping * std::abs(F) : vrel < 0 ? s.local_damping * std::abs(F) : 0.0;
        const double vnew = ((1 - s.hm) * vold + s.dtv * (F + Fd) / M) / (1 + s.hm);
        const double Fm = -s.mass_damping * M * 0.5 * (vold + vnew);
        // (a change of step: F over (x^{n+1} - x^{n-1}) / 2, fdem/node_update.hpp)
        const bool change = s.dt_before != s.dt;
        const double span = 0.5 * (s.dt_before * vold + s.dt * vnew);
        s.damp += change ? Fd * span : s.dt * Fd * 0.5 * (vold + vnew);
        s.damp_half += 0.5 * s.dt * Fd * vnew;
        s.mass += change ? Fm * span : s.dt * Fm * 0.5 * (vold + vnew);
        s.mass_half += 0.5 * s.dt * Fm * vnew;
        v_common = vnew;
        if (s.filter_tau > 0) v_ref += s.wf * (vnew - v_ref);
        for (int k : nodes)
            if (s.dof_owner[2 * k + c] == id) s.dof_vel[2 * k + c] = vnew;
    }
    template <class IO>
    void io(IO& io, int nn) {
        io_common(io, nn);
        io.pod(v_common), io.pod(v_ref);
    }
    void save(StateWriter& w) const override { const_cast<RigidSupport*>(this)->io(w, 0); }
    void load(StateReader& r, int nn) override { io(r, nn); }
};

class RigidKind final : public SupportKind {
public:
    const char* key() const override { return "rigid"; }
    DofMode mode() const override { return DofMode::rigid; }
    void read(case_detail::Ctx& ctx, case_detail::Reader& r, SupportSpec& s) const override {
        case_detail::read_dof_set(ctx, r, "rigid", DofMode::rigid, s);
    }
    std::unique_ptr<Support> begin(const SupportSpec& s, int c, const SupportStart& st) const override {
        auto a = std::make_unique<RigidSupport>(*this);
        // Starts from the group's momentum: the mass-weighted mean velocity.
        double p = 0, m = 0;
        for (int k : st.model.group(s.group).nodes) p += st.model.mass[k] * st.model.v[2 * k + c], m += st.model.mass[k];
        a->v_common = m > 0 ? p / m : 0.0;
        a->v_ref = a->v_common;  // the filtered local damping's mean starts there (no kick)
        return a;
    }
    std::unique_ptr<Support> restore() const override { return std::make_unique<RigidSupport>(*this); }
};

}  // namespace

const SupportKind& rigid_support_kind() {
    static const RigidKind kind;
    return kind;
}

}  // namespace fdem
