// contact/contact_law.hpp: the interface laws contact uses, and their validation.
//
// A law is given either by penalties in Pa (the Munjiza / Y-code convention) or by stiffnesses in Pa/m
// (the joint stiffnesses that 3DEC/UDEC studies report), never by a mixture of the two for one direction.
// Units: p_n, p_t in Pa; k_n, k_s in Pa/m; friction as a coefficient mu (-) or an angle phi (deg).
#pragma once

#include <limits>
#include <string>
#include <vector>

namespace fdem::contact {

struct ContactLaw {
    std::string name;           // for error messages, e.g. "interface brick/mortar" or "crack of brick"
    double p_n = 0.0;           // normal penalty (Pa), [MA00]; 0 = not given
    double k_n = 0.0;           // normal stiffness (Pa/m) of the interface; 0 = not given
    double p_t = 0.0;           // tangential penalty (Pa); 0 = not given
    double k_s = 0.0;           // shear stiffness (Pa/m); 0 = not given
    double mu = std::numeric_limits<double>::quiet_NaN();       // Coulomb coefficient (-); NaN = not given
    double phi_deg = std::numeric_limits<double>::quiet_NaN();  // friction angle (deg), mu = tan(phi); NaN = not given
    // Coefficient of restitution of the normal contact, 0 < e <= 1 (1: elastic, the default). Below 1 each loaded
    // edge unloads along a line of slope k / e^2 (Walton & Braun 1986), so an impact returns e^2 of the energy its
    // contact took (potential.hpp, PairParams::inv_e2).
    double restitution = 1.0;

    // A frictionless law with a normal penalty (Pa).
    static ContactLaw penalty(double p_n_Pa, double mu_ = 0.0, double p_t_Pa = 0.0);
    // A law with measured stiffnesses (Pa/m) and friction angle (deg).
    static ContactLaw stiffness(double k_n_Pa_per_m, double k_s_Pa_per_m, double phi_degrees);
};

// The validated law the kernels use: exactly one normal mode, a friction coefficient, a tangential mode.
struct ResolvedLaw {
    bool normal_is_stiffness = false;  // true: k_n given (Pa/m); false: p_n given (Pa)
    double normal = 0.0;               // p_n (Pa) or k_n (Pa/m)
    bool tangential_is_stiffness = false;
    double tangential = 0.0;           // p_t (Pa) or k_s (Pa/m); if neither was given, p_t = p_n or k_s = k_n
    double mu = 0.0;                   // friction coefficient (-)
    double restitution = 1.0;          // e (-), 0 < e <= 1
};

// Checks a law and resolves it. Throws std::invalid_argument naming the law and the offending value for:
// no normal penalty/stiffness, both p_n and k_n, zero/negative/non-finite values, both p_t and k_s,
// negative or non-finite friction, both mu and phi, phi >= 90 deg, a restitution outside (0, 1].
ResolvedLaw resolve_law(const ContactLaw& law);

// All laws of a scene. Two triangles of DIFFERENT bodies use interface(material_a, material_b)
// (symmetric; set either order); two triangles of the SAME body (crack faces inside a unit) use crack(material).
class ContactLaws {
public:
    explicit ContactLaws(int n_materials = 0);
    void set_interface(int material_a, int material_b, const ContactLaw& law);
    void set_crack(int material, const ContactLaw& law);
    int n_materials() const { return n_materials_; }
    // Used for every combination not set explicitly (optional).
    void set_default(const ContactLaw& law);
    // Combinations with no law (and no default) never form contact pairs, instead of being an error: for
    // scenes that declare where surfaces can touch (regions tied together, a beam that cannot crack).
    void set_unlisted_never_touch(bool on) { unlisted_never_touch_ = on; }
    bool unlisted_never_touch() const { return unlisted_never_touch_; }
    // nullptr when neither the combination nor a default was set; ContactSystem then throws at
    // construction if two triangles with that combination exist.
    const ContactLaw* interface(int material_a, int material_b) const;
    const ContactLaw* crack(int material) const;

private:
    int n_materials_ = 0;
    std::vector<ContactLaw> interface_;  // n_materials^2, symmetric
    std::vector<char> interface_set_;
    std::vector<ContactLaw> crack_;      // n_materials
    std::vector<char> crack_set_;
    ContactLaw default_;
    bool default_set_ = false;
    bool unlisted_never_touch_ = false;
};

}  // namespace fdem::contact
