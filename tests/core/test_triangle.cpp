// Closed-form checks of the deformable triangle and the integrator: rigid rotation, patch test,
// P-wave speed, energy conservation, cantilever convergence, stability limit.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>

#include "engine_helpers.hpp"
#include "fdem/common/errors.hpp"
#include "fdem/model.hpp"
#include "fdem/triangle.hpp"

#include <Eigen/Dense>
#include "mesh/gmsh_source.hpp"

using namespace fdem;

namespace {

const char* kBlockCase = R"(
[case]
name = "block"
thickness = 0.1
plane = "stress"
[geometry]
type = "rectangle"
width = 1.0
height = 0.6
mesh_size = 0.1
[materials.m]
E = 1.0e9
nu = 0.25
density = 1000.0
[regions]
body = "m"
[[stages]]
duration = 1.0
)";

// Net internal force on every node (gathered like the integrator does), for the current x.
std::vector<double> nodal_forces(const Model& md) {
    std::vector<double> f(2 * md.n_nodes(), 0.0);
    double f6[6], p;
    for (int e = 0; e < md.n_triangles(); ++e) {
        triangle_forces(md.tris[e], md.mat[md.tris[e].mat], md.x.data(), md.v.data(), f6, p);
        for (int k = 0; k < 3; ++k) f[2 * md.tris[e].n[k]] += f6[2 * k], f[2 * md.tris[e].n[k] + 1] += f6[2 * k + 1];
    }
    return f;
}

}  // namespace

TEST_CASE("a mesh rotated rigidly carries no stress", "[unit]") {
    auto sim = testing::make_simulation(kBlockCase, "rigid");
    Model& md = sim.model();
    const double E = 1e9;
    for (double deg : {90.0, 37.0, 180.0}) {
        const double a = deg * M_PI / 180, c = std::cos(a), s = std::sin(a);
        for (int k = 0; k < md.n_nodes(); ++k) {
            const double X = md.X[2 * k], Y = md.X[2 * k + 1];
            md.x[2 * k] = 0.3 + c * X - s * Y;
            md.x[2 * k + 1] = -0.2 + s * X + c * Y;
        }
        double max_stress = 0, max_force = 0;
        for (int e = 0; e < md.n_triangles(); ++e) {
            double s3[3], f6[6], p;
            triangle_stress(md.tris[e], md.mat[0], md.x.data(), s3);
            triangle_forces(md.tris[e], md.mat[0], md.x.data(), md.v.data(), f6, p);
            for (double v : s3) max_stress = std::max(max_stress, std::abs(v));
            // Force scale of the triangle: E * t * (edge length) ~ E * A0t / h.
            for (double v : f6) max_force = std::max(max_force, std::abs(v) / (E * md.tris[e].A0t / md.tri_altitude[e]));
        }
        INFO("rotation " << deg << " deg");
        CHECK(max_stress / E < 1e-9);
        CHECK(max_force < 1e-9);
        CHECK(sim.energies().elastic < 1e-9 * E * 0.06);
    }
}

