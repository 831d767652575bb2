// mesh/occ_build.hpp: small helpers of the Gmsh OpenCASCADE generators (mesh/wall.cpp, mesh/macro.cpp): a polygon
// as a plane surface, the curves and points found in a box, a named physical group. They act on the current Gmsh
// model (a gmsh_source.hpp session must be open).
#pragma once

#include <gmsh.h>

#include <algorithm>
#include <array>
#include <set>
#include <string>
#include <vector>

namespace fdem::mesh::occ_build {

using Polygon = std::vector<std::array<double, 2>>;

// A closed polygon (vertices in order, x y in m) as an OCC plane surface; returns its tag.
inline int add_polygon(const Polygon& p) {
    std::vector<int> pts, lines;
    for (const auto& v : p) pts.push_back(gmsh::model::occ::addPoint(v[0], v[1], 0));
    for (std::size_t i = 0; i < pts.size(); ++i) lines.push_back(gmsh::model::occ::addLine(pts[i], pts[(i + 1) % pts.size()]));
    return gmsh::model::occ::addPlaneSurface({gmsh::model::occ::addCurveLoop(lines)});
}

// The curves inside the box [x0, x1] x [y0, y1] (grown by tol) that bound one of `surfaces`, ascending.
inline std::vector<int> curves_in(double x0, double y0, double x1, double y1, double tol, const std::set<int>& surfaces) {
    gmsh::vectorpair found;
    gmsh::model::getEntitiesInBoundingBox(x0 - tol, y0 - tol, -tol, x1 + tol, y1 + tol, tol, found, 1);
    std::vector<int> out;
    for (const auto& [dim, tag] : found) {
        std::vector<int> up, down;
        gmsh::model::getAdjacencies(dim, tag, up, down);
        for (int sface : up)
            if (surfaces.count(sface)) {
                out.push_back(tag);
                break;
            }
    }
    std::sort(out.begin(), out.end());
    return out;
}

// The points within tol of (x, y).
inline std::vector<int> points_at(double x, double y, double tol) {
    gmsh::vectorpair found;
    gmsh::model::getEntitiesInBoundingBox(x - tol, y - tol, -tol, x + tol, y + tol, tol, found, 0);
    std::vector<int> out;
    for (const auto& dt : found) out.push_back(dt.second);
    return out;
}

// A physical group of dimension dim named `name` (nothing when tags is empty).
inline void add_group(int dim, const std::vector<int>& tags, const std::string& name) {
    if (tags.empty()) return;
    gmsh::model::setPhysicalName(dim, gmsh::model::addPhysicalGroup(dim, tags), name);
}

}  // namespace fdem::mesh::occ_build
