// fdem/body_step.cpp: see body_step.hpp.
#include "fdem/body_step.hpp"

#include <Eigen/Dense>
#include <map>

namespace fdem {

RigidBodies whole_run_bodies(const CaseSpec& spec, const Model& model) {
    RigidBodies rb;
    const int nn = model.n_nodes();
    if (spec.stages.empty()) return rb;
    // Per DOF, the block owning it as the stages go: the group of a body block, kHeld for a prescribed motion
    // (fixed, velocity, protocol), or "" for anything else.
    static const std::string kHeld = "\n";  // (not a group name)
    std::vector<std::string> owner(2 * static_cast<std::size_t>(nn));
    std::vector<std::string> always(nn);  // what a node was at every stage so far ("" free or mixed)
    for (std::size_t s = 0; s < spec.stages.size(); ++s) {
        for (const SupportSpec& sp : spec.stages[s].supports) {
            const auto& grp = model.group(sp.group);
            for (int c = 0; c < 2; ++c) {
                const DofMode m = sp.mode[c];
                if (m == DofMode::inherit) continue;
                const bool held = m == DofMode::fixed || m == DofMode::velocity || m == DofMode::protocol;
                for (int k : grp.nodes) owner[2 * k + c] = m == DofMode::body ? sp.group : held ? kHeld : std::string();
            }
        }
        for (int k = 0; k < nn; ++k) {
            const std::string& g = owner[2 * k];
            const std::string now = (!g.empty() && owner[2 * k + 1] == g) ? g : std::string();
            if (s == 0) always[k] = now;
            else if (always[k] != now) always[k].clear();
        }
    }
    rb.held.assign(nn, 0);
    bool any_held = false;
    for (int k = 0; k < nn; ++k)
        if (always[k] == kHeld) rb.held[k] = 1, always[k].clear(), any_held = true;
    // A body counts only when every node of its group stayed in it.
    std::map<std::string, int> id;
    for (int k = 0; k < nn; ++k)
        if (!always[k].empty()) id.emplace(always[k], 0);
    rb.node_body.assign(nn, -1);
    for (auto& [name, b] : id) {
        const auto& nodes = model.group(name).nodes;
        bool whole = !nodes.empty();
        for (int k : nodes) whole = whole && always[k] == name;
        if (!whole) continue;
        b = static_cast<int>(rb.nodes.size());
        rb.nodes.push_back(nodes);
        rb.group.push_back(name);
        for (int k : nodes) rb.node_body[k] = b;
    }
    if (rb.nodes.empty() && !any_held) return RigidBodies{};
    rb.tri.assign(model.n_triangles(), 0);
    for (int e = 0; e < model.n_triangles(); ++e) {
        const int* n = model.tris[e].n;
        const int b = rb.node_body[n[0]];
        rb.tri[e] = (b >= 0 && rb.node_body[n[1]] == b && rb.node_body[n[2]] == b) ||
                    (rb.held[n[0]] && rb.held[n[1]] && rb.held[n[2]]);
    }
    return rb;
}

double body_omega2(const std::vector<int>& nodes, const double* x, const double* mass, const double* k) {
    double M = 0, mx = 0, my = 0;
    for (int j : nodes) M += mass[j], mx += mass[j] * x[2 * j], my += mass[j] * x[2 * j + 1];
    if (!(M > 0)) return 0.0;
    const double cx = mx / M, cy = my / M;
    double I = 0;
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    for (int j : nodes) {
        const double rx = x[2 * j] - cx, ry = x[2 * j + 1] - cy;
        I += mass[j] * (rx * rx + ry * ry);
        const double kk = k[j];
        A(0, 0) += kk, A(1, 1) += kk;
        A(0, 2) -= kk * ry, A(1, 2) += kk * rx;
        A(2, 2) += kk * (rx * rx + ry * ry);
    }
    A(2, 0) = A(0, 2), A(2, 1) = A(1, 2);
    if (!(I > 0)) return (A(0, 0) + A(1, 1)) / M;  // (a single node: translation only)
    const Eigen::Vector3d d(1.0 / std::sqrt(M), 1.0 / std::sqrt(M), 1.0 / std::sqrt(I));
    const Eigen::Matrix3d S = d.asDiagonal() * A * d.asDiagonal();
    return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(S, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
}

}  // namespace fdem
