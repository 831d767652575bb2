// fdem/load_foundation.cpp: load kind `foundation` (cases/REFERENCE.md, stages[].loads[].foundation): an elastic
// (Winkler) foundation under a curve group, foundation = { normal = k_n, shear = k_s } in Pa/m (N per m^2 of
// contact per m of displacement).
//
// Each edge of the group carries distributed springs against the displacement of its nodes from their positions at
// the start of the stage whose block first set the foundation on the group (a later block on the group changes the
// stiffness and keeps those rest positions): k_n along the edge's outward normal and k_s along its tangent, both of
// the reference placement (fixed directions: small rotations of the edge), lumped to the edge's two nodes by half
// its reference length L times the thickness t. Node k thus carries the force f_k = -K_k (x_k - x0_k) with
//   K_k = sum over its edges of (L t / 2) (k_n n n^T + k_s s s^T).
// A block of foundation length L_f settling under its weight W comes to rest at the mean settlement W / (k_n L_f t)
// (weighted by the nodes' tributary lengths), and a horizontal force F on it gives F / (k_s L_f t) along a straight
// bottom (tests/core/test_foundation.cpp).
//
// Books: its forces are loads (f_ext): their work, minus the energy the springs store, is external work (W_ext), so
// the energy balance holds as for any load; a "load" monitor on the group reads its force. It holds the body as a
// support does: in a stage's equilibrium check its resultant counts with the reactions (Load::reacts).
// Stable step: the foundation is not in the step's bound (fdem/README.md 'Time step'); begin refuses one whose
// springs alone would need a step below twice the run's (a foundation stiffer than the body it carries).
#include <cmath>
#include <map>

#include "fdem/case_reader.hpp"
#include "fdem/common/errors.hpp"
#include "fdem/load.hpp"

namespace fdem {

namespace {

class FoundationLoad final : public Load {
public:
    using Load::Load;
    std::vector<int> nodes;                 // ascending
    std::vector<double> x0;                 // m, 2 per node: the springs' rest positions
    std::vector<std::array<double, 3>> K;   // N/m, per node: K_xx, K_xy, K_yy
    std::array<double, 2> resultant{0, 0};  // N, of the last add_forces

