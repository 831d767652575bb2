// mesh/roughness.hpp: uneven bearing at dry joints (a seeded joint roughness).
//
// Sawn stone faces are flat only to a fraction of a millimetre; two of them touch at points, and the load crosses
// a dry joint where the faces happen to meet. A mesh whose joint faces coincide bears over every face uniformly.
// roughen_dry_joints pulls each body's dry-joint faces back into the body by a small, smooth random offset:
//
//   offset_b(X) = amplitude * (1 + (1/K) sum_k cos(q_k . X + phi_k)) / 2,   |q_k| = 2 pi / wavelength,  K = 4,
//
// a field per body b (directions of q_k and phases phi_k drawn from `seed` and the body id), evaluated at the
// reference position X of each face point, so the profile does not depend on the mesh (a finer mesh samples it
// better). The offset lies in [0, amplitude]; the gap across a joint is the sum of both faces' offsets, so the
// faces touch only near the points where both are small. Each face point moves along minus the mean outward normal
// of the body's dry edges at that point (at a block corner, diagonally).
//
// Every copy of one input node inside one body moves by the same vector, so a crackable element inside a block
// starts closed. Points that also lie on a bonded edge of the body are not moved (a mortared joint must start
// closed), nor points where tied bodies share nodes (a beam tied to the top course). Draws use only the seed, the body ids and the reference coordinates: the same case gives the same mesh.
#pragma once

#include <cstdint>

#include "mesh/topology.hpp"

namespace fdem::mesh {

struct RoughnessStats {
    int points = 0;          // (body, input node) pairs moved
    double mean = 0;         // m, mean offset of the moved points
    double largest = 0;      // m, largest offset
    double smallest_altitude = 0;  // m, smallest altitude of a triangle at a moved point (before moving)
};

// Moves the dry-joint faces of every body of topo.mesh inwards (see above); amplitude and wavelength in m.
// amplitude = 0 does nothing. Throws MeshError if amplitude or wavelength is not positive and finite, or if
// amplitude exceeds a fifth of the smallest altitude of a triangle at a moved point (the move could turn that
// triangle inside out): the message gives both numbers and where.
RoughnessStats roughen_dry_joints(Topology& topo, double amplitude, double wavelength, std::uint64_t seed);

}  // namespace fdem::mesh
