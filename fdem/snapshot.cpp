// fdem/snapshot.cpp: Simulation's snapshots (fdem/README.md 'The run folder'): the mesh with its point and cell data as a VTU
// file per snapshot (run.pvd lists them), and beside it the loaded contact faces (contacts_N.vtu, contacts.pvd).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include "fdem/output.hpp"
#include "fdem/sim_detail.hpp"
#include "fdem/simulation.hpp"

namespace fdem {

void Simulation::write_snapshot() {
    if (opt_.out_dir.empty()) return;
    const int nn = model_.n_nodes(), nt = model_.n_triangles();
    VtuArray disp{"displacement", 3, {}, {}, false, {"ux", "uy", "uz"}}, vel{"velocity", 3, {}, {}, false, {"vx", "vy", "vz"}};
    disp.f64.resize(3 * nn), vel.f64.resize(3 * nn);
    for (int k = 0; k < nn; ++k) {
        disp.f64[3 * k] = model_.x[2 * k] - model_.X[2 * k], disp.f64[3 * k + 1] = model_.x[2 * k + 1] - model_.X[2 * k + 1], disp.f64[3 * k + 2] = 0;
        vel.f64[3 * k] = model_.v[2 * k], vel.f64[3 * k + 1] = model_.v[2 * k + 1], vel.f64[3 * k + 2] = 0;
    }
    VtuArray stress{"stress", 3, {}, {}, false, {"sxx", "syy", "sxy"}}, mat{"material", 1, {}, {}, true, {}};
    VtuArray region{"region", 1, {}, {}, true, {}};
    VtuArray body{"unit", 1, {}, {}, true, {}};  // the body (unit, beam, base) a triangle belongs to
    // Derived stress measures (Pa): von Mises with the out-of-plane stress (plane stress 0; plane strain, F_zz = 1,
    // the neo-Hookean law's s_zz = lambda ln J / J), and the in-plane principal stresses s1 >= s2.
    VtuArray von_mises{"von_mises", 1, {}, {}, false, {}}, principal{"principal_stress", 2, {}, {}, false, {"s1", "s2"}};
    // principal_direction: the unit vector of s1 (angle theta = atan2(2 sxy, sxx - syy) / 2 from x), for glyphs.
    VtuArray pdir{"principal_direction", 3, {}, {}, false, {"n1x", "n1y", "n1z"}};
    stress.f64.resize(3 * nt), mat.i32.resize(nt), region.i32.resize(nt), body.i32.resize(nt);
    von_mises.f64.resize(nt), principal.f64.resize(2 * nt), pdir.f64.resize(3 * nt);
    std::vector<int> tri(3 * nt);
    for (int e = 0; e < nt; ++e) {
        const MaterialConst& mc = model_.mat[model_.tris[e].mat];
        double* s3 = &stress.f64[3 * e];
        if (crush_.slot(e) < 0) triangle_stress(model_.tris[e], mc, model_.x.data(), s3);
        else crush_.stress(crush_.slot(e), model_.tris[e], model_.x.data(), s3);
        double F[4];
        triangle_F(model_.tris[e], model_.x.data(), F);
        const double J = F[0] * F[3] - F[1] * F[2];
        const double szz = spec_.plane == Plane::strain && J > 0 ? mc.lambda * std::log(J) / J : 0.0;
        const StressMeasures sm = stress_measures(s3[0], s3[1], s3[2], szz);
        von_mises.f64[e] = sm.von_mises, principal.f64[2 * e] = sm.s1, principal.f64[2 * e + 1] = sm.s2;
        const double theta = 0.5 * std::atan2(2 * s3[2], s3[0] - s3[1]);
        pdir.f64[3 * e] = std::cos(theta), pdir.f64[3 * e + 1] = std::sin(theta), pdir.f64[3 * e + 2] = 0;
        mat.i32[e] = model_.tri_material[e];
        region.i32[e] = model_.mesh.tri_region[e];
        body.i32[e] = model_.mesh.tri_body.empty() ? 0 : model_.mesh.tri_body[e];
        for (int k = 0; k < 3; ++k) tri[3 * e + k] = model_.tris[e].n[k];
    }
    // Cohesive elements and dry joint segments as line cells on their side-A edge, after the triangles: cell_kind
    // 0 triangle, 1 cohesive element, 2 dry joint (the codes of mesh.vtu, mesh/vtu.hpp; always written);
    // joint_damage (max over its points; -1 on triangles and dry joints),
    // joint_state (cohesive: 0 intact, 1 damaged, 2 broken; dry: 0 not recorded, 1 in the joint record; -1 on
    // triangles), joint_opening and joint_slip (m, the definitions of Interactions::joint_motion; NaN on triangles).
    std::vector<int> lines;
    VtuArray kind{"cell_kind", 1, {}, {}, true, {}}, damage{"joint_damage", 1, {}, {}, false, {}};
    VtuArray state{"joint_state", 1, {}, {}, true, {}};
    VtuArray opening{"joint_opening", 1, {}, {}, false, {}}, slip{"joint_slip", 1, {}, {}, false, {}};
    // With a compressive cap (fracture/law.hpp): joint_crushing, the plastic closure of each cohesive element (m,
    // Simpson mean over its points; NaN on triangles and dry joints).
    VtuArray crushing{"joint_crushing", 1, {}, {}, false, {}};
    // joint_normal_stress, joint_shear_stress: a cohesive element's mean traction at the last step (Pa, tension
    // positive; CohesiveSystem::mean_traction); NaN on triangles, dry joints and dormant (not inserted) elements.
    VtuArray jsn{"joint_normal_stress", 1, {}, {}, false, {}}, jss{"joint_shear_stress", 1, {}, {}, false, {}};
    jsn.f64.assign(nt, std::nan("")), jss.f64.assign(nt, std::nan(""));
    kind.i32.assign(nt, 0), damage.f64.assign(nt, -1.0), state.i32.assign(nt, -1);
    opening.f64.assign(nt, std::nan("")), slip.f64.assign(nt, std::nan("")), crushing.f64.assign(nt, std::nan(""));
    auto add_line = [&](const int* n, int cell_kind, double dmg, int st, double crush, double sn, double ss) {
        jsn.f64.push_back(sn), jss.f64.push_back(ss);
        for (int c = 0; c < 3; ++c) pdir.f64.push_back(std::nan(""));
        lines.push_back(n[0]), lines.push_back(n[1]);
        kind.i32.push_back(cell_kind);
        damage.f64.push_back(dmg);
        state.i32.push_back(st);
        double o, sl;
        Interactions::joint_motion(n, model_.x.data(), o, sl);
        opening.f64.push_back(o), slip.f64.push_back(sl), crushing.f64.push_back(crush);
        for (int c = 0; c < 3; ++c) stress.f64.push_back(std::nan(""));
        von_mises.f64.push_back(std::nan("")), principal.f64.push_back(std::nan("")), principal.f64.push_back(std::nan(""));
        mat.i32.push_back(-1), region.i32.push_back(-1), body.i32.push_back(-1);
    };
    if (const fracture::CohesiveSystem* j = inter_.joints())
        for (int e = 0; e < j->size(); ++e) {
            double sn, ss;
            j->mean_traction(e, model_.x.data(), sn, ss);
            add_line(j->element(e).n, 1, j->damage(e), static_cast<int>(j->state(e)), j->crushing(e), sn, ss);
        }
    // The contact faces as the next step loads them (ContactSystem::loaded_edges): the snapshot's contact file, and
    // the dry joints' normal and shear stress from the faces along them.
    const contact::ContactSystem* cs = inter_.contact();
    std::vector<contact::ContactSystem::LoadedEdge> faces;
    if (cs) faces = cs->loaded_edges(model_.x.data(), model_.v.data(), clock_.dt);
    std::vector<double> dry_force(2 * static_cast<std::size_t>(inter_.dry_joint_count()), 0.0);
    dry_joint_forces(faces, dry_force);
    for (int e = 0; e < inter_.dry_joint_count(); ++e) {
        double sn, ss;
        dry_joint_traction(inter_.dry_joints()[e].n.data(), &dry_force[2 * static_cast<std::size_t>(e)], sn, ss);
        add_line(inter_.dry_joints()[e].n.data(), 2, -1.0, inter_.dry_recorded(e) ? 1 : 0, std::nan(""), sn, ss);
    }
    char name[64];
    std::snprintf(name, sizeof name, "snapshots/step_%09ld.vtu", clock_.steps);
    std::vector<VtuArray> cells{stress, von_mises, principal, pdir, mat, region, body, kind};
    if (!lines.empty())
        for (const auto* a : {&damage, &state, &opening, &slip}) cells.push_back(*a);
    if (inter_.joints() || inter_.dry_joint_count() > 0) cells.push_back(jsn), cells.push_back(jss);
    if (inter_.joints() && inter_.joints()->has_cap()) cells.push_back(crushing);
    if (crush_.active()) {
        // block_crushing: kappa / kappa_u of each crushing triangle (0 intact, 1 no strength left; fdem/plasticity.hpp),
        // NaN on elastic triangles and line cells.
        VtuArray bc{"block_crushing", 1, {}, {}, false, {}};
        bc.f64.assign(nt + lines.size() / 2, std::nan(""));
        for (int e = 0; e < nt; ++e)
            if (crush_.slot(e) >= 0) bc.f64[e] = crush_.softening(crush_.slot(e));
        cells.push_back(bc);
    }
    // The names behind the ids: region_names[region], material_names[material].
    VtuStrings region_names{"region_names", model_.mesh.regions}, material_names{"material_names", {}};
    for (const auto& m : spec_.materials) material_names.values.push_back(m.name);
    write_file_atomic(
        (std::filesystem::path(opt_.out_dir) / name).string(),
        vtu_document(model_.X, tri, lines, {disp, vel}, cells, {region_names, material_names}, clock_.time));
    out_.snapshots.emplace_back(clock_.time, name);
    write_file_atomic((std::filesystem::path(opt_.out_dir) / "run.pvd").string(), pvd_document(out_.snapshots));
    if (cs) {
        write_file_atomic((std::filesystem::path(opt_.out_dir) / contact_snapshot_name(name)).string(),
                          contact_snapshot(faces));
        std::vector<std::pair<double, std::string>> list;
        for (const auto& [t, n] : out_.snapshots) list.emplace_back(t, contact_snapshot_name(n));
        write_file_atomic((std::filesystem::path(opt_.out_dir) / "contacts.pvd").string(), pvd_document(list));
    }
}

// Dry joint segment e's force from the faces along it: the force side B exerts on side A (N, 2 per segment), the sum
// over the faces whose edge is one of its two edges (each face carries half a contact: a face of A gets its own
// load, a face of B the reaction).
void Simulation::dry_joint_forces(const std::vector<contact::ContactSystem::LoadedEdge>& faces, std::vector<double>& force) const {
    if (force.empty() || faces.empty()) return;
    auto key = [](int a, int b) { return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b)); };
    std::unordered_map<std::uint64_t, int> side;  // edge -> 2 e (side A) or 2 e + 1 (side B)
    for (int e = 0; e < inter_.dry_joint_count(); ++e) {
        const auto& n = inter_.dry_joints()[e].n;
        side[key(n[0], n[1])] = 2 * e;
        side[key(n[2], n[3])] = 2 * e + 1;
    }
    for (const auto& f : faces) {
        const int* t = &model_.mesh.tri[3 * static_cast<std::size_t>(f.triangle)];
        const auto it = side.find(key(t[f.edge], t[(f.edge + 1) % 3]));
        if (it == side.end()) continue;
        const contact::EdgeRecord& r = f.record;
        // the force on the face's owner: -fn n + ft t, t = (-n_y, n_x)
        const double fx = -r.fn * r.nx - r.ft * r.ny, fy = -r.fn * r.ny + r.ft * r.nx;
        const double sign = (it->second & 1) ? -1.0 : 1.0;
        double* F = &force[2 * static_cast<std::size_t>(it->second / 2)];
        F[0] += sign * fx, F[1] += sign * fy;
    }
}

