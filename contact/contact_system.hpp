// contact/contact_system.hpp: the contact module as the engine sees it: NBS detection when the buffer is used up,
// distributed-potential normal forces, Coulomb friction with history, energies and statistics.
//
// DATA LAYOUT
//   Mesh (constant): tri[3 n_tri] node indices, counter-clockwise; tri_material[n_tri], tri_body[n_tri].
//   State passed in each step (owned by the engine): x[2 n_nodes] positions (m), v[2 n_nodes] velocities (m/s),
//   f[2 n_nodes] forces (N) to which contact forces are ADDED; node k at (2k, 2k+1).
//   Pairs (structure of arrays, index p): pair_a[p] < pair_b[p] triangle indices, pair_law[p] index into the
//   resolved law table, hist[kHistPerPair p] friction state (slots as in potential.hpp), pair_hist_on[p] bit s
//   set when slot s of hist may hold something (0: all zero, nothing to forget or read). Per law: law_prm[l], the pair kernel's parameters
//   resolved once per step (they depend on the law, dt and the dashpot only). Per-pair scratch
//   (forces 12 p, energies) is written by one thread per pair in parallel (each thread a contiguous share of the
//   blocks of pairs); the forces are then added in pair order, each node's by one thread (set_node_owner), and the
//   energies summed per block in pair order, then over the blocks in order: the same bits for any thread count.
//   "No index" is -1.
//
// HOW THE ENGINE USES IT
//   ContactLaws laws(n_classes);             // a "material" here is any integer class: the region index works
//   laws.set_interface(ra, rb, law);         // dry interface / broken bond between two bodies of classes ra, rb
//   laws.set_crack(r, law);                  // faces of a crack inside one body (residual friction); optional,
//                                            // defaults to the interface law (r, r)
//   ContactSystem cs(tri, n_tri, n_nodes, t, tri_class, tri_body, laws);   // throws std::invalid_argument
//   cs.set_capable(e, true) for free-boundary / dry-interface triangles; cs.exclude_pair(ea, eb) for the two
//   triangles of every intact cohesive element; when it breaks: include_pair + set_capable on both, and
//   release_vertex_of(k) for its nodes k (see set_vertex_copies).
//   dt = min(dt_triangles, cs.stable_dt(x, node_mass)) * safety.
//   each step, after zeroing f and before the update: cs.step(x, v, dt, f)  (adds contact forces); after the
//   update, with v^{n+1/2}: cs.finish_step(v) (the dashpots' books; nothing to do without dashpots).
//   energies: cs.elastic_energy() (J, set_compute_energy(true) on the steps that report it),
//   cs.friction_dissipation() (J, cumulative). For reaction monitors, pass a zeroed array instead of f and add.
#pragma once

#include <cstdint>
#include <vector>

#include "contact/contact_law.hpp"
#include "contact/nbs.hpp"
#include "contact/potential.hpp"
#include "fdem/common/state_io.hpp"

namespace fdem::contact {

struct ContactOptions {
    double buffer = 0.0;  // NBS buffer (m); 0 = smallest edge of all triangles / 5 at first use
    // Evaluate the normal contact energy each step (one polygon clip per loaded pair, ~15 % of the force time).
    // The engine may switch it on only for the steps it reports energies (set_compute_energy); the friction
    // dissipation and tangential energy are always accumulated.
    bool compute_energy = true;
};

struct ContactStats {
    long long detections = 0;      // NBS runs so far
    int candidate_pairs = 0;       // pairs in the current list
    int active_pairs = 0;          // pairs that carried load in the last step
    long long pair_evaluations = 0;  // candidate pairs evaluated, cumulative
    double time_detection = 0.0;   // s, cumulative wall time in detection
    double time_forces = 0.0;      // s, cumulative wall time in the force evaluation and scatter
    double time_scatter = 0.0;     // s, the part of time_forces adding pair forces in pair order (each thread its nodes)
};

class ContactSystem {
public:
    // thickness: out-of-plane thickness t (m). Throws std::invalid_argument when a law is invalid or missing for
    // a material combination present in the mesh (the message names the law or the materials).
    ContactSystem(const int* tri, int n_tri, int n_nodes, double thickness, std::vector<int> tri_material,
                  std::vector<int> tri_body, const ContactLaws& laws, ContactOptions options = {});

