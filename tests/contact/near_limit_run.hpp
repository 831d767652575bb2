// tests/contact/near_limit_run.hpp: stick-slip near the friction limit through the engine, shared by
// tests/contact/test_stick_slip_engine.cpp (8 s) and tests/validation/test_stick_slip_long.cpp (20 s, three forms of
// the same force history).
//
// SCENE. A 1 kg block 0.2 x 0.025 m (thickness 0.1 m, 2000 kg/m^3; E 1e10 Pa, nu 0.2, mesh 0.025 m) on a fixed base
// 0.7 x 0.1 m (mesh 0.1 m), a dry interface k_n 1e11 Pa/m (k_s the default), mu = 0.8 (friction atan 0.8), settled
// 0.05 s under gravity with local damping 0.7; then F = 1.02 mu m g cos(t) on the block's top edge, no local damping,
// contact dashpots xi, the block a rigid group (rigid = "xy": one velocity for all its nodes).
// CLOSED FORM (stick_slip_exact.hpp, phase pi/2): it slides at once (F(0) > mu m g), stops at 0.344 s after 4.63 mm,
// then slides 13.90 mm each way (stops at 3.539, 6.681, 9.822 s, ...). The first slide comes out 0.06 mm long: the
// sudden load meets an unstretched friction spring (an impulse deficit of about mu m g / sqrt(k_t / m)), which shrinks
// as the tangential stiffness grows.
// FORMS of the force history: a "sin" time function; a "table" time function of cos t at 0.01 s (piecewise linear,
// within 1.3e-5 of cos); 0.5 s stages, each with its own table of cos t at 0.01 s from its start.
#pragma once

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "core/engine_helpers.hpp"
#include "fdem/scene.hpp"
#include "stick_slip_exact.hpp"

