// fracture/cohesive_system.hpp: the set of 4-node cohesive crack elements of a model (fracture/README.md).
//
// Conventions (fixed; the engine must follow them, orient_elements() helps):
// - Element nodes n = {a0, a1, b0, b1}: side A edge a0->a1, side B edge b0->b1, a0/b0 and a1/b1 at the same
//   reference position. a0->a1 runs counter-clockwise around triangle tri_a, so side B lies to the RIGHT of a0->a1.
// - Current frame: tangent t along (a1 + b1) - (a0 + b0) (the mid-line of the two edges, so rigid rotations give
//   no opening or slip), normal n = (t_y, -t_x), i.e. the normal of edge A pointing into side B.
// - Relative displacement of the faces at a point, d = x_B - x_A; opening o = d.n (> 0 when the faces separate,
//   < 0 when they overlap), slip s = d.t. Normal stress tension positive.
// - Compression: the element stays a linear penalty sigma = K_n o (K_n = p_j/h or k_n) whatever its damage, until it
//   breaks; contact then takes over. Integration at the two ends and the midpoint with Simpson weights 1/6, 4/6, 1/6.
// - Breaking: when all three points reached D = 1 (the element then carries no tension or shear). A joint with one
//   fully damaged end still holds through the others, which is what lets a crack tip cross an element gradually.
// - Index "none" is -1 everywhere (tri_a, tri_b, units).
#pragma once

#include <cstdint>
#include <iosfwd>
#include <vector>

#include "fracture/composite_law.hpp"
#include "fdem/common/state_io.hpp"
#include "fracture/law.hpp"
#include "fracture/properties.hpp"

namespace fdem::fracture {

enum class JointClass : std::uint8_t { unit_interior = 0, interface = 1 };
enum class FractureMode : std::uint8_t { mode_I = 0, mode_II = 1, mixed = 2 };
enum class JointState : std::uint8_t { intact = 0, damaged = 1, broken = 2 };

const char* to_string(JointClass c);
const char* to_string(FractureMode m);

// Mode of a break from its damage components: "dominated" means at least twice the other, otherwise mixed.
FractureMode classify_mode(double damage_I, double damage_II);

struct CohesiveElement {
  int n[4] = {-1, -1, -1, -1};  // {a0, a1, b0, b1}, node indices
  int props = -1;               // index into the CohesiveProps vector
  int tri_a = -1;               // triangle on side A (becomes contact-capable when broken)
  int tri_b = -1;               // triangle on side B
  JointClass kind = JointClass::unit_interior;
  int unit_a = -1;              // unit (stone/brick) of side A, for the damage records
  int unit_b = -1;              // unit of side B (== unit_a for a unit-interior crack)
};

struct BreakRecord {
  int element;                  // index of the broken element
  double time;                  // s
  double control_displacement;  // m (whatever the engine passes as its control displacement)
  double x, y;                  // midpoint of the element at breaking, m
  JointClass kind;
  int unit_a, unit_b, tri_a, tri_b, props;
  FractureMode mode;
  double damage_I, damage_II;   // mean over the 3 points of D_I, D_II at the step it broke (may exceed 1)
  double residual_friction;     // tan(phi_res) of its class: the friction coefficient contact must use on this edge
  double length;                // reference length h of the element, m (crack length = sum over records)
  double x_ref, y_ref;          // midpoint of the element in the reference configuration, m
};

// Counts of broken elements per class and mode, for history columns.
struct BreakCounts {
  long long count[2][3] = {{0, 0, 0}, {0, 0, 0}};  // [JointClass][FractureMode]
  long long of(JointClass c, FractureMode m) const { return count[int(c)][int(m)]; }
  long long total() const;
};

// Make a0->a1 run counter-clockwise around tri_a (swapping a0<->a1 together with b0<->b1 when needed), using the
// triangle connectivity tri_nodes (3 per triangle). For tri_a == -1, b0->b1 is made clockwise around tri_b.
// Throws std::invalid_argument if an element's edge is not an edge of its triangle.
void orient_elements(std::vector<CohesiveElement>& elems, const int* tri_nodes);

namespace detail {
inline constexpr double kPi = 3.14159265358979323846;
inline constexpr double kSimpson[3] = {1.0 / 6.0, 4.0 / 6.0, 1.0 / 6.0};  // end 0, midpoint, end 1 of a face

// One intact element of CohesiveSystem's plain group (see CohesiveSystem::plain_): everything its force loop reads of
// it but the positions and the point histories, in one 128-byte record (two cache lines).
struct alignas(64) PlainJoint {
  int n[4];                 // a0 a1 b0 b1
  int e;                    // element index
  int unused;
  double w_end, w_mid;      // Simpson weights times the face area h t: kSimpson[0] h t (both ends), kSimpson[1] h t
  double K_n, inv_K_s;      // JointLaw::normal_stiffness, inv_shear_stiffness
  double o_p, inv_o_p, inv_o_t;            // opening_peak, inv_opening_peak, inv_opening_range
  double s_p0, inv_s_p0, inv_s_t0;         // slip_peak0, inv_slip_peak0, inv_slip_range0
  double f_t, c, tan_phi;   // tensile_strength, cohesion, tan_friction
};
static_assert(sizeof(PlainJoint) == 128, "PlainJoint: two cache lines");
}  // namespace detail

class CohesiveSystem {
 public:
  // thickness t (m) of the plane-stress model; x_reference: 2 * num_nodes reference coordinates (m), interleaved
  // x0 y0 x1 y1 ... Throws std::invalid_argument with every problem found (bad props, too-soft penalty for an
  // element, nodes out of range, a0/b0 or a1/b1 not coincident, zero-length edges).
  CohesiveSystem(std::vector<CohesiveElement> elems, std::vector<CohesiveProps> props, double thickness,
                 const double* x_reference, int num_nodes);