    // Contact-capable set (starts empty): free boundary, dry interface, broken joint. Changing it forces a
    // re-detection at the next step.
    void set_capable(int t, bool capable);
    bool capable(int t) const { return capable_[t] != 0; }
    // Triangles joined by an intact cohesive element never form a pair; include_pair when it breaks.
    void exclude_pair(int ta, int tb);
    void include_pair(int ta, int tb);
    // Copies of one mesh vertex (mesh/README.md 'Topology' duplicates a node wherever a crack may open; triangles sharing a node
    // never form a pair). vertex[k], one per node (or empty: off, the default), is the mesh vertex node k is a
    // copy of. Two triangles of one body that meet only at copies of a vertex (corner neighbours inside a crackable
    // unit) then form no pair until release_vertex_of(k) is called for a copy k of that vertex, which the engine
    // does for the nodes of every cohesive element that breaks. Without it, the corners of intact neighbours
    // overlap as the cohesive elements between them compress and carry contact forces that the continuum already
    // carries (in the dry-stone walls, a third of the loaded pairs). Triangles of different bodies are not affected.
    void set_vertex_copies(std::vector<int> vertex);
    void release_vertex_of(int node);

    // fdem/README.md 'Time step': min over nodes of 2 sqrt(m / k), m the node's mass (kg), k its Gershgorin row sum: over
    // the edges at the node that are or may become faces (all but the edges inside a continuum; any triangle may
    // become capable), (stiffest normal or tangential slope of the laws the triangle's material can meet, Pa/m) *
    // t * (edge length). x: positions (m) for the element sizes.
    double stable_dt(const double* x, const double* node_mass) const;
    // k of stable_dt per node (N/m): over the edges at the node that are or may become faces, the stiffest slope
    // the triangle's material can meet times t times the edge's length (the engine adds it to the triangles' and
    // joints' row sums for the step of the assembled system). held (optional): per triangle, bit e set when its edge e
    // (from node e to node e + 1) is held by an intact cohesive element, which keeps it out of contact until it breaks.
    // candidates: only the edges that were within the buffer of a candidate partner at the last detection (prepare
    // or step; near_law_), each with the slopes of those pairs' laws. A penalty spring loads only while its edge
    // overlaps the partner or the partner's faces cross it, the buffer keeps every pair that can overlap before the
    // next detection in the list, and each point moves at most half the buffer until then, so this count holds
    // every contact spring that can load until the next detection; false: every edge that is or may become a face,
    // with the stiffest law its material can meet, whatever the list (a bound for the whole run).
    std::vector<double> node_stiffness(const double* x, const std::uint8_t* held = nullptr,
                                       bool candidates = false) const;

    // One step: re-detects when 2 * (sum of dt max|v| since the last detection) would exceed the buffer, then
    // evaluates all pairs and adds the contact forces (N) to f. dt in s. v2max >= 0: the caller's largest |v|^2 over
    // the nodes (m^2/s^2; vx * vx + vy * vy, NaN passed over), which it had at hand (Simulation's node loop, which
    // wrote v); else the nodes are scanned for it here. Either way the same bits.
    void step(const double* x, const double* v, double dt, double* f, double v2max = -1.0);
    // The detection step(x, v, dt, f, v2max) would run first, run now (the faces brought up to date, then NBS when
    // the list is stale or 2 * (travel + dt max|v|) would exceed the buffer), so that a caller can bound its step by
    // the new list before the step that uses it; step() then finds nothing left to do. Returns true when the
    // detection set a bit of near_law_ that the one before had not.
    bool prepare(const double* x, const double* v, double dt, double v2max = -1.0);
    void set_compute_energy(bool on) { opt_.compute_energy = on; }
    // Contact dashpots ([C79]'s viscous contact damping, made stiffness-proportional like Rayleigh beta damping;
    // PairParams::beta, s; 0 = none, the default): c = beta k on every loaded edge, normal and,
    // while it sticks, tangential. beta = xi dt_c damps the stiffest contact spring (stable step dt_c = 2 / omega)
    // at a fraction xi of critical and a mode of frequency omega at xi omega dt_c / 2: the contact chatter of the
    // explicit step is damped, a mechanism moving at a quasi-static rate is not.
    void set_dashpot(double beta_s) { beta_ = beta_s; }
    // The dashpots' work over a step is booked as the engine books every other force's, -dt f_d . vbar with
    // vbar = (v^{n-1/2} + v^{n+1/2}) / 2 (fdem/step.cpp): step() books the half on v^{n-1/2}, which it has, and
    // keeps each loaded pair's dashpot forces; finish_step(v), called with v^{n+1/2} once the nodes are updated,
    // works out the half on v^{n+1/2}, booked when the next step starts, so dashpot_dissipation() is always the work
    // up to t^n, the time of the last step's forces, as the rest of the books.
    void finish_step(const double* v);
    double dashpot_dissipation() const { return damping_; }  // J, cumulative, to t^n
    // Forces a detection at the next step (e.g. after the engine moved nodes by other means).
    void invalidate() { dirty_ = true; }
    // Which thread of a parallel step adds the contact forces of node k: owner[k] in 0..parts-1 (the engine gives
    // the threads' shares of its node loop, so each thread's forces are written where that thread reads them next).
    // Only where the writes happen depends on it, never the result: every node's forces are added by one thread in
    // pair order. Without it, or for another thread count, node k goes to thread k * T / n_nodes.
    void set_node_owner(std::vector<unsigned char> owner, int parts) {
        owner_ = std::move(owner);
        owner_parts_ = parts;
        own_threads_ = 0;  // the pairs' node masks follow
    }