TEST_CASE("patch test: a uniform strain on the boundary of an unstructured mesh is reproduced inside", "[unit]") {
    const std::string text = std::string(kBlockCase) + R"(
[[stages.supports]]
group = "left"
fix = "xy"
[[stages.supports]]
group = "right"
fix = "xy"
[[stages.supports]]
group = "top"
fix = "xy"
[[stages.supports]]
group = "bottom"
fix = "xy"
)";
    // duration replaced: damped relaxation to equilibrium.
    auto sim = testing::make_simulation(text, "patch",
                                        {"stages.1.duration=0.5", "stages.1.local_damping=0.7"});
    Model& md = sim.model();
    const double F[4] = {1.002, 0.0007, -0.0004, 0.9985};  // uniform deformation gradient (finite strain)
    auto exact = [&](int k, int c) {
        const double X = md.X[2 * k], Y = md.X[2 * k + 1];
        return c == 0 ? F[0] * X + F[1] * Y : F[2] * X + F[3] * Y;
    };
    for (int k = 0; k < md.n_nodes(); ++k) md.x[2 * k] = exact(k, 0), md.x[2 * k + 1] = exact(k, 1);

    // 1. At the exact field every interior node is in equilibrium and every triangle has the same stress.
    const auto f = nodal_forces(md);
    std::vector<char> boundary(md.n_nodes(), 0);
    for (const char* side : {"left", "right", "top", "bottom"})
        for (int k : md.group(side).nodes) boundary[k] = 1;
    double fmax_int = 0, fscale = 0;
    for (int k = 0; k < md.n_nodes(); ++k) {
        fscale = std::max({fscale, std::abs(f[2 * k]), std::abs(f[2 * k + 1])});
        if (!boundary[k]) fmax_int = std::max({fmax_int, std::abs(f[2 * k]), std::abs(f[2 * k + 1])});
    }
    REQUIRE(fscale > 0);
    CHECK(fmax_int / fscale < 1e-10);
    double s_ref[3];
    triangle_stress(md.tris[0], md.mat[0], md.x.data(), s_ref);
    for (int e = 1; e < md.n_triangles(); ++e) {
        double s3[3];
        triangle_stress(md.tris[e], md.mat[0], md.x.data(), s3);
        for (int i = 0; i < 3; ++i) CHECK(s3[i] == Approx(s_ref[i]).epsilon(1e-9).margin(1e-9 * std::abs(s_ref[0])));
    }

    // 2. Perturb the interior nodes; damped dynamics must bring them back to the linear field.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-1e-3, 1e-3);
    for (int k = 0; k < md.n_nodes(); ++k)
        if (!boundary[k]) md.x[2 * k] += u(rng), md.x[2 * k + 1] += u(rng);
    sim.run();
    double err = 0;
    for (int k = 0; k < md.n_nodes(); ++k)
        for (int c = 0; c < 2; ++c) err = std::max(err, std::abs(md.x[2 * k + c] - exact(k, c)));
    CHECK(err < 1e-9);  // m, on displacements of order 1e-3 m
}

TEST_CASE("plane-stress P wave arrives at sqrt(E / (rho (1 - nu^2)))", "[unit]") {
    const std::string text = R"(
[case]
name = "wave"
thickness = 0.05
[geometry]
type = "rectangle"
width = 2.0
height = 0.05
mesh_size = 0.0125
[materials.m]
E = 1.0e9
nu = 0.25
density = 1000.0
[regions]
body = "m"
[[monitors]]
name = "v_end"
type = "velocity"
group = "right"
component = "x"
[[stages]]
duration = 0.003
  [[stages.supports]]
  group = "bottom"
  fix = "y"
  [[stages.supports]]
  group = "top"
  fix = "y"
  [[stages.supports]]
  group = "left"
  vx = 0.01
)";
    // Rollers top and bottom give a state of plane (uniaxial) strain in the plane of a plane-stress sheet, so the
    // front travels at c_p = sqrt(E / (rho (1 - nu^2))). At the free end the particle velocity jumps to 2 v0:
    // the arrival is when it crosses v0.
    auto sim = testing::make_simulation(text, "wave");
    const double c = std::sqrt(1e9 / (1000 * (1 - 0.0625)));
    sim.begin_stage(0);
    double arrival = -1;
    while (!sim.stage_finished()) {
        sim.step();
        if (arrival < 0 && sim.monitor_value(0) >= 0.01) arrival = sim.time();
    }
    REQUIRE(arrival > 0);
    CHECK(arrival == Approx(2.0 / c).epsilon(0.02));
}

