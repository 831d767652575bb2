// tests/contact/test_rocking.cpp: a block rocking on a fixed base through the engine against the rigid block
// (Housner 1963), with an inelastic contact (issue 54, item 2). Scene, measurements and closed form:
// rocking_run.hpp and rocking_exact.hpp; the study behind the settings: tests/contact/rocking_study/RESULTS.md.
//
// SCENE. A 0.2 x 1.0 m block on two pads 0.01 m wide at its bottom corners (so that, as Housner assumes, it lands
// on its corners), E 1e11 Pa, on k_n = k_s = 1e11 Pa/m, mu 0.8, restitution 0.2, released at rest from half its
// slenderness angle, theta0 = 0.0987 rad; 1.0 s: two impacts (2.5 million steps, about 2 minutes).
// CLOSED FORM. The rigid block of the same masses (alpha 0.1965 rad): the first impact at 0.3486 s; each impact
// keeps r = 0.9454 of the angular velocity with the impulse at the pads' centres (Housner's r at the corners:
// 0.9426). Measured: first impact +0.69 %, second +0.85 %, the amplitude before it +0.15 %, r +0.05 %.
// ASSERTIONS. First impact time within 2 %; r of the first impact (from the amplitudes either side) within 2 % of
// the pads' value and of Housner's; the second impact time and the amplitude before it within 2 %; the two pivots
// never off the base at once by more than the contact's static penetration (no hop); books within 0.5 %.
// The five-impact version is tests/validation/test_rocking_long.cpp.
#include <catch2/catch.hpp>

#include "contact/rocking_run.hpp"

using namespace contact_test;

TEST_CASE("engine rocking: a block on its corners with restitution 0.2 rocks as Housner's rigid block, first two "
          "impacts within 2 %, no hop",
          "[engine][regression]") {
    const RockingSetup s = housner_setting(1.0);
    const RockingResult r = rock(s, "rocking");
    std::vector<double> rt, ra;
    print_rocking(r, s, rt, ra);
    REQUIRE(r.times.size() >= 2);
    REQUIRE(r.amplitudes.size() >= 2);
    CHECK(r.times[0] == Approx(rt[0]).epsilon(0.02));
    CHECK(r.times[1] == Approx(rt[1]).epsilon(0.02));
    CHECK(r.amplitudes[1] == Approx(ra[1]).epsilon(0.02));
    const double r1 = print_measured_r(r, 0);
    CHECK(r1 == Approx(r.rigid.r(r.x_p)).epsilon(0.02));
    CHECK(r1 == Approx(r.rigid.r(r.rigid.b)).epsilon(0.02));
    CHECK(r.hop <= r.static_penetration);
    CHECK(std::fabs(r.books) < 5e-3);
}

TEST_CASE("restitution: a value outside 0 < e <= 1 is an input error naming the key", "[unit]") {
    const std::string geo = testing::write_text(
        testing::tmp_dir("restitution_bad_geo") / "two.geo",
        "SetFactory(\"OpenCASCADE\");\nRectangle(1) = {0, -0.1, 0, 0.3, 0.1};\nRectangle(2) = {0.1, 0, 0, 0.1, 0.1};\n"
        "MeshSize{ PointsOf{ Surface{1, 2}; } } = 0.05;\nPhysical Surface(\"base\") = {1};\nPhysical Surface(\"block\") = {2};\n");
    for (const char* e : {"0.0", "1.5", "-0.2"}) {
        const std::string c = std::string("[case]\nname = \"bad\"\nthickness = 1.0\n[geometry]\ntype = \"gmsh\"\nfile = \"") +
                              geo + "\"\n[materials.m]\nE = 1e10\nnu = 0.2\ndensity = 2000.0\n[regions]\nbase = \"m\"\n"
                              "block = \"m\"\n[[interfaces]]\nregions = [\"base\", \"block\"]\nkind = \"dry\"\nfriction = 30.0\n"
                              "normal_stiffness = 1e10\nrestitution = " + e + "\n[[stages]]\nname = \"s\"\nduration = 0.01\n";
        CHECK_THROWS_WITH(testing::make_simulation(c, "restitution_bad"),
                          Catch::Contains("restitution") && Catch::Contains("(0, 1]"));
    }
}

// The block as one rigid body (rigid = "body"), which takes the step of its mass and inertia (fdem/body_step.hpp),
// on a contact ten times stiffer, k_n 1e12 Pa/m, restitution 0.2: 1.1 s, 447,000 steps (about 25 s). Measured
// (tests/contact/rocking_study/RESULTS.md): first impact +0.21 %, second -0.04 %, the amplitude before it -0.45 %,
// r -0.16 % of the pads' value, no hop. The stiffer contact is closer to the rigid block: at k_n 1e11 the same body
// gives +0.66 %, -1.36 % and -0.50 %.
TEST_CASE("engine rocking as one rigid body on k_n 1e12: the first two impacts within 0.5 % of Housner's rigid "
          "block, no hop",
          "[engine][regression]") {
    RockingSetup s = housner_setting(1.1);
    s.kn = 1e12, s.body = true;
    const RockingResult r = rock(s, "rocking_body");
    std::vector<double> rt, ra;
    print_rocking(r, s, rt, ra);
    REQUIRE(r.times.size() >= 2);
    REQUIRE(r.amplitudes.size() >= 2);
    CHECK(r.times[0] == Approx(rt[0]).epsilon(0.005));
    CHECK(r.times[1] == Approx(rt[1]).epsilon(0.005));
    CHECK(r.amplitudes[1] == Approx(ra[1]).epsilon(0.005));
    const double r1 = print_measured_r(r, 0);
    CHECK(r1 == Approx(r.rigid.r(r.x_p)).epsilon(0.005));
    CHECK(r.hop <= r.static_penetration);
    CHECK(std::fabs(r.books) < 1e-4);
}
