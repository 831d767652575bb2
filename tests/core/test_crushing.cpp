// Compression softening of the triangles ([materials.NAME.crushing], fdem/plasticity.hpp).
//
// CLOSED FORMS (material point, plane stress, lambda and mu of the plane model, E the Young's modulus)
//   Uniaxial stress (S_xx = 0) in compression: linear with slope E up to S_yy = -f_c at E_yy = -f_c / E; then linear
//   softening; the strength is gone at kappa_u = 2 G_c / (f_c h); the work per unit volume to full softening,
//   INT S_yy dE_yy minus the elastic energy left, is G_c / h. Unloading from the softening branch: slope E again.
//   Uniaxial or biaxial tension of any size: elastic (no plastic strain).
//   Equal biaxial compression: both principal stresses stop at -f_c(kappa) (the corner of the surface).
// Engine: a square of two equal right triangles (h = sqrt(2 A) = the side), compressed by its top edge at a slow rate:
// peak reaction f_c B t (less the nominal-to-true area change, under 0.5 % here), crushing work booked under D_frac
// = G_c A t / h for the whole square, energy balance; and a 1,600-triangle panel gives the same bits on 1 and 2 threads.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <string>

#include "engine_helpers.hpp"
#include "fdem/plasticity.hpp"

namespace {

constexpr double kE = 1.0e9, kNu = 0.2, kFc = 1.0e6, kGc = 200.0, kH = 0.1;

fdem::CrushingParams params() {
    fdem::CrushingParams p;
    p.fc = kFc, p.Gc = kGc;
    p.mu = kE / (2 * (1 + kNu));
    p.lambda = kE * kNu / (1 - kNu * kNu);  // plane stress
    return p;
}

// A material point driven in uniaxial stress: E_yy prescribed, E_xx found so that S_xx = 0 (fixed-point iteration
// from the committed state; dS_xx / dE_xx = lambda + 2 mu in the elastic and the one-cap plastic case).
struct Point {
    fdem::CrushingParams p = params();
    double ku = 2 * kGc / (kFc * kH);
    double Ep[3] = {0, 0, 0}, kappa = 0, exx = 0, S[3] = {0, 0, 0}, E[3] = {0, 0, 0};
    bool flowed = false;
    void uniaxial(double eyy) {
        double x = exx;
        for (int it = 0; it < 200; ++it) {
            double ep[3] = {Ep[0], Ep[1], Ep[2]}, k = kappa, s[3];
            const double e[3] = {x, eyy, 0};
            fdem::crushing_update(p, ku, e, ep, k, s);
            if (std::abs(s[0]) < 1e-9 * kFc) break;
            x -= s[0] / (p.lambda + 2 * p.mu);
        }
        E[0] = x, E[1] = eyy, E[2] = 0;
        flowed = fdem::crushing_update(p, ku, E, Ep, kappa, S);
        exx = x;
    }
};

}  // namespace

TEST_CASE("crushing: uniaxial compression peaks at f_c and dissipates G_c per unit volume over h", "[unit][crushing]") {
    Point pt;
    const int n = 20000;
    const double e_end = -3.0 * pt.ku;  // well past the end of softening
    double peak = 0, work = 0, s_prev = 0, e_prev = 0, e_at_peak = 0;
    for (int i = 1; i <= n; ++i) {
        const double eyy = e_end * i / n;
        pt.uniaxial(eyy);
        CHECK(std::abs(pt.S[0]) < 1e-6 * kFc);
        work += 0.5 * (pt.S[1] + s_prev) * (eyy - e_prev);  // trapezoid of S_yy dE_yy (S_xx = 0)
        if (-pt.S[1] > peak) peak = -pt.S[1], e_at_peak = eyy;
        s_prev = pt.S[1], e_prev = eyy;
    }
    const double stored = fdem::crushing_energy_density(pt.p, pt.E, pt.Ep);
    const double dissipated = work - stored;  // J/m^3
    std::printf("[crushing] peak %.9e Pa (f_c %.3e) at E_yy %.6e (-f_c/E %.6e); dissipated %.6e J/m^3, G_c/h %.6e\n", peak,
                kFc, e_at_peak, -kFc / kE, dissipated, kGc / kH);
    // The sampled peak lies within one strain increment (9e-7) of the exact one on the softening slope.
    CHECK(peak <= kFc * (1 + 1e-12));
    CHECK(peak == Approx(kFc).epsilon(1e-4));
    // Just before E_yy = -f_c / E (uniaxial stress): S_yy = -f_c with no flow; just past it the point flows.
    Point at;
    at.uniaxial(-kFc / kE * (1 - 1e-10));
    CHECK(!at.flowed);
    CHECK(-at.S[1] == Approx(kFc).epsilon(1e-9));
    at.uniaxial(-kFc / kE * (1 + 1e-3));
    CHECK(at.flowed);
    CHECK(-at.S[1] == Approx(fdem::crushing_strength(at.p, at.ku, at.kappa)).epsilon(1e-9));
    CHECK(e_at_peak == Approx(-kFc / kE).epsilon(2.0 / n * 3 * pt.ku / (kFc / kE)));
    CHECK(dissipated == Approx(kGc / kH).epsilon(0.01));
    CHECK(fdem::crushing_dissipation_density(pt.p, pt.ku, pt.kappa) == Approx(kGc / kH).epsilon(1e-12));
    CHECK(std::abs(pt.S[1]) < 1e-6 * kFc);  // no strength left
}

