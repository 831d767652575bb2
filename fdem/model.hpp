// fdem/model.hpp: the model state the integrator advances.
//
// DATA LAYOUT
//   Hot node state, structure of arrays, 2 doubles per node (x then y): X (reference), x (current),
//   v (velocity at the half step), plus mass and inv_mass (one per node; inv_mass = 0 never happens for a
//   node of a triangle). Triangles: TriangleRef records (64 bytes). Node -> triangle-force incidence as CSR
//   (inc_ptr, inc_idx): inc_idx holds 3 * triangle + local node, in increasing order, so the gather of the
//   per-triangle forces adds them in the same order whatever the thread count.
//   Cold data (names, groups, regions) stays in `mesh`.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "fdem/case.hpp"
#include "fdem/triangle.hpp"
#include "mesh/mesh.hpp"
#include "mesh/topology.hpp"

namespace fdem {

struct Model {
    mesh::Mesh mesh;  // cold: regions, groups (node and edge lists by name)
    double thickness = 1;  // m
    Plane plane = Plane::stress;

    std::vector<double> X, x, v;        // 2 per node: m, m, m/s
    std::vector<double> mass, inv_mass;  // per node: inertial mass (kg, times numerics.mass_scale), 1/kg
    std::vector<double> grav_mass;       // per node: physical mass, kg (gravity)
    std::vector<TriangleRef> tris;
    std::vector<MaterialConst> mat;
    std::vector<int> tri_material;       // per triangle, index into CaseSpec::materials
    std::vector<double> tri_altitude;    // per triangle: smallest altitude in the reference configuration, m
    std::vector<int> inc_ptr, inc_idx;   // node -> 3 * triangle + local
    // From the topology (empty for a plain continuum), in the model's numbering.
    std::vector<mesh::CohesiveElement> cohesive;
    std::vector<mesh::CohesiveElement> dry_joints;  // one per dry edge (kind dry): followed for the joint record
    std::vector<int> contact_capable;  // sorted
    std::vector<int> node_vertex;      // per node: the input-mesh node it is a copy of (Topology::node_origin)
    bool has_topology = false;
    // build_model renumbers nodes and triangles for memory locality; these map the input mesh's ids to the model's.
    std::vector<int> node_new_of_old, tri_new_of_old;

    int n_nodes() const { return static_cast<int>(mass.size()); }
    int n_triangles() const { return static_cast<int>(tris.size()); }
    const mesh::PhysicalGroup& group(const std::string& name) const;
};

// Renumbers a mesh for memory locality: triangles along a Morton (Z-order) curve of their centroids, nodes in
// order of first use by those triangles. Groups, regions and bodies follow. Returns {node map, triangle map},
// each new_of_old. Deterministic (ties broken by the old index).
std::pair<std::vector<int>, std::vector<int>> reorder_for_locality(mesh::Mesh& mesh);

// Builds the model (after reorder_for_locality): lumped masses rho t A0 / 3 per node, precomputed D0^-1, A0, altitudes,
// material constants (plane stress or strain), viscous coefficients. Throws InputError for a region without
// material and mesh::MeshError for a triangle with non-positive reference area.
Model build_model(const CaseSpec& spec, mesh::Mesh mesh);
// The same from a topology: its split mesh, cohesive elements, dry joint segments, contact-capable triangles and
// node origins (renumbered with the mesh).
Model build_model(const CaseSpec& spec, mesh::Topology topo);

// Stable time step of the triangles alone: min over triangles of 2 / omega_e, omega_e the exact highest frequency of the
// lumped-mass constant-strain triangle (triangle_omega2), reduced for viscous damping and local damping alpha by
// the triangle's damped factor (triangle_damped_factor). Returns the limit (s) and the triangle that sets it.
// The damped factor of the central-difference step: dt <= (2 / omega) damped_step_factor(xi, alpha) for a mode of
// frequency omega with viscous damping at a fraction xi of critical, its force lagged half a step as the engine
// evaluates it, under local damping alpha ([C79]: -alpha |f| sign(v)). In the highest (alternating) mode,
// x^n = (-1)^n a, the lagged viscous force -c v^{n-1/2} has the sign of the elastic force -k x^n, both oppose
// v^{n-1/2}, and the local damping force then adds alpha |f| to them: v^{n+1/2} = v^{n-1/2} + (1 + alpha) f dt / m,
// stable while (1 + alpha)(omega^2 dt^2 + 4 xi omega dt) <= 4, that is omega dt <= 2 (sqrt(xi^2 + 1 / (1 + alpha)) -
// xi). alpha = 0 gives the damped limit sqrt(1 + xi^2) - xi (Belytschko, Liu & Moran 2000, §6.3); xi = 0 gives
// 1 / sqrt(1 + alpha) (0.745 at alpha = 0.8: at the default safety 0.8 the undamped mode at the bound would grow).
inline double damped_step_factor(double xi, double alpha) { return std::sqrt(xi * xi + 1.0 / (1.0 + alpha)) - xi; }

struct StepLimit {
    double dt = 0;  // s
    int element = -1;
};
StepLimit triangle_step_limit(const CaseSpec& spec, const Model& model, double alpha = 0.0,
                              const std::vector<char>* rigid_tri = nullptr);

// The triangles' share of the assembled system's nodal bound (fdem/README.md 'Time step'): adds to k[node] (or to
// k[rep[node]] when rep is given: tied copies that move as one) sum over the node's triangles of omega_e^2 m_e / 3
// (N/m), omega_e the triangle's highest frequency (damped: divided by triangle_damped_factor) and m_e / 3 its lumped
// share at mass_scale. With u^T K_e u <= omega_e^2 u^T M_e u per triangle (the element eigenvalue inequality behind
// the element step bound, Belytschko, Liu & Moran, Nonlinear Finite Elements for Continua and Structures, 2000, §6.3),
// u^T K u <= sum_i k_i u_i^2 for the triangles, so the node's k / m bounds omega^2 (Rayleigh quotient) together with
// the springs' Gershgorin row sums. rigid_tri (optional, per triangle): 1 leaves the triangle out, here and in
// triangle_step_limit (inside a rigid body, fdem/body_step.hpp).
void add_triangle_node_stiffness(const CaseSpec& spec, const Model& model, const int* rep, double* k, double alpha = 0.0,
                                 const std::vector<char>* rigid_tri = nullptr);

// The triangle's damped factor f_e: its stable step is (2 / omega_e) f_e under its viscous coefficient eta (Pa s,
// TriangleRef::eta) and local damping alpha; damped_step_factor(0, alpha) when eta = 0.
double triangle_damped_factor(const double* p, const int* n, const Material& m, Plane plane, double mass_scale,
                              double eta, double alpha);

// omega_e^2 (1/s^2) of triangle n (node indices into the coordinates p) of material m at the given mass scaling.
double triangle_omega2(const double* p, const int* n, const Material& m, Plane plane, double mass_scale);

// P-wave speed of a material in the plane model, m/s.
double p_wave_speed(const Material& m, Plane plane);

}  // namespace fdem
