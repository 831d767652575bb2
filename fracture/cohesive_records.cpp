// fracture/cohesive_records.cpp: the cohesive elements' insertion, damage update and records (energies, per-element
// states, the cracks.csv rows, the checkpoint state), and the helpers that classify and orient elements. The force
// loop and its kernels are in fracture/cohesive_system.cpp, which also states the data layout both files share.
#include "fracture/cohesive_system.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace fdem::fracture {

using detail::kPi;
using detail::kSimpson;

const char* to_string(JointClass c) { return c == JointClass::interface ? "interface" : "unit-interior"; }

const char* to_string(FractureMode m) {
  switch (m) {
    case FractureMode::mode_I: return "I";
    case FractureMode::mode_II: return "II";
    default: return "mixed";
  }
}

FractureMode classify_mode(double D_I, double D_II) {
  if (D_I >= 2.0 * D_II) return FractureMode::mode_I;
  if (D_II >= 2.0 * D_I) return FractureMode::mode_II;
  return FractureMode::mixed;
}

long long BreakCounts::total() const {
  long long s = 0;
  for (const auto& row : count)
    for (long long c : row) s += c;
  return s;
}

void orient_elements(std::vector<CohesiveElement>& elems, const int* tri_nodes) {
  // Position of node v in triangle tri, or -1.
  auto where = [tri_nodes](int tri, int v) {
    for (int k = 0; k < 3; ++k)
      if (tri_nodes[3 * tri + k] == v) return k;
    return -1;
  };
  for (std::size_t e = 0; e < elems.size(); ++e) {
    CohesiveElement& el = elems[e];
    const bool use_a = el.tri_a >= 0;
    const int tri = use_a ? el.tri_a : el.tri_b;
    const int u = use_a ? el.n[0] : el.n[2], v = use_a ? el.n[1] : el.n[3];
    if (tri < 0) throw std::invalid_argument("cohesive element " + std::to_string(e) + " has no triangle on either side");
    const int i = where(tri, u), j = where(tri, v);
    if (i < 0 || j < 0)
      throw std::invalid_argument("cohesive element " + std::to_string(e) + ": its edge is not an edge of triangle " +
                                  std::to_string(tri));
    const bool ccw = j == (i + 1) % 3;
    // Side A wants its edge counter-clockwise, side B clockwise (it is the same edge seen from the other side).
    if (ccw != use_a) {
      std::swap(el.n[0], el.n[1]);
      std::swap(el.n[2], el.n[3]);
    }
  }
}

int CohesiveSystem::extrinsic_count() const {
  int n = 0;
  for (const CohesiveElement& el : elems_) n += props_[el.props].extrinsic;
  return n;
}

void CohesiveSystem::insert(const std::vector<Insertion>& list) {
  if (list.empty()) return;
  for (const Insertion& in : list) {
    const int e = in.element;
    if (e < 0 || e >= size() || !dormant_[e]) throw std::logic_error("CohesiveSystem::insert: element not dormant");
    const JointLaw& L = law_[e];
    // Separation on the pre-peak curves (2 x - x^2) f (law.hpp) whose traction is the continuum's, capped at the peak
    // (x = 1); in compression the linear penalty (and no further than the cap, if any).
    double sigma = in.sigma;
    if (L.compressive_strength > 0.0) sigma = std::max(sigma, -L.compressive_strength);
    double o0;
    if (sigma >= 0.0) {
      const double r = L.tensile_strength > 0.0 ? std::min(sigma / L.tensile_strength, 1.0) : 1.0;
      o0 = (1.0 - std::sqrt(1.0 - r)) * L.opening_peak;
    } else {
      o0 = sigma / L.normal_stiffness;
    }
    const double f_s = shear_strength(std::min(sigma, 0.0), L.cohesion, L.tan_friction);
    const double s_p = 2.0 * f_s * L.inv_shear_stiffness;
    const double r = f_s > 0.0 ? std::min(std::abs(in.tau) / f_s, 1.0) : 1.0;
    const double s0 = (in.tau < 0.0 ? -1.0 : 1.0) * (1.0 - std::sqrt(1.0 - r)) * s_p;
    offset_[2 * std::size_t(e)] = o0;
    offset_[2 * std::size_t(e) + 1] = s0;
    // The points start from the law's state at (o_0, s_0): undamaged (at most at the peak), with its energy.
    const PointResponse pr = evaluate_point(L, o0, s0, initial_history(L));
    for (int i = 0; i < 3; ++i) history_[3 * std::size_t(e) + i] = pr.history;
    energy_[e] = pr.energy * length_[e] * thickness_;
    inserted_ += energy_[e];
    dormant_[e] = 0;
    --dormant_count_;
    active_.push_back(e);
  }
  std::sort(active_.begin(), active_.end());
  build_gather();
  build_hot();
}

