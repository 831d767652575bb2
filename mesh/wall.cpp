// mesh/wall.cpp: masonry wall -> OCC surfaces -> boolean fragment -> Gmsh mesh -> Mesh.
//
// DATA LAYOUT
//   Unit outlines are built as plain vertex lists first (wall_unit_outlines), so that the layout logic (bond,
//   courses, half units) is testable without Gmsh and every shared corner is computed by the same expression on
//   both sides of a joint (identical doubles, so the fragment merges them exactly and areas are preserved).
//   Each outline becomes one OCC plane surface; openings are cut from them; then one fragment of all units, beam
//   and base makes the interfaces conforming. The fragment map tells which output surface came from which input:
//   an output claimed by two inputs is an overlap, which we report instead of meshing.
#include "mesh/wall.hpp"

#include <gmsh.h>

#include <algorithm>
#include <cmath>
#include <limits>
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

using spec_check::num;

double joint_of(const WallSpec& s) { return s.joint == "mortar" ? s.joint_thickness : 0.0; }
double pitch_x(const WallSpec& s) { return s.unit_length + joint_of(s); }
double pitch_y(const WallSpec& s) { return s.unit_height + joint_of(s); }

double signed_area(const Polygon& p) {
    double a2 = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        const auto& u = p[i];
        const auto& v = p[(i + 1) % p.size()];
        a2 += u[0] * v[1] - v[0] * u[1];
    }
    return 0.5 * a2;
}

// Proper crossing of segments pq and rs (shared end points and collinear touching are not crossings).
bool segments_cross(const std::array<double, 2>& p, const std::array<double, 2>& q, const std::array<double, 2>& r,
                    const std::array<double, 2>& s) {
    auto orient = [](const std::array<double, 2>& a, const std::array<double, 2>& b, const std::array<double, 2>& c) {
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    };
    const double d1 = orient(p, q, r), d2 = orient(p, q, s), d3 = orient(r, s, p), d4 = orient(r, s, q);
    return ((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0));
}

struct Extent {
    double length = 0, height = 0;
    int courses = 0;
};

// Wall extents after defaults; only meaningful when check() found nothing.
Extent extent_of(const WallSpec& s) {
    Extent e;
    if (!s.stones.empty()) {
        double xmax = 0, ymax = 0;
        for (const auto& st : s.stones)
            for (const auto& v : st) xmax = std::max(xmax, v[0]), ymax = std::max(ymax, v[1]);
        e.length = s.length > 0 ? s.length : xmax;
        e.height = s.height > 0 ? s.height : ymax;
        return e;
    }
    e.length = s.length;
    const double py = pitch_y(s);
    e.courses = s.courses > 0 ? s.courses : static_cast<int>(std::lround(s.height / py));
    e.height = e.courses * py;
    return e;
}

}  // namespace

