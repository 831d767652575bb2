// fdem/body_step.hpp: the stable step of groups that move as one rigid body for the whole run (rigid = "body",
// fdem/support_body.cpp). Such a body's triangles never deform and its nodes move together: its step is set by its
// mass and inertia against the springs that tie it to the rest (contact, joints), not by its triangles or its
// nodes' own masses (fdem/README.md 'Time step').
//
// THE BOUND. The body's DOFs q = (X, Y, theta) move node k by u_k = B_k q, B_k = [[1, 0, -r_y], [0, 1, r_x]] with
// r = x_k - c (c the centre of mass). For the symmetric stiffness K of every spring at the body's nodes,
// u^T K u <= sum_i s_i u_i^2 with s_i the absolute row sum of DOF i (|u_i u_j| <= (u_i^2 + u_j^2) / 2), the per-node
// stiffness k_k of the nodal bound. So the body's highest omega^2 is at most the largest eigenvalue of
//   D^-1/2 A D^-1/2,   A = sum_k k_k B_k^T B_k,   D = diag(M, M, I),  I = sum_k m_k |r_k|^2,
// and, the bound being a sum over nodes, the whole model's highest omega^2 is at most the largest of this over the
// bodies and the nodal bound k / m over the other nodes. It does not change as the body turns (A and D turn together).
#pragma once

#include <string>
#include <vector>

#include "fdem/case.hpp"
#include "fdem/model.hpp"

namespace fdem {

// Nodes whose motion is prescribed in both components all run long (fixed, velocity, protocol) have no dynamics of
// their own either: they are left out of the bound, and so are the triangles between three of them (the springs and
// triangles that join them to moving nodes stay counted at those nodes).
struct RigidBodies {
    std::vector<int> node_body;              // per node: its body, -1 none
    std::vector<std::vector<int>> nodes;     // per body, its nodes
    std::vector<std::string> group;          // per body, its group
    std::vector<char> held;                  // per node: 1 when prescribed in both components all run long
    std::vector<char> tri;                   // per triangle: 1 when its three nodes are in one body, or all held
    bool empty() const { return tri.empty(); }  // (no body, no held node)
};

// The groups that are one rigid body in every stage (a rigid = "body" block owns both components of each of the
// group's nodes from the first stage to the last; a later block on the same group keeps it a body, one that names
// any of its nodes otherwise does not), and the nodes held in both components in every stage.
RigidBodies whole_run_bodies(const CaseSpec& spec, const Model& model);

// omega^2 (1/s^2) bound of THE BOUND for one body: its nodes, positions x (m, 2 per node), masses (kg) and per-node
// stiffness k (N/m, the nodal bound's row sums of the springs and of any triangle not inside the body).
double body_omega2(const std::vector<int>& nodes, const double* x, const double* mass, const double* k);

}  // namespace fdem
