// tests/contact/walk_study/study.cpp: the driver of the refinement study in RESULTS.md (issue 50 part 3, issue 54
// item 1): a 1 kg block (bw x bh m, thickness 1 / (2000 bw bh) m, 2000 kg/m^3) on a fixed base through the engine,
// a 0.05 s settling stage (local damping 0.7), then a push F = A mu m g cos(omega t) (or a constant F) on the block's
// top edge, mid-height nodes, bottom nodes or all its nodes. Prints the stops (mean velocity back through 0 after
// exceeding 1e-3 m/s), the final and largest |x|, the largest |mean y|, the stage's energy books and the contact
// part's energy audit. Not built by CMake (it has its own main); build it against a build tree, e.g.
//   B=build; c++ -O2 -ffp-contract=off -fopenmp -DTOML_HEADER_ONLY=0 -DTOML_SHARED_LIB=1 -DFDEM_VERSION=\"0.1.0\" -I. \
//     -isystem /usr/include/eigen3 -std=c++17 tests/contact/walk_study/study.cpp -o /tmp/study $B/fdem/libfdem_core.a \
//     $B/mesh/libfdem_mesh.a $B/contact/libfdem_contact.a $B/fracture/libfdem_fracture.a -lgmsh -lgomp -lpthread -ltomlplusplus
//   /tmp/study A 1.02 omega 1 T 8 bw 0.2 bh 0.025 h 0.0125 hb 0.1 where top safety 0.4
// Keys (value after each): E kn h hb bw bh x0 safety dt xi mu e A omega T F where settle tf every; WIN=s in the
// environment prints windows of that length.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>
#include <cstdlib>
#include <unistd.h>
#include "fdem/case.hpp"
#include "fdem/scene.hpp"
#include "fdem/simulation.hpp"

struct P {
    double E = 1e10, kn = 1e11, h = 0.05, safety = 0.8, xi = 0.0, mu = 0.8, vd = 0.0, e = 1.0;
    double A = 1.02, omega = 1.0, T = 8.0;  // A in units of mu m g; F = A cos(omega t)
    double F = 0.0;                         // constant force (N), if > 0
    std::string where = "top";              // top | mid | bottom | all
    std::string rigid;                      // "", "x", "y", "xy": the block a rigid group in those components
    double settle = 0.05, dt = 0, hb = 0.05, x0 = 0.0, bw = 0.1, bh = 0.1;                          // fixed dt if > 0
    int every = 0; int tf = 0;                          // print every n steps
};

double mean(const fdem::Simulation& sim, const std::vector<int>& nodes, const std::vector<double>& f, int c) {
    double sm = 0, s = 0;
    for (int k : nodes) { sm += sim.model().mass[k]; s += sim.model().mass[k] * f[2 * k + c]; }
    return s / sm;
}

