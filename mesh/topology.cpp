// mesh/topology.cpp: edge classification and node splitting (mesh/README.md 'Topology', [M04] ch. 7 for the cohesive
// element's two coincident edges).
//
// DATA LAYOUT
//   Corners: triangle t's local node i is corner 3t + i. Splitting is a union-find over corners: across every
//   edge whose nodes stay shared (class interior) the corners of the two triangles at each end point are united.
//   Each resulting class of corners is one node copy. That gives "as many copies as separated fans" directly,
//   including pinched vertices (fans touching at one point only), without walking fans.
//   Everything is serial and ordered by node, then triangle id: the output depends on the input alone.
#include "mesh/topology.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <tuple>
#include <sstream>
#include <utility>

namespace fdem::mesh {

const char* to_string(EdgeClass c) {
    switch (c) {
        case EdgeClass::interior: return "interior";
        case EdgeClass::crackable: return "crackable";
        case EdgeClass::bonded: return "bonded";
        case EdgeClass::dry: return "dry";
        case EdgeClass::free_boundary: return "free_boundary";
    }
    return "?";
}

bool parse_interface_kind(const std::string& text, InterfaceKind& kind) {
    for (auto k : {InterfaceKind::tied, InterfaceKind::bonded, InterfaceKind::dry})
        if (text == to_string(k)) {
            kind = k;
            return true;
        }
    return false;
}

const char* to_string(InterfaceKind k) {
    switch (k) {
        case InterfaceKind::tied: return "tied";
        case InterfaceKind::bonded: return "bonded";
        case InterfaceKind::dry: return "dry";
    }
    return "?";
}

namespace {

std::string where(const Mesh& m, int node) {
    std::ostringstream s;
    s.precision(6);
    s << "(" << m.xy[2 * node] << ", " << m.xy[2 * node + 1] << ") m";
    return s.str();
}

std::string region_name(const Mesh& m, int r) {
    return r >= 0 && r < static_cast<int>(m.regions.size()) ? "'" + m.regions[r] + "'" : "(no region)";
}

struct UnionFind {
    std::vector<int> parent;
    explicit UnionFind(int n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
    int find(int a) {
        while (parent[a] != a) a = parent[a] = parent[parent[a]];
        return a;
    }
    void unite(int a, int b) {
        a = find(a), b = find(b);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
};

void check_input(const Mesh& m) {
    const int nt = m.n_triangles(), nn = m.n_nodes();
    if (nt == 0) throw MeshError("the mesh has no triangles");
    if (static_cast<int>(m.tri_region.size()) != nt)
        throw MeshError("the mesh has " + std::to_string(nt) + " triangles but " + std::to_string(m.tri_region.size()) +
                        " region ids");
    if (!m.tri_body.empty() && static_cast<int>(m.tri_body.size()) != nt)
        throw MeshError("the mesh has " + std::to_string(nt) + " triangles but " + std::to_string(m.tri_body.size()) +
                        " body ids");
    for (int t = 0; t < nt; ++t) {
        const int* n = &m.tri[3 * t];
        for (int i = 0; i < 3; ++i)
            if (n[i] < 0 || n[i] >= nn)
                throw MeshError("triangle " + std::to_string(t) + " refers to node " + std::to_string(n[i]) +
                                ", outside 0.." + std::to_string(nn - 1));
        if (n[0] == n[1] || n[1] == n[2] || n[0] == n[2])
            throw MeshError("degenerate triangle " + std::to_string(t) + " in region " + region_name(m, m.tri_region[t]) +
                            " repeats a node at " + where(m, n[0]));
        const double* p = m.xy.data();
        const double a2 = (p[2 * n[1]] - p[2 * n[0]]) * (p[2 * n[2] + 1] - p[2 * n[0] + 1]) -
                          (p[2 * n[2]] - p[2 * n[0]]) * (p[2 * n[1] + 1] - p[2 * n[0] + 1]);
        if (!(a2 > 0))
            throw MeshError(std::string(a2 < 0 ? "inverted" : "degenerate") + " triangle " + std::to_string(t) +
                            " in region " + region_name(m, m.tri_region[t]) + " at " + where(m, n[0]) +
                            " (nodes must be counter-clockwise with positive area)");
    }
}

// Overlapping bodies: a conforming, non-overlapping mesh has no triangle centroid strictly inside another
// triangle. Centroids are tested against the triangles of other bodies found through a uniform grid of cells
// about one mean triangle size wide (each triangle listed in every cell its bounding box touches): O(n).
void check_overlaps(const Mesh& m, const std::vector<int>& body) {
    const int nt = m.n_triangles();
    double xmin = m.xy[0], xmax = m.xy[0], ymin = m.xy[1], ymax = m.xy[1], size = 0;
    for (int k = 0; k < m.n_nodes(); ++k) {
        xmin = std::min(xmin, m.xy[2 * k]), xmax = std::max(xmax, m.xy[2 * k]);
        ymin = std::min(ymin, m.xy[2 * k + 1]), ymax = std::max(ymax, m.xy[2 * k + 1]);
    }
    auto bbox = [&](int t, double& x0, double& y0, double& x1, double& y1) {
        const int* n = &m.tri[3 * t];
        x0 = std::min({m.xy[2 * n[0]], m.xy[2 * n[1]], m.xy[2 * n[2]]});
        x1 = std::max({m.xy[2 * n[0]], m.xy[2 * n[1]], m.xy[2 * n[2]]});
        y0 = std::min({m.xy[2 * n[0] + 1], m.xy[2 * n[1] + 1], m.xy[2 * n[2] + 1]});
        y1 = std::max({m.xy[2 * n[0] + 1], m.xy[2 * n[1] + 1], m.xy[2 * n[2] + 1]});
    };
    for (int t = 0; t < nt; ++t) {
        double x0, y0, x1, y1;
        bbox(t, x0, y0, x1, y1);
        size += std::max(x1 - x0, y1 - y0);
    }
    size /= nt;
    const int nx = std::max(1, std::min(4096, static_cast<int>((xmax - xmin) / size) + 1));
    const int ny = std::max(1, std::min(4096, static_cast<int>((ymax - ymin) / size) + 1));
    const double hx = (xmax - xmin) / nx + 1e-300, hy = (ymax - ymin) / ny + 1e-300;
    auto cx = [&](double x) { return std::clamp(static_cast<int>((x - xmin) / hx), 0, nx - 1); };
    auto cy = [&](double y) { return std::clamp(static_cast<int>((y - ymin) / hy), 0, ny - 1); };
    std::vector<int> start(static_cast<std::size_t>(nx) * ny + 1, 0), items;
    for (int pass = 0; pass < 2; ++pass) {
        std::vector<int> fill(start.begin(), start.end() - 1);
        if (pass == 1) items.resize(start.back());
        for (int t = 0; t < nt; ++t) {
            double x0, y0, x1, y1;
            bbox(t, x0, y0, x1, y1);
            for (int j = cy(y0); j <= cy(y1); ++j)
                for (int i = cx(x0); i <= cx(x1); ++i) {
                    const std::size_t c = static_cast<std::size_t>(j) * nx + i;
                    if (pass == 0) ++start[c + 1];
                    else items[fill[c]++] = t;
                }
        }
        if (pass == 0) std::partial_sum(start.begin(), start.end(), start.begin());
    }
    for (int t = 0; t < nt; ++t) {
        const int* n = &m.tri[3 * t];
        const double px = (m.xy[2 * n[0]] + m.xy[2 * n[1]] + m.xy[2 * n[2]]) / 3;
        const double py = (m.xy[2 * n[0] + 1] + m.xy[2 * n[1] + 1] + m.xy[2 * n[2] + 1]) / 3;
        const std::size_t c = static_cast<std::size_t>(cy(py)) * nx + cx(px);
        for (int q = start[c]; q < start[c + 1]; ++q) {
            const int u = items[q];
            if (body[u] == body[t]) continue;
            const int* v = &m.tri[3 * u];
            const double* a = &m.xy[2 * v[0]];
            const double* b = &m.xy[2 * v[1]];
            const double* d = &m.xy[2 * v[2]];
            const double area2 = (b[0] - a[0]) * (d[1] - a[1]) - (d[0] - a[0]) * (b[1] - a[1]);
            // Barycentric coordinates times area2; strictly inside with a margin of 1e-9 of the area.
            const double l0 = (b[0] - px) * (d[1] - py) - (d[0] - px) * (b[1] - py);
            const double l1 = (d[0] - px) * (a[1] - py) - (a[0] - px) * (d[1] - py);
            const double l2 = (a[0] - px) * (b[1] - py) - (b[0] - px) * (a[1] - py);
            const double eps = 1e-9 * area2;
            if (l0 > eps && l1 > eps && l2 > eps) {
                std::ostringstream s;
                s.precision(6);
                s << "bodies " << body[t] << " (region " << region_name(m, m.tri_region[t]) << ") and " << body[u]
                  << " (region " << region_name(m, m.tri_region[u]) << ") overlap near (" << px << ", " << py
                  << ") m: units must not overlap, and touching units must be meshed conformingly "
                     "(OpenCASCADE BooleanFragments in a .geo)";
                throw MeshError(s.str());
            }
        }
    }
}

// Bodies that touch without sharing nodes (a .geo or .msh whose units were not fragmented): a node on a free
// boundary lying on a free-boundary edge of another body, at its interior or at a coincident end point with a
// different id. Dry contact tolerates that (the contact set handles it) and is only counted; for a tied or bonded
// pair it would silently lose the joint, and a pair without a rule is a missing rule: both are errors.
template <class BodyOf, class RuleOf>
int count_nonconforming(const Mesh& m, const Topology& topo, BodyOf body_of, RuleOf rule_of) {
    std::vector<int> free_edges;
    double size = 0;
    for (int e = 0; e < topo.n_edges(); ++e)
        if (topo.edge_class[e] == EdgeClass::free_boundary) {
            free_edges.push_back(e);
            const int a = topo.edge_nodes[2 * e], b = topo.edge_nodes[2 * e + 1];
            size += std::hypot(m.xy[2 * b] - m.xy[2 * a], m.xy[2 * b + 1] - m.xy[2 * a + 1]);
        }
    if (free_edges.empty()) return 0;
    size /= static_cast<double>(free_edges.size());
    // Hash grid of cell `size` over the edges' bounding boxes.
    std::map<std::pair<long, long>, std::vector<int>> grid;
    auto cell = [&](double v) { return static_cast<long>(std::floor(v / size)); };
    for (int e : free_edges) {
        const int a = topo.edge_nodes[2 * e], b = topo.edge_nodes[2 * e + 1];
        for (long j = cell(std::min(m.xy[2 * a + 1], m.xy[2 * b + 1])); j <= cell(std::max(m.xy[2 * a + 1], m.xy[2 * b + 1])); ++j)
            for (long i = cell(std::min(m.xy[2 * a], m.xy[2 * b])); i <= cell(std::max(m.xy[2 * a], m.xy[2 * b])); ++i)
                grid[{i, j}].push_back(e);
    }
    std::vector<int> node_edge(m.n_nodes(), -1);  // one free edge at each free-boundary node
    for (int e : free_edges) node_edge[topo.edge_nodes[2 * e]] = node_edge[topo.edge_nodes[2 * e + 1]] = e;
    int count = 0;
    for (int k = 0; k < m.n_nodes(); ++k) {
        if (node_edge[k] < 0) continue;
        const int tk = topo.edge_tri[2 * node_edge[k]];
        const double px = m.xy[2 * k], py = m.xy[2 * k + 1];
        auto it = grid.find({cell(px), cell(py)});
        if (it == grid.end()) continue;
        for (int e : it->second) {
            const int a = topo.edge_nodes[2 * e], b = topo.edge_nodes[2 * e + 1];
            const int te = topo.edge_tri[2 * e];
            if (a == k || b == k || body_of(te) == body_of(tk)) continue;
            const double ex = m.xy[2 * b] - m.xy[2 * a], ey = m.xy[2 * b + 1] - m.xy[2 * a + 1];
            const double len2 = ex * ex + ey * ey;
            const double s = ((px - m.xy[2 * a]) * ex + (py - m.xy[2 * a + 1]) * ey) / len2;
            const double dist = std::abs((px - m.xy[2 * a]) * ey - (py - m.xy[2 * a + 1]) * ex) / std::sqrt(len2);
            if (s < -1e-9 || s > 1 + 1e-9 || dist > 1e-9 * std::sqrt(len2)) continue;
            const int ra = m.tri_region[tk], rb = m.tri_region[te];
            const int rule = rule_of(ra, rb);
            if (rule < 0 || rule != static_cast<int>(InterfaceKind::dry))
                throw MeshError("bodies " + std::to_string(body_of(tk)) + " (region " + region_name(m, ra) + ") and " +
                                std::to_string(body_of(te)) + " (region " + region_name(m, rb) + ") touch at " +
                                where(m, k) + " without sharing nodes; " +
                                (rule < 0 ? std::string("there is no interface rule for them, and ")
                                          : std::string("a ") + to_string(static_cast<InterfaceKind>(rule)) +
                                                " interface ") +
                                "needs a conforming mesh (OpenCASCADE BooleanFragments in a .geo)");
            ++count;
            break;
        }
    }
    return count;
}

}  // namespace

Topology build_topology(const Mesh& m, const TopologyOptions& opt) {
    check_input(m);
    const int nt = m.n_triangles(), nn = m.n_nodes(), nr = static_cast<int>(m.regions.size());
    auto body_of = [&](int t) { return m.tri_body.empty() ? m.tri_region[t] : m.tri_body[t]; };
    check_overlaps(m, m.tri_body.empty() ? m.tri_region : m.tri_body);

    // Rules by region index. -1 = no rule.
    std::vector<char> crackable(nr, 0);
    for (const auto& r : opt.regions) {
        const int i = m.find_region(r.region);
        if (i < 0) {
            std::string have;
            for (const auto& name : m.regions) have += (have.empty() ? "" : ", ") + name;
            throw MeshError("region '" + r.region + "' named by a crack rule does not exist in the mesh (regions: " +
                            have + ")");
        }
        crackable[i] = r.crackable ? 1 : 0;
    }
    std::vector<int> pair_rule(static_cast<std::size_t>(nr) * nr, -1);
    for (const auto& r : opt.interfaces) {
        const int a = m.find_region(r.region_a), b = m.find_region(r.region_b);
        for (const auto* name : {&r.region_a, &r.region_b})
            if (m.find_region(*name) < 0) {
                std::string have;
                for (const auto& n : m.regions) have += (have.empty() ? "" : ", ") + n;
                throw MeshError("region '" + *name + "' named by the interface rule '" + r.region_a + "' / '" +
                                r.region_b + "' does not exist in the mesh (regions: " + have + ")");
            }
        int& ab = pair_rule[static_cast<std::size_t>(a) * nr + b];
        if (ab >= 0 && ab != static_cast<int>(r.kind))
            throw MeshError("conflicting interface rules for regions '" + r.region_a + "' / '" + r.region_b + "': " +
                            to_string(static_cast<InterfaceKind>(ab)) + " and " + to_string(r.kind));
        ab = static_cast<int>(r.kind);
        pair_rule[static_cast<std::size_t>(b) * nr + a] = ab;
    }

    // Edges of the crack group (unordered node pairs), when crack lines are restricted.
    std::set<std::pair<int, int>> crack_edges;
    if (!opt.crack_group.empty())
        if (const PhysicalGroup* g = m.find_group(opt.crack_group))
            for (const auto& e : g->edges) crack_edges.insert({std::min(e[0], e[1]), std::max(e[0], e[1])});

    // Unique edges: sort the 3 * nt half-edges by their unordered node pair.
    struct Half {
        int lo, hi, tri, local;  // local: the half-edge runs from local node `local` to local node (local+1)%3
    };
    std::vector<Half> half;
    half.reserve(3 * static_cast<std::size_t>(nt));
    for (int t = 0; t < nt; ++t)
        for (int i = 0; i < 3; ++i) {
            const int a = m.tri[3 * t + i], b = m.tri[3 * t + (i + 1) % 3];
            half.push_back({std::min(a, b), std::max(a, b), t, i});
        }
    std::sort(half.begin(), half.end(), [](const Half& x, const Half& y) {
        return std::tie(x.lo, x.hi, x.tri) < std::tie(y.lo, y.hi, y.tri);
    });

    Topology topo;
    topo.n_nodes_before = nn;
    UnionFind corners(3 * nt);
    auto corner_of = [&](int t, int node) {
        for (int i = 0; i < 3; ++i)
            if (m.tri[3 * t + i] == node) return 3 * t + i;
        return -1;  // unreachable for a node of t
    };
    for (std::size_t i = 0; i < half.size();) {
        std::size_t j = i;
        while (j < half.size() && half[j].lo == half[i].lo && half[j].hi == half[i].hi) ++j;
        const Half& A = half[i];
        const int from = m.tri[3 * A.tri + A.local], to = m.tri[3 * A.tri + (A.local + 1) % 3];
        if (j - i > 2)
            throw MeshError("the edge " + where(m, from) + " - " + where(m, to) + " is shared by " +
                            std::to_string(j - i) + " triangles (regions " + region_name(m, m.tri_region[half[i].tri]) +
                            ", " + region_name(m, m.tri_region[half[i + 1].tri]) + ", " +
                            region_name(m, m.tri_region[half[i + 2].tri]) + "): overlapping triangles or units");
        EdgeClass cls = EdgeClass::free_boundary;
        int tb = -1;
        if (j - i == 2) {
            const Half& B = half[i + 1];
            tb = B.tri;
            if (m.tri[3 * B.tri + B.local] == from)
                throw MeshError("triangles " + std::to_string(A.tri) + " (region " + region_name(m, m.tri_region[A.tri]) +
                                ") and " + std::to_string(B.tri) + " (region " + region_name(m, m.tri_region[B.tri]) +
                                ") lie on the same side of their common edge at " + where(m, from) +
                                ": overlapping or inverted triangles");
            const int ra = m.tri_region[A.tri], rb = m.tri_region[B.tri];
            const bool same_body = body_of(A.tri) == body_of(B.tri) && ra == rb;
            bool tied = same_body;
            if (!same_body) {
                const int rule = (ra < 0 || rb < 0) ? -1 : pair_rule[static_cast<std::size_t>(ra) * nr + rb];
                if (rule < 0)
                    throw MeshError("no interface rule for regions " + region_name(m, ra) + " and " + region_name(m, rb) +
                                    (ra == rb ? " (two different bodies of one region)" : "") + ", which touch at " +
                                    where(m, from) + "; give one: tied, bonded or dry");
                const auto kind = static_cast<InterfaceKind>(rule);
                tied = kind == InterfaceKind::tied;
                if (kind == InterfaceKind::bonded) cls = EdgeClass::bonded;
                if (kind == InterfaceKind::dry) cls = EdgeClass::dry;
            }
            if (tied) {
                const bool can_crack = ra >= 0 && rb >= 0 && crackable[ra] && crackable[rb] &&
                                       (opt.crack_group.empty() || crack_edges.count({A.lo, A.hi}) > 0);
                cls = (opt.split_all || can_crack) ? EdgeClass::crackable : EdgeClass::interior;
            }
            if (cls == EdgeClass::interior) {
                corners.unite(corner_of(A.tri, from), corner_of(B.tri, from));
                corners.unite(corner_of(A.tri, to), corner_of(B.tri, to));
            }
        }
        topo.edge_nodes.push_back(from);
        topo.edge_nodes.push_back(to);
        topo.edge_tri.push_back(A.tri);
        topo.edge_tri.push_back(tb);
        topo.edge_class.push_back(cls);
        i = j;
    }

    topo.nonconforming_nodes = count_nonconforming(m, topo, body_of, [&](int ra, int rb) {
        return (ra < 0 || rb < 0) ? -1 : pair_rule[static_cast<std::size_t>(ra) * nr + rb];
    });

    // Node copies: corners of each node in triangle order; a new copy for each new union-find class.
    std::vector<int> node_start(nn + 1, 0);
    for (int c = 0; c < 3 * nt; ++c) ++node_start[m.tri[c] + 1];
    std::partial_sum(node_start.begin(), node_start.end(), node_start.begin());
    std::vector<int> node_corners(3 * static_cast<std::size_t>(nt));
    {
        std::vector<int> fill(node_start.begin(), node_start.end() - 1);
        for (int c = 0; c < 3 * nt; ++c) node_corners[fill[m.tri[c]]++] = c;  // c increases: triangle order
    }
    std::vector<int> corner_node(3 * static_cast<std::size_t>(nt), -1);  // corner -> split node
    std::vector<int> root_node(3 * static_cast<std::size_t>(nt), -1);    // union-find root -> split node
    std::vector<int> copies_start(nn + 1, 0);
    Mesh& out = topo.mesh;
    for (int k = 0; k < nn; ++k) {
        copies_start[k] = static_cast<int>(topo.node_origin.size());
        for (int p = node_start[k]; p < node_start[k + 1]; ++p) {
            const int c = node_corners[p];
            const int r = corners.find(c);
            if (root_node[r] < 0) {
                root_node[r] = static_cast<int>(topo.node_origin.size());
                topo.node_origin.push_back(k);
                out.xy.push_back(m.xy[2 * k]);
                out.xy.push_back(m.xy[2 * k + 1]);
            }
            corner_node[c] = root_node[r];
        }
    }
    copies_start[nn] = static_cast<int>(topo.node_origin.size());
    out.tri = corner_node;
    out.tri_region = m.tri_region;
    out.tri_body = m.tri_body.empty() ? m.tri_region : m.tri_body;
    out.regions = m.regions;

    // Cohesive elements and dry joint segments in edge order.
    for (int e = 0; e < topo.n_edges(); ++e) {
        const EdgeClass cls = topo.edge_class[e];
        if (cls != EdgeClass::crackable && cls != EdgeClass::bonded && cls != EdgeClass::dry) continue;
        CohesiveElement ce;
        const int p = topo.edge_nodes[2 * e], q = topo.edge_nodes[2 * e + 1];
        ce.tri_a = topo.edge_tri[2 * e];
        ce.tri_b = topo.edge_tri[2 * e + 1];
        ce.n = {corner_node[corner_of(ce.tri_a, p)], corner_node[corner_of(ce.tri_a, q)],
                corner_node[corner_of(ce.tri_b, p)], corner_node[corner_of(ce.tri_b, q)]};
        ce.body_a = out.tri_body[ce.tri_a];
        ce.body_b = out.tri_body[ce.tri_b];
        ce.region_a = m.tri_region[ce.tri_a];
        ce.region_b = m.tri_region[ce.tri_b];
        ce.kind = cls;
        ce.edge = e;
        (cls == EdgeClass::dry ? topo.dry_joints : topo.cohesive).push_back(ce);
    }

    // Contact-capable triangles.
    std::vector<char> capable(nt, 0);
    {
        std::vector<char> exposed_node(nn, 0);
        for (int e = 0; e < topo.n_edges(); ++e) {
            const EdgeClass cls = topo.edge_class[e];
            if (cls != EdgeClass::free_boundary && cls != EdgeClass::dry) continue;
            if (opt.contact_by_node) {
                exposed_node[topo.edge_nodes[2 * e]] = 1;
                exposed_node[topo.edge_nodes[2 * e + 1]] = 1;
            } else {
                capable[topo.edge_tri[2 * e]] = 1;
                if (topo.edge_tri[2 * e + 1] >= 0) capable[topo.edge_tri[2 * e + 1]] = 1;
            }
        }
        if (opt.contact_by_node)
            for (int t = 0; t < nt; ++t)
                for (int i = 0; i < 3; ++i)
                    if (exposed_node[m.tri[3 * t + i]]) capable[t] = 1;
    }
    for (int t = 0; t < nt; ++t)
        if (capable[t]) topo.contact_capable.push_back(t);

    // Groups on the split mesh.
    auto find_edge = [&](int a, int b) {
        const int lo = std::min(a, b), hi = std::max(a, b);
        // edge_nodes are sorted by (lo, hi) because `half` was.
        int first = 0, last = topo.n_edges();
        while (first < last) {
            const int mid = (first + last) / 2;
            const int mlo = std::min(topo.edge_nodes[2 * mid], topo.edge_nodes[2 * mid + 1]);
            const int mhi = std::max(topo.edge_nodes[2 * mid], topo.edge_nodes[2 * mid + 1]);
            if (std::make_pair(mlo, mhi) < std::make_pair(lo, hi)) first = mid + 1;
            else last = mid;
        }
        if (first < topo.n_edges() && std::min(topo.edge_nodes[2 * first], topo.edge_nodes[2 * first + 1]) == lo &&
            std::max(topo.edge_nodes[2 * first], topo.edge_nodes[2 * first + 1]) == hi)
            return first;
        return -1;
    };
    // The bodies each node copy belongs to (several only where tied bodies share it).
    const int n_split = static_cast<int>(topo.node_origin.size());
    std::vector<std::vector<int>> copy_bodies(n_split);
    for (int t = 0; t < nt; ++t)
        for (int i = 0; i < 3; ++i) {
            auto& b = copy_bodies[out.tri[3 * t + i]];
            if (std::find(b.begin(), b.end(), out.tri_body[t]) == b.end()) b.push_back(out.tri_body[t]);
        }
    // The bodies a group is attached to: a surface group's triangles, a curve group's edges (the triangles on
    // either side), a case group's `within` group. Empty: no rule (a point group, a box without `within`).
    auto owner_bodies = [&](const PhysicalGroup& g) {
        std::set<int> own;
        const PhysicalGroup* cur = &g;
        for (int depth = 0; cur && depth < 8; ++depth) {
            if (cur->dim == 2)
                for (int t : cur->triangles) own.insert(out.tri_body[t]);
            if (cur->dim == 1)
                for (const auto& ed : cur->edges) {
                    const int e = find_edge(ed[0], ed[1]);
                    if (e < 0) continue;
                    for (int side = 0; side < 2; ++side)
                        if (topo.edge_tri[2 * e + side] >= 0) own.insert(out.tri_body[topo.edge_tri[2 * e + side]]);
                }
            if (!own.empty() || cur->within.empty()) break;
            cur = m.find_group(cur->within);
        }
        return std::vector<int>(own.begin(), own.end());
    };
    for (const auto& g : m.groups) {
        PhysicalGroup h;
        h.name = g.name;
        h.dim = g.dim;
        h.triangles = g.triangles;
        h.within = g.within;
        h.every_copy = g.every_copy;
        if (g.dim == 2 && !g.triangles.empty()) {
            // A surface group keeps only the node copies of its own triangles: a support on the upper block must
            // not drag the lower block's copies of the nodes they shared before splitting.
            for (int t : g.triangles)
                for (int k = 0; k < 3; ++k) h.nodes.push_back(out.tri[3 * t + k]);
            std::sort(h.nodes.begin(), h.nodes.end());
            h.nodes.erase(std::unique(h.nodes.begin(), h.nodes.end()), h.nodes.end());
            h.bodies = owner_bodies(g);
        } else if (const std::vector<int> own = g.every_copy ? std::vector<int>{} : owner_bodies(g); !own.empty()) {
            // A curve group (or a case group with `within`) takes the copies on its own bodies only: a curve of the
            // upper block that ends at a corner of the lower block must not drag the lower block's copy there.
            std::set<int> left_out, taken;  // taken: the own bodies of the copies held (a point picked `within` a
            for (int k : g.nodes) {         // group of many bodies is on one or two of them)
                const std::size_t before = h.nodes.size();
                for (int c = copies_start[k]; c < copies_start[k + 1]; ++c) {
                    bool mine = false;
                    for (int b : copy_bodies[c])
                        if (std::binary_search(own.begin(), own.end(), b)) mine = true, taken.insert(b);
                    if (mine) h.nodes.push_back(c);
                    else left_out.insert(copy_bodies[c].begin(), copy_bodies[c].end());
                }
                if (h.nodes.size() == before)  // a node off the group's bodies (not reached by a mesh group)
                    for (int c = copies_start[k]; c < copies_start[k + 1]; ++c) h.nodes.push_back(c);
            }
            for (int b : left_out)
                if (!std::binary_search(own.begin(), own.end(), b)) h.left_out_bodies.push_back(b);
            h.bodies = taken.empty() ? own : std::vector<int>(taken.begin(), taken.end());
        } else {
            // No body rule: every copy. A node whose copies lie on bodies that share no copy (a dry or bonded
            // joint runs through it) is dragged on all of them; the case loader refuses to load or support it.
            std::set<int> split;
            for (int k : g.nodes) {
                std::set<int> all;
                bool one_copy_holds_all = false;
                for (int c = copies_start[k]; c < copies_start[k + 1]; ++c) {
                    h.nodes.push_back(c);
                    all.insert(copy_bodies[c].begin(), copy_bodies[c].end());
                }
                for (int c = copies_start[k]; c < copies_start[k + 1]; ++c)
                    one_copy_holds_all = one_copy_holds_all || copy_bodies[c].size() == all.size();
                if (!g.every_copy && all.size() > 1 && !one_copy_holds_all) {
                    split.insert(all.begin(), all.end());
                    if (h.split_node < 0) h.split_node = copies_start[k];
                }
            }
            h.split_bodies.assign(split.begin(), split.end());
        }
        for (const auto& ed : g.edges) {
            const int e = find_edge(ed[0], ed[1]);
            if (e < 0) continue;  // not an edge of any triangle (a curve outside the meshed regions)
            std::array<int, 2> seen[2];
            int n_seen = 0;
            for (int side = 0; side < 2; ++side) {
                const int t = topo.edge_tri[2 * e + side];
                if (t < 0) continue;
                const std::array<int, 2> copy{corner_node[corner_of(t, ed[0])], corner_node[corner_of(t, ed[1])]};
                if (n_seen == 1 && seen[0] == copy) continue;
                seen[n_seen++] = copy;
                h.edges.push_back(copy);
            }
        }
        out.groups.push_back(std::move(h));
    }
    return topo;
}

std::map<int, double> load_shares(const PhysicalGroup& g, const std::vector<double>& X) {
    std::map<int, double> share;
    double total = 0;
    for (const auto& ed : g.edges) {
        const double L = std::hypot(X[2 * ed[1]] - X[2 * ed[0]], X[2 * ed[1] + 1] - X[2 * ed[0] + 1]);
        share[ed[0]] += 0.5 * L, share[ed[1]] += 0.5 * L, total += L;
    }
    if (g.edges.empty())
        for (int k : g.nodes) share[k] += 1.0, total += 1.0;
    for (auto& [k, w] : share) w = w / total;
    return share;
}

}  // namespace fdem::mesh
