// tests/fracture/test_extrinsic.cpp: extrinsic insertion of cohesive elements (insertion = "extrinsic",
// fracture/cohesive_system.hpp, fracture/README.md "Extrinsic insertion"; issue 25, lever 2).
//
// One element (test_grid.hpp OneElement: side A edge (0,0)-(h,0), side B the same edge, n = (0,-1), t = (1,0)):
// dormant it carries nothing; inserted at the continuum's traction (sigma, tau) it carries exactly that traction at zero
// separation, and the energy it dissipates until it breaks is G_I (mode I) or G_II (mode II, plus the compressive
// energy it still holds when removed, as for the intrinsic law) whatever the traction at insertion.
// Through the engine: a bar pulled apart (one crack, f_t A, G_I A), a cantilever whose crackable material has the
// stiffness of the continuum while nothing cracks, and a restart after insertions.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/engine_helpers.hpp"
#include "fdem/scene.hpp"
#include "fracture/cohesive_system.hpp"
#include "test_grid.hpp"

using namespace fdem::fracture;
using fracture_test::OneElement;

namespace {

CohesiveProps stone_extrinsic(double penalty) {
  CohesiveProps p = fracture_test::sandstone(penalty);
  p.extrinsic = true;
  return p;
}

}  // namespace

TEST_CASE("extrinsic element: no force while dormant, the continuum's traction at insertion, G_I dissipated in mode I",
          "[unit]") {
  const double h = 0.025, t = 0.2, f_t = 3.7e6, G_I = 110.0;
  for (double p_j : {1e10, 4e11}) {
    for (double ratio : {1.0, 0.6}) {  // inserted at the peak, or below it (a shear-driven insertion's normal part)
      CAPTURE(p_j, ratio);
      OneElement el(stone_extrinsic(p_j), h, t);
      REQUIRE(el.sys.dormant_count() == 1);
      REQUIRE(el.sys.intact_count() == 0);
      el.move(1e-6, 0.0);  // a dormant element ignores any separation
      CHECK(el.sigma == 0.0);
      CHECK(el.tau == 0.0);
      CHECK(el.sys.reaches_strength(0, f_t, 0.0));
      CHECK_FALSE(el.sys.reaches_strength(0, 0.99 * f_t, 0.0));
      el.move(0.0, 0.0);
      el.work = 0.0;
      el.sys.insert({{0, ratio * f_t, 0.0}});
      CHECK(el.sys.dormant_count() == 0);
      CHECK(el.sys.intact_count() == 1);
      el.move(0.0, 0.0);
      CHECK(el.sigma == Approx(ratio * f_t).epsilon(1e-12));
      CHECK(el.tau == Approx(0.0).margin(1e-6));
      // The pre-peak energy the element holds at insertion, E_0(o_0) = (x^2 - x^3/3) f_t o_p with 2 x - x^2 = ratio.
      const JointLaw& L = el.sys.law(0);
      const double x = 1.0 - std::sqrt(1.0 - ratio);
      const double born = (x * x - x * x * x / 3.0) * f_t * L.opening_peak;  // J/m^2
      CHECK(el.sys.inserted_energy() / (h * t) == Approx(born).epsilon(1e-12));
      const double o_end = 1.05 * (L.opening_peak + L.opening_range);
      const int n = 20000;
      for (int i = 1; i <= n; ++i) el.move(o_end * i / n, 0.0);
      REQUIRE(el.breaks.size() == 1);
      CHECK(el.breaks[0].mode == FractureMode::mode_I);
      // Work after insertion plus the energy it started with = G_I; the module's books say the same.
      CHECK(el.work + born == Approx(G_I).epsilon(1e-3));
      CHECK(el.dissipated() == Approx(G_I).epsilon(1e-6));
    }
  }
}