TEST_CASE("undamped free vibration conserves energy over 100 periods", "[unit]") {
    const std::string text = R"(
[case]
name = "vibration"
thickness = 0.1
[geometry]
type = "rectangle"
width = 1.0
height = 0.1
mesh_size = 0.05
[materials.m]
E = 1.0e9
nu = 0.25
density = 1000.0
[regions]
body = "m"
[[stages]]
duration = 0.4
  [[stages.supports]]
  group = "left"
  fix = "x"
  [[stages.supports]]
  group = "bottom"
  fix = "y"
  [[stages.supports]]
  group = "top"
  fix = "y"
)";
    auto sim = testing::make_simulation(text, "vibration");
    Model& md = sim.model();
    // First axial mode of a fixed-free bar: v = v0 sin(pi X / 2L), period 4 L / c.
    const double c = std::sqrt(1e9 / (1000 * (1 - 0.0625)));
    const double period = 4.0 / c;
    for (int k = 0; k < md.n_nodes(); ++k) md.v[2 * k] = 0.1 * std::sin(M_PI * md.X[2 * k] / 2);
    sim.begin_stage(0);
    // The engine reports energies at t^n, the time of the last force evaluation (K^n = 1/2 m v^{n-1/2}.v^{n+1/2},
    // E_el(x^n)): their sum must stay constant, and so must the balance against the energy put in.
    const Energies e0 = sim.energies();
    const double E0 = e0.kinetic + e0.elastic;
    REQUIRE(E0 > 0);
    double drift = 0, balance = 0;
    while (sim.time() < 100 * period) {
        sim.step();
        if (sim.steps() % 10 == 0) {
            const Energies e = sim.energies();
            drift = std::max(drift, std::abs(e.kinetic + e.elastic - E0) / E0);
            balance = std::max(balance, e.balance_error());
        }
        if (sim.steps() > 200000) break;
    }
    CHECK(sim.time() >= 100 * period);
    INFO("energy drift " << drift << ", balance error " << balance);
    CHECK(drift < 0.005);
    CHECK(balance < 0.005);
}

TEST_CASE("cantilever tip deflection converges monotonically to Timoshenko-Goodier", "[convergence]") {
    const std::string file = std::string(FDEM_CASES_DIR) + "/elastic/cantilever.toml";
    const double exact = -4.02625e-3;  // m, P L^3 / (3 E I) + (4 + 5 nu) P L / (2 E D t)
    double prev_err = 1e9;
    for (double h : {0.05, 0.025, 0.0125}) {
        CaseSpec spec = load_case(file, {"geometry.mesh_size=" + std::to_string(h)});
        Model model = build_model(spec, make_mesh(spec));
        RunOptions opt;
        opt.quiet = true;
        opt.threads = 1;  // (ctest runs two tests at once on two cores; the bits do not depend on it)
        Simulation sim(spec, std::move(model), opt);
        sim.run();
        const double tip = sim.monitor_value(0);
        const double err = std::abs(tip - exact) / std::abs(exact);
        INFO("mesh " << h << " m: tip " << tip << " m, error " << 100 * err << " %");
        CHECK(std::abs(tip) < std::abs(exact));  // CST is too stiff: converges from below
        CHECK(err < prev_err);
        CHECK(sim.energies().balance_error() < 1e-4);
        // Equilibrium: the support carries the load.
        CHECK(sim.monitor_value(1) == Approx(100.0).epsilon(1e-3));
        prev_err = err;
    }
    CHECK(prev_err < 0.05);
}

TEST_CASE("1e5 steps at 0.9 of the computed time step stay stable and 3 x stops with exit code 2", "[unit]") {
    const std::string text = R"(
[case]
name = "stability"
thickness = 0.1
[geometry]
type = "rectangle"
width = 0.4
height = 0.1
mesh_size = 0.05
[materials.m]
E = 1.0e9
nu = 0.3
density = 2000.0
[regions]
body = "m"
[[monitors]]
name = "tip"
type = "displacement"
group = "right"
component = "y"
[numerics]
safety = 0.9
[[stages]]
duration = 1.0
gravity = [0.0, -9.81]
  [[stages.supports]]
  group = "left"
  fix = "xy"
)";
    {
        auto sim = testing::make_simulation(text, "stable");
        sim.begin_stage(0);
        for (int i = 0; i < 100000; ++i) sim.step();
        // Undamped oscillation about the static deflection stays bounded: the self-weight deflection is
        // q L^4 / (8 E I) = 7.5e-5 m and a suddenly applied load at most doubles it.
        CHECK(std::abs(sim.monitor_value(0)) < 3 * 7.5e-5);
        CHECK(sim.energies().balance_error() < 1e-2);
    }
    const auto dir = testing::tmp_dir("unstable");
    const std::string path = testing::write_text(dir / "case.toml", text);
    const auto r = testing::run_fdem("run \"" + path + "\" --quiet --out \"" + (dir / "run").string() +
                                     "\" --set numerics.safety=3 --set stages.1.duration=0.01", dir);
    CHECK(r.code == 2);
    CHECK(r.err.find("run failed") != std::string::npos);
    CHECK(r.err.find("step") != std::string::npos);
    // Everything written so far is kept.
    CHECK(std::filesystem::exists(dir / "run" / "history.csv"));
    CHECK(testing::read_text(dir / "run" / "summary.json").find("\"failed\"") != std::string::npos);
}