    // J, at the last step (the normal part only if that step computed energies, else 0)
    double elastic_energy() const { return energy_normal_ + energy_tangential_; }
    // Whether the last step evaluated the normal energy (set_compute_energy was on); if not, normal_energy_at
    // gives it for positions x (m) and the current pairs, without touching any state (serial; for reports).
    bool normal_energy_current() const { return energy_current_; }
    double normal_energy_at(const double* x) const;
    // Every loaded face of the current pairs at positions x (m) and velocities v (m/s), as the next step of length
    // dt (s) would load it (the pair kernel on a copy of each pair's friction history: nothing changes; serial; for
    // snapshots): the owner triangle, its edge (from node e to node e + 1), the triangle it enters and the record. Each contact is
    // carried by both faces, half each, so a face and the faces of the other body across it both appear.
    struct LoadedEdge {
        int triangle, edge;  // the owner triangle and its loaded edge
        int other;           // the triangle it enters
        EdgeRecord record;
    };
    std::vector<LoadedEdge> loaded_edges(const double* x, const double* v, double dt) const;
    double normal_energy() const { return energy_normal_; }                        // J
    double tangential_energy() const { return energy_tangential_; }                // J
    double friction_dissipation() const { return dissipation_; }                   // J, cumulative
    const ContactStats& stats() const { return stats_; }
    double buffer() const { return buffer_; }
    // The buffer the next detection uses for positions x (m): the one in use, else the option, else the default
    // (smallest edge of all triangles / 5). For the log before the first step; changes nothing.
    double effective_buffer(const double* x) const;

    // Read access for monitors and tests.
    const std::vector<int>& pair_a() const { return pair_a_; }
    const std::vector<int>& pair_b() const { return pair_b_; }
    const std::vector<double>& sliding_history() const { return hist_; }  // kHistPerPair per pair

    // Checkpoint (fdem/common/state_io.hpp): everything that carries from one step to the next: the contact-capable set,
    // excluded pairs and released vertices, the detection schedule (buffer, travel, dirty), the pair list with its
    // friction history (stick anchors and slips, kHistPerPair per pair), the energies and dissipations, the dashpot
    // coefficient and the counters. Not the wall-clock timings. load_state needs an object built from the same mesh.
    void save_state(StateWriter& w) const;
    void load_state(StateReader& r);
    template <class IO>
    void state_io(IO& io);  // the one list of fields behind both (IO = StateWriter or StateReader)

private:
    void update_faces();
    void detect(const double* x);
    void set_pair_nodes();  // pair_nodes_ from the pair list; the masks to be made again
    int law_of(int ta, int tb) const;
    // The pair kernel's parameters of every law for a step of dt (s); true when some law needs the altitudes.
    bool resolve_params(double dt, std::vector<PairParams>& prm_of) const;

    const int* tri_;
    int n_tri_, n_nodes_;
    double thickness_;  // m
    std::vector<int> material_, body_;
    ContactOptions opt_;
    int n_mat_ = 0;
    std::vector<int> interface_law_;  // n_mat^2 -> law index
    std::vector<int> crack_law_;      // n_mat -> law index
    std::vector<ResolvedLaw> laws_;

    std::vector<char> capable_;
    std::vector<std::vector<int>> excluded_;  // per triangle, partners joined by an intact cohesive element
    // Faces (TriangleGeometry::faces): per triangle, bit e set when edge e can carry contact load. continuum_faces_:
    // the edges no other triangle shares by both nodes (set at construction); faces_: those, less the edges an
    // excluded partner of the same body (intact cohesive element inside a unit) shares by both vertices. Derived,
    // recomputed when faces_dirty_.
    std::vector<unsigned char> continuum_faces_, faces_;
    bool faces_dirty_ = true;
    std::vector<int> vertex_;                 // per node: the mesh vertex it copies (empty: no vertex rule)
    std::vector<char> released_;              // per vertex: a cohesive element at it broke
    bool dirty_ = true;
    double buffer_ = 0.0;        // m
    double travel_ = 0.0;        // m, sum of dt max|v| since the last detection

