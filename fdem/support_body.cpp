// fdem/support_body.cpp: support kind `body` (rigid = "body" in a [[stages.supports]] block, both components): the
// group moves as one rigid body, translating and rotating under its resultant force and its moment about its centre
// of mass, free. The block's two components are two Supports: the x one carries the body's state and moves it, the
// y one only owns the y DOFs. Each step (Simulation::step_rigid_groups), with M, the centre of mass c, I = sum m_k
// |r_k|^2 (r_k = x_k - c at t^n, lumped masses), the resultant F and moment T about c of the nodes' forces at t^n:
//   V^{n+1/2} = V^{n-1/2} + dt (F + F_d) / M,   omega^{n+1/2} = omega^{n-1/2} + dt (T + T_d) / I
// (local damping F_d = -alpha |F| sign(V) per component and T_d = -alpha |T| sign(omega); mass damping as for the
// nodes: the semi-implicit factor on V and omega). The nodes then move rigidly to
//   x_k^{n+1} = c + dt V^{n+1/2} + R(dtheta) r_k,   sin(dtheta) = dt omega^{n+1/2},
// given to the node loop as their prescribed velocities (x_k^{n+1} - x_k^n) / dt: the distances between the nodes
// stay as they were (to round-off), and these chord velocities carry exactly the momentum M V and the angular
// momentum I omega (sum m r x (R - 1) r / dt = I sin(dtheta) / dt), so the reactions the node loop books inside the
// body add up to the damping force and moment alone; the step moves that share from work to damping (RigidStep's
// sums), as for the rigid supports. A later block that takes one component of the group over ends the run with a
// message: a body needs both.
#include <algorithm>
#include <cmath>

#include "fdem/case_reader.hpp"
#include "fdem/common/errors.hpp"
#include "fdem/support.hpp"

namespace fdem {

namespace {

class BodySupport final : public Support {
public:
    using Support::Support;
    double V[2] = {0, 0}, V_ref[2] = {0, 0};  // m/s: velocity of the centre of mass at the last half step; moving mean
    double omega = 0, omega_ref = 0;          // rad/s: angular velocity at the last half step; moving mean

