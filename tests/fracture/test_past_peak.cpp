// A pushover stage that ends past its peak ([[stages]] past_peak, fdem/case.hpp StageSpec::PastPeak): the cohesive
// bar of bar_structured.toml (peak f_t A = 74 kN, cases/README.md §C) pulled until it separates. The stage ends once
// the reaction, averaged over `smooth` of travel, has stayed below (1 - drop) of its largest average for `travel`.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>

#include "core/engine_helpers.hpp"
#include "fdem/case.hpp"
#include "fdem/scene.hpp"
#include "fdem/simulation.hpp"

namespace {

std::filesystem::path cases_dir() { return std::filesystem::path(FDEM_TEST_DATA_DIR).parent_path() / "fracture" / "cases"; }

std::string replace_once(std::string s, const std::string& from, const std::string& to) {
    const auto i = s.find(from);
    REQUIRE(i != std::string::npos);
    return s.replace(i, from.size(), to);
}

struct Bar {
    std::filesystem::path dir;
    std::string case_path;
};

// The bar at nx = 4, ny = 2, its stage ending at ux = `until` (m), with the given extra stage keys.
Bar bar_case(const std::string& name, double until, const std::string& extra) {
    Bar b;
    b.dir = testing::tmp_dir(name);
    const std::string geo =
        replace_once(testing::read_text(cases_dir() / "bar_structured.geo"), "nx = 16; ny = 8;", "nx = 4; ny = 2;");
    std::string toml = testing::read_text(cases_dir() / "bar_structured.toml");
    toml = replace_once(toml, "duration = 0.03          # s\n",
                        "until = { monitor = \"ux\", value = " + std::to_string(until) + " }\n" + extra);
    testing::write_text(b.dir / "bar_structured.geo", geo);
    b.case_path = testing::write_text(b.dir / "case.toml", toml);
    return b;
}

}  // namespace

TEST_CASE("past_peak: the pulled bar's stage ends `travel` after its averaged reaction falls below (1 - drop) of its "
          "largest average, not at its until",
          "[unit][stages]") {
    // The bar softens and separates near ux = 1.1e-4 m (0.0102 s at 0.01 m/s), after which R is 0. The raw R falls
    // below half its peak at u_half; the average over smooth = 2e-6 m follows within a few smooth lengths, and the
    // stage ends travel = 2e-5 m later, far before its until (1e-3 m).
    const double smooth = 2e-6, travel = 2e-5;
    const Bar b = bar_case("past_peak_bar", 1e-3,
                           "past_peak = { load = \"R\", displacement = \"ux\", drop = 0.5, travel = " +
                               std::to_string(travel) + ", smooth = " + std::to_string(smooth) + " }\n");
    fdem::CaseSpec spec = fdem::load_case(b.case_path, {});
    REQUIRE(spec.stages[0].past_peak);
    CHECK(spec.stages[0].past_peak->smooth == Approx(smooth));
    fdem::RunOptions opt;
    opt.quiet = true;
    opt.threads = 1;
    fdem::Simulation sim(spec, fdem::build_scene(spec), opt);
    sim.begin_stage(0);
    double peak = 0, u_half = -1;
    const double fA = 3.7e6 * 0.1 * 0.2;  // f_t x height x thickness of the bar (.geo: 0.1 m high)
    while (!sim.stage_finished()) {
        sim.step();
        const double R = sim.monitor_value(1), u = sim.monitor_value(0);
        peak = std::max(peak, R);
        if (u_half < 0 && peak > 0.5 * fA && R < 0.5 * peak) u_half = u;
    }
    REQUIRE(sim.stage_results().size() == 1);
    CHECK(sim.stage_results()[0].ended_by == "past_peak");
    REQUIRE(u_half > 0);
    CHECK(peak == Approx(fA).epsilon(0.01));
    const double u_end = sim.monitor_value(0);
    // ended between u_half + travel and u_half + travel + the averaging lag (a few smooth lengths)
    CHECK(u_end >= u_half + travel);
    CHECK(u_end <= u_half + travel + 5 * smooth);
}

