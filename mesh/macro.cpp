// mesh/macro.cpp: macro-block pier or wall -> OCC surfaces -> boolean fragment -> Gmsh mesh -> Mesh (layout:
// macro.hpp). panel_outlines builds one panel's blocks for both; mesh_blocks does the Gmsh part for both.
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

// The keys the pier and the wall share: sizes, beam and base, and the texture angle.
template <class Spec>
void common_checks(const spec_check::Lengths& len, const Spec& s) {
    len.positive(s.length, "length");
    len.positive(s.height, "height");
    len.positive(s.mesh_size, "mesh_size");
    spec_check::beam_and_sizes(len, s);
    len.nonnegative(s.base_height, "base_height");
    len.nonnegative(s.base_overhang, "base_overhang");
    if (!(s.texture_angle > 0 && s.texture_angle < 90))
        len.bad.push_back("geometry.texture_angle must be in (0, 90) deg, got " + num(s.texture_angle));
}

}  // namespace

std::vector<std::string> check(const MacroPierSpec& s) {
    std::vector<std::string> bad;
    const spec_check::Lengths len{bad};
    common_checks(len, s);
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

namespace {

// The tall layout of macro.hpp on the panel [x0, x1] x [y0, y1]. For the pier (x0 = y0 = 0, x1 = L, y1 = H) every
// expression below gives the same double as the pier code before the wall existed (0 + a = a, L - 0 = L).
std::vector<Polygon> tall_panel(double x0, double y0, double x1, double y1, double t, double w) {
    const double L = x1 - x0;
    const double r = 0.5 * (L - w);  // horizontal run of each diagonal
    const double xl = x0 + r, xm = x0 + 0.5 * L, xr = x1 - r;
    const double yt = y1 - r * t, yb = y0 + r * t;
    const double kt = yt + 0.5 * w * t, kb = yb - 0.5 * w * t;  // key apexes
    return {
        {{x0, y1}, {xl, yt}, {xm, kt}, {xr, yt}, {x1, y1}},             // cap, top
        {{x0, y0}, {x1, y0}, {xr, yb}, {xm, kb}, {xl, yb}},             // cap, bottom
        {{x0, y0}, {xl, yb}, {xm, yb}, {xm, yt}, {xl, yt}, {x0, y1}},   // side, left
        {{x1, y0}, {x1, y1}, {xr, yt}, {xm, yt}, {xm, yb}, {xr, yb}},   // side, right
        {{xl, yt}, {xm, yt}, {xr, yt}, {xm, kt}},                       // key, top
        {{xl, yb}, {xm, kb}, {xr, yb}, {xm, yb}},                       // key, bottom
    };
}

void throw_problems(const std::vector<std::string>& problems) {
    if (problems.empty()) return;
    std::string msg = problems.front();
    for (std::size_t i = 1; i < problems.size(); ++i) msg += "; " + problems[i];
    throw MeshError(msg);
}

}  // namespace

std::vector<std::vector<std::array<double, 2>>> panel_outlines(double x0, double y0, double x1, double y1,
                                                               double tan_phi, double w, bool transposed) {
    if (!transposed) return tall_panel(x0, y0, x1, y1, tan_phi, w);
    // Tall in swapped coordinates (x' = y, y' = x) with slope dy'/dx' = 1 / tan_phi, then swapped back; the swap
    // mirrors, so each outline is reversed to stay counter-clockwise.
    auto out = tall_panel(y0, x0, y1, x1, 1.0 / tan_phi, w);
    for (auto& poly : out) {
        for (auto& v : poly) std::swap(v[0], v[1]);
        std::reverse(poly.begin(), poly.end());
    }
    return out;
}

std::vector<std::vector<std::array<double, 2>>> macro_block_outlines(const MacroPierSpec& s) {
    throw_problems(check(s));
    const double t = std::tan(s.texture_angle * kPi / 180.0);
    return panel_outlines(0.0, 0.0, s.length, s.height, t, s.horizontal_joint, false);
}

namespace {

// What the shared Gmsh part needs: the masonry blocks with their region index, the region names in order, and the
// frame (extent of the masonry, beam, base, mesh sizes) common to MacroPierSpec and MacroWallSpec.
struct BlockSet {
    std::vector<Polygon> outlines;
    std::vector<int> region;                 // index into region_names, per outline
    std::vector<std::string> region_names;   // masonry regions; "beam" and "base" follow
    const char* edge_prefix = "pier";        // curve groups PREFIX_bottom, _top, _left, _right
    const char* what = "the macro-block pier";  // for messages
    double length = 0, height = 0;           // m, masonry extent [0, length] x [0, height]
    double beam_height = 0, beam_overhang = 0, base_height = 0, base_overhang = 0;  // m
    double mesh_size = 0, mesh_size_beam = 0, mesh_size_base = 0;                   // m
};

template <class Spec>
BlockSet frame_of(const Spec& s) {
    BlockSet b;
    b.length = s.length;
    b.height = s.height;
    b.beam_height = s.beam_height;
    b.beam_overhang = s.beam_overhang;
    b.base_height = s.base_height;
    b.base_overhang = s.base_overhang;
    b.mesh_size = s.mesh_size;
    b.mesh_size_beam = s.mesh_size_beam;
    b.mesh_size_base = s.mesh_size_base;
    return b;
}

// Blocks, beam and base -> OCC surfaces -> one boolean fragment (shared nodes on every joint) -> point sizes ->
// physical groups (regions first, in order) -> 2D mesh. The surfaces are added in the order given, beam and base
// last, so the pier's mesh is the one it had before the wall shared this code.
Mesh mesh_blocks(const BlockSet& b) {
    const double L = b.length, H = b.height;
    const bool has_beam = b.beam_height > 0, has_base = b.base_height > 0;
    const double top = H + b.beam_height, bottom = -b.base_height;
    const double scale = std::max(L + 2 * std::max(b.beam_overhang, b.base_overhang), top - bottom);
    const double tol = 1e-5 * scale;  // OCC bounding boxes carry its tolerance (~1e-7 m)
    const double h_beam = b.mesh_size_beam > 0 ? b.mesh_size_beam : b.mesh_size;
    const double h_base = b.mesh_size_base > 0 ? b.mesh_size_base : b.mesh_size;
    const int n_masonry = static_cast<int>(b.region_names.size());
    const int beam_role = n_masonry, base_role = n_masonry + 1;
    const std::string what = b.what;

    GmshSession session;
    try {
        gmsh::model::add("macro");
        gmsh::vectorpair inputs;
        std::vector<int> role;  // region index; beam_role, base_role
        for (std::size_t i = 0; i < b.outlines.size(); ++i) {
            inputs.push_back({2, add_polygon(b.outlines[i])});
            role.push_back(b.region[i]);
        }
        if (has_beam) {
            inputs.push_back({2, add_polygon({{-b.beam_overhang, H}, {L + b.beam_overhang, H},
                                              {L + b.beam_overhang, top}, {-b.beam_overhang, top}})});
            role.push_back(beam_role);
        }
        if (has_base) {
            inputs.push_back({2, add_polygon({{-b.base_overhang, bottom}, {L + b.base_overhang, bottom},
                                              {L + b.base_overhang, 0.0}, {-b.base_overhang, 0.0}})});
            role.push_back(base_role);
        }
        gmsh::vectorpair out;
        std::vector<gmsh::vectorpair> map;
        gmsh::model::occ::fragment(inputs, {}, out, map);
        throw_on_gmsh_error("fragmenting the macro-blocks, beam and base");
        std::vector<std::set<int>> by_role(static_cast<std::size_t>(n_masonry + 2));
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
        for (int k = 0; k < n_masonry; ++k) size_points(by_role[k], b.mesh_size);
        size_points(by_role[beam_role], h_beam);
        size_points(by_role[base_role], h_base);
        for (const auto& [pt, h] : point_size) gmsh::model::mesh::setSize({{0, pt}}, h);

        // Regions first, in the documented order (a region without blocks gets no group).
        for (int k = 0; k < n_masonry; ++k) add_group(2, {by_role[k].begin(), by_role[k].end()}, b.region_names[k]);
        add_group(2, {by_role[beam_role].begin(), by_role[beam_role].end()}, "beam");
        add_group(2, {by_role[base_role].begin(), by_role[base_role].end()}, "base");
        std::set<int> blocks;
        for (int k = 0; k < n_masonry; ++k) blocks.insert(by_role[k].begin(), by_role[k].end());
        const std::string pre = b.edge_prefix;
        add_group(1, curves_in(0, 0, L, 0, tol, blocks), pre + "_bottom");
        add_group(1, curves_in(0, H, L, H, tol, blocks), pre + "_top");
        add_group(1, curves_in(0, 0, 0, H, tol, blocks), pre + "_left");
        add_group(1, curves_in(L, 0, L, H, tol, blocks), pre + "_right");
        const std::set<int>& beam = by_role[beam_role];
        const std::set<int>& base = by_role[base_role];
        if (has_beam) {
            add_group(1, curves_in(-b.beam_overhang, top, L + b.beam_overhang, top, tol, beam), "beam_top");
            add_group(1, curves_in(-b.beam_overhang, H, -b.beam_overhang, top, tol, beam), "beam_left");
            add_group(1, curves_in(L + b.beam_overhang, H, L + b.beam_overhang, top, tol, beam), "beam_right");
        }
        if (has_base) {
            add_group(1, curves_in(-b.base_overhang, bottom, L + b.base_overhang, bottom, tol, base), "base_bottom");
            add_group(1, curves_in(-b.base_overhang, bottom, -b.base_overhang, 0, tol, base), "base_left");
            add_group(1, curves_in(L + b.base_overhang, bottom, L + b.base_overhang, 0, tol, base), "base_right");
        }
        add_group(0, points_at(0, 0, tol), "toe_left");
        add_group(0, points_at(L, 0, tol), "toe_right");

        gmsh::model::mesh::generate(2);
        throw_on_gmsh_error("meshing " + what);
        return extract_current_model();
    } catch (const MeshError&) {
        throw;
    } catch (const std::exception& ex) {
        throw MeshError("Gmsh failed on " + what + ": " + ex.what());
    } catch (...) {
        throw_on_gmsh_error("Gmsh failed on " + what);
        throw MeshError("Gmsh failed on " + what);
    }
}

}  // namespace

Mesh generate_macro_pier(const MacroPierSpec& s) {
    BlockSet b = frame_of(s);
    b.outlines = macro_block_outlines(s);  // throws the check() problems
    b.region = {0, 0, 1, 1, 2, 2};
    b.region_names = {"cap", "side", "key"};
    return mesh_blocks(b);
}

// ---- type = "macro_wall" (layout: macro.hpp "WALL WITH OPENINGS") ----

namespace {

// A rectangular cell of the wall's partition.
struct Cell {
    double x0, y0, x1, y1;  // m
    int kind;               // 0 pier panel, 1 spandrel panel, 2 node, 3 lintel
    std::string name;       // for messages: "pier panel 1", "spandrel above opening 2", ...
};

// The openings' input indices (0-based) sorted by x.
std::vector<std::size_t> by_x(const MacroWallSpec& s) {
    std::vector<std::size_t> order(s.openings.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return s.openings[a].x < s.openings[b].x; });
    return order;
}

// The partition: pier panels left to right, then spandrels (per opening: above, below), then nodes (per pier:
// above, below), then with a lintel the lintels (per opening) and the lintel band's nodes (per pier). Assumes the
// openings passed check(). Every coordinate is one of the spec's doubles (0, x, x + width, y, y + height, length,
// height) or one computed once from them (x - lintel_bearing, x + width + lintel_bearing, y + height +
// lintel_height), so touching cells share exact corners.
std::vector<Cell> wall_cells(const MacroWallSpec& s) {
    const auto order = by_x(s);
    const double ys = s.openings.front().y, yl = ys + s.openings.front().height, H = s.height;
    const bool lintel = s.lintel_height > 0;
    const double yu = lintel ? yl + s.lintel_height : yl;  // the upper band's bottom
    std::vector<double> px0{0.0}, px1;  // pier columns
    for (std::size_t i : order) {
        px1.push_back(s.openings[i].x);
        px0.push_back(s.openings[i].x + s.openings[i].width);
    }
    px1.push_back(s.length);
    std::vector<Cell> cells;
    for (std::size_t p = 0; p < px0.size(); ++p)
        cells.push_back({px0[p], ys, px1[p], yl, 0, "pier panel " + std::to_string(p + 1)});
    for (std::size_t k = 0; k < order.size(); ++k) {
        const std::string o = " opening " + std::to_string(order[k] + 1);
        if (yu < H) cells.push_back({px1[k], yu, px0[k + 1], H, 1, "spandrel above" + o});
        if (ys > 0) cells.push_back({px1[k], 0.0, px0[k + 1], ys, 1, "spandrel below" + o});
    }
    for (std::size_t p = 0; p < px0.size(); ++p) {
        if (yu < H) cells.push_back({px0[p], yu, px1[p], H, 2, "node above pier " + std::to_string(p + 1)});
        if (ys > 0) cells.push_back({px0[p], 0.0, px1[p], ys, 2, "node below pier " + std::to_string(p + 1)});
    }
    if (!lintel) return cells;
    // The lintel band [yl, yu]: a lintel over each opening reaching lintel_bearing into the piers on both sides,
    // the rest of each pier's width a node. The bearing ends are computed once each and used by both neighbours.
    const double b = s.lintel_bearing;
    std::vector<double> lx0, lx1;  // lintel k spans [lx0[k], lx1[k]]
    for (std::size_t k = 0; k < order.size(); ++k) {
        lx0.push_back(px1[k] - b);
        lx1.push_back(px0[k + 1] + b);
        cells.push_back({lx0[k], yl, lx1[k], yu, 3, "lintel over opening " + std::to_string(order[k] + 1)});
    }
    for (std::size_t p = 0; p < px0.size(); ++p) {
        const double x0 = p > 0 ? lx1[p - 1] : px0[p], x1 = p + 1 < px0.size() ? lx0[p] : px1[p];
        cells.push_back({x0, yl, x1, yu, 2, "node beside the lintels over pier " + std::to_string(p + 1)});
    }
    return cells;
}

// Tall layout when H_p > (L_p - w) t, else transposed (macro.hpp: one of the two always holds).
bool is_tall(const Cell& c, double t, double w) { return c.y1 - c.y0 > (c.x1 - c.x0 - w) * t; }

std::string range(double a, double b) { return "[" + num(a) + ", " + num(b) + "]"; }

}  // namespace

