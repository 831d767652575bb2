// Closed-form tests of the composite joint law (fracture/composite_law.hpp: [PDEM] §2, Fig. 4, with the cap of
// [LR97]): the dissipated energy of each branch equals its fracture energy, the cap surface sigma^2 + C_s tau^2 =
// f_m^2, unloading paths, the tension-shear and shear-compression couplings, the property checks, and determinism of
// the element loop for 1, 2 and 4 threads.
#include <omp.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "fracture/cohesive_system.hpp"
#include "fracture/composite_law.hpp"
#include "fracture/properties.hpp"
#include "test_grid.hpp"

using namespace fdem::fracture;

namespace {
constexpr double kDeg = 3.14159265358979323846 / 180.0;

// The unit-mortar interface of the 0.30 MPa Vermeltfoort wall ([PDEM] Table 1): k_n 82 GPa/m, k_s 36 GPa/m,
// f_t 0.25 MPa, c_0 = 1.4 f_t, theta 35 deg before and after, G_I 12, G_II 125, G_c 5000 J/m^2, f_m 10.5 MPa, C_s 9.
const double kn = 82e9, ks = 36e9, ft = 0.25e6, c0 = 0.35e6, GI = 12.0, GII = 125.0, fm = 10.5e6, Gc = 5000.0, Cs = 9.0;
const double tan35 = std::tan(35.0 * kDeg);

CompositeLaw mortar(double f_m = fm) {
    return make_composite_law(kn, ks, ft, GI, c0, 35.0, 35.0, GII, f_m, Gc, Cs);
}

// Drives one point along a straight path from its last state to (o1, s1) in n equal increments; sums the dissipation
// (fracture and crushing) and the friction work, and records the extreme stresses.
struct Driver {
    CompositeLaw L;
    CompositeHistory h;
    double o = 0.0, s = 0.0;
    double dissipated = 0.0, friction = 0.0, work = 0.0;
    double sigma = 0.0, tau = 0.0, sigma_max = -1e300, sigma_min = 1e300, tau_max = 0.0;
    void to(double o1, double s1, int n) {
        const double o0 = o, s0 = s;
        for (int k = 1; k <= n; ++k) {
            const double on = o0 + (o1 - o0) * k / n, sn = s0 + (s1 - s0) * k / n;
            const PointResponse r = evaluate_composite(L, on, sn, h);
            work += 0.5 * (sigma + r.sigma) * (on - o) + 0.5 * (tau + r.tau) * (sn - s);
            o = on;
            s = sn;
            sigma = r.sigma;
            tau = r.tau;
            dissipated += r.dissipated;
            friction += r.friction_dissipated;
            sigma_max = std::max(sigma_max, sigma);
            sigma_min = std::min(sigma_min, sigma);
            tau_max = std::max(tau_max, std::abs(tau));
            energy = r.energy;
        }
    }
    double energy = 0.0;
};

bool any_contains(const std::vector<std::string>& v, const std::string& what) {
    for (const auto& m : v)
        if (m.find(what) != std::string::npos) return true;
    return false;
}

CohesiveProps mortar_props() {
    CohesiveProps p;
    p.composite = true;
    p.tensile_strength = ft;
    p.cohesion = c0;
    p.friction_deg = 35.0;
    p.residual_friction_deg = 35.0;
    p.G_I = GI;
    p.G_II = GII;
    p.k_n = kn;
    p.k_s = ks;
    p.compressive_strength = fm;
    p.compressive_energy = Gc;
    p.cap_shear_factor = Cs;
    return p;
}
}  // namespace

TEST_CASE("composite law: pure tension peaks at f_t and dissipates G_I", "[unit]") {
    Driver d{mortar(), {}};
    const double o_u = 2.0 * GI / ft;  // 96 um: linear softening to zero, area f_t o_u / 2 = G_I
    d.to(1.2 * o_u, 0.0, 4000);
    CHECK(d.sigma_max == Approx(ft).epsilon(1e-3));
    CHECK(d.sigma == 0.0);
    CHECK(d.h.damage == 1.0);
    CHECK(d.dissipated == Approx(GI).epsilon(0.01));
    CHECK(d.friction == 0.0);
    CHECK(d.work == Approx(d.dissipated + d.energy).epsilon(1e-9));
    CHECK(d.h.damage_I == Approx(1.0));  // all of D came from opening: a mode I break
    CHECK(d.h.damage_II == 0.0);
}

