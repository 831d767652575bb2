// tests/contact/test_contact_dynamics.cpp: closed-form dynamics of blocks in contact, integrated with the test-only
// leap-frog of block_sim.hpp (fdem/README.md 'Time step') until the engine's integrator exists.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "block_sim.hpp"
#include "mesh/gmsh_source.hpp"

using contact_test::BlockSim;
using fdem::contact::ContactLaw;
using fdem::contact::ContactLaws;

namespace {

constexpr double kG = 9.81;        // m/s^2
constexpr double kDeg = M_PI / 180.0;

ContactLaws dry_joint(double kn, double ks, double phi_deg) {
    ContactLaws laws(1);
    ContactLaw law = ContactLaw::stiffness(kn, ks, phi_deg);
    law.name = "dry joint";
    laws.set_interface(0, 0, law);
    return laws;
}

ContactLaws dry_joint_mu(double kn, double ks, double mu) {
    ContactLaws laws(1);
    ContactLaw law;
    law.name = "dry joint";
    law.k_n = kn;
    law.k_s = ks;
    law.mu = mu;
    laws.set_interface(0, 0, law);
    return laws;
}

// Runs `seconds` of simulated time.
void run(BlockSim& s, double dt, double seconds) {
    const long n = std::lround(seconds / dt);
    for (long i = 0; i < n; ++i) s.step(dt);
}

double max_node_shift(const BlockSim& s, const std::vector<double>& x0, int first_body) {
    double d = 0.0;
    for (int k = s.body_first_node[first_body]; k < s.n_nodes(); ++k)
        d = std::max(d, std::hypot(s.x[2 * k] - x0[2 * k], s.x[2 * k + 1] - x0[2 * k + 1]));
    return d;
}

}  // namespace

TEST_CASE("A block resting on a base under gravity settles and then drifts < 1e-6 m over 1 s", "[regression]") {
    BlockSim s;
    s.add_block(-0.5, -0.1, 1.2, 0.1, 12, 1);  // base (fixed)
    s.add_block(0.0, 0.0, 0.2, 0.1, 2, 1);
    s.finish(dry_joint(5e9, 5e9, 30.0));
    s.fix_body(0);
    const double dt = 0.5 * s.stable_dt();
    s.alpha = 0.7;
    run(s, dt, 0.3);
    s.alpha = 0.0;
    const std::vector<double> x0 = s.x;
    double cx0, cy0, cx, cy;
    s.body_cm(1, cx0, cy0);
    // overlap: depth of the block's bottom row of nodes (the first 3 nodes of body 1) below the base top y = 0
    const int k0 = s.body_first_node[1];
    const double overlap = -(s.x[2 * k0 + 1] + s.x[2 * k0 + 3] + s.x[2 * k0 + 5]) / 3.0;
    run(s, dt, 1.0);
    s.body_cm(1, cx, cy);
    const double shift = max_node_shift(s, x0, 1);
    std::printf("[rest] dt %.3g s, settled overlap %.3g m (expected rho g h / k_n = %.3g), drift over 1 s: "
                "centre %.3g m, max node %.3g m\n",
                dt, overlap, 2000 * kG * 0.1 / 5e9, std::hypot(cx - cx0, cy - cy0), shift);
    CHECK(shift < 1e-6);
    CHECK(overlap == Approx(2000 * kG * 0.1 / 5e9).epsilon(0.02));  // static overlap rho g h / k_n
}

TEST_CASE("A stack of 10 blocks stands for 2 s, no block moving more than 1e-6 m after settling", "[regression]") {
    BlockSim s;
    s.add_block(-0.3, -0.1, 0.8, 0.1, 8, 1);
    for (int i = 0; i < 10; ++i) s.add_block(0.0 + 0.01 * (i % 2), 0.1 * i, 0.2, 0.1, 2, 1);  // slightly staggered
    s.finish(dry_joint(5e9, 5e9, 30.0));
    s.fix_body(0);
    const double dt = 0.5 * s.stable_dt();
    s.alpha = 0.7;
    run(s, dt, 0.5);
    s.alpha = 0.0;
    const std::vector<double> x0 = s.x;
    run(s, dt, 2.0);
    const double shift = max_node_shift(s, x0, 1);
    std::printf("[stack] 10 blocks, dt %.3g s, max node displacement over 2 s after settling: %.3g m\n", dt, shift);
    CHECK(shift < 1e-6);
}

