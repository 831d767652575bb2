// Long validation runs (ctest label "validation", excluded from ./test.sh; run with ./test.sh -L validation).
// Each runs a committed case file through the fdem executable and checks the result it prints into summary.json
// against the reference the case names: the tolerances are the acceptance limits of issue 5 / cases/README.md, not fitted.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "core/engine_helpers.hpp"

namespace {

// The number after "key": in the object "object" of summary.json (the engine writes these objects flat, one level
// deep).
double summary_number(const std::string& summary, const std::string& object, const std::string& key) {
    const auto obj = summary.find("\"" + object + "\"");
    REQUIRE(obj != std::string::npos);
    const auto k = summary.find("\"" + key + "\"", obj);
    REQUIRE(k != std::string::npos);
    const auto colon = summary.find(':', k);
    return std::stod(summary.substr(colon + 1));
}

double reference_number(const std::string& summary, const std::string& key) {
    return summary_number(summary, "reference", key);
}

std::string run_case(const std::string& rel_case, const std::string& name) {
    const auto dir = testing::tmp_dir(name);
    const std::string cmd = std::string("run \"") + FDEM_CASES_DIR + "/" + rel_case + "\" --out \"" + (dir / "run").string() +
                            "\" --threads 2 --quiet";
    const auto r = testing::run_fdem(cmd, dir);
    INFO(r.out << r.err);
    REQUIRE(r.code == 0);
    return testing::read_text(dir / "run" / "summary.json");
}

// Two columns (by header name) of the history.csv of the run run_case(.., name) made, row by row.
std::vector<std::pair<double, double>> history_columns(const std::string& name, const std::string& cx,
                                                      const std::string& cy) {
    std::istringstream in(testing::read_text(std::filesystem::path(FDEM_TEST_TMP) / name / "run" / "history.csv"));
    std::string line;
    REQUIRE(std::getline(in, line));
    int ix = -1, iy = -1, col = 0;
    std::istringstream head(line);
    for (std::string h; std::getline(head, h, ','); ++col) {
        if (h == cx) ix = col;
        if (h == cy) iy = col;
    }
    REQUIRE(ix >= 0);
    REQUIRE(iy >= 0);
    std::vector<std::pair<double, double>> rows;
    while (std::getline(in, line)) {
        std::istringstream row(line);
        double x = NAN, y = NAN;
        col = 0;
        for (std::string v; std::getline(row, v, ','); ++col) {
            if (col == ix) x = std::stod(v);
            if (col == iy) y = std::stod(v);
        }
        rows.emplace_back(x, y);
    }
    return rows;
}

// A wall case's peak against the test it names in [reference]: |relative error| within the acceptance tolerance.
void check_peak_against_test(const std::string& rel_case, const std::string& name, double tolerance) {
    const std::string s = run_case(rel_case, name);
    const double err = reference_number(s, "relative_error");
    INFO("peak " << reference_number(s, "computed") << " N against " << reference_number(s, "value")
                 << " N measured: error " << 100 * err << " %");
    CHECK(std::abs(err) <= tolerance);
}

}  // namespace

// cases/README.md §A2 / §C: a single stone pulled apart carries f_t A = 3.7 MPa x 0.1 m x 0.2 m = 74 kN at its peak. The
// 25 mm mesh of the wall cases gives about +1.5 % (cases/lourenco2005/RESULTS.md); 5 % is the case file's tolerance.
TEST_CASE("single stone in tension, 25 mm: peak force f_t A within 5 %", "[regression]") {
    const std::string s = run_case("lourenco2005/stone_tension_25mm.toml", "stone25");
    const double computed = reference_number(s, "computed");
    INFO("peak reaction " << computed << " N against f_t A = 74000 N");
    CHECK(std::abs(std::abs(computed) - 74.0e3) <= 0.05 * 74.0e3);
}

// A [K25]-style dry-stone wall (cases/README.md §A, seeds/004 set-up): issue 5's acceptance, the peak within 25 % of
// the test (issue 27 §2: none worse than 25 %), and issue 27 §2's, within 8 % of the published FDEM prediction of
// [K25] Table 3 (the same model). The engine's reference check takes the raw largest load; the family report's peaks
// are averaged over 0.5 mm. The tests' peaks are 20.23 / 44.73 / 69.96 / 102.95 kN, the published ones 17.10 / 47.75 /
// 86.82 / 106.17 kN; where the model misses them (cases/lourenco2005/RESULTS.md has the measured peaks) THESE TESTS
// FAIL (kept failing on purpose: they state the acceptance, they are not loosened). Family setting (per-node mass scaling 10, 0.01 m/s to 10 mm): about a
// minute each on one thread.
static void check_dry_stone_wall(const std::string& rel_case, const std::string& name, double published) {
    const std::string s = run_case(rel_case, name);
    const double err = reference_number(s, "relative_error");
    const double computed = std::abs(reference_number(s, "computed"));
    INFO("peak " << computed << " N against " << reference_number(s, "value") << " N measured (error " << 100 * err
                 << " %) and " << published << " N published (" << 100 * (computed / published - 1) << " %)");
    CHECK(std::abs(err) <= 0.25);
    CHECK(std::abs(computed / published - 1) <= 0.08);
}

TEST_CASE("dry-stone wall, N = 30 kN, [K25] style: peak within 25 % of the experiment and 8 % of the published FDEM",
          "[regression]") {
    check_dry_stone_wall("lourenco2005/k25_N30.toml", "k25_N30", 17.10e3);
}