TEST_CASE("composite law: pure shear at zero normal stress peaks at c_0 and dissipates G_II", "[unit]") {
    Driver d{mortar(), {}};
    const double kappa_u = 2.0 * GII / c0;  // plastic slip at which the cohesion is gone
    d.to(0.0, 1.2 * kappa_u, 4000);
    CHECK(d.tau_max == Approx(c0).epsilon(1e-3));
    CHECK(d.tau == Approx(0.0).margin(1e-6 * c0));
    CHECK(d.h.damage == 1.0);
    CHECK(d.dissipated == Approx(GII).epsilon(0.01));
    CHECK(d.friction == 0.0);
    CHECK(d.h.damage_II == Approx(1.0));
    CHECK(d.h.damage_I == 0.0);
}

TEST_CASE("composite law: shear under compression ends on sigma tan(theta_res) and books G_II plus friction",
          "[unit]") {
    // 2 MPa of compression (no cap reached: f_m = 10.5 MPa, tau <= 1.75 MPa, 4 + 9 x 3.1 = 31.6 < 110 MPa^2).
    const double sigma_n = 2.0e6;
    Driver d{mortar(), {}};
    d.to(-sigma_n / kn, 0.0, 100);
    const double kappa_u = 2.0 * GII / c0;
    const double s_end = 1.5 * kappa_u;
    d.to(-sigma_n / kn, s_end, 6000);
    CHECK(d.sigma == Approx(-sigma_n).epsilon(1e-12));
    CHECK(d.tau_max == Approx(c0 + sigma_n * tan35).epsilon(1e-3));
    CHECK(d.tau == Approx(sigma_n * tan35).epsilon(1e-9));  // friction kept, c_res = 0
    CHECK(d.h.crush == 0.0);
    CHECK(d.dissipated == Approx(GII).epsilon(0.01));
    // Friction: sigma tan(theta) times the whole plastic slip s_end - tau_end / k_s.
    CHECK(d.friction == Approx(sigma_n * tan35 * (s_end - d.tau / ks)).epsilon(1e-3));
}

TEST_CASE("composite law: pure compression peaks at f_m on the cap and dissipates G_c", "[unit]") {
    Driver d{mortar(), {}};
    const double u_u = 2.0 * Gc / fm;  // 0.95 mm
    d.to(-1.2 * u_u, 0.0, 4000);
    CHECK(d.sigma_min == Approx(-fm).epsilon(1e-3));
    CHECK(d.sigma == 0.0);
    CHECK(d.h.crush == 1.0);
    CHECK(d.h.damage == 0.0);  // one-way: crushing does not damage the tension-shear bond
    CHECK(d.dissipated == Approx(Gc).epsilon(0.01));
    // Without the cap the compression stays linear.
    Driver n{mortar(0.0), {}};
    n.to(-1.2 * u_u, 0.0, 10);
    CHECK(n.sigma == Approx(-kn * 1.2 * u_u).epsilon(1e-12));
}