// Mean normal and shear stress of a dry joint segment n = {a0, a1, b0, b1} carrying force F (from B on A): in the
// frame of its side-A edge (t from a0 to a1, n = (t_y, -t_x) into B), over its length times the thickness; tension
// positive, as the cohesive elements' joint_normal_stress.
void Simulation::dry_joint_traction(const int* n, const double* F, double& sigma, double& tau) const {
    const double* x = model_.x.data();
    double tx = x[2 * n[1]] - x[2 * n[0]], ty = x[2 * n[1] + 1] - x[2 * n[0] + 1];
    const double len = std::hypot(tx, ty);
    if (len <= 0) {
        sigma = tau = std::nan("");
        return;
    }
    tx /= len, ty /= len;
    const double area = len * spec_.thickness;
    sigma = (F[0] * ty - F[1] * tx) / area;
    tau = (F[0] * tx + F[1] * ty) / area;
}

// The contact file of a snapshot: one point per loaded face at its centre of pressure.
std::string Simulation::contact_snapshot(const std::vector<contact::ContactSystem::LoadedEdge>& faces) const {
    const std::size_t n = faces.size();
    std::vector<double> xy(2 * n);
    VtuArray normal{"normal", 3, {}, {}, false, {"nx", "ny", "nz"}}, force{"force", 3, {}, {}, false, {"fx", "fy", "fz"}};
    VtuArray fn{"normal_force", 1, {}, {}, false, {}}, ft{"shear_force", 1, {}, {}, false, {}};
    VtuArray sn{"normal_stress", 1, {}, {}, false, {}}, st{"shear_stress", 1, {}, {}, false, {}};
    VtuArray len{"length", 1, {}, {}, false, {}}, sliding{"sliding", 1, {}, {}, true, {}};
    // the face's triangle and unit, and those of the triangle it enters
    VtuArray tri{"triangle", 1, {}, {}, true, {}}, unit{"unit", 1, {}, {}, true, {}};
    VtuArray other{"other_triangle", 1, {}, {}, true, {}}, other_unit{"other_unit", 1, {}, {}, true, {}};
    auto unit_of = [&](int t) { return model_.mesh.tri_body.empty() ? 0 : model_.mesh.tri_body[static_cast<std::size_t>(t)]; };
    for (std::size_t i = 0; i < n; ++i) {
        const contact::EdgeRecord& r = faces[i].record;
        xy[2 * i] = r.px, xy[2 * i + 1] = r.py;
        normal.f64.insert(normal.f64.end(), {r.nx, r.ny, 0.0});
        force.f64.insert(force.f64.end(), {-r.fn * r.nx - r.ft * r.ny, -r.fn * r.ny + r.ft * r.nx, 0.0});
        fn.f64.push_back(r.fn), ft.f64.push_back(r.ft);
        const double area = r.length * spec_.thickness;
        sn.f64.push_back(area > 0 ? -r.fn / area : std::nan("")), st.f64.push_back(area > 0 ? r.ft / area : std::nan(""));
        len.f64.push_back(r.length), sliding.i32.push_back(r.sliding);
        tri.i32.push_back(faces[i].triangle), unit.i32.push_back(unit_of(faces[i].triangle));
        other.i32.push_back(faces[i].other), other_unit.i32.push_back(unit_of(faces[i].other));
    }
    return points_vtu_document(xy, {normal, force, fn, ft, sn, st, len, sliding, tri, unit, other, other_unit}, {},
                               clock_.time);
}

}  // namespace fdem
