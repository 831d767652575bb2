// tests/core/test_node_update.cpp: the node update kernel alone (fdem/node_update.hpp) on hand-made arrays: the
// central-difference update and its books for free, damped and held DOFs, and the same bits on 1, 2 and 4 threads.
#include <catch2/catch.hpp>

#include <omp.h>

#include <cmath>
#include <cstring>
#include <random>
#include <tuple>
#include <vector>

#include "fdem/node_update.hpp"

namespace {

// n plain nodes (no triangles: every force is in f_mod or f_ext), all DOFs free unless set.
struct Nodes {
    int n;
    std::vector<int> inc_ptr;
    std::vector<double> mass, grav_mass, inv_mass, f_ext, f_mod, dof_vel, reaction, x, v;
    std::vector<unsigned char> loaded;
    std::vector<std::uint8_t> kind;
    explicit Nodes(int nodes, double m)
        : n(nodes), inc_ptr(nodes + 1, 0), mass(nodes, m), grav_mass(nodes, m), inv_mass(nodes, 1 / m),
          f_ext(2 * nodes, 0.0), f_mod(2 * nodes, 0.0), dof_vel(2 * nodes, 0.0), reaction(2 * nodes, 0.0),
          x(2 * nodes, 0.0), v(2 * nodes, 0.0), loaded(nodes, 0), kind(2 * nodes, 0) {}
    fdem::NodeUpdate args(double dt, double alpha, double gy) {
        fdem::NodeUpdate a;
        a.n_units = n;
        a.inc_ptr = inc_ptr.data();
        a.mass = mass.data(), a.grav_mass = grav_mass.data(), a.inv_mass = inv_mass.data();
        a.f_ext = f_ext.data(), a.loaded = loaded.data(), a.f_mod = f_mod.data(), a.reset_fmod = true;
        a.dof_kind = kind.data(), a.dof_velocity = dof_vel.data(), a.reaction = reaction.data();
        a.x = x.data(), a.v = v.data();
        a.dt = a.dtv = dt, a.local_damping = alpha, a.gy = gy;
        return a;
    }
};

}  // namespace

TEST_CASE("node update kernel: free, damped and held DOFs move and book as central differences say", "[unit]") {
    const double dt = 1e-3, m = 2.0, g = -9.81;
    Nodes s(3, m);
    // node 0: a module force (1, 0) N from rest; node 1: an applied load (0, 4) N moving at (0.5, 0); node 2: x held
    s.f_mod[0] = 1.0;
    s.f_ext[3] = 4.0, s.loaded[1] = 1;
    s.v[2] = 0.5;
    s.kind[4] = 1;
    s.x[4] = 0.25;
    std::vector<fdem::NodeBlockSums> sums(1);
    fdem::update_nodes(s.args(dt, 0.0, g), sums);
    // v^{n+1/2} = v^{n-1/2} + dt f / m, x^{n+1} = x^n + dt v^{n+1/2}
    CHECK(s.v[0] == Approx(dt * 1.0 / m).epsilon(1e-15));
    CHECK(s.v[1] == Approx(dt * g).epsilon(1e-15));
    CHECK(s.x[0] == Approx(dt * dt * 1.0 / m).epsilon(1e-15));
    CHECK(s.v[2] == 0.5);  // no force along x on node 1
    CHECK(s.v[3] == Approx(dt * (4.0 + m * g) / m).epsilon(1e-15));
    // node 2's x is held: v stays 0, x stays, its reaction is m (0 - 0) / dt - f = 0 (no force along x)
    CHECK(s.v[4] == 0.0);
    CHECK(s.x[4] == 0.25);
    CHECK(s.reaction[4] == 0.0);
    CHECK(s.f_mod[0] == 0.0);  // reset for the next step
    // books: work dt (f_ext + m g) . vbar over the free DOFs (node 0's module force is internal), K^n = 1/2 m v v'
    const double work = dt * (m * g) * 0.5 * (0 + s.v[1]) + dt * (4.0 + m * g) * 0.5 * (0 + s.v[3]) +
                        dt * (m * g) * 0.5 * (0 + s.v[5]);
    CHECK(sums[0].work == Approx(work).epsilon(1e-12));
    CHECK(sums[0].kinetic == Approx(0.5 * m * 0.5 * 0.5).epsilon(1e-15));
    CHECK(sums[0].bad == -1);

    // local damping: -alpha |f| sign(v) against the motion of node 1 along x, pushed forward by 1 N
    Nodes d(1, m);
    d.v[0] = 0.5, d.f_mod[0] = 1.0;
    fdem::update_nodes(d.args(dt, 0.8, 0.0), sums);
    CHECK(d.v[0] == Approx(0.5 + dt * (1.0 - 0.8) / m).epsilon(1e-15));
    CHECK(sums[0].damping == Approx(dt * 0.8 * 0.5 * (0.5 + d.v[0])).epsilon(1e-12));

    // a non-finite force is reported by node
    Nodes bad(2, m);
    bad.f_mod[2] = std::nan("");
    fdem::update_nodes(bad.args(dt, 0.0, 0.0), sums);
    CHECK(sums[0].bad == 1);
}

