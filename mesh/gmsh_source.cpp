// mesh/gmsh_source.cpp: Gmsh model -> Mesh, and the simple geometry sources (rectangle, .geo, .msh).
#include "mesh/gmsh_source.hpp"

#include <gmsh.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <unordered_map>
#include <vector>

namespace fdem::mesh {

namespace {
int g_sessions = 0;
}  // namespace

// Gmsh's own default for API use (General.AbortOnError = 2) throws from deep inside its .geo parser, which leaves
// the parser and OpenProject's "busy" flag set for the rest of the process: every later gmsh::open then silently
// reads nothing. So errors are logged only (AbortOnError = 0), collected by the in-memory logger of this session,
// and turned into MeshError by throw_on_gmsh_error. (getLastError cannot be used: it keeps the last error forever.)
void throw_on_gmsh_error(const std::string& what) {
    std::vector<std::string> log;
    gmsh::logger::get(log);
    // Gmsh often logs the cause first and a summary ("Error loading 'x.msh'") last: every error line is kept,
    // cause first, so the message says why and not only that reading failed.
    std::string errors;
    int n = 0;
    for (const auto& line : log)
        if (line.rfind("Error", 0) == 0) {
            const auto colon = line.find(':');
            std::string text = colon == std::string::npos ? line : line.substr(colon + 1);
            text.erase(0, text.find_first_not_of(' '));
            if (errors.find(text) != std::string::npos) continue;
            if (++n > 4) break;
            errors += (errors.empty() ? "" : "; ") + text;
        }
    if (!errors.empty()) throw MeshError(what + ": Gmsh: " + errors);
}

GmshSession::GmshSession(bool verbose) {
    if (g_sessions++ == 0) {
        gmsh::initialize(0, nullptr, false);
        gmsh::logger::start();
    }
    gmsh::option::setNumber("General.Terminal", verbose ? 1 : 0);
    gmsh::option::setNumber("General.Verbosity", verbose ? 5 : 1);
    gmsh::option::setNumber("General.AbortOnError", 0);
    gmsh::clear();
}

GmshSession::~GmshSession() {
    if (--g_sessions == 0) {
        gmsh::logger::stop();
        gmsh::finalize();
    }
}

namespace {
// What the current Gmsh model holds instead of triangles, for the "no triangles" message: element counts by type
// and dimension, and the physical groups with their dimension.
std::string model_contents() {
    std::string elems;
    for (int dim = 0; dim <= 3; ++dim) {
        std::vector<int> types;
        gmsh::model::mesh::getElementTypes(types, dim, -1);
        for (int type : types) {
            std::vector<std::size_t> etags, ntags;
            gmsh::model::mesh::getElementsByType(type, etags, ntags, -1);
            std::string ename;
            int edim = 0, order = 0, nn = 0, nprim = 0;
            std::vector<double> local;
            gmsh::model::mesh::getElementProperties(type, ename, edim, order, nn, local, nprim);
            elems += (elems.empty() ? "" : ", ") + std::to_string(etags.size()) + " '" + ename + "' (" +
                     std::to_string(dim) + "D)";
        }
    }
    std::vector<std::pair<int, int>> phys;
    gmsh::model::getPhysicalGroups(phys);
    std::string groups;
    for (const auto& [dim, tag] : phys) {
        std::string name;
        gmsh::model::getPhysicalName(dim, tag, name);
        groups += (groups.empty() ? "" : ", ") + (name.empty() ? "#" + std::to_string(tag) : "'" + name + "'") + " (" +
                  std::to_string(dim) + "D)";
    }
    return "it holds " + (elems.empty() ? std::string("no elements at all") : elems) + "; physical groups: " +
           (groups.empty() ? std::string("none") : groups) +
           " (a .geo must define surfaces, e.g. Plane Surface, and a .msh must hold a 2D mesh: gmsh -2)";
}
}  // namespace

Mesh extract_current_model() {
    Mesh m;
    // All 3-node triangles with the surface entity each belongs to.
    std::vector<std::pair<int, int>> surfaces;
    gmsh::model::getEntities(surfaces, 2);
    struct RawTri {
        std::size_t n[3];
        int entity;
    };
    std::vector<RawTri> raw;
    for (const auto& [dim, tag] : surfaces) {
        // Only 3-node triangles are used: any other 2D element (quadrangles of a recombined surface, 6-node
        // second-order triangles) would be dropped silently, so it is refused with the surface that holds it.
        std::vector<int> types;
        gmsh::model::mesh::getElementTypes(types, 2, tag);
        for (int type : types) {
            if (type == 2) continue;
            std::string ename;
            int edim = 0, order = 0, nn = 0, nprim = 0;
            std::vector<double> local;
            gmsh::model::mesh::getElementProperties(type, ename, edim, order, nn, local, nprim);
            throw MeshError("surface " + std::to_string(tag) + " holds '" + ename + "' elements (" + std::to_string(nn) +
                            " nodes); only 3-node triangles are supported: do not recombine, use Mesh.ElementOrder = 1");
        }
        std::vector<std::size_t> etags, ntags;
        gmsh::model::mesh::getElementsByType(2, etags, ntags, tag);
        for (std::size_t e = 0; e < etags.size(); ++e)
            raw.push_back({{ntags[3 * e], ntags[3 * e + 1], ntags[3 * e + 2]}, tag});
        (void)dim;
    }
    if (raw.empty()) throw MeshError("the Gmsh model holds no 3-node triangles: " + model_contents());

    // Regions: 2D physical groups by entity. If the model defines none, every triangle is in "body".
    std::vector<std::pair<int, int>> phys;
    gmsh::model::getPhysicalGroups(phys);
    std::map<int, int> entity_region;
    for (const auto& [dim, ptag] : phys) {
        if (dim != 2) continue;
        std::string name;
        gmsh::model::getPhysicalName(dim, ptag, name);
        if (name.empty()) name = "surface_" + std::to_string(ptag);
        std::vector<int> ents;
        gmsh::model::getEntitiesForPhysicalGroup(dim, ptag, ents);
        const int region = static_cast<int>(m.regions.size());
        m.regions.push_back(name);
        for (int ent : ents) entity_region.emplace(ent, region);  // first group wins
    }
    const bool has_regions = !m.regions.empty();
    if (has_regions) {
        // With physical groups, a meshed surface outside every group would be dropped silently: refuse it.
        std::string orphans;
        for (const auto& [dim, tag] : surfaces) {
            std::vector<int> types;
            gmsh::model::mesh::getElementTypes(types, 2, tag);
            if (!types.empty() && entity_region.find(tag) == entity_region.end())
                orphans += (orphans.empty() ? "" : ", ") + std::to_string(tag);
            (void)dim;
        }
        if (!orphans.empty())
            throw MeshError("surface(s) " + orphans +
                            " hold triangles but belong to no 2D physical group; add them to a Physical Surface");
    }
    if (!has_regions) m.regions.push_back("body");

    // Node coordinates by tag.
    std::vector<std::size_t> node_tags;
    std::vector<double> coord, param;
    gmsh::model::mesh::getNodes(node_tags, coord, param, -1, -1, true, false);
    std::unordered_map<std::size_t, std::size_t> tag_pos;
    tag_pos.reserve(node_tags.size());
    for (std::size_t i = 0; i < node_tags.size(); ++i) tag_pos.emplace(node_tags[i], i);

    // Compact numbering over the nodes of kept triangles, in order of first appearance.
    std::unordered_map<std::size_t, int> tag_index;
    auto index_of = [&](std::size_t tag) {
        auto it = tag_index.find(tag);
        if (it != tag_index.end()) return it->second;
        auto pos = tag_pos.find(tag);
        if (pos == tag_pos.end()) throw MeshError("a triangle refers to node " + std::to_string(tag) + ", which has no coordinates");
        const int idx = static_cast<int>(m.xy.size() / 2);
        m.xy.push_back(coord[3 * pos->second]);
        m.xy.push_back(coord[3 * pos->second + 1]);
        tag_index.emplace(tag, idx);
        return idx;
    };
    std::map<int, std::vector<int>> entity_triangles;
    std::map<int, int> entity_body;  // Gmsh surface tag -> compact body index, in tag order (raw is tag-ordered)
    for (const auto& t : raw) {
        int region = 0;
        if (has_regions) {
            auto it = entity_region.find(t.entity);
            if (it == entity_region.end()) continue;  // with physical groups, only their elements belong to the model
            region = it->second;
        }
        int a = index_of(t.n[0]), b = index_of(t.n[1]), c = index_of(t.n[2]);
        const double* p = m.xy.data();
        double area2 = (p[2 * b] - p[2 * a]) * (p[2 * c + 1] - p[2 * a + 1]) -
                       (p[2 * c] - p[2 * a]) * (p[2 * b + 1] - p[2 * a + 1]);
        if (area2 < 0) std::swap(b, c);
        const int ti = m.n_triangles();
        m.tri.insert(m.tri.end(), {a, b, c});
        m.tri_region.push_back(region);
        m.tri_body.push_back(entity_body.emplace(t.entity, static_cast<int>(entity_body.size())).first->second);
        entity_triangles[t.entity].push_back(ti);
    }
    if (m.tri.empty()) throw MeshError("no triangle belongs to a 2D physical group");

    // Degenerate triangles: area below 1e-12 of the squared longest edge.
    for (int t = 0; t < m.n_triangles(); ++t) {
        const int* n = &m.tri[3 * t];
        const double* p = m.xy.data();
        const double ax = p[2 * n[1]] - p[2 * n[0]], ay = p[2 * n[1] + 1] - p[2 * n[0] + 1];
        const double bx = p[2 * n[2]] - p[2 * n[0]], by = p[2 * n[2] + 1] - p[2 * n[0] + 1];
        const double cx = p[2 * n[2]] - p[2 * n[1]], cy = p[2 * n[2] + 1] - p[2 * n[1] + 1];
        const double l2 = std::max({ax * ax + ay * ay, bx * bx + by * by, cx * cx + cy * cy});
        if (std::abs(ax * by - ay * bx) <= 1e-12 * l2)
            throw MeshError("degenerate triangle " + std::to_string(t) + " in region '" +
                            m.regions[m.tri_region[t]] + "' near (" + std::to_string(p[2 * n[0]]) + ", " +
                            std::to_string(p[2 * n[0] + 1]) + ")");
    }

    // Physical groups of every dimension, by name.
    for (const auto& [dim, ptag] : phys) {
        PhysicalGroup g;
        g.dim = dim;
        gmsh::model::getPhysicalName(dim, ptag, g.name);
        if (g.name.empty()) g.name = (dim == 0 ? "point_" : dim == 1 ? "curve_" : "surface_") + std::to_string(ptag);
        std::vector<int> ents;
        gmsh::model::getEntitiesForPhysicalGroup(dim, ptag, ents);
        for (int ent : ents) {
            if (dim == 2) {
                auto it = entity_triangles.find(ent);
                if (it != entity_triangles.end())
                    g.triangles.insert(g.triangles.end(), it->second.begin(), it->second.end());
            }
            if (dim == 1) {
                std::vector<std::size_t> etags, ntags;
                gmsh::model::mesh::getElementsByType(1, etags, ntags, ent);
                for (std::size_t e = 0; e < etags.size(); ++e) {
                    auto ia = tag_index.find(ntags[2 * e]), ib = tag_index.find(ntags[2 * e + 1]);
                    if (ia == tag_index.end() || ib == tag_index.end()) continue;  // edge of a dropped surface
                    g.edges.push_back({ia->second, ib->second});
                }
            }
            std::vector<std::size_t> ntags;
            std::vector<double> c, pc;
            gmsh::model::mesh::getNodes(ntags, c, pc, dim, ent, true, false);
            for (auto tag : ntags) {
                auto it = tag_index.find(tag);
                if (it != tag_index.end()) g.nodes.push_back(it->second);
            }
        }
        // A .msh 2.2 import has discrete curves without boundary points, so getNodes misses curve end nodes:
        // the nodes of the group's own elements are always part of it.
        for (const auto& e : g.edges) g.nodes.insert(g.nodes.end(), e.begin(), e.end());
        for (int t : g.triangles) g.nodes.insert(g.nodes.end(), &m.tri[3 * t], &m.tri[3 * t] + 3);
        std::sort(g.nodes.begin(), g.nodes.end());
        g.nodes.erase(std::unique(g.nodes.begin(), g.nodes.end()), g.nodes.end());
        std::sort(g.triangles.begin(), g.triangles.end());
        m.groups.push_back(std::move(g));
    }
    if (!has_regions) {
        PhysicalGroup body;
        body.name = "body";
        body.dim = 2;
        for (int t = 0; t < m.n_triangles(); ++t) body.triangles.push_back(t);
        for (int k = 0; k < m.n_nodes(); ++k) body.nodes.push_back(k);
        m.groups.push_back(std::move(body));
    }
    return m;
}

Mesh mesh_rectangle(double x0, double y0, double width, double height, double size) {
    if (!(width > 0) || !(height > 0) || !(size > 0))
        throw MeshError("rectangle needs width > 0, height > 0 and mesh size > 0");
    GmshSession session;
    gmsh::model::add("rectangle");
    const int s = gmsh::model::occ::addRectangle(x0, y0, 0, width, height);
    gmsh::model::occ::synchronize();
    std::vector<std::pair<int, int>> pts, curves;
    gmsh::model::getEntities(pts, 0);
    gmsh::model::mesh::setSize(pts, size);
    gmsh::option::setNumber("Mesh.MeshSizeMax", size);
    // Name the boundary by where it lies rather than by OCC's curve numbering.
    gmsh::model::getEntities(curves, 1);
    std::map<std::string, std::vector<int>> sides;
    const double tol = 1e-5 * std::max(width, height);  // OCC bounding boxes carry its tolerance (~1e-7 m)
    for (const auto& [dim, tag] : curves) {
        double xmin, ymin, zmin, xmax, ymax, zmax;
        gmsh::model::getBoundingBox(dim, tag, xmin, ymin, zmin, xmax, ymax, zmax);
        if (std::abs(ymax - ymin) < tol) sides[std::abs(ymin - y0) < tol ? "bottom" : "top"].push_back(tag);
        else sides[std::abs(xmin - x0) < tol ? "left" : "right"].push_back(tag);
    }
    std::map<std::string, std::vector<int>> corners;
    for (const auto& [dim, tag] : pts) {
        double xmin, ymin, zmin, xmax, ymax, zmax;
        gmsh::model::getBoundingBox(dim, tag, xmin, ymin, zmin, xmax, ymax, zmax);
        const bool left = std::abs(xmin - x0) < tol, bottom = std::abs(ymin - y0) < tol;
        corners[std::string("corner_") + (bottom ? "b" : "t") + (left ? "l" : "r")].push_back(tag);
    }
    gmsh::model::setPhysicalName(2, gmsh::model::addPhysicalGroup(2, {s}), "body");
    for (const auto& [name, tags] : sides) gmsh::model::setPhysicalName(1, gmsh::model::addPhysicalGroup(1, tags), name);
    for (const auto& [name, tags] : corners) gmsh::model::setPhysicalName(0, gmsh::model::addPhysicalGroup(0, tags), name);
    gmsh::model::mesh::generate(2);
    throw_on_gmsh_error("meshing the rectangle");
    return extract_current_model();
}

namespace {
// The file must exist, be a regular file and be readable; the message says which of these fails and why.
void require_readable(const std::string& path) {
    std::error_code ec;
    const auto st = std::filesystem::status(path, ec);
    if (!std::filesystem::exists(st)) throw MeshError("cannot read '" + path + "': no such file");
    if (std::filesystem::is_directory(st)) throw MeshError("cannot read '" + path + "': it is a directory, not a file");
    std::ifstream f(path);
    if (!f) throw MeshError("cannot read '" + path + "': " + std::strerror(errno));
    if (std::filesystem::file_size(path, ec) == 0 && !ec) throw MeshError("cannot read '" + path + "': the file is empty");
}
}  // namespace

namespace {
// Why a .msh file may have failed to load, from its section structure (Gmsh's own message for a truncated file is
// only "Error loading"): not a .msh at all, an unsupported version, or a section without its $End line.
std::string msh_diagnosis(const std::string& path) {
    std::ifstream f(path);
    std::string line, open_section, first;
    long n = 0, open_line = 0;
    while (std::getline(f, line)) {
        ++n;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (first.empty() && !line.empty()) first = line;
        if (line.rfind("$End", 0) == 0) {
            if (open_section.empty() || line.substr(4) != open_section)
                return "line " + std::to_string(n) + ": '" + line + "' closes no open section";
            open_section.clear();
        } else if (!line.empty() && line[0] == '$') {
            if (!open_section.empty())
                return "line " + std::to_string(n) + ": section $" + line.substr(1) + " starts inside $" + open_section +
                       " (opened at line " + std::to_string(open_line) + ")";
            open_section = line.substr(1), open_line = n;
            if (open_section == "MeshFormat" && std::getline(f, line)) {
                ++n;
                const std::string version = line.substr(0, line.find(' '));
                if (version != "2.2" && version.rfind("4", 0) != 0)
                    return "format version " + version + " (line " + std::to_string(n) + "): formats 2.2 and 4.1 are read";
            }
        }
    }
    if (first.rfind("$MeshFormat", 0) != 0) return "it does not start with $MeshFormat: not a Gmsh .msh file";
    if (!open_section.empty())
        return "the file ends inside section $" + open_section + " (opened at line " + std::to_string(open_line) +
               ", no $End" + open_section + "): truncated?";
    return "";
}

// Structure of an ASCII MSH 2.2 file, checked before Gmsh reads it: Gmsh 4.8's MSH2 reader trusts the node and element
// lines and crashes (SIGSEGV in GModel::_associateEntityWithMeshVertices) on a node line missing a coordinate, a node
// tag 0 or an element line short of nodes (issue 26 fuzzer). Returns "" when the file is sound, or not ASCII MSH 2.2
// (other formats are left to Gmsh), else "line N: what is wrong".
std::string msh2_structure(const std::string& path) {
    std::ifstream f(path);
    std::string line;
    long n = 0;
    auto next = [&]() {
        if (!std::getline(f, line)) return false;
        ++n;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        return true;
    };
    // A defect on the file's last line is a file cut short: left to Gmsh and msh_diagnosis, which say so.
    auto at = [&](const std::string& what) {
        return f.peek() == std::char_traits<char>::eof() ? std::string()
                                                         : "line " + std::to_string(n) + ": " + what + " ('" + line + "')";
    };
    auto fields = [](const std::string& l) {
        std::vector<std::string> out;
        std::istringstream is(l);
        for (std::string w; is >> w;) out.push_back(w);
        return out;
    };
    auto to_long = [](const std::string& w, long& v) {
        char* end = nullptr;
        errno = 0;
        v = std::strtol(w.c_str(), &end, 10);
        return errno == 0 && end && *end == '\0' && end != w.c_str();
    };
    auto to_double = [](const std::string& w) {
        char* end = nullptr;
        const double v = std::strtod(w.c_str(), &end);
        return end && *end == '\0' && end != w.c_str() && std::isfinite(v);
    };
    if (!next() || line.rfind("$MeshFormat", 0) != 0 || !next()) return "";
    {
        const auto w = fields(line);
        if (w.size() < 2 || w[0] != "2.2" || w[1] != "0") return "";  // not ASCII 2.2
    }
    std::unordered_map<long, char> nodes;
    // Nodes per element of the MSH 2 types fdem meets (line, triangle, quadrangle, tetrahedron, point, 2nd-order
    // line and triangle); another type is left to Gmsh.
    const std::map<long, long> nodes_of = {{1, 2}, {2, 3}, {3, 4}, {4, 4}, {15, 1}, {8, 3}, {9, 6}};
    while (next()) {
        if (line == "$Nodes" || line == "$Elements") {
            const bool is_nodes = line == "$Nodes";
            if (!next()) return "";
            long count = 0;
            const auto c = fields(line);
            if (c.size() != 1 || !to_long(c[0], count) || count < 0) return at("expected the number of entries");
            for (long i = 0; i < count; ++i) {
                if (!next()) return "";
                if (!line.empty() && line[0] == '$')
                    return at("the section announces " + std::to_string(count) + " entries and ends after " + std::to_string(i) +
                              "; expected $End" + (is_nodes ? "Nodes" : "Elements") + " after " + std::to_string(count));
                const auto w = fields(line);
                long id = 0;
                if (w.empty() || !to_long(w[0], id) || id <= 0) return at("expected a positive tag first");
                if (is_nodes) {
                    if (w.size() != 4) return at("a node line holds a tag and three coordinates");
                    for (int k = 1; k < 4; ++k)
                        if (!to_double(w[k])) return at("coordinate '" + w[k] + "' is not a finite number");
                    if (!nodes.emplace(id, 1).second) return at("node tag " + w[0] + " appears twice");
                } else {
                    long type = 0, ntags = 0;
                    if (w.size() < 3 || !to_long(w[1], type) || !to_long(w[2], ntags) || ntags < 0)
                        return at("expected: tag, type, number of tags, tags, nodes");
                    const auto it = nodes_of.find(type);
                    if (it == nodes_of.end()) continue;
                    if (static_cast<long>(w.size()) != 3 + ntags + it->second)
                        return at("element type " + w[1] + " with " + w[2] + " tags needs " + std::to_string(3 + ntags + it->second) +
                                  " numbers, the line has " + std::to_string(w.size()));
                    for (std::size_t k = 3; k < w.size(); ++k) {
                        long v = 0;
                        if (!to_long(w[k], v)) return at("'" + w[k] + "' is not an integer");
                        if (k >= static_cast<std::size_t>(3 + ntags) && !nodes.count(v)) return at("node " + w[k] + " is not in $Nodes");
                    }
                }
            }
            if (!next()) return "";
            if (line != (is_nodes ? "$EndNodes" : "$EndElements"))
                return at(std::string("expected $End") + (is_nodes ? "Nodes" : "Elements") + " after " + std::to_string(count) + " entries");
        }
    }
    return "";
}

// Opens a .geo or .msh through the API, meshes in 2D when asked, and extracts the Mesh; every Gmsh failure
// becomes a MeshError naming the file.
Mesh open_and_extract(const std::string& path, bool generate, double size_factor) {
    require_readable(path);
    if (!generate)
        if (const std::string why = msh2_structure(path); !why.empty()) throw MeshError("reading '" + path + "': " + why);
    GmshSession session;
    if (generate) gmsh::option::setNumber("Mesh.MeshSizeFactor", size_factor);
    try {
        gmsh::open(path);
        try {
            throw_on_gmsh_error("reading '" + path + "'");
        } catch (const MeshError& e) {
            const std::string why = generate ? "" : msh_diagnosis(path);
            throw MeshError(why.empty() ? std::string(e.what()) : std::string(e.what()) + " (" + why + ")");
        }
        if (generate) {
            gmsh::model::mesh::generate(2);
            throw_on_gmsh_error("meshing '" + path + "'");
        }
    } catch (const MeshError&) {
        throw;
    } catch (const std::exception& e) {
        throw MeshError("Gmsh failed on '" + path + "': " + e.what());
    } catch (...) {
        throw_on_gmsh_error("Gmsh failed on '" + path + "'");
        throw MeshError("Gmsh failed on '" + path + "'");
    }
    try {
        return extract_current_model();
    } catch (const MeshError& e) {
        throw MeshError("reading '" + path + "': " + e.what());
    }
}
}  // namespace

Mesh mesh_geo_file(const std::string& path, double size_factor) { return open_and_extract(path, true, size_factor); }

Mesh read_msh_file(const std::string& path) { return open_and_extract(path, false, 1.0); }

}  // namespace fdem::mesh
