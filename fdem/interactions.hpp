// fdem/interactions.hpp: the engine's side of the contact and fracture modules: builds them from the case
// and the model, calls them in the step, hands broken joints over to contact, keeps the damage records.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "contact/contact_system.hpp"
#include "fdem/case.hpp"
#include "fdem/model.hpp"
#include "fracture/cohesive_system.hpp"

namespace fdem {

class Interactions {
public:
    Interactions() = default;
    // Builds contact when the case has dry interfaces, bonded interfaces or cracking materials, and cohesive
    // elements when the topology produced some. Throws InputError for laws the modules reject (naming the case key).
    Interactions(const CaseSpec& spec, const Model& model);

    bool has_contact() const { return contact_ != nullptr; }
    bool has_joints() const { return joints_ != nullptr; }

    // Stable step bound of joint and contact springs (s); +inf when there are none. With contact dashpots at a
    // fraction xi_contact of critical on the stiffest contact spring and local damping alpha, the contact bound is
    // multiplied by the damped central-difference factor damped_step_factor(xi, alpha) (fdem/model.hpp; at alpha = 0
    // dt <= (2 / omega)(sqrt(1 + xi^2) - xi), Belytschko, Liu & Moran, Nonlinear Finite Elements for Continua and
    // Structures, 2000, §6.3), the joints' by damped_step_factor(0, alpha).
    // mass, rep (optional): the nodal masses to use instead of the model's, and a representative per node for nodes
    // that move as one (tied copies: mass holds the group's mass; fracture/cohesive_system.hpp).
    double stable_dt(const Model& model, double xi_contact = 0.0, const double* mass = nullptr, const int* rep = nullptr,
                     double alpha = 0.0) const;
    // The springs' share of the assembled system's nodal bound: adds to k_joint and k_contact (per node, or per
    // representative with rep) the Gershgorin row sums of the intact joints and of the contact springs (N/m), each
    // divided by damped_step_factor(xi, alpha)^2: xi_contact of critical for the contact's dashpots, 0 for the
    // joints', alpha the local damping. The contact springs counted are those of the edges near a candidate partner
    // at the last detection, at that pair's law (ContactSystem::node_stiffness: every spring that can load before
    // the next detection; refresh_contact keeps the list current), or with every_face those of every edge that is or
    // may become a face at the stiffest law its material can meet (a bound for the whole run, as a fixed step or the
    // masses of per-node scaling need).
    void add_node_stiffness(const Model& model, double xi_contact, double alpha, const int* rep, double* k_joint,
                            double* k_contact, bool every_face = false) const;
    // Runs the contact detection the next add_forces(x, v, dt, ..., v2max) would run first (ContactSystem::prepare);
    // true when it brought an edge or a law into the count that the list before had not (the step must be bounded
    // again).
    bool refresh_contact(const double* x, const double* v, double dt, double v2max) {
        return contact_ && contact_->prepare(x, v, dt, v2max);
    }
    // The contact list is stale (nodes were moved other than by the step): the next refresh or step detects.
    void invalidate_contact() {
        if (contact_) contact_->invalidate();
    }
    // Undamped stable step of the contact springs alone (s), +inf without contact: beta = xi * this.
    double contact_stable_dt(const Model& model, const double* mass = nullptr) const;
    void set_contact_dashpot(double beta_s) {
        if (contact_) contact_->set_dashpot(beta_s);
    }
    double contact_damping_dissipation() const { return contact_ ? contact_->dashpot_dissipation() : 0.0; }  // J
    // Which thread adds the contact forces of each node (contact::ContactSystem::set_node_owner).
    void set_node_owner(std::vector<unsigned char> owner, int parts) {
        if (contact_) contact_->set_node_owner(std::move(owner), parts);
    }
    // Whether the next add_forces must evaluate the contact energy (it costs a polygon clip per active pair).
    void want_energy(bool on) {
        if (contact_) contact_->set_compute_energy(on);
    }
    // Extrinsic insertion (fracture/cohesive_system.hpp): whether some elements are still dormant, and the check of
    // one step: the Cauchy stress of the two triangles of every dormant element at positions x (tri_sigma: 3 per
    // triangle, xx yy xy, Pa; their mean is the stress the tied continuum carries across the edge) gives the traction
    // (sigma, tau) in the element's frame; the elements whose traction reached the law's peak surface are inserted.
    // Only the edges of triangles whose stress may reach the strengths are computed (fracture::far_from_peak_surface
    // decides the others per triangle); the same elements are inserted as with every edge computed. Returns how many
    // were.
    bool has_dormant() const { return joints_ && joints_->dormant_count() > 0; }
    int insert_cracks(const double* x, const double* tri_sigma);
    double inserted_energy() const { return joints_ ? joints_->inserted_energy() : 0.0; }  // J
    // Adds joint and contact forces (N) at positions x, velocities v, to f.
    // after_joints (energy audit): receives the n values of f after the cohesive joints added theirs, before contact.
    // v2max: the largest |v|^2 over the nodes when the caller has it, else -1 (ContactSystem::step).
    void add_forces(const double* x, const double* v, double dt, double* f, double* after_joints = nullptr,
                    std::size_t n = 0, double v2max = -1.0);
    // After the node update, with v^{n+1/2}: the contact dashpots' books (ContactSystem::finish_step).
    void finish_step(const double* v) {
        if (contact_) contact_->finish_step(v);
    }
    // After the update: removes broken joints, makes their triangles contact-capable, records them.
    // Returns the number of joints that broke.
    int after_step(double time, double control_displacement, const double* x);

