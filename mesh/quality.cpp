// mesh/quality.cpp: per-triangle quality measures, mesh statistics and the sliver check.
//
// DATA LAYOUT: reads Mesh/Topology arrays only (xy, tri, tri_region, edge arrays); serial, ordered by
// triangle id, so the "worst triangle" reported is the lowest id among equals.
#include "mesh/quality.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace fdem::mesh {

namespace {
constexpr double kPi = 3.14159265358979323846;

double signed_area2(const double* a, const double* b, const double* c) {
    return (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
}

// Angle at vertex a of triangle abc (radians), from atan2(|cross|, dot): accurate for tiny and near-pi angles.
double angle_at(const double* a, const double* b, const double* c) {
    const double ux = b[0] - a[0], uy = b[1] - a[1], vx = c[0] - a[0], vy = c[1] - a[1];
    return std::atan2(std::abs(ux * vy - uy * vx), ux * vx + uy * vy);
}

std::string where(const Mesh& m, int t) {
    std::ostringstream s;
    s.precision(6);
    const int* n = &m.tri[3 * t];
    const double cx = (m.xy[2 * n[0]] + m.xy[2 * n[1]] + m.xy[2 * n[2]]) / 3;
    const double cy = (m.xy[2 * n[0] + 1] + m.xy[2 * n[1] + 1] + m.xy[2 * n[2] + 1]) / 3;
    s << "triangle " << t << " in region '"
      << (m.tri_region[t] >= 0 && m.tri_region[t] < static_cast<int>(m.regions.size()) ? m.regions[m.tri_region[t]]
                                                                                        : std::string("?"))
      << "' at (" << cx << ", " << cy << ") m";
    return s.str();
}
}  // namespace

TriangleQuality triangle_quality(const double* p0, const double* p1, const double* p2) {
    TriangleQuality q;
    const double A = 0.5 * signed_area2(p0, p1, p2);
    const double a = std::hypot(p1[0] - p0[0], p1[1] - p0[1]);
    const double b = std::hypot(p2[0] - p1[0], p2[1] - p1[1]);
    const double c = std::hypot(p0[0] - p2[0], p0[1] - p2[1]);
    const double lmax = std::max({a, b, c});
    q.min_angle_deg = std::min({angle_at(p0, p1, p2), angle_at(p1, p2, p0), angle_at(p2, p0, p1)}) * 180.0 / kPi;
    if (!(A > 0)) {
        q.min_angle_deg = A < 0 ? -q.min_angle_deg : 0.0;
        q.altitude = 0;
        q.aspect = std::numeric_limits<double>::infinity();
        return q;
    }
    q.altitude = 2 * A / lmax;
    q.aspect = a * b * c * (a + b + c) / (16 * A * A);
    return q;
}

MeshStats mesh_stats(const Topology& topo) {
    const Mesh& m = topo.mesh;
    MeshStats s;
    s.triangles = m.n_triangles();
    s.nodes_before = topo.n_nodes_before;
    s.nodes_after = m.n_nodes();
    s.bodies = m.n_bodies();
    for (int e = 0; e < topo.n_edges(); ++e) {
        const int c = static_cast<int>(topo.edge_class[e]);
        ++s.edges_per_class[c];
        // edge_nodes are input node ids; the first copy of each sits at the same point.
        const int a = topo.edge_nodes[2 * e], b = topo.edge_nodes[2 * e + 1];
        const int ta = topo.edge_tri[2 * e];
        int ca = -1, cb = -1;
        for (int i = 0; i < 3; ++i) {
            if (topo.node_origin[m.tri[3 * ta + i]] == a) ca = m.tri[3 * ta + i];
            if (topo.node_origin[m.tri[3 * ta + i]] == b) cb = m.tri[3 * ta + i];
        }
        s.length_per_class[c] += std::hypot(m.xy[2 * cb] - m.xy[2 * ca], m.xy[2 * cb + 1] - m.xy[2 * ca + 1]);
    }
    for (const auto& ce : topo.cohesive) (ce.kind == EdgeClass::bonded ? s.cohesive_bonded : s.cohesive_crackable)++;
    s.contact_capable = static_cast<int>(topo.contact_capable.size());
    s.nonconforming_nodes = topo.nonconforming_nodes;
    s.regions = m.regions;
    s.triangles_per_region.assign(m.regions.size(), 0);
    s.area_per_region.assign(m.regions.size(), 0.0);
    s.min_angle_deg = std::numeric_limits<double>::infinity();
    s.min_altitude = std::numeric_limits<double>::infinity();
    for (int t = 0; t < m.n_triangles(); ++t) {
        const int* n = &m.tri[3 * t];
        const auto q = triangle_quality(&m.xy[2 * n[0]], &m.xy[2 * n[1]], &m.xy[2 * n[2]]);
        if (q.min_angle_deg < s.min_angle_deg) s.min_angle_deg = q.min_angle_deg, s.min_angle_triangle = t;
        if (q.altitude < s.min_altitude) s.min_altitude = q.altitude, s.min_altitude_triangle = t;
        s.max_aspect = std::max(s.max_aspect, q.aspect);
        std::size_t bin = 0;
        while (bin < kAspectBins.size() && q.aspect >= kAspectBins[bin]) ++bin;
        ++s.aspect_histogram[bin];
        const int r = m.tri_region[t];
        if (r >= 0 && r < static_cast<int>(m.regions.size())) {
            ++s.triangles_per_region[r];
            s.area_per_region[r] += 0.5 * signed_area2(&m.xy[2 * n[0]], &m.xy[2 * n[1]], &m.xy[2 * n[2]]);
        }
    }
    return s;
}

std::string format_stats(const MeshStats& s) {
    std::ostringstream o;
    o << std::setprecision(6);
    o << "triangles            " << s.triangles << " in " << s.bodies << " bodies\n";
    for (std::size_t r = 0; r < s.regions.size(); ++r)
        o << "  region " << std::left << std::setw(12) << s.regions[r] << std::right << std::setw(8)
          << s.triangles_per_region[r] << " triangles, area " << s.area_per_region[r] << " m^2\n";
    o << "nodes                " << s.nodes_before << " shared, " << s.nodes_after << " after splitting\n";
    o << "edges by class\n";
    for (int c = 0; c < kEdgeClassCount; ++c)
        o << "  " << std::left << std::setw(14) << to_string(static_cast<EdgeClass>(c)) << std::right << std::setw(8)
          << s.edges_per_class[c] << " edges, " << s.length_per_class[c] << " m\n";
    o << "cohesive elements    " << s.cohesive_crackable << " crackable, " << s.cohesive_bonded << " bonded\n";
    o << "contact-capable      " << s.contact_capable << " triangles\n";
    if (s.nonconforming_nodes > 0)
        o << "non-conforming       " << s.nonconforming_nodes << " nodes where bodies touch without shared nodes (dry)\n";
    o << "minimum angle        " << s.min_angle_deg << " deg (triangle " << s.min_angle_triangle << ")\n";
    o << "minimum altitude     " << s.min_altitude << " m (triangle " << s.min_altitude_triangle << ")\n";
    o << "aspect ratio R/2r    max " << s.max_aspect << "\n";
    for (std::size_t b = 0; b < s.aspect_histogram.size(); ++b) {
        o << "  ";
        if (b == 0) o << "[1, " << kAspectBins[0] << ")";
        else if (b < kAspectBins.size()) o << "[" << kAspectBins[b - 1] << ", " << kAspectBins[b] << ")";
        else o << "[" << kAspectBins.back() << ", inf)";
        o << " " << s.aspect_histogram[b] << "\n";
    }
    return o.str();
}

void check_quality(const Mesh& m, double min_angle_deg) {
    int worst = -1;
    double worst_angle = std::numeric_limits<double>::infinity();
    for (int t = 0; t < m.n_triangles(); ++t) {
        const int* n = &m.tri[3 * t];
        const double a2 = signed_area2(&m.xy[2 * n[0]], &m.xy[2 * n[1]], &m.xy[2 * n[2]]);
        if (a2 < 0) throw MeshError("inverted " + where(m, t) + " (clockwise nodes)");
        if (!(a2 > 0)) throw MeshError("degenerate " + where(m, t) + " (zero area)");
        const auto q = triangle_quality(&m.xy[2 * n[0]], &m.xy[2 * n[1]], &m.xy[2 * n[2]]);
        if (q.min_angle_deg < worst_angle) worst_angle = q.min_angle_deg, worst = t;
    }
    if (worst >= 0 && worst_angle < min_angle_deg) {
        std::ostringstream s;
        s.precision(3);
        s << "sliver " << where(m, worst) << ": minimum angle " << worst_angle << " deg, below the limit "
          << min_angle_deg << " deg (refine the mesh or fix the geometry there)";
        throw MeshError(s.str());
    }
}

}  // namespace fdem::mesh
