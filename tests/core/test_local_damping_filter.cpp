// Stage key local_damping_filter = tau (s): the local damping force -alpha |f| sign(v - vbar) is signed by each DOF's
// velocity relative to its exponential moving mean vbar over tau, so a steady motion is not braked and only the
// fluctuations about it are damped (a wall driven at a constant rate whose oscillation rides on the drive's
// motion; fdem/README.md 'Mass scaling and damping').
//
// CONSERVATION LAW
//   A free body of mass M pulled by a spring k whose anchor moves at a constant v from t = 0 (the spring-load test's
//   set-up, no gravity) moves as x = v t - (v / w) sin(w t), w = sqrt(k / M): a drift v with an oscillation of
//   velocity -v cos(w t) about it. A first stage runs it undamped to t1 = (pi / 2 + 20 pi) / w, where the oscillation's
//   velocity is zero and the body moves at the drift v (so the filter's mean, which starts from the current
//   velocities, starts on the drift); a second stage switches the damping on. In the anchor's frame, which is
//   inertial, the body then oscillates with the energy E_rel = M v^2 / 2 (all of it elastic at t1). The damping force
//   F_d does work F_d . w on the relative motion w and F_d . v on the drift, so its dissipation over the stage is
//       D = E_rel(t1) - E_rel(T) - v I_d,     I_d = INT_t1^T F_d dt (the damping's net impulse on the body).
//   A damping that only acts on the oscillation has I_d = 0: the drive pays for the oscillation's energy and nothing
//   more. The impulse follows from the momentum balance of the body, I_d = M (V(T) - V(t1)) - INT_t1^T F dt, with F the
//   spring force (the load monitor) and V the mass-weighted mean velocity.
//   The absolute-velocity damping of [C79] brakes the drift: while the body moves forwards (its velocity
//   v (1 - cos w t) is never negative) every damping force points backwards, the spring must pull the body with an
//   extra impulse -I_d > 0, and the oscillation keeps its amplitude (measured below).
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <string>

#include "engine_helpers.hpp"

namespace {

// support: extra text for both stages (e.g. a rigid group), appended after each stage's keys.
std::string pull_case(const std::string& damping, double duration, const std::string& support = "") {
    return testing::column_with_left_load_monitor("ldf") + R"(
[[stages]]
name = "drift"
duration = 0.6440796326794897
local_damping = 0.0
  [[stages.loads]]
  group = "left"
  spring = { component = "x", stiffness = 4.0e5, velocity = 0.01 }
)" + support + R"(
[[stages]]
name = "damped"
duration = )" + std::to_string(duration) + "\n" + damping + support;
}

struct PullResult {
    double impulse_damping = 0;  // N s, I_d
    double amplitude_end = 0;    // N, largest |F| over the last 0.1 s (the spring force's oscillation about 0)
    double damped = 0;           // J, D_damp at the end
    double balance = 0;
};

PullResult pull(const std::string& damping, const std::string& name, double duration, const std::string& support = "") {
    auto sim = testing::make_simulation(pull_case(damping, duration, support), name);
    const auto& md = sim.model();
    double M = 0;
    for (int k = 0; k < md.n_nodes(); ++k) M += md.mass[k];
    auto momentum = [&] {  // at the last half step: the sum over the steps of dt (F + F_d)
        double p = 0;
        for (int k = 0; k < md.n_nodes(); ++k) p += md.mass[k] * md.v[2 * k];
        return p;
    };
    sim.begin_stage(0);
    while (!sim.stage_finished()) sim.step();
    const double p1 = momentum(), D1 = sim.energies().damping, t1 = sim.time();
    sim.begin_stage(1);
    PullResult r;
    double impulse_spring = 0;
    while (!sim.stage_finished()) {
        sim.step();
        const double F = sim.monitor_value(0);  // the spring force at t^n, the one this step applied
        impulse_spring += sim.dt() * F;
        if (sim.time() > t1 + duration - 0.1) r.amplitude_end = std::max(r.amplitude_end, std::abs(F));
    }
    r.impulse_damping = momentum() - p1 - impulse_spring;
    const fdem::Energies e = sim.energies();
    r.damped = e.damping - D1;
    r.balance = e.balance_error();
    std::printf("[local damping filter] %s: I_d = %.4e N s (M v = %.4e N s), spring force amplitude at the end %.4e N "
                "(k v / w = %.4e N), D_damp %.4e J (M v^2 / 2 = %.4e J), balance %.2e\n",
                name.c_str(), r.impulse_damping, M * 0.01, r.amplitude_end, 4.0e5 * 0.01 / std::sqrt(4.0e5 / M), r.damped,
                0.5 * M * 0.01 * 0.01, r.balance);
    return r;
}

}  // namespace

