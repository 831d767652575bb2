// mesh/roughness.cpp: see roughness.hpp.
#include "mesh/roughness.hpp"

#include "mesh/quality.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

namespace fdem::mesh {

namespace {

constexpr int kModes = 4;

// SplitMix64 (Steele, Lea & Flood 2014): a well-mixed 64-bit hash of a counter.
std::uint64_t mix(std::uint64_t z) {
    z += 0x9E3779B97F4A7C15ull;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

// A uniform number in [0, 1) from (seed, body, k, which).
double uniform(std::uint64_t seed, int body, int k, int which) {
    std::uint64_t h = mix(seed);
    h = mix(h ^ static_cast<std::uint64_t>(body));
    h = mix(h ^ static_cast<std::uint64_t>(4 * k + which));
    return static_cast<double>(h >> 11) * 0x1.0p-53;
}

std::string num(double v) {
    std::ostringstream s;
    s.precision(4);
    s << v;
    return s.str();
}

}  // namespace

RoughnessStats roughen_dry_joints(Topology& topo, double amplitude, double wavelength, std::uint64_t seed) {
    RoughnessStats stats;
    if (amplitude == 0) return stats;
    if (!(amplitude > 0) || !std::isfinite(amplitude))
        throw MeshError("joint roughness: the amplitude must be a finite length >= 0 (m), got " + num(amplitude));
    if (!(wavelength > 0) || !std::isfinite(wavelength))
        throw MeshError("joint roughness: the wavelength must be a finite length > 0 (m), got " + num(wavelength));
    Mesh& m = topo.mesh;
    const int nn = m.n_nodes(), nt = m.n_triangles();

    // The body a node copy belongs to: the smallest body among its triangles. An input node with a copy that several
    // bodies share (a tied interface, e.g. a beam tied to the top course) is not moved at all: its copies in one body
    // could otherwise have different owners and part.
    std::vector<int> owner(nn, std::numeric_limits<int>::max());
    std::vector<char> shared(nn, 0);
    for (int t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) {
            int& o = owner[m.tri[3 * t + k]];
            if (o != std::numeric_limits<int>::max() && o != m.tri_body[t]) shared[m.tri[3 * t + k]] = 1;
            o = std::min(o, m.tri_body[t]);
        }
    std::set<int> shared_origin;
    for (int c = 0; c < nn; ++c)
        if (shared[c]) shared_origin.insert(topo.node_origin[c]);
    auto key = [&](int c) { return std::make_pair(owner[c], topo.node_origin[c]); };

    std::set<std::pair<int, int>> bonded;
    for (const auto& ce : topo.cohesive)
        if (ce.kind == EdgeClass::bonded)
            for (int c : ce.n) bonded.insert(key(c));

    // Sum of the outward normals (times length) of each body's dry edges at each face point.
    std::map<std::pair<int, int>, std::array<double, 2>> normal;
    for (const auto& d : topo.dry_joints) {
        const double sx = m.xy[2 * d.n[1]] - m.xy[2 * d.n[0]], sy = m.xy[2 * d.n[1] + 1] - m.xy[2 * d.n[0] + 1];
        // a0 -> a1 runs counter-clockwise around tri_a: (sy, -sx) points out of side A, into side B.
        for (int side = 0; side < 2; ++side) {
            const double nx = side == 0 ? sy : -sy, ny = side == 0 ? -sx : sx;
            for (int j = 0; j < 2; ++j) {
                auto& v = normal[key(d.n[2 * side + j])];
                v[0] += nx, v[1] += ny;
            }
        }
    }

    std::map<std::pair<int, int>, int> first_copy;
    for (int c = 0; c < nn; ++c) first_copy.emplace(key(c), c);

    // The offset vector of each face point, from its body's field at the reference position.
    std::map<std::pair<int, int>, std::array<double, 2>> move;
    std::map<int, std::array<double, 3 * kModes>> field;  // body -> (qx, qy, phase) per mode
    const double q = 2 * M_PI / wavelength;
    double sum = 0;
    for (const auto& [k, v] : normal) {
        if (bonded.count(k) || shared_origin.count(k.second)) continue;
        const double len = std::hypot(v[0], v[1]);
        if (!(len > 0)) continue;
        auto it = field.find(k.first);
        if (it == field.end()) {
            std::array<double, 3 * kModes> f{};
            for (int i = 0; i < kModes; ++i) {
                const double angle = 2 * M_PI * uniform(seed, k.first, i, 0);
                f[3 * i] = q * std::cos(angle), f[3 * i + 1] = q * std::sin(angle);
                f[3 * i + 2] = 2 * M_PI * uniform(seed, k.first, i, 1);
            }
            it = field.emplace(k.first, f).first;
        }
        // Reference position: the input node's coordinates (every copy has them before the move).
        const int c0 = first_copy.at(k);
        const double X = m.xy[2 * c0], Y = m.xy[2 * c0 + 1];
        double s = 0;
        for (int i = 0; i < kModes; ++i) s += std::cos(it->second[3 * i] * X + it->second[3 * i + 1] * Y + it->second[3 * i + 2]);
        const double off = amplitude * 0.5 * (1 + s / kModes);
        move[k] = {-off * v[0] / len, -off * v[1] / len};
        sum += off;
        stats.largest = std::max(stats.largest, off);
        ++stats.points;
    }
    if (move.empty()) return stats;
    stats.mean = sum / stats.points;

    // Guard: no triangle at a moved point may have an altitude below 5 x amplitude.
    stats.smallest_altitude = std::numeric_limits<double>::infinity();
    double where[2] = {0, 0};
    for (int t = 0; t < nt; ++t) {
        const int* n = &m.tri[3 * t];
        bool touched = false;
        for (int k = 0; k < 3; ++k) touched = touched || move.count(key(n[k]));
        if (!touched) continue;
        const double* p = m.xy.data();
        const double h = triangle_quality(&p[2 * n[0]], &p[2 * n[1]], &p[2 * n[2]]).altitude;
        if (h < stats.smallest_altitude) {
            stats.smallest_altitude = h;
            where[0] = (p[2 * n[0]] + p[2 * n[1]] + p[2 * n[2]]) / 3, where[1] = (p[2 * n[0] + 1] + p[2 * n[1] + 1] + p[2 * n[2] + 1]) / 3;
        }
    }
    if (amplitude > 0.2 * stats.smallest_altitude)
        throw MeshError("joint roughness: the amplitude " + num(amplitude) + " m is more than a fifth of the smallest altitude (" +
                        num(stats.smallest_altitude) + " m) of a triangle at a dry joint, near (" + num(where[0]) + ", " +
                        num(where[1]) + ") m; expected an amplitude below " + num(0.2 * stats.smallest_altitude) +
                        " m or a coarser mesh there");

    for (int c = 0; c < nn; ++c) {
        auto it = move.find(key(c));
        if (it == move.end()) continue;
        m.xy[2 * c] += it->second[0];
        m.xy[2 * c + 1] += it->second[1];
    }
    return stats;
}

}  // namespace fdem::mesh
