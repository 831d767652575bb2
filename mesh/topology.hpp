// mesh/topology.hpp: mesh -> FDEM topology: edge classes, node splitting, cohesive and contact sets.
//
// Nodes are shared inside a continuum and duplicated only where a crack or a joint may open.
// Every edge of the mesh gets one class:
//   interior       two triangles of one continuum, nodes shared, no crack possible;
//   crackable      two triangles of one body (or of tied bodies) whose material may fracture: nodes duplicated,
//                  one cohesive element with the material's properties;
//   bonded         two bodies joined by mortar (the case's interface rule): nodes duplicated, one cohesive element
//                  with the interface's properties;
//   dry            two bodies in contact only: nodes duplicated, no cohesive element;
//   free_boundary  one triangle only.
//
// DATA LAYOUT (all plain arrays, 0-based, "no index" = -1)
//   Topology::mesh        the split mesh: xy has one entry per node copy, tri refers to copies, tri_region /
//                         tri_body / regions unchanged (triangle ids are the input's). Copies of one original node
//                         are consecutive and in original-node order, so node_origin is non-decreasing.
//   node_origin           n_split ints: split node -> node of the input mesh.
//   edge_nodes            2 * n_edges ints: the unique edges of the input mesh, as input node ids, oriented as in
//                         triangle edge_tri[2e] (counter-clockwise in it). Sorted by (min node, max node).
//   edge_tri              2 * n_edges ints: side A = the lower triangle id, side B = the other (-1 on a free boundary).
//   edge_class            n_edges classes.
//   cohesive              one per crackable or bonded edge, in edge order (see CohesiveElement).
//   dry_joints            one per dry edge, in edge order, the same record with kind = dry: no forces, only the
//                         node copies of both sides, so that the engine can follow the joint's opening and slip.
//   contact_capable       sorted triangle ids that have a node on a free-boundary or dry edge (or, with
//                         contact_by_node = false, an edge of those classes). Triangles of cohesive elements
//                         join the contact set when their element breaks; that is the engine's job.
//   Groups of the split mesh (PhysicalGroup::bodies / left_out_bodies / split_bodies say what was done):
//     surface group   the copies its own triangles use (a support on one block does not drag its neighbour's
//                     interface nodes);
//     curve group     the copies on the bodies its edges border (the triangles on either side of each edge): a
//                     curve of the upper block that ends at a corner shared with the lower block does not take the
//                     lower block's copy there; a curve along a joint borders both bodies and takes both copies;
//     case group with `within` (PhysicalGroup::within): the copies on the bodies of that group, by the same rules;
//     point group, case `nearest` without `within`: every copy; a node whose copies lie on bodies that share no
//                     copy (a dry or bonded joint runs through it) is recorded in split_bodies, since the group
//                     cannot say which body it means (the case loader refuses to load or support such a group);
//     case `box` without `within` (every_copy): every copy of every node in the box, on every body.
//   A dim-1 group holds, for each of its edges, the edge as seen from each adjacent triangle (both copies on an
//   interface, once where nodes are shared), in the group's orientation; triangle groups are unchanged.
//
// A node is split into as many copies as there are fans of triangles around it that stay connected through
// interior edges; a crackable edge that ends inside a continuum (possible only next to tied, non-crackable material)
// therefore keeps one shared node at its tip, and its cohesive element has a0 == b0 or a1 == b1 there.
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include "mesh/mesh.hpp"

namespace fdem::mesh {

enum class EdgeClass : int { interior = 0, crackable = 1, bonded = 2, dry = 3, free_boundary = 4 };
inline constexpr int kEdgeClassCount = 5;
const char* to_string(EdgeClass c);

// How two different bodies meet: tied = one continuum (nodes shared; crackable if both regions are),
// bonded = mortared joint (cohesive element), dry = contact only.
enum class InterfaceKind : int { tied = 0, bonded = 1, dry = 2 };
const char* to_string(InterfaceKind k);
// "tied", "bonded", "dry" -> kind; false for anything else (for the case loader).
bool parse_interface_kind(const std::string& text, InterfaceKind& kind);

// Per region (2D physical group name): may the material crack inside?
struct RegionRule {
    std::string region;
    bool crackable = false;
};

// Per unordered pair of regions; region_a == region_b means two different bodies of that region touching
// (unit against unit). Every pair that touches must have a rule: a missing one is an error, never a default.
struct InterfaceRule {
    std::string region_a, region_b;
    InterfaceKind kind = InterfaceKind::dry;
};

struct TopologyOptions {
    std::vector<RegionRule> regions;           // regions not listed are not crackable
    std::vector<InterfaceRule> interfaces;
    bool split_all = false;                    // classic FDEM limit: every interior and tied edge is crackable
    bool contact_by_node = true;               // contact_capable by a node on a free/dry edge (false: by an edge)
    // Non-empty: the 1D physical group of the only edges where a crackable material may crack (e.g. the wall
    // generator's "unit_cracks"); the other edges inside it are interior. Missing group = no such edge.
    std::string crack_group;
};

// A 4-node cohesive element joining side A edge a0->a1 and side B edge b0->b1 (split node ids), with a0 and b0
// at the same reference point, a1 and b1 likewise. a0->a1 runs counter-clockwise around tri_a, so tri_a lies to
// its left: with tangent s = (x(a1) - x(a0)) / |.|, the normal n = (s_y, -s_x) points from side A into side B,
// and the opening (u_B - u_A) . n is positive when the crack opens.
struct CohesiveElement {
    std::array<int, 4> n{};  // {a0, a1, b0, b1}
    int tri_a = -1, tri_b = -1;
    int body_a = -1, body_b = -1;
    int region_a = -1, region_b = -1;
    EdgeClass kind = EdgeClass::crackable;  // crackable or bonded (dry for Topology::dry_joints)
    int edge = -1;                          // index into the Topology edge arrays
};

struct Topology {
    Mesh mesh;
    std::vector<int> node_origin;
    std::vector<CohesiveElement> cohesive;
    std::vector<CohesiveElement> dry_joints;
    std::vector<int> contact_capable;
    std::vector<int> edge_nodes;
    std::vector<int> edge_tri;
    std::vector<EdgeClass> edge_class;
    int n_nodes_before = 0;
    // Free-boundary nodes lying on a free edge of another body (bodies touching without shared nodes, allowed for
    // dry pairs only: contact handles them). 0 for every generated wall.
    int nonconforming_nodes = 0;

    int n_edges() const { return static_cast<int>(edge_class.size()); }
};

// Classifies every edge and splits the nodes. Throws MeshError (one line, naming regions and a location) for:
// a rule naming a region the mesh does not have, conflicting rules for one pair, a pair of touching regions
// without a rule, an edge shared by more than two triangles or by two triangles on the same side (overlap or
// inversion), inverted or degenerate triangles, and overlapping bodies (a triangle's centroid strictly inside a
// triangle of another body: e.g. a .geo whose units were not fragmented), and bodies touching without shared
// nodes when their pair is tied, bonded or has no rule.
Topology build_topology(const Mesh& mesh, const TopologyOptions& options);

// The share of a total force on a group that each of its nodes takes (shares sum to 1): by tributary length along
// the group's edges (half of each edge to each end node), or equally among its nodes when it has no edges. X: the
// nodes' coordinates (x0, y0, x1, y1, ...). Used by the engine's loads and by the limit-analysis export alike.
std::map<int, double> load_shares(const PhysicalGroup& g, const std::vector<double>& X);

}  // namespace fdem::mesh