std::vector<std::string> check(const WallSpec& s) {
    std::vector<std::string> bad;
    const spec_check::Lengths len{bad};
    len.positive(s.mesh_size, "mesh_size");
    spec_check::beam_and_sizes(len, s);
    len.nonnegative(s.base_overhang, "base_overhang");
    if (s.joint != "dry" && s.joint != "mortar")
        bad.push_back("geometry.joint must be \"dry\" or \"mortar\", got \"" + s.joint + "\"");
    if (s.joint == "mortar") len.positive(s.joint_thickness, "joint_thickness");
    if (s.base != "none" && s.base != "fixed" && s.base != "slab")
        bad.push_back("geometry.base must be \"none\", \"fixed\" or \"slab\", got \"" + s.base + "\"");
    if (s.base == "slab") len.positive(s.base_height, "base_height");
    if (s.unit_cracks != "anywhere" && s.unit_cracks != "middle")
        bad.push_back("geometry.unit_cracks must be \"anywhere\" or \"middle\", got \"" + s.unit_cracks + "\"");
    if (s.unit_cracks == "middle" && !s.stones.empty())
        bad.push_back("geometry.unit_cracks = \"middle\" needs generated courses, not stones");

    if (s.stones.empty()) {
        len.positive(s.length, "length");
        len.positive(s.unit_length, "unit_length");
        len.positive(s.unit_height, "unit_height");
        if (s.courses < 0) bad.push_back("geometry.courses must be >= 0, got " + std::to_string(s.courses));
        if (s.courses == 0 && !(s.height > 0))
            bad.push_back("geometry: give the wall height or the number of courses");
        if (s.bond != "running" && s.bond != "stack" && s.bond != "offsets")
            bad.push_back("geometry.bond must be \"running\", \"stack\" or \"offsets\", got \"" + s.bond + "\"");
        if (s.bond == "offsets" && s.offsets.empty())
            bad.push_back("geometry.offsets: bond = \"offsets\" needs at least one course offset (m)");
        if (bad.empty()) {
            const double py = pitch_y(s);
            if (s.courses > 0 && s.height > 0 && std::abs(s.courses * py - s.height) > 1e-9 * s.height)
                bad.push_back("geometry: height " + num(s.height) + " m does not equal courses x course pitch = " +
                              std::to_string(s.courses) + " x " + num(py) + " m");
            if (s.courses == 0) {
                const double n = s.height / py;
                if (std::abs(n - std::round(n)) > 1e-9 * std::max(1.0, n) || std::round(n) < 1)
                    bad.push_back("geometry: height " + num(s.height) + " m is not a whole number of courses of " +
                                  num(py) + " m (" + num(n) + ")");
            }
        }
    } else {
        for (std::size_t i = 0; i < s.stones.size(); ++i) {
            const auto& p = s.stones[i];
            const std::string name = "geometry.stones[" + std::to_string(i) + "]";
            if (p.size() < 3) {
                bad.push_back(name + " has " + std::to_string(p.size()) + " vertices; a stone needs at least 3");
                continue;
            }
            double scale = 0;
            for (const auto& v : p) scale = std::max({scale, std::abs(v[0]), std::abs(v[1])});
            if (std::abs(signed_area(p)) <= 1e-12 * scale * scale) {
                bad.push_back(name + " has zero area");
                continue;
            }
            bool crossing = false;
            for (std::size_t a = 0; a < p.size() && !crossing; ++a)
                for (std::size_t b = a + 1; b < p.size() && !crossing; ++b)
                    crossing = segments_cross(p[a], p[(a + 1) % p.size()], p[b], p[(b + 1) % p.size()]);
            if (crossing) bad.push_back(name + " is self-intersecting");
            for (const auto& v : p)
                if (v[0] < -1e-12 || v[1] < -1e-12) {
                    bad.push_back(name + " has a vertex (" + num(v[0]) + ", " + num(v[1]) +
                                  ") m outside the wall (x >= 0, y >= 0)");
                    break;
                }
        }
    }
    if (!bad.empty()) return bad;

    const Extent e = extent_of(s);
    const double tol = 1e-9 * std::max(e.length, e.height);
    if (!s.stones.empty())
        for (std::size_t i = 0; i < s.stones.size(); ++i)
            for (const auto& v : s.stones[i])
                if (v[0] > e.length + tol || v[1] > e.height + tol) {
                    bad.push_back("geometry.stones[" + std::to_string(i) + "] has a vertex (" + num(v[0]) + ", " +
                                  num(v[1]) + ") m outside the wall [0, " + num(e.length) + "] x [0, " +
                                  num(e.height) + "] m");
                    break;
                }
    for (std::size_t i = 0; i < s.openings.size(); ++i) {
        const auto& o = s.openings[i];
        const std::string name = "geometry.openings[" + std::to_string(i) + "]";
        if (!(o.width > 0) || !(o.height > 0)) {
            bad.push_back(name + " needs width > 0 and height > 0 (m)");
            continue;
        }
        if (o.x < -tol || o.y < -tol || o.x + o.width > e.length + tol || o.y + o.height > e.height + tol)
            bad.push_back(name + " [" + num(o.x) + ", " + num(o.x + o.width) + "] x [" + num(o.y) + ", " +
                          num(o.y + o.height) + "] m is outside the wall [0, " + num(e.length) + "] x [0, " +
                          num(e.height) + "] m");
    }
    for (std::size_t i = 0; i < s.refine.size(); ++i) {
        const auto& r = s.refine[i];
        if (!(r.size > 0) || !(r.width > 0) || !(r.height > 0))
            bad.push_back("geometry.refine[" + std::to_string(i) + "] needs size, width and height > 0 (m)");
    }
    return bad;
}