namespace {

// Triangle (p: x0 y0 x1 y1 x2 y2, counter-clockwise) of thickness t at its reference placement, nodes 0, 1, 2.
TriangleRef reference_triangle(const double* p, double t) {
    const double det = (p[2] - p[0]) * (p[5] - p[1]) - (p[4] - p[0]) * (p[3] - p[1]);
    const double d00 = p[2] - p[0], d10 = p[3] - p[1], d01 = p[4] - p[0], d11 = p[5] - p[1];
    TriangleRef tr{};
    tr.n[0] = 0, tr.n[1] = 1, tr.n[2] = 2;
    tr.Dinv[0] = d11 / det, tr.Dinv[1] = -d01 / det, tr.Dinv[2] = -d10 / det, tr.Dinv[3] = d00 / det;
    tr.A0t = 0.5 * det * t;
    return tr;
}

// The plane Lame constants of a material.
MaterialConst plane_constants(const Material& mat, Plane plane) {
    MaterialConst mc;
    mc.mu = mat.E / (2 * (1 + mat.nu));
    mc.lambda = plane == Plane::stress ? mat.E * mat.nu / (1 - mat.nu * mat.nu)
                                       : mat.E * mat.nu / ((1 + mat.nu) * (1 - 2 * mat.nu));
    return mc;
}

}  // namespace

// The automatic time step of the triangles: triangle_omega2 must be the highest frequency of K w = omega^2 M w for the
// engine's own triangle (stiffness by central differences of triangle_forces at the reference state, lumped mass
// rho A t / 3 per node), for shapes from equilateral to skew and slender, plane stress and strain, with mass scaling.
TEST_CASE("triangle time step: omega_e is the lumped-mass CST's exact highest frequency", "[unit]") {
    const double shapes[][6] = {{0, 0, 1, 0, 0.5, 0.8660254037844386}, {0, 0, 1, 0, 0, 1},     {0, 0, 2, 0, 0, 1},
                                {0, 0, 1, 0, 0.9, 0.3},                 {0, 0, 1, 0, 0.5, 0.05}, {0.1, 0.2, 0.4, 0.25, 0.2, 0.6}};
    for (Plane plane : {Plane::stress, Plane::strain})
        for (const auto& p : shapes) {
            Material mat;
            mat.E = 3.0e10, mat.nu = 0.2, mat.density = 2500.0;
            const double t = 0.2, scale = 10.0;
            TriangleRef tr = reference_triangle(p, t);
            const MaterialConst mc = plane_constants(mat, plane);
            Eigen::Matrix<double, 6, 6> K;
            const double h = 1e-7, v[6] = {0, 0, 0, 0, 0, 0};
            for (int j = 0; j < 6; ++j) {
                double xp[6], xm[6], fp[6], fm[6], pw;
                for (int i = 0; i < 6; ++i) xp[i] = xm[i] = p[i];
                xp[j] += h, xm[j] -= h;
                triangle_forces(tr, mc, xp, v, fp, pw);
                triangle_forces(tr, mc, xm, v, fm, pw);
                for (int i = 0; i < 6; ++i) K(i, j) = -(fp[i] - fm[i]) / (2 * h);
            }
            const Eigen::Matrix<double, 6, 6> Ks = 0.5 * (K + K.transpose());
            const double m = mat.density * scale * tr.A0t / 3.0;
            const double w2_exact = Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>(Ks / m).eigenvalues().maxCoeff();
            const double w2 = triangle_omega2(p, tr.n, mat, plane, scale);
            CHECK(w2 == Approx(w2_exact).epsilon(1e-6));
        }
}

