// contact/contact_system.cpp: detection schedule, pair bookkeeping, deterministic parallel force evaluation.
// Layout and contract in contact_system.hpp; the pair physics in potential.hpp; detection in nbs.hpp.
#include "contact/contact_system.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <omp.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <sstream>
#include <stdexcept>

#include "contact/potential.hpp"

namespace fdem::contact {

namespace {

// Below this many items a loop runs on one thread: a parallel region costs more than it saves, and on a shared,
// oversubscribed machine its barrier can cost milliseconds. Results are the same bits either way.
constexpr int kParallelMin = 4096;
// Pairs per block of the pair loop (the unit of its threads' shares and of the lists of pairs with something to add):
// four batches, so that shares of a wall's 5662 pairs (22 blocks) are cut to a few per cent (64 and 128 ran alike on
// two threads and 1 % slower on one).
constexpr int kPairBlock = 256;
// Pairs per batch of edge integrals (PairBatch): its queued edges (about one per pair, 160 bytes each) and the pairs'
// geometry and history stay in the core's first-level cache from the first stage to the loads.
// (32 and 64 ran alike, 512 took as long as one pair at a time)
constexpr int kBatchPairs = 64;
constexpr int kPrefetchPairs = 8;  // how far ahead the pair loop asks for the boxes and geometry it will read
static_assert(kPairBlock % kBatchPairs == 0, "a block is whole batches");
// The cost of a block of the pair loop in units of a pair rejected by its boxes: a pair queued for edge integrals
// counts kQueuedCost more (the shares need only be about right: the queued pairs are spread evenly along the list).
constexpr int kQueuedCost = 8;

// The thread of a team of T that adds node k's contact forces: own[k] (set_node_owner's map, when it is for T
// threads), else the node's share k * T / n_nodes.
inline int thread_of(int k, int T, const unsigned char* own, int n_nodes) {
    if (T == 1) return 0;
    return own ? own[k] : static_cast<int>(static_cast<long long>(k) * T / n_nodes);
}

// Cuts n = cost.size() blocks into T contiguous shares of about equal total cost: thread t takes blocks
// [first[t], first[t + 1]) (first has T + 1 entries; a share may be empty).
inline void cut_shares(const std::vector<int>& cost, int T, std::vector<int>& first) {
    const int n = static_cast<int>(cost.size());
    first.assign(T + 1, n);
    first[0] = 0;
    long long total = 0, acc = 0;
    for (int c : cost) total += c;
    int t = 1;
    for (int b = 0; b < n && t < T; ++b) {
        acc += cost[b];
        while (t < T && acc * T >= total * t) first[t++] = b + 1;
    }
}

// Asks for the cache lines of bytes [p, p + n) ahead of their use (write: for a store).
inline void prefetch_bytes(const void* p, std::size_t n, bool write = false) {
    const char* c = static_cast<const char*>(p);
    for (std::size_t o = 0; o < n; o += 64) {
        if (write) __builtin_prefetch(c + o, 1);
        else __builtin_prefetch(c + o);
    }
}

// Whether a pair's friction state holds anything (some slot not all zero).
inline bool any_history(const double* h) {
    bool any = false;
    for (int s = 0; s < kHistPerPair; ++s) any = any || h[s] != 0.0;
    return any;
}

// A separated pair forgets its sliding history; written only when there is something to forget (most pairs
// are apart and this keeps their history lines clean in cache).
// Returns the energy its friction springs held (J), which the caller books as dissipated.
inline double forget(double* h) {
    double released = 0.0;
    if (any_history(h))
        for (int s = 0; s < 6; ++s) released += release_slot(h + kHistPerEdge * s);
    return released;
}

// max over the nodes of |v|^2 (m^2/s^2); a node with a NaN velocity is passed over (as std::max(m, NaN) = m). The
// max is exact in any order, so the lanes and threads give the same bits as one loop. In threads only above 16k
// nodes: the scan takes about 1 ns per node, less than a parallel region's fork and join below that.
double largest_speed2(const double* v, int n) {
    double m = 0.0;
#pragma omp parallel for schedule(static) reduction(max : m) if (n > 4 * kParallelMin)
    for (int b = 0; b < (n + 1023) / 1024; ++b) {
        const int k0 = 1024 * b, k1 = std::min(n, k0 + 1024);
        int k = k0;
        double mb = 0.0;
#if defined(__SSE2__)
        // two nodes per step: (vx0^2 + vy0^2, vx1^2 + vy1^2), the same sums as below; maxpd keeps its second
        // operand when the first is NaN
        __m128d acc = _mm_setzero_pd();
        for (; k + 1 < k1; k += 2) {
            const __m128d a = _mm_loadu_pd(v + 2 * k), c = _mm_loadu_pd(v + 2 * k + 2);
            const __m128d a2 = _mm_mul_pd(a, a), c2 = _mm_mul_pd(c, c);
            acc = _mm_max_pd(_mm_add_pd(_mm_unpacklo_pd(a2, c2), _mm_unpackhi_pd(a2, c2)), acc);
        }
        double lanes[2];
        _mm_storeu_pd(lanes, acc);
        mb = std::max(lanes[0], lanes[1]);
#endif
        for (; k < k1; ++k) mb = std::max(mb, v[2 * k] * v[2 * k] + v[2 * k + 1] * v[2 * k + 1]);
        m = std::max(m, mb);
    }
    return m;
}

// Whether segment PQ and triangle T (6 coordinates, m) are within d of each other (m): P or Q inside T, or PQ
// crossing an edge, or an end point within d of the other's segments. Collinear and touching cases count as within.
bool segment_near_triangle(const double* P, const double* Q, const double* T, double d) {
    auto orient = [](const double* a, const double* b, const double* c) {
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    };
    auto point_segment2 = [](const double* p, const double* a, const double* b) {
        const double ux = b[0] - a[0], uy = b[1] - a[1], wx = p[0] - a[0], wy = p[1] - a[1];
        const double uu = ux * ux + uy * uy;
        const double s = uu > 0.0 ? std::clamp((wx * ux + wy * uy) / uu, 0.0, 1.0) : 0.0;
        const double rx = wx - s * ux, ry = wy - s * uy;
        return rx * rx + ry * ry;
    };
    const double* A[3] = {T, T + 2, T + 4};
    const double area = orient(A[0], A[1], A[2]);
    for (const double* p : {P, Q}) {  // an end point inside T (or on its boundary)
        const double o0 = orient(A[0], A[1], p), o1 = orient(A[1], A[2], p), o2 = orient(A[2], A[0], p);
        if (area >= 0.0 ? (o0 >= 0.0 && o1 >= 0.0 && o2 >= 0.0) : (o0 <= 0.0 && o1 <= 0.0 && o2 <= 0.0)) return true;
    }
    const double d2 = d * d;
    for (int k = 0; k < 3; ++k) {
        const double* a = A[k];
        const double* b = A[(k + 1) % 3];
        const double s1 = orient(P, Q, a), s2 = orient(P, Q, b), s3 = orient(a, b, P), s4 = orient(a, b, Q);
        if (((s1 <= 0.0 && s2 >= 0.0) || (s1 >= 0.0 && s2 <= 0.0)) && ((s3 <= 0.0 && s4 >= 0.0) || (s3 >= 0.0 && s4 <= 0.0)))
            return true;  // PQ meets edge ab
        if (point_segment2(P, a, b) <= d2 || point_segment2(Q, a, b) <= d2 || point_segment2(a, P, Q) <= d2) return true;
    }
    return false;
}

}  // namespace

ContactSystem::ContactSystem(const int* tri, int n_tri, int n_nodes, double thickness, std::vector<int> tri_material,
                             std::vector<int> tri_body, const ContactLaws& laws, ContactOptions options)
    : tri_(tri),
      n_tri_(n_tri),
      n_nodes_(n_nodes),
      thickness_(thickness),
      material_(std::move(tri_material)),
      body_(std::move(tri_body)),
      opt_(options) {
    if (n_tri < 0 || n_nodes < 0) throw std::invalid_argument("ContactSystem: negative sizes");
    if (!(thickness > 0.0) || !std::isfinite(thickness))
        throw std::invalid_argument("ContactSystem: thickness must be > 0 m");
    if (static_cast<int>(material_.size()) != n_tri || static_cast<int>(body_.size()) != n_tri)
        throw std::invalid_argument("ContactSystem: tri_material and tri_body need one entry per triangle");
    if (!(opt_.buffer >= 0.0)) throw std::invalid_argument("ContactSystem: buffer must be >= 0 m");
    n_mat_ = laws.n_materials();
    for (int t = 0; t < n_tri; ++t) {
        if (material_[t] < 0) throw std::invalid_argument("ContactSystem: negative material index");
        n_mat_ = std::max(n_mat_, material_[t] + 1);
        for (int k = 0; k < 3; ++k)
            if (tri[3 * t + k] < 0 || tri[3 * t + k] >= n_nodes)
                throw std::invalid_argument("ContactSystem: triangle node index out of range");
    }
    std::vector<char> present(n_mat_, 0);
    for (int m : material_) present[m] = 1;
    interface_law_.assign(static_cast<size_t>(n_mat_) * n_mat_, -1);
    crack_law_.assign(n_mat_, -1);
    for (int a = 0; a < n_mat_; ++a) {
        if (!present[a]) continue;
        for (int b = a; b < n_mat_; ++b) {
            if (!present[b]) continue;
            const ContactLaw* law = laws.interface(a, b);
            if (!law && laws.unlisted_never_touch()) continue;  // index stays -1: never a pair
            if (!law) {
                std::ostringstream os;
                os << "no contact law for the interface between materials " << a << " and " << b;
                throw std::invalid_argument(os.str());
            }
            laws_.push_back(resolve_law(*law));
            interface_law_[a * n_mat_ + b] = interface_law_[b * n_mat_ + a] = static_cast<int>(laws_.size()) - 1;
        }
        // A crack inside a unit uses the material's crack law (residual friction); without one, the law of two
        // units of that material.
        if (const ContactLaw* law = laws.crack(a)) {
            laws_.push_back(resolve_law(*law));
            crack_law_[a] = static_cast<int>(laws_.size()) - 1;
        } else {
            crack_law_[a] = interface_law_[a * n_mat_ + a];
        }
    }
    for (const ResolvedLaw& L : laws_) inelastic_ = inelastic_ || L.restitution < 1.0;
    capable_.assign(n_tri, 0);
    near_law_.assign(3 * static_cast<std::size_t>(n_tri), 0);
    excluded_.resize(n_tri);
    // Edges shared by two triangles through both nodes lie inside a continuum: no face.
    continuum_faces_.assign(n_tri, 7);
    {
        std::vector<std::array<int, 4>> edges;  // (lower node, higher node, triangle, edge)
        edges.reserve(3 * static_cast<size_t>(n_tri));
        for (int t = 0; t < n_tri; ++t)
            for (int e = 0; e < 3; ++e) {
                const int p = tri[3 * t + e], q = tri[3 * t + (e + 1) % 3];
                edges.push_back({std::min(p, q), std::max(p, q), t, e});
            }
        std::sort(edges.begin(), edges.end());
        for (std::size_t i = 0; i + 1 < edges.size(); ++i)
            if (edges[i][0] == edges[i + 1][0] && edges[i][1] == edges[i + 1][1])
                for (std::size_t j : {i, i + 1})
                    continuum_faces_[edges[j][2]] &= static_cast<unsigned char>(~(1u << edges[j][3]));
    }
}

void ContactSystem::update_faces() {
    faces_ = continuum_faces_;
    auto key = [&](int node) { return vertex_.empty() ? node : vertex_[node]; };
    for (int t = 0; t < n_tri_; ++t)
        for (int u : excluded_[t]) {
            // A joint between two bodies keeps its faces: the neighbours of the other side pair with this triangle,
            // its partner across the joint (same body as them) does not, so nothing cancels their loads.
            if (body_[u] != body_[t]) continue;
            const int ku[3] = {key(tri_[3 * u]), key(tri_[3 * u + 1]), key(tri_[3 * u + 2])};
            auto in_u = [&](int k) { return k == ku[0] || k == ku[1] || k == ku[2]; };
            for (int e = 0; e < 3; ++e)
                if (in_u(key(tri_[3 * t + e])) && in_u(key(tri_[3 * t + (e + 1) % 3])))
                    faces_[t] &= static_cast<unsigned char>(~(1u << e));
        }
    faces_dirty_ = false;
}

int ContactSystem::law_of(int ta, int tb) const {
    const int ma = material_[ta], mb = material_[tb];
    if (body_[ta] == body_[tb] && ma == mb) return crack_law_[ma];
    return interface_law_[ma * n_mat_ + mb];
}

void ContactSystem::set_capable(int t, bool c) {
    if (t < 0 || t >= n_tri_) throw std::out_of_range("ContactSystem::set_capable: triangle index");
    if ((capable_[t] != 0) != c) dirty_ = true;
    capable_[t] = c ? 1 : 0;
}

void ContactSystem::exclude_pair(int ta, int tb) {
    if (ta < 0 || tb < 0 || ta >= n_tri_ || tb >= n_tri_)
        throw std::out_of_range("ContactSystem::exclude_pair: triangle index");
    auto add = [](std::vector<int>& v, int x) {
        if (std::find(v.begin(), v.end(), x) == v.end()) v.push_back(x);
    };
    add(excluded_[ta], tb);
    add(excluded_[tb], ta);
    dirty_ = faces_dirty_ = true;
}

void ContactSystem::include_pair(int ta, int tb) {
    if (ta < 0 || tb < 0 || ta >= n_tri_ || tb >= n_tri_)
        throw std::out_of_range("ContactSystem::include_pair: triangle index");
    auto del = [](std::vector<int>& v, int x) { v.erase(std::remove(v.begin(), v.end(), x), v.end()); };
    del(excluded_[ta], tb);
    del(excluded_[tb], ta);
    dirty_ = faces_dirty_ = true;
}

void ContactSystem::set_vertex_copies(std::vector<int> vertex) {
    if (!vertex.empty() && static_cast<int>(vertex.size()) != n_nodes_)
        throw std::invalid_argument("ContactSystem::set_vertex_copies: one vertex per node, or none");
    int n_vertices = 0;
    for (int v : vertex) {
        if (v < 0) throw std::invalid_argument("ContactSystem::set_vertex_copies: negative vertex index");
        n_vertices = std::max(n_vertices, v + 1);
    }
    vertex_ = std::move(vertex);
    released_.assign(n_vertices, 0);
    dirty_ = faces_dirty_ = true;
}

void ContactSystem::release_vertex_of(int node) {
    if (node < 0 || node >= n_nodes_) throw std::out_of_range("ContactSystem::release_vertex_of: node index");
    if (vertex_.empty()) return;
    char& r = released_[vertex_[node]];
    if (!r) dirty_ = true;
    r = 1;
}

std::vector<double> ContactSystem::node_stiffness(const double* x, const std::uint8_t* held, bool candidates) const {
    // Per law: the stiffest stiffness-law slope (Pa/m) and the largest penalty (Pa) it has, normal or tangential (an
    // inelastic law unloads along a line of slope k / e^2: potential.hpp, PairParams::inv_e2).
    const int nl = static_cast<int>(laws_.size());
    std::vector<double> k_law(nl, 0.0), p_law(nl, 0.0);
    for (int li = 0; li < nl; ++li) {
        const ResolvedLaw& L = laws_[li];
        const double unloading = L.normal / (L.restitution * L.restitution);
        (L.normal_is_stiffness ? k_law[li] : p_law[li]) = unloading;
        double& tg = L.tangential_is_stiffness ? k_law[li] : p_law[li];
        tg = std::max(tg, L.tangential);
    }
    // Per material: the same over every law it can meet (without candidates).
    std::vector<double> k_max(n_mat_, 0.0), p_max(n_mat_, 0.0);
    auto account = [&](int m, int li) {
        if (li < 0) return;
        k_max[m] = std::max(k_max[m], k_law[li]);
        p_max[m] = std::max(p_max[m], p_law[li]);
    };
    for (int a = 0; a < n_mat_; ++a) {
        account(a, crack_law_[a]);
        for (int b = 0; b < n_mat_; ++b) account(a, interface_law_[a * n_mat_ + b]);
    }
    // Gershgorin row sum of a node (as the cohesive elements' bound): a face of length L pressed with slope k
    // (Pa/m) couples its node to its own two nodes by k t L (1/3 + 1/6) and to the other face's nodes by k t L / 2,
    // so each face at the node adds k t L. Every edge that is or may become a face counts (all but the edges
    // inside a continuum): a node on a straight boundary of a continuum has two, a copy at a corner of a split
    // triangle two. (Counting one triangle's longest edge once, the bound let a stack of stiff dry joints go
    // unstable at 0.76-0.8 of the step it allowed.) With candidates, an edge counts with the laws of the candidate
    // partners it was near at the last detection (near_law_), and not at all without one.
    std::vector<double> k(n_nodes_, 0.0);
    for (int t = 0; t < n_tri_; ++t) {
        const std::uint64_t* near = &near_law_[3 * static_cast<std::size_t>(t)];
        if (candidates && (near[0] | near[1] | near[2]) == 0) continue;
        double T[6];
        gather(x, tri_ + 3 * t, T);
        const double h = smallest_altitude(T);
        for (int e = 0; e < 3; ++e) {
            if (!((continuum_faces_[t] >> e) & 1)) continue;
            if (held && ((held[t] >> e) & 1)) continue;
            // Penalty law: pressure/overlap slope 3 p (1/H_a + 1/H_b) <= 6 p / H ([MA00] phi = 3 min L_k).
            double slope = std::max(k_max[material_[t]], 6.0 * p_max[material_[t]] / h);  // Pa/m
            if (candidates) {
                double kc = 0.0, pc = 0.0;
                for (int li = 0; li < nl; ++li)
                    if ((near[e] >> std::min(li, 63)) & 1) kc = std::max(kc, k_law[li]), pc = std::max(pc, p_law[li]);
                if (kc == 0.0 && pc == 0.0) continue;
                slope = std::max(kc, 6.0 * pc / h);
            }
            const int e1 = (e + 1) % 3;
            const double kf = slope * thickness_ * std::hypot(T[2 * e1] - T[2 * e], T[2 * e1 + 1] - T[2 * e + 1]);  // N/m
            k[tri_[3 * t + e]] += kf;
            k[tri_[3 * t + e1]] += kf;
        }
    }
    return k;
}

double ContactSystem::stable_dt(const double* x, const double* node_mass) const {
    const std::vector<double> k = node_stiffness(x);
    double dt = std::numeric_limits<double>::infinity();
    for (int v = 0; v < n_nodes_; ++v)
        if (k[v] > 0.0) dt = std::min(dt, 2.0 * std::sqrt(node_mass[v] / k[v]));
    return dt;
}

double ContactSystem::effective_buffer(const double* x) const {
    if (buffer_ > 0.0) return buffer_;
    if (opt_.buffer > 0.0) return opt_.buffer;
    double lmin = std::numeric_limits<double>::infinity();
    for (int t = 0; t < n_tri_; ++t) {
        double T[6];
        gather(x, tri_ + 3 * t, T);
        for (int k = 0; k < 3; ++k) {
            const int j = (k + 1) % 3;
            lmin = std::min(lmin, std::hypot(T[2 * j] - T[2 * k], T[2 * j + 1] - T[2 * k + 1]));
        }
    }
    return std::isfinite(lmin) ? lmin / 5.0 : 0.0;  // cases/REFERENCE.md, contact.buffer
}

void ContactSystem::detect(const double* x) {
    const double t0 = omp_get_wtime();
    items_.clear();
    for (int t = 0; t < n_tri_; ++t)
        if (capable_[t]) items_.push_back(t);
    const int n = static_cast<int>(items_.size());
    if (buffer_ <= 0.0) buffer_ = effective_buffer(x);
    // scratch kept between detections: no allocation, no page faults on the hot path
    std::vector<double>& icx = cx_;
    std::vector<double>& icy = cy_;
    std::vector<double>& ir = cr_;
    icx.resize(n);
    icy.resize(n);
    ir.resize(n);
#pragma omp parallel for schedule(static) if (n > kParallelMin)
    for (int i = 0; i < n; ++i) {
        double T[6];
        gather(x, tri_ + 3 * items_[i], T);
        const double cxv = (T[0] + T[2] + T[4]) / 3.0, cyv = (T[1] + T[3] + T[5]) / 3.0;
        double r2 = 0.0;
        for (int k = 0; k < 3; ++k)
            r2 = std::max(r2, (T[2 * k] - cxv) * (T[2 * k] - cxv) + (T[2 * k + 1] - cyv) * (T[2 * k + 1] - cyv));
        icx[i] = cxv;
        icy[i] = cyv;
        ir[i] = std::sqrt(r2);
    }
    nbs_detect(icx.data(), icy.data(), ir.data(), items_.data(), n, buffer_, cand_, ws_);

    // Drop pairs that share a node, an intact cohesive element or an unreleased vertex of one body, in parallel into
    // flags, then compact in order.
    const int nc = cand_.size();
    std::vector<char>& keep = keep_;
    keep.resize(nc);
#pragma omp parallel for schedule(static) if (nc > kParallelMin)
    for (int p = 0; p < nc; ++p) {
        const int a = cand_.a[p], b = cand_.b[p];
        bool ok = true;
        for (int i = 0; i < 3 && ok; ++i)
            for (int j = 0; j < 3; ++j)
                if (tri_[3 * a + i] == tri_[3 * b + j]) {
                    ok = false;
                    break;
                }
        if (ok)
            for (int e : excluded_[a])
                if (e == b) {
                    ok = false;
                    break;
                }
        if (ok && law_of(a, b) < 0) ok = false;  // a combination that never touches
        if (ok && !vertex_.empty() && body_[a] == body_[b])  // corner neighbours inside an intact unit
            for (int i = 0; i < 3 && ok; ++i) {
                const int va = vertex_[tri_[3 * a + i]];
                if (released_[va]) continue;
                for (int j = 0; j < 3; ++j)
                    if (vertex_[tri_[3 * b + j]] == va) {
                        ok = false;
                        break;
                    }
            }
        keep[p] = ok ? 1 : 0;
    }
    std::vector<int>& na = new_a_;
    std::vector<int>& nb = new_b_;
    na.clear();
    nb.clear();
    for (int p = 0; p < nc; ++p)
        if (keep[p]) {
            na.push_back(cand_.a[p]);
            nb.push_back(cand_.b[p]);
        }
    const int np = static_cast<int>(na.size());

    // Carry the sliding history of pairs that persist ([K25] Eq. 4 needs the accumulated delta_s): old pairs
    // bucketed by their first triangle (counting sort, O(P)), each new pair looks in its bucket.
    std::vector<double>& nh = new_hist_;
    nh.assign(kHistPerPair * static_cast<size_t>(np), 0.0);
    std::vector<char>& non = new_hist_on_;
    non.assign(np, 0);
    const int op = static_cast<int>(pair_a_.size());
    if (op > 0) {
        std::vector<int>& start = csr_start_;
        std::vector<int>& order = csr_order_;
        start.assign(n_tri_ + 1, 0);
        order.resize(op);
        for (int p = 0; p < op; ++p) ++start[pair_a_[p] + 1];
        for (int t = 0; t < n_tri_; ++t) start[t + 1] += start[t];
        std::vector<int>& fill = csr_fill_;
        fill.assign(start.begin(), start.end() - 1);
        for (int p = 0; p < op; ++p) order[fill[pair_a_[p]]++] = p;
#pragma omp parallel for schedule(static) if (np > kParallelMin)
        for (int p = 0; p < np; ++p) {
            const int a = na[p], b = nb[p];
            for (int q = start[a]; q < start[a + 1]; ++q) {
                const int o = order[q];
                if (pair_b_[o] == b) {
                    for (int s = 0; s < kHistPerPair; ++s)
                        nh[kHistPerPair * static_cast<size_t>(p) + s] = hist_[kHistPerPair * static_cast<size_t>(o) + s];
                    non[p] = pair_hist_on_[o];
                    break;
                }
            }
        }
    }
    pair_a_.swap(na);
    pair_b_.swap(nb);
    hist_.swap(nh);
    pair_hist_on_.swap(non);
    pair_law_.resize(np);
    for (int p = 0; p < np; ++p) pair_law_[p] = law_of(pair_a_[p], pair_b_[p]);
    set_pair_nodes();
    // The edges that can load before the next detection, each with the laws it can meet: each edge of a pair's
    // triangle within the buffer of its partner, with the pair's law (each point of a triangle moves at most
    // travel_ <= buffer_ / 2 until then, so an edge farther than the buffer from the partner cannot enter it, nor
    // the partner's faces cross it). Law l is bit min(l, 63).
    std::vector<std::uint64_t>& now = near_law_new_;
    now.assign(3 * static_cast<std::size_t>(n_tri_), 0);
    for (int p = 0; p < np; ++p) {
        const int ab[2] = {pair_a_[p], pair_b_[p]};
        const std::uint64_t bit = std::uint64_t{1} << std::min(pair_law_[p], 63);
        double T[2][6];
        gather(x, tri_ + 3 * ab[0], T[0]);
        gather(x, tri_ + 3 * ab[1], T[1]);
        for (int i = 0; i < 2; ++i)
            for (int e = 0; e < 3; ++e) {
                std::uint64_t& m = now[3 * static_cast<std::size_t>(ab[i]) + e];
                if (!((continuum_faces_[ab[i]] >> e) & 1) || (m & bit)) continue;
                const int e1 = (e + 1) % 3;
                if (segment_near_triangle(T[i] + 2 * e, T[i] + 2 * e1, T[1 - i], buffer_)) m |= bit;
            }
    }
    for (std::size_t i = 0; i < now.size() && !candidates_grew_; ++i) candidates_grew_ = (now[i] & ~near_law_[i]) != 0;
    near_law_.swap(now);
    pair_f_.resize(12 * static_cast<size_t>(np));
    pair_e_.resize(4 * static_cast<size_t>(np));
    pair_on_.resize(np);
    block_cost_.assign((np + kPairBlock - 1) / kPairBlock, 1);  // (equal shares of blocks until the first step)
    box_.resize(8 * static_cast<size_t>(n_tri_));
    geom_.resize(n_tri_);
    dirty_ = false;
    travel_ = 0.0;
    ++stats_.detections;
    stats_.candidate_pairs = np;
    stats_.time_detection += omp_get_wtime() - t0;
}

void ContactSystem::set_pair_nodes() {
    const std::size_t np = pair_a_.size();
    pair_nodes_.resize(6 * np);
    for (std::size_t p = 0; p < np; ++p)
        for (int k = 0; k < 3; ++k) {
            pair_nodes_[6 * p + k] = tri_[3 * pair_a_[p] + k];
            pair_nodes_[6 * p + 3 + k] = tri_[3 * pair_b_[p] + k];
        }
    own_threads_ = 0;
}

// [MA98]: a pair can only appear once two triangles have moved towards each other by the buffer; each moved at most
// the accumulated dt max|v|. Anticipate this step's motion so the list is valid until the next call.
void ContactSystem::detect_if_due(const double* x, double dt, double vmax) {
    if (faces_dirty_) update_faces();
    if (dirty_ || 2.0 * (travel_ + dt * vmax) > buffer_) detect(x);
}

bool ContactSystem::prepare(const double* x, const double* v, double dt, double v2max) {
    candidates_grew_ = false;
    detect_if_due(x, dt, std::sqrt(v2max >= 0.0 ? v2max : largest_speed2(v, n_nodes_)));
    return candidates_grew_;
}

void ContactSystem::step(const double* x, const double* v, double dt, double* f, double v2max) {
    const double vmax = std::sqrt(v2max >= 0.0 ? v2max : largest_speed2(v, n_nodes_));
    detect_if_due(x, dt, vmax);
    travel_ += dt * vmax;

    const double t0 = omp_get_wtime();
    const int n_items = static_cast<int>(items_.size());
    const int np = static_cast<int>(pair_a_.size());
    // (the last step's dashpot work on v^{n+1/2}: finish_step)
    damping_ += damping_next_;
    damping_next_ = 0.0;
    const bool dashpots = beta_ > 0.0 || inelastic_;  // (forces whose work finish_step books half of)
    if (dashpots && pair_fd_.size() < 12 * static_cast<std::size_t>(np)) pair_fd_.resize(12 * static_cast<std::size_t>(np));
    dashpot_dt_ = dashpots ? dt : 0.0;
    const bool want_energy = opt_.compute_energy;
    // The kernel's parameters depend on the law, dt and the dashpot only: resolved once per law, not per pair.
    const bool altitudes = resolve_params(dt, law_prm_);  // some law's potential weighs by the altitudes
    // Bounding boxes and pair-kernel geometry of the capable triangles, once per step: most candidate pairs are
    // apart and are rejected from two contiguous boxes, and a triangle met by several overlapping pairs has its
    // area coordinates and altitudes computed once. One parallel region for this loop and the pair loop (a fork
    // and join less; the capable triangles, about half as many as the pairs, were below kParallelMin on their own
    // and ran serially in the wall cases).
    const int n_blocks = (np + kPairBlock - 1) / kPairBlock;
    double t1 = t0;
    double en = 0.0, et = 0.0, ed = 0.0, ec = 0.0;  // the sums of the blocks' sums, in block order
    int active = 0;
    if (scratch_.size() < static_cast<std::size_t>(omp_get_max_threads())) scratch_.resize(omp_get_max_threads());
    const bool parallel = np > kParallelMin || n_items > kParallelMin;
    // The scatter's node masks for the team about to run (made again after a detection or new owners).
    const int team = parallel ? omp_get_max_threads() : 1;
    if (own_threads_ != team) {
        const unsigned char* own =
            owner_parts_ == team && owner_.size() == static_cast<std::size_t>(n_nodes_) ? owner_.data() : nullptr;
        pair_mask_.assign(static_cast<std::size_t>(team) * np, 0);
        for (int p = 0; p < np; ++p)
            for (int s = 0; s < 6; ++s) {
                const int k = pair_nodes_[6 * static_cast<size_t>(p) + s];
                const int t = thread_of(k, team, own, n_nodes_);
                pair_mask_[static_cast<std::size_t>(t) * np + p] |= static_cast<unsigned char>(1u << s);
            }
        own_threads_ = team;
    }
    // Each thread's share of the pair blocks: a contiguous run of about equal cost in the last step. Contiguous and
    // nearly the same every step, a pair's friction history, forces and triangles stay in the cache of the core that
    // evaluated it the step before, and in the list's order (NBS cells) a thread's pairs are mostly on the nodes its
    // node loop integrates and its scatter adds (93 % of its pairs' nodes in the wall of k25_N100_quick.toml on 2
    // threads). A dynamic schedule balanced the blocks but sent each to either core; the contiguous shares ran
    // faster. Which thread evaluates a pair does not change its result.
    if (block_cost_.size() != static_cast<std::size_t>(n_blocks)) block_cost_.assign(n_blocks, 1);
    cut_shares(block_cost_, team, block_share_);
    list_idx_.resize(static_cast<std::size_t>(team) * np);
    list_cnt_.resize(static_cast<std::size_t>(team) * n_blocks);
    block_e_.resize(4 * static_cast<std::size_t>(n_blocks));
    block_active_.resize(n_blocks);
#pragma omp parallel if (parallel)
    {
#pragma omp for schedule(static)
        for (int i = 0; i < n_items; ++i) {
            double T[6];
            gather(x, tri_ + 3 * items_[i], T);
            double* bx = &box_[8 * static_cast<size_t>(items_[i])];
            bx[0] = std::min(T[0], std::min(T[2], T[4]));
            bx[1] = std::max(T[0], std::max(T[2], T[4]));
            bx[2] = std::min(T[1], std::min(T[3], T[5]));
            bx[3] = std::max(T[1], std::max(T[3], T[5]));
            // the box of the face edges' end points (empty, +inf..-inf, without faces)
            const unsigned faces = faces_[items_[i]];
            bx[4] = bx[6] = std::numeric_limits<double>::infinity();
            bx[5] = bx[7] = -std::numeric_limits<double>::infinity();
            for (int k = 0; k < 3; ++k)
                if (faces & (1u << k | 1u << (k + 2) % 3)) {  // vertex k ends edge k and edge k - 1
                    bx[4] = std::min(bx[4], T[2 * k]), bx[5] = std::max(bx[5], T[2 * k]);
                    bx[6] = std::min(bx[6], T[2 * k + 1]), bx[7] = std::max(bx[7], T[2 * k + 1]);
                }
            triangle_geometry(T, geom_[items_[i]], altitudes);
            geom_[items_[i]].faces = static_cast<int>(faces);
        }
        // A pair without forces that has energy to book in the sums below (released friction springs, or the
        // energy of an overlap whose load the faces of neighbouring pairs carry): pair_on_[p] = 2.
        auto book = [&](int p, double energy_normal, double released) {
            if (released == 0.0 && energy_normal == 0.0) return;
            pair_on_[p] = 2;
            double* pe = &pair_e_[4 * static_cast<size_t>(p)];
            pe[0] = energy_normal;
            pe[1] = pe[3] = 0.0;
            pe[2] = released;
        };
        // One pair, first stage: the boxes, then the separating-axis test and its edges queued in the thread's batch
        // (pending), or the history it forgets; pair_on_[p] says what the scatter and sums below take.
        auto begin_pair = [&](int p, PairBatch& batch, std::vector<int>& pending) {
            const int a = pair_a_[p], b = pair_b_[p];
            pair_on_[p] = 0;
            const double* ba = &box_[8 * static_cast<size_t>(a)];
            const double* bb = &box_[8 * static_cast<size_t>(b)];
            // Boxes touching along a side count as apart: the triangles overlap in no area, every edge integral is 0.
            auto disjoint = [](const double* P, const double* Q) {
                return P[1] <= Q[0] || Q[1] <= P[0] || P[3] <= Q[2] || Q[3] <= P[2];
            };
            // No load unless some face of one can enter the other: A's faces' box meets B's box or the reverse.
            // Disjoint triangle boxes also mean no overlap energy; only that is wanted of other faceless overlaps.
            const bool boxes_apart = disjoint(ba, bb);
            if (boxes_apart || (!want_energy && disjoint(ba + 4, bb) && disjoint(bb + 4, ba))) {
                if (!pair_hist_on_[p]) return;  // nothing to forget (the common case: apart since detection)
                pair_hist_on_[p] = 0;
                const double released = forget(&hist_[kHistPerPair * static_cast<size_t>(p)]);
                book(p, 0.0, released);
                return;
            }
            PairResult r;
            if (batch.begin(geom_[a], geom_[b], law_prm_[pair_law_[p]], want_energy,
                            &hist_[kHistPerPair * static_cast<size_t>(p)], r, pair_hist_on_[p])) {
                pending.push_back(p);
                // (its nodes' velocities and its friction history, which the loads read after the batch's
                // integrals, asked for now)
                for (int k = 0; k < 3; ++k)
                    __builtin_prefetch(&v[2 * tri_[3 * a + k]]), __builtin_prefetch(&v[2 * tri_[3 * b + k]]);
                prefetch_bytes(&hist_[kHistPerPair * static_cast<size_t>(p)], kHistPerPair * sizeof(double), true);
                return;
            }
            // apart, or no face on either: the history is all zero now; released springs, or the energy of an
            // overlap whose load the faces of neighbouring pairs carry, to book
            pair_hist_on_[p] = 0;
            book(p, r.energy_normal, r.dissipation);
        };
        // Second stage, after the batch's edge integrals: the pending pair's loads (pair_contact's third stage).
        auto end_pair = [&](int p, PairBatch& batch) {
            const int a = pair_a_[p], b = pair_b_[p];
            double va[6], vb[6];
            gather(v, tri_ + 3 * a, va);
            gather(v, tri_ + 3 * b, vb);
            PairResult r;
            // (the forces straight into the pair's slots, read below only when it is on; the history is all zero
            // when it is not)
            const bool on = batch.end(geom_[a], geom_[b], va, vb, law_prm_[pair_law_[p]], want_energy,
                                      &hist_[kHistPerPair * static_cast<size_t>(p)], r, pair_hist_on_[p],
                                      &pair_f_[12 * static_cast<size_t>(p)],
                                      dashpots ? &pair_fd_[12 * static_cast<size_t>(p)] : nullptr);
            pair_hist_on_[p] = static_cast<char>(r.held);
            if (on) {
                pair_on_[p] = 1;
                double* pe = &pair_e_[4 * static_cast<size_t>(p)];
                pe[0] = r.energy_normal;
                pe[1] = r.energy_tangential;
                pe[2] = r.dissipation;
                pe[3] = r.damping;
            } else {
                book(p, r.energy_normal, r.dissipation);
            }
        };
        // Blocks of kPairBlock pairs, each evaluated by one thread (its share, above): the first stage of every pair
        // in the block, the edge integrals of its pending pairs side by side (PairBatch), their loads; then, on the
        // same thread, the block's energy sums in pair order and each thread's scatter list of the block's loaded
        // pairs with some of its nodes. The scatter below walks its own lists; the energies are the blocks' sums
        // added in block order: both independent of the number of threads.
        PairScratch& scratch = scratch_[omp_get_thread_num()];
        // (a smaller team than asked for: equal shares of blocks)
        const int nt = omp_get_num_threads(), tn = omp_get_thread_num();
        // each pair's nodes' threads: the masks when they are for this team, else looked up node by node
        const bool masks = own_threads_ == nt;
        const unsigned char* own_map =
            owner_parts_ == nt && owner_.size() == static_cast<std::size_t>(n_nodes_) ? owner_.data() : nullptr;
        scratch.listed.resize(nt);
        const int b0 = nt == team ? block_share_[tn] : static_cast<int>(static_cast<long long>(n_blocks) * tn / nt);
        const int b1 = nt == team ? block_share_[tn + 1] : static_cast<int>(static_cast<long long>(n_blocks) * (tn + 1) / nt);
        for (int blk = b0; blk < b1; ++blk) {
            const int p0 = blk * kPairBlock, p1 = std::min(np, p0 + kPairBlock);
            int queued = 0;
            for (int c0 = p0; c0 < p1; c0 += kBatchPairs) {
                scratch.batch.clear(kBatchPairs);
                scratch.pending.clear();
                for (int p = c0; p < std::min(p1, c0 + kBatchPairs); ++p) {
                    // (the boxes and geometry of a pair a few ahead asked for now: indexed by triangle, they are
                    // read in no order the hardware prefetcher follows, and the test waits on them)
                    if (p + kPrefetchPairs < np) {
                        const int a = pair_a_[p + kPrefetchPairs], b = pair_b_[p + kPrefetchPairs];
                        __builtin_prefetch(&box_[8 * static_cast<size_t>(a)]);
                        __builtin_prefetch(&box_[8 * static_cast<size_t>(b)]);
                        prefetch_bytes(&geom_[a], sizeof(TriangleGeometry));
                        prefetch_bytes(&geom_[b], sizeof(TriangleGeometry));
                    }
                    begin_pair(p, scratch.batch, scratch.pending);
                }
                scratch.batch.integrate();
                queued += static_cast<int>(scratch.pending.size());
                for (int p : scratch.pending) end_pair(p, scratch.batch);
            }
            double be[4] = {0.0, 0.0, 0.0, 0.0};
            int loaded = 0;
            if (nt == 1) {  // (one thread: its list is every loaded pair)
                int* list = &list_idx_[p0];
                for (int p = p0; p < p1; ++p) {
                    const char on = pair_on_[p];
                    if (!on) continue;
                    const double* pe = &pair_e_[4 * static_cast<size_t>(p)];
                    if (on == 2) {  // energy to book, no forces
                        be[0] += pe[0], be[2] += pe[2];
                        continue;
                    }
                    be[0] += pe[0], be[1] += pe[1], be[2] += pe[2], be[3] += pe[3];
                    list[loaded++] = p;
                }
                list_cnt_[blk] = loaded;
            } else {
                std::fill(scratch.listed.begin(), scratch.listed.end(), 0);
                for (int p = p0; p < p1; ++p) {
                    const char on = pair_on_[p];
                    if (!on) continue;
                    const double* pe = &pair_e_[4 * static_cast<size_t>(p)];
                    if (on == 2) {
                        be[0] += pe[0], be[2] += pe[2];
                        continue;
                    }
                    ++loaded;
                    be[0] += pe[0], be[1] += pe[1], be[2] += pe[2], be[3] += pe[3];
                    for (int t = 0; t < nt; ++t) {
                        bool any = false;
                        if (masks) any = pair_mask_[static_cast<std::size_t>(t) * np + p] != 0;
                        else
                            for (int s = 0; s < 6 && !any; ++s)
                                any = thread_of(pair_nodes_[6 * static_cast<size_t>(p) + s], nt, own_map, n_nodes_) == t;
                        if (any) list_idx_[static_cast<std::size_t>(t) * np + p0 + scratch.listed[t]++] = p;
                    }
                }
                for (int t = 0; t < nt; ++t) list_cnt_[static_cast<std::size_t>(t) * n_blocks + blk] = scratch.listed[t];
            }
            for (int k = 0; k < 4; ++k) block_e_[4 * static_cast<size_t>(blk) + k] = be[k];
            block_active_[blk] = loaded;
            block_cost_[blk] = (p1 - p0) + kQueuedCost * queued;
        }
#pragma omp barrier
        // Scatter in pair order (the blocks in order, each block's list in order), each thread adding the forces of
        // the nodes it owns (set_node_owner: the nodes it integrates next): every node's sum is that of a serial walk
        // over every pair, the same bits for any thread count. A thread reads only the pairs on its lists: its own
        // blocks' loaded pairs on its nodes, and the few of the other threads' blocks that reach its nodes.
        const int me = tn;
        if (me == 0) t1 = omp_get_wtime();
        const unsigned char* mask = masks ? &pair_mask_[static_cast<std::size_t>(me) * np] : nullptr;
        const int* list = &list_idx_[static_cast<std::size_t>(me) * np];
        const int* count = &list_cnt_[static_cast<std::size_t>(me) * n_blocks];
        for (int blk = 0; blk < n_blocks; ++blk) {
            for (int i = 0; i < count[blk]; ++i) {
                const int p = list[blk * kPairBlock + i];
                const int* nd = &pair_nodes_[6 * static_cast<size_t>(p)];
                unsigned m = 0;
                if (mask) m = mask[p];
                else
                    for (int s = 0; s < 6; ++s) m |= thread_of(nd[s], nt, own_map, n_nodes_) == me ? 1u << s : 0u;
                const double* pf = &pair_f_[12 * static_cast<size_t>(p)];
                for (int k = 0; k < 3; ++k) {
                    if ((m >> k) & 1u) f[2 * nd[k]] += pf[2 * k], f[2 * nd[k] + 1] += pf[2 * k + 1];
                    if ((m >> (3 + k)) & 1u)
                        f[2 * nd[3 + k]] += pf[6 + 2 * k], f[2 * nd[3 + k] + 1] += pf[6 + 2 * k + 1];
                }
            }
        }
    }  // omp parallel
    for (int blk = 0; blk < n_blocks; ++blk) {
        const double* be = &block_e_[4 * static_cast<size_t>(blk)];
        en += be[0], et += be[1], ed += be[2], ec += be[3];
        active += block_active_[blk];
    }
    energy_normal_ = en;
    energy_tangential_ = et;
    energy_current_ = want_energy;
    dissipation_ += ed;
    damping_ += 0.5 * ec;  // the half on v^{n-1/2}; finish_step works out the other
    stats_.active_pairs = active;
    stats_.pair_evaluations += np;
    const double t2 = omp_get_wtime();
    stats_.time_forces += t2 - t0;
    stats_.time_scatter += t2 - t1;
}

void ContactSystem::finish_step(const double* v) {
    if (dashpot_dt_ == 0.0) return;
    // -dt / 2 f_d . v^{n+1/2} over the loaded pairs: per block in pair order, then the blocks in order (the same
    // bits for any thread count).
    const int np = static_cast<int>(pair_a_.size());
    const int n_blocks = (np + kPairBlock - 1) / kPairBlock;
    block_fd_.resize(n_blocks);
#pragma omp parallel for schedule(static) if (np > kParallelMin)
    for (int blk = 0; blk < n_blocks; ++blk) {
        double sum = 0.0;
        const int p1 = std::min(np, (blk + 1) * kPairBlock);
        for (int p = blk * kPairBlock; p < p1; ++p) {
            if (pair_on_[p] != 1) continue;
            const int* nd = &pair_nodes_[6 * static_cast<size_t>(p)];
            const double* fd = &pair_fd_[12 * static_cast<size_t>(p)];
            for (int s = 0; s < 6; ++s) sum += fd[2 * s] * v[2 * nd[s]] + fd[2 * s + 1] * v[2 * nd[s] + 1];
        }
        block_fd_[blk] = sum;
    }
    double power = 0.0;
    for (int blk = 0; blk < n_blocks; ++blk) power += block_fd_[blk];
    damping_next_ = -0.5 * dashpot_dt_ * power;
    dashpot_dt_ = 0.0;
}

bool ContactSystem::resolve_params(double dt, std::vector<PairParams>& prm_of) const {
    prm_of.resize(laws_.size());
    bool altitudes = false;  // some law's potential weighs by the altitudes (TriangleGeometry::h)
    for (std::size_t l = 0; l < laws_.size(); ++l) {
        const ResolvedLaw& L = laws_[l];
        PairParams& prm = prm_of[l];
        prm = PairParams{};
        prm.thickness = thickness_;
        prm.distance_potential = L.normal_is_stiffness;
        altitudes = altitudes || L.normal_is_stiffness;
        prm.c = L.normal_is_stiffness ? 0.5 * L.normal : L.normal;
        // A penalty p (Pa) becomes a pressure/overlap slope 3 p (1/H_a + 1/H_b) (Pa/m) ([MA00] phi = 3 min L_k):
        // p_t for friction, p_n for the dashpots; pair_contact works it out once it knows the pair overlaps.
        if (L.tangential_is_stiffness) prm.k_s = L.tangential;
        else prm.p_t = L.tangential;
        prm.mu = L.mu;
        prm.dt = dt;
        prm.inv_e2 = 1.0 / (L.restitution * L.restitution);
        if (beta_ > 0.0) {
            prm.beta = beta_;
            if (L.normal_is_stiffness) prm.k_n_area = L.normal;
            else prm.p_n = L.normal;
        }
    }
    return altitudes;
}

}  // namespace fdem::contact
