// tests/fracture/test_engine_fracture.cpp: fracture through the real engine (issue 7): case text -> Gmsh .geo ->
// topology (split nodes, cohesive elements) -> Interactions (joints + contact) -> Simulation, as `fdem run` does.
//
// DATA LAYOUT
//   Case files and .geo scripts live in tests/fracture/cases/ (read at test time through __FILE__, so the tests run
//   the very files a user can run with `fdem run`). Every test copies them into build/tests/tmp/<name>/ (the .geo
//   possibly edited, e.g. the bar's nx, ny) and builds the Simulation with fdem::build_scene: testing::make_simulation
//   skips the topology, so it would have no cohesive elements.
//   Broken elements are read from sim.interactions().joints(): state(e) == broken, element(e).n = {a0, a1, b0, b1}
//   (model node numbering); their reference geometry comes from sim.model().X (2 per node, m).
//   Forces are for the whole thickness (N), energies in J, as in the engine.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "contact/contact_system.hpp"
#include "core/engine_helpers.hpp"
#include "fdem/scene.hpp"
#include "fdem/triangle.hpp"
#include "fracture/cohesive_system.hpp"

namespace {

namespace fs = std::filesystem;
using fdem::fracture::JointState;

fs::path cases_dir() { return fs::path(__FILE__).parent_path() / "cases"; }

std::string replace_once(std::string text, const std::string& from, const std::string& to) {
    const auto p = text.find(from);
    REQUIRE(p != std::string::npos);
    return text.replace(p, from.size(), to);
}

// Writes `files` (name -> text) and the case next to each other in tmp/<name>/ and builds the Simulation with its
// topology. One thread: a few hundred triangles run fastest on one (the engine is bit-identical for any count).
fdem::Simulation make_fracture_sim(const std::string& name, const std::string& case_text,
                                   const std::map<std::string, std::string>& files,
                                   const std::vector<std::string>& overrides = {}) {
    const auto dir = testing::tmp_dir(name);
    for (const auto& [file, text] : files) testing::write_text(dir / file, text);
    const std::string path = testing::write_text(dir / "case.toml", case_text);
    fdem::CaseSpec spec = fdem::load_case(path, overrides);
    fdem::Model model = fdem::build_scene(spec);
    fdem::RunOptions opt;
    opt.quiet = true;
    opt.threads = 1;
    return fdem::Simulation(spec, std::move(model), opt);
}

// One broken cohesive element in the reference configuration.
struct Crack {
    int element;
    double x0, y0, x1, y1;  // reference end points a0, a1 (m)
    double xm() const { return 0.5 * (x0 + x1); }
    double ym() const { return 0.5 * (y0 + y1); }
    double length() const { return std::hypot(x1 - x0, y1 - y0); }
};

std::vector<Crack> broken_elements(const fdem::Simulation& sim) {
    std::vector<Crack> out;
    const auto* j = sim.interactions().joints();
    REQUIRE(j != nullptr);
    const auto& X = sim.model().X;
    for (int e = 0; e < j->size(); ++e)
        if (j->state(e) == JointState::broken) {
            const auto& el = j->element(e);
            out.push_back({e, X[2 * el.n[0]], X[2 * el.n[0] + 1], X[2 * el.n[1]], X[2 * el.n[1] + 1]});
        }
    return out;
}

// Contact pairs of one body whose triangles meet only at copies of one vertex (corner neighbours, fdem/README.md 'Contact'):
// the contact system drops them until a cohesive element at that vertex breaks.
int corner_pairs(const fdem::Simulation& sim) {
    const auto* c = sim.interactions().contact();
    REQUIRE(c != nullptr);
    const auto& m = sim.model();
    REQUIRE(m.node_vertex.size() == static_cast<std::size_t>(m.n_nodes()));
    auto body = [&](int t) { return m.mesh.tri_body.empty() ? 0 : m.mesh.tri_body[t]; };
    int n = 0;
    for (std::size_t p = 0; p < c->pair_a().size(); ++p) {
        const int a = c->pair_a()[p], b = c->pair_b()[p];
        if (body(a) != body(b)) continue;
        int shared = 0;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                shared += m.node_vertex[m.mesh.tri[3 * a + i]] == m.node_vertex[m.mesh.tri[3 * b + j]];
        n += shared == 1;
    }
    return n;
}

long long broken_count(const fdem::Simulation& sim) {
    const auto* c = sim.interactions().counts();
    return c ? c->total() : 0;
}

// Energies with the contact energy of the current state (the engine evaluates it on reported steps only): one more
// step with the energy switched on.
fdem::Energies energies_now(fdem::Simulation& sim) {
    sim.energy_every_step(true);
    sim.step();
    sim.energy_every_step(false);
    return sim.energies();
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------------
// 1. Bar in tension, every edge crackable (cases/README.md §C): the transfinite mesh has straight vertical lines of edges,
//    so the exact answer is one straight mode I crack across the bar, peak force f_t A and dissipation G_I A.
// ---------------------------------------------------------------------------------------------------------------
TEST_CASE("engine bar in tension with every edge crackable: one straight crack, peak f_t A, dissipation G_I A",
          "[engine][convergence]") {
    const std::string geo0 = testing::read_text(cases_dir() / "bar_structured.geo");
    const std::string toml = testing::read_text(cases_dir() / "bar_structured.toml");
    REQUIRE(!geo0.empty());
    REQUIRE(!toml.empty());
    const double ft = 3.7e6, GI = 110.0;  // Pa, J/m^2 (the case's stone)
    const double L = 0.2, H = 0.1, t = 0.2;  // m
    const double A = H * t;                 // m^2, cross-section
    for (int nx : {4, 8, 16, 20}) {
        const int ny = nx / 2;
        const double h = L / nx;  // m
        const std::string geo = replace_once(geo0, "nx = 16; ny = 8;", "nx = " + std::to_string(nx) + "; ny = " + std::to_string(ny) + ";");
        auto sim = make_fracture_sim("fracture_engine_bar_" + std::to_string(nx), toml, {{"bar_structured.geo", geo}});
        // Monitors of the case, in order: ux (right end), R (right support), R_left.
        sim.begin_stage(0);
        double peak = 0, peak_time = 0, peak_left = 0;
        double t_sep = -1;
        int corners_intact = -1, corners_cracked = -1;
        std::vector<std::array<double, 2>> rising;  // (R, R_left) at each new largest R (N)
        while (!sim.stage_finished()) {
            sim.step();
            if (corners_intact < 0) corners_intact = corner_pairs(sim);
            if (t_sep > 0 && corners_cracked < 0) corners_cracked = corner_pairs(sim);  // the step after separation
            const double R = sim.monitor_value(1);
            if (R > peak) {
                rising.push_back({R, sim.monitor_value(2)});
                peak = R, peak_time = sim.time(), peak_left = sim.monitor_value(2);
            }
            if (t_sep < 0 && broken_count(sim) >= ny) t_sep = sim.time();
            // 1 ms (5 axial transits of the bar) after the separation, to see whether anything else breaks.
            if (t_sep > 0 && sim.time() > t_sep + 1e-3) break;
        }
        // The loading branch at 98 % of the peak: the first step with R >= 0.98 peak (a new largest R, since every
        // step before it had less).
        double load_R = 0, load_left = 0;
        for (const auto& s : rising)
            if (s[0] >= 0.98 * peak) {
                load_R = s[0], load_left = s[1];
                break;
            }
        const fdem::Energies e = energies_now(sim);
        const auto cracks = broken_elements(sim);
        double xmin = 1e9, xmax = -1e9, len = 0, ymin = 1e9, ymax = -1e9;
        for (const auto& c : cracks) {
            xmin = std::min({xmin, c.x0, c.x1}), xmax = std::max({xmax, c.x0, c.x1});
            ymin = std::min({ymin, c.y0, c.y1}), ymax = std::max({ymax, c.y0, c.y1});
            len += c.length();
        }
        std::printf("bar nx=%d h=%.4g m: dt=%.4g s, %ld steps, broken %zu at x=%.5g..%.5g m, crack length %.5g m, "
                    "peak R/(f_t A)=%.5f at t=%.4g s (R_left/R=%.5f; at 0.98 peak %.5f), D_frac/(G_I A)=%.5f, balance error %.3g, "
                    "separated at %.4g s\n",
                    nx, h, sim.dt(), sim.steps(), cracks.size(), xmin, xmax, len, peak / (ft * A), peak_time,
                    -peak_left / peak, -load_left / load_R, e.fracture / (GI * A), e.balance_error(), t_sep);
        INFO("nx = " << nx);
        REQUIRE(t_sep > 0);
        // A single crack: exactly the ny edges of one vertical line, spanning the whole section.
        CHECK(cracks.size() == static_cast<std::size_t>(ny));
        CHECK(xmax - xmin < 1e-9);
        CHECK(len == Approx(H).epsilon(1e-9));
        // Corner neighbours along the free boundary form no pair while the bar is intact; the crack's vertices are
        // released when it breaks, so the triangles meeting at them across and along the crack may touch.
        CHECK(corners_intact == 0);
        CHECK(corners_cracked > 0);
        CHECK(ymin == Approx(0.0).margin(1e-9));
        CHECK(ymax == Approx(H).epsilon(1e-9));
        CHECK(peak / (ft * A) == Approx(1.0).epsilon(0.03));
        CHECK(e.fracture / (GI * A) == Approx(1.0).epsilon(0.05));
        // Quasi-static: the pull reaches the peak in ~10 ms, 25 periods of the bar's first axial mode (4 L / c =
        // 0.39 ms, c = sqrt(E / rho) = 2040 m/s), after a 1 ms smooth velocity ramp; the dynamic stress of the
        // velocity itself, rho c v = 49 kPa, is 1.3 % of f_t before damping. Check: both supports carry the same
        // force on the loading branch at 98 % of the peak (their difference is the bar's inertia force). Not at the
        // largest R itself: with local damping 0.8 the pulled end can hold f_t A for a few tenths of a ms while the
        // crack already softens (the damping, not inertia, then carries the difference), and the largest sample may
        // fall there (nx = 20 with the crack one element from the fixed end: R_left / R 0.72 at it).
        REQUIRE(load_R > 0.0);
        CHECK(std::abs(load_left + load_R) / load_R < 0.015);
        // Pure mode I, no compression, no contact: the books close to the integrator's O(dt^2) (measured < 2e-6).
        CHECK(e.balance_error() < 1e-4);
    }
}


namespace {

// Energy audit: the engine's balance W_ext = K + E_el + E_joint + E_contact + D_damp + D_visc + D_frac + D_fric is
// exact for K, W_ext and D_damp by construction (they are accumulated as dt f . vbar with the same vbar that changes
// K), so any residual comes from a force class whose work differs from the change of its own energy plus its
// dissipation. The audit evaluates each class on copies of the engine's systems at x^n before every step and
// accumulates W_class = sum dt f_class(x^n) . vbar^n, vbar^n = (v^{n-1/2} + v^{n+1/2}) / 2. Class mismatches (J, 0 for
// a class whose forces are consistent with its energy):
//   triangles: -W_tri - (E_el(end) - E_el(0)),  joints: -W_joint - (E_joint(end) - E_joint(0)) - D_frac,
//   contact:   -W_contact - (E_contact(end) - E_contact(0)) - D_fric,
// and W_ext - (K + E_el + ... + D_fric) = sum of the three (the test checks that too).
struct EnergyAudit {
    double W_tri = 0, W_joint = 0, W_contact = 0;  // J, work done BY each class on the nodes
    double E_el0 = 0, E_joint0 = 0, E_contact0 = 0, D_frac0 = 0, D_fric0 = 0;
    std::vector<double> v_old, f_tri, f_joint, f_contact;
    std::optional<fdem::fracture::CohesiveSystem> joints;
    std::optional<fdem::contact::ContactSystem> contact;

    void start(fdem::Simulation& sim) {
        const fdem::Energies e = energies_now(sim);
        E_el0 = e.elastic, E_joint0 = e.joint, E_contact0 = e.contact, D_frac0 = e.fracture, D_fric0 = e.friction;
    }
    // One engine step with the audit around it.
    void step(fdem::Simulation& sim) {
        const fdem::Model& md = sim.model();
        const int nn = md.n_nodes();
        f_tri.assign(2 * nn, 0.0), f_joint.assign(2 * nn, 0.0), f_contact.assign(2 * nn, 0.0);
        double f6[6], p;
        for (int e = 0; e < md.n_triangles(); ++e) {
            fdem::triangle_forces(md.tris[e], md.mat[md.tris[e].mat], md.x.data(), md.v.data(), f6, p);
            for (int k = 0; k < 3; ++k) f_tri[2 * md.tris[e].n[k]] += f6[2 * k], f_tri[2 * md.tris[e].n[k] + 1] += f6[2 * k + 1];
        }
        // Copy-assigned into kept copies: their vectors keep their storage (a fresh copy per step costs page faults).
        if (const auto* j = sim.interactions().joints()) {
            if (joints) *joints = *j;
            else joints.emplace(*j);
            joints->add_forces(md.x.data(), f_joint.data());
        }
        if (const auto* c = sim.interactions().contact()) {
            if (contact) *contact = *c;
            else contact.emplace(*c);
            contact->step(md.x.data(), md.v.data(), sim.dt(), f_contact.data());
        }
        v_old = md.v;
        sim.step();
        const double dt = sim.dt();
        for (int d = 0; d < 2 * nn; ++d) {
            const double vbar = 0.5 * (v_old[d] + md.v[d]);
            W_tri += dt * f_tri[d] * vbar, W_joint += dt * f_joint[d] * vbar, W_contact += dt * f_contact[d] * vbar;
        }
    }
    struct Report {
        double tri, joint, contact, total;  // J
    };
    // Mismatches from start() to the state e (take e from energies_now after the last audited step).
    Report mismatch(const fdem::Energies& e) const {
        Report r;
        r.tri = -W_tri - (e.elastic - E_el0);
        r.joint = -W_joint - (e.joint - E_joint0) - (e.fracture - D_frac0);
        r.contact = -W_contact - (e.contact - E_contact0) - (e.friction - D_fric0);
        r.total = e.external - (e.kinetic + e.elastic + e.joint + e.contact + e.damping + e.viscous + e.fracture + e.friction);
        return r;
    }
};

struct DiscResult {
    double peak = 0, peak_time = 0, peak_bottom = 0;  // N, s, N
    double first_abs_y = 1e9;                         // m, |y| of the first broken element(s)
    double balance_before = 0;                        // balance error when the first element broke
    std::vector<Crack> cracks;
    fdem::Energies e;
    EnergyAudit::Report m{};
    int triangles = 0, joints = 0;
    long steps = 0;
    double dt = 0;
};

// The Brazilian disc case (cases/brazilian_disc.*) with overrides, audited every step, run until the load has dropped
// below half its peak and 1 ms (20 transits of the disc) longer.
DiscResult run_disc(const std::string& name, const std::vector<std::string>& overrides) {
    const std::string geo = testing::read_text(cases_dir() / "brazilian_disc.geo");
    const std::string toml = testing::read_text(cases_dir() / "brazilian_disc.toml");
    REQUIRE(!geo.empty());
    auto sim = make_fracture_sim(name, toml, {{"brazilian_disc.geo", geo}}, overrides);
    DiscResult r;
    // Monitors: uy (top arc), P (top reaction, negative in compression), P_bottom.
    sim.begin_stage(0);
    EnergyAudit audit;
    audit.start(sim);
    double t_drop = -1;
    while (!sim.stage_finished()) {
        const bool none_yet = broken_count(sim) == 0;
        audit.step(sim);
        const double P = -sim.monitor_value(1);
        if (P > r.peak) r.peak = P, r.peak_time = sim.time(), r.peak_bottom = sim.monitor_value(2);
        if (none_yet && broken_count(sim) > 0) {
            for (const auto& k : broken_elements(sim)) r.first_abs_y = std::min(r.first_abs_y, std::abs(k.ym()));
            r.balance_before = sim.energies().balance_error();
        }
        if (t_drop < 0 && P < 0.5 * r.peak) t_drop = sim.time();
        if (t_drop > 0 && sim.time() > t_drop + 1e-3) break;
    }
    REQUIRE(t_drop > 0);
    // Contact energy evaluated at the final state, with the audit covering that last step too.
    sim.energy_every_step(true);
    audit.step(sim);
    r.e = sim.energies();
    r.m = audit.mismatch(r.e);
    r.cracks = broken_elements(sim);
    r.triangles = sim.model().n_triangles();
    r.joints = sim.interactions().joints()->size();
    r.steps = sim.steps();
    r.dt = sim.dt();
    return r;
}

void print_disc(const char* label, const DiscResult& r) {
    const double D = 0.1, t = 0.05;
    double xdev = 0, ymin = 1e9, ymax = -1e9;
    for (const auto& c : r.cracks) {
        xdev = std::max({xdev, std::abs(c.x0), std::abs(c.x1)});
        ymin = std::min({ymin, c.y0, c.y1}), ymax = std::max({ymax, c.y0, c.y1});
    }
    std::printf("disc %s: %d triangles, %d cohesive, dt=%.4g s, %ld steps; peak P=%.5g N at t=%.4g s (2P/(pi D t)=%.4g Pa, "
                "P_bottom/P=%.4f); %zu broken, first at |y|=%.4g m, max |x|=%.4g m, y in [%.4g, %.4g] m; D_frac=%.4g J, "
                "D_fric=%.4g J, D_damp=%.4g J, W_ext=%.4g J; balance error %.3g at the first break, %.3g at the end; "
                "class mismatches (J): triangles %.3g, joints %.3g, contact %.3g (sum of all %.3g)\n",
                label, r.triangles, r.joints, r.dt, r.steps, r.peak, r.peak_time, 2 * r.peak / (M_PI * D * t),
                r.peak_bottom / r.peak, r.cracks.size(), r.first_abs_y, xdev, ymin, ymax, r.e.fracture, r.e.friction,
                r.e.damping, r.e.external, r.balance_before, r.e.balance_error(), r.m.tri, r.m.joint, r.m.contact,
                r.m.total);
}

}  // namespace

// ---------------------------------------------------------------------------------------------------------------
// 2. Brazilian disc (cases/README.md §C), every edge crackable, squeezed through 12-degree arcs: the tensile stress across
//    the loaded diameter is nearly uniform (2 P / (pi D t)) over its central part and the stress near the arcs is
//    compressive, so the crack starts near the centre and runs along the loaded diameter.
// ---------------------------------------------------------------------------------------------------------------
TEST_CASE("engine Brazilian disc with every edge crackable splits along the loaded diameter", "[engine][regression]") {
    const DiscResult r = run_disc("fracture_engine_disc", {});
    print_disc("phi=35", r);
    const double D = 0.1, lc = 0.0075;  // m: diameter, mesh size of the .geo
    double xdev = 0, ymin = 1e9, ymax = -1e9;
    for (const auto& c : r.cracks) {
        xdev = std::max({xdev, std::abs(c.x0), std::abs(c.x1)});
        ymin = std::min({ymin, c.y0, c.y1}), ymax = std::max({ymax, c.y0, c.y1});
    }
    // Unstructured mesh: the crack follows edges, which lie up to about one element size off the diameter.
    CHECK(xdev < 1.5 * lc);
    // It spans most of the diameter (the wedges under the arcs stay whole): D / lc = 13 elements; at least 10 broken
    // and their extent along the diameter at least 80 % of D.
    CHECK(r.cracks.size() >= 10);
    CHECK(ymax - ymin > 0.8 * D);
    // It starts in the central part of the diameter, not at the arcs.
    CHECK(r.first_abs_y < D / 4);

    // 4. Energy balance after cracking. The audit splits the residual by force class: triangles O(dt^2) and contact
    //    (a few hundred crack-face pairs) are small; the residual is the joints', i.e. the bookkeeping of the cohesive
    //    law (the Mohr-Coulomb shear strength c + max(0, -sigma) tan(phi) makes the stored shear energy depend on the
    //    normal stress, which does no shear work: fracture/law.hpp says so). The test below shows it vanishes with
    //    phi = 0. Bounds: triangles and contact 1e-4 and 5e-4 of W_ext (measured 1.3e-5, 1e-4), the total 4 %
    //    (measured 2.5 %: the number to beat when the law's books are fixed).
    // The class mismatches add up to the engine's residual (up to the engine's joint energy being that of the last
    // force evaluation, one step behind the triangles'; measured 6e-6 of W_ext).
    CHECK(std::abs(r.m.total - (r.m.tri + r.m.joint + r.m.contact)) < 1e-4 * r.e.external);
    CHECK(std::abs(r.m.tri) < 1e-4 * r.e.external);
    CHECK(std::abs(r.m.contact) < 5e-4 * r.e.external);
    CHECK(r.e.balance_error() < 0.04);
}

TEST_CASE("engine Brazilian disc with a frictionless cohesive law: the energy books close after cracking",
          "[engine][regression]") {
    // Same disc, phi = 0 in the cohesive law (f_s = c whatever the normal stress: the law is then a potential up to
    // its damage). If the 2.5 % of the test above were contact, damping or engine bookkeeping it would remain here.
    const DiscResult r = run_disc("fracture_engine_disc_phi0", {"materials.stone.fracture.friction=0"});
    print_disc("phi=0", r);
    REQUIRE(r.cracks.size() >= 10);  // it did crack (the balance is checked after cracking)
    CHECK(std::abs(r.m.tri) < 1e-4 * r.e.external);
    CHECK(std::abs(r.m.contact) < 5e-4 * r.e.external);
    CHECK(r.e.balance_error() < 0.003);  // measured 0.12 %
}

// ---------------------------------------------------------------------------------------------------------------
// 3. Mode II through the engine (cases/mode2_shear.*): a bonded interface under a constant compression sigma,
//    the upper block dragged sideways as a rigid body. Peak shear stress c + sigma tan(phi) (the joint law's
//    Mohr-Coulomb strength, [K25]), then, after the joints have broken and contact holds the faces, Coulomb sliding
//    at sigma tan(phi_res) (the engine hands the faces over with the residual friction of the bond).
// ---------------------------------------------------------------------------------------------------------------
TEST_CASE("engine mode II: bonded interface under compression peaks at c + sigma tan(phi), then slides at sigma tan(phi_res)",
          "[engine][regression]") {
    const std::string geo = testing::read_text(cases_dir() / "mode2_shear.geo");
    const std::string toml = testing::read_text(cases_dir() / "mode2_shear.toml");
    REQUIRE(!geo.empty());
    auto sim = make_fracture_sim("fracture_engine_mode2", toml, {{"mode2_shear.geo", geo}});
    const double L = 0.1, t = 0.1, A = L * t;                // m, m, m^2 (joint area)
    const double sigma = 1.0e6, c = 0.4e6, k_n = 1.0e11;     // Pa, Pa, Pa/m
    const double GII = 50.0;                                  // J/m^2
    const double phi = 35.0 * M_PI / 180, phi_res = 30.0 * M_PI / 180;
    const double peak_expected = c + sigma * std::tan(phi), residual_expected = sigma * std::tan(phi_res);  // Pa
    // Monitors: ux (upper block), R (x reactions on the upper block = interface shear force, N), N (load on top, N).
    sim.begin_stage(0);
    while (!sim.stage_finished()) sim.step();
    const double N0 = -sim.monitor_value(2);
    REQUIRE(N0 == Approx(sigma * A).epsilon(1e-9));
    sim.begin_stage(1);
    EnergyAudit audit;
    audit.start(sim);
    double peak = 0, peak_time = 0, t_broken = -1;
    double slide_sum = 0, contact_ratio_min = 1e9, contact_ratio_max = -1e9;
    long slide_n = 0;
    const auto* cs = sim.interactions().contact();
    REQUIRE(cs != nullptr);
    // Upper-block nodes (of triangles above y = 0), for the contact force on it.
    std::vector<char> upper(sim.model().n_nodes(), 0);
    for (const auto& tr : sim.model().tris) {
        double cy = 0;
        for (int q = 0; q < 3; ++q) cy += sim.model().X[2 * tr.n[q] + 1];
        if (cy > 0)
            for (int q = 0; q < 3; ++q) upper[tr.n[q]] = 1;
    }
    while (!sim.stage_finished()) {
        audit.step(sim);
        const double tau = sim.monitor_value(1) / A;
        if (tau > peak) peak = tau, peak_time = sim.time();
        if (t_broken < 0 && broken_count(sim) == sim.interactions().joints()->size()) t_broken = sim.time();
        // Sliding: from 1 ms after the last joint broke (the faces have settled on contact) to the end.
        if (t_broken > 0 && sim.time() > t_broken + 1e-3) {
            slide_sum += tau, ++slide_n;
            if (slide_n % 500 == 1) {  // the contact force itself: friction / normal on the upper block
                fdem::contact::ContactSystem copy = *sim.interactions().contact();
                std::vector<double> fc(sim.model().x.size(), 0.0);
                copy.step(sim.model().x.data(), sim.model().v.data(), sim.dt(), fc.data());
                double fx = 0, fy = 0;
                for (std::size_t k = 0; k < upper.size(); ++k)
                    if (upper[k]) fx += fc[2 * k], fy += fc[2 * k + 1];
                contact_ratio_min = std::min(contact_ratio_min, -fx / fy);
                contact_ratio_max = std::max(contact_ratio_max, -fx / fy);
            }
        }
    }
    sim.energy_every_step(true);
    audit.step(sim);
    const fdem::Energies e = sim.energies();
    const auto m = audit.mismatch(e);
    const double residual = slide_n ? slide_sum / slide_n : 0.0;
    const auto* counts = sim.interactions().counts();
    const double compressive = 0.5 * sigma * sigma / k_n * A;  // J, joint energy at sigma: handed to contact
    std::printf("mode II: N=%.6g N; peak tau=%.6g Pa at t=%.4g s (expected %.6g, ratio %.5f); all %d joints broken at "
                "t=%.4g s (mode II: %lld); mean sliding tau=%.6g Pa over %ld steps (expected %.6g, ratio %.5f); contact "
                "friction/normal %.5f..%.5f (tan phi_res %.5f); D_frac=%.5g J (G_II A + sigma^2 A / (2 k_n) = %.5g J), "
                "D_fric=%.4g J, E_contact=%.4g J; balance error %.3g; class mismatches (J): triangles %.3g, joints %.3g, "
                "contact %.3g\n",
                N0, peak, peak_time, peak_expected, peak / peak_expected, sim.interactions().joints()->size(), t_broken,
                counts->of(fdem::fracture::JointClass::interface, fdem::fracture::FractureMode::mode_II), residual, slide_n,
                residual_expected, residual / residual_expected, contact_ratio_min, contact_ratio_max, std::tan(phi_res),
                e.fracture, GII * A + compressive, e.friction, e.contact, e.balance_error(), m.tri, m.joint, m.contact);
    // Peak: the joint law reaches f_s = c + sigma tan(phi) at s_p exactly and the slip is uniform along the joint
    // (the 2 mm strips lag by tau s / G = 0.5 um of 22 um, the same at every element): 1 %.
    CHECK(peak / peak_expected == Approx(1.0).epsilon(0.01));
    REQUIRE(t_broken > 0);
    CHECK(counts->of(fdem::fracture::JointClass::interface, fdem::fracture::FractureMode::mode_II) == 10);
    // The law dissipates G_II per unit area at constant compression, plus the compressive energy it still holds when
    // it is removed (booked as dissipation, see below): 0.5 %.
    CHECK(e.fracture / (GII * A + compressive) == Approx(1.0).epsilon(0.005));
    // Residual: contact is Coulomb per pair; measured on a copy, the crack faces' force ratio is 1.005 tan(phi_res)
    // (the potential normal force gets an x component where the upper block overhangs the lower one at the ends),
    // and the reaction wobbles by ~1 % as the free interface nodes slide; averaged over the sliding: 1.5 %.
    CHECK(residual / residual_expected == Approx(1.0).epsilon(0.015));
    CHECK(contact_ratio_min / std::tan(phi_res) == Approx(1.0).epsilon(0.01));
    CHECK(contact_ratio_max / std::tan(phi_res) == Approx(1.0).epsilon(0.01));
    // Energy: the joints' own books close (constant compression: no Mohr-Coulomb coupling) and so do the triangles';
    // the contact class is short by the compressive energy the broken joints held: the joint books it as fracture
    // dissipation when it is removed, and contact, which finds the same overlap, stores it again without any work.
    CHECK(std::abs(m.tri) < 1e-3 * e.external);
    CHECK(std::abs(m.joint) < 1e-3 * e.external);
    CHECK(m.contact / -compressive == Approx(1.0).epsilon(0.05));  // measured 0.99
    // So the engine's balance error (5.2 % here) is that hand-over: without it the books close to 1e-3 of W_ext.
    CHECK(std::abs(m.total + compressive) < 1e-3 * e.external);
    CHECK(e.balance_error() < 0.06);
}

// ---------------------------------------------------------------------------------------------------------------
// 4. The same joint with shear_softening = "cohesion" (fracture/law.hpp, [LR97]): only the cohesion softens, so
//    between the peak and the breaking of the joints the interface still carries sigma tan(phi) instead of falling
//    to zero; the slider's work is booked as friction and the books still close.
// ---------------------------------------------------------------------------------------------------------------
TEST_CASE("engine mode II with shear_softening = cohesion: the softening ends on sigma tan(phi), not on zero",
          "[engine][regression]") {
    const std::string geo = testing::read_text(cases_dir() / "mode2_shear.geo");
    const std::string toml = testing::read_text(cases_dir() / "mode2_shear.toml");
    REQUIRE(!geo.empty());
    const double A = 0.1 * 0.1, sigma = 1.0e6, c = 0.4e6, k_n = 1.0e11;  // m^2, Pa, Pa, Pa/m
    const double phi = 35.0 * M_PI / 180, phi_res = 30.0 * M_PI / 180;
    struct Run {
        double peak = 0, low_after_peak = 1e30, t_broken = -1, slider = 0;
        double dip = 1e30, slide_sum = 0;  // lowest tau after the first break; sum of tau 1 ms after the last
        long slide_n = 0;
        fdem::Energies e;
        EnergyAudit::Report m{};
    };
    auto run = [&](const std::string& mode) {
        auto sim = make_fracture_sim("fracture_engine_mode2_" + mode, toml, {{"mode2_shear.geo", geo}},
                                     {"interfaces.1.shear_softening=\"" + mode + "\"",
                                      // 0.4 mm of slip: the cohesion's range s_t = (G_II - (2/3) c s_p) / (kappa c)
                                      // is 0.29 mm past s_p = 22 um
                                      "stages.2.duration=0.04"});
        Run r;
        sim.begin_stage(0);
        while (!sim.stage_finished()) sim.step();
        sim.begin_stage(1);
        EnergyAudit audit;
        audit.start(sim);
        bool past_peak = false;
        while (!sim.stage_finished()) {
            audit.step(sim);
            const double tau = sim.monitor_value(1) / A;
            if (tau > r.peak) r.peak = tau;
            past_peak = past_peak || tau < 0.99 * r.peak;
            const int broken = broken_count(sim);
            if (r.t_broken < 0 && broken == sim.interactions().joints()->size()) r.t_broken = sim.time();
            if (past_peak && broken == 0) r.low_after_peak = std::min(r.low_after_peak, tau);  // softening, intact
            if (broken > 0) r.dip = std::min(r.dip, tau);
            if (r.t_broken > 0 && sim.time() > r.t_broken + 1e-3) r.slide_sum += tau, ++r.slide_n;
        }
        sim.energy_every_step(true);
        audit.step(sim);
        r.e = sim.energies();
        r.m = audit.mismatch(r.e);
        r.slider = sim.interactions().joints()->friction_energy();
        std::printf("mode II, shear_softening=%s: peak %.6g Pa, lowest tau before the first joint broke %.6g Pa "
                    "(sigma tan(phi) %.6g), all broken at %.4g s, lowest tau after the first break %.6g Pa, mean "
                    "sliding tau %.6g Pa; D_frac %.5g J, D_fric %.5g J (sliders %.5g J), "
                    "balance %.3g; mismatches (J) joints %.3g, contact %.3g, total %.3g\n",
                    mode.c_str(), r.peak, r.low_after_peak, sigma * std::tan(phi), r.t_broken, r.dip,
                    r.slide_n ? r.slide_sum / r.slide_n : 0.0, r.e.fracture,
                    r.e.friction, r.slider, r.e.balance_error(), r.m.joint, r.m.contact, r.m.total);
        return r;
    };
    const Run k = run("strength"), h = run("cohesion");
    REQUIRE(k.t_broken > 0);
    REQUIRE(h.t_broken > 0);
    // The same peak c + sigma tan(phi): the pre-peak curve is unchanged (1 %, as in the test above).
    CHECK(h.peak / (c + sigma * std::tan(phi)) == Approx(1.0).epsilon(0.01));
    // (The reaction peaks just past s_p, where the two laws part at first order in D: 1e-3.)
    CHECK(h.peak / k.peak == Approx(1.0).epsilon(1e-3));
    // [K25] softening: the interface sheds its whole strength before the first joint breaks (below a tenth of it);
    // cohesion softening keeps f_f + z(D) c >= sigma tan(phi) (2 % for the reaction's wobble).
    CHECK(k.low_after_peak < 0.1 * sigma * std::tan(phi));
    CHECK(h.low_after_peak / (sigma * std::tan(phi)) > 0.98);
    // Then both hand the faces to contact, which starts with no tangential history: the reaction dips while its
    // springs stretch (printed above, 11 % of sigma tan(phi) at its lowest; not asserted: a known limit), and both
    // slide on the same contact at sigma tan(phi_res) (measured 1.016 and 1.020 x over this longer slide: the overhang
    // of the test above grows with the slip), within 1 % of each other.
    REQUIRE(h.slide_n > 0);
    REQUIRE(k.slide_n > 0);
    CHECK((h.slide_sum / h.slide_n) / (k.slide_sum / k.slide_n) == Approx(1.0).epsilon(0.01));
    CHECK(h.slide_sum / h.slide_n / (sigma * std::tan(phi_res)) == Approx(1.0).epsilon(0.025));
    // The sliders did work, booked as friction: the joints' own books close once it is counted with them, the
    // contact's once it is taken out (short by the compressive energy handed over, as in the test above).
    const double compressive = 0.5 * sigma * sigma / k_n * A;  // J
    CHECK(h.slider > 0.0);
    CHECK(std::abs(h.m.joint - h.slider) < 1e-3 * h.e.external);
    CHECK((h.m.contact + h.slider) / -compressive == Approx(1.0).epsilon(0.05));
    CHECK(std::abs(h.m.total + compressive) < 1e-3 * h.e.external);
    CHECK(k.slider == 0.0);
}

// ---------------------------------------------------------------------------------------------------------------
// 4b. The compressive cap (compressive_strength, fracture/law.hpp) through the engine, on the same joint pressed by
//     1 MPa: a cap above the pressure changes no bit; a cap of 0.5 MPa lets the joint close plastically (the upper
//     block sinks into the lower one, no damage) and books f_c A |plastic closure| as fracture dissipation.
// ---------------------------------------------------------------------------------------------------------------
TEST_CASE("engine compressive cap: none reached changes nothing, reached the joint crushes at f_c and books f_c A |o_c|",
          "[engine][regression]") {
    const std::string geo = testing::read_text(cases_dir() / "mode2_shear.geo");
    const std::string toml = testing::read_text(cases_dir() / "mode2_shear.toml");
    REQUIRE(!geo.empty());
    const double A = 0.1 * 0.1, k_n = 1.0e11, f_c = 0.5e6;  // m^2, Pa/m, Pa
    auto press = [&](const std::string& tag, const std::vector<std::string>& overrides) {
        auto sim = make_fracture_sim("fracture_engine_cap_" + tag, toml, {{"mode2_shear.geo", geo}}, overrides);
        sim.begin_stage(0);
        EnergyAudit audit;
        audit.start(sim);
        while (!sim.stage_finished()) audit.step(sim);  // (audit.step advances the simulation by one step)
        sim.energy_every_step(true);
        audit.step(sim);
        const auto& m = sim.model();
        // Mean vertical displacement of the interface nodes (reference y = 0) of each block: the joint's closure.
        double up = 0, lo = 0;
        int nu = 0, nl = 0;
        std::vector<char> side(m.n_nodes(), 0);
        for (const auto& tr : m.tris) {
            double cy = 0;
            for (int q = 0; q < 3; ++q) cy += m.X[2 * tr.n[q] + 1];
            for (int q = 0; q < 3; ++q) side[tr.n[q]] = cy > 0 ? 1 : 2;
        }
        for (int k = 0; k < m.n_nodes(); ++k) {
            if (std::abs(m.X[2 * k + 1]) > 1e-12) continue;
            const double uy = m.x[2 * k + 1] - m.X[2 * k + 1];
            if (side[k] == 1) up += uy, ++nu;
            if (side[k] == 2) lo += uy, ++nl;
        }
        REQUIRE(nu > 0);
        REQUIRE(nl > 0);
        struct Out {
            std::vector<double> x;
            fdem::Energies e;
            EnergyAudit::Report m;
            double closure;
            long long broken;
            double crushed_volume;  // m^3: sum over elements of length x thickness x plastic closure
            bool cap;
        };
        const fdem::Energies e = sim.energies();
        const auto* j = sim.interactions().joints();
        double vol = 0;
        for (int k = 0; k < j->size(); ++k) vol += j->length(k) * 0.1 * j->crushing(k);
        return Out{sim.model().x, e, audit.mismatch(e), up / nu - lo / nl, broken_count(sim), vol, j->has_cap()};
    };
    const auto none = press("none", {});
    const auto high = press("high", {"interfaces.1.compressive_strength=2.0e6"});
    const auto low = press("low", {"interfaces.1.compressive_strength=" + std::to_string(f_c)});
    // Not reached (the joint carries 1 MPa): every position is the same bit.
    CHECK(high.x == none.x);
    CHECK(high.e.fracture == 0.0);
    // Reached: the joint closes far past its elastic closure f_c / k_n (5 um) and dissipates f_c A per metre of
    // plastic closure; it is not damaged by it. The pressure keeps pushing (perfectly plastic: no hardening), so
    // the upper block is still sinking at the end of the stage; what is checked is the bookkeeping along the way.
    const double plastic = -low.closure - f_c / k_n;  // m, mean plastic closure
    std::printf("cap: closure none %.4g um, cap 2 MPa %.4g um, cap 0.5 MPa %.4g um; D_frac %.6g J against f_c A |o_c| "
                "%.6g J; balance %.3g; mismatches (J): joints %.3g, triangles %.3g, contact %.3g; E_contact %.4g J "
                "(no cap: %.3g J); W_ext %.4g J, D_damp %.4g J\n",
                -none.closure * 1e6, -high.closure * 1e6, -low.closure * 1e6, low.e.fracture, f_c * A * plastic,
                low.e.balance_error(), low.m.joint, low.m.tri, low.m.contact, low.e.contact, none.e.contact,
                low.e.external, low.e.damping);
    CHECK(-none.closure == Approx(1.0e6 / k_n).epsilon(0.02));  // 10 um: the elastic closure sigma / k_n
    CHECK(plastic > 10.0 * f_c / k_n);
    CHECK(low.broken == 0);
    // The law books f_c |d o_c| per unit area at each point: with a monotonic closure that is f_c times the crushed
    // volume (CohesiveSystem::crushing, the points' Simpson mean) to rounding; against the mean closure of the
    // interface nodes, 2 % (measured 1.06 % over: the closure is not quite uniform, see the contact below).
    CHECK(!none.cap);
    CHECK(low.cap);
    CHECK(none.crushed_volume == 0.0);
    CHECK(low.e.fracture / (f_c * low.crushed_volume) == Approx(1.0).epsilon(1e-9));
    CHECK(low.e.fracture / (f_c * A * plastic) == Approx(1.0).epsilon(0.02));
    // The joints' own books close: their work = stored energy + crushing.
    CHECK(std::abs(low.m.joint) < 1e-3 * low.e.external);
    // Known limit (fracture/README.md): the blocks now overlap by 0.3 mm, and pairs of triangles of the two blocks
    // that meet only at a corner of the joint (no cohesive element between them) are contact pairs, so contact
    // carries part of the load across a crushed joint (E_contact 0.76 J here against 3e-5 J without the cap) and its
    // slight non-conservation is the balance error (0.56 %, all of it the contact class's mismatch).
    CHECK(none.e.contact < 1e-3 * none.e.joint);
    CHECK(low.e.contact > 0.1 * low.e.external);
    CHECK(std::abs(low.m.total - low.m.contact) < 1e-3 * low.e.external);
}

// Known limit of the cap, checked so that it stays reported: the same joint crushed by a prescribed closure of the
// upper block (0.01 m/s for 4 ms against f_c = 0.2 MPa) and then sheared until it breaks. The broken elements hand
// their overlap, plastic closure included, to contact, which pushes the blocks apart with energy nobody put in; the
// engine's energy guard stops the run (exit code 2) and its message names the crushed, broken elements.
TEST_CASE("engine compressive cap: joints that break while crushed are named when the energy guard stops the run",
          "[engine][regression]") {
    const std::string toml = replace_once(testing::read_text(cases_dir() / "mode2_shear.toml"),
                                          "  fix = \"x\"\n  [[stages.loads]]\n  group = \"upper_top\"\n"
                                          "  pressure = 1.0e6       # Pa\n  ramp = 0.001           # s",
                                          "  fix = \"x\"\n  vy = -0.01\n  ramp = 0.0002");
    const auto dir = testing::tmp_dir("fracture_engine_cap_crushed_break");
    testing::write_text(dir / "mode2_shear.geo", testing::read_text(cases_dir() / "mode2_shear.geo"));
    testing::write_text(dir / "case.toml", toml);
    const auto r = testing::run_fdem("run \"" + (dir / "case.toml").string() + "\" --out \"" + (dir / "run").string() +
                                         "\" --quiet --threads 1 --set interfaces.1.compressive_strength=2e5"
                                         " --set stages.2.duration=0.1",
                                     dir);
    INFO(r.out << r.err);
    CHECK(r.code == 2);
    CHECK(r.err.find("energy grew without work") != std::string::npos);
    CHECK(r.err.find("broke while crushed") != std::string::npos);
}

// ---------------------------------------------------------------------------------------------------------------
// 5. The run folder through the command line: history.csv has the broken_* columns, cracks.csv one row per broken
//    element, the same elements as the same case run in-process.
// ---------------------------------------------------------------------------------------------------------------
TEST_CASE("engine fdem run with fracture writes broken_* history columns and one cracks.csv row per broken element",
          "[engine][regression]") {
    const std::string geo = replace_once(testing::read_text(cases_dir() / "bar_structured.geo"), "nx = 16; ny = 8;", "nx = 4; ny = 2;");
    const std::string toml = testing::read_text(cases_dir() / "bar_structured.toml");
    const std::vector<std::string> overrides = {"stages.1.duration=0.012"};  // the bar separates at 0.0102 s
    // In-process reference.
    auto sim = make_fracture_sim("fracture_engine_cli_ref", toml, {{"bar_structured.geo", geo}}, overrides);
    sim.run();
    std::vector<int> expected;
    for (const auto& c : broken_elements(sim)) expected.push_back(c.element);
    REQUIRE(expected.size() == 2);

    const auto dir = testing::tmp_dir("fracture_engine_cli");
    testing::write_text(dir / "bar_structured.geo", geo);
    testing::write_text(dir / "case.toml", toml);
    const auto out = dir / "run";
    const auto r = testing::run_fdem("run \"" + (dir / "case.toml").string() + "\" --out \"" + out.string() +
                                         "\" --quiet --threads 1 --set stages.1.duration=0.012",
                                     dir);
    INFO(r.out << r.err);
    REQUIRE(r.code == 0);
    auto lines_of = [](const std::string& text) {
        std::vector<std::string> lines;
        std::stringstream ss(text);
        for (std::string l; std::getline(ss, l);)
            if (!l.empty()) lines.push_back(l);
        return lines;
    };
    auto split = [](const std::string& line) {
        std::vector<std::string> cells;
        std::stringstream ss(line);
        for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
        return cells;
    };
    const auto history = lines_of(testing::read_text(out / "history.csv"));
    REQUIRE(history.size() > 2);
    const auto header = split(history.front());
    const std::vector<std::string> cols = {"broken_unit_I", "broken_unit_II", "broken_unit_mixed",
                                           "broken_interface_I", "broken_interface_II", "broken_interface_mixed"};
    std::vector<long> last(cols.size(), -1), first(cols.size(), -1);
    const auto row0 = split(history[1]), rowN = split(history.back());
    for (std::size_t i = 0; i < cols.size(); ++i) {
        const auto it = std::find(header.begin(), header.end(), cols[i]);
        REQUIRE(it != header.end());
        const std::size_t k = static_cast<std::size_t>(it - header.begin());
        REQUIRE(rowN.size() == header.size());
        first[i] = std::stol(row0[k]), last[i] = std::stol(rowN[k]);
    }
    CHECK(first == std::vector<long>(cols.size(), 0));
    CHECK(last == std::vector<long>({2, 0, 0, 0, 0, 0}));  // the two elements of the crack, mode I, unit interior

    const auto cracks = lines_of(testing::read_text(out / "cracks.csv"));
    REQUIRE(cracks.size() == 1 + expected.size());
    const auto ch = split(cracks.front());
    auto col = [&](const std::string& name) {
        const auto it = std::find(ch.begin(), ch.end(), name);
        REQUIRE(it != ch.end());
        return static_cast<std::size_t>(it - ch.begin());
    };
    const std::size_t c_el = col("element"), c_class = col("class"), c_mode = col("mode"), c_len = col("length_m"),
                      c_x = col("x_ref_m");
    std::vector<int> got;
    for (std::size_t i = 1; i < cracks.size(); ++i) {
        const auto row = split(cracks[i]);
        REQUIRE(row.size() == ch.size());
        got.push_back(std::stoi(row[c_el]));
        CHECK(row[c_class] == "unit-interior");
        CHECK(row[c_mode] == "I");
        CHECK(std::stod(row[c_len]) == Approx(0.05).epsilon(1e-9));
        CHECK(std::stod(row[c_x]) == Approx(std::stod(split(cracks[1])[c_x])).epsilon(1e-12));
    }
    std::sort(got.begin(), got.end());
    std::sort(expected.begin(), expected.end());
    CHECK(got == expected);

    // The same run with a compressive cap nothing reaches (1 GPa): the same history bit for bit, and its snapshots
    // carry the joint_crushing array (zero everywhere) that the run without a cap does not write.
    const auto out2 = dir / "run_cap";
    const auto r2 = testing::run_fdem("run \"" + (dir / "case.toml").string() + "\" --out \"" + out2.string() +
                                          "\" --quiet --threads 1 --set stages.1.duration=0.012"
                                          " --set materials.stone.fracture.compressive_strength=1e9",
                                      dir);
    INFO(r2.out << r2.err);
    REQUIRE(r2.code == 0);
    CHECK(testing::read_text(out2 / "history.csv") == testing::read_text(out / "history.csv"));
    auto last_snapshot = [](const std::filesystem::path& run) {
        std::string newest;
        for (const auto& f : std::filesystem::directory_iterator(run / "snapshots"))
            if (f.path().string() > newest) newest = f.path().string();
        return testing::read_text(newest);
    };
    CHECK(last_snapshot(out2).find("Name=\"joint_crushing\"") != std::string::npos);
    CHECK(last_snapshot(out).find("joint_crushing") == std::string::npos);
}

// ---------------------------------------------------------------------------------------------------------------
// 6. Bonded joints in a running-bond assembly (cases/vermeltfoort/checks/joint_panel_121.toml): a squat panel of the
//    1.21 MPa Vermeltfoort walls' bricks and joints under N = 239.6 kN held constant, sheared 2 mm. It slides along
//    whole bed joints, so statics brackets its peak by mu V (friction alone) and c A + mu V (every point at its
//    Coulomb strength at once), and once the sliding joint has broken its load is contact's Coulomb friction mu V.
// ---------------------------------------------------------------------------------------------------------------
TEST_CASE("engine running-bond panel: peak between mu V and c A + mu V, then slides at mu V", "[engine][regression]") {
    const auto dir = testing::tmp_dir("fracture_engine_joint_panel");
    const auto r = testing::run_fdem(std::string("run \"") + FDEM_CASES_DIR + "/vermeltfoort/checks/joint_panel_121.toml\" --out \"" +
                                         (dir / "run").string() + "\" --quiet --threads 2",
                                     dir);
    INFO(r.out << r.err);
    REQUIRE(r.code == 0);
    std::istringstream in(testing::read_text(dir / "run" / "history.csv"));
    std::string line;
    REQUIRE(std::getline(in, line));
    std::vector<std::string> head;
    {
        std::stringstream ss(line);
        for (std::string c; std::getline(ss, c, ',');) head.push_back(c);
    }
    auto col = [&](const std::string& name) {
        const auto it = std::find(head.begin(), head.end(), name);
        REQUIRE(it != head.end());
        return static_cast<std::size_t>(it - head.begin());
    };
    const std::size_t c_stage = col("stage"), c_u = col("u_top"), c_H = col("H"), c_V = col("V_base");
    double peak = 0, V_at_peak = 0, H_end = 0, V_end = 0, u_end = 0;
    while (std::getline(in, line)) {
        std::vector<double> v;
        std::stringstream ss(line);
        for (std::string c; std::getline(ss, c, ',');) v.push_back(std::stod(c));
        if (v[c_stage] != 2) continue;
        if (v[c_H] > peak) peak = v[c_H], V_at_peak = v[c_V];
        H_end = v[c_H], V_end = v[c_V], u_end = v[c_u];
    }
    const double mu = std::tan(35.0 * M_PI / 180), cA = 0.224e6 * 1.98 * 0.1;  // -, N (c x joint area)
    std::printf("joint panel: peak %.6g N with V %.6g N (mu V %.6g, c A + mu V %.6g); at u = %.4g mm H %.6g N against "
                "mu V %.6g N (ratio %.4f)\n",
                peak, V_at_peak, mu * V_at_peak, cA + mu * V_at_peak, u_end * 1e3, H_end, mu * V_end, H_end / (mu * V_end));
    REQUIRE(u_end == Approx(0.002).epsilon(1e-3));
    CHECK(peak > mu * V_at_peak);
    CHECK(peak < cA + mu * V_at_peak);
    // Sliding on contact, Coulomb per pair; the reaction wobbles by about 1 % as nodes pass (the mode II test): 2 %.
    CHECK(H_end / (mu * V_end) == Approx(1.0).epsilon(0.02));
}