std::vector<std::vector<std::array<double, 2>>> wall_unit_outlines(const WallSpec& s) {
    const auto problems = check(s);
    if (!problems.empty()) {
        std::string msg = problems.front();
        for (std::size_t i = 1; i < problems.size(); ++i) msg += "; " + problems[i];
        throw MeshError(msg);
    }
    if (!s.stones.empty()) return s.stones;

    const Extent e = extent_of(s);
    const double px = pitch_x(s), py = pitch_y(s);
    std::vector<double> offsets;
    if (s.bond == "running") offsets = {0.0, 0.5 * px};
    else if (s.bond == "stack") offsets = {0.0};
    else offsets = s.offsets;

    // A head joint closer than this to another joint or to a wall end is dropped: it would make a sliver unit.
    const double min_piece = 1e-6 * px;
    std::vector<Polygon> units;
    for (int c = 0; c < e.courses; ++c) {
        double o = std::fmod(offsets[static_cast<std::size_t>(c) % offsets.size()], px);
        if (o < 0) o += px;
        std::vector<double> xs{0.0};
        for (int k = 0;; ++k) {
            const double x = o + k * px;
            if (x >= e.length - min_piece) break;
            if (x > xs.back() + min_piece) xs.push_back(x);
        }
        xs.push_back(e.length);
        const double y0 = c * py, y1 = (c + 1) * py;
        for (std::size_t i = 0; i + 1 < xs.size(); ++i)
            units.push_back({{xs[i], y0}, {xs[i + 1], y0}, {xs[i + 1], y1}, {xs[i], y1}});
    }
    return units;
}

namespace {


int add_box(double x0, double y0, double x1, double y1) {
    return add_polygon({{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}});
}

// unit_cracks = "middle": the two halves of a split unit are one body (one continuum with a potential crack), so
// the triangles of the halves of outline i (split[i] not NaN; found by their centroid) get one body id; bodies are
// then renumbered in order of first appearance.
void join_split_units(Mesh& m, const std::vector<Polygon>& outlines, const std::vector<double>& split) {
    const int units = m.find_region("units");
    if (units < 0 || m.tri_body.empty()) return;
    std::map<int, int> first_body;  // outline -> body of its first triangle
    std::map<int, int> same;        // body -> body it joins
    for (int t = 0; t < m.n_triangles(); ++t) {
        if (m.tri_region[t] != units) continue;
        double cx = 0, cy = 0;
        for (int k = 0; k < 3; ++k) cx += m.xy[2 * m.tri[3 * t + k]] / 3, cy += m.xy[2 * m.tri[3 * t + k] + 1] / 3;
        for (std::size_t i = 0; i < outlines.size(); ++i) {
            if (std::isnan(split[i])) continue;
            const auto& p = outlines[i];
            if (cx < p[0][0] || cx > p[1][0] || cy < p[0][1] || cy > p[2][1]) continue;
            const int b = first_body.emplace(static_cast<int>(i), m.tri_body[t]).first->second;
            if (b != m.tri_body[t]) same[m.tri_body[t]] = b;
            break;
        }
    }
    std::map<int, int> renumber;
    for (int& b : m.tri_body) {
        auto j = same.find(b);
        const int root = j == same.end() ? b : j->second;
        b = renumber.emplace(root, static_cast<int>(renumber.size())).first->second;
    }
}


}  // namespace

