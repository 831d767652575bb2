// tests/core/test_scene_features.cpp: time functions on loads, supports and gravity; initial conditions
// ([[initial]]); the rotation monitor. Each checked against its closed form on a free elastic square.
//
// CLOSED FORMS (a body of mass M, no support unless said; leap-frog from rest, v^{-1/2} = 0):
//   sin force   F(t) = F0 sin(omega t): v(t) = F0 / (M omega) (1 - cos omega t).
//   table force F(t) = F0 f(t), f piecewise linear: the momentum at t is F0 INT_0^t f dt.
//   gravity function: g(t) = g f(t): the mean velocity is g INT_0^t f dt.
//   support velocity v(t) = v0 sin(omega t): displacement v0 / omega (1 - cos omega t).
//   rigid spin: a body given v = omega x (x - c), free of loads, turns at omega: rotation monitor omega t (deg);
//   its kinetic energy stays 1/2 I omega^2 (the neo-Hookean triangles are stress-free under rotation).
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <string>

#include "core/engine_helpers.hpp"

namespace {

constexpr double kPi = 3.14159265358979323846;

// A 0.2 x 0.2 m square (t = 0.1 m, steel-like E so it moves almost rigidly, 2000 kg/m^3: M = 8 kg), groups of
// the rectangle generator (body, left, right, top, bottom, corners); monitors: mean x velocity and displacement of
// the body, its rotation, and of the right edge's x displacement.
std::string square_head(const std::string& name) {
    return "[case]\nname = \"" + name + R"("
thickness = 0.1
[geometry]
type = "rectangle"
width = 0.2
height = 0.2
mesh_size = 0.05
[materials.m]
E = 2.0e11
nu = 0.3
density = 2000.0
[regions]
body = "m"
[[monitors]]
name = "vx"
type = "velocity"
group = "body"
component = "x"
[[monitors]]
name = "vy"
type = "velocity"
group = "body"
component = "y"
[[monitors]]
name = "rot"
type = "rotation"
group = "body"
[[monitors]]
name = "ux_right"
type = "displacement"
group = "right"
component = "x"
)";
}

// Mass-weighted mean x velocity (m/s).
double mean_vx(const fdem::Simulation& sim) {
    const auto& md = sim.model();
    double p = 0, m = 0;
    for (int k = 0; k < md.n_nodes(); ++k) p += md.mass[k] * md.v[2 * k], m += md.mass[k];
    return p / m;
}

// The value of the monitor named `name` now.
double monitor(const fdem::Simulation& sim, const std::string& name) {
    for (std::size_t i = 0; i < sim.spec().monitors.size(); ++i)
        if (sim.spec().monitors[i].name == name) return sim.monitor_value(static_cast<int>(i));
    FAIL("no monitor " << name);
    return 0.0;
}

// Mean x displacement of the right edge's nodes (m).
double right_edge_ux(const fdem::Simulation& sim) {
    const auto& md = sim.model();
    double ux = 0;
    for (int k : md.group("right").nodes) ux += md.x[2 * k] - md.X[2 * k];
    return ux / static_cast<double>(md.group("right").nodes.size());
}

double total_mass(const fdem::Simulation& sim) {
    double m = 0;
    for (int k = 0; k < sim.model().n_nodes(); ++k) m += sim.model().mass[k];
    return m;
}

}  // namespace

TEST_CASE("time function: a force F0 sin(omega t) gives the body v = F0 / (M omega) (1 - cos omega t)", "[unit][scene]") {
    const double F0 = 80.0, omega = 2 * kPi * 5.0;  // N, rad/s
    auto sim = testing::make_simulation(square_head("tf_sin") + R"(
[[stages]]
name = "shake"
duration = 0.13
local_damping = 0.0
  [[stages.loads]]
  group = "body"
  force = [80.0, 0.0]
  function = { type = "sin", amplitude = 1.0, omega = 31.41592653589793 }
)",
                                        "tf_sin");
    sim.run();
    const double M = total_mass(sim), t = sim.time();
    // v^{n-1/2}: the velocity half a step before the run's end time t^n.
    const double th = t - 0.5 * sim.dt();
    const double expected = F0 / (M * omega) * (1 - std::cos(omega * th));
    std::printf("[scene] sin force: M %.4f kg, mean vx %.8f m/s, closed form %.8f m/s at t %.5f s\n", M, mean_vx(sim),
                expected, th);
    CHECK(mean_vx(sim) == Approx(expected).epsilon(1e-3));
}