    double joint_energy() const;        // J
    double contact_energy(const double* x_n) const;  // J, at x_n (the positions of the last force evaluation)
    double fracture_dissipation() const;  // J
    double friction_dissipation() const;  // J
    const fracture::BreakCounts* counts() const { return joints_ ? &joints_->counts() : nullptr; }
    const std::string& cracks_csv() const { return cracks_csv_; }

    // Dry joint record. Dry joints have no cohesive element, so a rocking or sliding mechanism would leave nothing
    // in cracks.csv; each dry joint segment is followed instead: the relative displacement of its two sides at each
    // end, d = x_B - x_A (the sides coincide in the reference configuration), split along the side-A edge tangent s
    // and the normal n pointing from A into B. A segment gets one cracks.csv row (class interface-dry, mode open)
    // the first time max(d0.n, d1.n) > open_threshold, and one (mode slip) the first time |(d0.s + d1.s)/2| >
    // slip_threshold; D_I, D_II hold those two ratios at detection. Thresholds in m.
    void set_dry_record(double open_threshold, double slip_threshold) { open_thr_ = open_threshold, slip_thr_ = slip_threshold; }
    bool has_dry_joints() const { return !dry_.empty(); }
    int dry_joint_count() const { return static_cast<int>(dry_.size()); }
    // Checks every segment at positions x; appends the first openings and slips to the crack record. Returns the
    // number of new rows.
    int record_dry_joints(double time, double control_displacement, const double* x);
    // Current opening and slip of a dry segment or a cohesive element's edge (same definition), m.
    static void joint_motion(const int* n, const double* x, double& opening, double& slip);
    const std::vector<mesh::CohesiveElement>& dry_joints() const { return dry_; }
    bool dry_recorded(int e) const { return dry_open_[e] || dry_slip_[e]; }
    long long dry_open_count() const { return n_open_; }
    long long dry_slip_count() const { return n_slip_; }
    double open_threshold() const { return open_thr_; }
    double slip_threshold() const { return slip_thr_; }
    const contact::ContactSystem* contact() const { return contact_.get(); }
    const fracture::CohesiveSystem* joints() const { return joints_.get(); }

    // Checkpoint (fdem/common/state_io.hpp): the crack record, the dry joint record, then the contact and cohesive systems'
    // own states. load_state needs an object built from the same case and model.
    void save_state(StateWriter& w) const;
    void load_state(StateReader& r);
    template <class IO>
    void state_io(IO& io);  // the one list of fields behind both (IO = StateWriter or StateReader)

    // One line per class whose penalty = "auto" was resolved and per inelastic dry interface (for the log).
    const std::vector<std::string>& penalty_notes() const { return auto_notes_; }

private:
    // The constructor's parts, in order (fdem/interactions.cpp).
    void setup_dry_joints(const CaseSpec& spec, const Model& model);
    void setup_joints(const CaseSpec& spec, const Model& model, std::vector<double>& crack_penalty,
                      std::vector<double>& bond_penalty);
    void setup_contact(const CaseSpec& spec, const Model& model, const std::vector<double>& crack_penalty,
                       const std::vector<double>& bond_penalty);

    std::vector<std::string> auto_notes_;
    std::unique_ptr<contact::ContactSystem> contact_;
    std::unique_ptr<fracture::CohesiveSystem> joints_;
    std::string cracks_csv_;
    std::vector<int> dormant_;         // dormant elements, ascending (listed on the first check and after insertions)
    // What the insertion check reads of each entry of dormant_, side by side (the elements' and laws' records are
    // large and the check runs every step over all of them): its triangles and edge nodes, f_t, c, tan(phi).
    struct DormantEdge {
        int tri_a, tri_b, n0, n1;
        double tensile_strength, cohesion, tan_friction;  // Pa, Pa, -
    };
    std::vector<DormantEdge> dormant_edge_;
    bool dormant_listed_ = false;
    std::vector<std::uint8_t> due_;    // per entry of dormant_: reached the strength this step
    std::vector<double> due_traction_; // sigma, tau per entry of dormant_ (Pa)
    // Per triangle index: the smallest f_t and c (Pa) of the dormant edges it borders (2 per triangle), and whether
    // its stress may reach them this step (insert_cracks); dormant_tri_: the triangles that border one, ascending.
    std::vector<double> tri_strength_;
    std::vector<std::uint8_t> near_;
    std::vector<int> dormant_tri_;
    void list_dormant();
    std::vector<mesh::CohesiveElement> dry_;
    std::vector<char> dry_open_, dry_slip_;
    std::vector<double> dry_len_, dry_ref_mid_;  // m: reference length and midpoint (2 per segment)
    std::vector<double> dry_motion0_;            // m: opening and slip in the reference state (2 per segment)
    double open_thr_ = 1e-4, slip_thr_ = 1e-4;   // m
    long long n_open_ = 0, n_slip_ = 0;
};

}  // namespace fdem
