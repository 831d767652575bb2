// The force loop's plain group (CohesiveSystem::plain_: the [K25] law without keep_friction or cap, evaluated inline,
// eight, four, two or one element at a time) against the general point law: the same bits as evaluate_point element by
// element and the same node sums, through every state (intact, damaged, compressed past the shear peak, broken), with
// elements of another law (keep_friction) mixed in, for 1 and 2 threads and each vector width.
#include <catch2/catch.hpp>

#include <omp.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "fracture/cohesive_system.hpp"
#include "test_grid.hpp"

using namespace fdem::fracture;
using fracture_test::make_split_grid;
using fracture_test::SplitGrid;

namespace {
double noise(std::uint64_t i) {  // splitmix64 in [-1, 1)
  std::uint64_t z = i + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return double(z >> 11) / double(1ull << 52) - 1.0;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// The general loop of CohesiveSystem::add_forces written out for every element with evaluate_point, element order.
struct Reference {
  const SplitGrid& g;
  const CohesiveSystem& sys;  // for the law constants and lengths only
  double thickness;
  std::vector<PointHistory> hist;
  std::vector<double> dissipated, friction, energy;
  std::vector<char> broken;
  Reference(const SplitGrid& grid, const CohesiveSystem& s, double t)
      : g(grid), sys(s), thickness(t), dissipated(s.size(), 0.0), friction(s.size(), 0.0), energy(s.size(), 0.0),
        broken(s.size(), 0) {
    for (int e = 0; e < s.size(); ++e)
      for (int i = 0; i < 3; ++i) hist.push_back(initial_history(s.law(e)));
  }
  // Forces at x (node sums in element order from 0.0), and the elements that became fully damaged, ascending.
  std::vector<double> step(const std::vector<double>& x, std::vector<int>& newly_broken) {
    const double simpson[3] = {1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0};
    std::vector<double> f(x.size(), 0.0);
    newly_broken.clear();
    for (int e = 0; e < sys.size(); ++e) {
      if (broken[e]) continue;
      const int* n = sys.element(e).n;
      double tx = (x[2 * n[1]] + x[2 * n[3]]) - (x[2 * n[0]] + x[2 * n[2]]);
      double ty = (x[2 * n[1] + 1] + x[2 * n[3] + 1]) - (x[2 * n[0] + 1] + x[2 * n[2] + 1]);
      const double len = std::sqrt(tx * tx + ty * ty);
      if (len > 0.0) {
        tx /= len;
        ty /= len;
      } else {
        tx = 1.0;
        ty = 0.0;
      }
      const double nx = ty, ny = -tx;
      const double d0x = x[2 * n[2]] - x[2 * n[0]], d0y = x[2 * n[2] + 1] - x[2 * n[0] + 1];
      const double d1x = x[2 * n[3]] - x[2 * n[1]], d1y = x[2 * n[3] + 1] - x[2 * n[1] + 1];
      const double dx[3] = {d0x, 0.5 * (d0x + d1x), d1x}, dy[3] = {d0y, 0.5 * (d0y + d1y), d1y};
      const double area = sys.length(e) * thickness;
      double Tx[3], Ty[3], en = 0.0, dis = 0.0, fr = 0.0;
      bool all_broken = true;
      for (int i = 0; i < 3; ++i) {
        const double o = dx[i] * nx + dy[i] * ny + 0.0, s = dx[i] * tx + dy[i] * ty + 0.0;
        const PointResponse r = evaluate_point(sys.law(e), o, s, hist[3 * e + i]);
        hist[3 * e + i] = r.history;
        const double w = simpson[i] * area;
        Tx[i] = w * (r.sigma * nx + r.tau * tx);
        Ty[i] = w * (r.sigma * ny + r.tau * ty);
        en += w * r.energy;
        dis += w * r.dissipated;
        fr += w * r.friction_dissipated;
        all_broken = all_broken && r.history.damage >= 1.0;
      }
      energy[e] = en;
      dissipated[e] += dis;
      friction[e] += fr;
      const double fa[4] = {Tx[0] + 0.5 * Tx[1], Ty[0] + 0.5 * Ty[1], Tx[2] + 0.5 * Tx[1], Ty[2] + 0.5 * Ty[1]};
      const double fe[8] = {fa[0], fa[1], fa[2], fa[3], -fa[0], -fa[1], -fa[2], -fa[3]};
      for (int k = 0; k < 4; ++k) {  // node sums in element order (the gather's order)
        f[2 * n[k]] += fe[2 * k];
        f[2 * n[k] + 1] += fe[2 * k + 1];
      }
      if (all_broken) newly_broken.push_back(e);
    }
    for (int e : newly_broken) {
      dissipated[e] += energy[e];
      energy[e] = 0.0;
      broken[e] = 1;
    }
    return f;
  }
};

// Per-node random walk of growing amplitude about the reference positions, with reversals: points open and close,
// slip both ways, get compressed past their shear peak, damage and break.
std::vector<double> positions(const SplitGrid& g, int step, double amplitude) {
  std::vector<double> x = g.x;
  const double lam = double(step) * (1.0 + 0.6 * std::sin(0.7 * step));
  for (std::size_t i = 0; i < x.size(); ++i) x[i] += lam * amplitude * noise(i) * (1.0 + 0.3 * noise(i + 7 * step));
  return x;
}

struct Counts {
  int broken = 0, damaged = 0, compressed_past_shear_peak = 0;
};

Counts compare_with_reference(const SplitGrid& g, int threads, int lanes) {
  CohesiveProps plain = fracture_test::sandstone(4e10), other = plain;
  other.keep_friction = true;
  std::vector<CohesiveElement> elems = g.elems;
  for (std::size_t e = 0; e < elems.size(); ++e) elems[e].props = (e % 7 == 3) ? 1 : 0;  // a few of another law
  const double t = 0.1;
  CohesiveSystem sys(elems, {plain, other}, t, g.x.data(), g.num_nodes());
  sys.set_vector_lanes(lanes);
  Reference ref(g, sys, t);
  omp_set_num_threads(threads);
  Counts c;
  const double amplitude = 2e-6;  // m per step (o_p is 1.85e-6 m for these 10 mm edges)
  for (int step = 1; step <= 60; ++step) {
    const std::vector<double> x = positions(g, step, amplitude);
    std::vector<double> f(x.size(), 0.0);
    sys.add_forces(x.data(), f.data());
    const std::vector<BreakRecord> rec = sys.update_damage(0.0, 0.0, x.data());
    std::vector<int> ref_broken;
    const std::vector<double> f_ref = ref.step(x, ref_broken);
    REQUIRE(rec.size() == ref_broken.size());
    for (std::size_t k = 0; k < rec.size(); ++k) REQUIRE(rec[k].element == ref_broken[k]);
    c.broken += int(rec.size());
    // == rather than bits for the node sums: the zeroed slots of broken elements may turn a -0.0 sum into +0.0
    for (std::size_t i = 0; i < f.size(); ++i) REQUIRE(f[i] == f_ref[i]);
    for (int e = 0; e < sys.size(); ++e) {
      for (int i = 0; i < 3; ++i) REQUIRE(same_bits(sys.point_damage(e, i), ref.hist[3 * e + i].damage));
      REQUIRE(same_bits(sys.dissipated_energy(e), ref.dissipated[e]));
    }
    // compressed points past their shear peak in this step (the plain group's slow path)
    for (int e = 0; e < sys.size(); ++e)
      for (int i = 0; i < 3; ++i) {
        const PointHistory& h = ref.hist[3 * e + i];
        if (!ref.broken[e] && h.damage > 0.0 && h.damage < 1.0 && h.undamaged_energy > 0.0) ++c.damaged;
      }
    double elastic_ref = 0.0;
    for (int e = 0; e < sys.size(); ++e)
      if (!ref.broken[e]) elastic_ref += ref.energy[e];
    REQUIRE(same_bits(sys.elastic_energy(), elastic_ref));
    double friction_ref = 0.0;
    for (double d : ref.friction) friction_ref += d;
    REQUIRE(same_bits(sys.friction_energy(), friction_ref));
  }
  // points in compression past their shear peak at the last step, from the law itself
  const std::vector<double> x = positions(g, 60, amplitude);
  for (int e = 0; e < sys.size(); ++e) {
    if (ref.broken[e]) continue;
    const int* n = sys.element(e).n;
    const double ox = x[2 * n[2]] - x[2 * n[0]], oy = x[2 * n[2] + 1] - x[2 * n[0] + 1];
    double tx = x[2 * n[1]] - x[2 * n[0]], ty = x[2 * n[1] + 1] - x[2 * n[0] + 1];
    const double l = std::sqrt(tx * tx + ty * ty);
    tx /= l, ty /= l;
    const double o = ox * ty - oy * tx, s = ox * tx + oy * ty;
    const JointLaw& L = sys.law(e);
    if (o < 0.0) {
      const double f_s = shear_strength(L.normal_stiffness * o, L.cohesion, L.tan_friction);
      if (std::abs(s) > 2.0 * f_s * L.inv_shear_stiffness) ++c.compressed_past_shear_peak;
    }
  }
  return c;
}
}  // namespace

TEST_CASE("plain group of the force loop: the bits of evaluate_point through every state, 1 and 2 threads, 8, 4, 2, "
          "1 lanes", "[unit]") {
  const SplitGrid g = make_split_grid(60, 40, 0.01);  // ~7100 elements: above the parallel threshold
  const int saved = omp_get_max_threads();
  const Counts c1 = compare_with_reference(g, 1, 4);  // four at a time (AVX; two where the CPU has no AVX)
  const Counts c2 = compare_with_reference(g, 2, 4);
  const Counts c8 = compare_with_reference(g, 1, 8);  // eight at a time (AVX-512; else as with 4)
  compare_with_reference(g, 2, 8);
  compare_with_reference(g, 1, 2);  // two at a time (SSE2)
  compare_with_reference(g, 2, 1);  // one at a time
  omp_set_num_threads(saved);
  WARN("plain group: broken " << c1.broken << ", damaged point-steps " << c1.damaged
                              << ", compressed past the shear peak (last step) " << c1.compressed_past_shear_peak);
  CHECK(c1.broken > 100);
  CHECK(c1.damaged > 100);
  CHECK(c1.compressed_past_shear_peak > 10);
  CHECK(c2.broken == c1.broken);
  CHECK(c8.broken == c1.broken);
}
