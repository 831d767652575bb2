// mesh/macro.cpp: macro-block pier -> OCC surfaces -> boolean fragment -> Gmsh mesh -> Mesh (layout: macro.hpp).
//
// The block outlines are plain vertex lists built from one set of doubles (r, y_t, y_b, L/2, L - r), so a corner
// shared by two blocks is the same double on both sides and the fragment merges it exactly (areas preserved).
#include "mesh/macro.hpp"

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "mesh/gmsh_source.hpp"
#include "mesh/occ_build.hpp"
#include "mesh/spec_check.hpp"

namespace fdem::mesh {

namespace {

using occ_build::add_group;
using occ_build::add_polygon;
using occ_build::curves_in;
using occ_build::points_at;

using Polygon = std::vector<std::array<double, 2>>;

constexpr double kPi = 3.14159265358979323846;

using spec_check::num;

}  // namespace

std::vector<std::string> check(const MacroPierSpec& s) {
    std::vector<std::string> bad;
    const spec_check::Lengths len{bad};
    len.positive(s.length, "length");
    len.positive(s.height, "height");
    len.positive(s.mesh_size, "mesh_size");
    spec_check::beam_and_sizes(len, s);
    len.nonnegative(s.base_height, "base_height");
    len.nonnegative(s.base_overhang, "base_overhang");
    if (!(s.texture_angle > 0 && s.texture_angle < 90))
        bad.push_back("geometry.texture_angle must be in (0, 90) deg, got " + num(s.texture_angle));
    if (!(s.horizontal_joint > 0 && s.horizontal_joint < 0.5 * s.length))
        bad.push_back("geometry.horizontal_joint must be in (0, length/2) = (0, " + num(0.5 * s.length) + ") m, got " +
                      num(s.horizontal_joint));
    if (!bad.empty()) return bad;
    const double t = std::tan(s.texture_angle * kPi / 180.0);
    const double rise = (s.length - s.horizontal_joint) * t;  // the upper and lower diagonals' drops together
    if (!(s.height > rise))
        bad.push_back("geometry.height " + num(s.height) + " m is not above (length - horizontal_joint) tan(texture_angle) = " +
                      num(rise) + " m: the upper and lower diagonal joints would cross (a squat pier needs another layout)");
    return bad;
}

std::vector<std::vector<std::array<double, 2>>> macro_block_outlines(const MacroPierSpec& s) {
    const auto problems = check(s);
    if (!problems.empty()) {
        std::string msg = problems.front();
        for (std::size_t i = 1; i < problems.size(); ++i) msg += "; " + problems[i];
        throw MeshError(msg);
    }
    const double L = s.length, H = s.height, w = s.horizontal_joint;
    const double t = std::tan(s.texture_angle * kPi / 180.0);
    const double r = 0.5 * (L - w);  // horizontal run of each diagonal
    const double xl = r, xm = 0.5 * L, xr = L - r;
    const double yt = H - r * t, yb = r * t;
    const double kt = yt + 0.5 * w * t, kb = yb - 0.5 * w * t;  // key apexes
    return {
        {{0, H}, {xl, yt}, {xm, kt}, {xr, yt}, {L, H}},             // cap, top
        {{0, 0}, {L, 0}, {xr, yb}, {xm, kb}, {xl, yb}},             // cap, bottom
        {{0, 0}, {xl, yb}, {xm, yb}, {xm, yt}, {xl, yt}, {0, H}},   // side, left
        {{L, 0}, {L, H}, {xr, yt}, {xm, yt}, {xm, yb}, {xr, yb}},   // side, right
        {{xl, yt}, {xm, yt}, {xr, yt}, {xm, kt}},                   // key, top
        {{xl, yb}, {xm, kb}, {xr, yb}, {xm, yb}},                   // key, bottom
    };
}

Mesh generate_macro_pier(const MacroPierSpec& s) {
    const auto outlines = macro_block_outlines(s);  // throws the check() problems
    const double L = s.length, H = s.height;
    const bool has_beam = s.beam_height > 0, has_base = s.base_height > 0;
    const double top = H + s.beam_height, bottom = -s.base_height;
    const double scale = std::max(L + 2 * std::max(s.beam_overhang, s.base_overhang), top - bottom);
    const double tol = 1e-5 * scale;  // OCC bounding boxes carry its tolerance (~1e-7 m)
    const double h_blocks = s.mesh_size;
    const double h_beam = s.mesh_size_beam > 0 ? s.mesh_size_beam : s.mesh_size;
    const double h_base = s.mesh_size_base > 0 ? s.mesh_size_base : s.mesh_size;

    GmshSession session;
    try {
        gmsh::model::add("macro");
        gmsh::vectorpair inputs;
        std::vector<int> role;  // 0 cap, 1 side, 2 key, 3 beam, 4 base
        for (std::size_t i = 0; i < outlines.size(); ++i) {
            inputs.push_back({2, add_polygon(outlines[i])});
            role.push_back(static_cast<int>(i / 2));
        }
        if (has_beam) {
            inputs.push_back({2, add_polygon({{-s.beam_overhang, H}, {L + s.beam_overhang, H},
                                              {L + s.beam_overhang, top}, {-s.beam_overhang, top}})});
            role.push_back(3);
        }
        if (has_base) {
            inputs.push_back({2, add_polygon({{-s.base_overhang, bottom}, {L + s.base_overhang, bottom},
                                              {L + s.base_overhang, 0.0}, {-s.base_overhang, 0.0}})});
            role.push_back(4);
        }
        gmsh::vectorpair out;
        std::vector<gmsh::vectorpair> map;
        gmsh::model::occ::fragment(inputs, {}, out, map);
        throw_on_gmsh_error("fragmenting the macro-blocks, beam and base");
        std::array<std::set<int>, 5> by_role;
        for (std::size_t i = 0; i < map.size() && i < inputs.size(); ++i)
            for (const auto& dt : map[i])
                if (dt.first == 2) by_role[role[i]].insert(dt.second);
        std::size_t pieces = 0;
        for (const auto& set : by_role) pieces += set.size();
        if (pieces != inputs.size())
            throw MeshError("geometry: the macro-block fragment gave " + std::to_string(pieces) + " surfaces for " +
                            std::to_string(inputs.size()) + " inputs (blocks overlap or vanish)");
        gmsh::model::occ::synchronize();

        // Sizes on the corner points: the smallest size of the surfaces meeting there.
        std::map<int, double> point_size;
        auto size_points = [&](const std::set<int>& surfaces, double h) {
            for (int sface : surfaces) {
                gmsh::vectorpair pts;
                gmsh::model::getBoundary({{2, sface}}, pts, false, false, true);
                for (const auto& dt : pts) {
                    auto it = point_size.emplace(dt.second, h).first;
                    it->second = std::min(it->second, h);
                }
            }
        };
        for (int k = 0; k < 3; ++k) size_points(by_role[k], h_blocks);
        size_points(by_role[3], h_beam);
        size_points(by_role[4], h_base);
        for (const auto& [pt, h] : point_size) gmsh::model::mesh::setSize({{0, pt}}, h);

        // Regions first, in the documented order.
        const char* names[] = {"cap", "side", "key", "beam", "base"};
        for (int k = 0; k < 5; ++k) add_group(2, {by_role[k].begin(), by_role[k].end()}, names[k]);
        std::set<int> blocks;
        for (int k = 0; k < 3; ++k) blocks.insert(by_role[k].begin(), by_role[k].end());
        add_group(1, curves_in(0, 0, L, 0, tol, blocks), "pier_bottom");
        add_group(1, curves_in(0, H, L, H, tol, blocks), "pier_top");
        add_group(1, curves_in(0, 0, 0, H, tol, blocks), "pier_left");
        add_group(1, curves_in(L, 0, L, H, tol, blocks), "pier_right");
        if (has_beam) {
            add_group(1, curves_in(-s.beam_overhang, top, L + s.beam_overhang, top, tol, by_role[3]), "beam_top");
            add_group(1, curves_in(-s.beam_overhang, H, -s.beam_overhang, top, tol, by_role[3]), "beam_left");
            add_group(1, curves_in(L + s.beam_overhang, H, L + s.beam_overhang, top, tol, by_role[3]), "beam_right");
        }
        if (has_base) {
            add_group(1, curves_in(-s.base_overhang, bottom, L + s.base_overhang, bottom, tol, by_role[4]), "base_bottom");
            add_group(1, curves_in(-s.base_overhang, bottom, -s.base_overhang, 0, tol, by_role[4]), "base_left");
            add_group(1, curves_in(L + s.base_overhang, bottom, L + s.base_overhang, 0, tol, by_role[4]), "base_right");
        }
        add_group(0, points_at(0, 0, tol), "toe_left");
        add_group(0, points_at(L, 0, tol), "toe_right");

        gmsh::model::mesh::generate(2);
        throw_on_gmsh_error("meshing the macro-block pier");
        return extract_current_model();
    } catch (const MeshError&) {
        throw;
    } catch (const std::exception& ex) {
        throw MeshError(std::string("Gmsh failed on the macro-block pier: ") + ex.what());
    } catch (...) {
        throw_on_gmsh_error("Gmsh failed on the macro-block pier");
        throw MeshError("Gmsh failed on the macro-block pier");
    }
}

}  // namespace fdem::mesh