std::vector<std::string> check(const MacroWallSpec& s) {
    std::vector<std::string> bad;
    const spec_check::Lengths len{bad};
    common_checks(len, s);
    len.nonnegative(s.lintel_height, "lintel_height");
    len.nonnegative(s.lintel_bearing, "lintel_bearing");
    if (s.lintel_bearing > 0 && !(s.lintel_height > 0))
        bad.push_back("geometry.lintel_bearing = " + num(s.lintel_bearing) + " m needs a lintel: geometry.lintel_height "
                      "must be > 0 with it, got " + num(s.lintel_height) + " m");
    if (!(s.horizontal_joint > 0))
        bad.push_back("geometry.horizontal_joint must be > 0 (m), got " + num(s.horizontal_joint));
    if (s.openings.empty()) {
        bad.push_back("geometry.openings: macro_wall needs at least one opening ([[geometry.openings]] {x, y, width, "
                      "height}); a wall without openings is one pier: type = \"macro\"");
        return bad;
    }
    auto key = [](std::size_t i) { return "geometry.openings[" + std::to_string(i + 1) + "]"; };
    for (std::size_t i = 0; i < s.openings.size(); ++i) {
        const auto& o = s.openings[i];
        if (!(o.width > 0)) bad.push_back(key(i) + ".width must be > 0 (m), got " + num(o.width));
        if (!(o.height > 0)) bad.push_back(key(i) + ".height must be > 0 (m), got " + num(o.height));
    }
    if (!bad.empty()) return bad;
    // One row: the first opening sets the sill and lintel.
    const auto& first = s.openings.front();
    for (std::size_t i = 1; i < s.openings.size(); ++i) {
        const auto& o = s.openings[i];
        if (o.y != first.y)
            bad.push_back(key(i) + ".y = " + num(o.y) + " m differs from geometry.openings[1].y = " + num(first.y) +
                          " m: macro_wall needs one row of openings (the same y and the same height for all)");
        if (o.height != first.height)
            bad.push_back(key(i) + ".height = " + num(o.height) + " m differs from geometry.openings[1].height = " +
                          num(first.height) + " m: macro_wall needs one row of openings (the same y and the same "
                          "height for all)");
    }
    if (!(first.y >= 0)) bad.push_back(key(0) + ".y (the sill) must be >= 0 (m), got " + num(first.y));
    if (!(first.y + first.height <= s.height))
        bad.push_back(key(0) + ": the lintel y + height = " + num(first.y + first.height) +
                      " m is above the wall's geometry.height = " + num(s.height) + " m");
    // Piers of positive length at both ends and between openings (in x order).
    const auto order = by_x(s);
    const auto& lo = s.openings[order.front()];
    if (!(lo.x > 0))
        bad.push_back(key(order.front()) + ".x = " + num(lo.x) +
                      " m leaves no pier at the wall's left end (x = 0): an opening must lie strictly inside the wall");
    const auto& hi = s.openings[order.back()];
    if (!(hi.x + hi.width < s.length))
        bad.push_back(key(order.back()) + ": x + width = " + num(hi.x + hi.width) +
                      " m leaves no pier at the wall's right end (geometry.length = " + num(s.length) +
                      " m): an opening must lie strictly inside the wall");
    for (std::size_t k = 0; k + 1 < order.size(); ++k) {
        const auto& a = s.openings[order[k]];
        const auto& b = s.openings[order[k + 1]];
        if (!(b.x > a.x + a.width))
            bad.push_back(key(order[k]) + " (x in " + range(a.x, a.x + a.width) + " m) and " + key(order[k + 1]) +
                          " (x in " + range(b.x, b.x + b.width) +
                          " m) overlap or touch: macro_wall needs a pier of positive length between two openings");
    }
    if (!bad.empty()) return bad;
    // The lintel band must fit under the wall top, and the bearings must leave node material on every pier.
    if (s.lintel_height > 0) {
        const double yl = first.y + first.height;
        if (!(yl + s.lintel_height <= s.height))
            bad.push_back("geometry.lintel_height = " + num(s.lintel_height) + " m puts the lintels' top (y + height + "
                          "lintel_height = " + num(yl + s.lintel_height) + " m) above the wall's geometry.height = " +
                          num(s.height) + " m");
        const double b = s.lintel_bearing;
        const std::size_t n = order.size() + 1;  // piers
        for (std::size_t p = 0; p < n; ++p) {
            const double x0 = p == 0 ? 0.0 : s.openings[order[p - 1]].x + s.openings[order[p - 1]].width;
            const double x1 = p + 1 < n ? s.openings[order[p]].x : s.length;
            const int bearings = (p > 0) + (p + 1 < n);
            // The node's ends as wall_cells computes them (x + width + bearing, x - bearing).
            const double n0 = p > 0 ? x0 + b : x0, n1 = p + 1 < n ? x1 - b : x1;
            if (!(n0 < n1))
                bad.push_back("geometry.lintel_bearing = " + num(b) + " m leaves no node between the lintels on pier " +
                              std::to_string(p + 1) + " (x in " + range(x0, x1) + " m): its " +
                              (bearings == 1 ? "bearing" : std::to_string(bearings) + " bearings") + " (" +
                              num(bearings * b) + " m) must be shorter than its length " + num(x1 - x0) + " m");
        }
        if (!bad.empty()) return bad;
    }
    // Every panel's keys must fit: w below half the panel's length (tall) or height (transposed).
    const double t = std::tan(s.texture_angle * kPi / 180.0), w = s.horizontal_joint;
    for (const Cell& c : wall_cells(s)) {
        if (c.kind >= 2) continue;  // nodes and lintels are plain blocks
        const bool tall = is_tall(c, t, w);
        const double side = tall ? c.x1 - c.x0 : c.y1 - c.y0;
        if (!(w < 0.5 * side))
            bad.push_back("geometry.horizontal_joint = " + num(w) + " m does not fit the " + c.name + " (x in " +
                          range(c.x0, c.x1) + " m, y in " + range(c.y0, c.y1) + " m, " +
                          (tall ? "tall layout): must be below half its length, " : "transposed layout): must be "
                                                                                    "below half its height, ") +
                          num(0.5 * side) + " m");
    }
    return bad;
}