TEST_CASE("composite law: compressive damage starts on the cap sigma^2 + C_s tau^2 = f_m^2 at several ratios",
          "[unit]") {
    // Radial paths in stress, tau / sigma = r, all inside the Mohr-Coulomb limit where they reach the cap (tau_cap <=
    // c_0 + |sigma| tan(theta)): the first state with D_c > 0 and the last with D_c = 0 bracket the cap.
    for (const double r : {0.0, 0.1, 0.25, 0.4, 0.55}) {
        const CompositeLaw L = mortar();
        CompositeHistory h;
        const double sig_cap = fm / std::sqrt(1.0 + Cs * r * r), tau_cap = r * sig_cap;  // on the cap
        REQUIRE(tau_cap < c0 + sig_cap * tan35);
        const int n = 20000;
        double before = 0.0, after = 0.0;
        for (int k = 1; k <= n; ++k) {
            const double lam = 1.2 * k / n;  // stress-path parameter: 1 = the cap
            const PointResponse p = evaluate_composite(L, -lam * sig_cap / kn, lam * tau_cap / ks, h);
            const double F = std::sqrt(p.sigma * p.sigma + Cs * p.tau * p.tau);
            if (h.crush == 0.0)
                before = F;
            else {
                after = F;
                break;
            }
        }
        INFO("tau/sigma = " << r << ": sqrt(sigma^2 + C_s tau^2) " << before << " .. " << after << " Pa");
        CHECK(before <= fm);
        CHECK(before == Approx(fm).epsilon(1e-4));
        CHECK(after > 0.0);
        CHECK(h.damage == 0.0);  // elastic in shear all the way
    }
}

TEST_CASE("composite law: unloading returns to the origin after tension or compression damage, elastic in shear",
          "[unit]") {
    const double o_p = ft / kn, o_u = 2.0 * GI / ft;
    SECTION("tension: secant unloading and reloading without dissipation") {
        Driver d{mortar(), {}};
        const double o_half = o_p + 0.5 * (o_u - o_p);  // D = 0.5
        d.to(o_half, 0.0, 400);
        CHECK(d.h.damage == Approx(0.5).epsilon(1e-12));
        CHECK(d.sigma == Approx(0.5 * ft).epsilon(1e-12));
        const double diss = d.dissipated;
        d.to(0.5 * o_half, 0.0, 100);
        CHECK(d.sigma == Approx(0.25 * ft).epsilon(1e-12));  // straight line to the origin
        d.to(0.0, 0.0, 100);
        CHECK(d.sigma == 0.0);
        CHECK(d.energy == 0.0);
        d.to(o_half, 0.0, 200);  // reload on the same secant
        CHECK(d.sigma == Approx(0.5 * ft).epsilon(1e-12));
        CHECK(d.dissipated == Approx(diss).margin(1e-9 * GI));
        CHECK(d.h.damage == Approx(0.5).epsilon(1e-12));
    }
    SECTION("compression: secant unloading after crushing") {
        Driver d{mortar(), {}};
        const double u_p = fm / kn, u_u = 2.0 * Gc / fm, u_half = u_p + 0.5 * (u_u - u_p);
        d.to(-u_half, 0.0, 1000);
        CHECK(d.h.crush == Approx(0.5).epsilon(1e-12));
        CHECK(d.sigma == Approx(-0.5 * fm).epsilon(1e-12));
        const double diss = d.dissipated;
        d.to(-0.5 * u_half, 0.0, 100);
        CHECK(d.sigma == Approx(-0.25 * fm).epsilon(1e-12));
        d.to(0.0, 0.0, 100);
        CHECK(d.sigma == 0.0);
        CHECK(d.dissipated == Approx(diss).margin(1e-9 * Gc));
        // The tensile side is untouched by crushing (one-way coupling): f_t and k_n as new.
        d.to(0.5 * o_p, 0.0, 10);
        CHECK(d.sigma == Approx(0.5 * ft).epsilon(1e-12));
    }
    SECTION("shear: no stiffness degradation, the plastic slip stays") {
        Driver d{mortar(), {}};
        const double kappa_u = 2.0 * GII / c0, s1 = c0 / ks + 0.3 * kappa_u;
        d.to(0.0, s1, 2000);
        const double tau1 = d.tau, D1 = d.h.damage, diss = d.dissipated;
        CHECK(D1 > 0.25);
        CHECK(tau1 == Approx(c0 * (1.0 - D1)).epsilon(1e-9));
        const double ds = 0.5 * tau1 / ks;
        d.to(0.0, s1 - ds, 50);  // unloads with k_s
        CHECK(d.tau == Approx(tau1 - ks * ds).epsilon(1e-9));
        d.to(0.0, d.h.plastic_slip, 50);  // zero stress at the plastic slip
        CHECK(d.tau == Approx(0.0).margin(1e-6 * c0));
        CHECK(d.dissipated == Approx(diss).margin(1e-9 * GII));
        CHECK(d.h.damage == D1);
        // Reverse slip: yields at -c_0 (1 - D) on the other side.
        d.to(0.0, d.h.plastic_slip - 2.0 * c0 / ks, 400);
        CHECK(d.tau == Approx(-c0 * (1.0 - d.h.damage)).epsilon(1e-6));
    }
}

