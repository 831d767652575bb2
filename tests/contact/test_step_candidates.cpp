// tests/contact/test_step_candidates.cpp: the automatic step counts the contact springs of the faces near a candidate
// pair only, and shrinks at the detection that brings new ones (issue 53; fdem/README.md 'Time step').
//
// THE BOUND. dt = safety * min(dt_t, 2 / sqrt(max_i (k_tri,i + k_contact,i) / m_i)) (no joints here). k_contact,i
// sums k t L over the faces at node i that were within the detection buffer of a candidate partner at the last
// detection, k the slope of that pair's law (ContactSystem::node_stiffness(x, held, true)); the rule before counted
// every face at the stiffest law its material can meet (node_stiffness(x, held, false)). A pair not in the list
// cannot touch before the next detection, and a face farther than the buffer from its partner cannot load until
// then, so every spring that can load is counted as long as the step is bounded again at each detection.
//
// SCENE. Two elastic blocks 0.2 x 0.1 m (E 0.1 GPa, nu 0.2, 2000 kg/m^3, t 0.1 m, mesh 0.01 m), 0.01 m apart along x
// (the buffer is the smallest edge / 5, about 1.5 mm: no face is near the other block at the start), a frictionless
// undamped dry interface with k_n = 5e10 Pa/m (its springs k_n t L = 5e7 N/m per 0.01 m face), no gravity. Block a
// moves at +1 m/s, b at -0.5 m/s: they meet after about 6.7 ms, collide (the bars' wave round trip 2 L / c, about
// 1.8 ms) and part. The step starts at 1.89e-5 s (the triangles' bound) and shrinks to the old rule's 9.92e-6 s.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "core/engine_helpers.hpp"
#include "fdem/common/state_io.hpp"
#include "fdem/scene.hpp"

namespace {

const char* kGeo =
    "SetFactory(\"OpenCASCADE\");\nRectangle(1) = {0, 0, 0, 0.2, 0.1};\nRectangle(2) = {0.21, 0, 0, 0.2, 0.1};\n"
    "MeshSize{ PointsOf{ Surface{1}; } } = 0.01;\nMeshSize{ PointsOf{ Surface{2}; } } = 0.01;\n"
    "Physical Surface(\"a\") = {1};\nPhysical Surface(\"b\") = {2};\n";

const char* kCase = R"(
[case]
name = "step_candidates"
thickness = 0.1
[geometry]
type = "gmsh"
file = "blocks.geo"
[materials.m]
E = 1.0e8
nu = 0.2
density = 2000.0
[regions]
a = "m"
b = "m"
[[interfaces]]
regions = ["a", "b"]
kind = "dry"
friction = 0.0
normal_stiffness = 5.0e10
[[stages]]
name = "collide"
duration = 0.012
local_damping = 0.0
)";

// The scene with topology (the blocks share no node), the blocks launched towards each other, stage 0 begun.
fdem::Simulation launched(const std::string& name, int threads) {
    const auto dir = testing::tmp_dir(name);
    testing::write_text(dir / "blocks.geo", kGeo);
    const std::string path = testing::write_text(dir / "case.toml", kCase);
    fdem::CaseSpec spec = fdem::load_case(path, {});
    fdem::Model model = fdem::build_scene(spec);
    fdem::RunOptions opt;
    opt.quiet = true;
    opt.threads = threads;
    fdem::Simulation sim(spec, std::move(model), opt);
    sim.energy_every_step(true);
    fdem::Model& md = sim.model();
    for (int k : md.group("a").nodes) md.v[2 * k] = 1.0;
    for (int k : md.group("b").nodes) md.v[2 * k] = -0.5;
    sim.begin_stage(0);
    return sim;
}

// safety * the nodal bound with the triangles' share and the contact count of node_stiffness(X, nullptr, candidates),
// and safety * dt_t (s).
struct Bounds {
    double nodal = 0, triangles = 0;
    std::vector<double> kc;  // N/m per node
};
Bounds bounds(const fdem::Simulation& sim, bool candidates) {
    const fdem::Model& md = sim.model();
    const int nn = md.n_nodes();
    std::vector<double> kt(nn, 0.0);
    fdem::add_triangle_node_stiffness(sim.spec(), md, nullptr, kt.data());
    Bounds b;
    b.kc = sim.interactions().contact()->node_stiffness(md.X.data(), nullptr, candidates);
    double w2 = 0;
    for (int k = 0; k < nn; ++k) w2 = std::max(w2, (kt[k] + b.kc[k]) / md.mass[k]);
    b.nodal = sim.spec().safety * 2.0 / std::sqrt(w2);
    b.triangles = sim.spec().safety * fdem::triangle_step_limit(sim.spec(), md).dt;
    return b;
}

std::string state_of(const fdem::Simulation& sim) {
    fdem::StateWriter w;
    sim.save_state(w);
    return w.data();
}

}  // namespace

