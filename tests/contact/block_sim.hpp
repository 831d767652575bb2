// tests/contact/block_sim.hpp: a tiny explicit leap-frog integrator for elastic blocks in contact, used only by the
// contact tests until the engine's integrator exists. Neo-Hookean CST triangles (fdem/README.md 'Triangles'), lumped masses,
// gravity, nodal loads, fixed DOFs, optional local damping ([C79], fdem/README.md 'Mass scaling and damping'), contact from ContactSystem.
//
// DATA LAYOUT: x, v, f, m as 2-per-node arrays (m, m/s, N, kg); tri 3 per triangle (CCW); per triangle the
// reference inverse D0^-1 (4 doubles, row-major) and area A0 (m^2).
#pragma once

#include <cmath>
#include <memory>
#include <vector>

#include "contact/contact_system.hpp"
#include "mesh/mesh.hpp"

namespace contact_test {

struct BlockSim {
    // material of every block (SI): E (Pa), nu (-), rho (kg/m^3), thickness t (m)
    double E = 1e9, nu = 0.2, rho = 2000.0, t = 0.1;
    double gx = 0.0, gy = -9.81;  // gravity (m/s^2)
    double alpha = 0.0;           // local damping coefficient (-)
    std::vector<double> x, v, m, f, fext;
    std::vector<char> fixed;  // per DOF
    std::vector<int> tri, tri_body;
    std::vector<int> body_first_node, body_last_node;  // node range [first, last) of each body
    std::vector<double> Dinv, A0;
    std::unique_ptr<fdem::contact::ContactSystem> cs;

    int n_nodes() const { return static_cast<int>(x.size() / 2); }
    int n_tri() const { return static_cast<int>(tri.size() / 3); }
    int n_bodies() const { return static_cast<int>(body_first_node.size()); }

    // A w x h rectangle at (x0, y0) split into nx x ny cells of two triangles each (diagonals alternate).
    int add_block(double x0, double y0, double w, double h, int nx, int ny) {
        const int body = n_bodies(), off = n_nodes();
        for (int j = 0; j <= ny; ++j)
            for (int i = 0; i <= nx; ++i) {
                x.push_back(x0 + w * i / nx);
                x.push_back(y0 + h * j / ny);
            }
        auto id = [&](int i, int j) { return off + j * (nx + 1) + i; };
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) {
                const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
                if ((i + j) % 2 == 0) {
                    tri.insert(tri.end(), {a, b, c, a, c, d});
                } else {
                    tri.insert(tri.end(), {a, b, d, b, c, d});
                }
                tri_body.push_back(body);
                tri_body.push_back(body);
            }
        body_first_node.push_back(off);
        body_last_node.push_back(n_nodes());
        return body;
    }

    int add_mesh(const fdem::mesh::Mesh& mesh) {
        const int body = n_bodies(), off = n_nodes();
        x.insert(x.end(), mesh.xy.begin(), mesh.xy.end());
        for (int q : mesh.tri) tri.push_back(q + off);
        for (int k = 0; k < mesh.n_triangles(); ++k) tri_body.push_back(body);
        body_first_node.push_back(off);
        body_last_node.push_back(n_nodes());
        return body;
    }

    void fix_body(int b) {
        for (int k = body_first_node[b]; k < body_last_node[b]; ++k) fixed[2 * k] = fixed[2 * k + 1] = 1;
    }

    // Reference geometry, masses and the contact system (every triangle contact-capable).
    void finish(const fdem::contact::ContactLaws& laws, fdem::contact::ContactOptions opt = {}) {
        const int nn = n_nodes(), nt = n_tri();
        v.assign(2 * nn, 0.0);
        m.assign(2 * nn, 0.0);
        f.assign(2 * nn, 0.0);
        fext.assign(2 * nn, 0.0);
        fixed.assign(2 * nn, 0);
        Dinv.resize(4 * nt);
        A0.resize(nt);
        for (int e = 0; e < nt; ++e) {
            const int* q = &tri[3 * e];
            const double a = x[2 * q[1]] - x[2 * q[0]], c = x[2 * q[1] + 1] - x[2 * q[0] + 1];
            const double b = x[2 * q[2]] - x[2 * q[0]], d = x[2 * q[2] + 1] - x[2 * q[0] + 1];
            const double det = a * d - b * c;
            A0[e] = 0.5 * det;
            Dinv[4 * e] = d / det;
            Dinv[4 * e + 1] = -b / det;
            Dinv[4 * e + 2] = -c / det;
            Dinv[4 * e + 3] = a / det;
            for (int k = 0; k < 3; ++k) {
                m[2 * q[k]] += rho * t * A0[e] / 3.0;
                m[2 * q[k] + 1] += rho * t * A0[e] / 3.0;
            }
        }
        cs = std::make_unique<fdem::contact::ContactSystem>(tri.data(), nt, nn, t, std::vector<int>(nt, 0), tri_body,
                                                           laws, opt);
        for (int e = 0; e < nt; ++e) cs->set_capable(e, true);
    }