  int size() const { return int(elems_.size()); }
  int intact_count() const { return int(active_.size()); }  // elements in the force loop

  // Extrinsic insertion (CohesiveProps::extrinsic; fracture/README.md "Extrinsic insertion"). The elements of such a
  // class start dormant: out of the force loop, their two sides held together by the engine (tied copies, one
  // continuum). The engine computes the traction the continuum carries across a dormant edge, sigma (normal, tension
  // positive) and tau (along t, the element's frame), both Pa, and inserts the element once it reaches the peak
  // surface of the law: sigma >= f_t or |tau| >= c + max(0, -sigma) tan(phi). An inserted element starts on the
  // pre-peak curve at the separation (o_0, s_0) whose traction is (sigma, tau) (at the peak when the surface was
  // reached), kept as an offset of the geometric separation, which is zero at insertion: the traction stays
  // continuous and the separation work from there to the break is what the law gives, G_I or G_II less the
  // pre-peak part already stored. That stored part, E_0(o_0, s_0) h t, appears with the element (the continuum had
  // no compliance to hold it): inserted_energy() sums it for the engine's balance.
  int dormant_count() const { return dormant_count_; }
  int extrinsic_count() const;  // elements of extrinsic classes, dormant or not
  bool dormant(int e) const { return dormant_[e] != 0; }
  // Whether element e keeps its two faces out of contact: an intact element of an intrinsic class (an extrinsic one
  // is counted as its copies' faces from the start: the engine sets their masses once, before any insertion).
  bool holds_faces(int e) const { return !props_[elems_[e].props].extrinsic && !broken_[e] && !pending_[e]; }
  bool reaches_strength(int e, double sigma, double tau) const {
    const JointLaw& L = law_[e];
    return reaches_peak_surface(sigma, tau, L.tensile_strength, L.cohesion, L.tan_friction);
  }
  struct Insertion {
    int element;
    double sigma, tau;  // Pa, the continuum's traction at insertion (see above)
  };
  // Inserts the listed dormant elements (any order; each once) and rebuilds the node gather.
  void insert(const std::vector<Insertion>& list);
  double inserted_energy() const { return inserted_; }  // J, cumulative (see above)
  const CohesiveElement& element(int e) const { return elems_[e]; }
  const JointLaw& law(int e) const { return law_[e]; }
  double length(int e) const { return length_[e]; }  // reference length h, m

