// fdem/model.cpp: Mesh + CaseSpec -> Model (masses, reference data, incidence).
#include "fdem/model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <tuple>

#include <Eigen/Dense>

#include "fdem/common/errors.hpp"

namespace fdem {

const mesh::PhysicalGroup& Model::group(const std::string& name) const {
    const auto* g = mesh.find_group(name);
    if (!g) throw InputError("no group named '" + name + "' in the mesh");
    return *g;
}

double p_wave_speed(const Material& m, Plane plane) {
    // Plane stress: sqrt(E / (rho (1 - nu^2))); plane strain: sqrt(E (1 - nu) / (rho (1 + nu)(1 - 2 nu))).
    if (plane == Plane::stress) return std::sqrt(m.E / (m.density * (1 - m.nu * m.nu)));
    return std::sqrt(m.E * (1 - m.nu) / (m.density * (1 + m.nu) * (1 - 2 * m.nu)));
}

std::pair<std::vector<int>, std::vector<int>> reorder_for_locality(mesh::Mesh& m) {
    const int nn = m.n_nodes(), nt = m.n_triangles();
    double xmin = 1e300, ymin = 1e300, xmax = -1e300, ymax = -1e300;
    for (int k = 0; k < nn; ++k) {
        xmin = std::min(xmin, m.xy[2 * k]), xmax = std::max(xmax, m.xy[2 * k]);
        ymin = std::min(ymin, m.xy[2 * k + 1]), ymax = std::max(ymax, m.xy[2 * k + 1]);
    }
    const double span = std::max({xmax - xmin, ymax - ymin, 1e-300});
    auto spread = [](std::uint64_t v) {  // interleave the low 21 bits with zeros
        v &= 0x1fffff;
        v = (v | (v << 32)) & 0x1f00000000ffffULL;
        v = (v | (v << 16)) & 0x1f0000ff0000ffULL;
        v = (v | (v << 8)) & 0x100f00f00f00f00fULL;
        v = (v | (v << 4)) & 0x10c30c30c30c30c3ULL;
        v = (v | (v << 2)) & 0x1249249249249249ULL;
        return v;
    };
    std::vector<std::pair<std::uint64_t, int>> key(nt);
    for (int e = 0; e < nt; ++e) {
        double cx = 0, cy = 0;
        for (int k = 0; k < 3; ++k) cx += m.xy[2 * m.tri[3 * e + k]], cy += m.xy[2 * m.tri[3 * e + k] + 1];
        const auto qx = static_cast<std::uint64_t>((cx / 3 - xmin) / span * 2097151.0);
        const auto qy = static_cast<std::uint64_t>((cy / 3 - ymin) / span * 2097151.0);
        key[e] = {spread(qx) | (spread(qy) << 1), e};
    }
    std::sort(key.begin(), key.end());
    std::vector<int> tri_new(nt), node_new(nn, -1);
    int next = 0;
    for (int i = 0; i < nt; ++i) {
        const int e = key[i].second;
        tri_new[e] = i;
        for (int k = 0; k < 3; ++k)
            if (node_new[m.tri[3 * e + k]] < 0) node_new[m.tri[3 * e + k]] = next++;
    }
    for (int k = 0; k < nn; ++k)
        if (node_new[k] < 0) node_new[k] = next++;  // nodes of no triangle (rejected later)
    mesh::Mesh r;
    r.regions = m.regions;
    r.xy.resize(m.xy.size());
    for (int k = 0; k < nn; ++k) r.xy[2 * node_new[k]] = m.xy[2 * k], r.xy[2 * node_new[k] + 1] = m.xy[2 * k + 1];
    r.tri.resize(m.tri.size());
    r.tri_region.resize(nt);
    if (!m.tri_body.empty()) r.tri_body.resize(nt);
    for (int e = 0; e < nt; ++e) {
        const int ne = tri_new[e];
        for (int k = 0; k < 3; ++k) r.tri[3 * ne + k] = node_new[m.tri[3 * e + k]];
        r.tri_region[ne] = m.tri_region[e];
        if (!m.tri_body.empty()) r.tri_body[ne] = m.tri_body[e];
    }
    for (auto g : m.groups) {
        for (int& k : g.nodes) k = node_new[k];
        std::sort(g.nodes.begin(), g.nodes.end());
        for (auto& ed : g.edges) ed = {node_new[ed[0]], node_new[ed[1]]};
        for (int& t : g.triangles) t = tri_new[t];
        std::sort(g.triangles.begin(), g.triangles.end());
        r.groups.push_back(std::move(g));
    }
    m = std::move(r);
    return {std::move(node_new), std::move(tri_new)};
}

Model build_model(const CaseSpec& spec, mesh::Mesh mesh) {
    Model md;
    std::tie(md.node_new_of_old, md.tri_new_of_old) = reorder_for_locality(mesh);
    md.thickness = spec.thickness;
    md.plane = spec.plane;
    const int nn = mesh.n_nodes(), nt = mesh.n_triangles();

    // Material constants, indexed like spec.materials.
    for (const auto& m : spec.materials) {
        MaterialConst c;
        c.mu = m.E / (2 * (1 + m.nu));
        c.lambda = spec.plane == Plane::stress ? m.E * m.nu / (1 - m.nu * m.nu) : m.E * m.nu / ((1 + m.nu) * (1 - 2 * m.nu));
        md.mat.push_back(c);
    }
    std::vector<int> region_mat(mesh.regions.size(), -1);
    for (std::size_t r = 0; r < mesh.regions.size(); ++r) {
        auto it = spec.region_material.find(mesh.regions[r]);
        if (it == spec.region_material.end())
            throw InputError(spec.file + ": key 'regions." + mesh.regions[r] + "': missing; every region needs a material");
        region_mat[r] = spec.material_index(it->second);
    }

    md.X = mesh.xy;
    md.x = mesh.xy;
    md.v.assign(2 * nn, 0.0);
    md.mass.assign(nn, 0.0);
    md.tris.resize(nt);
    md.tri_material.resize(nt);
    md.tri_altitude.resize(nt);
    for (int e = 0; e < nt; ++e) {
        const int* n = &mesh.tri[3 * e];
        const double* p = mesh.xy.data();
        const double d00 = p[2 * n[1]] - p[2 * n[0]], d10 = p[2 * n[1] + 1] - p[2 * n[0] + 1];
        const double d01 = p[2 * n[2]] - p[2 * n[0]], d11 = p[2 * n[2] + 1] - p[2 * n[0] + 1];
        const double det = d00 * d11 - d01 * d10;  // 2 A0
        const int r = mesh.tri_region[e];
        if (!(det > 0))
            throw mesh::MeshError("triangle " + std::to_string(e) + " in region '" + mesh.regions[r] +
                                  "' has a non-positive reference area");
        const int mi = region_mat[r];
        const Material& mat = spec.materials[mi];
        TriangleRef& t = md.tris[e];
        t.n[0] = n[0], t.n[1] = n[1], t.n[2] = n[2];
        t.mat = mi;
        t.Dinv[0] = d11 / det, t.Dinv[1] = -d01 / det, t.Dinv[2] = -d10 / det, t.Dinv[3] = d00 / det;
        const double A0 = 0.5 * det;
        t.A0t = A0 * spec.thickness;
        // Smallest altitude = 2 A0 / longest edge.
        const double l0 = std::hypot(d00, d10), l1 = std::hypot(d01, d11), l2 = std::hypot(d01 - d00, d11 - d10);
        const double h = det / std::max({l0, l1, l2});
        md.tri_altitude[e] = h;
        // [M04]: eta = xi 2 h sqrt(E rho), xi = 1 critical.
        t.eta = mat.viscous_damping * 2 * h * std::sqrt(mat.E * mat.density * spec.mass_scale);  // inertial density
        md.tri_material[e] = mi;
        const double m3 = mat.density * t.A0t / 3.0;  // lumped mass, a third of the triangle's
        for (int k = 0; k < 3; ++k) md.mass[n[k]] += m3;
    }
    md.inv_mass.resize(nn);
    md.grav_mass = md.mass;
    for (int k = 0; k < nn; ++k) {
        if (!(md.mass[k] > 0)) throw mesh::MeshError("node " + std::to_string(k) + " belongs to no triangle");
        md.mass[k] *= spec.mass_scale;
        md.inv_mass[k] = 1.0 / md.mass[k];
    }
    // Incidence CSR in increasing (triangle, local) order.
    md.inc_ptr.assign(nn + 1, 0);
    for (int e = 0; e < nt; ++e)
        for (int k = 0; k < 3; ++k) ++md.inc_ptr[md.tris[e].n[k] + 1];
    for (int k = 0; k < nn; ++k) md.inc_ptr[k + 1] += md.inc_ptr[k];
    md.inc_idx.resize(3 * nt);
    std::vector<int> fill(md.inc_ptr.begin(), md.inc_ptr.end() - 1);
    for (int e = 0; e < nt; ++e)
        for (int k = 0; k < 3; ++k) md.inc_idx[fill[md.tris[e].n[k]]++] = 3 * e + k;
    md.mesh = std::move(mesh);
    return md;
}

Model build_model(const CaseSpec& spec, mesh::Topology topo) {
    Model md = build_model(spec, std::move(topo.mesh));
    for (auto* list : {&topo.cohesive, &topo.dry_joints})
        for (auto& c : *list) {
            for (int& n : c.n) n = md.node_new_of_old[n];
            if (c.tri_a >= 0) c.tri_a = md.tri_new_of_old[c.tri_a];
            if (c.tri_b >= 0) c.tri_b = md.tri_new_of_old[c.tri_b];
        }
    for (int& t : topo.contact_capable) t = md.tri_new_of_old[t];
    std::sort(topo.contact_capable.begin(), topo.contact_capable.end());
    md.cohesive = std::move(topo.cohesive);
    md.dry_joints = std::move(topo.dry_joints);
    md.contact_capable = std::move(topo.contact_capable);
    md.node_vertex.resize(topo.node_origin.size());
    for (std::size_t k = 0; k < topo.node_origin.size(); ++k) md.node_vertex[md.node_new_of_old[k]] = topo.node_origin[k];
    md.has_topology = true;
    return md;
}

namespace {

// B B^T of the constant-strain triangle (Voigt order xx, yy, 2xy) and its plane elasticity matrix D.
void triangle_gram(const double* p, const int* n, Eigen::Matrix3d& G) {
    const double x[3] = {p[2 * n[0]], p[2 * n[1]], p[2 * n[2]]}, y[3] = {p[2 * n[0] + 1], p[2 * n[1] + 1], p[2 * n[2] + 1]};
    const double det = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);  // 2 A
    double bb = 0, cc = 0, bc = 0;  // sums over the nodes of dN/dx^2, dN/dy^2, dN/dx dN/dy
    for (int i = 0; i < 3; ++i) {
        const int j = (i + 1) % 3, k = (i + 2) % 3;
        const double b = (y[j] - y[k]) / det, c = (x[k] - x[j]) / det;
        bb += b * b, cc += c * c, bc += b * c;
    }
    G << bb, 0, bc, 0, cc, bc, bc, bc, bb + cc;
}

Eigen::Matrix3d plane_elasticity(const Material& m, Plane plane) {
    double l, mu;  // plane Lame constants: D = [[l + 2 mu, l, 0], [l, l + 2 mu, 0], [0, 0, mu]]
    mu = m.E / (2 * (1 + m.nu));
    l = plane == Plane::stress ? m.E * m.nu / (1 - m.nu * m.nu) : m.E * m.nu / ((1 + m.nu) * (1 - 2 * m.nu));
    Eigen::Matrix3d D;
    D << l + 2 * mu, l, 0, l, l + 2 * mu, 0, 0, 0, mu;
    return D;
}

}  // namespace