TEST_CASE("crushing: elastic slope E before the peak and unloading from the softening branch at slope E",
          "[unit][crushing]") {
    Point pt;
    pt.uniaxial(-0.5 * kFc / kE);
    CHECK(!pt.flowed);
    CHECK(pt.S[1] / pt.E[1] == Approx(kE).epsilon(1e-6));  // small-strain E (Green-Lagrange, S)
    // Into the softening branch, halfway down in strength.
    const double e1 = -kFc / kE - 0.5 * pt.ku;
    for (int i = 1; i <= 1000; ++i) pt.uniaxial(-0.5 * kFc / kE + (e1 + 0.5 * kFc / kE) * i / 1000.0);
    CHECK(pt.flowed);
    const double s1 = pt.S[1], k1 = pt.kappa;
    const double left = fdem::crushing_strength(pt.p, pt.ku, k1);
    CHECK(-s1 == Approx(left).epsilon(1e-9));
    // On the uniaxial path the total strain is f_c(kappa) / E + kappa: kappa = (-e1 - f_c/E) / (1 - f_c / (E kappa_u)).
    const double k_expected = (-e1 - kFc / kE) / (1 - kFc / (kE * pt.ku));
    CHECK(k1 == Approx(k_expected).epsilon(1e-6));
    CHECK(left == Approx(kFc * (1 - k_expected / pt.ku)).epsilon(1e-6));
    // Unload by a strain step: elastic, slope E, kappa kept.
    const double de = 0.2 * left / kE;
    pt.uniaxial(e1 + de);
    CHECK(!pt.flowed);
    CHECK(pt.kappa == k1);
    const double slope = (pt.S[1] - s1) / de;
    std::printf("[crushing] unloading slope %.6e Pa, E %.3e Pa\n", slope, kE);
    CHECK(slope == Approx(kE).epsilon(1e-3));
    // Reloading: elastic until the strength left, then flow again at it.
    pt.uniaxial(e1 - 0.01 * pt.ku);
    CHECK(pt.flowed);
    CHECK(-pt.S[1] == Approx(fdem::crushing_strength(pt.p, pt.ku, pt.kappa)).epsilon(1e-9));
    CHECK(pt.kappa > k1);
}

TEST_CASE("crushing: tension of any size leaves the model elastic", "[unit][crushing]") {
    const auto p = params();
    const double ku = 2 * kGc / (kFc * kH);
    for (const auto& e : {std::array<double, 3>{0.0, 0.02, 0.0}, std::array<double, 3>{0.05, 0.05, 0.0},
                          std::array<double, 3>{0.03, 0.01, 0.004}}) {
        double Ep[3] = {0, 0, 0}, kappa = 0, S[3];
        CHECK(!fdem::crushing_update(p, ku, e.data(), Ep, kappa, S));
        CHECK(kappa == 0.0);
        CHECK(Ep[0] == 0.0);
        CHECK(Ep[1] == 0.0);
        CHECK(Ep[2] == 0.0);
        const double tr = e[0] + e[1];
        CHECK(S[0] == Approx(p.lambda * tr + 2 * p.mu * e[0]));
        CHECK(S[1] == Approx(p.lambda * tr + 2 * p.mu * e[1]));
        CHECK(S[2] == Approx(2 * p.mu * e[2]));
    }
}

TEST_CASE("crushing: equal biaxial compression stops both principal stresses at the strength left", "[unit][crushing]") {
    const auto p = params();
    const double ku = 2 * kGc / (kFc * kH);
    double Ep[3] = {0, 0, 0}, kappa = 0, S[3];
    for (int i = 1; i <= 400; ++i) {
        const double e = -4.0 * kFc / kE * i / 400.0;
        const double E[3] = {e, e, 0};
        fdem::crushing_update(p, ku, E, Ep, kappa, S);
    }
    const double left = fdem::crushing_strength(p, ku, kappa);
    std::printf("[crushing] biaxial: S %.6e %.6e %.3e Pa, strength left %.6e Pa, kappa %.3e\n", S[0], S[1], S[2], left, kappa);
    CHECK(kappa > 0);
    CHECK(-S[0] == Approx(left).epsilon(1e-9));
    CHECK(-S[1] == Approx(left).epsilon(1e-9));
    CHECK(std::abs(S[2]) < 1e-9 * kFc);
}