namespace {

// The column pulled through the spring: mass (kg), anchor speed (m/s), spring (N/m), angular frequency (1/s), damped
// stage (s, 32 periods).
const double kM = 0.2 * 1.0 * 0.1 * 2000.0, kV = 0.01, kK = 4.0e5;
const double kW = std::sqrt(kK / kM);  // 100 rad/s: period 0.063 s
const double kT = 2.0;

// The checks shared by the node and the rigid-group cases: absolute against filtered damping.
void check_absolute_against_filtered(const PullResult& absolute, const PullResult& filtered) {
    const double M = kM, v = kV, k = kK, w = kW;
    // The filtered damping takes the oscillation out; the absolute one does not touch it (the velocity never
    // changes sign, so its force is a drag of constant direction that does no work on the oscillation).
    CHECK(filtered.amplitude_end < 1e-3 * k * v / w);
    CHECK(absolute.amplitude_end > 0.95 * k * v / w);
    // The absolute one brakes the drift with many times the drift's momentum; the filtered one's net impulse is
    // a small fraction of that (the mean lags the decaying oscillation by a little).
    CHECK(absolute.impulse_damping < -10 * M * v);
    CHECK(std::abs(filtered.impulse_damping) < 0.02 * std::abs(absolute.impulse_damping));
    // Dissipation: the oscillation's energy M v^2 / 2 minus what is left, plus the drag work -v I_d.
    CHECK(filtered.damped == Approx(0.5 * M * v * v - filtered.impulse_damping * v).epsilon(0.01));
    CHECK(absolute.damped == Approx(-absolute.impulse_damping * v).epsilon(0.01));  // its oscillation keeps E_rel
    CHECK(filtered.balance < 1e-3);
    CHECK(absolute.balance < 1e-3);
}

}  // namespace

TEST_CASE("local damping filter: the damping dissipates the oscillation about a steady drift and does not brake the drift",
          "[unit][damping]") {
    const PullResult none = pull("local_damping = 0.0\n", "ldf_none", kT);
    const PullResult absolute = pull("local_damping = 0.2\n", "ldf_absolute", kT);
    const PullResult filtered = pull("local_damping = 0.2\nlocal_damping_filter = 0.3\n", "ldf_filtered", kT);

    // Undamped: no damping impulse, the oscillation keeps its amplitude k v / w.
    CHECK(none.impulse_damping == Approx(0.0).margin(1e-12));
    CHECK(none.amplitude_end > 0.95 * kK * kV / kW);
    check_absolute_against_filtered(absolute, filtered);
}

TEST_CASE("local damping filter: the same on a rigid group (the whole column moving as one in x)", "[unit][damping]") {
    // The rigid group's damping acts on its shared velocity (Simulation::step, the rigid-group loop) and keeps its own
    // moving mean; signed by the absolute velocity it brakes the drift (checked: with the rigid loop signed by v
    // alone, the amplitude, impulse and dissipation checks fail).
    const std::string rigid = "  [[stages.supports]]\n  group = \"body\"\n  rigid = \"x\"\n";
    const PullResult absolute = pull("local_damping = 0.2\n", "ldf_rigid_absolute", kT, rigid);
    const PullResult filtered = pull("local_damping = 0.2\nlocal_damping_filter = 0.3\n", "ldf_rigid_filtered", kT, rigid);
    check_absolute_against_filtered(absolute, filtered);
}

TEST_CASE("local damping filter: a negative time constant is refused, naming the key", "[unit][damping]") {
    CHECK_THROWS_WITH(testing::make_simulation(pull_case("local_damping = 0.2\nlocal_damping_filter = -1.0\n", 0.1), "ldf_bad"),
                      Catch::Contains("local_damping_filter") && Catch::Contains(">= 0"));
}
