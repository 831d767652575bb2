// fdem/case_geometry.cpp: the [geometry] table of a case (rectangle, Gmsh script or mesh, the wall and macro-block
// generators) and the size guard on the expected triangle counts (mesh/wall.hpp, mesh/macro.hpp) before meshing. Part of the case reader (fdem/case_reader.hpp).
#include <filesystem>

#include "fdem/case_reader.hpp"

namespace fdem::case_detail {

namespace {

// [geometry] max_triangles: the size guard of generated meshes (rectangle, wall), checked before meshing.
void check_triangle_count(Ctx& ctx, Reader& r, int line, double expected) {
    const double limit = r.number("max_triangles", false, "a triangle limit >= 1 for generated meshes",
                                  [](double v) { return v >= 1; }).value_or(2e6);
    if (!(expected <= limit))
        ctx.error("geometry.max_triangles", line, "the generated mesh would have about " + fmt_num(expected) +
                  " triangles, more than the limit of " + fmt_num(limit) +
                  "; expected a coarser geometry.mesh_size (or larger units), or raise geometry.max_triangles");
}

// [[geometry.openings]] blocks { x, y, width, height } of the wall and the macro-block wall (mesh::WallOpening,
// mesh::MacroWallOpening), in file order.
template <class Opening>
void read_openings(Ctx& ctx, Reader& r, std::vector<Opening>& out, bool required) {
    auto positive = [](double v) { return v >= kMinLength && v <= kMaxLength; };
    for (const toml::table* t : r.tables("openings", required, "[[geometry.openings]] blocks { x, y, width, height }")) {
        Reader o(ctx, *t, r.key_path("openings." + std::to_string(out.size() + 1)));
        Opening op;
        op.x = o.number("x", true, "the opening's left edge in m").value_or(0);
        op.y = o.number("y", true, "the opening's bottom edge (sill) in m").value_or(0);
        op.width = o.number("width", true, "a width > 0 in m", positive).value_or(0);
        op.height = o.number("height", true, "a height > 0 in m", positive).value_or(0);
        o.finish();
        out.push_back(op);
    }
}

// [geometry] type = "wall": keys named after mesh::WallSpec's fields; the generator's own check() runs later,
// with the mesh, and its messages are reported against the [geometry] table.
void read_wall(Ctx& ctx, Reader& r, mesh::WallSpec& w) {
    // Lengths are bounded to [1e-6, 1e4] m: beyond them Gmsh aborts or hangs (issue 26), and no masonry wall needs them.
    auto nonneg = [](double v) { return v == 0 || (v >= kMinLength && v <= kMaxLength); };
    auto positive = [](double v) { return v >= kMinLength && v <= kMaxLength; };
    w.length = r.number("length", false, "a wall length > 0 in m", positive).value_or(0);
    w.height = r.number("height", false, "a wall height > 0 in m", positive).value_or(0);
    w.courses = r.integer("courses", false, "a whole number of courses >= 1", [](long long v) { return v >= 1; }).value_or(0);
    w.unit_length = r.number("unit_length", false, "a unit length > 0 in m", positive).value_or(0);
    w.unit_height = r.number("unit_height", false, "a unit height > 0 in m", positive).value_or(0);
    w.bond = r.string("bond", false, "the bond pattern", {"running", "stack", "offsets"}).value_or("running");
    if (auto o = r.numbers("offsets", false, "an array of course offsets in m")) w.offsets = *o;
    if (const toml::node* n = r.node("stones", false, "an array of polygons [[x, y], ...] in m")) {
        bool ok = n->is_array();
        if (ok)
            for (const auto& poly : *n->as_array()) {
                std::vector<std::array<double, 2>> pts;
                if (!poly.is_array()) { ok = false; break; }
                for (const auto& pt : *poly.as_array()) {
                    const toml::array* a = pt.as_array();
                    if (!a || a->size() != 2 || !(*a)[0].is_number() || !(*a)[1].is_number()) { ok = false; break; }
                    pts.push_back({*(*a)[0].value<double>(), *(*a)[1].value<double>()});
                }
                if (pts.size() < 3) ok = false;
                w.stones.push_back(pts);
            }
        if (!ok) ctx.error(r.key_path("stones"), line_of(n), "expected an array of polygons, each at least 3 [x, y] points in m");
    }
    w.joint = r.string("joint", false, "the joint type", {"dry", "mortar"}).value_or("dry");
    w.joint_thickness = r.number("joint_thickness", false, "a mortar joint thickness of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    w.unit_cracks = r.string("unit_cracks", false, "where crackable units may crack",
                             {"anywhere", "middle"}).value_or("anywhere");
    w.beam_height = r.number("beam_height", false, "a beam depth of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    w.beam_overhang = r.number("beam_overhang", false, "a beam overhang of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    w.base = r.string("base", false, "the base", {"none", "fixed", "slab"}).value_or("none");
    w.base_height = r.number("base_height", false, "a base depth of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    w.base_overhang = r.number("base_overhang", false, "a base overhang of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    w.mesh_size = r.number("mesh_size", true, "a mesh size > 0 in m", positive).value_or(1);
    w.mesh_size_beam = r.number("mesh_size_beam", false, "a mesh size > 0 in m", positive).value_or(0);
    w.mesh_size_base = r.number("mesh_size_base", false, "a mesh size > 0 in m", positive).value_or(0);
    read_openings(ctx, r, w.openings, false);
    for (const toml::table* t : r.tables("refine", false, "[[geometry.refine]] blocks { x, y, width, height, size }")) {
        Reader o(ctx, *t, r.key_path("refine." + std::to_string(w.refine.size() + 1)));
        mesh::WallRefinement rf;
        rf.x = o.number("x", true, "the box's left edge in m").value_or(0);
        rf.y = o.number("y", true, "the box's bottom edge in m").value_or(0);
        rf.width = o.number("width", true, "a width > 0 in m", positive).value_or(0);
        rf.height = o.number("height", true, "a height > 0 in m", positive).value_or(0);
        rf.size = o.number("size", true, "a mesh size > 0 in m", positive).value_or(0);
        o.finish();
        w.refine.push_back(rf);
    }
}

// The [geometry] keys of the macro-block pier and wall (mesh::MacroPierSpec, mesh::MacroWallSpec); `what` names the
// length and height ("pier", "wall").
template <class Spec>
void read_macro_common(Reader& r, Spec& m, const std::string& what) {
    auto nonneg = [](double v) { return v == 0 || (v >= kMinLength && v <= kMaxLength); };
    auto positive = [](double v) { return v >= kMinLength && v <= kMaxLength; };
    m.length = r.number("length", true, "a " + what + " length > 0 in m", positive).value_or(1);
    m.height = r.number("height", true, "a " + what + " height > 0 in m", positive).value_or(1);
    m.texture_angle = r.number("texture_angle", true, "a texture angle in (0, 90) deg",
                               [](double v) { return v > 0 && v < 90; }).value_or(45);
    m.horizontal_joint = r.number("horizontal_joint", false, "a horizontal joint length > 0 in m (below half the panel)",
                                  positive).value_or(0.05);
    m.mesh_size = r.number("mesh_size", true, "a mesh size > 0 in m", positive).value_or(1);
    m.beam_height = r.number("beam_height", false, "a beam depth of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    m.beam_overhang = r.number("beam_overhang", false, "a beam overhang of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    m.base_height = r.number("base_height", false, "a base depth of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    m.base_overhang = r.number("base_overhang", false, "a base overhang of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    m.mesh_size_beam = r.number("mesh_size_beam", false, "a mesh size > 0 in m", positive).value_or(0);
    m.mesh_size_base = r.number("mesh_size_base", false, "a mesh size > 0 in m", positive).value_or(0);
}

// [geometry] type = "macro": the macro-block pier (M-DEM); keys named after mesh::MacroPierSpec's fields. The
// generator's check() (diagonals that would cross) runs later, with the mesh, reported against [geometry].
void read_macro(Reader& r, mesh::MacroPierSpec& m) { read_macro_common(r, m, "pier"); }

// [geometry] type = "macro_wall": the macro-block wall with one row of openings (mesh/macro.hpp); keys named after
// mesh::MacroWallSpec's fields, the openings as in read_wall. The generator's check() (one row, piers of positive
// length, the keys fitting every panel) runs later, with the mesh, reported against [geometry].
void read_macro_wall(Ctx& ctx, Reader& r, mesh::MacroWallSpec& m) {
    read_macro_common(r, m, "wall");
    auto nonneg = [](double v) { return v == 0 || (v >= kMinLength && v <= kMaxLength); };
    m.lintel_height = r.number("lintel_height", false, "a lintel depth of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    m.lintel_bearing = r.number("lintel_bearing", false, "a lintel bearing of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    read_openings(ctx, r, m.openings, true);
}

}  // namespace

void read_geometry(Ctx& ctx, Reader& top, CaseSpec& spec) {
    namespace fs = std::filesystem;
    auto positive = [](double v) { return v > 0; };
    if (const toml::table* t = top.table("geometry", true, "a [geometry] table")) {
        Reader r(ctx, *t, "geometry");
        GeometrySpec& g = spec.geometry;
        g.line = r.line();
        g.type = r.string("type", true, "the geometry source", {"rectangle", "gmsh", "msh", "wall", "macro", "macro_wall"}).value_or("");
        if (g.type == "rectangle") {
            auto origin = r.vec2("origin", false, "[x0, y0] in m");
            if (origin) g.x0 = (*origin)[0], g.y0 = (*origin)[1];
            g.width = r.number("width", true, "a width > 0 in m", positive).value_or(1);
            g.height = r.number("height", true, "a height > 0 in m", positive).value_or(1);
            g.mesh_size = r.number("mesh_size", true, "a mesh size > 0 in m", positive).value_or(1);
            check_triangle_count(ctx, r, g.line, 2.31 * g.width * g.height / (g.mesh_size * g.mesh_size));
            if (g.mesh_size > 0 && std::min(g.width, g.height) / g.mesh_size > 5000)
                ctx.error("geometry.mesh_size", g.line, "a mesh size of " + fmt_num(g.mesh_size) +
                          " m gives more than 5000 elements across the rectangle; expected a coarser size");
        } else if (g.type == "gmsh" || g.type == "msh") {
            if (auto f = r.string("file", true, g.type == "gmsh" ? "the path of a .geo script" : "the path of a .msh file")) {
                fs::path p(*f);
                if (p.is_relative()) p = fs::path(spec.dir) / p;
                g.file = p.string();
                if (!fs::exists(p)) ctx.error("geometry.file", line_of(t->get("file")), "no such file '" + g.file + "'");
            }
            if (g.type == "gmsh")
                g.size_factor = r.number("size_factor", false, "a factor > 0 on the script's mesh sizes", positive).value_or(1.0);
        } else if (g.type == "wall") {
            read_wall(ctx, r, g.wall);
            check_triangle_count(ctx, r, g.line, mesh::expected_triangles(g.wall));
        } else if (g.type == "macro") {
            read_macro(r, g.macro);
            check_triangle_count(ctx, r, g.line, mesh::expected_triangles(g.macro));
        } else if (g.type == "macro_wall") {
            read_macro_wall(ctx, r, g.macro_wall);
            check_triangle_count(ctx, r, g.line, mesh::expected_triangles(g.macro_wall));
        }
        g.min_angle = r.number("min_angle", false, "a minimum triangle angle in [0, 60) deg (sliver check)",
                               [](double v) { return v >= 0 && v < 60; }).value_or(10.0);
        g.split_all = r.string("split", false, "\"joints\" (default) or \"all\" (every edge crackable, the classic FDEM limit)",
                               {"joints", "all"}).value_or("joints") == "all";
        g.joint_roughness = r.number("joint_roughness", false, "the largest inward offset of a dry-joint face, >= 0 in m",
                                     [](double v) { return v >= 0; }).value_or(0.0);
        g.roughness_wavelength = r.number("roughness_wavelength", g.joint_roughness > 0,
                                          "the wavelength of the joint roughness, > 0 in m (needed with joint_roughness > 0)",
                                          positive).value_or(0.0);
        g.roughness_seed = r.integer("roughness_seed", false, "a whole number >= 0 that seeds the joint roughness",
                                     [](long long v) { return v >= 0 && v <= 2147483647; }).value_or(1);
        r.finish();
    }
}

}  // namespace fdem::case_detail
