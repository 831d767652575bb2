// Many-element tests on a fully split grid: determinism for 1, 2 and 4 threads, global energy bookkeeping,
// and the throughput benchmark (hidden: run with `test_fracture "[bench]"`).
#include <catch2/catch.hpp>

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "fracture/cohesive_system.hpp"
#include "test_grid.hpp"

using namespace fdem::fracture;
using fracture_test::make_split_grid;
using fracture_test::SplitGrid;

namespace {
CohesiveProps stone() { return fracture_test::sandstone(4e10); }  // cases/README.md §A sandstone

// Deterministic pseudo-random numbers in [-1, 1) (splitmix64), identical on every run and thread count.
double noise(std::uint64_t i) {
  std::uint64_t z = i + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return double(z >> 11) / double(1ull << 52) - 1.0;
}

// Positions at load factor lam: each triangle translates by lam * amplitude * grad(phi)(centroid) with phi convex,
// phi = (x^2 + y^2) / (2 L) + 0.3 x^4 / L^3, so neighbours separate (the Hessian is positive definite) by amounts that
// grow four-fold from left to right, with slip from the anisotropy: intact, damaged and broken elements at once,
// and no overlaps. noisy = true adds a per-node jitter (triangles then also deform) for the determinism test.
std::vector<double> positions(const SplitGrid& g, double lam, double amplitude, bool noisy = false) {
  std::vector<double> x = g.x;
  const double L = g.x[g.x.size() - 2];
  for (int t = 0; t < g.num_triangles(); ++t) {
    double cx = 0.0, cy = 0.0;
    for (int k = 0; k < 3; ++k) {
      cx += g.x[2 * g.tri[3 * t + k]] / 3.0;
      cy += g.x[2 * g.tri[3 * t + k] + 1] / 3.0;
    }
    const double ux = lam * amplitude * (cx / L + 1.2 * std::pow(cx / L, 3));
    const double uy = lam * amplitude * (cy / L);
    for (int k = 0; k < 3; ++k) {
      const int v = g.tri[3 * t + k];
      x[2 * v] += ux * (noisy ? 1.0 + 0.05 * noise(2 * v) : 1.0);
      x[2 * v + 1] += uy * (noisy ? 1.0 + 0.05 * noise(2 * v + 1) : 1.0);
    }
  }
  return x;
}

struct RunResult {
  std::vector<double> f, damage;
  std::vector<int> broken_order;
  double elastic, dissipated;
};

RunResult run(const SplitGrid& g, int threads, int steps, double amplitude) {
  omp_set_num_threads(threads);
  CohesiveSystem sys(g.elems, {stone()}, 0.1, g.x.data(), g.num_nodes());
  RunResult r;
  r.f.assign(g.x.size(), 0.0);
  for (int s = 1; s <= steps; ++s) {
    const std::vector<double> x = positions(g, double(s) / steps, amplitude, true);
    for (std::size_t i = 0; i < r.f.size(); ++i) r.f[i] = 1e-3 * noise(1000003ull * s + i);  // forces are ADDED
    sys.add_forces(x.data(), r.f.data());
    for (const BreakRecord& b : sys.update_damage(s * 1e-3, s * 1e-5, x.data())) r.broken_order.push_back(b.element);
  }
  r.damage.resize(sys.size());
  sys.damage_per_element(r.damage.data());
  r.elastic = sys.elastic_energy();
  r.dissipated = sys.dissipated_energy();
  return r;
}

bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}
}  // namespace

TEST_CASE("split grid: every interior edge gets one correctly oriented element", "[unit]") {
  const SplitGrid g = make_split_grid(3, 2, 0.1);
  CHECK(g.num_triangles() == 12);
  // Interior edges: horizontal 3*1, vertical 2*2, diagonals 3*2.
  CHECK(g.elems.size() == 13);
  std::vector<CohesiveElement> oriented = g.elems;
  orient_elements(oriented, g.tri.data());
  for (std::size_t e = 0; e < oriented.size(); ++e)
    for (int k = 0; k < 4; ++k) CHECK(oriented[e].n[k] == g.elems[e].n[k]);
  CohesiveSystem sys(g.elems, {stone()}, 0.1, g.x.data(), g.num_nodes());  // coincidence checked inside
  CHECK(sys.size() == 13);
}

