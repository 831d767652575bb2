// tests/core/test_body_step.cpp: the stable step of rigid bodies and held nodes (fdem/body_step.hpp).
//
// CLOSED FORMS. body_omega2 is the largest omega^2 of the body's three DOFs (X, Y, theta) on springs k_k at its nodes:
//   two equal masses m at (+-a, 0), a spring k at each: translation k / m in x and y, rotation 2 k a^2 / (2 m a^2)
//   = k / m: omega^2 = k / m;
//   the same with the spring at one node only: the node's effective mass 1 / (1 / M + r^2 / I) = m, omega^2 = k / m;
//   three nodes on a line at -a, 0, a (masses m), springs k at the ends: omega^2 = max(2 k / 3 m, 2 k a^2 / 2 m a^2)
//   = k / m (rotation).
// ENGINE. A block on a fixed base with rigid = "body" in every stage: the block is one body, the base's nodes held,
// the step set by the body (its triangles and its nodes' masses no longer count) and larger than the elastic block's;
// a later stage that frees the block, or a body in the second stage only, leaves the bound as for elastic nodes.
// STABILITY. At safety 1 (the bound itself), undamped: the rigid block resting on elastic contact (e = 1) stays at
// rest for 0.2 s (books within 1e-6 of m g h, h its height); dropped 2 mm on contact with restitution 0.5 it lands,
// bounces and settles (books within 5 % of m g h at every step, its kinetic energy at 0.2 s below 1 % of it), as at
// the default safety. An unstable step grows the energy without bound. (The large step resolves an impact in about
// ten steps: the books' error while it lands, 0.6-1.6 %, is that of the impact, not growth.)
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "engine_helpers.hpp"
#include "fdem/body_step.hpp"

TEST_CASE("rigid body step: body_omega2 gives the closed forms of two- and three-node bodies", "[engine][unit]") {
    const double m = 2.0, k = 5e6, a = 0.3;
    {
        const double x[4] = {-a, 0.0, a, 0.0}, mass[2] = {m, m}, kk[2] = {k, k};
        CHECK(fdem::body_omega2({0, 1}, x, mass, kk) == Approx(k / m).epsilon(1e-12));
    }
    {
        const double x[4] = {-a, 0.0, a, 0.0}, mass[2] = {m, m}, kk[2] = {0.0, k};
        CHECK(fdem::body_omega2({0, 1}, x, mass, kk) == Approx(k / m).epsilon(1e-12));
    }
    {
        const double x[6] = {-a, 0.0, 0.0, 0.0, a, 0.0}, mass[3] = {m, m, m}, kk[3] = {k, 0.0, k};
        CHECK(fdem::body_omega2({0, 1, 2}, x, mass, kk) == Approx(k / m).epsilon(1e-12));
    }
}

namespace {

// A 0.2 x 0.1 m block (E 1e10, mesh 0.05 m) on a fixed 0.6 x 0.1 m base, dry contact k_n 1e11 Pa/m; stages as given.
std::string block_case(const std::string& stages, double safety = 0.8, double lift = 0.0, double e = 1.0) {
    std::ostringstream g;
    g << "SetFactory(\"OpenCASCADE\");\nRectangle(1) = {-0.3, -0.1, 0, 0.6, 0.1};\nRectangle(2) = {-0.1, " << lift
      << ", 0, 0.2, 0.1};\nMeshSize{ PointsOf{ Surface{1:2}; } } = 0.05;\n"
      << "Physical Surface(\"base\") = {1};\nPhysical Surface(\"block\") = {2};\n";
    const std::string geo = testing::write_text(testing::tmp_dir("body_step_geo") / "blocks.geo", g.str());
    std::ostringstream c;
    c << "[case]\nname = \"body_step\"\nthickness = 0.1\n[geometry]\ntype = \"gmsh\"\nfile = \"" << geo << "\"\n"
      << "[materials.m]\nE = 1e10\nnu = 0.2\ndensity = 2000.0\n[regions]\nbase = \"m\"\nblock = \"m\"\n"
      << "[[interfaces]]\nregions = [\"base\", \"block\"]\nkind = \"dry\"\nfriction = 30.0\nnormal_stiffness = 1e11\nrestitution = " << e
      << "\n[numerics]\nsafety = " << safety << "\n" << stages;
    return c.str();
}

const char* kFixedBase = "  [[stages.supports]]\n  group = \"base\"\n  fix = \"xy\"\n";
const char* kBody = "  [[stages.supports]]\n  group = \"block\"\n  rigid = \"body\"\n";

std::string stage(const std::string& name, const std::string& supports) {
    return "[[stages]]\nname = \"" + name + "\"\nduration = 0.01\nlocal_damping = 0.0\ngravity = [0.0, -9.81]\n" +
           supports;
}

}  // namespace