int main(int argc, char** argv) {
    P p;
    for (int i = 1; i + 1 < argc; i += 2) {
        std::string k = argv[i]; std::string v = argv[i + 1];
        if (k == "E") p.E = std::stod(v); else if (k == "kn") p.kn = std::stod(v); else if (k == "h") p.h = std::stod(v);
        else if (k == "safety") p.safety = std::stod(v); else if (k == "xi") p.xi = std::stod(v); else if (k == "vd") p.vd = std::stod(v);
        else if (k == "A") p.A = std::stod(v); else if (k == "omega") p.omega = std::stod(v); else if (k == "T") p.T = std::stod(v);
        else if (k == "F") p.F = std::stod(v); else if (k == "where") p.where = v; else if (k == "dt") p.dt = std::stod(v);
        else if (k == "bw") p.bw = std::stod(v); else if (k == "bh") p.bh = std::stod(v);
        else if (k == "settle") p.settle = std::stod(v);
        else if (k == "hb") p.hb = std::stod(v); else if (k == "x0") p.x0 = std::stod(v);
        else if (k == "tf") p.tf = std::stoi(v);
        else if (k == "every") p.every = std::stoi(v); else if (k == "mu") p.mu = std::stod(v);
        else if (k == "e") p.e = std::stod(v);
        else if (k == "rigid") p.rigid = v;
        else { std::fprintf(stderr, "unknown %s\n", k.c_str()); return 1; }
    }
    const double g = 9.81, m = 1.0;
    std::ostringstream geo;
    geo << "SetFactory(\"OpenCASCADE\");\nRectangle(1) = {-0.3, -0.1, 0, 0.7, 0.1};\nRectangle(2) = {" << p.x0 << ", 0, 0, " << p.bw << ", " << p.bh << "};\n"
        << "MeshSize{ PointsOf{ Surface{1}; } } = " << p.hb << ";\nMeshSize{ PointsOf{ Surface{2}; } } = " << p.h << ";\n"
        << (p.tf > 0 ? "Transfinite Curve{5, 6, 7, 8} = " + std::to_string(p.tf + 1) + ";\nTransfinite Surface{2} Alternated;\n" : std::string())
        << "Physical Surface(\"base\") = {1};\nPhysical Surface(\"block\") = {2};\nPhysical Curve(\"block_top\") = {7};\n";
    std::ostringstream c;
    c.precision(17);
    const double eps = 1e-6;
    const double bx = p.x0;
    c << "[case]\nname = \"walk\"\nthickness = " << 1.0 / (2000.0 * p.bw * p.bh) << "\n[geometry]\ntype = \"gmsh\"\nfile = \"blocks.geo\"\n"
      << "[materials.m]\nE = " << p.E << "\nnu = 0.2\ndensity = 2000.0\nviscous_damping = " << p.vd << "\n[regions]\nbase = \"m\"\nblock = \"m\"\n"
      << "[groups.mid]\nbox = [" << bx - eps << ", " << 0.5 * p.bh - eps << ", " << bx + p.bw + eps << ", " << 0.5 * p.bh + eps << "]\nwithin = \"block\"\n"
      << "[groups.bottom]\nbox = [" << bx - eps << ", " << -eps << ", " << bx + p.bw + eps << ", " << eps << "]\nwithin = \"block\"\n"
      << "[[interfaces]]\nregions = [\"base\", \"block\"]\nkind = \"dry\"\nfriction = " << std::atan(p.mu) * 180 / M_PI
      << "\nnormal_stiffness = " << p.kn << "\nrestitution = " << p.e << "\n[numerics]\nenergy_audit = true\nsafety = "
      << p.safety << "\n";
    if (p.dt > 0) c << "dt = " << p.dt << "\n";
    const std::string grp = p.where == "top" ? "block_top" : p.where == "mid" ? "mid" : p.where == "bottom" ? "bottom" : "block";
    if (p.settle > 0) c << "[[stages]]\nname = \"settle\"\nduration = " << p.settle << "\nlocal_damping = 0.7\ngravity = [0.0, -9.81]\n  [[stages.supports]]\n  group = \"base\"\n  fix = \"xy\"\n";
    c << "[[stages]]\nname = \"go\"\nduration = " << p.T << "\nlocal_damping = 0.0\ncontact_damping = " << p.xi
      << "\ngravity = [0.0, -9.81]\n  [[stages.supports]]\n  group = \"base\"\n  fix = \"xy\"\n"
      << (p.rigid.empty() ? std::string() : "  [[stages.supports]]\n  group = \"block\"\n  rigid = \"" + p.rigid + "\"\n")
      << "  [[stages.loads]]\n  group = \"" << grp << "\"\n";
    if (p.F > 0) c << "  force = [" << p.F << ", 0.0]\n";
    else c << "  force = [" << p.A * p.mu * m * g << ", 0.0]\n  function = { type = \"sin\", amplitude = 1.0, omega = " << p.omega
           << ", phase = " << M_PI / 2 << ", offset = 0.0 }\n";
    const auto dir = std::filesystem::path("/tmp/walkstudy/run_" + std::to_string(getpid()));
    std::filesystem::create_directories(dir);
    { std::ofstream(dir / "blocks.geo") << geo.str(); }
    { std::ofstream(dir / "case.toml") << c.str(); }
    fdem::CaseSpec spec = fdem::load_case((dir / "case.toml").string(), {});
    fdem::Model model = fdem::build_scene(spec);
    fdem::RunOptions opt; opt.quiet = true; opt.threads = 1;
    fdem::Simulation sim(spec, std::move(model), opt);
    const auto& bn = sim.model().group("block").nodes;
    double mass = 0; for (int k : bn) mass += sim.model().mass[k];
    if (p.settle > 0) {
        sim.begin_stage(0);
        while (!sim.stage_finished()) sim.step();
    }
    const double x0 = mean(sim, bn, sim.model().x, 0);
    const double tstart = sim.time();
    const fdem::Energies e0 = sim.energies();
    sim.begin_stage(p.settle > 0 ? 1 : 0);
    std::printf("# nodes block %zu mass %.6f dt %.4e\n", bn.size(), mass, sim.dt());
    double s = 0; int nstop = 0; double vmax_late = 0, xmax = 0;
    double t1v = 0, v1 = 0; int n1 = 0; double v2 = 0; int n2 = 0;
    double ymax = 0, y0 = mean(sim, bn, sim.model().x, 1);
    while (!sim.stage_finished()) {
        sim.step();
        const double t = sim.time() - tstart;
        const double v = mean(sim, bn, sim.model().v, 0);
        const double x = mean(sim, bn, sim.model().x, 0) - x0;
        const double y = mean(sim, bn, sim.model().x, 1) - y0;
        ymax = std::max(ymax, std::fabs(y));
        {
            static double wy0 = 1e9, wy1 = -1e9, wnext = 0.0; static const double win = std::getenv("WIN") ? std::atof(std::getenv("WIN")) : 0.0;
            wy0 = std::min(wy0, y), wy1 = std::max(wy1, y);
            if (win > 0 && t >= wnext) { std::printf("win t %.4f y [%.3e, %.3e] x %.5e v %.5e\n", t, wy0, wy1, x, v); wy0 = 1e9, wy1 = -1e9; wnext += win; }
        }
        xmax = std::max(xmax, std::fabs(x));
        if (p.F > 0) {
            if (t > 0.05 && t <= 0.06) v1 += v, ++n1;
            if (t > p.T - 0.01) v2 += v, ++n2;
        }
        if (s == 0 && std::fabs(v) > 1e-3) s = v > 0 ? 1 : -1;
        if (s != 0 && v * s <= 0) { std::printf("stop %d t %.5f x %.7e\n", nstop++, t, x); s = 0; }
        if (p.every && sim.steps() % p.every == 0) {
            std::printf("t %.5f x %.6e v %.6e y %.3e F/mumg %.4f\n", t, x, v, y, std::cos(p.omega * t) * p.A);
        }
        (void)t1v; (void)vmax_late;
    }
    const fdem::Energies e = sim.energies();
    auto held_of = [](const fdem::Energies& q) { return q.kinetic + q.elastic + q.contact + q.damping + q.viscous + q.friction + q.fracture + q.joint; };
    const double held = held_of(e) - held_of(e0);
    const double Wst = e.external - e0.external;
    std::printf("final x %.6e  |x|max %.4e  |y|max %.3e  W %.6e held %.6e  (held-W)/W %.3e  fric %.5e visc %.3e steps %ld\n",
                mean(sim, bn, sim.model().x, 0) - x0, xmax, ymax, Wst, held, (held - Wst) / Wst,
                e.friction, e.viscous, sim.steps());
    {
        const auto a = sim.energy_audit(e);
        for (int i = 0; i < 3; ++i) std::printf("audit part %d worked %.6e grew %.6e\n", i, a[i].worked, a[i].grew);
    }
    if (p.F > 0) {
        v1 /= n1, v2 /= n2;
        const double w = (p.T - 0.005) - 0.055;
        const double mu_eff = (p.F * w - mass * (v2 - v1)) / (mass * g * w);
        std::printf("mu_eff %.6f (%+.4f %%)\n", mu_eff, 100 * (mu_eff / p.mu - 1));
        const double vend = mean(sim, bn, sim.model().v, 0), xend = mean(sim, bn, sim.model().x, 0) - x0;
        std::printf("mu_eff from v(T)/T %.6f, from 2x(T)/T^2 %.6f\n", (p.F - mass * vend / p.T) / (mass * g),
                    (p.F - mass * 2 * xend / (p.T * p.T)) / (mass * g));
    }
    std::filesystem::remove_all(dir);
}