TEST_CASE("time function: a table factor interpolates linearly and the momentum is F0 INT f dt", "[unit][scene]") {
    // f: 0 at 0, 1 at 0.02 s, 1 at 0.04 s, 0 at 0.06 s, then held at 0: INT f = 0.04 s.
    auto sim = testing::make_simulation(square_head("tf_table") + R"(
[[stages]]
name = "pulse"
duration = 0.08
local_damping = 0.0
  [[stages.loads]]
  group = "body"
  force = [100.0, 0.0]
  function = { type = "table", points = [[0.0, 0.0], [0.02, 1.0], [0.04, 1.0], [0.06, 0.0]] }
)",
                                        "tf_table");
    sim.run();
    const double M = total_mass(sim);
    std::printf("[scene] table pulse: mean vx %.8f m/s, F0 INT f / M %.8f m/s\n", mean_vx(sim), 100.0 * 0.04 / M);
    CHECK(mean_vx(sim) == Approx(100.0 * 0.04 / M).epsilon(2e-3));
}

TEST_CASE("time function: gravity switched off by a table after 0.05 s leaves the body at -g 0.05 m/s",
          "[unit][scene]") {
    auto sim = testing::make_simulation(square_head("tf_gravity") + R"(
[[stages]]
name = "drop"
duration = 0.1
local_damping = 0.0
gravity = [0.0, -9.81]
gravity_function = { type = "table", points = [[0.0, 1.0], [0.05, 1.0], [0.0500001, 0.0]] }
)",
                                        "tf_gravity");
    sim.run();
    const auto& md = sim.model();
    double p = 0, m = 0;
    for (int k = 0; k < md.n_nodes(); ++k) p += md.mass[k] * md.v[2 * k + 1], m += md.mass[k];
    std::printf("[scene] gravity function: mean vy %.8f m/s, closed form %.8f m/s\n", p / m, -9.81 * 0.05);
    CHECK(p / m == Approx(-9.81 * 0.05).epsilon(2e-3));
}

TEST_CASE("time function: a support velocity v0 sin(omega t) moves its edge by v0 / omega (1 - cos omega t)",
          "[unit][scene]") {
    const double v0 = 0.01, omega = 2 * kPi * 2.0;
    auto sim = testing::make_simulation(square_head("tf_support") + R"(
[[stages]]
name = "drive"
duration = 0.2
local_damping = 0.0
  [[stages.supports]]
  group = "right"
  vx = 0.01
  function = { type = "sin", omega = 12.566370614359172 }
)",
                                        "tf_support");
    sim.run();
    const double t = sim.time();
    const double expected = v0 / omega * (1 - std::cos(omega * t));
    const double ux = right_edge_ux(sim);
    std::printf("[scene] support function: edge displacement %.8e m, closed form %.8e m\n", ux, expected);
    CHECK(ux == Approx(expected).epsilon(1e-3));
}

TEST_CASE("initial conditions: a body spun about its centre turns at omega (rotation monitor omega t) and keeps "
          "its kinetic energy",
          "[unit][scene]") {
    const double omega = 2.0;  // rad/s
    auto sim = testing::make_simulation(square_head("ic_spin") + R"(
[[initial]]
group = "body"
angular_velocity = 2.0
center = [0.1, 0.1]
[[stages]]
name = "spin"
duration = 0.3
local_damping = 0.0
)",
                                        "ic_spin");
    const double I = 8.0 * (0.2 * 0.2 + 0.2 * 0.2) / 12.0;  // kg m^2, square about its centre (lumped: close)
    sim.run();
    const double t = sim.time();
    const double theta = monitor(sim, "rot");
    const fdem::Energies e = sim.energies();
    std::printf("[scene] spin: rotation %.6f deg at t %.5f s, omega t %.6f deg; kinetic %.6e J (1/2 I omega^2 of "
                "the continuous square %.6e J), balance %.2e\n",
                theta, t, omega * t * 180 / kPi, e.kinetic, 0.5 * I * omega * omega, e.balance_error());
    CHECK(theta == Approx(omega * t * 180 / kPi).epsilon(2e-3));
    CHECK(e.balance_error() < 1e-3);
}