TEST_CASE("rigid body step: a block rigid all run long takes its body's step, larger than the elastic block's, "
          "a body for part of the run does not",
          "[engine][regression]") {
    fdem::Simulation elastic = testing::make_simulation(block_case(stage("a", kFixedBase)), "body_step_elastic", {}, 1);
    fdem::Simulation body =
        testing::make_simulation(block_case(stage("a", std::string(kFixedBase) + kBody) + stage("b", "")),
                                 "body_step_body", {}, 1);
    const fdem::RigidBodies& rb = body.bodies();
    REQUIRE(rb.nodes.size() == 1);
    CHECK(rb.group[0] == "block");
    CHECK(rb.nodes[0].size() == body.model().group("block").nodes.size());
    for (int k : body.model().group("base").nodes) CHECK(rb.held[k] == 1);
    CHECK(body.nodal_limit().body == 0);
    std::printf("[body step] elastic block %.4e s, rigid body %.4e s\n", elastic.dt(), body.dt());
    CHECK(body.dt() > 1.5 * elastic.dt());
    CHECK(body.nodal_limit().k_contact > 0.0);  // (the body's sums: contact springs at its nodes)
    // freed in the second stage, or a body only from the second stage: the nodes' own bound
    fdem::Simulation freed = testing::make_simulation(
        block_case(stage("a", std::string(kFixedBase) + kBody) +
                   stage("b", "  [[stages.supports]]\n  group = \"block\"\n  free = \"xy\"\n")),
        "body_step_freed", {}, 1);
    CHECK(freed.bodies().nodes.empty());
    CHECK(freed.dt() == elastic.dt());
    fdem::Simulation late =
        testing::make_simulation(block_case(stage("a", kFixedBase) + stage("b", kBody)), "body_step_late", {}, 1);
    CHECK(late.bodies().nodes.empty());
    CHECK(late.dt() == elastic.dt());
}

namespace {

struct Drop {
    int landings = 0;
    double worst = 0, final_kinetic = 0, scale = 0, dt = 0;
};

// The rigid block released `lift` above the base (restitution e), undamped, 0.2 s at `safety`.
Drop drop(double safety, double lift, double e) {
    const std::string st = "[[stages]]\nname = \"drop\"\nduration = 0.2\nlocal_damping = 0.0\ngravity = [0.0, -9.81]\n" +
                           std::string(kFixedBase) + kBody;
    fdem::Simulation sim = testing::make_simulation(block_case(st, safety, lift, e), "body_step_drop", {}, 1);
    sim.energy_every_step(true);
    sim.begin_stage(0);
    Drop d;
    bool was_touching = false;
    while (!sim.stage_finished()) {
        sim.step();
        const fdem::Energies en = sim.energies();
        // (external: the work done plus the energy held at the start)
        const double held = en.kinetic + en.elastic + en.contact + en.friction + en.damping + en.viscous;
        d.worst = std::max(d.worst, std::fabs(held - en.external));
        const bool touching = en.contact > 0.0;
        if (touching && !was_touching) ++d.landings;
        was_touching = touching;
        d.final_kinetic = en.kinetic;
    }
    d.dt = sim.dt();
    d.scale = 0.2 * 0.1 * 0.1 * 2000.0 * 9.81 * (lift > 0.0 ? lift : 0.1);  // m g (drop height, or the block's height) (J)
    std::printf("[body step] safety %.1f, lift %.3f m, e %.1f: dt %.3e s, %d landings, largest imbalance %.3e J, "
                "kinetic energy at 0.2 s %.3e J, of %.3e J\n", safety, lift, e, d.dt, d.landings, d.worst,
                d.final_kinetic, d.scale);
    return d;
}

}  // namespace

TEST_CASE("rigid body step: at safety 1 the rigid block resting on undamped contact stays at rest, and dropped on "
          "inelastic contact settles",
          "[engine][regression]") {
    const Drop rest = drop(1.0, 0.0, 1.0);
    CHECK(rest.worst < 1e-6 * rest.scale);
    CHECK(rest.final_kinetic < 1e-6 * rest.scale);
    for (double safety : {1.0, 0.8}) {
        const Drop d = drop(safety, 0.002, 0.5);
        CHECK(d.landings >= 2);
        CHECK(d.worst < 0.05 * d.scale);
        CHECK(d.final_kinetic < 0.01 * d.scale);
    }
}
