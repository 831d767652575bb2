// fdem/limit_export.cpp: see limit_export.hpp.
#include "fdem/limit_export.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include "fdem/common/errors.hpp"
#include "fdem/output.hpp"

namespace fdem {
namespace {

std::string num(double v) {
    if (!std::isfinite(v)) return "null";
    char b[32];
    std::snprintf(b, sizeof b, "%.17g", v);
    return b;
}

std::string str(const std::string& s) {
    std::string o = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') o += '\\', o += c;
        else if (static_cast<unsigned char>(c) < 0x20) {
            char b[8];
            std::snprintf(b, sizeof b, "\\u%04x", c);
            o += b;
        } else o += c;
    }
    return o + "\"";
}

template <class T, class F>
std::string list(const std::vector<T>& v, F f) {
    std::string o = "[";
    for (std::size_t i = 0; i < v.size(); ++i) o += (i ? "," : "") + f(v[i]);
    return o + "]";
}

struct UnionFind {
    std::vector<int> p;
    explicit UnionFind(int n) : p(n) { std::iota(p.begin(), p.end(), 0); }
    int find(int a) {
        while (p[a] != a) a = p[a] = p[p[a]];
        return a;
    }
    void join(int a, int b) {
        a = find(a), b = find(b);
        if (a != b) p[std::max(a, b)] = std::min(a, b);
    }
};

const InterfaceSpec* find_interface(const CaseSpec& spec, const std::string& a, const std::string& b) {
    for (const auto& i : spec.interfaces)
        if ((i.region_a == a && i.region_b == b) || (i.region_a == b && i.region_b == a)) return &i;
    return nullptr;
}

// A rigid body of the limit model: triangles joined through shared node copies and across crackable edges.
struct Body {
    double area = 0, mass = 0, mx = 0, my = 0, ax = 0, ay = 0;
    int triangles = 0;
    std::vector<int> regions;
};

struct Bodies {
    std::vector<int> tri_body, node_body;  // the body of each triangle and node (-1: a node on no triangle)
    std::vector<Body> list;
    std::vector<std::string> region_material;  // per region, "" when no material is assigned
};

// An interface segment between two different rigid bodies.
struct Segment {
    std::string kind;
    int body_a, body_b;
    std::array<double, 2> p0, p1;
    double friction = std::nan(""), cohesion = 0, tensile = 0;
    std::string region_a, region_b;
};

struct Segments {
    std::vector<Segment> list;
    int internal_joints = 0, missing_rule = 0;  // joint segments inside one body; touching faces with no dry rule
};

struct Owner {
    int stage = -1, block = -1, comp = 0;
};

struct Active {
    int stage, block;
};

std::string region_name(const mesh::Mesh& m, int tri) { return m.tri_region[tri] >= 0 ? m.regions[m.tri_region[tri]] : std::string(); }

Bodies rigid_bodies(const CaseSpec& spec, const mesh::Topology& topo) {
    const mesh::Mesh& m = topo.mesh;
    const int nn = m.n_nodes(), nt = m.n_triangles();
    const double t = spec.thickness;
    // Rigid bodies: triangles joined through shared node copies, and across crackable edges (cohesive elements of
    // kind crackable: a potential crack inside a unit, not a joint).
    UnionFind uf(nt);
    std::vector<int> node_tri(nn, -1);
    for (int e = 0; e < nt; ++e)
        for (int k = 0; k < 3; ++k) {
            const int n = m.tri[3 * e + k];
            if (node_tri[n] < 0) node_tri[n] = e;
            else uf.join(node_tri[n], e);
        }
    for (const auto& c : topo.cohesive)
        if (c.kind == mesh::EdgeClass::crackable && c.tri_a >= 0 && c.tri_b >= 0) uf.join(c.tri_a, c.tri_b);
    std::vector<int> tri_rigid(nt), root_id(nt, -1);
    int nb = 0;
    for (int e = 0; e < nt; ++e) {
        const int r = uf.find(e);
        if (root_id[r] < 0) root_id[r] = nb++;
        tri_rigid[e] = root_id[r];
    }
    std::vector<int> node_body(nn, -1);
    for (int n = 0; n < nn; ++n)
        if (node_tri[n] >= 0) node_body[n] = tri_rigid[node_tri[n]];

    // Region -> density (kg/m^3) and material name.
    std::vector<double> region_density(m.regions.size(), std::nan(""));
    std::vector<std::string> region_material(m.regions.size());
    for (std::size_t r = 0; r < m.regions.size(); ++r) {
        auto it = spec.region_material.find(m.regions[r]);
        if (it == spec.region_material.end()) continue;
        const int mi = spec.material_index(it->second);
        if (mi >= 0) region_density[r] = spec.materials[mi].density, region_material[r] = it->second;
    }
    std::vector<Body> bodies(nb);
    for (int e = 0; e < nt; ++e) {
        const int* n = &m.tri[3 * e];
        const double x0 = m.xy[2 * n[0]], y0 = m.xy[2 * n[0] + 1], x1 = m.xy[2 * n[1]], y1 = m.xy[2 * n[1] + 1];
        const double x2 = m.xy[2 * n[2]], y2 = m.xy[2 * n[2] + 1];
        const double A = 0.5 * ((x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0));
        const double cx = (x0 + x1 + x2) / 3, cy = (y0 + y1 + y2) / 3;
        const int r = m.tri_region[e];
        const double rho = r >= 0 ? region_density[r] : std::nan("");
        Body& b = bodies[tri_rigid[e]];
        b.area += A, b.ax += A * cx, b.ay += A * cy;
        b.mass += rho * A * t, b.mx += rho * A * t * cx, b.my += rho * A * t * cy;
        ++b.triangles;
        if (r >= 0 && std::find(b.regions.begin(), b.regions.end(), r) == b.regions.end()) b.regions.push_back(r);
    }

    return {std::move(tri_rigid), std::move(node_body), std::move(bodies), std::move(region_material)};
}

// The bonded and dry joints of the topology between two different bodies.
void add_joint_segments(const CaseSpec& spec, const mesh::Topology& topo, const std::vector<int>& tri_body, Segments& out) {
    const mesh::Mesh& m = topo.mesh;
    auto add_joint = [&](const mesh::CohesiveElement& c, bool bonded) {
        if (c.tri_a < 0 || c.tri_b < 0) return;
        const int ba = tri_body[c.tri_a], bb = tri_body[c.tri_b];
        if (ba == bb) {
            ++out.internal_joints;
            return;
        }
        Segment s;
        s.kind = bonded ? "bonded" : "dry";
        s.body_a = ba, s.body_b = bb;
        // Midpoint of the two faces' copies (they coincide unless the faces were roughened).
        s.p0 = {0.5 * (m.xy[2 * c.n[0]] + m.xy[2 * c.n[2]]), 0.5 * (m.xy[2 * c.n[0] + 1] + m.xy[2 * c.n[2] + 1])};
        s.p1 = {0.5 * (m.xy[2 * c.n[1]] + m.xy[2 * c.n[3]]), 0.5 * (m.xy[2 * c.n[1] + 1] + m.xy[2 * c.n[3] + 1])};
        s.region_a = region_name(m, c.tri_a), s.region_b = region_name(m, c.tri_b);
        const InterfaceSpec* is = find_interface(spec, s.region_a, s.region_b);
        if (is) {
            if (bonded) {
                s.friction = is->bond.friction;
                s.cohesion = std::isfinite(is->bond.cohesion) ? is->bond.cohesion : 0.0;
                s.tensile = std::isfinite(is->bond.tensile_strength) ? is->bond.tensile_strength : 0.0;
            } else s.friction = is->friction;
        }
        out.list.push_back(s);
    };
    for (const auto& c : topo.cohesive)
        if (c.kind == mesh::EdgeClass::bonded) add_joint(c, true);
    for (const auto& c : topo.dry_joints) add_joint(c, false);

}

// Free faces of two bodies that touch without shared nodes (non-conforming meshes of dry pairs): collinear,
// opposite, overlapping free-boundary edges. The overlap is one segment, oriented around the first face's body.
void add_contact_segments(const CaseSpec& spec, const mesh::Topology& topo, const std::vector<int>& tri_body, Segments& out) {
    const mesh::Mesh& m = topo.mesh;
    const int nn = m.n_nodes(), nt = m.n_triangles();
    {
        struct Face {
            int tri, n0, n1;
            std::array<double, 2> a, b;
        };
        // Faces on no other triangle of the split mesh (free faces, joint and crack faces), by node copies.
        std::map<std::pair<int, int>, int> count;
        for (int e = 0; e < nt; ++e)
            for (int k = 0; k < 3; ++k) {
                const int n0 = m.tri[3 * e + k], n1 = m.tri[3 * e + (k + 1) % 3];
                ++count[{std::min(n0, n1), std::max(n0, n1)}];
            }
        std::vector<Face> free_faces;
        for (int e = 0; e < nt; ++e)
            for (int k = 0; k < 3; ++k) {
                const int n0 = m.tri[3 * e + k], n1 = m.tri[3 * e + (k + 1) % 3];
                if (count[{std::min(n0, n1), std::max(n0, n1)}] == 1)
                    free_faces.push_back({e, n0, n1, {m.xy[2 * n0], m.xy[2 * n0 + 1]}, {m.xy[2 * n1], m.xy[2 * n1 + 1]}});
            }
        const auto& origin = topo.node_origin;
        double span = 0;
        for (int n = 0; n < nn; ++n) span = std::max({span, std::abs(m.xy[2 * n]), std::abs(m.xy[2 * n + 1])});
        const double tol = 1e-9 * std::max(1.0, span);
        std::sort(free_faces.begin(), free_faces.end(),
                  [](const Face& p, const Face& q) { return std::min(p.a[0], p.b[0]) < std::min(q.a[0], q.b[0]); });
        for (std::size_t i = 0; i < free_faces.size(); ++i) {
            const Face& f = free_faces[i];
            const double fxmax = std::max(f.a[0], f.b[0]);
            for (std::size_t j = i + 1; j < free_faces.size(); ++j) {
                const Face& g = free_faces[j];
                if (std::min(g.a[0], g.b[0]) > fxmax + tol) break;
                const int ba = tri_body[f.tri], bb = tri_body[g.tri];
                if (ba == bb) continue;
                // The two faces of one edge of the input mesh (a joint of the topology, listed above): skip.
                if (!origin.empty() && origin[f.n0] == origin[g.n1] && origin[f.n1] == origin[g.n0]) continue;
                const double dx = f.b[0] - f.a[0], dy = f.b[1] - f.a[1], L = std::hypot(dx, dy);
                if (!(L > 0)) continue;
                const double sx = dx / L, sy = dy / L;
                // g must lie on f's line and run the other way.
                const double dga = (g.a[0] - f.a[0]) * sy - (g.a[1] - f.a[1]) * sx;
                const double dgb = (g.b[0] - f.a[0]) * sy - (g.b[1] - f.a[1]) * sx;
                if (std::abs(dga) > tol || std::abs(dgb) > tol) continue;
                const double ta = (g.a[0] - f.a[0]) * sx + (g.a[1] - f.a[1]) * sy;
                const double tb = (g.b[0] - f.a[0]) * sx + (g.b[1] - f.a[1]) * sy;
                if (!(tb < ta)) continue;
                const double lo = std::max(0.0, tb), hi = std::min(L, ta);
                if (hi - lo <= tol) continue;
                Segment s;
                s.kind = "contact";
                s.body_a = ba, s.body_b = bb;
                s.p0 = {f.a[0] + lo * sx, f.a[1] + lo * sy};
                s.p1 = {f.a[0] + hi * sx, f.a[1] + hi * sy};
                s.region_a = region_name(m, f.tri), s.region_b = region_name(m, g.tri);
                const InterfaceSpec* is = find_interface(spec, s.region_a, s.region_b);
                if (!is || is->kind != "dry") {
                    ++out.missing_rule;
                    continue;
                }
                s.friction = is->friction;
                out.list.push_back(s);
            }
        }
    }

}

// Supports after the last stage: DOF ownership with the engine's carry-over rule (fdem/stages.cpp); (stage, block,
// component) -> nodes.
std::map<std::array<int, 3>, std::vector<int>> last_supports(const CaseSpec& spec, const mesh::Mesh& m) {
    const int nn = m.n_nodes();
    std::vector<Owner> owner(2 * static_cast<std::size_t>(nn));
    auto group_of = [&](const std::string& name) -> const mesh::PhysicalGroup& { return m.require_group(name); };
    for (std::size_t s = 0; s < spec.stages.size(); ++s)
        for (std::size_t i = 0; i < spec.stages[s].supports.size(); ++i) {
            const SupportSpec& sp = spec.stages[s].supports[i];
            for (int c = 0; c < 2; ++c) {
                if (sp.mode[c] == DofMode::inherit) continue;
                for (int k : group_of(sp.group).nodes) owner[2 * k + c] = {static_cast<int>(s), static_cast<int>(i), c};
            }
        }
    std::map<std::array<int, 3>, std::vector<int>> owned;  // (stage, block, comp) -> nodes
    for (int n = 0; n < nn; ++n)
        for (int c = 0; c < 2; ++c)
            if (owner[2 * n + c].stage >= 0) owned[{owner[2 * n + c].stage, owner[2 * n + c].block, c}].push_back(n);

    return owned;
}

// Loads in force at the last stage: a block on a group replaces that group's load of the same kind.
std::vector<Active> last_loads(const CaseSpec& spec) {
    std::vector<Active> loads;
    for (std::size_t s = 0; s < spec.stages.size(); ++s)
        for (std::size_t i = 0; i < spec.stages[s].loads.size(); ++i) {
            const LoadSpec& ls = spec.stages[s].loads[i];
            for (auto it = loads.begin(); it != loads.end(); ++it) {
                const LoadSpec& o = spec.stages[it->stage].loads[it->block];
                if (o.group == ls.group && o.kind == ls.kind) {
                    loads.erase(it);
                    break;
                }
            }
            loads.push_back({static_cast<int>(s), static_cast<int>(i)});
        }

    return loads;
}

// The case, the mesh (nodes, triangles with their bodies and regions) and the bodies' mass properties.
void write_geometry(std::ostream& o, const CaseSpec& spec, const mesh::Mesh& m, const Bodies& B) {
    const int nn = m.n_nodes(), nt = m.n_triangles();
    const double t = spec.thickness;
    o << "{\n\"format\": \"fdem-limit-model\",\n\"version\": 1,\n";
    o << "\"case\": {\"name\": " << str(spec.name) << ", \"file\": " << str(spec.file) << ", \"thickness\": " << num(t)
      << ", \"overrides\": " << list(spec.overrides, [](const auto& p) { return str(p.first + "=" + p.second); }) << "},\n";
    o << "\"stages\": " << list(spec.stages, [](const StageSpec& s) { return str(s.name); }) << ",\n";
    o << "\"regions\": " << list(m.regions, str) << ",\n";
    std::vector<int> idx(nn);
    std::iota(idx.begin(), idx.end(), 0);
    o << "\"nodes\": {\"xy\": " << list(idx, [&](int n) { return "[" + num(m.xy[2 * n]) + "," + num(m.xy[2 * n + 1]) + "]"; })
      << ",\n  \"body\": " << list(B.node_body, [](int b) { return std::to_string(b); }) << "},\n";
    std::vector<int> tidx(nt);
    std::iota(tidx.begin(), tidx.end(), 0);
    o << "\"triangles\": {\"nodes\": "
      << list(tidx, [&](int e) {
             return "[" + std::to_string(m.tri[3 * e]) + "," + std::to_string(m.tri[3 * e + 1]) + "," + std::to_string(m.tri[3 * e + 2]) + "]";
         })
      << ",\n  \"body\": " << list(B.tri_body, [](int b) { return std::to_string(b); })
      << ",\n  \"region\": " << list(m.tri_region, [](int r) { return std::to_string(r); }) << "},\n";
        o << "\"bodies\": [\n"
      << [&] {
             std::string s;
             for (int b = 0; b < static_cast<int>(B.list.size()); ++b) {
                 const Body& Bb = B.list[b];
                 std::vector<std::string> rn, mn;
                 for (int r : Bb.regions) rn.push_back(m.regions[r]), mn.push_back(B.region_material[r]);
                 s += std::string(b ? ",\n" : "") + "  {\"id\": " + std::to_string(b) + ", \"regions\": " + list(rn, str) +
                      ", \"materials\": " + list(mn, str) + ", \"triangles\": " + std::to_string(Bb.triangles) +
                      ", \"area\": " + num(Bb.area) + ", \"mass\": " + num(Bb.mass) +
                      ", \"density\": " + num(Bb.mass / (Bb.area * t)) + ", \"centroid\": [" + num(Bb.mx / Bb.mass) + "," +
                      num(Bb.my / Bb.mass) + "], \"area_centroid\": [" + num(Bb.ax / Bb.area) + "," + num(Bb.ay / Bb.area) + "]}";
             }
             return s;
         }()
      << "\n],\n";
}

void write_interfaces(std::ostream& o, const Segments& S) {
    const std::vector<Segment>& segs = S.list;
    o << "\"interfaces\": [\n";
    for (std::size_t i = 0; i < segs.size(); ++i) {
        const Segment& s = segs[i];
        o << (i ? ",\n" : "") << "  {\"kind\": " << str(s.kind) << ", \"body_a\": " << s.body_a << ", \"body_b\": " << s.body_b
          << ", \"p0\": [" << num(s.p0[0]) << "," << num(s.p0[1]) << "], \"p1\": [" << num(s.p1[0]) << "," << num(s.p1[1])
          << "], \"friction_deg\": " << num(s.friction) << ", \"cohesion\": " << num(s.cohesion)
          << ", \"tensile_strength\": " << num(s.tensile) << ", \"region_a\": " << str(s.region_a)
          << ", \"region_b\": " << str(s.region_b) << "}";
    }
    o << "\n],\n\"interface_notes\": {\"internal_joint_segments\": " << S.internal_joints
      << ", \"touching_faces_without_dry_rule\": " << S.missing_rule << "},\n";
}

void write_supports(std::ostream& o, const CaseSpec& spec, const std::map<std::array<int, 3>, std::vector<int>>& owned) {
    o << "\"supports\": [\n";
    {
        bool first = true;
        for (const auto& [key, nodes] : owned) {
            const SupportSpec& sp = spec.stages[key[0]].supports[key[1]];
            const int c = key[2];
            double protocol_last = 0;  // the displacement of the protocol's first point away from 0: its direction
            for (double u : sp.protocol_u)
                if (u != 0) {
                    protocol_last = u;
                    break;
                }
            o << (first ? "" : ",\n") << "  {\"group\": " << str(sp.group) << ", \"stage\": " << key[0] + 1
              << ", \"block\": " << key[1] + 1 << ", \"component\": " << str(c ? "y" : "x")
              << ", \"mode\": " << str(to_string(sp.mode[c])) << ", \"velocity\": " << num(sp.velocity[c])
              << ", \"protocol_first_displacement\": " << num(protocol_last)
              << ", \"has_function\": " << (sp.function.present() ? "true" : "false")
              << ", \"nodes\": " << list(nodes, [](int n) { return std::to_string(n); }) << "}";
            first = false;
        }
    }
}

// Each load in force with its nodal forces (pressure on the group's edges at the mesh's placement; a force shared by
// tributary length; a spring's force depends on the motion and is left out).
void write_loads(std::ostream& o, const CaseSpec& spec, const mesh::Mesh& m, const std::vector<Active>& loads) {
    const int nt = m.n_triangles();
    const double t = spec.thickness;
    auto group_of = [&](const std::string& name) -> const mesh::PhysicalGroup& { return m.require_group(name); };
    o << "\n],\n\"loads\": [\n";
    for (std::size_t i = 0; i < loads.size(); ++i) {
        const LoadSpec& ls = spec.stages[loads[i].stage].loads[loads[i].block];
        const mesh::PhysicalGroup& g = group_of(ls.group);
        std::map<int, std::array<double, 2>> f;
        const std::string& kind = ls.kind;  // (a spring's or a foundation's force depends on the motion: none listed)
        if (kind == "pressure") {
            // Each group edge as it runs counter-clockwise around a triangle: the outward normal is on its right.
            std::map<std::pair<int, int>, int> directed;
            for (int e = 0; e < nt; ++e)
                for (int k = 0; k < 3; ++k) directed[{m.tri[3 * e + k], m.tri[3 * e + (k + 1) % 3]}] = e;
            for (auto ed : g.edges) {
                if (!directed.count({ed[0], ed[1]})) std::swap(ed[0], ed[1]);
                if (!directed.count({ed[0], ed[1]})) continue;
                const double dx = m.xy[2 * ed[1]] - m.xy[2 * ed[0]], dy = m.xy[2 * ed[1] + 1] - m.xy[2 * ed[0] + 1];
                for (int k : {ed[0], ed[1]}) f[k][0] += -0.5 * ls.pressure * t * dy, f[k][1] += 0.5 * ls.pressure * t * dx;
            }
        } else if (kind == "force") {
            for (const auto& [k, w] : mesh::load_shares(g, m.xy)) f[k] = {w * ls.force[0], w * ls.force[1]};
        }
        o << (i ? ",\n" : "") << "  {\"group\": " << str(ls.group) << ", \"stage\": " << loads[i].stage + 1
          << ", \"kind\": " << str(kind) << ", \"force\": [" << num(ls.force[0]) << "," << num(ls.force[1])
          << "], \"pressure\": " << num(ls.pressure) << ", \"spring_component\": " << str(ls.spring_component ? "y" : "x")
          << ", \"spring_velocity\": " << num(ls.spring_velocity)
          << ", \"has_function\": " << (ls.function.present() ? "true" : "false") << ", \"node_forces\": [";
        bool first = true;
        for (const auto& [k, v] : f) {
            o << (first ? "" : ",") << "[" << k << "," << num(v[0]) << "," << num(v[1]) << "]";
            first = false;
        }
        o << "]}";
    }
}

}  // namespace