TEST_CASE("A block launched at v0 on a flat base stops at v0^2 / (2 mu g) within 2 %", "[regression]") {
    for (double mu : {0.3, 0.6}) {
        BlockSim s;
        s.add_block(-0.2, -0.1, 1.0, 0.1, 20, 1);
        s.add_block(0.0, 0.0, 0.2, 0.1, 4, 2);
        s.finish(dry_joint_mu(5e9, 5e9, mu));
        s.fix_body(0);
        const double dt = 0.5 * s.stable_dt();
        s.alpha = 0.7;
        run(s, dt, 0.1);
        s.alpha = 0.0;
        const double v0 = 1.0;
        for (int k = s.body_first_node[1]; k < s.body_last_node[1]; ++k) s.v[2 * k] += v0;
        double cx0, cy0, cx, cy, vx, vy;
        s.body_cm(1, cx0, cy0);
        const double d0 = s.cs->friction_dissipation(), k0 = s.kinetic(), e0 = s.elastic(false);
        const double c0 = s.cs->elastic_energy();
        double t = 0.0;
        for (; t < 2.0; t += dt) {
            s.step(dt);
            s.body_velocity(1, vx, vy);
            if (vx <= 0.0) break;
        }
        s.body_cm(1, cx, cy);
        const double expected = v0 * v0 / (2.0 * mu * kG);
        std::printf("[slide] mu %.2f: stop distance %.5f m, expected %.5f m (error %.2f %%), stop time %.4f s "
                    "(expected %.4f s)\n",
                    mu, cx - cx0, expected, 100.0 * (cx - cx0 - expected) / expected, t, v0 / (mu * kG));
        CHECK(cx - cx0 == Approx(expected).epsilon(0.02));
        // energy balance: the friction dissipation equals the kinetic energy lost, 1/2 M v0^2 (M = 4 kg)
        const double dissipated = s.cs->friction_dissipation() - d0;
        const double lost = k0 - s.kinetic() + (e0 - s.elastic(false)) + (c0 - s.cs->elastic_energy());
        std::printf("[slide] mu %.2f: friction dissipation %.5f J, kinetic+elastic energy lost %.5f J (1/2 M v0^2 = "
                    "%.5f J)\n",
                    mu, dissipated, lost, 0.5 * 4.0 * v0 * v0);
        CHECK(dissipated == Approx(lost).epsilon(0.01));
        CHECK(dissipated == Approx(0.5 * 4.0 * v0 * v0).epsilon(0.02));
    }
}

namespace {

// A block on a base under gravity tilted by theta (the base stays horizontal, gravity rotates: the same
// problem as an incline). Settles at theta = 0 with damping, rotates gravity to theta_ramp in ramp_s seconds with
// damping (quasi-static, no overshoot), then runs undamped.
struct Incline {
    BlockSim s;
    double dt = 0.0;
    Incline(double b, double h, int nx, int ny, const ContactLaws& laws) {
        s.add_block(-0.3, -0.1, 2.0, 0.1, 20, 1);
        s.add_block(0.0, 0.0, b, h, nx, ny);
        s.finish(laws);
        s.fix_body(0);
        dt = 0.5 * s.stable_dt();
    }
    void set_angle(double theta) {
        s.gx = kG * std::sin(theta);
        s.gy = -kG * std::cos(theta);
    }
    void ramp(double theta, double seconds) {
        s.alpha = 0.7;
        run(s, dt, 0.1);
        const long n = std::lround(seconds / dt);
        for (long i = 1; i <= n; ++i) {
            const double r = static_cast<double>(i) / n;
            set_angle(theta * (3 * r * r - 2 * r * r * r));  // smooth step
            s.step(dt);
        }
        run(s, dt, 0.05);
        s.alpha = 0.0;
    }
};

}  // namespace

