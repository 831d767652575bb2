// fdem/load_pressure.cpp: load kind `pressure` (cases/REFERENCE.md, stages[].loads[]): a pressure p (Pa) on the
// edges of a curve group, acting against each edge's current outward normal (a follower load), lumped half to each
// end node; ramped linearly over `ramp` from the value of the pressure it replaces, times an optional time function.
#include <map>

#include "fdem/case_reader.hpp"
#include "fdem/common/errors.hpp"
#include "fdem/load.hpp"

namespace fdem {

namespace {

class PressureLoad final : public Load {
public:
    using Load::Load;
    std::vector<std::array<int, 2>> edges;  // oriented counter-clockwise around the body (outward normal on the right)
    RampedValue value;                      // Pa (component 0)

    void add_forces(const LoadStep& s) override {
        const double p = value(s.t)[0];
        const double* x = s.model.x.data();
        const double th = s.model.thickness;
        // Pressure p on edge a->b (body on its left): force -p t L n_out = -p t (dy, -dx), half to each node.
        for (auto ed : edges) {
            const double dx = x[2 * ed[1]] - x[2 * ed[0]], dy = x[2 * ed[1] + 1] - x[2 * ed[0] + 1];
            const double fx = -0.5 * p * th * dy, fy = 0.5 * p * th * dx;
            for (int k : {ed[0], ed[1]}) {
                s.f_ext[2 * k] += fx, s.f_ext[2 * k + 1] += fy;
                s.loaded.push_back(2 * k), s.loaded.push_back(2 * k + 1);
            }
        }
    }
    std::array<double, 2> value_at(double t) const override { return value.ramped(t); }
    template <class IO>
    void io(IO& io, int nn) {
        io.vec(edges);
        if constexpr (IO::loading)
            for (const auto& e : edges) check_load_node(e[0], nn, "load edge node"), check_load_node(e[1], nn, "load edge node");
        value.io(io);
    }
    void save(StateWriter& w) const override { const_cast<PressureLoad*>(this)->io(w, 0); }
    void load(StateReader& r, int nn) override { io(r, nn); }
};

class PressureKind final : public LoadKind {
public:
    const char* key() const override { return "pressure"; }
    const char* expect() const override { return "pressure (Pa)"; }
    void read(case_detail::Ctx& ctx, case_detail::Reader& r, LoadSpec& l) const override {
        l.is_pressure = true;
        l.pressure = r.number("pressure", true, "a pressure in Pa").value_or(0.0);
        l.ramp = r.number("ramp", false, "a ramp time >= 0 in s", [](double v) { return v >= 0; }).value_or(0.0);
        l.function = case_detail::read_function(ctx, r, "function");
    }
    bool needs_edges() const override { return true; }
    std::unique_ptr<Load> begin(const LoadSpec& l, const Load* previous, const LoadStart& s) const override {
        auto p = std::make_unique<PressureLoad>(*this);
        p->value.t0 = s.time, p->value.ramp = l.ramp, p->value.fn = l.function, p->value.target = {l.pressure, 0};
        if (previous) p->value.start = previous->value_at(s.time);
        p->edges = oriented_edges(s.model, l, s.file);
        return p;
    }
    std::unique_ptr<Load> restore() const override { return std::make_unique<PressureLoad>(*this); }
};

}  // namespace

// The group's edges, each oriented as it runs counter-clockwise around its triangle (the body on its left, the
// outward normal on its right). Throws InputError for an edge on no triangle.
std::vector<std::array<int, 2>> oriented_edges(const Model& model, const LoadSpec& l, const std::string& file) {
    std::map<std::pair<int, int>, int> directed;
    for (int e = 0; e < model.n_triangles(); ++e)
        for (int k = 0; k < 3; ++k) directed[{model.tris[e].n[k], model.tris[e].n[(k + 1) % 3]}] = e;
    std::vector<std::array<int, 2>> out;
    for (auto ed : model.group(l.group).edges) {
        if (directed.count({ed[0], ed[1]})) out.push_back(ed);
        else if (directed.count({ed[1], ed[0]})) out.push_back({ed[1], ed[0]});
        else throw InputError(file + ":" + std::to_string(l.line) + ": group '" + l.group + "' has an edge that lies on no triangle");
    }
    return out;
}

const LoadKind& pressure_load_kind() {
    static const PressureKind kind;
    return kind;
}

}  // namespace fdem
