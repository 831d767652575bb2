// Test helpers for the fracture tests: a fully split structured triangle grid (every edge crackable, the classic
// FDEM limit of mesh/README.md 'Topology') and a kinematic driver for one element.
#pragma once

#include <algorithm>
#include <map>
#include <utility>
#include <vector>

#include "fracture/cohesive_system.hpp"

namespace fracture_test {

// The sandstone's cohesive properties (cases/README.md §A) with joint penalty p_j (Pa).
inline fdem::fracture::CohesiveProps sandstone(double penalty) {
  fdem::fracture::CohesiveProps p;
  p.tensile_strength = 3.7e6;
  p.cohesion = 5.2e6;
  p.friction_deg = 35.0;
  p.residual_friction_deg = 30.0;
  p.G_I = 110.0;
  p.G_II = 770.0;
  p.penalty = penalty;
  return p;
}

using fdem::fracture::CohesiveElement;
using fdem::fracture::CohesiveProps;

// nx x ny square cells of size a (m), each split by its rising diagonal into two CCW triangles; every triangle owns
// its 3 nodes (node 3 t + k), and each interior edge gets one cohesive element (side A = the triangle seen first).
struct SplitGrid {
  std::vector<double> x;      // reference coordinates, 2 per node
  std::vector<int> tri;       // 3 per triangle, CCW
  std::vector<CohesiveElement> elems;
  int num_nodes() const { return int(x.size() / 2); }
  int num_triangles() const { return int(tri.size() / 3); }
};

inline SplitGrid make_split_grid(int nx, int ny, double a) {
  SplitGrid g;
  auto vid = [nx](int i, int j) { return j * (nx + 1) + i; };
  std::vector<int> tv;  // grid vertex of each triangle node
  auto add_tri = [&](int v0, int v1, int v2) {
    for (int v : {v0, v1, v2}) {
      const int i = v % (nx + 1), j = v / (nx + 1);
      g.x.push_back(i * a);
      g.x.push_back(j * a);
      g.tri.push_back(int(tv.size()));
      tv.push_back(v);
    }
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      add_tri(vid(i, j), vid(i + 1, j), vid(i + 1, j + 1));
      add_tri(vid(i, j), vid(i + 1, j + 1), vid(i, j + 1));
    }
  // Grid edge (sorted vertex pair) -> (triangle, local index of the edge's first node in CCW order).
  std::map<std::pair<int, int>, std::pair<int, int>> seen;
  const int nt = int(g.tri.size() / 3);
  for (int t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      const int p = g.tri[3 * t + k], q = g.tri[3 * t + (k + 1) % 3];
      const std::pair<int, int> key{std::min(tv[p], tv[q]), std::max(tv[p], tv[q])};
      auto it = seen.find(key);
      if (it == seen.end()) {
        seen.emplace(key, std::make_pair(t, k));
        continue;
      }
      const int ta = it->second.first, ka = it->second.second;
      CohesiveElement el;
      el.n[0] = g.tri[3 * ta + ka];
      el.n[1] = g.tri[3 * ta + (ka + 1) % 3];
      // Side B runs the same edge the other way: its node at the vertex of a0 is q, at a1 is p.
      el.n[2] = tv[q] == tv[el.n[0]] ? q : p;
      el.n[3] = tv[q] == tv[el.n[0]] ? p : q;
      el.props = 0;
      el.tri_a = ta;
      el.tri_b = t;
      g.elems.push_back(el);
    }
  return g;
}

// One horizontal element of length h: A = {0: (0,0), 1: (h,0)} above, B = {2, 3} below, so n = (0, -1), t = (1, 0).
// move(o, s) places side B at opening o and slip s; the driver integrates the work of the tractions by the trapezoid
// rule, W = sum 0.5 (T_old + T_new) . (du), per unit area (J/m^2).
struct OneElement {
  double h, t;
  std::vector<double> x;
  fdem::fracture::CohesiveSystem sys;
  double o = 0.0, s = 0.0;        // m
  double sigma = 0.0, tau = 0.0;  // Pa, from the nodal forces
  double work = 0.0;              // J/m^2
  std::vector<fdem::fracture::BreakRecord> breaks;

  static std::vector<double> reference(double h_) { return {0.0, 0.0, h_, 0.0, 0.0, 0.0, h_, 0.0}; }
  static std::vector<CohesiveElement> element() {
    CohesiveElement el;
    el.n[0] = 0;
    el.n[1] = 1;
    el.n[2] = 2;
    el.n[3] = 3;
    el.props = 0;
    el.tri_a = 0;
    el.tri_b = 1;
    return {el};
  }
  OneElement(const CohesiveProps& p, double h_, double t_)
      : h(h_), t(t_), x(reference(h_)), sys(element(), {p}, t_, reference(h_).data(), 4) {}

  void move(double o_new, double s_new) {
    x[4] = s_new;
    x[5] = -o_new;
    x[6] = h + s_new;
    x[7] = -o_new;
    std::vector<double> f(8, 0.0);
    sys.add_forces(x.data(), f.data());
    const double A = h * t;
    // Force on side B: -(sigma n + tau t) A with n = (0,-1), t = (1,0).
    const double sig = (f[5] + f[7]) / A, ta = -(f[4] + f[6]) / A;
    work += 0.5 * (sigma + sig) * (o_new - o) + 0.5 * (tau + ta) * (s_new - s);
    sigma = sig;
    tau = ta;
    o = o_new;
    s = s_new;
    auto b = sys.update_damage(0.0, o_new, x.data());
    breaks.insert(breaks.end(), b.begin(), b.end());
  }
  double elastic() const { return sys.elastic_energy() / (h * t); }       // J/m^2
  double dissipated() const { return sys.dissipated_energy() / (h * t); }  // J/m^2
};

}  // namespace fracture_test