// The damped step of a viscous triangle: central differences with the viscous force from v^{n-1/2} are stable while
// the spectral radius of the step's amplification matrix [x; v] -> [x + dt v+; v+], v+ = v + dt M^-1 (-K x - C v),
// stays at 1. K and C from central differences of the engine's triangle_forces in x and in v at the reference state,
// M lumped. The limit triangle_damped_factor gives, (2 / omega_e) f_e, must be that threshold: at 0.999 of it the
// radius is 1, at 1.002 above 1. The nominal damped_step_factor(xi) of eta = xi 2 h sqrt(E rho) is not (it is above
// the threshold for every shape: the highest viscous mode is damped at about twice xi).
TEST_CASE("triangle time step: the viscous triangle's damped limit is the threshold of the lagged-viscosity update",
          "[unit]") {
    const double shapes[][6] = {{0, 0, 1, 0, 0.5, 0.8660254037844386}, {0, 0, 1, 0, 0, 1}, {0, 0, 2, 0, 0, 1},
                                {0, 0, 1, 0, 0.9, 0.3}, {0.1, 0.2, 0.4, 0.25, 0.2, 0.6}};
    for (Plane plane : {Plane::stress, Plane::strain})
        for (const auto& p : shapes)
            for (double xi : {0.1, 0.5, 1.0}) {
                Material mat;
                mat.E = 3.0e10, mat.nu = 0.2, mat.density = 2500.0;
                const double t = 0.2, scale = 1.0;
                TriangleRef tr = reference_triangle(p, t);
                const double d00 = p[2] - p[0], d10 = p[3] - p[1], d01 = p[4] - p[0], d11 = p[5] - p[1];
                const double l0 = std::hypot(d00, d10), l1 = std::hypot(d01, d11), l2 = std::hypot(d01 - d00, d11 - d10);
                tr.eta = xi * 2 * (2 * tr.A0t / t / std::max({l0, l1, l2})) * std::sqrt(mat.E * mat.density * scale);
                const MaterialConst mc = plane_constants(mat, plane);
                Eigen::Matrix<double, 6, 6> K, C;
                const double h = 1e-7, hv = 1e-3, zero[6] = {0, 0, 0, 0, 0, 0};
                for (int j = 0; j < 6; ++j) {
                    double xp[6], xm[6], vp[6] = {0, 0, 0, 0, 0, 0}, vm[6] = {0, 0, 0, 0, 0, 0}, fp[6], fm[6], pw;
                    for (int i = 0; i < 6; ++i) xp[i] = xm[i] = p[i];
                    xp[j] += h, xm[j] -= h;
                    triangle_forces(tr, mc, xp, zero, fp, pw);
                    triangle_forces(tr, mc, xm, zero, fm, pw);
                    for (int i = 0; i < 6; ++i) K(i, j) = -(fp[i] - fm[i]) / (2 * h);
                    vp[j] = hv, vm[j] = -hv;
                    triangle_forces(tr, mc, p, vp, fp, pw);
                    triangle_forces(tr, mc, p, vm, fm, pw);
                    for (int i = 0; i < 6; ++i) C(i, j) = -(fp[i] - fm[i]) / (2 * hv);
                }
                const Eigen::Matrix<double, 6, 6> Ks = 0.5 * (K + K.transpose()), Cs = 0.5 * (C + C.transpose());
                const double m = mat.density * scale * tr.A0t / 3.0;
                const double w2 = triangle_omega2(p, tr.n, mat, plane, scale);
                const double f = triangle_damped_factor(p, tr.n, mat, plane, scale, tr.eta, 0.0);
                const double dt_lim = 2.0 / std::sqrt(w2) * f;
                auto radius = [&](double dt) {
                    using M6 = Eigen::Matrix<double, 6, 6>;
                    const M6 I = M6::Identity(), Vk = I - dt / m * Cs, Xk = -dt / m * Ks;
                    Eigen::Matrix<double, 12, 12> T;
                    T << I + dt * Xk, dt * Vk, Xk, Vk;
                    return Eigen::EigenSolver<Eigen::Matrix<double, 12, 12>>(T, false).eigenvalues().cwiseAbs().maxCoeff();
                };
                INFO("plane " << (plane == Plane::stress ? "stress" : "strain") << ", shape " << p[4] << ", " << p[5]
                              << ", xi " << xi << ", f_e " << f << ", nominal " << damped_step_factor(xi, 0.0));
                CHECK(radius(0.999 * dt_lim) < 1.0 + 1e-6);
                CHECK(radius(1.002 * dt_lim) > 1.0 + 1e-6);
                CHECK(f < damped_step_factor(xi, 0.0));
                // Without viscosity the factor is the undamped one, the same bits as damped_step_factor(0, alpha).
                CHECK(triangle_damped_factor(p, tr.n, mat, plane, scale, 0.0, 0.7) == damped_step_factor(0.0, 0.7));
            }
}