  // Largest stable central-difference step (s) of the joint springs on their own: min over nodes of
  // 2 sqrt(m / k), k the Gershgorin bound of the joint stiffness on that node (N/m). node_mass: kg per node
  // (nodes with m <= 0 are taken as fixed and skipped).
  // Returns +infinity when no element is intact. The engine combines it with the triangles' limit and a safety factor.
  // rep (optional): a representative per node for nodes that move as one (the engine's tied copies; node_mass then
  // holds the group's mass): the stiffnesses are summed per representative. Dormant elements do not act.
  double stable_dt(const double* node_mass, const int* rep = nullptr) const;
  // k of stable_dt per node (or representative, with rep): the Gershgorin row sums of its intact elements, N/m
  // (the engine adds them to the triangles' and contact springs' for the step of the assembled system).
  std::vector<double> node_stiffness(const int* rep) const;

  // Evaluate every intact element at positions x (2 * num_nodes, m), update its irreversible damage and
  // dissipation, and ADD its nodal forces (N, whole thickness) to f (2 * num_nodes). Deterministic: per-element
  // forces are computed in parallel, then every node sums its contributions in element order.
  void add_forces(const double* x, double* f);
  // Elements the force loop evaluates at once where it can (fracture/README.md "Force loop"): 8 (AVX-512 F and DQ,
  // where the CPU has them; the default), 4 (AVX, where the CPU has it), 2 (SSE2) or 1. The results are the same
  // bits for each; tests compare them.
  void set_vector_lanes(int lanes) { lanes_ = lanes; }

  // Remove the elements that became fully damaged in the last add_forces from the force loop and return one record
  // each, in element order. x: the current positions (for the midpoint). The engine writes cracks.csv and makes
  // tri_a/tri_b contact-capable with friction residual_friction on that edge.
  std::vector<BreakRecord> update_damage(double time, double control_displacement, const double* x);

  // Energies (J, whole thickness), summed in element order. Elastic: recoverable energy of the intact elements at the
  // last add_forces. Dissipated: cumulative damage dissipation, including the elastic energy left in an element
  // when it is removed (so that the engine's balance closes).
  double elastic_energy() const;
  double dissipated_energy() const;
  double dissipated_energy(int e) const { return dissipated_[e]; }
  // Cumulative work of the friction sliders of keep_friction classes (J, whole thickness; 0 without them).
  // Not part of dissipated_energy(): the engine books it as friction.
  double friction_energy() const;

  // Output for VTU snapshots: damage per element = max over its points; state intact / damaged / broken.
  double damage(int e) const;
  // The mean traction on element e at its last force evaluation (add_forces), in the frame of the positions x:
  // sigma = F_A . n / (h t) (Pa, tension positive) and tau = F_A . t / (h t) (Pa, along edge A's direction), F_A the
  // force the element put on its side-A nodes (the Simpson sum of its points' tractions). NaN for a dormant element
  // (extrinsic, not inserted: the continuum carries that edge).
  void mean_traction(int e, const double* x, double& sigma, double& tau) const;
  double point_damage(int e, int point) const { return history_[3 * e + point].damage; }
  JointState state(int e) const;
  // Compressive cap (law.hpp): the plastic closure of element e, Simpson mean of -o_c over its points (m, >= 0; 0
  // without a cap), and whether any class has a cap.
  double crushing(int e) const;
  bool has_cap() const { return has_cap_; }
  // law = "composite": compressive damage D_c of element e, max over its points (0 for other laws), and whether any
  // class uses the composite law.
  double crush_damage(int e) const;
  bool has_composite() const { return !composite_law_.empty(); }
  void damage_per_element(double* out) const;
  void state_per_element(std::uint8_t* out) const;
  const BreakCounts& counts() const { return counts_; }
  double residual_friction(int e) const;  // tan(phi_res) of element e's class