    double start_velocity() const override { return V[comp]; }
    bool carries_reaction() const override { return false; }
    void filter_started() override { V_ref[0] = V[0], V_ref[1] = V[1], omega_ref = omega; }
    void rigid_step(RigidStep& s, int id) override;
    template <class IO>
    void io(IO& io, int nn) {
        io_common(io, nn);
        io.pod(V[0]), io.pod(V[1]), io.pod(V_ref[0]), io.pod(V_ref[1]), io.pod(omega), io.pod(omega_ref);
    }
    void save(StateWriter& w) const override { const_cast<BodySupport*>(this)->io(w, 0); }
    void load(StateReader& r, int nn) override { io(r, nn); }
};

// The body's other component: the support owning DOF d, if it is a body support of the same block.
const BodySupport* partner(const RigidStep& s, const BodySupport& self, int d) {
    const int o = s.dof_owner[d];
    if (o < 0 || o >= s.n_supports) return nullptr;
    const auto* p = dynamic_cast<const BodySupport*>(s.supports[o].get());
    return p && p->comp != self.comp && p->group == self.group && p->t0 == self.t0 ? p : nullptr;
}

void BodySupport::rigid_step(RigidStep& s, int id) {
    // the nodes whose x this body still owns, and the y support of the same block that owns their y
    int y = -1;
    for (int k : nodes)
        if (s.dof_owner[2 * k + comp] == id) {
            const int d = 2 * k + 1 - comp;
            if (!partner(s, *this, d))
                throw RunError("support on '" + group + "' (rigid = \"body\"): a later support took its " +
                               (comp == 0 ? "y" : "x") + " component; a rigid body needs both (give the group's new "
                               "support for both components, or rigid = \"x\" / \"y\")");
            y = s.dof_owner[d];
            break;
        }
    if (comp == 1 || y < 0) return;  // the x support moves the body
    const Model& m = s.model;
    auto owned = [&](int k) { return s.dof_owner[2 * k] == id && s.dof_owner[2 * k + 1] == y; };
    double M = 0, mx = 0, my = 0;
    for (int k : nodes)
        if (owned(k)) M += m.mass[k], mx += m.mass[k] * m.x[2 * k], my += m.mass[k] * m.x[2 * k + 1];
    if (!(M > 0)) return;
    const double cx = mx / M, cy = my / M;
    double F[2] = {0, 0}, T = 0, I = 0;
    for (int k : nodes) {
        if (!owned(k)) continue;
        double f[2];
        for (int c = 0; c < 2; ++c) {
            const int d = 2 * k + c;
            f[c] = s.f_mod[d] + s.f_ext[d] + m.grav_mass[k] * s.gravity[c];
            for (int j = m.inc_ptr[k]; j < m.inc_ptr[k + 1]; ++j) f[c] += s.tri_forces[2 * static_cast<std::size_t>(m.inc_idx[j]) + c];
            F[c] += f[c];
        }
        const double rx = m.x[2 * k] - cx, ry = m.x[2 * k + 1] - cy;
        T += rx * f[1] - ry * f[0];
        I += m.mass[k] * (rx * rx + ry * ry);
    }
    auto advance = [&](double vold, double ref, double force, double inertia) {
        const double vrel = s.filter_tau > 0 ? vold - ref : vold;
        const double fd = vrel > 0 ? -s.local_damping * std::abs(force) : vrel < 0 ? s.local_damping * std::abs(force) : 0.0;
        const double vnew = ((1 - s.hm) * vold + s.dtv * (force + fd) / inertia) / (1 + s.hm);
        const double fm = -s.mass_damping * inertia * 0.5 * (vold + vnew);
        s.damp += s.dt * fd * 0.5 * (vold + vnew), s.damp_half += 0.5 * s.dt * fd * vnew;
        s.mass += s.dt * fm * 0.5 * (vold + vnew), s.mass_half += 0.5 * s.dt * fm * vnew;
        return vnew;
    };
    V[0] = advance(V[0], V_ref[0], F[0], M);
    V[1] = advance(V[1], V_ref[1], F[1], M);
    if (I > 0) omega = advance(omega, omega_ref, T, I);
    if (s.filter_tau > 0) {
        V_ref[0] += s.wf * (V[0] - V_ref[0]), V_ref[1] += s.wf * (V[1] - V_ref[1]);
        omega_ref += s.wf * (omega - omega_ref);
    }
    const double dt = s.dt;
    const double sn = std::max(-1.0, std::min(1.0, dt * omega)), cs = std::sqrt(1.0 - sn * sn);  // of dtheta
    for (int k : nodes) {
        if (!owned(k)) continue;
        const double rx = m.x[2 * k] - cx, ry = m.x[2 * k + 1] - cy;
        // (x^{n+1} - x^n) / dt = V + (R(dtheta) - 1) r / dt
        s.dof_vel[2 * k] = V[0] + ((cs - 1.0) * rx - sn * ry) / dt;
        s.dof_vel[2 * k + 1] = V[1] + (sn * rx + (cs - 1.0) * ry) / dt;
    }
}

class BodyKind final : public SupportKind {
public:
    const char* key() const override { return "body"; }
    DofMode mode() const override { return DofMode::body; }
    // (read by the rigid kind: rigid = "body" is a value of its key, case_detail::read_dof_set)
    void read(case_detail::Ctx&, case_detail::Reader&, SupportSpec&) const override {}
    std::unique_ptr<Support> begin(const SupportSpec& sp, int, const SupportStart& st) const override {
        // Starts from the group's momentum and its angular momentum about its centre of mass: V = P / M,
        // omega = L / I (lumped masses).
        auto a = std::make_unique<BodySupport>(*this);
        const Model& md = st.model;
        double m = 0, mx = 0, my = 0, px = 0, py = 0;
        for (int k : md.group(sp.group).nodes) {
            const double mk = md.mass[k];
            m += mk, mx += mk * md.x[2 * k], my += mk * md.x[2 * k + 1];
            px += mk * md.v[2 * k], py += mk * md.v[2 * k + 1];
        }
        if (m > 0) {
            a->V[0] = px / m, a->V[1] = py / m;
            const double cx = mx / m, cy = my / m;
            double L = 0, I = 0;
            for (int k : md.group(sp.group).nodes) {
                const double mk = md.mass[k], rx = md.x[2 * k] - cx, ry = md.x[2 * k + 1] - cy;
                L += mk * (rx * (md.v[2 * k + 1] - a->V[1]) - ry * (md.v[2 * k] - a->V[0]));
                I += mk * (rx * rx + ry * ry);
            }
            a->omega = I > 0 ? L / I : 0.0;
        }
        a->V_ref[0] = a->V[0], a->V_ref[1] = a->V[1], a->omega_ref = a->omega;
        return a;
    }
    std::unique_ptr<Support> restore() const override { return std::make_unique<BodySupport>(*this); }
};

}  // namespace

const SupportKind& body_support_kind() {
    static const BodyKind kind;
    return kind;
}

}  // namespace fdem