    void add_forces(const LoadStep& s) override {
        const double* x = s.model.x.data();
        double rx = 0, ry = 0;
        for (std::size_t i = 0; i < nodes.size(); ++i) {
            const int k = nodes[i];
            const double ux = x[2 * k] - x0[2 * i], uy = x[2 * k + 1] - x0[2 * i + 1];
            const double fx = -(K[i][0] * ux + K[i][1] * uy), fy = -(K[i][1] * ux + K[i][2] * uy);
            s.f_ext[2 * k] += fx, s.f_ext[2 * k + 1] += fy;
            s.loaded.push_back(2 * k), s.loaded.push_back(2 * k + 1);
            rx += fx, ry += fy;
        }
        resultant = {rx, ry};
    }
    bool reacts(std::array<double, 2>& r) const override {
        r = resultant;
        return true;
    }
    template <class IO>
    void io(IO& io, int nn) {
        io.vec(nodes), io.vec(x0), io.vec(K), io.pod(resultant);
        if constexpr (IO::loading) {
            for (int k : nodes) check_load_node(k, nn, "foundation node");
            if (x0.size() != 2 * nodes.size() || K.size() != nodes.size()) throw StateError("foundation of another group");
        }
    }
    void save(StateWriter& w) const override { const_cast<FoundationLoad*>(this)->io(w, 0); }
    void load(StateReader& r, int nn) override { io(r, nn); }
};

class FoundationKind final : public LoadKind {
public:
    const char* key() const override { return "foundation"; }
    const char* expect() const override { return "foundation = { normal, shear } (Pa/m)"; }
    void read(case_detail::Ctx& ctx, case_detail::Reader& r, LoadSpec& l) const override {
        const toml::table* p = r.table("foundation", true, "a table { normal = k_n (Pa/m), shear = k_s (Pa/m) }");
        if (!p) return;
        case_detail::Reader fr(ctx, *p, r.key_path("foundation"));
        auto stiffness = [](double v) { return v >= 0; };
        const auto kn = fr.number("normal", true, "a normal stiffness >= 0 in Pa/m", stiffness);
        const auto ks = fr.number("shear", true, "a shear stiffness >= 0 in Pa/m", stiffness);
        fr.finish();
        if (kn && ks && !(*kn > 0 || *ks > 0))
            ctx.error(r.key_path("foundation"), fr.line(), "expected a normal or shear stiffness > 0 in Pa/m, got both 0");
        l.param["normal"] = kn.value_or(0.0);
        l.param["shear"] = ks.value_or(0.0);
    }
    bool needs_edges() const override { return true; }
    std::unique_ptr<Load> begin(const LoadSpec& l, const Load* previous, const LoadStart& s) const override {
        const Model& m = s.model;
        const double kn = l.param.at("normal"), ks = l.param.at("shear"), t = m.thickness;
        std::map<int, std::array<double, 3>> Kn;  // by node, ascending
        const auto edges = oriented_edges(m, l, s.file);
        if (edges.empty())
            throw InputError(s.file + ":" + std::to_string(l.line) + ": group '" + l.group + "' has no edges; a foundation needs a curve");
        for (const auto& ed : edges) {
            // Tangent a -> b and outward normal (on the right of a -> b: the body is on its left), reference placement.
            const double dx = m.X[2 * ed[1]] - m.X[2 * ed[0]], dy = m.X[2 * ed[1] + 1] - m.X[2 * ed[0] + 1];
            const double L = std::hypot(dx, dy);
            if (!(L > 0)) continue;
            const double sx = dx / L, sy = dy / L, nx = sy, ny = -sx;
            const double h = 0.5 * L * t;
            for (int k : {ed[0], ed[1]}) {
                auto& a = Kn[k];
                a[0] += h * (kn * nx * nx + ks * sx * sx);
                a[1] += h * (kn * nx * ny + ks * sx * sy);
                a[2] += h * (kn * ny * ny + ks * sy * sy);
            }
        }
        auto f = std::make_unique<FoundationLoad>(*this);
        const auto* prev = dynamic_cast<const FoundationLoad*>(previous);
        for (const auto& [k, a] : Kn) {
            f->nodes.push_back(k), f->K.push_back(a);
            // Rest position: the previous block's on this group (a stiffness change keeps it), else x now.
            double r0 = m.x[2 * k], r1 = m.x[2 * k + 1];
            if (prev)
                for (std::size_t i = 0; i < prev->nodes.size(); ++i)
                    if (prev->nodes[i] == k) r0 = prev->x0[2 * i], r1 = prev->x0[2 * i + 1];
            f->x0.push_back(r0), f->x0.push_back(r1);
            // Its springs alone: stable at the run's step with a margin (the body's triangles share the node).
            const double kmax = 0.5 * (a[0] + a[2]) + std::hypot(0.5 * (a[0] - a[2]), a[1]);
            if (s.dt > 0 && kmax * s.dt * s.dt > m.mass[k])
                throw InputError(s.file + ":" + std::to_string(l.line) + ": key 'foundation': too stiff for the time step: at (" +
                                 case_detail::g4(m.X[2 * k]) + ", " + case_detail::g4(m.X[2 * k + 1]) + ") m its springs of " +
                                 case_detail::g4(kmax) + " N/m on a node of " + case_detail::g4(m.mass[k]) +
                                 " kg need a step below " + case_detail::g4(2 * std::sqrt(m.mass[k] / kmax)) +
                                 " s, twice the run's step " + case_detail::g4(s.dt) +
                                 " s at most (the stable step does not count the foundation); expected a softer foundation");
        }
        return f;
    }
    std::unique_ptr<Load> restore() const override { return std::make_unique<FoundationLoad>(*this); }
};

}  // namespace

const LoadKind& foundation_load_kind() {
    static const FoundationKind kind;
    return kind;
}

}  // namespace fdem
