// fdem/support_protocol.cpp: support kind `protocol` (protocol = { component, points } or cyclic = { component,
// amplitudes, cycles, rate } in a [[stages.supports]] block; the reader turns a cyclic block into its points): the
// group's DOFs in the component follow a piecewise-linear displacement-versus-time history from the stage start,
// corner-smoothed over `ramp`.
#include <algorithm>
#include <cmath>

#include "fdem/case_reader.hpp"
#include "fdem/support.hpp"

namespace fdem {

namespace {

class ProtocolSupport final : public Support {
public:
    using Support::Support;
    std::vector<double> pt, pu;  // times (s, from t0) and displacements (m)
    std::vector<double> pI;      // INT_pt[0]^pt[i] u dt at each knot (m s), for the corner smoothing

    double displacement(double tau) const {
        if (tau <= pt.front()) return pu.front();
        if (tau >= pt.back()) return pu.back();
        const auto it = std::upper_bound(pt.begin(), pt.end(), tau);
        const std::size_t i = static_cast<std::size_t>(it - pt.begin());
        const double w = (tau - pt[i - 1]) / (pt[i] - pt[i - 1]);
        return pu[i - 1] + w * (pu[i] - pu[i - 1]);
    }
    double integral(double tau) const {
        // INT_{pt[0]}^{tau} u dt of the piecewise-linear protocol, u held at its end values outside [pt[0], pt[n-1]].
        if (tau <= pt.front()) return (tau - pt.front()) * pu.front();
        if (tau >= pt.back()) return pI.back() + (tau - pt.back()) * pu.back();
        const auto it = std::upper_bound(pt.begin(), pt.end(), tau);
        const std::size_t i = static_cast<std::size_t>(it - pt.begin());
        const double w = (tau - pt[i - 1]) / (pt[i] - pt[i - 1]);
        const double u = pu[i - 1] + w * (pu[i] - pu[i - 1]);  // displacement(tau), same segment
        return pI[i - 1] + 0.5 * (tau - pt[i - 1]) * (pu[i - 1] + u);
    }
    double position(double tau) const {
        // Corner smoothing: with ramp T > 0 the driven position is the protocol averaged over the trailing window
        // [tau - T, tau], u_T(tau) = (I(tau) - I(tau - T)) / T. Its velocity (u(tau) - u(tau - T)) / T is continuous:
        // it starts from 0 at the stage start and changes linearly over T at every corner (largest acceleration
        // |dv| / T), instead of jumping in one step (a reversal of v then asks the driven nodes for a force
        // m 2 v / dt, which the reaction monitor reports and which hits the specimen like an impact). The price: the
        // motion lags the protocol by T / 2 and each corner is cut by |dv| T / 8 (an amplitude a reached at rate v
        // and reversed: a - v T / 4).
        if (!(ramp > 0)) return displacement(tau);
        return (integral(tau) - integral(tau - ramp)) / ramp;
    }
    bool prescribe(double t, double dt, double& v) const override {
        // The velocity that lands exactly on u(t + dt) from u(t) (corner-smoothed when the support has a ramp).
        v = (position(t + dt - t0) - position(t - t0)) / dt;
        return true;
    }
    template <class IO>
    void io(IO& io, int nn) {
        io_common(io, nn);
        io.vec(pt), io.vec(pu), io.vec(pI);
        if constexpr (IO::loading)
            if (pt.empty() || pu.size() != pt.size() || pI.size() != pt.size()) throw StateError("protocol of another length");
    }
    void save(StateWriter& w) const override { const_cast<ProtocolSupport*>(this)->io(w, 0); }
    void load(StateReader& r, int nn) override { io(r, nn); }
};

class ProtocolKind final : public SupportKind {
public:
    const char* key() const override { return "protocol"; }
    DofMode mode() const override { return DofMode::protocol; }
    // protocol = { component, points = [[t, u], ...] } or cyclic = { component, amplitudes, cycles, rate }, which
    // becomes the points of its cycles.
    void read(case_detail::Ctx& ctx, case_detail::Reader& r, SupportSpec& s) const override {
        using case_detail::component_index;
        using case_detail::kComponents;
        using case_detail::line_of;
        using case_detail::Reader;
        auto add_protocol = [&](int comp, std::vector<double> t_pts, std::vector<double> u_pts, const std::string& key, int line) {
            if (s.mode[comp] != DofMode::inherit) {
                ctx.error(r.key_path(key), line, "component " + kComponents[comp] + " already has a support in this block");
                return;
            }
            s.mode[comp] = DofMode::protocol;
            s.protocol_t = std::move(t_pts);
            s.protocol_u = std::move(u_pts);
        };
        if (const toml::table* p = r.table("protocol", false, "a table { component = \"x\", points = [[t, u], ...] }")) {
            Reader pr(ctx, *p, r.key_path("protocol"));
            const int comp = component_index(pr.string("component", true, "\"x\" or \"y\"", kComponents).value_or("x"));
            const toml::node* pts = pr.node("points", true, "an array of [time s, displacement m] pairs");
            std::vector<double> tt, uu;
            bool ok = pts && pts->is_array() && pts->as_array()->size() >= 2;
            if (ok)
                for (const auto& e : *pts->as_array()) {
                    const toml::array* pair = e.as_array();
                    if (!pair || pair->size() != 2 || !(*pair)[0].is_number() || !(*pair)[1].is_number()) {
                        ok = false;
                        break;
                    }
                    tt.push_back(*(*pair)[0].value<double>());
                    uu.push_back(*(*pair)[1].value<double>());
                }
            for (std::size_t i = 1; ok && i < tt.size(); ++i)
                if (!(tt[i] > tt[i - 1])) ok = false;
            if (pts && !ok)
                ctx.error(pr.key_path("points"), line_of(pts),
                          "expected at least two [time s, displacement m] pairs with strictly increasing times");
            pr.finish();
            if (ok) add_protocol(comp, tt, uu, "protocol", pr.line());
        }
        if (const toml::table* p = r.table("cyclic", false, "a table { component, amplitudes, cycles, rate }")) {
            Reader pr(ctx, *p, r.key_path("cyclic"));
            const int comp = component_index(pr.string("component", true, "\"x\" or \"y\"", kComponents).value_or("x"));
            auto amps = pr.numbers("amplitudes", true, "an array of displacement amplitudes > 0 in m");
            const int cycles = pr.integer("cycles", false, "a whole number of cycles per amplitude >= 1",
                                          [](long long v) { return v >= 1; }).value_or(1);
            auto rate = pr.number("rate", true, "a loading rate > 0 in m/s", [](double v) { return v > 0; });
            pr.finish();
            if (amps && rate) {
                bool ok = !amps->empty();
                for (double a : *amps) ok = ok && a > 0;
                if (!ok) {
                    ctx.error(pr.key_path("amplitudes"), pr.line(), "expected a non-empty array of amplitudes > 0 in m");
                } else {
                    // Each cycle: 0 -> +a -> 0 -> -a -> 0 at the constant rate.
                    std::vector<double> tt{0}, uu{0};
                    for (double a : *amps)
                        for (int c = 0; c < cycles; ++c)
                            for (double target : {a, 0.0, -a, 0.0}) {
                                tt.push_back(tt.back() + std::abs(target - uu.back()) / *rate);
                                uu.push_back(target);
                            }
                    add_protocol(comp, tt, uu, "cyclic", pr.line());
                }
            }
        }
    }
    std::unique_ptr<Support> begin(const SupportSpec& s, int, const SupportStart&) const override {
        auto a = std::make_unique<ProtocolSupport>(*this);
        a->pt = s.protocol_t, a->pu = s.protocol_u;
        a->pI.assign(a->pt.size(), 0.0);
        for (std::size_t i = 1; i < a->pt.size(); ++i) a->pI[i] = a->pI[i - 1] + 0.5 * (a->pt[i] - a->pt[i - 1]) * (a->pu[i] + a->pu[i - 1]);
        return a;
    }
    std::unique_ptr<Support> restore() const override { return std::make_unique<ProtocolSupport>(*this); }
};

}  // namespace

const SupportKind& protocol_support_kind() {
    static const ProtocolKind kind;
    return kind;
}

}  // namespace fdem
