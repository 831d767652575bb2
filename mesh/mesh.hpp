// mesh/mesh.hpp: the plain-array triangle mesh that every geometry source produces and the engine consumes.
//
// DATA LAYOUT
//   xy        2 * n_nodes doubles, node k at (xy[2k], xy[2k+1]), metres.
//   tri       3 * n_tri ints, counter-clockwise (reference area > 0), indices into the nodes.
//   tri_region n_tri ints, index into `regions` (the 2D physical group the triangle belongs to; -1 = none).
//   tri_body  n_tri ints, compact index of the Gmsh surface entity the triangle was meshed on: one body is one
//             masonry unit, the beam, the base ... (numbered in increasing Gmsh surface tag order, 0..n_bodies-1).
//             It lets the topology tell a crack inside a unit (same body) from a joint between units.
//   groups    every physical group of the Gmsh model by name, with its nodes (sorted, unique), its
//             boundary edges (dim 1: node pairs in the order Gmsh gives) and its triangles (dim 2).
// Indices are 0-based. "No index" is -1.
#pragma once

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

namespace fdem::mesh {

// Thrown for geometry or mesh problems a user can fix (bad file, missing group, degenerate triangle).
struct MeshError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct PhysicalGroup {
    std::string name;
    int dim = 0;                            // 0 points, 1 curves, 2 surfaces
    std::vector<int> nodes;                 // sorted, unique
    std::vector<std::array<int, 2>> edges;  // dim 1 only
    std::vector<int> triangles;             // dim 2 only
    // Which node copies the group takes once the topology splits nodes between bodies (mesh/topology.hpp):
    std::string within;       // non-empty (case [groups] with `within`): only the copies on that group's bodies
    bool every_copy = false;  // true (case [groups] box without `within`): every copy of every node, no check
    // Set by build_topology on the split mesh's groups (body ids as in tri_body):
    std::vector<int> bodies;          // the bodies whose copies the group holds (empty: every copy, no body rule)
    std::vector<int> left_out_bodies; // bodies that share a node of the group but whose copies it does not hold
    std::vector<int> split_bodies;    // no body rule and a node split between these bodies: the group holds
                                      // every copy, which drags all of them (a case may not load or support it)
    int split_node = -1;              // split mesh: one copy of such a node (for the message's location)
};

struct Mesh {
    std::vector<double> xy;
    std::vector<int> tri;
    std::vector<int> tri_region;
    std::vector<int> tri_body;  // empty only for meshes built by hand; see DATA LAYOUT
    std::vector<std::string> regions;
    std::vector<PhysicalGroup> groups;

    int n_nodes() const { return static_cast<int>(xy.size() / 2); }
    int n_triangles() const { return static_cast<int>(tri.size() / 3); }
    int n_bodies() const {
        int n = 0;
        for (int b : tri_body) n = b + 1 > n ? b + 1 : n;
        return n;
    }
    const PhysicalGroup* find_group(const std::string& name) const {
        for (const auto& g : groups)
            if (g.name == name) return &g;
        return nullptr;
    }
    // The group a case file refers to; throws MeshError naming it and listing the groups that exist.
    // dim >= 0 also requires that dimension (0 points, 1 curves, 2 surfaces).
    const PhysicalGroup& require_group(const std::string& name, int dim = -1) const {
        const PhysicalGroup* g = find_group(name);
        if (g && (dim < 0 || g->dim == dim)) return *g;
        std::string have;
        for (const auto& h : groups) have += (have.empty() ? "" : ", ") + h.name + " (" + std::to_string(h.dim) + "D)";
        if (g)
            throw MeshError("physical group '" + name + "' is " + std::to_string(g->dim) + "D, expected " +
                            std::to_string(dim) + "D");
        throw MeshError("physical group '" + name + "' does not exist in the mesh (groups: " +
                        (have.empty() ? std::string("none") : have) + ")");
    }
    int find_region(const std::string& name) const {
        for (std::size_t r = 0; r < regions.size(); ++r)
            if (regions[r] == name) return static_cast<int>(r);
        return -1;
    }
};

}  // namespace fdem::mesh
