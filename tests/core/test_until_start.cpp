// tests/core/test_until_start.cpp: a stage whose `until` condition already holds when it starts ends at once (issue
// 54, 4): a monitor already at or beyond the target, seen from zero (monitor / value >= 1), ends the stage at once
// (seen from the start value, a monitor already past the target would make the stage wait for it to come back, to
// max_duration).
//
// SCENE. The elastic column of the rigid-support tests (0.2 x 1.0 m), bottom fixed, top driven at vx = 0.01 m/s (vy free),
// monitor u_top (x displacement of the top). Stage 1 runs 1 s (u_top = 0.01 m); stage 2 keeps the drive with
// until = { monitor = "u_top", value = V } and max_duration 1 s.
#include <catch2/catch.hpp>

#include <string>

#include "engine_helpers.hpp"

namespace {

std::string until_case(double value) {
    return testing::column_case_head("until_start") + R"(
[[monitors]]
name = "u_top"
type = "displacement"
group = "top"
component = "x"
[[stages]]
name = "drive"
duration = 1.0
local_damping = 0.8
  [[stages.supports]]
  group = "bottom"
  fix = "xy"
  [[stages.supports]]
  group = "top"
  vx = 0.01
[[stages]]
name = "more"
until = { monitor = "u_top", value = )" + std::to_string(value) + R"( }
max_duration = 1.0
)";
}

}  // namespace

TEST_CASE("stages: an until condition that already holds at the stage's start ends the stage at once, and one ahead is "
          "reached by the drive",
          "[unit][stages]") {
    // Already past: 5 mm and 0.1 mm behind the monitor's 0.01 m (the first stage ends within dt x 0.01 m/s of 1 s).
    for (double value : {0.005, 0.0099}) {
        auto sim = testing::make_simulation(until_case(value), "until_start");
        sim.run();
        REQUIRE(sim.stage_results().size() == 2);
        const auto& r = sim.stage_results()[1];
        CHECK(r.ended_by == "until");
        CHECK(r.steps == 0);
        CHECK(sim.monitor_value(0) == Approx(0.01).epsilon(1e-3));
    }
    // Ahead: the drive takes the monitor to 0.015 m in 0.5 s, by until (not max_duration).
    auto sim = testing::make_simulation(until_case(0.015), "until_ahead");
    sim.run();
    const auto& r = sim.stage_results()[1];
    CHECK(r.ended_by == "until");
    CHECK(r.time == Approx(1.5).epsilon(1e-3));
    CHECK(sim.monitor_value(0) >= 0.015);
}
