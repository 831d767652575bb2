// tests/contact/rocking_run.hpp: a block rocking on a fixed base through the engine (issue 54, item 2), shared by
// tests/contact/test_rocking.cpp (two impacts) and tests/validation/test_rocking_long.cpp (five impacts).
//
// SCENE. A block bw x bh (2000 kg/m^3, nu 0.2, thickness 1 m, mesh h, 1/5 of it at the pads) stands on two pads
// `foot` wide and foot / 2 high at its bottom corners (foot = 0: a flat bottom), on a fixed base 3 bw x 0.1 m,
// through a dry interface (k_n = k_s = kn, mu, restitution e). It is tilted by theta0 about its right pivot
// (the outer corner of the right pad) and released at rest under gravity, undamped.
// MEASURED. The tilt theta = asin((y_L - y_R) / bw) of the outer bottom corners; an impact where theta changes sign
// (its time by linear interpolation between the steps); the amplitude, the largest |theta| between impacts; the
// highest lift of the lower of the two corners above the base's top (both pivots off: a hop).
// EXACT. rocking_exact.hpp with the block's own lumped masses (G, I_G, b, h of the upright placement).
#pragma once

#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "contact/rocking_exact.hpp"
#include "core/engine_helpers.hpp"

namespace contact_test {

struct RockingSetup {
    double bw = 0.2, bh = 1.0, foot = 0.01, h = 0.05, E = 1e10, kn = 1e10, e = 0.2, T = 1.1, mu = 0.8;
    double theta0_of_alpha = 0.5;  // theta0 = this x atan(bw / bh)
    bool body = false;             // the block one rigid body (a support rigid = "body") instead of elastic
};

// The tests' setting (test_rocking.cpp, test_rocking_long.cpp): 0.01 m pads, E 1e11 Pa, k_n 1e11 Pa/m, e 0.2.
inline RockingSetup housner_setting(double T) {
    RockingSetup s;
    s.foot = 0.01, s.h = 0.05, s.E = 1e11, s.kn = 1e11, s.e = 0.2, s.T = T;
    return s;
}

struct RockingResult {
    RigidRocking rigid;
    double theta0 = 0, x_p = 0;
    std::vector<double> times, amplitudes;  // of the impacts; amplitudes[0] = theta0, [i] after impact i
    double hop = 0;                          // m, the highest lift of both pivots at once
    double static_penetration = 0;           // m, m g / (k_n L_contact) standing upright
    double books = 0;                        // (held - worked) / worked over the run
    long steps = 0;
    double dt = 0;
};

inline RockingResult rock(const RockingSetup& s, const std::string& name) {
    const double th0 = s.theta0_of_alpha * std::atan(s.bw / s.bh), px = 0.5 * s.bw;
    std::ostringstream g;
    g.precision(17);
    g << "SetFactory(\"OpenCASCADE\");\nRectangle(1) = {" << -1.5 * s.bw << ", -0.1, 0, " << 3 * s.bw << ", 0.1};\n"
      << "Rectangle(2) = {" << -px << ", 0, 0, " << s.bw << ", " << s.bh << "};\n";
    int block = 2;
    if (s.foot > 0) {
        g << "Rectangle(3) = {" << -px + s.foot << ", 0, 0, " << s.bw - 2 * s.foot << ", " << 0.5 * s.foot << "};\n"
          << "BooleanDifference(4) = { Surface{2}; Delete; }{ Surface{3}; Delete; };\n";
        block = 4;
    }
    g << "MeshSize{ PointsOf{ Surface{1}; } } = " << s.h << ";\nMeshSize{ PointsOf{ Surface{" << block << "}; } } = " << s.h
      << ";\n";
    if (s.foot > 0)
        g << "pads() = Point In BoundingBox{" << -px - 1e-6 << ", -1e-6, -1, " << px + 1e-6 << ", " << 0.5 * s.foot + 1e-6
          << ", 1};\nMeshSize{ pads() } = "
          << std::min(s.h, s.foot) << ";\n";
    g << "Rotate{{0, 0, 1}, {" << px << ", 0, 0}, " << -th0 << "} { Surface{" << block << "}; }\n"
      << "Physical Surface(\"base\") = {1};\nPhysical Surface(\"block\") = {" << block << "};\n";
    const std::string geo = testing::write_text(testing::tmp_dir(name + "_geo") / "rocking.geo", g.str());
    std::ostringstream c;
    c.precision(17);
    c << "[case]\nname = \"rocking\"\nthickness = 1.0\n[geometry]\ntype = \"gmsh\"\nfile = \"" << geo << "\"\n"
      << "[materials.m]\nE = " << s.E << "\nnu = 0.2\ndensity = 2000.0\n[regions]\nbase = \"m\"\nblock = \"m\"\n"
      << "[[interfaces]]\nregions = [\"base\", \"block\"]\nkind = \"dry\"\nfriction = " << std::atan(s.mu) * 180 / M_PI
      << "\nnormal_stiffness = " << s.kn << "\nrestitution = " << s.e << "\n"
      << "[[stages]]\nname = \"rock\"\nduration = " << s.T << "\nlocal_damping = 0.0\ngravity = [0.0, -9.81]\n"
      << "  [[stages.supports]]\n  group = \"base\"\n  fix = \"xy\"\n"
      << (s.body ? "  [[stages.supports]]\n  group = \"block\"\n  rigid = \"body\"\n" : "");
    fdem::Simulation sim = testing::make_simulation(c.str(), name, {}, 1);
    const auto& bn = sim.model().group("block").nodes;
    const auto& X = sim.model().x;
    // the outer bottom corners, and the rigid block of the same lumped masses turned back upright
    const double ct = std::cos(th0), st = std::sin(th0);
    const double lx = px - s.bw * ct, ly = s.bw * st;
    int L = -1, R = -1;
    double dL = 1e9, dR = 1e9, mass = 0, sx = 0, sy = 0;
    std::vector<double> ux, uy;
    for (int k : bn) {
        const double x = X[2 * k], y = X[2 * k + 1];
        if (std::hypot(x - lx, y - ly) < dL) dL = std::hypot(x - lx, y - ly), L = k;
        if (std::hypot(x - px, y) < dR) dR = std::hypot(x - px, y), R = k;
        ux.push_back(px + ct * (x - px) - st * y), uy.push_back(st * (x - px) + ct * y);
        const double m = sim.model().mass[k];
        mass += m, sx += m * ux.back(), sy += m * uy.back();
    }
    RockingResult out;
    RigidRocking& rig = out.rigid;
    rig.m = mass;
    const double xg = sx / mass, yg = sy / mass;
    for (std::size_t i = 0; i < bn.size(); ++i)
        rig.I_G += sim.model().mass[bn[i]] * ((ux[i] - xg) * (ux[i] - xg) + (uy[i] - yg) * (uy[i] - yg));
    rig.b = px - xg, rig.h = yg;
    out.theta0 = th0;
    out.x_p = rig.b - 0.5 * s.foot;  // the impulse at the pads' centres (Housner: at the corner)
    out.static_penetration = mass * 9.81 / (s.kn * (s.foot > 0 ? 2 * s.foot : s.bw));
    auto tilt = [&] { return std::asin((X[2 * L + 1] - X[2 * R + 1]) / s.bw); };
    const fdem::Energies e0 = sim.energies();
    sim.begin_stage(0);
    out.dt = sim.dt();
    double prev = tilt(), amp = std::fabs(prev), tprev = 0.0;
    out.amplitudes.assign(1, th0);
    while (!sim.stage_finished()) {
        sim.step();
        ++out.steps;
        const double th = tilt(), t = sim.time();
        amp = std::max(amp, std::fabs(th));
        out.hop = std::max(out.hop, std::min(X[2 * L + 1], X[2 * R + 1]));
        if ((th < 0) != (prev < 0) && th != 0.0) {
            if (!out.times.empty()) out.amplitudes.push_back(amp);
            out.times.push_back(tprev + (t - tprev) * prev / (prev - th));
            amp = 0.0;
        }
        prev = th, tprev = t;
    }
    const fdem::Energies e = sim.energies();
    auto held = [](const fdem::Energies& q) {
        return q.kinetic + q.elastic + q.contact + q.damping + q.viscous + q.friction + q.fracture + q.joint;
    };
    const double work = e.external - e0.external;
    out.books = (held(e) - held(e0) - work) / work;
    return out;
}

// Prints the impacts against the rigid block with the impulse at x_p, and returns the rigid sequence.
inline void print_rocking(const RockingResult& r, const RockingSetup& s, std::vector<double>& rt, std::vector<double>& ra) {
    const RigidRocking& rig = r.rigid;
    rig.impacts(r.theta0, rig.r(r.x_p), static_cast<int>(std::max<std::size_t>(r.times.size(), 1)), rt, ra);
    std::printf("[rocking] %.2f x %.2f m, pads %.3f m, E %.1e Pa, k_n %.1e Pa/m, e %.2f: dt %.3e s, %ld steps; r at the "
                "pads' centres %.5f, Housner's (corners) %.5f\n",
                s.bw, s.bh, s.foot, s.E, s.kn, s.e, r.dt, r.steps, rig.r(r.x_p), rig.r(rig.b));
    for (std::size_t i = 0; i < r.times.size(); ++i) {
        const double a = i < r.amplitudes.size() ? r.amplitudes[i] : NAN;
        std::printf("[rocking]   impact %zu at %.5f s (rigid %.5f, %+.2f %%), amplitude before %.5f rad (rigid %.5f, %+.2f %%)\n",
                    i + 1, r.times[i], rt[i], 100 * (r.times[i] / rt[i] - 1), a, ra[i], 100 * (a / ra[i] - 1));
    }
    std::printf("[rocking]   hop %.3e m (static penetration %.3e m), books %+.4f %%\n", r.hop, r.static_penetration,
                100 * r.books);
}

// The angular-velocity ratio of impact i (0-based) from the amplitudes either side of it.
inline double measured_r(const RockingResult& r, std::size_t i) {
    const double al = r.rigid.alpha();
    return std::sqrt((std::cos(al - r.amplitudes[i + 1]) - std::cos(al)) / (std::cos(al - r.amplitudes[i]) - std::cos(al)));
}

// measured_r of impact i + 1, printed against the pads' centres' and Housner's values.
inline double print_measured_r(const RockingResult& r, std::size_t i) {
    const double ri = measured_r(r, i);
    std::printf("[rocking]   r of impact %zu: %.5f (pads' centres %+.2f %%, Housner %+.2f %%)\n", i + 1, ri,
                100 * (ri / r.rigid.r(r.x_p) - 1), 100 * (ri / r.rigid.r(r.rigid.b) - 1));
    return ri;
}

}  // namespace contact_test
