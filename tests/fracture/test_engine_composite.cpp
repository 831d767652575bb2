// tests/fracture/test_engine_composite.cpp: the composite joint law (fracture/composite_law.hpp) through the engine.
// A bonded interface between two blocks (tests/fracture/cases/mode2_shear.*) pressed by 3 MPa and dragged sideways
// as a rigid body: the slip and the normal stress are uniform along the joint, so the interface's shear force over
// its area is the law's tau. Closed form: peak c_0 + sigma tan(theta_0), then the cohesion softens to zero while
// the friction sigma tan(theta_res) stays ([PDEM] §2: c_res = 0, theta kept); the cap (f_m 10.5 MPa, C_s 9) is not
// reached (sigma^2 + 9 tau^2 = 65 < 110 MPa^2 at the peak).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/engine_helpers.hpp"
#include "fdem/common/errors.hpp"
#include "fdem/scene.hpp"
#include "fracture/cohesive_system.hpp"

namespace {

namespace fs = std::filesystem;

fs::path cases_dir() {
    return fs::path(__FILE__).parent_path() / "cases";
}

// As tests/fracture/test_engine_fracture.cpp: the case and its .geo in tmp/<name>/, built with its topology.
fdem::Simulation make_sim(const std::string& name, const std::vector<std::string>& overrides) {
    const auto dir = testing::tmp_dir(name);
    testing::write_text(dir / "mode2_shear.geo", testing::read_text(cases_dir() / "mode2_shear.geo"));
    const std::string path =
        testing::write_text(dir / "case.toml", testing::read_text(cases_dir() / "mode2_shear.toml"));
    fdem::CaseSpec spec = fdem::load_case(path, overrides);
    fdem::Model model = fdem::build_scene(spec);
    fdem::RunOptions opt;
    opt.quiet = true;
    opt.threads = 1;
    return fdem::Simulation(spec, std::move(model), opt);
}

}  // namespace

TEST_CASE("engine composite law: a joint sheared under high compression keeps sigma tan(theta) while c softens",
          "[engine][regression]") {
    const double A = 0.1 * 0.1, sigma = 3.0e6, c = 0.4e6;  // m^2, Pa, Pa (the case's cohesion)
    const double mu = std::tan(35.0 * M_PI / 180.0);
    auto sim = make_sim("fracture_engine_composite",
                        {"interfaces.1.law=\"composite\"", "interfaces.1.residual_friction=35.0",
                         "interfaces.1.compressive_strength=10.5e6", "interfaces.1.compressive_energy=5000.0",
                         "interfaces.1.cap_shear_factor=9.0", "stages.1.loads.1.pressure=3.0e6",
                         // kappa_u = 2 G_II / c = 0.25 mm of plastic slip after s_p = 25 um: 0.04 s at 0.01 m/s
                         "stages.2.duration=0.04"});
    sim.begin_stage(0);
    while (!sim.stage_finished()) sim.step();
    sim.begin_stage(1);
    const auto* joints = sim.interactions().joints();
    REQUIRE(joints != nullptr);
    REQUIRE(joints->has_composite());
    double peak = 0.0, low_softening = 1e30, t_first_break = -1.0, crush = 0.0, tau_at_break = 0.0;
    bool past_peak = false;
    while (!sim.stage_finished()) {
        sim.step();
        const double tau = sim.monitor_value(1) / A;
        peak = std::max(peak, tau);
        past_peak = past_peak || (peak > 0.5 * (c + sigma * mu) && tau < 0.99 * peak);  // (not the ramp's start)
        long long broken = 0;
        for (int e = 0; e < joints->size(); ++e) {
            broken += joints->state(e) == fdem::fracture::JointState::broken;
            crush = std::max(crush, joints->crush_damage(e));
        }
        if (broken == 0 && past_peak) low_softening = std::min(low_softening, tau);
        if (broken > 0 && t_first_break < 0.0) t_first_break = sim.time(), tau_at_break = tau;
    }
    std::printf(
        "composite law under sigma = %.3g Pa: peak tau %.6g Pa (c + sigma tan = %.6g), lowest tau while "
        "softening %.6g Pa (sigma tan = %.6g), first break at %.4g s with tau %.6g Pa, largest D_c %.3g\n",
        sigma, peak, c + sigma * mu, low_softening, sigma * mu, t_first_break, tau_at_break, crush);
    // Peak on the Mohr-Coulomb line of the intact joint (1 %, the reaction's dynamics).
    CHECK(peak / (c + sigma * mu) == Approx(1.0).epsilon(0.01));
    // While the cohesion softens the joint keeps the friction (2 % for the wobble) and does reach it: the last of the
    // cohesion is gone before the first element breaks (within 5 % of c above sigma tan(theta)).
    REQUIRE(t_first_break > 0.0);
    CHECK(low_softening / (sigma * mu) > 0.98);
    CHECK(low_softening < sigma * mu + 0.05 * c);
    // The cap is not reached: no compressive damage.
    CHECK(crush == 0.0);
}

// Bad input (exit code 1 through InputError): the cap keys are all three or none, and belong to the composite law.
TEST_CASE("engine composite law: case errors name the key for a partial cap and for cap keys without the law",
          "[unit]") {
    const auto dir = testing::tmp_dir("fracture_composite_errors");
    testing::write_text(dir / "mode2_shear.geo", testing::read_text(cases_dir() / "mode2_shear.geo"));
    const std::string path =
        testing::write_text(dir / "case.toml", testing::read_text(cases_dir() / "mode2_shear.toml"));
    auto message = [&](const std::vector<std::string>& overrides) {
        try {
            fdem::load_case(path, overrides);
        } catch (const fdem::InputError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    const std::string partial = message({"interfaces.1.law=\"composite\"", "interfaces.1.compressive_strength=1e7"});
    INFO(partial);
    CHECK(partial.find("interfaces.1.law") != std::string::npos);
    CHECK(partial.find("all three cap keys") != std::string::npos);
    const std::string stray = message({"interfaces.1.cap_shear_factor=9.0"});
    INFO(stray);
    CHECK(stray.find("interfaces.1.cap_shear_factor") != std::string::npos);
    CHECK(stray.find("only with law = \"composite\"") != std::string::npos);
    const std::string soft = message({"interfaces.1.law=\"composite\"", "interfaces.1.shear_softening=\"cohesion\""});
    INFO(soft);
    CHECK(soft.find("interfaces.1.shear_softening") != std::string::npos);
    CHECK(message({"interfaces.1.law=\"composite\""}).empty());  // no cap at all is fine
}
