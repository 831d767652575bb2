// mesh/quality.hpp: mesh quality checks and the statistics `fdem mesh` prints.
//
// Definitions (per triangle, edges l1 <= l2 <= l3, area A):
//   minimum angle   smallest interior angle (degrees); equilateral 60.
//   altitude        2 A / l3, the smallest height (m): it bounds the critical time step of the triangle.
//   aspect ratio    R / (2 r) (circumradius over twice the inradius) = l1 l2 l3 (l1 + l2 + l3) / (16 A^2):
//                   1 for the equilateral triangle, growing without bound for slivers.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "mesh/mesh.hpp"
#include "mesh/topology.hpp"

namespace fdem::mesh {

// Default sliver limit (degrees): Gmsh's Frontal-Delaunay gives minimum angles above ~25 deg on masonry
// geometry; a triangle below 10 deg means a geometric sliver (a tiny part unit, a near-coincident vertex).
inline constexpr double kDefaultMinAngleDeg = 10.0;

// Upper edges of the aspect-ratio histogram bins; the last bin is open (>= 10).
inline constexpr std::array<double, 6> kAspectBins = {1.25, 1.5, 2.0, 3.0, 5.0, 10.0};

struct TriangleQuality {
    double min_angle_deg = 0;  // degrees
    double altitude = 0;       // m
    double aspect = 0;         // R / (2 r), 1 = equilateral
};
TriangleQuality triangle_quality(const double* p0, const double* p1, const double* p2);

struct MeshStats {
    int triangles = 0;
    int nodes_before = 0;   // shared-node mesh
    int nodes_after = 0;    // after splitting
    int bodies = 0;
    std::array<int, kEdgeClassCount> edges_per_class{};  // indexed by EdgeClass
    std::array<double, kEdgeClassCount> length_per_class{};  // m
    int cohesive_crackable = 0, cohesive_bonded = 0;
    int contact_capable = 0;
    int nonconforming_nodes = 0;    // see Topology::nonconforming_nodes
    double min_angle_deg = 0;       // degrees, over all triangles
    int min_angle_triangle = -1;
    double min_altitude = 0;        // m
    int min_altitude_triangle = -1;
    double max_aspect = 0;
    std::array<int, kAspectBins.size() + 1> aspect_histogram{};  // bin i: aspect < kAspectBins[i] (and >= the previous)
    std::vector<std::string> regions;
    std::vector<int> triangles_per_region;
    std::vector<double> area_per_region;  // m^2
};

MeshStats mesh_stats(const Topology& topo);

// Multi-line, human-readable statistics for the CLI.
std::string format_stats(const MeshStats& stats);

// Throws MeshError naming the region and the location of the worst triangle if any triangle is inverted,
// degenerate, or has a minimum angle below min_angle_deg (degrees).
void check_quality(const Mesh& mesh, double min_angle_deg = kDefaultMinAngleDeg);

}  // namespace fdem::mesh