TEST_CASE("A block on an incline sticks below phi - 1 deg and slides above phi + 1 deg at g (sin - mu cos)",
          "[regression]") {
    const double phi = 30.0;
    const double mu = std::tan(phi * kDeg);
    SECTION("sticks") {
        Incline inc(0.2, 0.1, 4, 2, dry_joint(5e9, 5e9, phi));
        const double theta = (phi - 1.0) * kDeg;
        inc.ramp(theta, 0.3);
        double cx0, cy0, cx, cy;
        inc.s.body_cm(1, cx0, cy0);
        run(inc.s, inc.dt, 0.5);
        inc.s.body_cm(1, cx, cy);
        std::printf("[incline] theta = phi - 1 deg: slip over 0.5 s = %.3g m\n", cx - cx0);
        CHECK(std::fabs(cx - cx0) < 1e-6);
    }
    SECTION("slides") {
        for (double dtheta : {1.0, 5.0}) {
            Incline inc(0.2, 0.1, 4, 2, dry_joint(5e9, 5e9, phi));
            const double theta = (phi + dtheta) * kDeg;
            inc.ramp(theta, 0.3);
            // least-squares fit of x_cm(t) = c0 + c1 t + c2 t^2 over 0.5 s
            const int n_samples = 200;
            const long per = std::lround(0.5 / n_samples / inc.dt);
            double S[5] = {0, 0, 0, 0, 0}, R[3] = {0, 0, 0};
            for (int i = 0; i < n_samples; ++i) {
                run(inc.s, inc.dt, per * inc.dt);
                double cx, cy;
                inc.s.body_cm(1, cx, cy);
                const double t = (i + 1) * per * inc.dt;
                double tp = 1.0;
                for (int p = 0; p < 5; ++p, tp *= t) S[p] += tp;
                R[0] += cx;
                R[1] += cx * t;
                R[2] += cx * t * t;
            }
            // normal equations 3x3 (Cramer)
            const double M[3][3] = {{S[0], S[1], S[2]}, {S[1], S[2], S[3]}, {S[2], S[3], S[4]}};
            auto det3 = [](const double A[3][3]) {
                return A[0][0] * (A[1][1] * A[2][2] - A[1][2] * A[2][1]) -
                       A[0][1] * (A[1][0] * A[2][2] - A[1][2] * A[2][0]) +
                       A[0][2] * (A[1][0] * A[2][1] - A[1][1] * A[2][0]);
            };
            double M2[3][3];
            for (int r = 0; r < 3; ++r)
                for (int c = 0; c < 3; ++c) M2[r][c] = c == 2 ? R[r] : M[r][c];
            const double a = 2.0 * det3(M2) / det3(M);
            const double expected = kG * (std::sin(theta) - mu * std::cos(theta));
            std::printf("[incline] theta = phi + %.0f deg: acceleration %.5f m/s^2, expected %.5f (error %.2f %%)\n",
                        dtheta, a, expected, 100.0 * (a - expected) / expected);
            CHECK(a == Approx(expected).epsilon(0.03));
        }
    }
}

namespace {

// Tilting table: gravity rotates at omega (rad/s) from theta0; returns the angle (deg) of the first event and
// whether it was overturning (rotation > 0.01 rad) rather than sliding (slip > 0.5 mm).
double tilt_until_event(double b, double h, double mu, double theta0_deg, bool& overturned) {
    // A stiff joint: a compliant one lets the corner sink and tips the block earlier (by ~0.9 deg at 5e9 Pa/m).
    Incline inc(b, h, 2, 4, dry_joint_mu(2e10, 2e10, mu));
    inc.ramp(theta0_deg * kDeg, 0.3);
    double cx0, cy0;
    inc.s.body_cm(1, cx0, cy0);
    const double ref = inc.s.body_ref_angle(1);
    const double omega = 1.0 * kDeg;  // rad/s
    double theta = theta0_deg * kDeg;
    for (double t = 0.0; t < 6.0; t += inc.dt) {
        theta = theta0_deg * kDeg + omega * t;
        inc.set_angle(theta);
        inc.s.step(inc.dt);
        double cx, cy;
        inc.s.body_cm(1, cx, cy);
        const double rot = std::fabs(inc.s.body_angle(1, ref));
        // slip: motion of the bottom-left node along the base
        const int k = inc.s.body_first_node[1];
        static_cast<void>(cy);
        if (rot > 0.01) {
            overturned = true;
            return theta / kDeg;
        }
        if (inc.s.x[2 * k] - 0.0 > 5e-4 && rot < 0.005) {
            overturned = false;
            return theta / kDeg;
        }
    }
    overturned = false;
    return 1e9;
}

}  // namespace