TEST_CASE("dry-stone wall, N = 100 kN, [K25] style: peak within 25 % of the experiment and 8 % of the published FDEM",
          "[regression]") {
    check_dry_stone_wall("lourenco2005/k25_N100.toml", "k25_N100", 47.75e3);
}

TEST_CASE("dry-stone wall, N = 200 kN, [K25] style: peak within 25 % of the experiment and 8 % of the published FDEM",
          "[regression]") {
    check_dry_stone_wall("lourenco2005/k25_N200.toml", "k25_N200", 86.82e3);
}

TEST_CASE("dry-stone wall, N = 250 kN, [K25] style: peak within 25 % of the experiment and 8 % of the published FDEM",
          "[regression]") {
    check_dry_stone_wall("lourenco2005/k25_N250.toml", "k25_N250", 106.17e3);
}

// Issue 27 acceptance for the mortared walls (cases/README.md §B): the three held walls (top beam neither rotating nor moving
// vertically after the precompression) with the published values and the composite joint law (law = "composite",
// fracture/composite_law.hpp), no calibration, each peak within +-15 % of 50 / 120 / 175 kN. Measured
// (vermeltfoort/RESULTS.md, "Composite law"): 0.30 MPa in its band; the 1.21 and 2.12 MPa walls about 38 % and 36 %
// low, so THE LAST TWO TESTS FAIL until the model ingredient RESULTS.md names is resolved (kept failing on purpose:
// they state the acceptance, they are not loosened). About 1 minute of CPU each on 1 thread.
TEST_CASE("mortared wall, 0.30 MPa (Vermeltfoort J4D/J5D), composite law: peak within 15 % of the experiment",
          "[regression]") {
    check_peak_against_test("vermeltfoort/vermeltfoort_030.toml", "vermeltfoort_030", 0.15);
}

TEST_CASE("mortared wall, 1.21 MPa (Vermeltfoort J6D), composite law: peak within 15 % of the experiment",
          "[regression]") {
    check_peak_against_test("vermeltfoort/vermeltfoort_121.toml", "vermeltfoort_121_peak", 0.15);
}

TEST_CASE("mortared wall, 2.12 MPa (Vermeltfoort J7D), composite law: peak within 15 % of the experiment",
          "[regression]") {
    check_peak_against_test("vermeltfoort/vermeltfoort_212.toml", "vermeltfoort_212", 0.15);
}

// The engine's energy balance W_ext = K + E_el + E_joint + E_contact + D_damp + D_visc + D_frac + D_fric, read from the
// "energy" object of summary.json. Damaged mortar joints that vibrate pumped energy with the [K25] law (its
// Mohr-Coulomb coupling has no potential, fracture/README.md): the 1.21 MPa wall closed its books to 2.3 % only with
// the bricks' element viscous damping. With the composite law (dissipative plastic slip) it closes them
// to 0.20 % with 158.7 J of fracture dissipation (vermeltfoort/RESULTS.md). The engine warns above 5 %, the limit
// checked here. About 50 s on 1 thread.
TEST_CASE("mortared wall, 1.21 MPa (Vermeltfoort J6D): the energy balance closes within 5 % through the cracking",
          "[regression]") {
    const std::string s = run_case("vermeltfoort/vermeltfoort_121.toml", "vermeltfoort_121");
    const double balance = summary_number(s, "energy", "balance_error");
    const double fracture = summary_number(s, "energy", "fracture");
    INFO("balance error " << 100 * balance << " %, fracture dissipation " << fracture << " J");
    CHECK(fracture > 10.0);  // the joints did crack (158.7 J), so the check covers the damaged joints
    CHECK(balance < 0.05);
}

// Issue 5 item 3 and cases/README.md §C: on a tilting table the whole wall cannot stay on its dry base joint once
// tan(alpha) > mu (friction 32 deg): some mechanism must have started by then. The committed case (filtered local
// damping 0.05) starts a stepped wedge tipping about the toe at 28-29 deg (u_top_right > 1 mm at 28.95 deg; 28.85 at
// half the tilt rate; tilting/RESULTS.md); with local damping 0.8 against the velocity, as until 24 Nov, it ran away
// only at 34-36 deg and this check fails. At 20 deg the wall stands (0.034 mm, elastic). About 2 minutes on 1 thread.
TEST_CASE("tilting table: the dry-stone wall collapses before the whole-wall sliding angle atan(mu) = 32 deg",
          "[regression]") {
    run_case("tilting/tilting_wall.toml", "tilting_wall");
    const auto rows = history_columns("tilting_wall", "tilt", "u_top_right");
    double onset = NAN, u_at_20 = NAN;
    for (const auto& [tilt, u] : rows) {
        if (std::isnan(u_at_20) && tilt >= 20.0) u_at_20 = u;
        if (std::isnan(onset) && std::abs(u) > 1e-3) onset = tilt;
    }
    const double sliding = 32.0;  // deg: tan(alpha) = mu with the case's friction angle of 32 deg
    INFO("u_top_right at 20 deg " << u_at_20 << " m; first beyond 1 mm at " << onset << " deg; sliding angle "
                                  << sliding << " deg");
    REQUIRE_FALSE(std::isnan(onset));
    CHECK(onset < sliding);
    CHECK(std::abs(u_at_20) < 1e-4);
}