TEST_CASE("contact step: blocks launched from beyond the buffer start at the step without contact springs, shrink "
          "when they become candidates, stay within the bound of the springs near candidates and conserve energy",
          "[engine][unit]") {
    auto sim = launched("step_candidates", 1);
    const fdem::contact::ContactSystem* cs = sim.interactions().contact();
    REQUIRE(cs != nullptr);
    const fdem::Model& md = sim.model();
    // At the start no face is near a candidate partner: the step is that of the triangles and their nodal shares.
    const Bounds start = bounds(sim, true), old_rule = bounds(sim, false);
    for (double k : start.kc) REQUIRE(k == 0.0);
    const double dt0 = sim.dt();
    CHECK(dt0 == Approx(std::min(start.nodal, start.triangles)).epsilon(1e-12));
    CHECK(dt0 > 1.3 * old_rule.nodal);  // the rule that counted every face
    const fdem::Energies e0 = sim.energies();
    const double E0 = e0.kinetic + e0.elastic + e0.contact;
    double worst = 0, peak_contact = 0, dt_first_shrink = 0;
    long shrinks = 0;
    double prev = sim.dt();
    bool facing_checked = false;
    while (!sim.stage_finished()) {
        sim.step();
        // The step is never above the bound of the springs that can load until the next detection.
        const Bounds now = bounds(sim, true);
        REQUIRE(sim.dt() <= std::min(now.nodal, now.triangles) * (1 + 1e-12));
        REQUIRE(sim.dt() <= prev);  // never grows
        if (sim.dt() < prev) {
            ++shrinks;
            if (dt_first_shrink == 0) dt_first_shrink = sim.dt();
        }
        prev = sim.dt();
        const fdem::Energies e = sim.energies();
        worst = std::max(worst, e.balance_error());
        // In contact every node of the two facing sides (x = 0.2 and 0.21 m) counts what the old rule counted: the
        // detection before the touch found every facing edge within the buffer of the other block.
        if (!facing_checked && e.contact > 0) {
            const Bounds all = bounds(sim, false);
            int n_facing = 0;
            for (int k = 0; k < md.n_nodes(); ++k) {
                const double X = md.X[2 * k];
                if (std::fabs(X - 0.2) > 1e-9 && std::fabs(X - 0.21) > 1e-9) continue;
                ++n_facing;
                CHECK(now.kc[k] == all.kc[k]);
            }
            CHECK(n_facing >= 22);  // 11 nodes a side at 0.01 m
            facing_checked = true;
        }
        peak_contact = std::max(peak_contact, e.contact);
    }
    const fdem::Energies e1 = sim.energies();
    const double E1 = e1.kinetic + e1.elastic + e1.contact;
    const double va = [&] {
        double p = 0, m = 0;
        for (int k : md.group("a").nodes) p += md.mass[k] * md.v[2 * k], m += md.mass[k];
        return p / m;
    }();
    std::printf("[step candidates] dt at the start %.6g s (old rule %.6g s), first shrink to %.6g s, at the end %.6g s "
                "after %ld shrinks; peak contact energy %.3g of %.3g J, energy change %.3g %%, worst balance %.3g %%, "
                "block a after %.4f m/s\n",
                dt0, old_rule.nodal, dt_first_shrink, sim.dt(), shrinks, peak_contact, E0, 100 * (E1 - E0) / E0,
                100 * worst, va);
    CHECK(facing_checked);
    CHECK(peak_contact > 1e-3 * E0);  // they collided
    CHECK(va < 0.0);                 // and parted (equal masses, elastic: a leaves at about -0.5 m/s)
    CHECK(shrinks >= 1);
    CHECK(sim.dt() < dt0);
    CHECK(sim.dt() >= old_rule.nodal * (1 - 1e-12));  // never below the rule that counts every face
    // The old rule's limiting node is on a facing side (its count there is the old one, above): the step shrinks to
    // the old rule's at the detection that finds the facing edges near, and stays there.
    CHECK(dt_first_shrink == Approx(old_rule.nodal).epsilon(1e-12));
    CHECK(sim.dt() == Approx(old_rule.nodal).epsilon(1e-12));
    CHECK(std::fabs(E1 - E0) < 0.01 * E0);
    CHECK(worst < 0.01);
}

TEST_CASE("contact step: a state saved after the step shrank at a new candidate and loaded into a fresh simulation "
          "runs on to the uninterrupted run's state byte for byte",
          "[engine][regression]") {
    auto a = launched("step_candidates_a", 1);
    const double dt0 = a.dt();
    long shrink_step = -1;
    while (!a.stage_finished()) {
        a.step();
        if (shrink_step < 0 && a.dt() < dt0) shrink_step = a.steps();
    }
    REQUIRE(shrink_step > 0);
    const std::string end_a = state_of(a);

    // Saved a few steps after the first shrink (the collision still ahead: more shrinks may follow the load).
    auto b = launched("step_candidates_b", 1);
    while (b.steps() < shrink_step + 3) b.step();
    REQUIRE(b.dt() < dt0);
    const std::string mid = state_of(b);
    auto c = launched("step_candidates_c", 1);
    fdem::StateReader r(mid.data(), mid.size());
    c.load_state(r);
    CHECK(state_of(c) == mid);
    CHECK(c.dt() == b.dt());
    while (!c.stage_finished()) c.step();
    CHECK(c.steps() == a.steps());
    CHECK(c.dt() == a.dt());
    CHECK(state_of(c) == end_a);
}

TEST_CASE("contact step: the run with its step shrinking at new candidates gives the same bits on 1 and 2 threads",
          "[engine][regression]") {
    auto one = launched("step_candidates_t1", 1);
    auto two = launched("step_candidates_t2", 2);
    const double dt0 = one.dt();
    while (!one.stage_finished()) one.step();
    while (!two.stage_finished()) two.step();
    REQUIRE(one.dt() < dt0);
    CHECK(two.steps() == one.steps());
    CHECK(two.dt() == one.dt());
    CHECK(state_of(two) == state_of(one));
}