TEST_CASE("node update kernel: across a change of step the books take the work of the positions", "[unit]") {
    // A free node under a constant load F with local damping alpha (the damping force -alpha F while it moves up),
    // three steps of h1, then h2: at the change the velocity update spans (h1 + h2) / 2 and the work is F over
    // (x^{n+1} - x^{n-1}) / 2. The loads' work and the damping are then exact: F and alpha F times the distance
    // between the positions the books stand at (dt vbar at the change would be off by F v^{n-1/2} (h1 - h2) / 2,
    // 10 % here). K^n = m v^{n-1/2} v^{n+1/2} / 2 then differs from the net work by the leapfrog's second-order term
    // (h1 - h2) / (4 hbar) m |dv|^2 of the changing step, dv its velocity change (node_update.hpp).
    const double m = 2.0, F = 3.0, alpha = 0.5, h1 = 1e-3, h2 = 4e-4;
    Nodes s(1, m);
    s.f_ext[1] = F, s.loaded[0] = 1;
    s.v[1] = 0.2;
    std::vector<fdem::NodeBlockSums> sums(1);
    double W = 0, D = 0, dv_change = 0;
    std::vector<double> y, Wt, Dt, K;
    for (int j = 0; j < 6; ++j) {
        const double h = j < 3 ? h1 : h2, before = j == 3 ? h1 : h;
        fdem::NodeUpdate a = s.args(h, alpha, 0.0);
        a.dtv = 0.5 * (before + h), a.dt_before = before;
        y.push_back(s.x[1]);
        const double v0 = s.v[1];
        fdem::update_nodes(a, sums);
        if (j == 3) dv_change = s.v[1] - v0;
        W += sums[0].work, D += sums[0].damping;
        Wt.push_back(W - sums[0].work_half), Dt.push_back(D - sums[0].damping_half), K.push_back(sums[0].kinetic);
    }
    const double dy = y[5] - y[0];
    CHECK(Wt[5] - Wt[0] == Approx(F * dy).epsilon(1e-12));
    CHECK(Dt[5] - Dt[0] == Approx(alpha * F * dy).epsilon(1e-12));
    const double hbar = 0.5 * (h1 + h2);
    CHECK(dv_change == Approx(hbar * (1 - alpha) * F / m).epsilon(1e-12));
    CHECK(K[5] - K[0] == Approx((1 - alpha) * F * dy + (h1 - h2) / (4 * hbar) * m * dv_change * dv_change).epsilon(1e-12));
}

TEST_CASE("node update kernel: the same bits on 1, 2 and 4 threads", "[unit]") {
    const int n = 5000, blocks = (n + 255) / 256;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-1, 1);
    Nodes ref(n, 1.5);
    for (int i = 0; i < 2 * n; ++i) ref.v[i] = u(rng), ref.f_mod[i] = u(rng), ref.x[i] = u(rng);
    for (int k = 0; k < n; k += 7) ref.kind[2 * k] = 2, ref.dof_vel[2 * k] = 0.1;
    auto run = [&](int threads) {
        Nodes s = ref;
        const int saved = omp_get_max_threads();
        omp_set_num_threads(threads);
        std::vector<fdem::NodeBlockSums> sums(blocks);
        for (int step = 0; step < 3; ++step) {
            for (int i = 0; i < 2 * n; ++i) s.f_mod[i] = std::sin(s.x[i]);
            fdem::update_nodes(s.args(1e-3, 0.3, -9.81), sums);
        }
        omp_set_num_threads(saved);
        double total = 0;
        for (const auto& b : sums) total += b.work + b.damping + b.kinetic;
        return std::make_pair(s, total);
    };
    const auto one = run(1);
    for (int t : {2, 4}) {
        const auto other = run(t);
        CHECK(std::memcmp(one.first.x.data(), other.first.x.data(), one.first.x.size() * sizeof(double)) == 0);
        CHECK(std::memcmp(one.first.v.data(), other.first.v.data(), one.first.v.size() * sizeof(double)) == 0);
        CHECK(std::memcmp(&one.second, &other.second, sizeof(double)) == 0);
    }
}