TEST_CASE("extrinsic element in mode II under compression: inserted at c + sigma tan(phi), G_II dissipated", "[unit]") {
  const double h = 0.025, t = 0.2, p_j = 1e10, G_II = 770.0;
  const double sigma = -2.0e6;  // Pa, held: the geometric opening stays 0, the offset keeps the compression
  OneElement el(stone_extrinsic(p_j), h, t);
  const JointLaw& L = el.sys.law(0);
  const double f_s = L.cohesion - sigma * L.tan_friction;
  CHECK(el.sys.reaches_strength(0, sigma, -f_s));
  CHECK_FALSE(el.sys.reaches_strength(0, sigma, 0.99 * f_s));
  el.sys.insert({{0, sigma, f_s}});
  el.move(0.0, 0.0);
  CHECK(el.sigma == Approx(sigma).epsilon(1e-12));
  CHECK(el.tau == Approx(f_s).epsilon(1e-12));
  const double s_p = 2.0 * f_s / L.shear_stiffness;
  const double born = (2.0 / 3.0) * f_s * s_p + 0.5 * sigma * sigma / L.normal_stiffness;  // J/m^2: at the peak
  CHECK(el.sys.inserted_energy() / (h * t) == Approx(born).epsilon(1e-12));
  const double s_end = 1.05 * (s_p + shear_softening_range(L, f_s, s_p));
  const int n = 20000;
  double peak = 0.0;
  for (int i = 1; i <= n; ++i) {
    el.move(0.0, s_end * i / n);
    peak = std::max(peak, el.tau);
  }
  REQUIRE(el.breaks.size() == 1);
  CHECK(el.breaks[0].mode == FractureMode::mode_II);
  CHECK(peak <= f_s * (1.0 + 1e-12));  // never above the strength it was inserted at
  // The softening from the peak releases G_II; the compressive energy still held leaves with the element (booked as
  // dissipation, as for the intrinsic law).
  const double compressive = 0.5 * sigma * sigma / L.normal_stiffness;
  CHECK(el.dissipated() == Approx(G_II + compressive).epsilon(1e-6));
  CHECK(el.work + born == Approx(G_II + compressive).epsilon(1e-3));
}

namespace {

namespace fs = std::filesystem;

fs::path cases_dir() { return fs::path(__FILE__).parent_path() / "cases"; }

std::string replace_once(std::string text, const std::string& from, const std::string& to) {
  const auto p = text.find(from);
  REQUIRE(p != std::string::npos);
  return text.replace(p, from.size(), to);
}

fdem::Simulation make_sim(const std::string& name, const std::string& case_text,
                          const std::vector<std::pair<std::string, std::string>>& files, int threads = 1,
                          const std::vector<std::string>& sets = {}) {
  const auto dir = testing::tmp_dir(name);
  for (const auto& [file, text] : files) testing::write_text(dir / file, text);
  const std::string path = testing::write_text(dir / "case.toml", case_text);
  fdem::CaseSpec spec = fdem::load_case(path, sets);
  fdem::Model model = fdem::build_scene(spec);
  fdem::RunOptions opt;
  opt.quiet = true;
  opt.threads = threads;
  return fdem::Simulation(spec, std::move(model), opt);
}

const std::string kExtrinsic = "  penalty = 1.0e11           # Pa\n  insertion = \"extrinsic\"\n";

}  // namespace

TEST_CASE("engine bar with extrinsic insertion: one straight crack, peak f_t A, dissipation G_I A to 1 %",
          "[engine][regression]") {
  const std::string geo = testing::read_text(cases_dir() / "bar_structured.geo");
  const std::string toml =
      replace_once(testing::read_text(cases_dir() / "bar_structured.toml"), "  penalty = 1.0e11           # Pa\n", kExtrinsic);
  const double ft = 3.7e6, GI = 110.0, H = 0.1, t = 0.2, A = H * t;
  auto sim = make_sim("extrinsic_bar", toml, {{"bar_structured.geo", geo}});
  const auto* J = sim.interactions().joints();
  REQUIRE(J != nullptr);
  const int ny = 8;
  REQUIRE(J->dormant_count() == J->size());
  sim.begin_stage(0);
  double peak = 0, t_sep = -1, dt0 = sim.dt();
  while (!sim.stage_finished()) {
    sim.step();
    peak = std::max(peak, sim.monitor_value(1));
    if (t_sep < 0 && J->counts().total() >= ny) t_sep = sim.time();
    if (t_sep > 0 && sim.time() > t_sep + 1e-3) break;
  }
  REQUIRE(t_sep > 0);
  sim.energy_every_step(true);
  sim.step();
  const fdem::Energies e = sim.energies();
  // The broken elements: one vertical line of ny edges.
  const auto& X = sim.model().X;
  int broken = 0;
  double xmin = 1e9, xmax = -1e9;
  for (int k = 0; k < J->size(); ++k)
    if (J->state(k) == JointState::broken) {
      ++broken;
      for (int q : {0, 1}) xmin = std::min(xmin, X[2 * J->element(k).n[q]]), xmax = std::max(xmax, X[2 * J->element(k).n[q]]);
    }
  const int inserted = J->size() - J->dormant_count();
  std::printf("extrinsic bar: %d of %d elements inserted, %d broken at x = %.5g..%.5g m; dt %.4g -> %.4g s, %ld steps; "
              "peak R/(f_t A) = %.5f; D_frac/(G_I A) = %.5f; inserted energy %.4g J; balance error %.3g\n",
              inserted, J->size(), broken, xmin, xmax, dt0, sim.dt(), sim.steps(), peak / (ft * A), e.fracture / (GI * A),
              sim.interactions().inserted_energy(), e.balance_error());
  CHECK(broken == ny);
  CHECK(xmax - xmin < 1e-9);
  CHECK(peak / (ft * A) == Approx(1.0).epsilon(0.03));
  CHECK(e.fracture / (GI * A) == Approx(1.0).epsilon(0.01));
  CHECK(e.balance_error() < 1e-4);
  // Before the first insertion the copies are tied: the step is the continuum's, larger than with every element in.
  CHECK(sim.dt() <= dt0);
}

