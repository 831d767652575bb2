// Displacement protocols and cyclic supports: the driven position, and the corner smoothing of `ramp`.
//
// CLOSED FORMS
//   A whole body driven in x (its box group takes every node) moves as a rigid translation, so its internal forces
//   are zero and the support's reaction is exactly M a (M the body's inertial mass).
//   Cyclic protocol 0 -> +a -> 0 -> -a -> 0 at rate v: the corners of the displacement are velocity jumps of v or
//   2 v. Without smoothing the jump happens within the step or two around the corner: a reversal gives a
//   velocity change between v and 2 v in one step, so M v / dt <= max |R| <= M 2 v / dt. With ramp T the driven
//   position is the protocol averaged over the trailing window [t - T, t]:
//     u_T(t) = (I(t) - I(t - T)) / T,  I(t) = INT_0^t u dt,
//   its velocity changes linearly over T at each corner, so |R| <= M 2 v / T, and the turning points are cut to
//   a - v T / 4 (the mean of a tent of slope v over a window T centred on its tip).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "engine_helpers.hpp"

namespace {

constexpr double kA = 1.0e-3;   // m, amplitude
constexpr double kV = 0.01;     // m/s, rate
constexpr double kRho = 1000.0; // kg/m^3
constexpr double kT = 0.02;     // m, thickness

std::string driven_block(const std::string& ramp) {
    return R"(
[case]
name = "driven_block"
thickness = 0.02
plane = "stress"
[geometry]
type = "rectangle"
width = 0.1
height = 0.1
mesh_size = 0.05
[materials.m]
E = 1.0e7
nu = 0.2
density = 1000.0
[regions]
body = "m"
[groups.all]
box = [-1.0, -1.0, 1.0, 1.0]
[[stages]]
name = "cycle"
duration = 0.45
  [[stages.supports]]
  group = "all"
  cyclic = { component = "x", amplitudes = [0.001], cycles = 1, rate = 0.01 }
)" + ramp;
}

// The protocol of driven_block: u(t) of the tent wave 0 -> a -> 0 -> -a -> 0 (period 4 a / v), 0 after it.
double tent(double t) {
    const double q = kA / kV;  // s, a quarter period
    if (t <= 0 || t >= 4 * q) return 0.0;
    if (t <= q) return kV * t;
    if (t <= 3 * q) return kA - kV * (t - q);
    return -kA + kV * (t - 3 * q);
}

// INT_0^t tent (exact: piecewise quadratic), for the smoothed position.
double tent_integral(double t) {
    const double q = kA / kV;
    if (t <= 0) return 0.0;
    double s = 0.0, t0 = 0.0;
    const double knots[5] = {0, q, 2 * q, 3 * q, 4 * q};
    for (int i = 0; i < 4 && t > t0; ++i) {
        const double t1 = std::min(t, knots[i + 1]);
        s += 0.5 * (t1 - t0) * (tent(t0) + tent(t1));
        t0 = t1;
    }
    return s;
}

struct Trace {
    double max_err = 0;       // m, largest |u - expected| over the steps
    double max_u = 0;         // m, largest displacement reached
    double max_reaction = 0;  // N, largest |sum of x reactions|
    double mass = 0;          // kg, inertial mass of the body
    double dt = 0;            // s
};

template <class Expected>
Trace run_block(const std::string& ramp, const std::string& name, Expected expected) {
    auto sim = testing::make_simulation(driven_block(ramp), name);
    const auto& md = sim.model();
    Trace tr;
    for (double m : md.mass) tr.mass += m;
    tr.dt = sim.dt();
    const int k0 = md.group("all").nodes.front();
    sim.begin_stage(0);
    while (!sim.stage_finished()) {
        sim.step();
        const double u = md.x[2 * k0] - md.X[2 * k0];
        tr.max_err = std::max(tr.max_err, std::abs(u - expected(sim.time())));
        tr.max_u = std::max(tr.max_u, u);
        double R = 0;
        for (int k : md.group("all").nodes) R += sim.reactions()[2 * k];
        tr.max_reaction = std::max(tr.max_reaction, std::abs(R));
    }
    return tr;
}

}  // namespace