TEST_CASE("composite law: one damage couples tension and shear both ways", "[unit]") {
    const double o_p = ft / kn, o_u = 2.0 * GI / ft;
    // Opening to D = 0.4 takes 40 % of the cohesion.
    Driver d{mortar(), {}};
    d.to(o_p + 0.4 * (o_u - o_p), 0.0, 400);
    d.to(0.0, 0.0, 100);
    REQUIRE(d.h.damage == Approx(0.4).epsilon(1e-12));
    d.to(0.0, 2.0 * c0 / ks, 400);
    CHECK(d.tau_max == Approx(0.6 * c0).epsilon(1e-3));
    // Slip to D = 0.5 lowers the tensile strength to f_t / 2 (the secant of the envelope point D = 0.5).
    Driver e{mortar(), {}};
    const double kappa_u = 2.0 * GII / c0;
    e.to(0.0, c0 / ks + 0.5 * kappa_u, 4000);
    const double D = e.h.damage;
    REQUIRE(D > 0.45);
    e.to(0.0, e.h.plastic_slip, 100);
    e.to(o_p + D * (o_u - o_p), e.h.plastic_slip, 400);
    CHECK(e.sigma_max == Approx(ft * (1.0 - D)).epsilon(1e-6));
}

TEST_CASE("composite law: the same path gives the same bits", "[unit]") {
    auto path = [] {
        Driver d{mortar(), {}};
        d.to(-3e6 / kn, 0.0, 50);
        d.to(-3e6 / kn, 1e-3, 500);
        d.to(2e-4, 2e-4, 500);
        d.to(-2.5 * fm / kn, -1e-3, 500);
        return std::vector<double>{d.sigma, d.tau, d.dissipated, d.friction, d.h.damage, d.h.crush, d.h.plastic_slip};
    };
    const std::vector<double> a = path(), b = path();
    CHECK(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

TEST_CASE("composite law: check() names missing cap keys, shear_softening and too-soft joints", "[unit]") {
    CHECK(check(mortar_props(), 0.0).empty());
    CohesiveProps p = mortar_props();
    p.compressive_energy = CohesiveProps::unset;
    CHECK(any_contains(check(p, 0.0), "compressive fracture energy G_c"));
    p = mortar_props();
    p.keep_friction = true;
    CHECK(any_contains(check(p, 0.0), "shear_softening"));
    p = mortar_props();
    p.G_II = 1.0;  // c_0^2 / (2 k_s) = 1.7 J/m^2
    CHECK(any_contains(check(p, 0.0), "mode II"));
    p = mortar_props();
    p.compressive_strength = CohesiveProps::unset;  // no cap at all is allowed
    p.compressive_energy = CohesiveProps::unset;
    p.cap_shear_factor = CohesiveProps::unset;
    CHECK(check(p, 0.0).empty());
    // The element loop sees only the stiffnesses in JointLaw (stable time step).
    const JointLaw L = make_law(mortar_props(), 0.03);
    CHECK(L.normal_stiffness == kn);
    CHECK(L.shear_stiffness == ks);
}

namespace {
// A fully split grid stretched and sheared (as tests/fracture/test_system.cpp) with the composite law.
std::vector<double> grid_positions(const fracture_test::SplitGrid& g, double lam) {
    std::vector<double> x = g.x;
    const double L = g.x[g.x.size() - 2];
    for (int t = 0; t < g.num_triangles(); ++t) {
        double cx = 0.0, cy = 0.0;
        for (int k = 0; k < 3; ++k) {
            cx += g.x[2 * g.tri[3 * t + k]] / 3.0;
            cy += g.x[2 * g.tri[3 * t + k] + 1] / 3.0;
        }
        // Shear and stretch growing to the right, compression growing upwards: every branch of the law.
        const double ux = lam * 4e-3 * (cx / L + 2.0 * std::pow(cx / L, 3) + cy / L);
        const double uy = lam * 4e-3 * (0.3 * cx / L - 2.0 * (cy / L) * (cy / L));
        for (int k = 0; k < 3; ++k) {
            const int v = g.tri[3 * t + k];
            x[2 * v] += ux;
            x[2 * v + 1] += uy;
        }
    }
    return x;
}

struct GridRun {
    std::vector<double> f, damage;
    double elastic = 0.0, dissipated = 0.0, friction = 0.0, work = 0.0;
    std::size_t broken = 0;
};

GridRun grid_run(const fracture_test::SplitGrid& g, int threads, int steps) {
    omp_set_num_threads(threads);
    CohesiveProps p = mortar_props();
    p.k_n = CohesiveProps::unset;
    p.k_s = CohesiveProps::unset;
    p.penalty = 5e10;  // Pa: K = p_j / h
    CohesiveSystem sys(g.elems, {p}, 0.1, g.x.data(), g.num_nodes());
    GridRun r;
    std::vector<double> f_old(g.x.size(), 0.0), x_old = g.x;
    for (int s = 1; s <= steps; ++s) {
        const std::vector<double> x = grid_positions(g, double(s) / steps);
        r.f.assign(g.x.size(), 0.0);
        sys.add_forces(x.data(), r.f.data());
        r.broken += sys.update_damage(0.0, 0.0, x.data()).size();
        for (std::size_t i = 0; i < r.f.size(); ++i) r.work -= 0.5 * (f_old[i] + r.f[i]) * (x[i] - x_old[i]);
        f_old = r.f;
        x_old = x;
    }
    r.damage.resize(sys.size());
    sys.damage_per_element(r.damage.data());
    r.elastic = sys.elastic_energy();
    r.dissipated = sys.dissipated_energy();
    r.friction = sys.friction_energy();
    return r;
}
}  // namespace

TEST_CASE("composite law in CohesiveSystem: bitwise identical for 1 and 2 and 4 threads, books close", "[unit]") {
    const auto g = fracture_test::make_split_grid(80, 40, 0.01);  // ~9500 elements: above the parallel threshold
    const int saved = omp_get_max_threads();
    const GridRun r1 = grid_run(g, 1, 400), r2 = grid_run(g, 2, 400), r4 = grid_run(g, 4, 400);
    omp_set_num_threads(saved);
    int damaged = 0;
    for (double d : r1.damage) damaged += (d > 0.0 && d < 1.0) ? 1 : 0;
    WARN("composite grid: elements " << r1.damage.size() << ", broken " << r1.broken << ", damaged " << damaged
                                     << "; work " << r1.work << " J, elastic " << r1.elastic << ", dissipated "
                                     << r1.dissipated << ", friction " << r1.friction);
    CHECK(r1.broken > 100);
    CHECK(damaged > 100);
    CHECK(r1.friction > 0.0);
    CHECK(std::memcmp(r1.f.data(), r2.f.data(), r1.f.size() * sizeof(double)) == 0);
    CHECK(std::memcmp(r1.f.data(), r4.f.data(), r1.f.size() * sizeof(double)) == 0);
    CHECK(std::memcmp(r1.damage.data(), r4.damage.data(), r1.damage.size() * sizeof(double)) == 0);
    CHECK(std::memcmp(&r1.dissipated, &r4.dissipated, sizeof(double)) == 0);
    CHECK(r1.broken == r4.broken);
    // Work of the joint forces = recoverable + dissipated + friction (+ what broken elements took with them, which is
    // booked as dissipated).
    CHECK(r1.work == Approx(r1.elastic + r1.dissipated + r1.friction).epsilon(5e-3));
}