TEST_CASE("A block on a slowly tilting base overturns at atan(b/h) if mu > b/h, else slides at atan(mu)",
          "[regression]") {
    const double b = 0.1, h = 0.2;
    bool over = false;
    const double a1 = tilt_until_event(b, h, 0.7, std::atan(b / h) / kDeg - 2.0, over);
    std::printf("[tilt] mu 0.7 > b/h: event at %.2f deg (%s), expected overturning at %.2f deg\n", a1,
                over ? "overturning" : "sliding", std::atan(b / h) / kDeg);
    CHECK(over);
    CHECK(a1 == Approx(std::atan(b / h) / kDeg).margin(1.0));
    const double a2 = tilt_until_event(b, h, 0.3, std::atan(0.3) / kDeg - 2.0, over);
    std::printf("[tilt] mu 0.3 < b/h: event at %.2f deg (%s), expected sliding at %.2f deg\n", a2,
                over ? "overturning" : "sliding", std::atan(0.3) / kDeg);
    CHECK_FALSE(over);
    CHECK(a2 == Approx(std::atan(0.3) / kDeg).margin(1.0));
}

TEST_CASE("A frictionless undamped collision of two elastic blocks conserves momentum and energy", "[regression]") {
    for (int law_kind = 0; law_kind < 2; ++law_kind) {  // k_n (distance potential) and p_n (Munjiza potential)
        BlockSim s;
        s.gx = s.gy = 0.0;
        s.add_block(0.0, 0.0, 0.2, 0.1, 4, 2);
        s.add_block(0.25, 0.03, 0.2, 0.1, 4, 2);
        if (law_kind == 0) {
            s.finish(dry_joint_mu(5e9, 5e9, 0.0));
        } else {
            ContactLaws laws(1);
            laws.set_interface(0, 0, ContactLaw::penalty(5e7, 0.0));
            s.finish(laws);
        }
        const double dt = 0.25 * s.stable_dt();
        for (int k = s.body_first_node[0]; k < s.body_last_node[0]; ++k) s.v[2 * k] = 1.0;
        for (int k = s.body_first_node[1]; k < s.body_last_node[1]; ++k) s.v[2 * k] = -0.5;
        auto momentum = [&](double& px, double& py, double& scale) {
            px = py = scale = 0.0;
            for (int k = 0; k < s.n_nodes(); ++k) {
                px += s.m[2 * k] * s.v[2 * k];
                py += s.m[2 * k + 1] * s.v[2 * k + 1];
                scale += s.m[2 * k] * std::hypot(s.v[2 * k], s.v[2 * k + 1]);
            }
        };
        double px0, py0, sc0;
        momentum(px0, py0, sc0);
        const double e0 = s.kinetic() + s.elastic(false);
        double max_contact = 0.0;
        for (double t = 0.0; t < 0.1; t += dt) {
            s.step(dt);
            max_contact = std::max(max_contact, s.cs->elastic_energy());
        }
        double px, py, sc;
        momentum(px, py, sc);
        const double e1 = s.kinetic() + s.elastic(false) + s.cs->elastic_energy();
        double v0x, v0y, v1x, v1y;
        s.body_velocity(0, v0x, v0y);
        s.body_velocity(1, v1x, v1y);
        std::printf("[collision] %s: momentum change %.3g (relative %.3g), energy change %.4f %% (peak contact energy %.3g J "
                    "of %.3g J), velocities after: %.4f %.4f m/s\n",
                    law_kind == 0 ? "k_n law" : "p_n law", std::hypot(px - px0, py - py0),
                    std::hypot(px - px0, py - py0) / sc0, 100.0 * (e1 - e0) / e0,
                    max_contact, e0, v0x, v1x);
        CHECK(max_contact > 0.1 * e0);  // they did collide
        CHECK(v1x > 0.0);
        CHECK(std::hypot(px - px0, py - py0) <= 1e-10 * sc0);
        CHECK(std::fabs(e1 - e0) < 0.01 * e0);
    }
}