TEST_CASE("cyclic protocol without smoothing: the body lands on the tent wave at every step and a reversal costs "
          "between M v / dt and M 2 v / dt", "[unit][protocol]") {
    const Trace tr = run_block("", "protocol_sharp", tent);
    const double M = kRho * 0.1 * 0.1 * kT;
    std::printf("[protocol] sharp: max |u - u_protocol| %.3e m, max u %.6e m, max |R| %.4e N (M 2 v / dt = %.4e N)\n",
                tr.max_err, tr.max_u, tr.max_reaction, M * 2 * kV / tr.dt);
    CHECK(tr.mass == Approx(M).epsilon(1e-12));
    CHECK(tr.max_err < 1e-12);
    CHECK(tr.max_u <= kA * (1 + 1e-12));  // the tip lies inside a step: seen at the step ends, within v dt
    CHECK(tr.max_u >= kA - kV * tr.dt);
    // a reversal (v -> -v) spread over at most two steps; rigid translation: no internal force
    CHECK(tr.max_reaction <= M * 2 * kV / tr.dt * (1 + 1e-6));
    CHECK(tr.max_reaction >= M * kV / tr.dt * (1 - 1e-6));
}

TEST_CASE("cyclic protocol with ramp T: the trailing-window average, turning points a - v T / 4, reaction bounded "
          "by M 2 v / T", "[unit][protocol]") {
    const double T = 0.01;
    auto smoothed = [T](double t) { return (tent_integral(t) - tent_integral(t - T)) / T; };
    const Trace tr = run_block("  ramp = 0.01\n", "protocol_smooth", smoothed);
    const double M = kRho * 0.1 * 0.1 * kT;
    std::printf("[protocol] ramp %.3g s: max |u - u_T| %.3e m, max u %.6e m (a - v T / 4 = %.6e m), max |R| %.4e N "
                "(M 2 v / T = %.4e N)\n",
                T, tr.max_err, tr.max_u, kA - kV * T / 4, tr.max_reaction, M * 2 * kV / T);
    CHECK(tr.max_err < 1e-12);
    CHECK(tr.max_u == Approx(kA - kV * T / 4).epsilon(1e-3));
    CHECK(tr.max_reaction <= M * 2 * kV / T * (1 + 1e-6));
    CHECK(tr.max_reaction >= 0.9 * M * 2 * kV / T);  // the reversal does take about T
}

TEST_CASE("a protocol stage ends with its protocol: no duration ends at its last point, a shorter duration is refused",
          "[unit]") {
    // driven_block's cycle: one cycle of 1 mm at 0.01 m/s, 0.4 s (4 a / v)
    std::string text = driven_block("");
    const auto at = text.find("duration = 0.45\n");
    REQUIRE(at != std::string::npos);
    {
        std::string open = text;
        open.erase(at, std::string("duration = 0.45\n").size());
        auto sim = testing::make_simulation(open, "protocol_end_open");
        sim.begin_stage(0);
        while (!sim.stage_finished()) sim.step();
        REQUIRE(sim.stage_results().size() == 1);
        CHECK(sim.stage_results()[0].ended_by == "duration");
        CHECK(sim.time() == Approx(4 * kA / kV).margin(2 * sim.dt()));
    }
    const auto dir = testing::tmp_dir("protocol_end_short");
    std::string cut = text;
    cut.replace(at, std::string("duration = 0.45\n").size(), "duration = 0.3\n");
    const std::string path = testing::write_text(dir / "case.toml", cut);
    const auto r = testing::run_fdem("check \"" + path + "\"", dir);
    INFO(r.out << r.err);
    CHECK(r.code == 1);
    CHECK(r.err.find("key 'stages.1.duration': the stage ends at 0.3 s, before the protocol of stages.1.supports.1 "
                     "(its last point at 0.4 s)") != std::string::npos);
}
