// fdem/scene.hpp: case -> mesh -> topology (edge classes, split nodes, cohesive and contact sets) -> model.
#pragma once

#include <vector>

#include "fdem/case.hpp"
#include "fdem/model.hpp"
#include "mesh/roughness.hpp"
#include "mesh/topology.hpp"

namespace fdem {

// Builds the mesh the case's [geometry] describes (Gmsh API; rectangle, .geo, .msh, wall generator, macro-block
// pier), checks its quality and adds the case-defined node groups, then checks the case's names against it. MeshError
// becomes InputError naming the [geometry] line.
mesh::Mesh make_mesh(const CaseSpec& spec);

// Whether the case needs a topology: any interface rule that is not "tied", any material that may crack, or split = "all".
bool needs_topology(const CaseSpec& spec);

// The rules handed to mesh::build_topology: a region is crackable when its material has a fracture table;
// interfaces as the case gives them. Throws InputError (naming the line) for split = "all" with a material that
// cannot crack.
mesh::TopologyOptions topology_options(const CaseSpec& spec, const mesh::Mesh& mesh);

// Mesh, topology if needed (MeshError -> InputError naming the [geometry] / [[interfaces]] of the case),
// then the model with its cohesive elements and contact-capable triangles.
Model build_scene(const CaseSpec& spec);

// The mesh and its topology, for `fdem mesh`; with geometry.joint_roughness the faces are roughened and, if
// `roughness` is given, what moved is reported there.
mesh::Topology build_topology_only(const CaseSpec& spec, mesh::RoughnessStats* roughness = nullptr);

// The groups named by loads, supports and initial conditions against the split mesh's node copies: throws
// InputError for a group whose node is split between bodies with no rule to choose (a point group at a corner two
// blocks share); warns on stderr when a curve group left out other bodies' copies at its ends.
void check_group_bodies(const CaseSpec& spec, const mesh::Topology& topo);

}  // namespace fdem
