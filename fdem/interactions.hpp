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

    // Stable step bound of joint and contact springs (s); +inf when there are none.
    double stable_dt(const Model& model) const;
    // Whether the next add_forces must evaluate the contact energy (it costs a polygon clip per active pair).
    void want_energy(bool on) {
        if (contact_) contact_->set_compute_energy(on);
    }
    // Adds joint and contact forces (N) at positions x, velocities v, to f.
    void add_forces(const double* x, const double* v, double dt, double* f);
    // After the update: removes broken joints, makes their triangles contact-capable, records them.
    // Returns the number of joints that broke.
    int after_step(double time, double control_displacement, const double* x);

    double joint_energy() const;        // J
    double contact_energy(const double* x_n) const;  // J, at x_n (the positions of the last force evaluation)
    double fracture_dissipation() const;  // J
    double friction_dissipation() const;  // J
    const fracture::BreakCounts* counts() const { return joints_ ? &joints_->counts() : nullptr; }
    const std::string& cracks_csv() const { return cracks_csv_; }
    const contact::ContactSystem* contact() const { return contact_.get(); }
    const fracture::CohesiveSystem* joints() const { return joints_.get(); }

private:
    std::unique_ptr<contact::ContactSystem> contact_;
    std::unique_ptr<fracture::CohesiveSystem> joints_;
    std::string cracks_csv_;
};

}  // namespace fdem
