// law = "mohr_coulomb" (fracture/mc_law.hpp) through the engine: the mode II shear case of cases/mode2_shear.*
// (two blocks, bonded interface of length L = 0.1 m, sigma = 1 MPa, upper block dragged at 0.01 m/s) with the
// Mohr-Coulomb law instead of the [K25] softening: the shear stress rises to c + sigma tan(phi) and stays there to
// the end (16 times the elastic slip), no element breaks, the slip work is booked under D_fric and the energy
// balances.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "core/engine_helpers.hpp"

namespace fs = std::filesystem;

TEST_CASE("mc law engine: a bonded Mohr-Coulomb interface holds c + sigma tan(phi) without softening", "[engine][mc]") {
    const fs::path cases = fs::path(__FILE__).parent_path() / "cases";
    const auto dir = testing::tmp_dir("mc_engine_shear");
    testing::write_text(dir / "mode2_shear.geo", testing::read_text(cases / "mode2_shear.geo"));
    std::string toml = testing::read_text(cases / "mode2_shear.toml");
    for (const std::string key : {"GI = 10.0 ", "GII = 50.0 "}) {
        const auto at = toml.find(key);
        REQUIRE(at != std::string::npos);
        toml.erase(at, toml.find('\n', at) - at + 1);
    }
    const auto at = toml.find("kind = \"bonded\"");
    REQUIRE(at != std::string::npos);
    toml.insert(toml.find('\n', at) + 1, "law = \"mohr_coulomb\"\n");
    const std::string path = testing::write_text(dir / "case.toml", toml);
    fdem::CaseSpec spec = fdem::load_case(path);
    fdem::Model model = fdem::build_scene(spec);
    fdem::RunOptions opt;
    opt.quiet = true;
    opt.threads = 1;
    fdem::Simulation sim(spec, std::move(model), opt);
    const double A = 0.1 * 0.1, sigma = 1.0e6, c = 0.4e6, phi = 35.0 * M_PI / 180;
    const double f_s = c + sigma * std::tan(phi);  // Pa
    sim.begin_stage(0);
    while (!sim.stage_finished()) sim.step();
    sim.begin_stage(1);
    double peak = 0, last = 0, low_late = 1e300, high_late = 0, sum_late = 0;
    long n_late = 0;
    while (!sim.stage_finished()) {
        sim.step();
        last = sim.monitor_value(1) / A;
        peak = std::max(peak, last);
        if (sim.time() > 0.004 + 0.008) {  // second half of the drag
            low_late = std::min(low_late, last), high_late = std::max(high_late, last);
            sum_late += last, ++n_late;
        }
    }
    const fdem::Energies e = sim.energies();
    const auto* j = sim.interactions().joints();
    REQUIRE(j != nullptr);
    int broken = 0;
    for (int k = 0; k < j->size(); ++k) broken += static_cast<int>(j->state(k)) == 2;
    const double slip = sim.monitor_value(0);
    std::printf("[mc] peak tau %.6g Pa, end %.6g Pa, second half %.6g..%.6g Pa, mean %.6g Pa (c + sigma tan(phi) %.6g Pa); "
                "slip %.4g m; broken %d; D_fric %.5g J (f_s A slip %.5g J); D_frac %.3g J; balance %.3g\n",
                peak, last, low_late, high_late, sum_late / n_late, f_s, slip, broken, e.friction, f_s * A * slip, e.fracture, e.balance_error());
    // The reaction rings about the plateau while the joint slips (the blocks' elastic modes excited at the law's sharp
    // yield corner; measured -0.8 % .. +2.5 %); its mean over the second half of the drag is c + sigma tan(phi) to
    // 0.2 % (measured): no softening.
    CHECK(peak / f_s == Approx(1.0).epsilon(0.03));
    CHECK(low_late / f_s == Approx(1.0).epsilon(0.03));
    CHECK(high_late / f_s == Approx(1.0).epsilon(0.03));
    CHECK(sum_late / n_late / f_s == Approx(1.0).epsilon(0.005));
    CHECK(broken == 0);
    CHECK(e.friction == Approx(f_s * A * slip).epsilon(0.1));  // less the elastic slip and the ramp: within 10 %
    CHECK(e.balance_error() < 0.01);
}
