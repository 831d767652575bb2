// fdem/load_spring.cpp: load kind `spring` (cases/REFERENCE.md, stages[].loads[].spring): a compliant actuator. A
// spring of stiffness k (N/m) pulls the group (force shared as for a force load) towards an anchor that starts at the
// group's weighted mean position and moves at `velocity` (m/s) in one component: F = k (anchor - mean position). The
// anchor's velocity ramps up smoothly, (1 - cos), over `ramp`, like a prescribed velocity. The other component is
// left free.
#include <cmath>

#include "fdem/case_reader.hpp"
#include "fdem/common/errors.hpp"
#include "fdem/load.hpp"
#include "fdem/sim_detail.hpp"

namespace fdem {

namespace {

class SpringLoad final : public Load {
public:
    using Load::Load;
    std::vector<int> nodes;
    std::vector<double> weight;  // force share per node (sums to 1): also the weights of the mean position
    int comp = 0;
    double k = 0, v = 0, anchor0 = 0;  // N/m, m/s, m
    double ramp = 0, t0 = 0;           // s

    void add_forces(const LoadStep& s) override {
        // Anchor displacement: the integral of a velocity ramped up like a prescribed one, (1 - cos) over ramp.
        constexpr double kPi = sim_detail::kPi;
        const double tau = s.t - t0, R = ramp;
        const double d = R > 0 && tau < R ? v * 0.5 * (tau - R / kPi * std::sin(kPi * tau / R)) : v * (tau - (R > 0 ? 0.5 * R : 0.0));
        const double* x = s.model.x.data();
        double xm = 0;
        for (std::size_t i = 0; i < nodes.size(); ++i) xm += weight[i] * x[2 * nodes[i] + comp];
        const double F = k * (anchor0 + d - xm);
        for (std::size_t i = 0; i < nodes.size(); ++i) {
            const int dof = 2 * nodes[i] + comp;
            s.f_ext[dof] += weight[i] * F;
            s.loaded.push_back(dof);
        }
    }
    template <class IO>
    void io(IO& io, int nn) {
        io.vec(nodes), io.vec(weight);
        if constexpr (IO::loading) {
            for (int n : nodes) check_load_node(n, nn, "load node");
            if (weight.size() != nodes.size()) throw StateError("load weights of another group");
            if (comp != 0 && comp != 1) throw StateError("spring component out of range");
        }
        io.pod(comp), io.pod(k), io.pod(v), io.pod(anchor0), io.pod(ramp), io.pod(t0);
    }
    void save(StateWriter& w) const override { const_cast<SpringLoad*>(this)->io(w, 0); }
    void load(StateReader& r, int nn) override { io(r, nn); }
};

class SpringKind final : public LoadKind {
public:
    const char* key() const override { return "spring"; }
    const char* expect() const override { return "spring = { component, stiffness, velocity }"; }
    void read(case_detail::Ctx& ctx, case_detail::Reader& r, LoadSpec& l) const override {
        using case_detail::Reader;
        l.is_spring = true;
        if (const toml::table* p = r.table("spring", true, "a table { component = \"x\", stiffness = k (N/m), velocity = v (m/s) }")) {
            Reader sr(ctx, *p, r.key_path("spring"));
            l.spring_component =
                case_detail::component_index(sr.string("component", true, "\"x\" or \"y\"", case_detail::kComponents).value_or("x"));
            l.spring_stiffness = sr.number("stiffness", true, "a spring stiffness > 0 in N/m", [](double v) { return v > 0; }).value_or(1.0);
            l.spring_velocity = sr.number("velocity", true, "the anchor's velocity in m/s").value_or(0.0);
            sr.finish();
        }
        l.ramp = r.number("ramp", false, "a ramp time >= 0 in s", [](double v) { return v >= 0; }).value_or(0.0);
        l.function = case_detail::read_function(ctx, r, "function");
        if (l.function.present())
            ctx.error(r.key_path("function"), r.line(), "a time function multiplies a force or pressure, not a spring");
    }
    std::unique_ptr<Load> begin(const LoadSpec& l, const Load* /*previous*/, const LoadStart& s) const override {
        auto sp = std::make_unique<SpringLoad>(*this);
        for (const auto& [k, w] : mesh::load_shares(s.model.group(l.group), s.model.X)) sp->nodes.push_back(k), sp->weight.push_back(w);
        sp->t0 = s.time, sp->ramp = l.ramp;
        // The anchor starts at the group's weighted mean position: no force at the start of the stage.
        sp->comp = l.spring_component, sp->k = l.spring_stiffness, sp->v = l.spring_velocity;
        sp->anchor0 = 0;
        for (std::size_t i = 0; i < sp->nodes.size(); ++i) sp->anchor0 += sp->weight[i] * s.model.x[2 * sp->nodes[i] + sp->comp];
        // The spring's stiffness on the group, K_ij = k w_i w_j, has rank one: its largest omega^2 under the lumped
        // masses is k sum_i w_i^2 / m_i. The step does not count it; it is stable with the rest while
        // omega_s^2 dt^2 <= 1, since lambda_max(M^-1 (K_rest + K_s)) <= lambda_max(M^-1 K_rest) + omega_s^2 and the
        // rest's bound at the default safety 0.8 gives (2 safety)^2 = 2.56 < 4 - 1.
        double w2 = 0;  // 1/s^2
        for (std::size_t i = 0; i < sp->nodes.size(); ++i) w2 += sp->weight[i] * sp->weight[i] / s.model.mass[sp->nodes[i]];
        w2 *= sp->k;
        if (s.dt > 0 && w2 * s.dt * s.dt > 1.0)
            throw InputError(s.file + ":" + std::to_string(l.line) + ": key 'spring': too stiff for the time step: " +
                             case_detail::g4(sp->k) + " N/m on group '" + l.group + "' (omega " + case_detail::g4(std::sqrt(w2)) +
                             " rad/s on its nodes' masses) needs a step below " + case_detail::g4(1.0 / std::sqrt(w2)) +
                             " s, and the run's step is " + case_detail::g4(s.dt) +
                             " s (the stable step does not count load springs); expected a stiffness below " +
                             case_detail::g4(sp->k / (w2 * s.dt * s.dt)) + " N/m");
        return sp;
    }
    std::unique_ptr<Load> restore() const override { return std::make_unique<SpringLoad>(*this); }
};

}  // namespace

const LoadKind& spring_load_kind() {
    static const SpringKind kind;
    return kind;
}

}  // namespace fdem