void write_limit_model(const std::string& path, const CaseSpec& spec, const mesh::Topology& topo) {
    const mesh::Mesh& m = topo.mesh;
    const Bodies bodies = rigid_bodies(spec, topo);
    Segments segs;
    add_joint_segments(spec, topo, bodies.tri_body, segs);
    add_contact_segments(spec, topo, bodies.tri_body, segs);
    const auto owned = last_supports(spec, m);
    const std::vector<Active> loads = last_loads(spec);
    // Gravity: the last vector a stage set; tilt_rate and gravity_function of the last stage(s).
    std::array<double, 2> gravity{0, 0};
    bool gravity_function = false;
    for (const auto& st : spec.stages) {
        if (st.gravity) gravity = *st.gravity, gravity_function = false;
        if (st.gravity_function.present()) gravity_function = true;
    }
    const StageSpec* last = spec.stages.empty() ? nullptr : &spec.stages.back();

    std::ostringstream o;
    write_geometry(o, spec, m, bodies);
    write_interfaces(o, segs);
    o << "\"groups\": {\n";
    for (std::size_t g = 0; g < m.groups.size(); ++g)
        o << (g ? ",\n" : "") << "  " << str(m.groups[g].name) << ": {\"dim\": " << m.groups[g].dim
          << ", \"nodes\": " << list(m.groups[g].nodes, [](int n) { return std::to_string(n); }) << "}";
    o << "\n},\n";
    write_supports(o, spec, owned);
    write_loads(o, spec, m, loads);
    o << "\n],\n\"gravity\": {\"vector\": [" << num(gravity[0]) << "," << num(gravity[1])
      << "], \"tilt_rate_deg_s\": " << num(last ? last->tilt_rate : 0.0)
      << ", \"has_function\": " << (gravity_function ? "true" : "false") << "}\n}\n";
    try {
        write_file_atomic(path, o.str());
    } catch (const std::exception& e) {
        throw InputError(std::string("cannot write the limit model: ") + e.what());
    }
}

}  // namespace fdem