namespace contact_test {

enum class ForceForm { sin, table, stages };

struct NearLimitResult {
    std::vector<Stop> stops, exact;
    double amplitude = 0;  // m, the exact whole slide (second stop to first)
    double books = 0;      // (held - worked) / worked over the push
};

inline double group_mean(const fdem::Simulation& sim, const std::string& group, const std::vector<double>& field, int c) {
    const auto& nodes = sim.model().group(group).nodes;
    double sm = 0, s = 0;
    for (int k : nodes) {
        const double m = sim.model().mass[k];
        sm += m;
        s += m * field[2 * k + c];
    }
    return s / sm;
}

// Points [t, cos(t)] every 0.01 s from t0 over dur (s), times counted from t0.
inline std::string cos_table(double t0, double dur) {
    std::ostringstream p;
    p.precision(17);
    const int n = static_cast<int>(std::lround(dur / 0.01));
    p << "{ type = \"table\", points = [";
    for (int i = 0; i <= n; ++i) p << (i ? ", " : "") << "[" << 0.01 * i << ", " << std::cos(t0 + 0.01 * i) << "]";
    p << "] }";
    return p.str();
}

inline NearLimitResult run_near_limit(double duration, double xi, ForceForm form) {
    const double kMuN = 0.8, kGN = 9.81, m = 1.0, f0 = 1.02 * kMuN * m * kGN;
    NearLimitResult out;
    out.exact = exact_stops(f0 / m, 1.0, duration, kMuN, kGN, M_PI / 2);
    if (out.exact.size() >= 2) out.amplitude = out.exact[0].x - out.exact[1].x;
    std::ostringstream g;
    g << "SetFactory(\"OpenCASCADE\");\nRectangle(1) = {-0.3, -0.1, 0, 0.7, 0.1};\nRectangle(2) = {0, 0, 0, 0.2, 0.025};\n"
      << "MeshSize{ PointsOf{ Surface{1}; } } = 0.1;\nMeshSize{ PointsOf{ Surface{2}; } } = 0.025;\n"
      << "Physical Surface(\"base\") = {1};\nPhysical Surface(\"block\") = {2};\nPhysical Curve(\"block_top\") = {7};\n";
    std::ostringstream c;
    c.precision(17);
    c << "[case]\nname = \"near_limit\"\nthickness = 0.1\n[geometry]\ntype = \"gmsh\"\nfile = \"blocks.geo\"\n"
      << "[materials.m]\nE = 1.0e10\nnu = 0.2\ndensity = 2000.0\n[regions]\nbase = \"m\"\nblock = \"m\"\n"
      << "[[interfaces]]\nregions = [\"base\", \"block\"]\nkind = \"dry\"\nfriction = " << std::atan(kMuN) * 180 / M_PI
      << "\nnormal_stiffness = 1e11\n"
      << "[[stages]]\nname = \"settle\"\nduration = 0.05\nlocal_damping = 0.7\ngravity = [0.0, -9.81]\n"
      << "  [[stages.supports]]\n  group = \"base\"\n  fix = \"xy\"\n";
    const double piece = form == ForceForm::stages ? 0.5 : duration;
    const int pieces = static_cast<int>(std::lround(duration / piece));
    for (int k = 0; k < pieces; ++k) {
        c << "[[stages]]\nname = \"push" << k << "\"\nduration = " << piece << "\nlocal_damping = 0.0\ncontact_damping = " << xi
          << "\ngravity = [0.0, -9.81]\n  [[stages.supports]]\n  group = \"base\"\n  fix = \"xy\"\n"
          << "  [[stages.supports]]\n  group = \"block\"\n  rigid = \"xy\"\n"
          << "  [[stages.loads]]\n  group = \"block_top\"\n  force = [" << f0 << ", 0.0]\n  function = ";
        if (form == ForceForm::sin)
            c << "{ type = \"sin\", amplitude = 1.0, omega = 1.0, phase = " << M_PI / 2 << ", offset = 0.0 }\n";
        else
            c << cos_table(k * piece, piece) << "\n";
    }
    const char* names[] = {"sin", "table", "stages"};
    const auto dir = testing::tmp_dir(std::string("near_limit_") + names[static_cast<int>(form)]);
    testing::write_text(dir / "blocks.geo", g.str());
    const std::string path = testing::write_text(dir / "case.toml", c.str());
    fdem::CaseSpec spec = fdem::load_case(path, {});
    fdem::Model model = fdem::build_scene(spec);
    fdem::RunOptions opt;
    opt.quiet = true;
    opt.threads = 1;
    fdem::Simulation sim(spec, std::move(model), opt);
    sim.begin_stage(0);
    while (!sim.stage_finished()) sim.step();
    const double x_start = group_mean(sim, "block", sim.model().x, 0), t_start = sim.time();
    const fdem::Energies e0 = sim.energies();
    double s = 0;  // the sign of the slide under way, 0 while sticking
    for (int k = 1; k <= pieces; ++k) {
        sim.begin_stage(k);
        while (!sim.stage_finished()) {
            sim.step();
            const double v = group_mean(sim, "block", sim.model().v, 0);
            if (s == 0 && std::fabs(v) > 1e-3) s = v > 0 ? 1 : -1;
            if (s != 0 && v * s <= 0) {
                out.stops.push_back({sim.time() - t_start, group_mean(sim, "block", sim.model().x, 0) - x_start});
                s = 0;
            }
        }
    }
    const fdem::Energies e = sim.energies();
    auto held = [](const fdem::Energies& q) {
        return q.kinetic + q.elastic + q.contact + q.damping + q.viscous + q.friction + q.fracture + q.joint;
    };
    const double work = e.external - e0.external;
    out.books = (held(e) - held(e0) - work) / work;
    std::printf("[near the friction limit, rigid block, %s, contact damping %.1f, %.0f s] whole slide %.5f m, books %.2e\n",
                names[static_cast<int>(form)], xi, duration, out.amplitude, out.books);
    for (std::size_t i = 0; i < std::min(out.stops.size(), out.exact.size()); ++i)
        std::printf("  stop %zu: t %.4f s (exact %.4f), x %.6f m (exact %.6f), error %.3f %% of the slide\n", i,
                    out.stops[i].t, out.exact[i].t, out.stops[i].x, out.exact[i].x,
                    100 * (out.stops[i].x - out.exact[i].x) / out.amplitude);
    return out;
}

}  // namespace contact_test
