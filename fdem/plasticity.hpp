// fdem/plasticity.hpp: compression softening ("crushing") of the triangles of a material with a
// [materials.NAME.crushing] table: the homogenised FE macro-blocks of the macro distinct element model (M-DEM, issue 29).
//
// DATA LAYOUT
//   Only the triangles of crushing materials carry state. slot_of_tri (one int per triangle, -1: elastic triangle,
//   the neo-Hookean kernel of fdem/triangle.hpp) indexes the per-slot arrays, structure of arrays: Ep (3 doubles per
//   slot: plastic Green-Lagrange strain xx, yy, xy, tensor components), kappa (equivalent plastic strain, -),
//   kappa_u (the kappa at which the strength is gone, -), par (index into the parameter table). A slot's state is
//   written only by the force evaluation of its own triangle, so the update is per item and the same for any thread
//   count; the dissipated energy is summed over slots in slot order.
//
// The model (per triangle, small strains in the rotation-free Green-Lagrange measure):
//   Elasticity, Saint Venant-Kirchhoff on the elastic part of the Green-Lagrange strain E = (F^T F - I) / 2:
//     S = lambda tr(E - Ep) I + 2 mu (E - Ep),  P = F S (the nodal forces of fdem/triangle.hpp),
//   stored energy W = 1/2 (E - Ep) : C : (E - Ep) per unit volume; lambda, mu are the plane model's constants,
//   so at small strain this is the same linear elasticity as the elastic triangles (rigid rotations: S = 0).
//   Surface: Tresca with internal friction phi_b = 0 and cohesion c_b = f_c / 2 (seeds/000 Eq. 5, whose text was
//   lost in the extraction; with phi_b = 0 the Mohr-Coulomb relation f_c = 2 c cos(phi) / (1 - sin(phi)) gives
//   c_b = f_c / 2). In plane stress with both in-plane principal stresses s1 >= s2 compressive the Tresca surface is
//   -s2 = 2 c_b = f_c; this project uses that compressive principal-stress cap for every stress state:
//     f = -s2 - f_c(kappa) <= 0,
//   so a principal tension never yields (tension is the interfaces' business in M-DEM; the blocks' own tensile
//   cracking is not modelled), uniaxial and biaxial compression yield at f_c as Tresca does, and in the
//   tension-compression quadrant the cap is at -s2 = f_c where Tresca would give s1 - s2 = f_c.
//   Flow: associated, dEp = -dlambda n2 n2 (n2 the direction of s2); dkappa = dlambda. Where the return would
//   take s1 below s2 (near-equal biaxial compression) both caps are active: dEp = -dl1 n1 n1 - dl2 n2 n2,
//   dkappa = dl1 + dl2 (corner return, closed form below).
//   Linear softening (a linearised Feenstra-de Borst compression law, seeds/000):
//     f_c(kappa) = f_c (1 - kappa / kappa_u) for kappa < kappa_u, 0 after;
//   energy-regularised by the element size (crack band, Bazant & Oh 1983): the work per unit volume to full
//   softening, INT f_c(kappa) dkappa = f_c kappa_u / 2, equals G_c / h, so kappa_u = 2 G_c / (f_c h), with the
//   characteristic length h = sqrt(2 A0) of the triangle (A0 its reference area; Rots 1988's choice for linear
//   triangles). A triangle crushed to the end has dissipated G_c A0 t / h (J). The dissipated energy of a slot is
//   that integral up to its kappa, D = A0 t g(kappa) with g(k) = f_c (k - k^2 / (2 kappa_u)) (k < kappa_u), and
//   is booked under D_frac.
//   Requirement (no snap-back at the material point): the softening modulus H = f_c / kappa_u = f_c^2 h / (2 G_c)
//   must stay below lambda + mu (the corner's stiffness, the smaller one) — checked for every triangle at setup;
//   a larger element is an input error that names the material and the largest size allowed.
#pragma once

#include <string>
#include <vector>

#include "fdem/triangle.hpp"

namespace fdem {

struct CaseSpec;
struct Model;

struct CrushingParams {
    double fc = 0;      // uniaxial compressive strength f_c, Pa
    double Gc = 0;      // compressive fracture energy G_c, J/m^2
    double mu = 0;      // Pa, the plane model's shear modulus
    double lambda = 0;  // Pa, the plane model's Lame constant
};

// One material-point update. E: Green-Lagrange strain (xx, yy, xy tensor components). Ep (in/out): plastic strain;
// kappa (in/out): equivalent plastic strain; kappa_u: where the strength is gone. S out: second Piola-Kirchhoff
// stress (xx, yy, xy), Pa. Returns true when the point flowed plastically in this update.
bool crushing_update(const CrushingParams& p, double kappa_u, const double* E, double* Ep, double& kappa, double* S);

// Stored elastic energy per unit volume, J/m^3, of strain E with plastic strain Ep.
double crushing_energy_density(const CrushingParams& p, const double* E, const double* Ep);

// Dissipated energy per unit volume, J/m^3, at equivalent plastic strain kappa: INT_0^kappa f_c(k) dk.
double crushing_dissipation_density(const CrushingParams& p, double kappa_u, double kappa);

// The strength left, Pa: f_c(kappa).
double crushing_strength(const CrushingParams& p, double kappa_u, double kappa);

// Green-Lagrange strain (xx, yy, xy) of a deformation gradient F (row-major).
void green_lagrange(const double* F, double* E);

class Crushing {
public:
    // Sets up the slots of the triangles whose material has a crushing table. Throws InputError (naming the
    // case file and the material's crushing keys) when a triangle is too large for its G_c (see the header).
    void setup(const CaseSpec& spec, const Model& model);
    bool active() const { return !kappa.empty(); }
    int slot(int tri) const { return slot_of_tri.empty() ? -1 : slot_of_tri[tri]; }

    // Forces of the triangle of slot s (state updated), like triangle_forces: returns J (<= 0: inverted, no update).
    double forces(int s, const TriangleRef& t, const double* x, const double* v, double* f6, double& visc_power);
    double energy(int s, const TriangleRef& t, const double* x) const;       // J, stored elastic energy
    void stress(int s, const TriangleRef& t, const double* x, double* s3) const;  // Cauchy xx, yy, xy, Pa
    double dissipated() const;                                                // J, all slots, in slot order
    double softening(int s) const { return kappa[s] >= kappa_u[s] ? 1.0 : kappa[s] / kappa_u[s]; }  // kappa / kappa_u

    std::vector<CrushingParams> params;  // per crushing material
    std::vector<int> slot_of_tri;        // per triangle: slot or -1
    std::vector<int> tri_of_slot;        // per slot: the triangle
    std::vector<int> par;                // per slot: index into params
    std::vector<double> Ep;              // 3 per slot, -
    std::vector<double> kappa;           // per slot, -
    std::vector<double> kappa_u;         // per slot, -
    std::vector<double> A0t;             // per slot: reference area times thickness, m^3
};

}  // namespace fdem