    std::vector<int> pair_a_, pair_b_, pair_law_;
    // Per triangle edge (3 t + e): the laws of the candidate partners it was within the buffer of at the last
    // detection, law l as bit min(l, 63) (from the positions then: saved); scratch for the next; and whether the last
    // detection set a bit the one before had not.
    std::vector<std::uint64_t> near_law_, near_law_new_;
    bool candidates_grew_ = false;
    // The detection when the list is stale or this step's motion would exceed the buffer (step, prepare).
    void detect_if_due(const double* x, double dt, double vmax);
    std::vector<double> hist_;  // kHistPerPair per pair
    // scratch
    std::vector<char> pair_hist_on_;  // per pair: bit s set when slot s of hist_ may be nonzero (derived, not saved)
    std::vector<PairParams> law_prm_;  // per resolved law: PairParams for this step's dt and dashpot
    std::vector<int> items_;
    std::vector<double> cx_, cy_, cr_;  // per capable triangle at the last detection: bounding circles (m)
    std::vector<char> keep_;
    std::vector<int> new_a_, new_b_, csr_start_, csr_order_, csr_fill_;
    std::vector<double> new_hist_;
    std::vector<char> new_hist_on_;
    CandidatePairs cand_;
    NbsWorkspace ws_;
    std::vector<double> pair_f_;   // 12 per pair
    std::vector<double> pair_fd_;  // 12 per pair, with dashpots: their part of pair_f_ (for finish_step)
    std::vector<double> pair_e_;   // 4 per pair: normal energy, tangential energy, friction dissipation, dashpot work
    std::vector<char> pair_on_;
    // Per thread t, its scatter lists: for each block of pairs the loaded pairs with some of the nodes t adds, in pair
    // order (list_idx_[t * n_pairs + first pair of the block + i]; list_cnt_[t * n_blocks + block] of them).
    std::vector<int> list_idx_, list_cnt_;
    // Per block of pairs, its energy sums in pair order (normal, tangential, friction, dashpots) and its loaded pairs.
    std::vector<double> block_e_;
    std::vector<int> block_active_;
    // Per block of pairs, its cost in the last step (pairs, and queued pairs weighted), and per thread the first block
    // of its share (then the end): which core evaluates which pairs, not what they give (not saved by save_state).
    std::vector<int> block_cost_, block_share_;
    std::vector<unsigned char> owner_;  // per node: the thread that adds its forces (set_node_owner), for owner_parts_
    int owner_parts_ = 0;
    // Per pair, for the scatter: its six nodes (A's, then B's), and per thread t the bits of those that t adds
    // (pair_mask_[t * n_pairs + p]), for own_threads_ threads (0: to be made; detection and set_node_owner reset it).
    std::vector<int> pair_nodes_;
    std::vector<unsigned char> pair_mask_;
    int own_threads_ = 0;
    std::vector<double> box_;      // 8 per triangle, capable ones, this step: xmin, xmax, ymin, ymax (m) of the
                                   // triangle, then of its faces' end points (empty without faces)
    std::vector<TriangleGeometry> geom_;  // per triangle, capable ones, this step: what the pair kernel needs
    // per thread: a block's pairs in their batch, and those pending in it (on lines of its own: the batch's counters
    // change with every pair)
    struct alignas(128) PairScratch {
        PairBatch batch;
        std::vector<int> pending;
        std::vector<int> listed;  // per thread of the team: how many pairs of the block are on its scatter list
    };
    std::vector<PairScratch> scratch_;

    double energy_normal_ = 0.0, energy_tangential_ = 0.0, dissipation_ = 0.0, damping_ = 0.0;
    double beta_ = 0.0;  // s
    // Dashpots' books (finish_step): the last step's dt (s) when its pairs' dashpot forces await finish_step (else
    // 0), and the half of that step's dashpot work on v^{n+1/2} (J) that the next step books.
    double dashpot_dt_ = 0.0, damping_next_ = 0.0;
    bool inelastic_ = false;  // some law has a restitution below 1 (its hysteresis is booked like the dashpots)
    std::vector<double> block_fd_;  // per block of pairs: its share of finish_step's sum
    bool energy_current_ = true;
    ContactStats stats_;
};

}  // namespace fdem::contact