TEST_CASE("initial conditions: a placement turned by 30 deg reads 30 deg on the rotation monitor and holds no "
          "strain energy",
          "[unit][scene]") {
    auto sim = testing::make_simulation(square_head("ic_rotate") + R"(
[[initial]]
group = "body"
rotation = 30.0
center = [0.0, 0.0]
[[stages]]
name = "rest"
duration = 0.01
local_damping = 0.0
)",
                                        "ic_rotate");
    sim.run();
    const double theta = monitor(sim, "rot");
    const fdem::Energies e = sim.energies();
    std::printf("[scene] turned placement: rotation %.10f deg, elastic energy %.3e J, kinetic %.3e J\n", theta,
                e.elastic, e.kinetic);
    CHECK(theta == Approx(30.0).epsilon(1e-9));
    // Stress-free: what is left is the round-off of the energy formula near F = R, about 1e-17 E V here.
    CHECK(e.elastic < 1e-15 * 2.0e11 * 0.2 * 0.2 * 0.1);
    CHECK(e.kinetic < 1e-9);
}

TEST_CASE("scene features: bad time functions and initial conditions are exit 1 naming the key", "[unit][scene]") {
    const auto dir = testing::tmp_dir("scene_bad");
    const std::string stage = "[[stages]]\nname = \"s\"\nduration = 0.01\n";
    struct Bad {
        std::string text, key;
    };
    const Bad cases[] = {
        {stage + "  [[stages.loads]]\n  group = \"body\"\n  force = [1.0, 0.0]\n  function = { type = \"cos\", omega = 1.0 }\n",
         "stages.1.loads.1.function.type"},
        {stage + "  [[stages.loads]]\n  group = \"body\"\n  force = [1.0, 0.0]\n  function = { type = \"sin\" }\n",
         "stages.1.loads.1.function.omega"},
        {stage + "  [[stages.loads]]\n  group = \"body\"\n  force = [1.0, 0.0]\n  function = { type = \"table\", points = [[0.1, 1.0], [0.0, 0.0]] }\n",
         "stages.1.loads.1.function.points"},
        {stage + "  [[stages.supports]]\n  group = \"left\"\n  fix = \"x\"\n  function = { type = \"sin\", omega = 1.0 }\n",
         "stages.1.supports.1.function"},
        {"[[initial]]\ngroup = \"body\"\nrotation = 10.0\n" + stage, "initial.1.center"},
        {"[[initial]]\ngroup = \"nowhere\"\nvelocity = [1.0, 0.0]\n" + stage, "initial.1.group"},
        {"[[initial]]\ngroup = \"body\"\nspin = 1.0\n" + stage, "initial.1.spin"},
        {stage + "  [[stages.supports]]\n  group = \"right\"\n  vx = 0.01\n  servo = { ratio = 1.5, time = 0.01 }\n",
         "stages.1.supports.1.servo.ratio"},
        {stage + "  [[stages.supports]]\n  group = \"right\"\n  vx = 0.01\n  servo = { ratio = 0.01 }\n",
         "stages.1.supports.1.servo.time"},
        {stage + "  [[stages.supports]]\n  group = \"right\"\n  fix = \"x\"\n  servo = { ratio = 0.01, time = 0.01 }\n",
         "stages.1.supports.1.servo"},
    };
    int i = 0;
    for (const Bad& b : cases) {
        const auto path = testing::write_text(dir / ("case" + std::to_string(i++) + ".toml"), square_head("bad") + b.text);
        const auto r = testing::run_fdem("check \"" + path + "\"", dir);
        INFO(b.key << "\n" << r.err);
        CHECK(r.code == 1);
        CHECK(r.err.find(b.key) != std::string::npos);
    }
}

