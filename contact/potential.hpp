// contact/potential.hpp: distributed-potential contact force and Coulomb friction of one triangle pair
// ([MA00]; [M04] ch. 2; [K25] Eqs. 2-5; fdem/README.md 'Contact'). Pure functions on small fixed arrays, and
// PairBatch, the same kernel run on many pairs at once (their edge integrals side by side).
//
// DATA LAYOUT
//   A triangle is 6 doubles (x0, y0, x1, y1, x2, y2), counter-clockwise, current configuration (m).
//   Velocities likewise (m/s). Forces out: 6 doubles per triangle, node-ordered like the coordinates (N, whole
//   thickness). Friction state: kHistPerPair doubles per pair, kHistPerEdge per slot, slot e = edge e of A (nodes
//   e, e+1) inside B for e = 0..2, slot 3 + e = edge e of B inside A; in a slot: [0] the elastic tangential
//   displacement delta_s (m) of its two stick anchors, [1] the owner's anchor s0 along its edge (0..1), [2..4] the
//   other triangle's anchor in its area coordinates (all zero: no anchor yet), [5] the slot's tangential stiffness
//   k_t (N/m) at its last step, so that its stored energy k_t delta_s^2 / 2 is known when it lets go, [6] the
//   largest push per length q_max (N/m) of an inelastic contact (PairParams::inv_e2; 0 for an elastic one).
//
// THE POTENTIAL
//   [MA00] phi(P) = 3 min_i A_i(P) / A = 3 min_k L_k(P): L_k is the area coordinate of vertex k, i.e. A_i / A for the
//   edge i opposite k. We use the general form phi(P) = min_k w_k L_k(P):
//     penalty law (p_n, Pa):      w_k = 3 (Munjiza's phi, 1 at the centroid), coefficient c = p_n;
//     stiffness law (k_n, Pa/m):  w_k = H_k, the altitude from vertex k (m), so phi(P) is the distance from P to the
//                                 triangle's boundary, coefficient c = k_n / 2. Near a flat face the pressure is
//                                 then (k_n/2) d_A + (k_n/2) d_B = k_n * overlap exactly, whatever the element size:
//                                 this is p_n = k_n H / 6 derived per element edge (issue 4 item 2).
//   Energy of the pair (J):  E = t INT_{A∩B} (c_A phi_A + c_B phi_B) dA.
//   Its derivative for a rigid translation/rotation of A, by the divergence theorem on A∩B (phi_A = 0 on dA,
//   phi_B = 0 on dB), gives the force on A
//       f_A = t [ c_A INT_{dB ∩ A} n_B phi_A dG  -  c_B INT_{dA ∩ B} n_A phi_B dG ],   f_B = -f_A,
//   n_X the outward normal of X. ([MA00] writes f_c = p t INT (grad phi_t - grad phi_c) dA with the opposite
//   sign convention for grad phi; the force here is repulsive, checked against -dE/du in the tests.)
//   Discrete: each edge segment inside the other triangle is split where the minimum in phi changes branch; on each
//   piece phi is linear, so INT N_a phi dG (edge nodes, linear shape functions N) and INT L_k phi dG (the other
//   triangle's nodes, area coordinates) are products of linear functions. All of them follow exactly from the two
//   moments INT phi ds and INT s phi ds along the segment, summed over the pieces from phi's values at the breakpoints.
//   Both ends get the same distributed load at the same points: sum of forces and of moments are zero exactly.
#pragma once

#include <vector>