TEST_CASE("Two stiff blocks meeting through an inelastic contact part at e times their approach speed, losing (1 - e^2)",
          "[regression]") {
    // Walton & Braun (1986): loaded along k, unloaded along k / e^2, a contact gives back e^2 of the work it took, so
    // two rigid bodies separate at e times the speed they met with. Blocks 100 times stiffer than their contact (E t
    // / L = 1e11 Pa x 0.1 m / 0.2 m against k_n L_c t = 5e8 Pa/m x 0.1 m x 0.1 m) come close to rigid.
    for (const double e : {1.0, 0.5, 0.2}) {
        BlockSim s;
        s.gx = s.gy = 0.0;
        s.E = 1e11;
        s.add_block(0.0, 0.0, 0.2, 0.1, 4, 2);
        s.add_block(0.25, 0.0, 0.2, 0.1, 4, 2);
        ContactLaws laws(1);
        ContactLaw law = ContactLaw::stiffness(5e8, 5e8, 0.0);
        law.name = "impact";
        law.restitution = e;
        laws.set_interface(0, 0, law);
        s.finish(laws);
        const double dt = 0.5 * s.stable_dt();
        for (int k = s.body_first_node[0]; k < s.body_last_node[0]; ++k) s.v[2 * k] = 1.0;
        for (int k = s.body_first_node[1]; k < s.body_last_node[1]; ++k) s.v[2 * k] = -1.0;
        const double k0 = s.kinetic();
        run(s, dt, 0.12);
        double v0x, v0y, v1x, v1y;
        s.body_velocity(0, v0x, v0y);
        s.body_velocity(1, v1x, v1y);
        const double ratio = (v1x - v0x) / 2.0;  // separation speed over approach speed
        // Kinetic energy of the bodies' mean motion, and what the contact took (dissipated + still held).
        const double half_m = 0.5 * 2000.0 * 0.1 * 0.02;  // 0.5 rho t (w h) per block, kg
        const double k_mean = half_m * (v0x * v0x + v1x * v1x);
        const double taken = s.cs->dashpot_dissipation();
        std::printf("[restitution] e %.2f: separation / approach %.4f, kinetic kept %.4f (e^2 %.4f), contact dissipated "
                    "%.4f of it, energy change %.2e of the initial\n",
                    e, ratio, k_mean / k0, e * e, taken / k0, (s.kinetic() + s.elastic(false) + taken - k0) / k0);
        CHECK(s.cs->elastic_energy() == 0.0);  // apart again
        CHECK(ratio == Approx(e).epsilon(0.03));
        CHECK(std::fabs(s.kinetic() + s.elastic(false) + taken - k0) < 0.005 * k0);  // the books close
        if (e < 1.0) CHECK(taken / k0 == Approx(1.0 - e * e).epsilon(0.05));
        else CHECK(taken == 0.0);
    }
}

TEST_CASE("Two blocks pressed through a dry joint of stiffness k_n close by q / k_n at 50, 25, 12.5 mm",
          "[convergence]") {
    const double kn = 1e10, q = 1e6, W = 0.2, H = 0.1;
    for (double size : {0.05, 0.025, 0.0125}) {
        BlockSim s;
        s.E = 3e10;
        s.rho = 2500.0;
        const fdem::mesh::Mesh lower = fdem::mesh::mesh_rectangle(0.0, 0.0, W, H, size);
        const fdem::mesh::Mesh upper = fdem::mesh::mesh_rectangle(0.0, H, W, H, size * 0.9);
        s.add_mesh(lower);
        const int off = s.n_nodes();
        s.add_mesh(upper);
        s.gy = 0.0;
        s.finish(dry_joint(kn, kn, 35.0));
        for (int k : lower.find_group("bottom")->nodes) s.fixed[2 * k] = s.fixed[2 * k + 1] = 1;
        for (const auto& e : upper.find_group("top")->edges) {
            const int a = e[0] + off, c = e[1] + off;
            const double len = std::fabs(s.x[2 * a] - s.x[2 * c]);
            s.fext[2 * a + 1] -= 0.5 * q * s.t * len;
            s.fext[2 * c + 1] -= 0.5 * q * s.t * len;
        }
        const double dt = 0.5 * s.stable_dt();
        s.alpha = 0.8;
        run(s, dt, 0.03);
        // closure: lower top surface interpolated at each node of the upper bottom surface
        std::map<double, double> top;
        for (int k : lower.find_group("top")->nodes) top[s.x[2 * k]] = s.x[2 * k + 1];
        double sum = 0.0;
        int n = 0;
        for (int k0 : upper.find_group("bottom")->nodes) {
            const int k = k0 + off;
            const double xk = s.x[2 * k];
            auto hi = top.lower_bound(xk);
            if (hi == top.begin() || hi == top.end()) continue;
            auto lo = std::prev(hi);
            const double y = lo->second + (hi->second - lo->second) * (xk - lo->first) / (hi->first - lo->first);
            sum += y - s.x[2 * k + 1];
            ++n;
        }
        const double closure = sum / n;
        std::printf("[pressed] mesh %.4f m: %d triangles, closure %.4g m, q/k_n = %.4g m (error %.2f %%), "
                    "kinetic energy at the end %.3g J\n",
                    size, s.n_tri(), closure, q / kn, 100.0 * (closure - q / kn) / (q / kn), s.kinetic());
        CHECK(closure == Approx(q / kn).epsilon(0.05));
    }
}
