// fdem/interactions.cpp: see interactions.hpp.
//
// Contact "materials" are the mesh regions (so that an interface rule, given per pair of regions, is a contact
// law per pair of contact materials): two triangles of different bodies use the law of their regions' interface,
// two triangles of one body (the faces of a crack inside a unit) the crack law of their region's material.
#include "fdem/interactions.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "fdem/common/errors.hpp"

namespace fdem {

namespace {

std::string fmt_g(double v) {
    std::ostringstream o;
    o.precision(4);
    o << v;
    return o.str();
}

// E (Pa): the modulus that sets the reference of penalty = "auto" (10 E) when penalty_ref is not given.
fracture::CohesiveProps to_props(const JointSpec& j, double E) {
    fracture::CohesiveProps p;
    p.penalty_auto = j.penalty_auto;
    // 10 E: a joint of the element's length adds a tenth of the element's compliance (K_n = p_j / h against E / h).
    p.penalty_ref = std::isnan(j.penalty_ref) ? 10.0 * E : j.penalty_ref;
    p.tensile_strength = j.tensile_strength;
    p.cohesion = j.cohesion;
    p.friction_deg = j.friction;
    p.residual_friction_deg = j.residual_friction;
    p.G_I = j.GI;
    p.G_II = j.GII;
    p.penalty = j.penalty;
    p.k_n = j.normal_stiffness;
    p.k_s = j.shear_stiffness;
    p.keep_friction = j.keep_friction;
    p.mohr_coulomb = j.mohr_coulomb;
    p.compressive_strength = j.compressive_strength;
    p.composite = j.composite;  // law = "composite"
    p.compressive_energy = j.compressive_energy;
    p.cap_shear_factor = j.cap_shear_factor;
    p.extrinsic = j.extrinsic;
    return p;
}

const Material& material_of(const CaseSpec& spec, const Model& model, int region) {
    return spec.materials[spec.material_index(spec.region_material.at(model.mesh.regions[region]))];
}

const InterfaceSpec* find_interface(const CaseSpec& spec, const std::string& a, const std::string& b) {
    for (const auto& i : spec.interfaces)
        if ((i.region_a == a && i.region_b == b) || (i.region_a == b && i.region_b == a)) return &i;
    return nullptr;
}

}  // namespace

Interactions::Interactions(const CaseSpec& spec, const Model& model) {
    if (!model.has_topology) return;
    setup_dry_joints(spec, model);
    const int nr = static_cast<int>(model.mesh.regions.size());
    // The joint penalty of each cracking region's crack faces and each bonded interface after breaking, p_j (Pa):
    // the case's value, or with penalty = "auto" the value setup_joints resolves (its reference where no element
    // uses it).
    std::vector<double> crack_penalty(static_cast<std::size_t>(nr), std::nan(""));
    std::vector<double> bond_penalty(spec.interfaces.size(), std::nan(""));
    for (int r = 0; r < nr; ++r)
        if (const JointSpec& j = material_of(spec, model, r).fracture; j.present)
            crack_penalty[static_cast<std::size_t>(r)] = j.penalty_auto ? to_props(j, material_of(spec, model, r).E).penalty_ref : j.penalty;
    for (std::size_t i = 0; i < spec.interfaces.size(); ++i) bond_penalty[i] = spec.interfaces[i].bond.penalty;
    if (!model.cohesive.empty()) setup_joints(spec, model, crack_penalty, bond_penalty);
    setup_contact(spec, model, crack_penalty, bond_penalty);
}

// The dry joints' records: reference lengths and midpoints, and the opening and slip they start with.
void Interactions::setup_dry_joints(const CaseSpec& spec, const Model& model) {
    dry_ = model.dry_joints;
    dry_open_.assign(dry_.size(), 0), dry_slip_.assign(dry_.size(), 0);
    for (const auto& d : dry_) {
        const double* X = model.X.data();
        dry_len_.push_back(std::hypot(X[2 * d.n[1]] - X[2 * d.n[0]], X[2 * d.n[1] + 1] - X[2 * d.n[0] + 1]));
        dry_ref_mid_.push_back(0.5 * (X[2 * d.n[0]] + X[2 * d.n[1]]));
        dry_ref_mid_.push_back(0.5 * (X[2 * d.n[0] + 1] + X[2 * d.n[1] + 1]));
        // A roughened joint (geometry.joint_roughness) starts with a gap: opening and slip count from the start.
        double opening, slip;
        joint_motion(d.n.data(), X, opening, slip);
        dry_motion0_.push_back(opening), dry_motion0_.push_back(slip);
    }
    set_dry_record(spec.joint_open, spec.joint_slip);
}

// Cohesive elements: crackable edges take their material's fracture properties, bonded edges their interface's. One
// props entry per material / interface, in that order. Resolves penalty = "auto" into crack_penalty / bond_penalty.
void Interactions::setup_joints(const CaseSpec& spec, const Model& model, std::vector<double>& crack_penalty,
                                std::vector<double>& bond_penalty) {
    const auto& regions = model.mesh.regions;
    const int nr = static_cast<int>(regions.size());
    auto material_of = [&](int region) -> const Material& { return fdem::material_of(spec, model, region); };
    std::vector<fracture::CohesiveProps> props;
    std::vector<int> crack_props(nr, -1);
    std::vector<std::string> props_key;
    for (int r = 0; r < nr; ++r)
        if (material_of(r).fracture.present) {
            crack_props[r] = static_cast<int>(props.size());
            props.push_back(to_props(material_of(r).fracture, material_of(r).E));
            props_key.push_back("materials." + material_of(r).name + ".fracture");
        }
    std::vector<int> bond_props(spec.interfaces.size(), -1);
    for (std::size_t i = 0; i < spec.interfaces.size(); ++i)
        if (spec.interfaces[i].kind == "bonded") {
            bond_props[i] = static_cast<int>(props.size());
            const auto region_E = [&](const std::string& name) {
                return spec.materials[spec.material_index(spec.region_material.at(name))].E;
            };
            props.push_back(to_props(spec.interfaces[i].bond,
                                     std::min(region_E(spec.interfaces[i].region_a), region_E(spec.interfaces[i].region_b))));
            props_key.push_back("interfaces." + std::to_string(i + 1));
        }
    // Too-soft penalties: checked against the longest element of each class.
    std::vector<double> h_max(props.size(), 0.0);
    std::vector<fracture::CohesiveElement> elems;
    elems.reserve(model.cohesive.size());
    for (const auto& c : model.cohesive) {
        fracture::CohesiveElement e;
        for (int k = 0; k < 4; ++k) e.n[k] = c.n[k];
        e.tri_a = c.tri_a;
        e.tri_b = c.tri_b;
        e.unit_a = c.body_a;
        e.unit_b = c.body_b;
        if (c.kind == mesh::EdgeClass::crackable) {
            e.kind = fracture::JointClass::unit_interior;
            e.props = crack_props[c.region_a];
        } else {
            e.kind = fracture::JointClass::interface;
            const InterfaceSpec* in = find_interface(spec, regions[c.region_a], regions[c.region_b]);
            e.props = in ? bond_props[static_cast<std::size_t>(in - spec.interfaces.data())] : -1;
        }
        if (e.props < 0)
            throw InputError(spec.file + ": no cohesive properties for a joint between regions '" + regions[c.region_a] +
                             "' and '" + regions[c.region_b] + "'");
        const double h = std::hypot(model.X[2 * c.n[1]] - model.X[2 * c.n[0]], model.X[2 * c.n[1] + 1] - model.X[2 * c.n[0] + 1]);
        h_max[e.props] = std::max(h_max[e.props], h);
        elems.push_back(e);
    }
    // penalty = "auto": resolved per class from its longest element (fracture/properties.hpp).
    for (std::size_t p = 0; p < props.size(); ++p)
        if (props[p].penalty_auto && h_max[p] > 0) {
            props[p].penalty = fracture::auto_penalty(props[p], h_max[p]);
            auto_notes_.push_back("[" + props_key[p] + "]: penalty = \"auto\": p_j = " + fmt_g(props[p].penalty) +
                                  " Pa at h_max = " + fmt_g(h_max[p]) + " m");
        }
    for (int r = 0; r < nr; ++r)
        if (crack_props[r] >= 0 && props[static_cast<std::size_t>(crack_props[r])].penalty_auto &&
            h_max[static_cast<std::size_t>(crack_props[r])] > 0)
            crack_penalty[static_cast<std::size_t>(r)] = props[static_cast<std::size_t>(crack_props[r])].penalty;
    for (std::size_t i = 0; i < spec.interfaces.size(); ++i)
        if (bond_props[i] >= 0) bond_penalty[i] = props[static_cast<std::size_t>(bond_props[i])].penalty;
    std::vector<std::string> problems;
    for (std::size_t p = 0; p < props.size(); ++p)
        for (const auto& msg : fracture::check(props[p], h_max[p])) problems.push_back(spec.file + ": [" + props_key[p] + "]: " + msg);
    if (!problems.empty()) throw InputError(problems);
    try {
        fracture::orient_elements(elems, model.mesh.tri.data());
        joints_ = std::make_unique<fracture::CohesiveSystem>(std::move(elems), std::move(props), spec.thickness,
                                                             model.X.data(), model.n_nodes());
    } catch (const std::invalid_argument& e) {
        throw InputError(spec.file + ": cohesive elements: " + e.what());
    }
}

// Contact laws per pair of regions, and the contact system when any surfaces can touch.
void Interactions::setup_contact(const CaseSpec& spec, const Model& model, const std::vector<double>& crack_penalty,
                                 const std::vector<double>& bond_penalty) {
    const auto& regions = model.mesh.regions;
    const int nr = static_cast<int>(regions.size());
    auto material_of = [&](int region) -> const Material& { return fdem::material_of(spec, model, region); };
    bool any_contact = false;
    for (const auto& i : spec.interfaces) any_contact = any_contact || i.kind != "tied";
    for (const auto& m : spec.materials) any_contact = any_contact || m.fracture.present;
    if (!any_contact) return;
    // Contact happens only where the case says surfaces can touch: region pairs with a dry or bonded rule and the
    // crack faces of cracking materials. Other combinations (tied regions, a beam that cannot crack) never pair.
    contact::ContactLaws laws(nr);
    laws.set_unlisted_never_touch(true);
    for (int a = 0; a < nr; ++a) {
        const Material& ma = material_of(a);
        if (ma.fracture.present) {
            // Crack faces: the joint penalty as normal penalty (or the table's contact_penalty), the residual friction.
            const double pc = std::isnan(ma.fracture.contact_penalty) ? crack_penalty[static_cast<std::size_t>(a)] : ma.fracture.contact_penalty;
            contact::ContactLaw l = contact::ContactLaw::penalty(pc, std::tan(ma.fracture.residual_friction * M_PI / 180));
            l.name = "crack faces of " + ma.name;
            laws.set_crack(a, l);
        }
        for (int b = a; b < nr; ++b) {
            const InterfaceSpec* in = find_interface(spec, regions[a], regions[b]);
            if (!in || in->kind == "tied") continue;
            contact::ContactLaw l;
            l.name = "interface " + regions[a] + "/" + regions[b];
            if (in->kind == "dry") {
                if (!std::isnan(in->normal_penalty)) l.p_n = in->normal_penalty;
                if (!std::isnan(in->normal_stiffness)) l.k_n = in->normal_stiffness;
                if (!std::isnan(in->tangential_penalty)) l.p_t = in->tangential_penalty;
                if (!std::isnan(in->shear_stiffness)) l.k_s = in->shear_stiffness;
                l.phi_deg = in->friction;
                l.restitution = in->restitution;
                if (in->restitution < 1.0)
                    auto_notes_.push_back("[[interfaces]] " + regions[a] + "/" + regions[b] + ": restitution " +
                                          fmt_g(in->restitution) + ": an impact gives back " +
                                          fmt_g(in->restitution * in->restitution) +
                                          " of the work its contact took; unloading at k_n / e^2 = " +
                                          fmt_g(1.0 / (in->restitution * in->restitution)) +
                                          " k_n bounds the step (for impacts and rocking; a joint that carries "
                                          "friction while it vibrates can gain energy: fdem/README.md, Contact)");
            } else {  // bonded: after breaking, contact with the joint's stiffness and the residual friction
                if (const double pb = bond_penalty[static_cast<std::size_t>(in - spec.interfaces.data())]; !std::isnan(pb)) l.p_n = pb;
                if (!std::isnan(in->bond.normal_stiffness)) l.k_n = in->bond.normal_stiffness;
                if (!std::isnan(in->bond.shear_stiffness)) l.k_s = in->bond.shear_stiffness;
                l.phi_deg = in->bond.residual_friction;
            }
            laws.set_interface(a, b, l);
        }
    }
    try {
        contact::ContactOptions copt;
        copt.buffer = spec.contact_buffer;
        std::vector<int> tri_region(model.mesh.tri_region.begin(), model.mesh.tri_region.end());
        std::vector<int> tri_body = model.mesh.tri_body.empty() ? std::vector<int>(model.n_triangles(), 0) : model.mesh.tri_body;
        contact_ = std::make_unique<contact::ContactSystem>(model.mesh.tri.data(), model.n_triangles(), model.n_nodes(),
                                                            spec.thickness, std::move(tri_region), std::move(tri_body), laws, copt);
    } catch (const std::invalid_argument& e) {
        throw InputError(spec.file + ": [[interfaces]]: " + e.what());
    }
    for (int t : model.contact_capable) contact_->set_capable(t, true);
    contact_->set_vertex_copies(model.node_vertex);
    if (joints_)
        for (int e = 0; e < joints_->size(); ++e) {
            const auto& el = joints_->element(e);
            if (el.tri_a >= 0 && el.tri_b >= 0) contact_->exclude_pair(el.tri_a, el.tri_b);
        }
}

double Interactions::stable_dt(const Model& model, double xi_contact, const double* mass, const int* rep, double alpha) const {
    double dt = std::numeric_limits<double>::infinity();
    if (joints_) dt = std::min(dt, joints_->stable_dt(mass ? mass : model.mass.data(), rep) * damped_step_factor(0.0, alpha));
    if (contact_) {
        const double damped = damped_step_factor(xi_contact, alpha);
        dt = std::min(dt, contact_stable_dt(model, mass) * damped);
    }
    return dt;
}

void Interactions::add_node_stiffness(const Model& model, double xi_contact, double alpha, const int* rep, double* k_joint,
                                      double* k_contact, bool every_face) const {
    if (joints_) {
        // (1 + alpha = 1 / damped_step_factor(0, alpha)^2: the joints' springs have no dashpots)
        const std::vector<double> k = joints_->node_stiffness(rep);
        for (std::size_t v = 0; v < k.size(); ++v) k_joint[v] += k[v] * (1.0 + alpha);
    }
    if (contact_) {
        const double damped = damped_step_factor(xi_contact, alpha);
        // The faces of intact intrinsic cohesive elements cannot touch until the element breaks (its two triangles are
        // an excluded pair, and the edge is inside the body): not counted; the engine checks the step again when
        // elements break (reduce_dt_after_insertion).
        std::vector<std::uint8_t> held;
        if (joints_) {
            held.assign(model.n_triangles(), 0);
            auto mark = [&](int t, int a, int b) {
                if (t < 0) return;
                for (int e = 0; e < 3; ++e) {
                    const int p = model.mesh.tri[3 * t + e], q = model.mesh.tri[3 * t + (e + 1) % 3];
                    if ((p == a && q == b) || (p == b && q == a)) held[t] |= static_cast<std::uint8_t>(1u << e);
                }
            };
            for (int e = 0; e < joints_->size(); ++e) {
                if (!joints_->holds_faces(e)) continue;
                const auto& el = joints_->element(e);
                mark(el.tri_a, el.n[0], el.n[1]);
                mark(el.tri_b, el.n[2], el.n[3]);
            }
        }
        const std::vector<double> k =
            contact_->node_stiffness(model.X.data(), held.empty() ? nullptr : held.data(), !every_face);
        // A tied group (rep) takes its stiffest copy's, not the sum: each copy's count holds the faces a crack could
        // open at it, which are no faces while the group is tied (summed, the default wall's groups asked 4 times the
        // mass); once an insertion unties the copies, reduce_dt_after_insertion checks the step again.
        std::vector<double> top(k.size(), 0.0);
        for (std::size_t v = 0; v < k.size(); ++v) {
            const std::size_t r = rep ? static_cast<std::size_t>(rep[v]) : v;
            top[r] = std::max(top[r], k[v]);
        }
        for (std::size_t v = 0; v < k.size(); ++v) k_contact[v] += top[v] / (damped * damped);
    }
}

double Interactions::contact_stable_dt(const Model& model, const double* mass) const {
    return contact_ ? contact_->stable_dt(model.X.data(), mass ? mass : model.mass.data())
                    : std::numeric_limits<double>::infinity();
}

void Interactions::list_dormant() {
    dormant_.clear();
    if (joints_)
        for (int e = 0; e < joints_->size(); ++e)
            if (joints_->dormant(e)) dormant_.push_back(e);
    dormant_edge_.resize(dormant_.size());
    for (std::size_t i = 0; i < dormant_.size(); ++i) {
        const auto& el = joints_->element(dormant_[i]);
        const auto& law = joints_->law(dormant_[i]);
        dormant_edge_[i] = {el.tri_a, el.tri_b, el.n[0], el.n[1], law.tensile_strength, law.cohesion, law.tan_friction};
    }
    due_.assign(dormant_.size(), 0);
    due_traction_.assign(2 * dormant_.size(), 0.0);
    // The triangles that border a dormant edge, each with the smallest f_t and c of those edges (c = -inf when some
    // edge's tan(phi) < 0: the bound of insert_cracks does not hold for it, so the triangle is always checked).
    int n_tri = 0;
    for (const DormantEdge& el : dormant_edge_) n_tri = std::max(n_tri, std::max(el.tri_a, el.tri_b) + 1);
    const double inf = std::numeric_limits<double>::infinity();
    tri_strength_.assign(2 * static_cast<std::size_t>(n_tri), inf);
    std::vector<char> borders(n_tri, 0);
    for (const DormantEdge& el : dormant_edge_)
        for (int t : {el.tri_a, el.tri_b})
            if (t >= 0) {
                double* st = &tri_strength_[2 * static_cast<std::size_t>(t)];
                st[0] = std::min(st[0], el.tensile_strength);
                st[1] = std::min(st[1], el.tan_friction >= 0.0 ? el.cohesion : -inf);
                borders[t] = 1;
            }
    dormant_tri_.clear();
    for (int t = 0; t < n_tri; ++t)
        if (borders[t]) dormant_tri_.push_back(t);
    near_.assign(n_tri, 0);  // set by insert_cracks for the triangles of dormant_tri_
    dormant_listed_ = true;
}

int Interactions::insert_cracks(const double* x, const double* tri_sigma) {
    if (!has_dormant()) return 0;
    if (!dormant_listed_) list_dormant();
    // Most of a unit is far from its strength, and that is decided per triangle from its stress alone
    // (fracture::far_from_peak_surface against the smallest f_t and c of the triangle's dormant edges): an edge
    // between two far triangles (or with one far triangle on a free boundary) cannot reach the peak surface with
    // their mean stress, so only the edges with a triangle that is not far are checked below. The elements inserted
    // are the ones the check of every edge would insert.
    const int nt = static_cast<int>(dormant_tri_.size());
    int near = 0;
#pragma omp parallel for schedule(static) reduction(+ : near) if (nt >= 2048)
    for (int i = 0; i < nt; ++i) {
        const int t = dormant_tri_[i];
        const double* st = &tri_strength_[2 * static_cast<std::size_t>(t)];
        const bool far = fracture::far_from_peak_surface(tri_sigma + 3 * static_cast<std::size_t>(t), st[0], st[1]);
        near_[t] = far ? 0 : 1;
        near += far ? 0 : 1;
    }
    if (near == 0) return 0;
    const int ne = static_cast<int>(dormant_.size());
    int found = 0;
#pragma omp parallel for schedule(static) reduction(+ : found) if (ne >= 2048)
    for (int i = 0; i < ne; ++i) {
        const DormantEdge& el = dormant_edge_[i];
        if (!(el.tri_a >= 0 && near_[el.tri_a]) && !(el.tri_b >= 0 && near_[el.tri_b])) {
            due_[i] = 0;
            continue;
        }
        // Mean stress of the two sides (one side on a free boundary: its own).
        double sg[3] = {0, 0, 0};
        int sides = 0;
        for (int t : {el.tri_a, el.tri_b})
            if (t >= 0) {
                const double* q = tri_sigma + 3 * static_cast<std::size_t>(t);
                sg[0] += q[0], sg[1] += q[1], sg[2] += q[2], ++sides;
            }
        // (x / 2 and x * 0.5 are the same bits, as x / 1 and x: no division)
        const double inv_sides = sides == 2 ? 0.5 : 1.0;
        for (double& q : sg) q *= inv_sides;
        // Frame of the element (cohesive_system.cpp): t along edge A's a0 -> a1, n = (t_y, -t_x) into side B, here
        // not normalised: both tractions are quadratic in (t, n), so one division by |t|^2 does it.
        const double tx = x[2 * el.n1] - x[2 * el.n0], ty = x[2 * el.n1 + 1] - x[2 * el.n0 + 1];
        const double nx = ty, ny = -tx;
        const double inv_len2 = 1.0 / (tx * tx + ty * ty);
        // Traction on the plane of normal n: T = sigma n; sigma_n = n.T, tau = t.T.
        const double Tx = sg[0] * nx + sg[2] * ny, Ty = sg[2] * nx + sg[1] * ny;
        const double sn = (Tx * nx + Ty * ny) * inv_len2, tau = (Tx * tx + Ty * ty) * inv_len2;
        // (CohesiveSystem::reaches_strength on the copied constants)
        const bool due = fracture::reaches_peak_surface(sn, tau, el.tensile_strength, el.cohesion, el.tan_friction);
        due_[i] = due;
        if (due) {
            due_traction_[2 * static_cast<std::size_t>(i)] = sn;
            due_traction_[2 * static_cast<std::size_t>(i) + 1] = tau;
        }
        found += due;
    }
    if (found == 0) return 0;
    std::vector<fracture::CohesiveSystem::Insertion> list;
    for (int i = 0; i < ne; ++i)
        if (due_[i]) list.push_back({dormant_[i], due_traction_[2 * static_cast<std::size_t>(i)], due_traction_[2 * static_cast<std::size_t>(i) + 1]});
    joints_->insert(list);
    list_dormant();
    return found;
}

void Interactions::add_forces(const double* x, const double* v, double dt, double* f, double* after_joints,
                              std::size_t n, double v2max) {
    if (joints_) joints_->add_forces(x, f);
    if (after_joints) std::copy(f, f + n, after_joints);
    if (contact_) contact_->step(x, v, dt, f, v2max);
}

int Interactions::after_step(double time, double control_displacement, const double* x) {
    if (!joints_) return 0;
    const auto broken = joints_->update_damage(time, control_displacement, x);
    if (broken.empty()) return 0;
    std::ostringstream os;
    for (const auto& r : broken) {
        fracture::write_cracks_csv_row(os, r);
        if (contact_) {
            if (r.tri_a >= 0) contact_->set_capable(r.tri_a, true);
            if (r.tri_b >= 0) contact_->set_capable(r.tri_b, true);
            if (r.tri_a >= 0 && r.tri_b >= 0) contact_->include_pair(r.tri_a, r.tri_b);
            for (int k : joints_->element(r.element).n) contact_->release_vertex_of(k);
        }
    }
    cracks_csv_ += os.str();
    return static_cast<int>(broken.size());
}

void Interactions::joint_motion(const int* n, const double* x, double& opening, double& slip) {
    // n = {a0, a1, b0, b1}; a0 -> a1 runs counter-clockwise around side A, so n = (s_y, -s_x) points into B.
    double sx = x[2 * n[1]] - x[2 * n[0]], sy = x[2 * n[1] + 1] - x[2 * n[0] + 1];
    const double len = std::hypot(sx, sy);
    if (len <= 0) {
        opening = slip = 0;
        return;
    }
    sx /= len, sy /= len;
    const double d0x = x[2 * n[2]] - x[2 * n[0]], d0y = x[2 * n[2] + 1] - x[2 * n[0] + 1];
    const double d1x = x[2 * n[3]] - x[2 * n[1]], d1y = x[2 * n[3] + 1] - x[2 * n[1] + 1];
    opening = std::max(d0x * sy - d0y * sx, d1x * sy - d1y * sx);
    slip = 0.5 * ((d0x + d1x) * sx + (d0y + d1y) * sy);
}

int Interactions::record_dry_joints(double time, double control_displacement, const double* x) {
    int rows = 0;
    std::ostringstream os;
    os.precision(10);
    for (int e = 0; e < static_cast<int>(dry_.size()); ++e) {
        if (dry_open_[e] && dry_slip_[e]) continue;
        const auto& d = dry_[e];
        double opening, slip;
        joint_motion(d.n.data(), x, opening, slip);
        opening -= dry_motion0_[2 * e], slip -= dry_motion0_[2 * e + 1];
        const double r_open = opening / open_thr_, r_slip = std::abs(slip) / slip_thr_;
        for (int mode = 0; mode < 2; ++mode) {
            char& seen = mode == 0 ? dry_open_[e] : dry_slip_[e];
            if (seen || (mode == 0 ? r_open : r_slip) <= 1) continue;
            seen = 1;
            ++(mode == 0 ? n_open_ : n_slip_);
            ++rows;
            double mx = 0, my = 0;
            for (int k = 0; k < 4; ++k) mx += 0.25 * x[2 * d.n[k]], my += 0.25 * x[2 * d.n[k] + 1];
            // The columns of fracture::write_cracks_csv_header.
            os << time << ',' << control_displacement << ',' << mx << ',' << my << ",interface-dry," << d.body_a << ','
               << d.body_b << ',' << (mode == 0 ? "open" : "slip") << ',' << r_open << ',' << r_slip << ',' << e << ','
               << d.tri_a << ',' << d.tri_b << ',' << dry_len_[e] << ',' << dry_ref_mid_[2 * e] << ','
               << dry_ref_mid_[2 * e + 1] << '\n';
        }
    }
    if (rows) cracks_csv_ += os.str();
    return rows;
}

double Interactions::joint_energy() const { return joints_ ? joints_->elastic_energy() : 0.0; }
double Interactions::contact_energy(const double* x_n) const {
    if (!contact_) return 0.0;
    if (contact_->normal_energy_current()) return contact_->elastic_energy();
    // The last step skipped the normal energy (only reported steps evaluate it): evaluate it now at x^n.
    return contact_->normal_energy_at(x_n) + contact_->tangential_energy();
}
double Interactions::fracture_dissipation() const { return joints_ ? joints_->dissipated_energy() : 0.0; }
// Contact friction plus the friction of cohesive elements that keep it while their cohesion softens.
double Interactions::friction_dissipation() const {
    return (contact_ ? contact_->friction_dissipation() : 0.0) + (joints_ ? joints_->friction_energy() : 0.0);
}

// Checkpoint. The sizeof guard fails the build when a field is added to Interactions (x86-64 libstdc++): add the
// field to save_state and load_state if it changes during a run, then update the size.
void Interactions::save_state(StateWriter& w) const {
#if defined(__x86_64__) && defined(__GLIBCXX__)
    static_assert(sizeof(Interactions) == 424, "Interactions changed: update state_io and this size");
#endif
    const_cast<Interactions*>(this)->state_io(w);  // (the writer only reads the fields)
}

void Interactions::load_state(StateReader& r) { state_io(r); }

template <class IO>
void Interactions::state_io(IO& io) {
    io.section("interactions");
    io.str(cracks_csv_);
    io.vec_sized(dry_open_, dry_.size(), "dry joint open flags");
    io.vec_sized(dry_slip_, dry_.size(), "dry joint slip flags");
    io.pod(n_open_), io.pod(n_slip_);
    std::uint8_t has_c = contact_ != nullptr, has_j = joints_ != nullptr;
    io.pod(has_c), io.pod(has_j);
    if constexpr (IO::loading)
        if ((has_c != 0) != (contact_ != nullptr) || (has_j != 0) != (joints_ != nullptr))
            throw StateError("interactions: another set of modules");
    if constexpr (IO::loading) {
        if (contact_) contact_->load_state(io);
        if (joints_) joints_->load_state(io);
        dormant_listed_ = false;  // (the joints' dormant set is the saved one: listed again by the next insertion check)
    } else {
        if (contact_) contact_->save_state(io);
        if (joints_) joints_->save_state(io);
    }
}

}  // namespace fdem