namespace {

// A square of side B = 0.1 m meshed as two equal right triangles (h = sqrt(2 A) = B), compressed by its top edge.
std::string square_case(const std::string& dir, double vy) {
    testing::write_text(std::filesystem::path(dir) / "square.geo", R"(
Point(1) = {0, 0, 0, 0.1}; Point(2) = {0.1, 0, 0, 0.1}; Point(3) = {0.1, 0.1, 0, 0.1}; Point(4) = {0, 0.1, 0, 0.1};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Transfinite Curve{1, 2, 3, 4} = 2; Transfinite Surface{1} = {1, 2, 3, 4};
Physical Surface("body") = {1}; Physical Curve("bottom") = {1}; Physical Curve("top") = {3};
Physical Point("corner_bl") = {1};
)");
    char v[64];
    std::snprintf(v, sizeof v, "%.17g", vy);
    return std::string(R"(
[case]
name = "crush_square"
thickness = 0.1
[geometry]
type = "gmsh"
file = "square.geo"
min_angle = 0
[materials.m]
E = 1.0e9
nu = 0.2
density = 2000.0
[materials.m.crushing]
compressive_strength = 1.0e6
Gc = 200.0
[regions]
body = "m"
[[monitors]]
name = "F"
type = "reaction"
group = "top"
component = "y"
[[monitors]]
name = "u"
type = "displacement"
group = "top"
component = "y"
[output]
history_interval = 0.01
[[stages]]
name = "press"
duration = 0.6
local_damping = 0.3
  [[stages.supports]]
  group = "bottom"
  fix = "y"
  [[stages.supports]]
  group = "corner_bl"
  fix = "x"
  [[stages.supports]]
  group = "top"
  vy = )") + v + "\n  ramp = 0.02\n";
}

fdem::Simulation load(const std::filesystem::path& dir, const std::string& text, int threads) {
    const std::string path = testing::write_text(dir / "case.toml", text);
    fdem::CaseSpec spec = fdem::load_case(path);
    fdem::Model model = fdem::build_scene(spec);
    fdem::RunOptions opt;
    opt.quiet = true;
    opt.threads = threads;
    return fdem::Simulation(spec, std::move(model), opt);
}

// Runs every stage step by step; returns {largest |monitor 0|, final monitor 0}.
std::pair<double, double> run_tracking(fdem::Simulation& sim) {
    double peak = 0, last = 0;
    for (int st = 0; st < static_cast<int>(sim.spec().stages.size()); ++st) {
        sim.begin_stage(st);
        while (!sim.stage_finished()) {
            sim.step();
            last = sim.monitor_value(0);
            peak = std::max(peak, std::abs(last));
        }
    }
    return {peak, last};
}

}  // namespace

TEST_CASE("crushing engine: a square of two triangles peaks at f_c B t and books G_c A t / h under D_frac",
          "[engine][crushing]") {
    const auto dir = testing::tmp_dir("crush_square");
    auto sim = load(dir, square_case(dir.string(), -1.0e-3), 1);
    REQUIRE(sim.model().n_triangles() == 2);
    REQUIRE(sim.crushing().active());
    const auto [peak, final_F] = run_tracking(sim);
    const double B = 0.1, t = 0.1;
    const fdem::Energies e = sim.energies();
    const double expected_D = kGc * B * B * t / kH;  // J: the whole square crushed, h = B for both triangles
    std::printf("[crushing] square: peak reaction %.6e N (f_c B t %.6e N), D_frac %.6e J (G_c A t / h %.6e J), "
                "kappa/kappa_u %.4f %.4f, final reaction %.3e N, balance %.2e\n",
                peak, kFc * B * t, e.fracture, expected_D, sim.crushing().softening(0), sim.crushing().softening(1),
                final_F, e.balance_error());
    // The reaction is nominal (per reference area): P_yy = F_yy S_yy with F_yy = 1 - f_c / E at the peak (0.1 % here).
    CHECK(peak == Approx(kFc * B * t).epsilon(0.005));
    CHECK(peak < kFc * B * t);
    CHECK(sim.crushing().softening(0) == 1.0);
    CHECK(sim.crushing().softening(1) == 1.0);
    CHECK(e.fracture == Approx(expected_D).epsilon(0.01));
    CHECK(std::abs(final_F) < 0.02 * kFc * B * t);  // no strength left at the end
    CHECK(e.balance_error() < 0.01);
}