TEST_CASE("energy audit on the extrinsic bar: each part's books close on the work its forces took, the same bits as "
          "without the audit", "[engine][regression]") {
  const std::string geo = testing::read_text(cases_dir() / "bar_structured.geo");
  const std::string toml =
      replace_once(testing::read_text(cases_dir() / "bar_structured.toml"), "  penalty = 1.0e11           # Pa\n", kExtrinsic);
  auto plain = make_sim("extrinsic_bar_plain", toml, {{"bar_structured.geo", geo}});
  auto sim = make_sim("extrinsic_bar_audit", toml, {{"bar_structured.geo", geo}}, 1, {"numerics.energy_audit=true"});
  REQUIRE(sim.spec().energy_audit);
  const auto* J = sim.interactions().joints();
  plain.begin_stage(0);
  sim.begin_stage(0);
  double t_sep = -1;
  while (!sim.stage_finished()) {
    sim.step();
    plain.step();
    if (t_sep < 0 && J->counts().total() >= 8) t_sep = sim.time();
    if (t_sep > 0 && sim.time() > t_sep + 1e-3) break;
  }
  REQUIRE(t_sep > 0);
  CHECK(sim.model().x == plain.model().x);  // the audit reads the forces, it does not add them otherwise
  const fdem::Energies e = sim.energies();
  const auto parts = sim.energy_audit(e);
  double scale = 0;
  for (const auto& q : parts) scale += std::abs(q.worked);
  std::printf("energy audit, extrinsic bar: triangles %.6g / %.6g J, joints %.6g / %.6g J, contact %.6g / %.6g J\n",
              parts[0].worked, parts[0].grew, parts[1].worked, parts[1].grew, parts[2].worked, parts[2].grew);
  // The bar breaks in mode I, where the law is a potential (fracture/law.hpp): every part holds and dissipates the
  // work its forces took, to the step's integration error.
  REQUIRE(scale > 0);
  CHECK(parts[1].grew > 0.5 * e.fracture);  // the joints did take work: they broke
  for (const auto& q : parts) CHECK(std::abs(q.grew - q.worked) < 1e-3 * scale);
}

TEST_CASE("engine cantilever: a crackable material with extrinsic insertion has the continuum's stiffness until it cracks",
          "[engine][regression]") {
  // cases/elastic/cantilever.toml at 50 mm: the continuum (no fracture table), the same material crackable with
  // intrinsic elements on every edge, and with extrinsic insertion (strengths far above the stresses: nothing cracks).
  const std::string base = testing::read_text(std::string(FDEM_CASES_DIR) + "/elastic/cantilever.toml");
  REQUIRE(!base.empty());
  // Held to equilibrium 1e-7 (the case's 1e-5 stops the three runs 0.6 % apart: their unbalanced-force ratios differ).
  const std::string coarse =
      replace_once(replace_once(base, "mesh_size = 0.0125", "mesh_size = 0.05"), "equilibrium = 1e-5", "equilibrium = 1e-7");
  auto with_fracture = [&](const std::string& insertion) {
    return replace_once(coarse, "density = 1000.0         # kg/m^3\n",
                        "density = 1000.0         # kg/m^3\n  [materials.steelish.fracture]\n  tensile_strength = 1e8\n"
                        "  cohesion = 1e8\n  friction = 30.0\n  GI = 1e5\n  GII = 1e5\n  penalty = 1e10\n  insertion = \"" +
                            insertion + "\"\n");
  };
  auto tip = [](const std::string& name, const std::string& text, int& inserted, long& steps) {
    auto sim = make_sim(name, text, {});
    sim.run();
    const auto* J = sim.interactions().joints();
    inserted = J ? J->size() - J->dormant_count() : 0;
    steps = sim.steps();
    return sim.monitor_value(0);
  };
  int ins_c = 0, ins_e = 0, ins_i = 0;
  long st_c = 0, st_e = 0, st_i = 0;
  const double u_cont = tip("extrinsic_cantilever_continuum", coarse, ins_c, st_c);
  const double u_ext = tip("extrinsic_cantilever_extrinsic", with_fracture("extrinsic"), ins_e, st_e);
  const double u_intr = tip("extrinsic_cantilever_intrinsic", with_fracture("intrinsic"), ins_i, st_i);
  std::printf("cantilever tip deflection (m): continuum %.8g (%ld steps), extrinsic %.8g (%ld steps, %d inserted, ratio "
              "%.8f), intrinsic %.8g (%ld steps, ratio %.5f)\n",
              u_cont, st_c, u_ext, st_e, ins_e, u_ext / u_cont, u_intr, st_i, u_intr / u_cont);
  CHECK(ins_e == 0);
  CHECK(u_ext / u_cont == Approx(1.0).epsilon(1e-3));
  // The intrinsic elements add the penalty's compliance: softer than the continuum.
  CHECK(std::abs(u_intr / u_cont) > 1.01);
}

