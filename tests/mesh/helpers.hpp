// tests/mesh/helpers.hpp: small checks shared by the mesh tests.
#pragma once

#include <cmath>
#include <map>
#include <utility>
#include <vector>

#include "mesh/topology.hpp"
#include "mesh/wall.hpp"

namespace fdem::mesh::testing {

inline WallSpec cases_a_wall(double mesh_size = 0.05) {
    WallSpec s;  // cases/README.md §A: 1000 x 1000 mm, 200 x 100 mm units, running bond, dry joints
    s.length = 1.0;
    s.height = 1.0;
    s.unit_length = 0.2;
    s.unit_height = 0.1;
    s.bond = "running";
    s.joint = "dry";
    s.mesh_size = mesh_size;
    return s;
}

inline double tri_area(const Mesh& m, int t) {
    const int* n = &m.tri[3 * t];
    const double* p = m.xy.data();
    return 0.5 * ((p[2 * n[1]] - p[2 * n[0]]) * (p[2 * n[2] + 1] - p[2 * n[0] + 1]) -
                  (p[2 * n[2]] - p[2 * n[0]]) * (p[2 * n[1] + 1] - p[2 * n[0] + 1]));
}

inline double mesh_area(const Mesh& m, int region = -1) {
    double a = 0;
    for (int t = 0; t < m.n_triangles(); ++t)
        if (region < 0 || m.tri_region[t] == region) a += tri_area(m, t);
    return a;
}

inline double edge_length(const Topology& topo, int e) {
    // edge_nodes are nodes of the shared mesh; the split mesh keeps coordinates, so use any copy.
    const Mesh& m = topo.mesh;
    int ca = -1, cb = -1;
    const int ta = topo.edge_tri[2 * e];
    for (int i = 0; i < 3; ++i) {
        const int c = m.tri[3 * ta + i];
        if (topo.node_origin[c] == topo.edge_nodes[2 * e]) ca = c;
        if (topo.node_origin[c] == topo.edge_nodes[2 * e + 1]) cb = c;
    }
    return std::hypot(m.xy[2 * cb] - m.xy[2 * ca], m.xy[2 * cb + 1] - m.xy[2 * ca + 1]);
}

inline double class_length(const Topology& topo, EdgeClass c) {
    double l = 0;
    for (int e = 0; e < topo.n_edges(); ++e)
        if (topo.edge_class[e] == c) l += edge_length(topo, e);
    return l;
}

// Mesh-independent description of a layout: per body its area-weighted centroid (rounded to 1 um) and area,
// and per pair of touching bodies the length of their interface by class.
struct LayoutSignature {
    std::map<std::pair<long, long>, double> bodies;  // centroid -> area
    std::map<std::pair<std::pair<long, long>, std::pair<long, long>>, std::map<int, double>> joints;
    std::map<int, double> class_lengths;
};

inline LayoutSignature signature(const Topology& topo) {
    const Mesh& m = topo.mesh;
    const int nb = m.n_bodies();
    std::vector<double> a(nb, 0), cx(nb, 0), cy(nb, 0);
    for (int t = 0; t < m.n_triangles(); ++t) {
        const int* n = &m.tri[3 * t];
        const double at = tri_area(m, t);
        const int b = m.tri_body[t];
        a[b] += at;
        cx[b] += at * (m.xy[2 * n[0]] + m.xy[2 * n[1]] + m.xy[2 * n[2]]) / 3;
        cy[b] += at * (m.xy[2 * n[0] + 1] + m.xy[2 * n[1] + 1] + m.xy[2 * n[2] + 1]) / 3;
    }
    std::vector<std::pair<long, long>> key(nb);
    LayoutSignature s;
    for (int b = 0; b < nb; ++b) {
        key[b] = {std::lround(cx[b] / a[b] * 1e6), std::lround(cy[b] / a[b] * 1e6)};
        s.bodies[key[b]] += a[b];
    }
    for (int e = 0; e < topo.n_edges(); ++e) {
        const double l = edge_length(topo, e);
        s.class_lengths[static_cast<int>(topo.edge_class[e])] += l;
        if (topo.edge_tri[2 * e + 1] < 0) continue;
        auto ka = key[m.tri_body[topo.edge_tri[2 * e]]], kb = key[m.tri_body[topo.edge_tri[2 * e + 1]]];
        if (ka == kb) continue;
        if (kb < ka) std::swap(ka, kb);
        s.joints[{ka, kb}][static_cast<int>(topo.edge_class[e])] += l;
    }
    return s;
}

}  // namespace fdem::mesh::testing