TEST_CASE("past_peak: a load that never falls (the bar pulled only to 80 % of its strength) ends by until", "[unit][stages]") {
    // The bar's elastic stiffness E A / L = 1e10 x 0.02 / 0.2 = 1e9 N/m: 0.8 f_t A is reached at ux = 5.9e-5 m.
    const Bar b = bar_case("past_peak_bar_rising", 5.9e-5,
                           "past_peak = { load = \"R\", displacement = \"ux\", drop = 0.05, travel = 1e-6 }\n");
    fdem::CaseSpec spec = fdem::load_case(b.case_path, {});
    fdem::RunOptions opt;
    opt.quiet = true;
    opt.threads = 1;
    fdem::Simulation sim(spec, fdem::build_scene(spec), opt);
    sim.begin_stage(0);
    while (!sim.stage_finished()) sim.step();
    REQUIRE(sim.stage_results().size() == 1);
    CHECK(sim.stage_results()[0].ended_by == "until");
}

TEST_CASE("past_peak: bad keys are exit 1 naming the key and what was expected", "[unit][stages]") {
    struct Bad {
        std::string extra, key, expect;
    };
    const Bad bad[] = {
        {"past_peak = { load = \"ux\", displacement = \"ux\", drop = 0.2, travel = 1e-5 }\n", "stages.1.past_peak.load",
         "expected a reaction or load monitor"},
        {"past_peak = { load = \"R\", displacement = \"R_left\", drop = 0.2, travel = 1e-5 }\n",
         "stages.1.past_peak.displacement", "expected a displacement, rotation or tilt monitor"},
        {"past_peak = { load = \"R\", displacement = \"ux\", drop = 1.5, travel = 1e-5 }\n", "stages.1.past_peak.drop",
         "a fraction of the largest load in (0, 1)"},
        {"past_peak = { load = \"R\", displacement = \"ux\", drop = 0.2 }\n", "stages.1.past_peak.travel", "travel"},
        {"past_peak = { load = \"Rx\", displacement = \"ux\", drop = 0.2, travel = 1e-5 }\n", "stages.1.past_peak.load",
         "no monitor named 'Rx'"},
    };
    int i = 0;
    for (const Bad& c : bad) {
        const Bar b = bar_case("past_peak_bad_" + std::to_string(i++), 1e-4, c.extra);
        const auto r = testing::run_fdem("check \"" + b.case_path + "\"", b.dir);
        INFO(c.extra << r.out << r.err);
        CHECK(r.code == 1);
        CHECK(r.err.find(c.key) != std::string::npos);
        CHECK(r.err.find(c.expect) != std::string::npos);
    }
}

TEST_CASE("past_peak: a 'peak' result that ended while still rising is reported as a lower bound, one past its peak "
          "is not",
          "[unit][stages]") {
    const std::string ref = "\n[reference]\nmonitor = \"R\"\nquantity = \"peak\"\nvalue = 74.0e3\nsource = \"f_t A\"\n";
    struct Run {
        double until;
        std::string extra;
        bool past;
    };
    const Run runs[] = {{5.9e-5, "", false},
                        {1e-3, "past_peak = { load = \"R\", displacement = \"ux\", drop = 0.5, travel = 2e-5, smooth = 2e-6 }\n",
                         true}};
    int i = 0;
    for (const Run& c : runs) {
        Bar b = bar_case("past_peak_cli_" + std::to_string(i++), c.until, c.extra);
        testing::write_text(b.case_path, testing::read_text(b.case_path) + ref);
        const auto out = b.dir / "run";
        const auto r = testing::run_fdem("run \"" + b.case_path + "\" --threads 1 --out \"" + out.string() + "\"", b.dir);
        INFO(r.out << r.err);
        REQUIRE(r.code == 0);
        CHECK((r.out.find("not past the peak") == std::string::npos) == c.past);
        const std::string summary = testing::read_text(out / "summary.json");
        CHECK(summary.find(std::string("\"past_peak\": ") + (c.past ? "true" : "false")) != std::string::npos);
    }
}
