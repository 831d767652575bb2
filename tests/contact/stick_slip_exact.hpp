// tests/contact/stick_slip_exact.hpp: the exact stick-slip of a rigid block on a rigid base under F0 sin(omega t + phi)
// with Coulomb friction mu (CLOSED FORMS "harmonic" in test_friction_hold.cpp), shared by the BlockSim and the
// engine tests. The block is at rest at t = 0. It sticks while |F| <= mu m g; slides with m dv/dt = F(t) - mu m g s
// (s the sign of F when it starts); stops when v returns to 0. On a slide that starts at (t0, x0), with
// theta = omega t + phi:
//   v(t) = F0/(m omega) (cos theta0 - cos theta) - s mu g (t - t0)
//   x(t) = x0 + F0/(m omega) [(t - t0) cos theta0 - (sin theta - sin theta0) / omega] - s mu g (t - t0)^2 / 2
// phi = pi/2 gives F0 cos(omega t): |F| > mu m g at t = 0 when F0 > mu m g, so the first slide starts at t = 0.
#pragma once

#include <cmath>
#include <vector>

namespace contact_test {

struct Stop {
    double t, x;  // s, m
};

// The block's stops up to t_end (s); f0_per_m = F0 / m (m/s^2), omega (rad/s), mu (-), g (m/s^2), phase phi (rad).
// Each start and stop is found by stepping 1e-5 s and then bisecting to round-off; a slide under way at t = 0
// starts at 0.
inline std::vector<Stop> exact_stops(double f0_per_m, double omega, double t_end, double mu, double g,
                                     double phase = 0.0) {
    const double fs = mu * g;  // m/s^2
    std::vector<Stop> stops;
    double t0 = 0.0, x0 = 0.0;
    const double h = 1e-5;
    for (;;) {
        // stick until |F| > mu m g
        double t = t0;
        auto force = [&](double tt) { return f0_per_m * std::sin(omega * tt + phase); };  // F / m
        while (t < t_end && std::fabs(force(t)) <= fs) t += h;
        if (t >= t_end) break;
        double lo = t - h, hi = t;  // refine the start
        for (int i = 0; i < 60 && t > t0; ++i) {
            const double mid = 0.5 * (lo + hi);
            (std::fabs(force(mid)) <= fs ? lo : hi) = mid;
        }
        const double ts = hi;
        const double s = force(ts) > 0 ? 1.0 : -1.0;
        const double c0 = std::cos(omega * ts + phase), s0 = std::sin(omega * ts + phase);
        auto v = [&](double tt) {
            return f0_per_m / omega * (c0 - std::cos(omega * tt + phase)) - s * fs * (tt - ts);
        };
        auto x = [&](double tt) {
            const double d = tt - ts;
            return x0 + f0_per_m / omega * (d * c0 - (std::sin(omega * tt + phase) - s0) / omega) - 0.5 * s * fs * d * d;
        };
        double te = ts + h;
        while (te < t_end && v(te) * s > 0) te += h;
        if (te >= t_end) break;
        lo = te - h, hi = te;
        for (int i = 0; i < 60; ++i) {
            const double mid = 0.5 * (lo + hi);
            (v(mid) * s > 0 ? lo : hi) = mid;
        }
        t0 = hi;
        x0 = x(hi);
        stops.push_back({t0, x0});
    }
    return stops;
}

}  // namespace contact_test