    double stable_dt() const {
        const double cp = std::sqrt(E / (rho * (1.0 - nu * nu)));
        double dt = 1e300;
        for (int e = 0; e < n_tri(); ++e) {
            const int* q = &tri[3 * e];
            double lmax = 0.0;
            for (int k = 0; k < 3; ++k) {
                const int j = (k + 1) % 3;
                lmax = std::max(lmax, std::hypot(x[2 * q[j]] - x[2 * q[k]], x[2 * q[j] + 1] - x[2 * q[k] + 1]));
            }
            dt = std::min(dt, (2.0 * A0[e] / lmax) / cp);
        }
        std::vector<double> mn(n_nodes());
        for (int k = 0; k < n_nodes(); ++k) mn[k] = m[2 * k];
        return std::min(dt, cs->stable_dt(x.data(), mn.data()));
    }

    // Neo-Hookean CST forces (fdem/README.md 'Triangles'): f_a = -t A0 tau F^-T grad0 N_a; returns the strain energy (J) if asked.
    double elastic(bool add_forces) {
        const double mu = E / (2.0 * (1.0 + nu)), lam = E * nu / (1.0 - nu * nu);
        double W = 0.0;
        for (int e = 0; e < n_tri(); ++e) {
            const int* q = &tri[3 * e];
            const double* Di = &Dinv[4 * e];
            const double d00 = x[2 * q[1]] - x[2 * q[0]], d10 = x[2 * q[1] + 1] - x[2 * q[0] + 1];
            const double d01 = x[2 * q[2]] - x[2 * q[0]], d11 = x[2 * q[2] + 1] - x[2 * q[0] + 1];
            const double F00 = d00 * Di[0] + d01 * Di[2], F01 = d00 * Di[1] + d01 * Di[3];
            const double F10 = d10 * Di[0] + d11 * Di[2], F11 = d10 * Di[1] + d11 * Di[3];
            const double J = F00 * F11 - F01 * F10, lnJ = std::log(J);
            const double B00 = F00 * F00 + F01 * F01, B01 = F00 * F10 + F01 * F11, B11 = F10 * F10 + F11 * F11;
            W += t * A0[e] * (0.5 * mu * (B00 + B11 - 2.0) - mu * lnJ + 0.5 * lam * lnJ * lnJ);
            if (!add_forces) continue;
            const double t00 = mu * (B00 - 1.0) + lam * lnJ, t01 = mu * B01, t11 = mu * (B11 - 1.0) + lam * lnJ;
            // F^-T
            const double i00 = F11 / J, i01 = -F10 / J, i10 = -F01 / J, i11 = F00 / J;
            const double P00 = t00 * i00 + t01 * i10, P01 = t00 * i01 + t01 * i11;
            const double P10 = t01 * i00 + t11 * i10, P11 = t01 * i01 + t11 * i11;
            // grad0 N_1 = first row of D0^-1, grad0 N_2 = second row, grad0 N_0 = -(sum)
            const double g[3][2] = {{-Di[0] - Di[2], -Di[1] - Di[3]}, {Di[0], Di[1]}, {Di[2], Di[3]}};
            for (int a = 0; a < 3; ++a) {
                f[2 * q[a]] -= t * A0[e] * (P00 * g[a][0] + P01 * g[a][1]);
                f[2 * q[a] + 1] -= t * A0[e] * (P10 * g[a][0] + P11 * g[a][1]);
            }
        }
        return W;
    }

    void step(double dt) {
        const int nn = n_nodes();
        for (int k = 0; k < nn; ++k) {
            f[2 * k] = fext[2 * k] + m[2 * k] * gx;
            f[2 * k + 1] = fext[2 * k + 1] + m[2 * k + 1] * gy;
        }
        elastic(true);
        cs->step(x.data(), v.data(), dt, f.data());
        for (int i = 0; i < 2 * nn; ++i) {
            if (fixed[i]) {
                v[i] = 0.0;
                continue;
            }
            double fi = f[i];
            if (alpha > 0.0 && v[i] != 0.0) fi -= alpha * std::fabs(fi) * (v[i] > 0.0 ? 1.0 : -1.0);
            v[i] += dt * fi / m[i];
            x[i] += dt * v[i];
        }
        cs->finish_step(v.data());
    }

    double kinetic() const {
        double K = 0.0;
        for (size_t i = 0; i < v.size(); ++i) K += 0.5 * m[i] * v[i] * v[i];
        return K;
    }
    // Body centre of mass and mean velocity (lumped masses).
    void body_cm(int b, double& cx, double& cy) const {
        double mx = 0.0, my = 0.0, mt = 0.0;
        for (int k = body_first_node[b]; k < body_last_node[b]; ++k) {
            mx += m[2 * k] * x[2 * k];
            my += m[2 * k] * x[2 * k + 1];
            mt += m[2 * k];
        }
        cx = mx / mt;
        cy = my / mt;
    }
    void body_velocity(int b, double& vx, double& vy) const {
        double mx = 0.0, my = 0.0, mt = 0.0;
        for (int k = body_first_node[b]; k < body_last_node[b]; ++k) {
            mx += m[2 * k] * v[2 * k];
            my += m[2 * k] * v[2 * k + 1];
            mt += m[2 * k];
        }
        vx = mx / mt;
        vy = my / mt;
    }
    // Rotation of a body (rad, CCW) from its first to its last node, relative to a reference vector.
    double body_angle(int b, double ref_angle) const {
        const int i = body_first_node[b], j = body_last_node[b] - 1;
        return std::atan2(x[2 * j + 1] - x[2 * i + 1], x[2 * j] - x[2 * i]) - ref_angle;
    }
    double body_ref_angle(int b) const { return body_angle(b, 0.0); }
};

}  // namespace contact_test
