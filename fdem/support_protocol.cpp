// fdem/support_protocol.cpp: support kind `protocol` (protocol = { component, points } or cyclic = { component,
// amplitudes, cycles, rate } in a [[stages.supports]] block; the reader turns a cyclic block into its points): the
// group's DOFs in the component follow a piecewise-linear displacement-versus-time history from the stage start,
// corner-smoothed over `ramp`.
#include <algorithm>

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