namespace fdem::contact {

constexpr int kHistPerEdge = 7;                  // doubles of state per loaded-edge slot (friction; impacts)
constexpr int kHistPerPair = 6 * kHistPerEdge;  // per pair (six slots)

struct PairParams {
    double thickness = 0.0;  // out-of-plane thickness t (m)
    double c = 0.0;          // potential coefficient: p_n (Pa) for w = 3, k_n / 2 (Pa/m) for w = H
    bool distance_potential = false;  // false: w_k = 3 (penalty law); true: w_k = H_k (stiffness law)
    double k_s = 0.0;        // tangential stiffness per unit contact area (Pa/m)
    double mu = 0.0;         // friction coefficient (-)
    double dt = 0.0;         // time step (s); the sliding increment is v_rel,t dt
    // Contact dashpots (stiffness-proportional damping of the contact springs; 0 = none): on each loaded edge a
    // normal dashpot c_n = beta k_n,edge and, while the edge sticks, a tangential one c_t = beta k_t, acting on the
    // relative velocity at the edge's centre of pressure. k_n,edge = k_n_area t L / 2 and k_t = k_s t L / 2, L the
    // length of the edge inside the other triangle (each of the two faces carries half the contact).
    double beta = 0.0;       // s
    double k_n_area = 0.0;   // normal pressure per overlap (Pa/m), for the dashpot
    // Penalty laws: when > 0, k_s (and, with beta > 0, k_n_area) are set inside pair_contact, only for pairs that
    // overlap, to the pressure/overlap slope 3 p (1/H_a + 1/H_b) (Pa/m) of the tangential penalty p_t and normal
    // penalty p_n (Pa) ([MA00] phi = 3 min L_k; H the triangles' smallest altitudes). 0: use k_s, k_n_area as given.
    double p_t = 0.0;        // Pa
    double p_n = 0.0;        // Pa
    // Impacts: 1 / e^2 for a coefficient of restitution e < 1 (1: elastic). Walton & Braun (1986), written on each
    // loaded edge's mean push per length of contact q = fn / L (N/m, fn the elastic push of the edge, L its length
    // inside the other triangle; so an edge whose contact only grows or shrinks along the face at a constant depth
    // is not unloading): while q is at its largest value q_max since the edge first touched, the edge carries fn; below
    // it, max(0, q_max - (q_max - q) / e^2) L, the unloading line of slope k / e^2. A contact loaded and unloaded once
    // returns e^2 of the work it took. q_max is the slot's h[6]; it is forgotten when the edge leaves the other
    // triangle. The force the hysteresis removes acts with the normal dashpot's, at the centre of pressure, and its
    // work is booked with the dashpots' (PairResult::damping).
    double inv_e2 = 1.0;     // -
};

struct PairResult {
    double fa[6];               // force on A's nodes (N)
    double fb[6];               // force on B's nodes (N)
    double energy_normal = 0.0;      // t INT (c phi_A + c phi_B) dA (J); only when asked for
    double energy_tangential = 0.0;  // sum 0.5 k_t delta_s^2 over the edges (J)
    double dissipation = 0.0;        // friction work dissipated in this step (J)
    double damping = 0.0;            // work of the dashpots and impacts in this step on v^{n-1/2}, -dt f_d . v (J)
    int active_edges = 0;            // edges carrying a normal force
    unsigned held = 0;               // bit s: friction slot s may hold state after the call (the loaded edges)
};

// One loaded edge of a pair, as the pair kernel loaded it (PairBatch::end's records; for snapshots): the owner's
// face and where its load acts. Slots without load have loaded = false.
struct EdgeRecord {
    bool loaded = false;
    double px = 0.0, py = 0.0;  // centre of pressure on the owner's edge (m)
    double nx = 0.0, ny = 0.0;  // the owner edge's outward normal n_O (its load presses along -n_O)
    double fn = 0.0;            // normal force pressing the faces together, elastic push and dashpot (N, >= 0)
    double ft = 0.0;            // tangential force on the owner along t_O = (-n_y, n_x), spring and dashpot (N)
    double length = 0.0;        // the part of the edge inside the other triangle (m)
    int sliding = -1;           // 1 slid this step, 0 stuck, -1 no friction
};

// A triangle's three nodes' values (2 per node, e.g. positions or velocities) from a node array: out[2k], out[2k+1] of
// node t[k].
inline void gather(const double* x, const int* t, double* out) {
    for (int k = 0; k < 3; ++k) {
        out[2 * k] = x[2 * t[k]];
        out[2 * k + 1] = x[2 * t[k] + 1];
    }
}

// Smallest altitude of a triangle (m): twice its area over its longest edge.
double smallest_altitude(const double* x);

// Potential weights w_k of a triangle (see THE POTENTIAL).
void potential_weights(const double* x, bool distance_potential, double* w);

// What the pair kernel needs of one triangle, for a triangle met by several pairs in one step: computed once by
// triangle_geometry instead of once per pair (the same arithmetic, so the same bits either way).
struct TriangleGeometry {
    double x[6];       // coordinates (m), as in DATA LAYOUT
    double g[9];       // area coordinates as affine functions: L_k(P) = g[3k] + g[3k+1] P.x + g[3k+2] P.y
    double h[3];       // altitude from each vertex onto the opposite edge (m): the distance-potential weights
                       // (NaN when triangle_geometry was told no law needs them)
    double inv_h_min;  // 1 / smallest altitude (1/m)
    // Bit e set: edge e (nodes e, e+1) is a face that can carry contact load. triangle_geometry sets all three; an
    // edge inside a continuum or an intact joint is cleared by the caller (ContactSystem: its loads from the two
    // triangles that share it cancel, and it is not a face that friction can act on).
    int faces = 7;
};
// altitudes = false: h is left NaN (only the distance potential, a stiffness law's, reads it) and inv_h_min is
// computed from the longest edge alone, the same bits at one square root instead of three.
void triangle_geometry(const double* x, TriangleGeometry& out, bool altitudes = true);

// Clears one friction slot (kHistPerEdge doubles) and returns the energy its spring held (J), which the caller
// books as dissipated: a stretched tangential spring that loses its contact lets its energy go.
double release_slot(double* h);

// The force, friction and energies of the pair (A, B). hist[kHistPerPair] is read and updated. Only the edges in
// TriangleGeometry::faces are loaded. Returns true when the triangles interact (some edge carries load); false
// leaves fa = fb = 0 and resets hist to 0. Either way out.dissipation includes the energy of friction springs that
// let go (release_slot), and with want_energy out.energy_normal is the overlap's energy (pair_energy), also when no
// face carries the load (it is carried by the faces of neighbouring pairs).
bool pair_contact(const double* xa, const double* xb, const double* va, const double* vb, const PairParams& p,
                  bool want_energy, double* hist, PairResult& out);
// The same from precomputed triangle geometry. held: bit s clear when slot s of hist is known to be all zero (the
// previous call's out.held), so that slot is not read or written unless its edge is loaded. f12 (optional): the
// forces go there (A's six, then B's six) instead of out.fa, out.fb, and are written only when the triangles
// overlap (out.fa, out.fb are then not touched; f12 is not to be read when the call returns false).
bool pair_contact(const TriangleGeometry& a, const TriangleGeometry& b, const double* va, const double* vb,
                  const PairParams& p, bool want_energy, double* hist, PairResult& out, unsigned held = 0x3f,
                  double* f12 = nullptr);

// pair_contact for many pairs, in three stages, so that the edge integrals of many pairs run side by side, several
// edges per vector instruction (each edge takes the same operations in the same order as alone: the same bits for
// any batch and any vector width). pair_contact itself is these three stages on one pair.
//   for each pair: begin(...)  -> false: settled (apart or faceless), out as pair_contact leaves it
//   integrate()                   the edge integrals of every pending pair
//   for each pair begin kept, in begin's order: end(...) with the same a, b, p, want_energy, hist, held
class PairBatch {
public:
    // Scratch: a copy starts empty (col_ points into the object's own soa_).
    PairBatch() = default;
    PairBatch(const PairBatch&) : PairBatch() {}
    PairBatch& operator=(const PairBatch&) { return *this; }
    // Separating-axis test and the pair's candidate edges (faces of one whose end points' area coordinates in the
    // other are queued). Returns false when the pair needs no edge integral: out and hist are then as pair_contact
    // leaves them when it returns false (out.fa, out.fb zero). True: the pair is pending.
    bool begin(const TriangleGeometry& a, const TriangleGeometry& b, const PairParams& p, bool want_energy,
               double* hist, PairResult& out, unsigned held = 0x3f);
    void integrate();
    // The next pending pair: loads its edges (pair_contact's f12 and return value). fd12 (optional, read only with
    // dashpots, p.beta > 0): the dashpots' part of the forces (A's six, then B's six; written whenever the pair
    // overlaps), so that their work can be booked on the step's mean velocity (ContactSystem::finish_step).
    // records (optional): six EdgeRecords, one per slot (A's edge e at e, B's at 3 + e).
    bool end(const TriangleGeometry& a, const TriangleGeometry& b, const double* va, const double* vb,
             const PairParams& p, bool want_energy, double* hist, PairResult& out, unsigned held = 0x3f,
             double* f12 = nullptr, double* fd12 = nullptr, EdgeRecord* records = nullptr);
    // Forget all pairs and make room for up to max_pairs more (the storage stays).
    void clear(int max_pairs);