TEST_CASE("contact_penalty sets the crack faces' penalty apart from p_j: the contact step bound scales as its inverse root",
          "[engine][unit]") {
  // The bar's only contact law is that of its crack faces (no interfaces), penalty p_j = 1e11 Pa by default; with
  // contact_penalty = 1e9 Pa the contact springs' bound (6 p / H per triangle, contact_system.cpp) grows 10-fold.
  const std::string geo = testing::read_text(cases_dir() / "bar_structured.geo");
  const std::string base = testing::read_text(cases_dir() / "bar_structured.toml");
  auto sim0 = make_sim("extrinsic_contact_penalty_default", base, {{"bar_structured.geo", geo}});
  auto sim1 = make_sim("extrinsic_contact_penalty_1e9",
                       replace_once(base, "  penalty = 1.0e11           # Pa\n", "  penalty = 1.0e11           # Pa\n  contact_penalty = 1e9\n"),
                       {{"bar_structured.geo", geo}});
  const double dt0 = sim0.interactions().contact_stable_dt(sim0.model());
  const double dt1 = sim1.interactions().contact_stable_dt(sim1.model());
  CHECK(dt1 / dt0 == Approx(10.0).epsilon(1e-12));
  // The cohesive elements keep p_j.
  CHECK(sim1.interactions().joints()->law(0).normal_stiffness == sim0.interactions().joints()->law(0).normal_stiffness);
  // A value that is not a positive number is refused with the key.
  const auto dir = testing::tmp_dir("extrinsic_contact_penalty_bad");
  testing::write_text(dir / "bar_structured.geo", geo);
  const std::string bad = testing::write_text(
      dir / "case.toml", replace_once(base, "  penalty = 1.0e11           # Pa\n", "  penalty = 1.0e11           # Pa\n  contact_penalty = -1\n"));
  try {
    fdem::load_case(bad, {});
    FAIL("a negative contact_penalty was accepted");
  } catch (const std::exception& e) {
    CHECK(std::string(e.what()).find("materials.stone.fracture.contact_penalty") != std::string::npos);
  }
}

TEST_CASE("extrinsic bar: a non-finite velocity of a group of tied copies stops the step naming one of them", "[engine]") {
  const std::string geo = testing::read_text(cases_dir() / "bar_structured.geo");
  const std::string toml =
      replace_once(testing::read_text(cases_dir() / "bar_structured.toml"), "  penalty = 1.0e11           # Pa\n", kExtrinsic);
  for (double bad : {std::nan(""), HUGE_VAL}) {
    auto sim = make_sim("extrinsic_bar_nonfinite", toml, {{"bar_structured.geo", geo}});
    REQUIRE(sim.interactions().joints()->dormant_count() > 0);  // tied copies: the node loop runs by units
    sim.begin_stage(0);
    for (int s = 0; s < 5; ++s) sim.step();
    // every copy of the vertex of node p (the same reference position): the group's velocity
    auto& md = sim.model();
    const int p = md.n_nodes() / 2;
    int copies = 0;
    for (int k = 0; k < md.n_nodes(); ++k)
      if (md.X[2 * k] == md.X[2 * p] && md.X[2 * k + 1] == md.X[2 * p + 1]) md.v[2 * k + 1] = bad, ++copies;
    REQUIRE(copies > 1);
    std::string msg;
    try {
      sim.step();
    } catch (const std::exception& e) {
      msg = e.what();
    }
    INFO(msg);
    const auto at = msg.find("node ");
    REQUIRE(at != std::string::npos);
    CHECK(msg.find("has a non-finite velocity") != std::string::npos);
    const int k = std::stoi(msg.substr(at + 5));
    CHECK(md.X[2 * k] == md.X[2 * p]);
    CHECK(md.X[2 * k + 1] == md.X[2 * p + 1]);
  }
}