  // Checkpoint (fdem/common/state_io.hpp): the point histories (damage, trial damage, slider slip, cap closure), forces,
  // energies and dissipations per element, the pending and broken flags, the intact list, the node gather with its
  // stale slots (it fixes the summation order) and the break counts. load_state needs an object built from the same
  // elements and properties.
  void save_state(StateWriter& w) const;
  void load_state(StateReader& r);
  template <class IO>
  void state_io(IO& io);  // the one list of fields behind both (IO = StateWriter or StateReader)

 private:
  std::vector<CohesiveElement> elems_;
  std::vector<CohesiveProps> props_;
  bool has_cap_ = false;  // some class has a compressive cap (output of crushing)
  double thickness_;
  int num_nodes_;
  // Per element (index e): law constants (AoS: the general loop reads them all together; plain_ holds its own copy),
  // reference length, history at the 3 points (3e + i), force buffer (8e: a0x a0y a1x a1y b0x b0y b1x b1y), energies.
  std::vector<JointLaw> law_;
  std::vector<double> length_;
  std::vector<double> ref_mid_;        // cold: reference midpoint, 2 per element
  std::vector<PointHistory> history_;
  std::vector<double> force_;
  std::vector<double> energy_;
  std::vector<double> dissipated_;
  std::vector<double> friction_;  // J per element, keep_friction sliders
  std::vector<double> break_DI_, break_DII_;
  std::vector<std::uint8_t> pending_;  // 1: fully damaged at the last add_forces, not yet removed
  std::vector<std::uint8_t> broken_;
  std::vector<int> active_;            // intact elements, ascending (inserted ones only, for extrinsic classes)
  std::vector<std::uint8_t> dormant_;  // 1: extrinsic element not inserted yet
  std::vector<double> offset_;         // o_0, s_0 per element (m): the separation at insertion (0 for intrinsic)
  int dormant_count_ = 0;
  double inserted_ = 0.0;              // J, sum of the pre-peak energies of the inserted elements
  int pending_count_ = 0;
  // Node -> contributions gather (CSR over the intact elements): for row r, node gather_node_[r] sums force_[gather_slot_[k]] (x) and
  // force_[gather_slot_[k] + 1] (y) for k in [gather_start_[r], gather_start_[r+1]), slots in element order.
  std::vector<int> gather_node_, gather_start_, gather_slot_;
  std::size_t stale_slots_ = 0;  // slots of elements broken since the last build_gather()
  void build_gather();
  // The force loop's view of the intact elements, grouped by law (derived from active_, elems_ and law_; rebuilt by
  // build_hot() whenever active_ changes, never saved). plain_: the intact elements of intrinsic classes with the
  // [K25] law and neither keep_friction nor a compressive cap, in active_ order (detail::PlainJoint); other_: the
  // remaining intact elements (composite, mohr_coulomb, keep_friction, cap, extrinsic), in active_ order, evaluated by
  // the general point laws.
  std::vector<detail::PlainJoint> plain_;
  std::vector<int> other_;
  int lanes_ = 8;
  bool plain_law(int e) const;  // whether intact element e belongs in plain_
  void build_hot();
  BreakCounts counts_;
  // law = "composite" (composite_law.hpp): composite_index_[e] >= 0 indexes composite_law_ and the 3 points
  // composite_history_[3 ci + i] of a composite element; -1 for the [K25] law (law_, history_ alone).
  std::vector<int> composite_index_;
  std::vector<CompositeLaw> composite_law_;
  std::vector<CompositeHistory> composite_history_;
};

// cracks.csv: one row per broken element.
void write_cracks_csv_header(std::ostream& os);
void write_cracks_csv_row(std::ostream& os, const BreakRecord& r);

}  // namespace fdem::fracture