std::vector<BreakRecord> CohesiveSystem::update_damage(double time, double control_displacement, const double* x) {
  std::vector<BreakRecord> out;
  if (pending_count_ == 0) return out;
  std::size_t kept = 0;
  for (std::size_t k = 0; k < active_.size(); ++k) {
    const int e = active_[k];
    if (!pending_[e]) {
      active_[kept++] = e;
      continue;
    }
    const CohesiveElement& el = elems_[e];
    BreakRecord rec{};
    rec.element = e;
    rec.time = time;
    rec.control_displacement = control_displacement;
    rec.x = 0.25 * (x[2 * el.n[0]] + x[2 * el.n[1]] + x[2 * el.n[2]] + x[2 * el.n[3]]);
    rec.y = 0.25 * (x[2 * el.n[0] + 1] + x[2 * el.n[1] + 1] + x[2 * el.n[2] + 1] + x[2 * el.n[3] + 1]);
    rec.kind = el.kind;
    rec.unit_a = el.unit_a;
    rec.unit_b = el.unit_b;
    rec.tri_a = el.tri_a;
    rec.tri_b = el.tri_b;
    rec.props = el.props;
    rec.damage_I = break_DI_[e];
    rec.damage_II = break_DII_[e];
    rec.mode = classify_mode(rec.damage_I, rec.damage_II);
    rec.residual_friction = residual_friction(e);
    rec.length = length_[e];
    rec.x_ref = ref_mid_[2 * e];
    rec.y_ref = ref_mid_[2 * e + 1];
    out.push_back(rec);
    ++counts_.count[int(el.kind)][int(rec.mode)];
    // Whatever the element still stores (only compression can remain at D = 1) leaves with it: book it as
    // dissipated so that elastic + dissipated stays continuous across the removal.
    dissipated_[e] += energy_[e];
    energy_[e] = 0.0;
    std::fill(force_.begin() + 8 * std::size_t(e), force_.begin() + 8 * std::size_t(e) + 8, 0.0);
    broken_[e] = 1;
    pending_[e] = 0;
  }
  stale_slots_ += 4 * (active_.size() - kept);
  active_.resize(kept);
  plain_.erase(std::remove_if(plain_.begin(), plain_.end(),
                              [this](const detail::PlainJoint& J) { return broken_[J.e] != 0; }),
               plain_.end());
  other_.erase(std::remove_if(other_.begin(), other_.end(), [this](int e) { return broken_[e] != 0; }), other_.end());
  pending_count_ = 0;
  // Broken elements' slots hold zeros, so the gather stays right; rebuild it once they are a quarter of it, which
  // keeps a fragmented block from paying for its dead joints (amortised O(1) per break).
  if (4 * stale_slots_ > gather_slot_.size()) build_gather();
  return out;
}

double CohesiveSystem::elastic_energy() const {
  double s = 0.0;
  for (int e : active_) s += energy_[e];
  return s;
}

double CohesiveSystem::friction_energy() const {
  double s = 0.0;
  for (double d : friction_) s += d;
  return s;
}

double CohesiveSystem::dissipated_energy() const {
  double s = 0.0;
  for (double d : dissipated_) s += d;
  return s;
}

double CohesiveSystem::damage(int e) const {
  const PointHistory* h = &history_[3 * std::size_t(e)];
  return std::max(h[0].damage, std::max(h[1].damage, h[2].damage));
}

double CohesiveSystem::crushing(int e) const {
  const PointHistory* h = &history_[3 * std::size_t(e)];
  return -(kSimpson[0] * h[0].closure + kSimpson[1] * h[1].closure + kSimpson[2] * h[2].closure);
}

double CohesiveSystem::crush_damage(int e) const {
  const int ci = composite_index_[e];
  if (ci < 0) return 0.0;
  const CompositeHistory* h = &composite_history_[3 * std::size_t(ci)];
  return std::max(h[0].crush, std::max(h[1].crush, h[2].crush));
}

void CohesiveSystem::mean_traction(int e, const double* x, double& sigma, double& tau) const {
  if (dormant(e)) {
    sigma = tau = std::nan("");
    return;
  }
  const int* n = elems_[e].n;
  // the frame of add_forces: the mid-line of the two edges, n pointing from side A into side B
  double tx = (x[2 * n[1]] + x[2 * n[3]]) - (x[2 * n[0]] + x[2 * n[2]]);
  double ty = (x[2 * n[1] + 1] + x[2 * n[3] + 1]) - (x[2 * n[0] + 1] + x[2 * n[2] + 1]);
  const double len = std::sqrt(tx * tx + ty * ty);
  if (len > 0.0) tx /= len, ty /= len;
  else tx = 1.0, ty = 0.0;
  const double nx = ty, ny = -tx;
  const double* fe = &force_[8 * std::size_t(e)];
  const double fx = fe[0] + fe[2], fy = fe[1] + fe[3];
  const double area = length_[e] * thickness_;
  sigma = (fx * nx + fy * ny) / area;
  tau = (fx * tx + fy * ty) / area;
}

JointState CohesiveSystem::state(int e) const {
  if (broken_[e]) return JointState::broken;
  return damage(e) > 0.0 ? JointState::damaged : JointState::intact;
}