Mesh generate_wall(const WallSpec& s) {
    const auto outlines = wall_unit_outlines(s);  // throws the check() problems
    const Extent e = extent_of(s);
    const bool has_beam = s.beam_height > 0, has_base = s.base == "slab";
    const double top = e.height + s.beam_height, bottom = has_base ? -s.base_height : 0.0;
    const double scale = std::max({e.length + 2 * std::max(s.beam_overhang, s.base_overhang), top - bottom});
    const double tol = 1e-5 * scale;  // OCC bounding boxes carry its tolerance (~1e-7 m)
    const double h_units = s.mesh_size;
    const double h_beam = s.mesh_size_beam > 0 ? s.mesh_size_beam : s.mesh_size;
    const double h_base = s.mesh_size_base > 0 ? s.mesh_size_base : s.mesh_size;
    const char* what_unit = s.stones.empty() ? "unit" : "stone";

    GmshSession session;
    try {
        gmsh::model::add("wall");
        // Inputs of the fragment, with a label each so that overlaps name what overlaps.
        gmsh::vectorpair inputs;
        std::vector<std::string> labels;
        std::vector<int> role;  // 0 unit, 1 beam, 2 base
        gmsh::vectorpair unit_surfaces;
        // unit_cracks = "middle": whole units become two halves (rectangles of the generated bond); split[i] is
        // the x of the cut of outline i, or NaN.
        std::vector<double> split(outlines.size(), std::numeric_limits<double>::quiet_NaN());
        std::vector<std::size_t> unit_of_surface;  // input surface -> outline index
        if (s.unit_cracks == "middle") {
            double widest = 0.0;
            for (const auto& p : outlines) widest = std::max(widest, p[1][0] - p[0][0]);
            for (std::size_t i = 0; i < outlines.size(); ++i) {
                const auto& p = outlines[i];
                const double x0 = p[0][0], x1 = p[1][0], y0 = p[0][1], y1 = p[2][1];
                if (x1 - x0 < 0.75 * widest) {
                    unit_surfaces.push_back({2, add_polygon(p)});
                    unit_of_surface.push_back(i);
                    continue;
                }
                split[i] = 0.5 * (x0 + x1);
                unit_surfaces.push_back({2, add_box(x0, y0, split[i], y1)});
                unit_of_surface.push_back(i);
                unit_surfaces.push_back({2, add_box(split[i], y0, x1, y1)});
                unit_of_surface.push_back(i);
            }
        } else {
            for (std::size_t i = 0; i < outlines.size(); ++i) {
                unit_surfaces.push_back({2, add_polygon(outlines[i])});
                unit_of_surface.push_back(i);
            }
        }
        std::vector<std::vector<int>> unit_pieces(unit_surfaces.size());
        if (!s.openings.empty()) {
            gmsh::vectorpair holes, out;
            std::vector<gmsh::vectorpair> map;
            for (const auto& o : s.openings) holes.push_back({2, add_box(o.x, o.y, o.x + o.width, o.y + o.height)});
            gmsh::model::occ::cut(unit_surfaces, holes, out, map);
            throw_on_gmsh_error("cutting the openings out of the units");
            for (std::size_t i = 0; i < unit_surfaces.size(); ++i)
                for (const auto& dt : map[i])
                    if (dt.first == 2) unit_pieces[i].push_back(dt.second);
        } else {
            for (std::size_t i = 0; i < unit_surfaces.size(); ++i) unit_pieces[i].push_back(unit_surfaces[i].second);
        }
        for (std::size_t i = 0; i < unit_pieces.size(); ++i)
            for (int tag : unit_pieces[i]) {
                inputs.push_back({2, tag});
                labels.push_back(std::string(what_unit) + " " + std::to_string(unit_of_surface[i]));
                role.push_back(0);
            }
        if (has_beam) {
            inputs.push_back({2, add_box(-s.beam_overhang, e.height, e.length + s.beam_overhang, top)});
            labels.push_back("the beam");
            role.push_back(1);
        }
        if (has_base) {
            inputs.push_back({2, add_box(-s.base_overhang, bottom, e.length + s.base_overhang, 0.0)});
            labels.push_back("the base");
            role.push_back(2);
        }
        if (inputs.empty()) throw MeshError("geometry: the openings leave no unit");

        gmsh::vectorpair out;
        std::vector<gmsh::vectorpair> map;
        if (inputs.size() > 1) {
            gmsh::model::occ::fragment(inputs, {}, out, map);
            throw_on_gmsh_error("fragmenting the units, beam and base");
        } else {
            map = {inputs};  // OCC refuses to fragment a single shape; it is its own fragment
        }
        std::map<int, std::vector<std::size_t>> owners;  // output surface -> inputs that contain it
        for (std::size_t i = 0; i < map.size() && i < inputs.size(); ++i)
            for (const auto& dt : map[i])
                if (dt.first == 2) owners[dt.second].push_back(i);
        for (const auto& [tag, who] : owners)
            if (who.size() > 1) {
                double x = 0, y = 0, z = 0, area = 0;
                gmsh::model::occ::getCenterOfMass(2, tag, x, y, z);
                gmsh::model::occ::getMass(2, tag, area);
                throw MeshError("geometry: " + labels[who[0]] + " and " + labels[who[1]] + " overlap near (" + num(x) +
                                ", " + num(y) + ") m over " + num(area) + " m^2");
            }
        gmsh::model::occ::synchronize();

        std::set<int> units, beam, base;
        for (const auto& [tag, who] : owners) (role[who[0]] == 0 ? units : role[who[0]] == 1 ? beam : base).insert(tag);

        // Sizes on the corner points: the smallest size of the surfaces meeting there, interpolated along curves.
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
        size_points(units, h_units);
        size_points(beam, h_beam);
        size_points(base, h_base);
        for (const auto& [pt, h] : point_size) gmsh::model::mesh::setSize({{0, pt}}, h);
        if (!s.refine.empty()) {
            const double h_out = std::max({h_units, h_beam, h_base});
            std::vector<double> boxes;
            for (const auto& r : s.refine) {
                const int f = gmsh::model::mesh::field::add("Box");
                gmsh::model::mesh::field::setNumber(f, "VIn", r.size);
                gmsh::model::mesh::field::setNumber(f, "VOut", h_out);
                gmsh::model::mesh::field::setNumber(f, "XMin", r.x);
                gmsh::model::mesh::field::setNumber(f, "XMax", r.x + r.width);
                gmsh::model::mesh::field::setNumber(f, "YMin", r.y);
                gmsh::model::mesh::field::setNumber(f, "YMax", r.y + r.height);
                gmsh::model::mesh::field::setNumber(f, "ZMin", -1);
                gmsh::model::mesh::field::setNumber(f, "ZMax", 1);
                boxes.push_back(f);
            }
            const int fmin = gmsh::model::mesh::field::add("Min");
            gmsh::model::mesh::field::setNumbers(fmin, "FieldsList", boxes);
            gmsh::model::mesh::field::setAsBackgroundMesh(fmin);
        }

        // Physical groups: regions first, so that their order (units, beam, base) is the region order.
        add_group(2, {units.begin(), units.end()}, "units");
        add_group(2, {beam.begin(), beam.end()}, "beam");
        add_group(2, {base.begin(), base.end()}, "base");
        const double L = e.length, H = e.height;
        add_group(1, curves_in(0, 0, L, 0, tol, units), "wall_bottom");
        add_group(1, curves_in(0, H, L, H, tol, units), "wall_top");
        add_group(1, curves_in(0, 0, 0, H, tol, units), "wall_left");
        add_group(1, curves_in(L, 0, L, H, tol, units), "wall_right");
        if (has_beam) {
            add_group(1, curves_in(-s.beam_overhang, top, L + s.beam_overhang, top, tol, beam), "beam_top");
            add_group(1, curves_in(-s.beam_overhang, H, -s.beam_overhang, top, tol, beam), "beam_left");
            add_group(1, curves_in(L + s.beam_overhang, H, L + s.beam_overhang, top, tol, beam), "beam_right");
        }
        if (has_base) {
            add_group(1, curves_in(-s.base_overhang, bottom, L + s.base_overhang, bottom, tol, base), "base_bottom");
            add_group(1, curves_in(-s.base_overhang, bottom, -s.base_overhang, 0, tol, base), "base_left");
            add_group(1, curves_in(L + s.base_overhang, bottom, L + s.base_overhang, 0, tol, base), "base_right");
        }
        if (s.unit_cracks == "middle") {
            std::vector<int> mids;
            for (std::size_t i = 0; i < outlines.size(); ++i)
                if (!std::isnan(split[i]))
                    for (int c : curves_in(split[i], outlines[i][0][1], split[i], outlines[i][2][1], tol, units))
                        mids.push_back(c);
            std::sort(mids.begin(), mids.end());
            mids.erase(std::unique(mids.begin(), mids.end()), mids.end());
            add_group(1, mids, "unit_cracks");
        }
        add_group(0, points_at(0, 0, tol), "toe_left");
        add_group(0, points_at(L, 0, tol), "toe_right");
        add_group(0, points_at(0, H, tol), "wall_top_left");
        add_group(0, points_at(L, H, tol), "wall_top_right");

        gmsh::model::mesh::generate(2);
        throw_on_gmsh_error("meshing the wall");
        Mesh m = extract_current_model();
        if (s.unit_cracks == "middle") join_split_units(m, outlines, split);
        return m;
    } catch (const MeshError&) {
        throw;
    } catch (const std::exception& ex) {
        throw MeshError(std::string("Gmsh failed on the wall geometry: ") + ex.what());
    } catch (...) {
        throw_on_gmsh_error("Gmsh failed on the wall geometry");
        throw MeshError("Gmsh failed on the wall geometry");
    }
}