TEST_CASE("crushing engine: no effect under tension", "[engine][crushing]") {
    // The square pulled to 3 f_c / E: the reaction equals the elastic one of a material without the crushing table.
    const auto dir = testing::tmp_dir("crush_square_tension");
    const std::string with = square_case(dir.string(), 5.0e-4);
    std::string without = with;
    const std::string table = "[materials.m.crushing]\ncompressive_strength = 1.0e6\nGc = 200.0\n";
    without.erase(without.find(table), table.size());
    auto a = load(dir, with, 1);
    const double Fa = run_tracking(a).second;
    const auto dir2 = testing::tmp_dir("crush_square_tension_b");
    square_case(dir2.string(), 5.0e-4);  // writes the .geo there
    auto b = load(dir2, without, 1);
    const double Fb = run_tracking(b).second;
    std::printf("[crushing] tension: reaction %.9e N with crushing, %.9e N without; D_frac %.3e J\n", Fa, Fb, a.energies().fracture);
    CHECK(a.crushing().softening(0) == 0.0);
    CHECK(a.crushing().softening(1) == 0.0);
    CHECK(a.energies().fracture == 0.0);
    CHECK(std::abs(Fa) > 2.5 * kFc * 0.1 * 0.1);  // the tension went past f_c
    CHECK(Fa == Approx(Fb).epsilon(0.01));       // Saint Venant-Kirchhoff against neo-Hookean at 0.3 % strain
}

TEST_CASE("crushing engine: a crushing panel gives the same bits on 1 and 2 threads", "[engine][crushing]") {
    const std::string text = R"(
[case]
name = "crush_panel"
thickness = 0.1
[geometry]
type = "rectangle"
width = 0.2
height = 0.4
mesh_size = 0.01
[materials.m]
E = 1.0e9
nu = 0.2
density = 2000.0
[materials.m.crushing]
compressive_strength = 1.0e6
Gc = 200.0
[regions]
body = "m"
[[stages]]
name = "press"
duration = 0.08
local_damping = 0.3
  [[stages.supports]]
  group = "bottom"
  fix = "xy"
  [[stages.supports]]
  group = "top"
  vy = -1.2e-2
  vx = 2.0e-3
  ramp = 0.005
)";
    std::vector<double> x[2];
    double D[2];
    for (int i = 0; i < 2; ++i) {
        const auto dir = testing::tmp_dir("crush_panel_" + std::to_string(i));
        auto sim = load(dir, text, i + 1);
        REQUIRE(sim.model().n_triangles() > 4 * 256);  // several blocks of the parallel loop
        sim.run();
        x[i] = sim.model().x;
        D[i] = sim.energies().fracture;
        int crushed = 0;
        for (std::size_t s = 0; s < sim.crushing().kappa.size(); ++s) crushed += sim.crushing().kappa[s] > 0;
        std::printf("[crushing] panel, %d thread(s): %d of %d triangles crushing, D_frac %.9e J\n", i + 1, crushed,
                    sim.model().n_triangles(), D[i]);
        CHECK(crushed > 0);
    }
    REQUIRE(x[0].size() == x[1].size());
    CHECK(std::memcmp(x[0].data(), x[1].data(), x[0].size() * sizeof(double)) == 0);
    CHECK(std::memcmp(&D[0], &D[1], sizeof(double)) == 0);
}

TEST_CASE("crushing: case errors name the file and the key", "[unit][crushing]") {
    const auto dir = testing::tmp_dir("crush_bad");
    const std::string good = square_case(dir.string(), -1.0e-3);
    auto with = [&](const std::string& from, const std::string& to) {
        std::string s = good;
        s.replace(s.find(from), from.size(), to);
        return s;
    };
    struct Bad {
        std::string text, key;
    };
    for (const Bad& b : {Bad{with("Gc = 200.0", "Gc = -1.0"), "materials.m.crushing.Gc"},
                         Bad{with("compressive_strength = 1.0e6\n", ""), "materials.m.crushing.compressive_strength"},
                         Bad{with("Gc = 200.0", "Gc = 200.0\nGf = 1.0"), "materials.m.crushing.Gf"},
                         // too coarse: h = 0.1 m needs G_c >= f_c^2 h / (2 (lambda + mu)) = 80 J/m^2
                         Bad{with("Gc = 200.0", "Gc = 50.0"), "materials.m.crushing.Gc"}}) {
        const auto path = testing::write_text(dir / "case.toml", b.text);
        const auto r = testing::run_fdem("check \"" + path + "\"", dir);
        INFO(r.err);
        CHECK(r.code == 1);
        CHECK(r.err.find(b.key) != std::string::npos);
        CHECK(r.err.find("case.toml") != std::string::npos);
    }
}