    // Vector width of integrate() (edges per instruction): 4 where the processor has AVX2 (chosen when the
    // program starts), else 2 (SSE2, every x86-64). set_lanes(1, 2 or 4) forces one, for tests; returns the old one.
    static int lanes();
    static int set_lanes(int w);

private:
    static constexpr int kColumns = 20;  // per queued edge: 13 inputs, 7 results (potential.cpp)
    int n_edges_ = 0, n_pending_ = 0, next_pending_ = 0, next_edge_ = 0, cap_ = 0;
    std::vector<double> soa_;            // kColumns columns of cap_ edges
    double* col_[kColumns] = {};         // the columns, set by clear()
    std::vector<unsigned char> tested_;  // per pending pair: bit s set when slot s's edge was queued
    std::vector<unsigned char> loaded_;  // per queued edge: it enters the other triangle with load
};

// t INT_{A∩B} (c phi_A + c phi_B) dA (J): the pair's normal contact energy, by polygon clipping.
double pair_energy(const double* xa, const double* xb, const PairParams& p);

// Integrals along the part of segment p0-p1 inside triangle T of phi_T (w): out[0] = INT N0 phi dG,
// out[1] = INT N1 phi dG, out[2..4] = INT L_k phi dG (m^2 when w = 3), out[5] = length inside (m).
// Returns false when the segment does not enter T.
bool edge_in_triangle(const double* p0, const double* p1, const double* T, const double* w, double* out);

}  // namespace fdem::contact