TEST_CASE("add_forces and damage are bitwise identical for 1 and 2 and 4 threads", "[unit]") {
  const SplitGrid g = make_split_grid(80, 40, 0.01);  // 6400 triangles, ~9500 elements: above the parallel threshold
  const int saved = omp_get_max_threads();
  const double amplitude = 4e-3;  // m: a gradient from intact to broken
  const RunResult r1 = run(g, 1, 12, amplitude);
  const RunResult r2 = run(g, 2, 12, amplitude);
  const RunResult r4 = run(g, 4, 12, amplitude);
  omp_set_num_threads(saved);
  // The scene must exercise every state, or the test proves little.
  const int broken = int(r1.broken_order.size());
  int damaged = 0;
  for (double d : r1.damage) damaged += (d > 0.0 && d < 1.0) ? 1 : 0;
  WARN("elements " << r1.damage.size() << ": broken " << broken << ", damaged " << damaged);
  CHECK(broken > 100);
  CHECK(damaged > 100);
  CHECK(same_bits(r1.f, r2.f));
  CHECK(same_bits(r1.f, r4.f));
  CHECK(same_bits(r1.damage, r2.damage));
  CHECK(same_bits(r1.damage, r4.damage));
  CHECK(r1.broken_order == r2.broken_order);
  CHECK(r1.broken_order == r4.broken_order);
  CHECK(std::memcmp(&r1.elastic, &r4.elastic, sizeof(double)) == 0);
  CHECK(std::memcmp(&r1.dissipated, &r4.dissipated, sizeof(double)) == 0);
}

TEST_CASE("grid under a slow ramp: work of the joint forces = elastic + dissipated energy and forces sum to zero",
          "[unit]") {
  const SplitGrid g = make_split_grid(30, 20, 0.01);
  CohesiveSystem sys(g.elems, {stone()}, 0.1, g.x.data(), g.num_nodes());
  const int steps = 4000;
  const double amplitude = 2e-3;
  std::vector<double> f_old(g.x.size(), 0.0), x_old = g.x;
  double work = 0.0, peak_force = 0.0;
  std::size_t broken = 0;
  for (int s = 1; s <= steps; ++s) {
    const std::vector<double> x = positions(g, double(s) / steps, amplitude);
    std::vector<double> f(g.x.size(), 0.0);
    sys.add_forces(x.data(), f.data());
    broken += sys.update_damage(0.0, 0.0, x.data()).size();
    double sx = 0.0, sy = 0.0, fmax = 0.0;
    for (std::size_t i = 0; i < f.size(); ++i) {
      work -= 0.5 * (f_old[i] + f[i]) * (x[i] - x_old[i]);  // work done on the joints by the driver
      (i % 2 ? sy : sx) += f[i];
      fmax = std::max(fmax, std::abs(f[i]));
    }
    peak_force = std::max(peak_force, fmax);
    REQUIRE(std::abs(sx) <= 1e-9 * fmax * g.num_nodes());
    REQUIRE(std::abs(sy) <= 1e-9 * fmax * g.num_nodes());
    f_old = f;
    x_old = x;
  }
  const double stored = sys.elastic_energy(), dissipated = sys.dissipated_energy();
  WARN("grid ramp: work " << work << " J, elastic " << stored << " J, dissipated " << dissipated << " J, broken "
                          << broken << " of " << sys.size());
  CHECK(broken > 50);
  CHECK(dissipated > 0.0);
  CHECK(work == Approx(stored + dissipated).epsilon(2e-3));
}

TEST_CASE("throughput of the joint force loop on a 51200-triangle block intact and fragmented", "[.][bench]") {
  const SplitGrid g = make_split_grid(160, 160, 0.005);  // 51,200 triangles, every edge crackable
  const int nt = g.num_triangles();
  const int saved = omp_get_max_threads();
  std::printf("block: %d triangles, %zu cohesive elements, %d nodes\n", nt, g.elems.size(), g.num_nodes());
  std::printf("state,threads,intact_elements,steps,median_step_s,triangle_steps_per_s_median,triangle_steps_per_s_best\n");
  for (const char* state : {"intact", "compressed", "fragmented"}) {
    for (int threads : {1, 2}) {
      omp_set_num_threads(threads);
      CohesiveSystem sys(g.elems, {stone()}, 0.1, g.x.data(), g.num_nodes());
      std::vector<double> f(g.x.size(), 0.0);
      std::vector<double> x;
      if (std::string(state) == "intact") {
        x = positions(g, 1.0, 2e-7);  // small strains: every element in its pre-peak branch
      } else if (std::string(state) == "compressed") {
        x = positions(g, 1.0, -2e-7);  // every joint overlapping a little (a precompressed wall)
      } else {
        x = positions(g, 1.0, 2.4e-2);  // most elements broken, the rest damaged (softening branch, exp)
      }
      sys.add_forces(x.data(), f.data());
      sys.update_damage(0.0, 0.0, x.data());
      // Per-step timing; the machine is shared, so report the median and the best step (least disturbed).
      const int steps = 300;
      std::vector<double> dt(steps);
      for (int s = 0; s < steps; ++s) {
        const auto t0 = std::chrono::steady_clock::now();
        sys.add_forces(x.data(), f.data());
        sys.update_damage(0.0, 0.0, x.data());
        dt[s] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      }
      std::sort(dt.begin(), dt.end());
      std::printf("%s,%d,%d,%d,%.3e,%.3e,%.3e\n", state, threads, sys.intact_count(), steps, dt[steps / 2],
                  double(nt) / dt[steps / 2], double(nt) / dt[0]);
    }
  }
  omp_set_num_threads(saved);
  SUCCEED();
}