std::vector<MacroWallBlock> macro_wall_blocks(const MacroWallSpec& s) {
    throw_problems(check(s));
    const double t = std::tan(s.texture_angle * kPi / 180.0), w = s.horizontal_joint;
    static const char* const kPanelRegions[2][3] = {{"cap", "side", "key"},
                                                    {"spandrel_cap", "spandrel_side", "spandrel_key"}};
    std::vector<MacroWallBlock> out;
    for (const Cell& c : wall_cells(s)) {
        if (c.kind >= 2) {
            out.push_back({{{c.x0, c.y0}, {c.x1, c.y0}, {c.x1, c.y1}, {c.x0, c.y1}}, c.kind == 2 ? "node" : "lintel",
                           false});
            continue;
        }
        const bool transposed = !is_tall(c, t, w);
        const auto polys = panel_outlines(c.x0, c.y0, c.x1, c.y1, t, w, transposed);
        for (std::size_t i = 0; i < polys.size(); ++i) out.push_back({polys[i], kPanelRegions[c.kind][i / 2], transposed});
    }
    return out;
}

Mesh generate_macro_wall(const MacroWallSpec& s) {
    const auto blocks = macro_wall_blocks(s);  // throws the check() problems
    BlockSet b = frame_of(s);
    b.region_names = {"cap", "side", "key", "spandrel_cap", "spandrel_side", "spandrel_key", "node", "lintel"};
    b.edge_prefix = "wall";
    b.what = "the macro-block wall";
    for (const auto& blk : blocks) {
        b.outlines.push_back(blk.outline);
        b.region.push_back(static_cast<int>(std::find(b.region_names.begin(), b.region_names.end(), blk.region) -
                                            b.region_names.begin()));
    }
    return mesh_blocks(b);
}