void CohesiveSystem::damage_per_element(double* out) const {
  for (int e = 0; e < size(); ++e) out[e] = damage(e);
}

void CohesiveSystem::state_per_element(std::uint8_t* out) const {
  for (int e = 0; e < size(); ++e) out[e] = std::uint8_t(state(e));
}

double CohesiveSystem::residual_friction(int e) const {
  return std::tan(props_[elems_[e].props].residual_friction_deg * kPi / 180.0);
}

void write_cracks_csv_header(std::ostream& os) {
  // x_m, y_m: current midpoint at breaking; x_ref_m, y_ref_m: reference midpoint (to find the mesh edge).
  os << "time_s,control_displacement_m,x_m,y_m,class,unit_a,unit_b,mode,D_I,D_II,element,tri_a,tri_b,length_m,x_ref_m,"
        "y_ref_m\n";
}

void write_cracks_csv_row(std::ostream& os, const BreakRecord& r) {
  std::ostringstream line;
  line.precision(10);
  line << r.time << ',' << r.control_displacement << ',' << r.x << ',' << r.y << ',' << to_string(r.kind) << ','
       << r.unit_a << ',' << r.unit_b << ',' << to_string(r.mode) << ',' << r.damage_I << ',' << r.damage_II << ','
       << r.element << ',' << r.tri_a << ',' << r.tri_b << ',' << r.length << ',' << r.x_ref << ',' << r.y_ref << '\n';
  os << line.str();
}

// Checkpoint. The sizeof guards fail the build when a field is added to CohesiveSystem or PointHistory (x86-64
// libstdc++): add the field to save_state and load_state if it carries from one step to the next, then update the size.
// Derived fields are not saved: plain_ and other_ (the force loop's groups) are rebuilt from active_ on load.
void CohesiveSystem::save_state(StateWriter& w) const {
#if defined(__x86_64__) && defined(__GLIBCXX__)
  static_assert(sizeof(CohesiveSystem) == 712, "CohesiveSystem changed: update state_io and this size");
  static_assert(sizeof(PointHistory) == 40, "PointHistory changed: check CohesiveSystem::state_io and this size");
#endif
  const_cast<CohesiveSystem*>(this)->state_io(w);  // (the writer only reads the fields)
}

void CohesiveSystem::load_state(StateReader& r) { state_io(r); }

template <class IO>
void CohesiveSystem::state_io(IO& io) {
  constexpr bool load = IO::loading;
  io.section("cohesive");
  std::int32_t hist_size = std::int32_t(sizeof(PointHistory)), n = size();
  io.pod(hist_size);
  if constexpr (load)
    if (hist_size != std::int32_t(sizeof(PointHistory))) throw StateError("cohesive: another point history");
  io.pod(n);
  if constexpr (load)
    if (n != size()) throw StateError("cohesive: another number of elements");
  const std::size_t ne = std::size_t(size());
  io.vec_sized(history_, 3 * ne, "cohesive point histories");
  io.vec_sized(force_, 8 * ne, "cohesive forces");
  io.vec_sized(energy_, ne, "cohesive energies");
  io.vec_sized(dissipated_, ne, "cohesive dissipation");
  io.vec_sized(friction_, ne, "cohesive friction");
  io.vec_sized(break_DI_, ne, "cohesive break damage I");
  io.vec_sized(break_DII_, ne, "cohesive break damage II");
  io.vec_sized(pending_, ne, "cohesive pending flags");
  io.vec_sized(broken_, ne, "cohesive broken flags");
  io.vec(active_);
  if constexpr (load)
    for (int e : active_)
      if (e < 0 || e >= size()) throw StateError("cohesive: element index out of range");
  io.pod(pending_count_);
  io.vec(gather_node_), io.vec(gather_start_), io.vec(gather_slot_);
  if constexpr (load) {
    if (gather_start_.empty() || gather_start_.size() != gather_node_.size() + 1 || gather_start_.back() != int(gather_slot_.size()))
      throw StateError("cohesive: inconsistent node gather");
    for (int v : gather_node_)
      if (v < 0 || v >= num_nodes_) throw StateError("cohesive: gather node out of range");
    for (int sl : gather_slot_)
      if (sl < 0 || std::size_t(sl) + 1 >= force_.size()) throw StateError("cohesive: gather slot out of range");
  }
  std::uint64_t stale = stale_slots_;
  io.pod(stale);
  if constexpr (load) stale_slots_ = std::size_t(stale);
  io.pod(counts_);
  // law = "composite": its point histories (composite_index_ and composite_law_ are fixed when the system is built).
  io.vec_sized(composite_history_, composite_history_.size(), "composite point histories");
  // Extrinsic insertion.
  io.vec_sized(dormant_, ne, "cohesive dormant flags");
  io.vec_sized(offset_, 2 * ne, "cohesive insertion offsets");
  std::int32_t dormant = std::int32_t(dormant_count_);
  io.pod(dormant);
  if constexpr (load) dormant_count_ = dormant;
  io.pod(inserted_);
  if constexpr (load) build_hot();
}

}  // namespace fdem::fracture
