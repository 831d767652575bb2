// contact/contact_law.cpp: validation of contact laws (units in contact_law.hpp).
#include "contact/contact_law.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace fdem::contact {

ContactLaw ContactLaw::penalty(double p_n_Pa, double mu_, double p_t_Pa) {
    ContactLaw law;
    law.p_n = p_n_Pa;
    law.mu = mu_;
    law.p_t = p_t_Pa;
    return law;
}

ContactLaw ContactLaw::stiffness(double k_n_Pa_per_m, double k_s_Pa_per_m, double phi_degrees) {
    ContactLaw law;
    law.k_n = k_n_Pa_per_m;
    law.k_s = k_s_Pa_per_m;
    law.phi_deg = phi_degrees;
    return law;
}

namespace {

[[noreturn]] void bad(const ContactLaw& law, const std::string& what, double value) {
    std::ostringstream os;
    os << "contact law '" << (law.name.empty() ? std::string("(unnamed)") : law.name) << "': " << what
       << " (got " << value << ")";
    throw std::invalid_argument(os.str());
}

// A key counts as "given" when it is not the default 0 (penalties) / negative (friction).
void check_positive(const ContactLaw& law, const char* key, const char* unit, double v) {
    if (!std::isfinite(v) || v < 0.0)
        bad(law, std::string(key) + " must be a positive number in " + unit, v);
}

}  // namespace

ResolvedLaw resolve_law(const ContactLaw& law) {
    ResolvedLaw r;
    check_positive(law, "p_n", "Pa", law.p_n);
    check_positive(law, "k_n", "Pa/m", law.k_n);
    check_positive(law, "p_t", "Pa", law.p_t);
    check_positive(law, "k_s", "Pa/m", law.k_s);
    if (law.p_n > 0.0 && law.k_n > 0.0) bad(law, "give either p_n (Pa) or k_n (Pa/m), not both; k_n", law.k_n);
    if (law.p_n == 0.0 && law.k_n == 0.0)
        bad(law, "a normal penalty p_n (Pa) or stiffness k_n (Pa/m) > 0 is required; p_n", law.p_n);
    if (law.p_t > 0.0 && law.k_s > 0.0) bad(law, "give either p_t (Pa) or k_s (Pa/m), not both; k_s", law.k_s);
    r.normal_is_stiffness = law.k_n > 0.0;
    r.normal = r.normal_is_stiffness ? law.k_n : law.p_n;
    if (law.p_t > 0.0) {
        r.tangential_is_stiffness = false;
        r.tangential = law.p_t;
    } else if (law.k_s > 0.0) {
        r.tangential_is_stiffness = true;
        r.tangential = law.k_s;
    } else {  // not given: same as normal, in the normal's units
        r.tangential_is_stiffness = r.normal_is_stiffness;
        r.tangential = r.normal;
    }
    const bool has_mu = !std::isnan(law.mu);
    const bool has_phi = !std::isnan(law.phi_deg);
    if (has_mu && has_phi) bad(law, "give either mu or the friction angle, not both; mu", law.mu);
    if (has_mu) {
        if (!std::isfinite(law.mu) || law.mu < 0.0) bad(law, "friction coefficient mu must be >= 0", law.mu);
        r.mu = law.mu;
    } else if (has_phi) {
        if (!std::isfinite(law.phi_deg) || law.phi_deg < 0.0 || law.phi_deg >= 90.0)
            bad(law, "friction angle must be in [0, 90) deg", law.phi_deg);
        r.mu = std::tan(law.phi_deg * M_PI / 180.0);
    } else {
        r.mu = 0.0;
    }
    if (!(law.restitution > 0.0 && law.restitution <= 1.0))
        bad(law, "the coefficient of restitution must be in (0, 1]", law.restitution);
    r.restitution = law.restitution;
    return r;
}

ContactLaws::ContactLaws(int n_materials)
    : n_materials_(n_materials),
      interface_(static_cast<size_t>(n_materials) * n_materials),
      interface_set_(static_cast<size_t>(n_materials) * n_materials, 0),
      crack_(n_materials),
      crack_set_(n_materials, 0) {
    if (n_materials < 0) throw std::invalid_argument("ContactLaws: negative number of materials");
}

void ContactLaws::set_interface(int a, int b, const ContactLaw& law) {
    if (a < 0 || b < 0 || a >= n_materials_ || b >= n_materials_)
        throw std::invalid_argument("ContactLaws::set_interface: material index out of range");
    resolve_law(law);  // fail early, where the case loader can still name the key
    interface_[a * n_materials_ + b] = law;
    interface_[b * n_materials_ + a] = law;
    interface_set_[a * n_materials_ + b] = interface_set_[b * n_materials_ + a] = 1;
}

void ContactLaws::set_crack(int m, const ContactLaw& law) {
    if (m < 0 || m >= n_materials_) throw std::invalid_argument("ContactLaws::set_crack: material index out of range");
    resolve_law(law);
    crack_[m] = law;
    crack_set_[m] = 1;
}

void ContactLaws::set_default(const ContactLaw& law) {
    resolve_law(law);
    default_ = law;
    default_set_ = true;
}

const ContactLaw* ContactLaws::interface(int a, int b) const {
    if (a >= 0 && b >= 0 && a < n_materials_ && b < n_materials_ && interface_set_[a * n_materials_ + b])
        return &interface_[a * n_materials_ + b];
    return default_set_ ? &default_ : nullptr;
}

const ContactLaw* ContactLaws::crack(int m) const {
    if (m >= 0 && m < n_materials_ && crack_set_[m]) return &crack_[m];
    return default_set_ ? &default_ : nullptr;
}

}  // namespace fdem::contact