// Expected triangle count of a macro-block pier (equilateral triangles of edge h, as for a wall).
double expected_triangles(const MacroPierSpec& m) {
    const double per = 4.0 / std::sqrt(3.0);
    if (!(m.mesh_size > 0)) return 0;
    const double hb = m.mesh_size_base > 0 ? m.mesh_size_base : m.mesh_size;
    const double hm = m.mesh_size_beam > 0 ? m.mesh_size_beam : m.mesh_size;
    return per * m.length * m.height / (m.mesh_size * m.mesh_size) + 12 +
           per * (m.length + 2 * m.beam_overhang) * m.beam_height / (hm * hm) +
           per * (m.length + 2 * m.base_overhang) * m.base_height / (hb * hb);
}

// Expected triangle count of a macro-block wall: the masonry area less the openings, beam and base.
double expected_triangles(const MacroWallSpec& m) {
    const double per = 4.0 / std::sqrt(3.0);
    if (!(m.mesh_size > 0)) return 0;
    const double hb = m.mesh_size_base > 0 ? m.mesh_size_base : m.mesh_size;
    const double hm = m.mesh_size_beam > 0 ? m.mesh_size_beam : m.mesh_size;
    double area = m.length * m.height;
    for (const auto& o : m.openings) area -= o.width * o.height;
    return per * std::max(area, 0.0) / (m.mesh_size * m.mesh_size) + 12.0 * (2 * m.openings.size() + 1) +
           per * (m.length + 2 * m.beam_overhang) * m.beam_height / (hm * hm) +
           per * (m.length + 2 * m.base_overhang) * m.base_height / (hb * hb);
}

}  // namespace fdem::mesh