// Servo-controlled loading rate (stage support key servo): the velocity factor f follows
// f <- clamp(f exp(w clamp(ln(R* / rbar), -2, 2)), f_min, 1), w = dt / T, rbar the ratio's mean over T.
//   - The unbalanced-force ratio R = sum |f| / sum (|f_int| + |f_ext|) is at most 1 (triangle inequality), so a
//     target of 0.999999 never slows the drive: same bits as without the servo.
//   - A target far below every ratio reached (1e-12) saturates the controller at e^-2 per T from the first steps,
//     so f(t) = max(f_min, exp(-2 t / T)) and the driven edge moves by
//     u = v T / 2 (1 - f_min) + f_min v (t_end - t1),  t1 = T ln(1 / f_min) / 2.
TEST_CASE("servo loading: a target above every unbalanced-force ratio leaves the drive unchanged, and a target below "
          "them slows it at e^-2 per response time down to min_factor",
          "[unit][scene]") {
    const std::string head = square_head("servo") + R"(
[[stages]]
name = "pull"
duration = 0.05
local_damping = 0.0
  [[stages.supports]]
  group = "left"
  fix = "xy"
  [[stages.supports]]
  group = "right"
  vx = 0.01
)";
    auto plain = testing::make_simulation(head, "servo_plain");
    plain.run();
    auto high = testing::make_simulation(head + "  servo = { ratio = 0.999999, time = 0.01 }\n", "servo_high");
    high.run();
    CHECK(high.model().x == plain.model().x);
    CHECK(high.model().v == plain.model().v);

    const double v = 0.01, T = 0.01, fmin = 0.05;
    auto low = testing::make_simulation(head + "  servo = { ratio = 1e-12, time = 0.01, min_factor = 0.05 }\n", "servo_low");
    low.run();
    const double t_end = low.time(), t1 = 0.5 * T * std::log(1 / fmin);
    const double expected = 0.5 * v * T * (1 - fmin) + fmin * v * (t_end - t1);
    std::printf("[scene] servo: unslowed edge %.6e m; slowed %.6e m, closed form %.6e m\n", right_edge_ux(plain), right_edge_ux(low),
                expected);
    CHECK(right_edge_ux(plain) == Approx(v * t_end).epsilon(1e-3));
    CHECK(right_edge_ux(low) == Approx(expected).epsilon(5e-3));
}

TEST_CASE("the tilt monitor reads the angle of gravity: a vector given tilted by 20 deg reads 20, then 20 + rate t",
          "[unit][scene]") {
    // The fixed elastic column of these tests (only the monitor matters): gravity [g sin 20, -g cos 20] reads 20 deg; the same with tilt_rate
    // 5 deg/s reads 20 + 5 t at the monitors' time t^n; no gravity reads 0 (issue 54: it read 0 for a tilted vector).
    const double a = 20.0 * 3.14159265358979323846 / 180.0;
    auto text = [&](const std::string& gravity, double rate) {
        return testing::column_case_head("tilt_monitor") + "[[monitors]]\nname = \"tilt\"\ntype = \"tilt\"\n"
               "[[stages]]\nname = \"s\"\nduration = 0.1\n" + gravity + "tilt_rate = " + std::to_string(rate) +
               "\n  [[stages.supports]]\n  group = \"bottom\"\n  fix = \"xy\"\n";
    };
    char g[128];
    std::snprintf(g, sizeof g, "gravity = [%.17g, %.17g]\n", 9.81 * std::sin(a), -9.81 * std::cos(a));
    for (double rate : {0.0, 5.0}) {
        auto sim = testing::make_simulation(text(g, rate), "tilt_monitor_" + std::to_string(static_cast<int>(rate)));
        sim.begin_stage(0);
        while (!sim.stage_finished()) sim.step();
        const double t_n = sim.time() - sim.dt();  // the monitors' time
        CHECK(sim.monitor_value(0) == Approx(20.0 + rate * t_n).epsilon(1e-12));
    }
    auto none = testing::make_simulation(text("", 0.0), "tilt_monitor_none");
    none.begin_stage(0);
    none.step();
    CHECK(none.monitor_value(0) == 0.0);
}