// Expected triangle count of a generated wall before meshing: area / (sqrt(3)/4 h^2) for each part meshed at size
// h (equilateral triangles of edge h), and at least 2 triangles per unit. 0 when the sizes are not known here.
double expected_triangles(const WallSpec& w) {
    const double per = 4.0 / std::sqrt(3.0);
    const double H = w.height > 0 ? w.height : w.courses * (w.unit_height + w.joint_thickness);
    const double L = w.length;
    if (!(L > 0) || !(H > 0) || !(w.mesh_size > 0)) return 0;
    double n = per * L * H / (w.mesh_size * w.mesh_size);
    if (w.unit_length > 0 && w.unit_height > 0) n = std::max(n, 2.0 * (L / w.unit_length + 1) * (H / w.unit_height + 1));
    const double hb = w.mesh_size_base > 0 ? w.mesh_size_base : w.mesh_size;
    const double hm = w.mesh_size_beam > 0 ? w.mesh_size_beam : w.mesh_size;
    if (w.base == "slab") n += per * (L + 2 * w.base_overhang) * w.base_height / (hb * hb);
    n += per * (L + 2 * w.beam_overhang) * w.beam_height / (hm * hm);
    for (const auto& rf : w.refine)
        if (rf.size > 0) n += per * rf.width * rf.height / (rf.size * rf.size);
    return n;
}

}  // namespace fdem::mesh
