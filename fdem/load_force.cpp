// fdem/load_force.cpp: load kind `force` (cases/REFERENCE.md, stages[].loads[]): a total force [Fx, Fy] (N, whole
// thickness) on a group, shared by tributary length along its edges (or equally among its nodes: mesh::load_shares),
// ramped linearly over `ramp` from the value of the force it replaces, times an optional time function.
#include "fdem/case_reader.hpp"
#include "fdem/load.hpp"

namespace fdem {

namespace {

class ForceLoad final : public Load {
public:
    using Load::Load;
    std::vector<int> nodes;
    std::vector<double> weight;  // force share per node (sums to 1)
    RampedValue value;           // N

    void add_forces(const LoadStep& s) override {
        const auto [v0, v1] = value(s.t);
        for (std::size_t i = 0; i < nodes.size(); ++i) {
            const int k = nodes[i];
            s.f_ext[2 * k] += weight[i] * v0, s.f_ext[2 * k + 1] += weight[i] * v1;
            s.loaded.push_back(2 * k), s.loaded.push_back(2 * k + 1);
        }
    }
    std::array<double, 2> value_at(double t) const override { return value.ramped(t); }
    template <class IO>
    void io(IO& io, int nn) {
        io.vec(nodes), io.vec(weight);
        if constexpr (IO::loading) {
            for (int k : nodes) check_load_node(k, nn, "load node");
            if (weight.size() != nodes.size()) throw StateError("load weights of another group");
        }
        value.io(io);
    }
    void save(StateWriter& w) const override { const_cast<ForceLoad*>(this)->io(w, 0); }
    void load(StateReader& r, int nn) override { io(r, nn); }
};

class ForceKind final : public LoadKind {
public:
    const char* key() const override { return "force"; }
    const char* expect() const override { return "force = [Fx, Fy] (N)"; }
    void read(case_detail::Ctx& ctx, case_detail::Reader& r, LoadSpec& l) const override {
        if (auto f = r.vec2("force", true, "[Fx, Fy], the total force on the group in N")) l.force = *f;
        l.ramp = r.number("ramp", false, "a ramp time >= 0 in s", [](double v) { return v >= 0; }).value_or(0.0);
        l.function = case_detail::read_function(ctx, r, "function");
    }
    std::unique_ptr<Load> begin(const LoadSpec& l, const Load* previous, const LoadStart& s) const override {
        auto f = std::make_unique<ForceLoad>(*this);
        f->value.t0 = s.time, f->value.ramp = l.ramp, f->value.fn = l.function, f->value.target = l.force;
        if (previous) f->value.start = previous->value_at(s.time);
        for (const auto& [k, w] : mesh::load_shares(s.model.group(l.group), s.model.X)) f->nodes.push_back(k), f->weight.push_back(w);
        return f;
    }
    std::unique_ptr<Load> restore() const override { return std::make_unique<ForceLoad>(*this); }
};

}  // namespace

const LoadKind& force_load_kind() {
    static const ForceKind kind;
    return kind;
}

}  // namespace fdem
