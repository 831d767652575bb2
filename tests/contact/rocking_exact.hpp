// tests/contact/rocking_exact.hpp: the rocking of a rigid block on a rigid base (Housner 1963), shared by the
// engine test (test_rocking.cpp) and the study driver (rocking_study/study.cpp).
//
// A rigid body of mass m, moment of inertia I_G about its centre of mass G, rocks on two pivots, its bottom corners
// (or the outer corners of two pads), at b either side of G and h below it: alpha = atan(b / h), R = sqrt(b^2 + h^2).
// Between impacts it turns about one pivot, I_B theta'' = -m g R sin(alpha - |theta|) sign(theta), I_B = I_G + m R^2
// (theta the tilt, 0 upright). Energy in flight: omega^2 = 2 p^2 (cos(alpha - |theta|) - cos(alpha - a)), p^2 =
// m g R / I_B, a the amplitude (the tilt at rest). From rest at a it reaches theta = 0 after
//   t_q(a) = INT_0^a dth / sqrt(2 p^2 (cos(alpha - a) - cos(alpha - th))),
// evaluated with th = a (1 - s^2), which removes the end singularity. At theta = 0 the other pivot lands. The impact
// is inelastic and its impulse acts at a point P at x_p from G towards the new pivot (Housner: at the pivot itself,
// x_p = b); the angular momentum about P is kept, so the angular velocity after the impact is r times that before:
//   r = (I_G + m (h^2 - x_p b)) / (I_G + m (h^2 + x_p b)),
// (before: turning about the old pivot, v_G = omega (-h, b); after: about the new one, v_G = omega' (-h, -b)), which
// for a rectangle on its corners (I_G = m R^2 / 3, x_p = b) is Housner's r = 1 - 1.5 sin^2(alpha). The amplitude a'
// after an impact follows from the energy: cos(alpha - a') - cos(alpha) = r^2 (cos(alpha - a) - cos(alpha)).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace contact_test {

struct RigidRocking {
    double m = 0, I_G = 0, b = 0, h = 0, g = 9.81;

    double alpha() const { return std::atan(b / h); }
    double R() const { return std::hypot(b, h); }
    double p() const { return std::sqrt(m * g * R() / (I_G + m * R() * R())); }
    // Angular-velocity ratio of an impact whose impulse acts at x_p from G (x_p = b: Housner's).
    double r(double x_p) const { return (I_G + m * (h * h - x_p * b)) / (I_G + m * (h * h + x_p * b)); }
    double quarter_time(double a) const {
        const int n = 20000;
        const double al = alpha(), pp = p();
        double t = 0.0;
        for (int i = 0; i < n; ++i) {
            const double s = (i + 0.5) / n;
            const double th = a * (1.0 - s * s);
            t += 2.0 * a * s / std::sqrt(2.0 * pp * pp * (std::cos(al - a) - std::cos(al - th))) / n;
        }
        return t;
    }
    double next_amplitude(double a, double rr) const {
        const double al = alpha();
        const double c = std::cos(al) + rr * rr * (std::cos(al - a) - std::cos(al));
        return al - std::acos(std::min(1.0, c));
    }
    // Released at rest from a0: the times of the first n impacts and the amplitudes before each (a0 first).
    void impacts(double a0, double rr, int n, std::vector<double>& t, std::vector<double>& a) const {
        t.assign(1, quarter_time(a0));
        a.assign(1, a0);
        for (int i = 1; i < n; ++i) {
            a.push_back(next_amplitude(a.back(), rr));
            t.push_back(t.back() + 2.0 * quarter_time(a.back()));
        }
    }
};

}  // namespace contact_test