TEST_CASE("node update kernel: two plain nodes at a time give the bits of one at a time", "[unit]") {
    // Odd blocks, nodes with 0-3 triangles, loads, fixed and prescribed DOFs, and each damping variant: the pairs
    // (AVX where the CPU has it) against lanes = 1 (unit by unit).
    const int n = 1001, blocks = (n + 255) / 256, nt = 700;
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1, 1);
    std::uniform_int_distribution<int> pick(0, 99);
    Nodes ref(n, 1.0);
    std::vector<double> tf(6 * nt), vref(2 * n);
    std::vector<int> inc_idx;
    for (int k = 0; k < n; ++k) {
        ref.mass[k] = 1 + 0.5 * u(rng), ref.grav_mass[k] = 0.7 * ref.mass[k], ref.inv_mass[k] = 1 / ref.mass[k];
        const int c = pick(rng) % 4;
        for (int j = 0; j < c; ++j) inc_idx.push_back(pick(rng) * 3 * nt / 100 % (3 * nt));
        ref.inc_ptr[k + 1] = static_cast<int>(inc_idx.size());
        if (pick(rng) < 10) ref.loaded[k] = 1, ref.f_ext[2 * k] = u(rng), ref.f_ext[2 * k + 1] = u(rng);
        for (int c2 = 0; c2 < 2; ++c2) {
            const int r = pick(rng);
            ref.kind[2 * k + c2] = r < 3 ? 1 : (r < 6 ? 2 : 0);
            ref.dof_vel[2 * k + c2] = 0.1 * u(rng);
        }
    }
    ref.kind[2 * 600] = ref.kind[2 * 600 + 1] = 0;  // (free: its non-finite force below makes a non-finite velocity)
    for (double& t : tf) t = u(rng);
    for (int i = 0; i < 2 * n; ++i) ref.v[i] = u(rng), ref.x[i] = u(rng), vref[i] = 0.5 * u(rng);
    for (int variant = 0; variant < 4; ++variant) {
        const bool filter = variant & 1, mass_damping = variant & 2;
        auto run = [&](int lanes, bool nan) {
            Nodes s = ref;
            std::vector<double> vr = vref;
            std::vector<fdem::NodeBlockSums> sums(blocks);
            for (int step = 0; step < 3; ++step) {
                for (int i = 0; i < 2 * n; ++i) s.f_mod[i] = std::sin(3 * s.x[i]);
                if (nan && step == 2) s.f_mod[2 * 600 + 1] = std::nan("");
                fdem::NodeUpdate a = s.args(1e-3, 0.3, -9.81);
                a.gx = 0.5;
                a.dtv = 1.1e-3;
                a.tri_forces = tf.data(), a.inc_idx = inc_idx.data();
                if (filter) a.v_ref = vr.data(), a.wf = 0.05;
                if (mass_damping) a.mass_damping = 20.0, a.hm = 0.5 * a.dtv * a.mass_damping;
                a.lanes = lanes;
                fdem::update_nodes(a, sums);
            }
            return std::make_tuple(s, vr, sums);
        };
        const auto one = run(1, false), two = run(0, false);
        const Nodes& a = std::get<0>(one);
        const Nodes& b = std::get<0>(two);
        INFO("variant " << variant);
        auto same = [](const std::vector<double>& p, const std::vector<double>& q) {
            return std::memcmp(p.data(), q.data(), p.size() * sizeof(double)) == 0;
        };
        CHECK(same(a.x, b.x));
        CHECK(same(a.v, b.v));
        CHECK(same(a.reaction, b.reaction));
        CHECK(same(a.f_mod, b.f_mod));
        CHECK(same(std::get<1>(one), std::get<1>(two)));
        for (int bl = 0; bl < blocks; ++bl) {
            const fdem::NodeBlockSums &p = std::get<2>(one)[bl], &q = std::get<2>(two)[bl];
            const std::vector<double> bp{p.work, p.damping, p.unbalanced, p.scale, p.kinetic, p.work_half,
                                         p.damping_half, p.mass, p.mass_half, p.v2};
            const std::vector<double> bq{q.work, q.damping, q.unbalanced, q.scale, q.kinetic, q.work_half,
                                         q.damping_half, q.mass, q.mass_half, q.v2};
            CHECK(same(bp, bq));
            CHECK(p.bad == -1);
            CHECK(q.bad == -1);
        }
        // a non-finite velocity: the same node reported
        const auto one_nan = run(1, true), two_nan = run(0, true);
        CHECK(std::get<2>(one_nan)[2].bad == 600);
        CHECK(std::get<2>(two_nan)[2].bad == 600);
    }
}