double triangle_omega2(const double* p, const int* n, const Material& m, Plane plane, double mass_scale) {
    // Largest eigenvalue of K_e w = omega^2 M_e w for the constant-strain triangle with lumped mass: K_e = t A B^T D B,
    // M_e = (rho t A / 3) I, so omega^2 = 3 lambda_max(B^T D B) / rho = 3 lambda_max(D^1/2 (B B^T) D^1/2) / rho, a 3 x 3
    // problem (B: strain-displacement matrix, Voigt order xx, yy, 2xy). The estimate h_min / c_p used before is up to 18 %
    // above the exact 2 / omega (equilateral 16 %, a 1 x 0.3 skew triangle 18 %), which left no margin at safety 0.8 where a
    // node belongs to one or two triangles (coarse meshes of blocks).
    Eigen::Matrix3d G;  // B B^T
    triangle_gram(p, n, G);
    const Eigen::Matrix3d D = plane_elasticity(m, plane);
    const Eigen::Matrix3d Dh = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(D).operatorSqrt();
    const Eigen::Matrix3d S = Dh * G * Dh;
    const double lmax = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(S, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
    return 3.0 * lmax / (m.density * mass_scale);
}

double triangle_damped_factor(const double* p, const int* n, const Material& m, Plane plane, double mass_scale,
                              double eta, double alpha) {
    if (!(eta > 0)) return damped_step_factor(0.0, alpha);
    // Central differences with the viscous force lagged (from v^{n-1/2}) and local damping alpha are stable while
    // (1 + alpha) lambda_max(M^-1 (dt^2 K + 2 dt C)) <= 4 (the energy condition 4 M - dt^2 K - 2 dt C > 0, here with
    // the local damping's factor 1 + alpha of the damped_step_factor derivation). For the triangle with lumped mass,
    // M_e^-1 (dt^2 K_e + 2 dt C_e) = (3 / rho) B^T (dt^2 D + 2 dt eta W) B, W = diag(1, 1, 1/2) the viscous stress
    // eta sym(L) in Voigt form (fdem/triangle.hpp); its largest eigenvalue is that of G^1/2 (dt^2 D + 2 dt eta W) G^1/2,
    // G = B B^T. K_e and C_e are not proportional (C_e has no lambda part) and the highest viscous mode is damped at
    // 1.6-2.3 times the nominal xi of eta = xi 2 h sqrt(E rho) (equilateral, nu 0.2: 1.90), so damped_step_factor(xi)
    // of the nominal xi is not a limit. The largest stable dt is found by bisection between the bound that adds the
    // two largest eigenvalues separately (below the limit) and the smaller of the two single-term limits (above it).
    Eigen::Matrix3d G;
    triangle_gram(p, n, G);
    const Eigen::Matrix3d Gh = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(G).operatorSqrt();
    const Eigen::Matrix3d W = Eigen::Vector3d(1.0, 1.0, 0.5).asDiagonal();
    const Eigen::Matrix3d A = Gh * plane_elasticity(m, plane) * Gh, B = Gh * W * Gh;
    const double r = 3.0 / (m.density * mass_scale), lim = 4.0 / (1.0 + alpha);
    auto lmax = [](const Eigen::Matrix3d& S) {
        return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(S, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
    };
    const double w2 = r * lmax(A), c = eta * r * lmax(B);  // omega_e^2 (1/s^2), the largest eigenvalue of M^-1 C (1/s)
    const double w = std::sqrt(w2);
    double lo = (std::sqrt(c * c + w2 * lim) - c) / w2;        // dt^2 w2 + 2 dt c = lim (the eigenvalues added)
    double hi = std::min(std::sqrt(lim / w2), lim / (2.0 * c));  // either term alone at the limit
    for (int it = 0; it < 60 && hi - lo > 1e-12 * hi; ++it) {
        const double mid = 0.5 * (lo + hi);
        (r * lmax(mid * mid * A + 2.0 * mid * eta * B) <= lim ? lo : hi) = mid;
    }
    return 0.5 * lo * w;
}

void add_triangle_node_stiffness(const CaseSpec& spec, const Model& model, const int* rep, double* k, double alpha,
                                 const std::vector<char>* rigid_tri) {
    for (int e = 0; e < model.n_triangles(); ++e) {
        if (rigid_tri && (*rigid_tri)[e]) continue;
        const Material& m = spec.materials[model.tri_material[e]];
        const double f = triangle_damped_factor(model.X.data(), model.tris[e].n, m, spec.plane, spec.mass_scale,
                                                model.tris[e].eta, alpha);
        const double w2 = triangle_omega2(model.X.data(), model.tris[e].n, m, spec.plane, spec.mass_scale) / (f * f);
        const double m3 = m.density * spec.mass_scale * model.tris[e].A0t / 3.0;  // kg
        for (int j = 0; j < 3; ++j) {
            const int v = model.tris[e].n[j];
            k[rep ? rep[v] : v] += w2 * m3;
        }
    }
}

StepLimit triangle_step_limit(const CaseSpec& spec, const Model& model, double alpha, const std::vector<char>* rigid_tri) {
    StepLimit lim;
    lim.dt = 1e300;
    // Damped central difference: dt <= (2 / omega) damped_step_factor(xi, alpha). With lumped masses the assembled
    // model's highest frequency is at most the highest element frequency, so the minimum over the triangles is a safe
    // limit.
    for (int e = 0; e < model.n_triangles(); ++e) {
        if (rigid_tri && (*rigid_tri)[e]) continue;  // inside a rigid body: it never deforms
        const Material& m = spec.materials[model.tri_material[e]];
        const double w2 = triangle_omega2(model.X.data(), model.tris[e].n, m, spec.plane, spec.mass_scale);
        const double dt = 2.0 / std::sqrt(w2) *
                          triangle_damped_factor(model.X.data(), model.tris[e].n, m, spec.plane, spec.mass_scale,
                                                 model.tris[e].eta, alpha);
        if (dt < lim.dt) lim.dt = dt, lim.element = e;
    }
    return lim;
}

}  // namespace fdem
