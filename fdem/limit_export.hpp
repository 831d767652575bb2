// fdem/limit_export.hpp: the rigid-block model of a case for limit analysis (issue 49), as `fdem mesh` writes it to
// DIR/limit_model.json; `fdem-tools limit` (tools/fdemtools/limit.py) reads it and sets up the linear programme.
//
// Everything comes from the engine's own resolved case (after --set) and meshed topology, so the limit analysis sees
// the same units, beam, base and joints as `fdem run`:
//   bodies      rigid bodies = connected sets of triangles of the split mesh joined by shared node copies (a tied
//               interface shares its nodes) or by crackable edges (a crack that may open inside a unit does not
//               split it); per body its area, mass (density x area x thickness), centroid and regions;
//   interfaces  one segment per mesh edge between two different bodies: dry joints, bonded joints (cohesive
//               elements of kind bonded), and free faces of two bodies that touch at the start without shared nodes
//               (kind "contact", friction of the pair's dry rule); end points p0 -> p1 run counter-clockwise around
//               body_a, so the normal (s_y, -s_x), s = (p1 - p0) / |p1 - p0|, points from body_a into body_b;
//   groups      every group of the split mesh: its node copies (ids into nodes.xy);
//   supports    the DOF ownership after the last stage's support blocks, with the engine's carry-over rule (a new
//               block takes the DOFs it names, the others keep their previous support); per active support the
//               node copies it still owns;
//   loads       the loads in force at the last stage (a block on a group replaces that group's load of the same kind),
//               each with its nodal forces as the engine distributes them (force: by tributary length along the
//               group's edges, else equally; pressure: -p t L n_out per edge, half to each end);
//   gravity     the last vector a stage set and the last stage's tilt_rate.
#pragma once

#include <string>

#include "fdem/case.hpp"
#include "mesh/topology.hpp"

namespace fdem {

// Writes the JSON (format "fdem-limit-model", version 1) to `path` (through a temporary file and a rename).
void write_limit_model(const std::string& path, const CaseSpec& spec, const mesh::Topology& topo);

}  // namespace fdem
