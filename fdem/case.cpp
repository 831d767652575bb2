// fdem/case.cpp: TOML case file -> validated CaseSpec (toml++ from Debian; no hand-written parser): the file and its
// --set / --unset overrides, the case hash, and the sections other than [geometry] (fdem/case_geometry.cpp) and
// [[stages]] (fdem/case_stages.cpp); the error context and the table reader they share: fdem/case_reader.hpp.
#include "fdem/case.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <set>
#include <sstream>

#include "fdem/case_json.hpp"
#include "fdem/load.hpp"
#include "fdem/case_reader.hpp"
#include "fdem/common/errors.hpp"

namespace fdem {

using namespace case_detail;

namespace {

// --set a.b.1.c=value: parse the value as TOML (a bare word becomes a string) and put it into the tree. Array
// elements count from 1 (stages.1 is the first stage), as in the logs, the history's stage column and the messages.
long array_index(const std::string& p, std::size_t size) {
    char* end = nullptr;
    const long idx = std::strtol(p.c_str(), &end, 10);
    if (p.empty() || *end || idx < 1 || static_cast<std::size_t>(idx) > size) return -1;
    return idx - 1;
}

// '!' KEY (fdem --unset KEY): removes the key, so that its default applies.
void apply_unset(toml::table& root, const std::string& path, Ctx& ctx) {
    std::vector<std::string> parts;
    std::stringstream ss(path);
    for (std::string p; std::getline(ss, p, '.');) parts.push_back(p);
    toml::node* cur = &root;
    for (std::size_t i = 0; i + 1 < parts.size() && cur; ++i) {
        if (auto* t = cur->as_table()) cur = t->get(parts[i]);
        else if (auto* a = cur->as_array()) {
            const long idx = array_index(parts[i], a->size());
            cur = idx < 0 ? nullptr : a->get(static_cast<std::size_t>(idx));
        } else cur = nullptr;
    }
    toml::table* t = cur ? cur->as_table() : nullptr;
    if (parts.empty() || !t || !t->contains(parts.back()))
        throw InputError("--unset " + path + ": no such key in " + ctx.file + " (or the --set options before it)");
    t->erase(parts.back());
    ctx.set_paths.insert(path);
}

void apply_override(toml::table& root, const std::string& spec, Ctx& ctx) {
    if (!spec.empty() && spec[0] == '!') return apply_unset(root, spec.substr(1), ctx);
    const auto eq = spec.find('=');
    if (eq == std::string::npos || eq == 0) throw InputError("--set " + spec + ": expected key=value, e.g. --set materials.stone.E=1e9");
    const std::string path = spec.substr(0, eq), value = spec.substr(eq + 1);
    toml::table parsed;
    try {
        parsed = toml::parse("v = " + value);
    } catch (const toml::parse_error&) {
        parsed = toml::table{{"v", value}};
    }
    std::vector<std::string> parts;
    std::stringstream ss(path);
    for (std::string p; std::getline(ss, p, '.');) parts.push_back(p);
    toml::node* cur = &root;
    for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
        const std::string& p = parts[i];
        if (auto* t = cur->as_table()) {
            if (!t->contains(p)) t->insert(p, toml::table{});
            cur = t->get(p);
        } else if (auto* a = cur->as_array()) {
            const long idx = array_index(p, a->size());
            if (idx < 0)
                throw InputError("--set " + spec + ": '" + p + "' is not an index of the array (1.." +
                                 std::to_string(a->size()) + "; elements count from 1)");
            cur = a->get(static_cast<std::size_t>(idx));
        } else {
            throw InputError("--set " + spec + ": '" + parts[i - 1] + "' is a value, not a table");
        }
    }
    const std::string& last = parts.back();
    const toml::node* v = parsed.get("v");
    if (auto* t = cur->as_table()) {
        v->visit([&](auto&& val) { t->insert_or_assign(last, val); });
    } else if (auto* a = cur->as_array()) {
        const long idx = array_index(last, a->size());
        if (idx < 0)
            throw InputError("--set " + spec + ": '" + last + "' is not an index of the array (1.." +
                             std::to_string(a->size()) + "; elements count from 1)");
        v->visit([&](auto&& val) { a->replace(a->cbegin() + idx, val); });
    } else {
        throw InputError("--set " + spec + ": the parent of '" + last + "' is a value, not a table");
    }
    ctx.set_paths.insert(path);
}

// Cohesive keys shared by [materials.NAME.fracture] and bonded [[interfaces]]; stiffness keys only where allowed.
void read_joint(Reader& r, JointSpec& j, bool allow_stiffness) {
    auto positive = [](double v) { return v > 0; };
    auto angle = [](double v) { return v >= 0 && v < 90; };
    j.present = true;
    j.line = r.line();
    j.tensile_strength = r.number("tensile_strength", true, "a tensile strength f_t >= 0 in Pa", [](double v) { return v >= 0; }).value_or(std::nan(""));
    j.cohesion = r.number("cohesion", true, "a cohesion c >= 0 in Pa", [](double v) { return v >= 0; }).value_or(std::nan(""));
    j.friction = r.number("friction", true, "a friction angle in [0, 90) deg", angle).value_or(std::nan(""));
    j.residual_friction = r.number("residual_friction", false, "a residual friction angle in [0, 90) deg (default: friction)", angle).value_or(j.friction);
    // law: "k25" (default, also "K25": the [K25] softening law, fracture/law.hpp), "composite" (below) or
    // "mohr_coulomb" (fracture/mc_law.hpp, the M-DEM spring layers: no softening, so no G_I, G_II).
    const std::string law = r.string("law", false, "the joint law: \"k25\" (default), \"composite\" or \"mohr_coulomb\"",
                                     {"k25", "K25", "composite", "mohr_coulomb"})
                                .value_or("k25");
    j.mohr_coulomb = law == "mohr_coulomb";
    j.composite = law == "composite";
    j.GI = r.number("GI", !j.mohr_coulomb, "a mode I fracture energy > 0 in J/m^2", positive).value_or(std::nan(""));
    j.GII = r.number("GII", !j.mohr_coulomb, "a mode II fracture energy > 0 in J/m^2", positive).value_or(std::nan(""));
    // penalty: a number (p_j, Pa) or "auto": p_j from the element size, fracture/README.md "Mesh-aware penalty".
    const char* kPenalty = "a joint penalty p_j > 0 in Pa or \"auto\"";
    if (const toml::node* pn = r.node("penalty", false, kPenalty); pn && pn->is_string()) {
        if (*pn->value<std::string>() == "auto") j.penalty_auto = true;
        else r.number("penalty", false, kPenalty, positive);  // reports the key, the line and what was expected
    } else {
        j.penalty = r.number("penalty", false, kPenalty, positive).value_or(std::nan(""));
    }
    j.penalty_ref = r.number("penalty_ref", false, "a reference joint penalty > 0 in Pa (with penalty = \"auto\")", positive)
                        .value_or(std::nan(""));
    if (j.mohr_coulomb && j.penalty_auto)
        r.number("penalty", false, "a joint penalty p_j > 0 in Pa (\"auto\" needs G_I, G_II: not with law = \"mohr_coulomb\")",
                 [](double) { return false; });
    if (!std::isnan(j.penalty_ref) && !j.penalty_auto)
        r.number("penalty_ref", false, "penalty_ref only with penalty = \"auto\"", [](double) { return false; });
    // "strength" ([K25]): the whole shear strength c + |sigma| tan(phi) softens; "cohesion" ([LR97]): only c does,
    // the friction is kept (fracture/law.hpp).
    j.keep_friction = r.string("shear_softening", false, "what softens in shear", {"strength", "cohesion"})
                          .value_or("strength") == "cohesion";
    // Compressive cap f_c (fracture/law.hpp): optional; without it the compression is an unbounded penalty.
    j.compressive_strength = r.number("compressive_strength", false, "a compressive strength f_c > 0 in Pa", positive)
                                 .value_or(std::nan(""));
    // law = "composite" (fracture/composite_law.hpp, [PDEM] §2): bilinear tension / shear / compression, friction
    // kept, the cap sigma^2 + C_s tau^2 = f_m^2 of [LR97] (compressive_strength = f_m, compressive_energy = G_c,
    // cap_shear_factor = C_s: all three or none). The cap keys below belong to it alone.
    j.compressive_energy =
        r.number("compressive_energy", false, "a compressive fracture energy G_c > 0 in J/m^2", positive)
            .value_or(std::nan(""));
    j.cap_shear_factor = r.number("cap_shear_factor", false, "a cap shear factor C_s > 0 (dimensionless)", positive)
                             .value_or(std::nan(""));
    if (!j.composite && (!std::isnan(j.compressive_energy) || !std::isnan(j.cap_shear_factor))) {
        const char* key = !std::isnan(j.compressive_energy) ? "compressive_energy" : "cap_shear_factor";
        r.number(key, false, std::string(key) + " only with law = \"composite\"", [](double) { return false; });
    }
    if (j.composite) {
        if (j.keep_friction)
            r.number("shear_softening", false, "no shear_softening with law = \"composite\" (it keeps the friction)");
        const int cap_keys = !std::isnan(j.compressive_strength) + !std::isnan(j.compressive_energy) +
                             !std::isnan(j.cap_shear_factor);
        if (cap_keys != 0 && cap_keys != 3)
            r.number("law", false, "law = \"composite\" with all three cap keys (compressive_strength, compressive_energy, "
                                   "cap_shear_factor) or none");  // a string: reported with this expectation
    }
    if (allow_stiffness) {
        j.normal_stiffness = r.number("normal_stiffness", false, "a normal stiffness k_n > 0 in Pa/m", positive).value_or(std::nan(""));
        j.shear_stiffness = r.number("shear_stiffness", false, "a shear stiffness k_s > 0 in Pa/m", positive).value_or(std::nan(""));
    }
}

}  // namespace

double TimeFunction::operator()(double tau) const {
    if (type == "sin") return offset + amplitude * std::sin(omega * tau + phase);
    if (type == "table") {
        if (tau <= t.front()) return f.front();
        if (tau >= t.back()) return f.back();
        const std::size_t i = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), tau) - t.begin());
        return f[i - 1] + (tau - t[i - 1]) / (t[i] - t[i - 1]) * (f[i] - f[i - 1]);
    }
    return 1.0;
}

std::string MonitorSpec::unit() const {
    if (type == "displacement") return "m";
    if (type == "velocity") return "m/s";
    if (type == "tilt" || type == "rotation") return "deg";
    return "N";
}

int CaseSpec::material_index(const std::string& n) const {
    for (std::size_t i = 0; i < materials.size(); ++i)
        if (materials[i].name == n) return static_cast<int>(i);
    return -1;
}

const MonitorSpec* CaseSpec::find_monitor(const std::string& n) const {
    for (const auto& m : monitors)
        if (m.name == n) return &m;
    return nullptr;
}

// The [case] table: name, description, thickness, plane.
static void read_case_table(Ctx& ctx, Reader& top, CaseSpec& spec) {
    if (const toml::table* t = top.table("case", true, "a [case] table")) {
        Reader r(ctx, *t, "case");
        spec.name = r.string("name", true, "a case name").value_or("");
        spec.description = r.string("description", false, "a text").value_or("");
        spec.thickness = r.number("thickness", true, "an out-of-plane thickness in [1e-6, 1e4] m",
                                  [](double v) { return v >= kMinLength && v <= kMaxLength; }).value_or(1.0);
        spec.plane = r.string("plane", false, "\"stress\" or \"strain\"", {"stress", "strain"}).value_or("stress") == "strain"
                         ? Plane::strain
                         : Plane::stress;
        r.finish();
    }
}

// The [materials.NAME] tables (with their fracture and crushing tables), [regions] and [groups.NAME].
static void read_materials(Ctx& ctx, Reader& top, CaseSpec& spec) {
    auto positive = [](double v) { return v > 0; };
    if (const toml::table* t = top.table("materials", true, "a [materials.NAME] table per material")) {
        for (const auto& [k, v] : *t) {
            Material m;
            m.name = std::string(k.str());
            const std::string p = "materials." + m.name;
            if (!v.is_table()) {
                ctx.error(p, line_of(&v), "expected a table of material properties (E, nu, density)");
                continue;
            }
            Reader r(ctx, *v.as_table(), p);
            m.line = r.line();
            m.E = r.number("E", true, "Young's modulus > 0 in Pa", positive).value_or(1);
            m.nu = r.number("nu", true, "Poisson's ratio in (-1, 0.5)", [](double x) { return x > -1 && x < 0.5; }).value_or(0);
            m.density = r.number("density", true, "a density in [1e-3, 1e6] kg/m^3", [](double rho) { return rho >= 1e-3 && rho <= 1e6; }).value_or(1);
            m.viscous_damping = r.number("viscous_damping", false, "a fraction of critical damping in [0, 1]",
                                         [](double x) { return x >= 0 && x <= 1; }).value_or(0);
            if (const toml::table* ft = r.table("fracture", false, "a [materials.NAME.fracture] table")) {
                Reader fr(ctx, *ft, p + ".fracture");
                read_joint(fr, m.fracture, false);
                // insertion: "intrinsic" (default: a cohesive element on every crackable edge from the start) or
                // "extrinsic" (the unit is one continuum, its copies tied, until an edge's traction reaches the
                // strength; the element is then inserted at the peak of the [K25] law, fracture/README.md
                // "Extrinsic insertion").
                m.fracture.extrinsic = fr.string("insertion", false, "when the cohesive elements join the model",
                                                 {"intrinsic", "extrinsic"})
                                           .value_or("intrinsic") == "extrinsic";
                // contact_penalty: the crack faces' normal penalty once an element has broken (default: p_j).
                m.fracture.contact_penalty =
                    fr.number("contact_penalty", false, "a contact penalty > 0 in Pa for the crack faces (default: the penalty p_j)",
                              positive)
                        .value_or(std::nan(""));
                if (m.fracture.extrinsic && (m.fracture.composite || m.fracture.mohr_coulomb))
                    fr.number("insertion", false, "insertion = \"extrinsic\" only with the [K25] law (law = \"k25\")",
                              [](double) { return false; });  // a string: reported with this expectation
                if (std::isnan(m.fracture.penalty) && !m.fracture.penalty_auto)
                    ctx.error(p + ".fracture.penalty", fr.line(), "missing; expected a joint penalty p_j > 0 in Pa (it also "
                                                                  "serves as the contact penalty of the crack faces)");
                fr.finish();
            }
            // Compression softening of the triangles (fdem/plasticity.hpp).
            if (const toml::table* ct = r.table("crushing", false, "a [materials.NAME.crushing] table")) {
                Reader cr(ctx, *ct, p + ".crushing");
                m.crushing.present = true;
                m.crushing.line = cr.line();
                m.crushing.compressive_strength =
                    cr.number("compressive_strength", true, "a compressive strength f_c > 0 in Pa", positive).value_or(std::nan(""));
                m.crushing.Gc = cr.number("Gc", true, "a compressive fracture energy G_c > 0 in J/m^2", positive).value_or(std::nan(""));
                cr.finish();
            }
            if (m.crushing.present && m.fracture.extrinsic)
                ctx.error(p + ".fracture.insertion", m.fracture.line,
                          "\"extrinsic\" is not available with a [" + p + ".crushing] table (the insertion test reads the "
                          "elastic stress); expected \"intrinsic\"");
            r.finish();
            spec.materials.push_back(m);
        }
        if (spec.materials.empty()) ctx.error("materials", line_of(t), "expected at least one [materials.NAME] table");
    }

    if (const toml::table* t = top.table("regions", true, "a [regions] table mapping each region to a material")) {
        for (const auto& [k, v] : *t) {
            const std::string p = "regions." + std::string(k.str());
            if (!v.is_string()) {
                ctx.error(p, line_of(&v), "expected the name of a material, got " + describe(v));
                continue;
            }
            const std::string mat = *v.value<std::string>();
            if (spec.material_index(mat) < 0)
                ctx.error(p, line_of(&v), "no material named '" + mat + "' in [materials]");
            spec.region_material[std::string(k.str())] = mat;
        }
    }

    if (const toml::table* t = top.table("groups", false, "a [groups.NAME] table per extra group")) {
        for (const auto& [k, v] : *t) {
            GroupSpec g;
            g.name = std::string(k.str());
            const std::string p = "groups." + g.name;
            if (!v.is_table()) {
                ctx.error(p, line_of(&v), "expected a table with box = [xmin, ymin, xmax, ymax] or nearest = [x, y]");
                continue;
            }
            Reader r(ctx, *v.as_table(), p);
            g.line = r.line();
            if (auto b = r.numbers("box", false, "[xmin, ymin, xmax, ymax] in m", 4)) {
                g.box = std::array<double, 4>{(*b)[0], (*b)[1], (*b)[2], (*b)[3]};
                if (!((*b)[2] >= (*b)[0] && (*b)[3] >= (*b)[1])) ctx.error(p + ".box", g.line, "expected xmin <= xmax and ymin <= ymax");
            }
            g.nearest = r.vec2("nearest", false, "[x, y] in m");
            g.within = r.string("within", false, "the name of a physical group to select from").value_or("");
            if (g.box.has_value() == g.nearest.has_value()) ctx.error(p, g.line, "give exactly one of box or nearest");
            r.finish();
            spec.groups.push_back(g);
        }
    }
}

// The [[interfaces]] blocks and the [contact] table.
static void read_interfaces(Ctx& ctx, Reader& top, CaseSpec& spec) {
    auto positive = [](double v) { return v > 0; };
    for (const toml::table* t : top.tables("interfaces", false, "[[interfaces]] blocks")) {
        const std::string p = "interfaces." + std::to_string(spec.interfaces.size() + 1);
        Reader r(ctx, *t, p);
        InterfaceSpec in;
        in.line = r.line();
        const toml::node* regs = r.node("regions", true, "the two regions that meet, e.g. [\"units\", \"units\"]");
        if (regs) {
            const toml::array* a = regs->as_array();
            if (!a || a->size() != 2 || !(*a)[0].is_string() || !(*a)[1].is_string())
                ctx.error(p + ".regions", line_of(regs), "expected two region names, e.g. [\"units\", \"beam\"]");
            else
                in.region_a = *(*a)[0].value<std::string>(), in.region_b = *(*a)[1].value<std::string>();
        }
        in.kind = r.string("kind", true, "how the regions meet", {"tied", "bonded", "dry"}).value_or("tied");
        if (in.kind == "dry") {
            in.friction = r.number("friction", true, "a friction angle in [0, 90) deg", [](double v) { return v >= 0 && v < 90; }).value_or(0);
            in.normal_penalty = r.number("normal_penalty", false, "a normal penalty p_n > 0 in Pa", positive).value_or(std::nan(""));
            in.normal_stiffness = r.number("normal_stiffness", false, "a normal stiffness k_n > 0 in Pa/m", positive).value_or(std::nan(""));
            in.tangential_penalty = r.number("tangential_penalty", false, "a tangential penalty p_t > 0 in Pa", positive).value_or(std::nan(""));
            in.shear_stiffness = r.number("shear_stiffness", false, "a shear stiffness k_s > 0 in Pa/m", positive).value_or(std::nan(""));
            in.restitution = r.number("restitution", false, "a coefficient of restitution e in (0, 1] (1: elastic)",
                                      [](double v) { return v > 0 && v <= 1; }).value_or(1.0);
            if (std::isnan(in.normal_penalty) == std::isnan(in.normal_stiffness))
                ctx.error(p, in.line, "give exactly one of normal_penalty (Pa) or normal_stiffness (Pa/m)");
            if (!std::isnan(in.tangential_penalty) && !std::isnan(in.shear_stiffness))
                ctx.error(p, in.line, "give at most one of tangential_penalty (Pa) or shear_stiffness (Pa/m)");
        } else if (in.kind == "bonded") {
            read_joint(r, in.bond, true);
            const bool pen = !std::isnan(in.bond.penalty) || in.bond.penalty_auto, kn = !std::isnan(in.bond.normal_stiffness), ks = !std::isnan(in.bond.shear_stiffness);
            if (pen == (kn || ks) || kn != ks)
                ctx.error(p, in.line, "give either penalty (Pa) or both normal_stiffness and shear_stiffness (Pa/m)");
        }
        r.finish();
        for (const auto& other : spec.interfaces)
            if ((other.region_a == in.region_a && other.region_b == in.region_b) || (other.region_a == in.region_b && other.region_b == in.region_a))
                ctx.error(p + ".regions", in.line, "the pair " + in.region_a + "/" + in.region_b + " already has an interface rule");
        spec.interfaces.push_back(in);
    }
    if (const toml::table* t = top.table("contact", false, "a [contact] table")) {
        Reader r(ctx, *t, "contact");
        spec.contact_buffer = r.number("buffer", false, "an NBS buffer > 0 in m", [](double v) { return v > 0; }).value_or(0);
        r.finish();
    }
}

// The [[monitors]] and [[initial]] blocks.
static void read_monitors(Ctx& ctx, Reader& top, CaseSpec& spec) {
    for (const toml::table* t : top.tables("monitors", false, "[[monitors]] blocks")) {
        const std::string p = "monitors." + std::to_string(spec.monitors.size() + 1);
        Reader r(ctx, *t, p);
        MonitorSpec m;
        m.line = r.line();
        m.name = r.string("name", true, "a column name for history.csv").value_or("");
        m.type = r.string("type", true, "the monitored quantity",
                          {"displacement", "velocity", "reaction", "load", "tilt", "rotation"}).value_or("displacement");
        if (m.type != "tilt") m.group = r.string("group", true, "the name of a group").value_or("");
        if (m.type != "tilt" && m.type != "rotation")
            m.component = component_index(r.string("component", true, "\"x\" or \"y\"", kComponents).value_or("x"));
        r.finish();
        static const std::set<std::string> reserved{"time", "step", "stage", "E_kin", "E_el", "E_joint", "E_contact",
                                                    "W_ext", "D_damp", "D_visc", "D_frac", "D_fric", "E_balance",
                                                    "unbalanced"};
        if (reserved.count(m.name) || spec.find_monitor(m.name))
            ctx.error(p + ".name", m.line, "the name '" + m.name + "' is already used by another column");
        if (!m.name.empty() && m.name.find_first_of(", \"\n") != std::string::npos)
            ctx.error(p + ".name", m.line, "expected a name without commas, spaces or quotes");
        spec.monitors.push_back(m);
    }

    for (const toml::table* t : top.tables("initial", false, "[[initial]] blocks")) {
        const std::string p = "initial." + std::to_string(spec.initial.size() + 1);
        Reader r(ctx, *t, p);
        InitialSpec in;
        in.line = r.line();
        in.group = r.string("group", true, "the name of a group or region").value_or("");
        in.velocity = r.vec2("velocity", false, "[vx, vy] in m/s").value_or(std::array<double, 2>{0, 0});
        const auto w = r.number("angular_velocity", false, "an angular velocity in rad/s (counter-clockwise)");
        const auto rot = r.number("rotation", false, "a rotation of the placement in deg (counter-clockwise)",
                                  [](double v) { return std::fabs(v) <= 360; });
        const auto c = r.vec2("center", w || rot, "[x, y] in m, the centre of the rotation");
        if (!w && !rot && !r.has("velocity"))
            ctx.error(p, in.line, "give velocity, angular_velocity or rotation");
        in.angular_velocity = w.value_or(0.0);
        in.rotation = rot.value_or(0.0);
        if (c) in.center = *c;
        r.finish();
        spec.initial.push_back(in);
    }
}

// The [numerics], [output] and [reference] tables.
static void read_numerics(Ctx& ctx, Reader& top, CaseSpec& spec) {
    auto positive = [](double v) { return v > 0; };
    if (const toml::table* t = top.table("numerics", false, "a [numerics] table")) {
        Reader r(ctx, *t, "numerics");
        // Above 1 the run is unstable; allowed up to 4 so that the stability limit itself can be tested.
        spec.safety = r.number("safety", false, "a time-step safety factor in (0, 4] (above 1 the run is unstable)",
                               [](double v) { return v > 0 && v <= 4; }).value_or(0.8);
        if (auto dt = r.number("dt", false, "a fixed time step > 0 in s", positive)) spec.dt_override = dt;
        spec.mass_scale = r.number("mass_scale", false, "an inertial mass multiplier in [1, 1e12] (quasi-static density scaling)",
                                   [](double v) { return v >= 1 && v <= 1e12; }).value_or(1.0);
        spec.per_node_mass = r.string("mass_scaling", false,
                                      "\"uniform\" (every mass times mass_scale) or \"per_node\" (and nodes whose springs "
                                      "need it heavier, for the triangles' time step)",
                                      {"uniform", "per_node"}).value_or("uniform") == "per_node";
        spec.energy_audit = r.boolean("energy_audit", false, "true or false (the energy books of each part, in run.log)")
                                .value_or(false);
        r.finish();
    }

    if (const toml::table* t = top.table("output", false, "an [output] table")) {
        Reader r(ctx, *t, "output");
        spec.history_interval = r.number("history_interval", false, "an interval > 0 in s", positive).value_or(0);
        spec.snapshot_interval = r.number("snapshot_interval", false, "an interval > 0 in s", positive).value_or(0);
        spec.checkpoint_interval =
            r.number("checkpoint_interval", false, "a checkpoint interval > 0 in s of simulated time", positive).value_or(0);
        spec.checkpoint_wall_interval =
            r.number("checkpoint_wall_interval", false, "a checkpoint interval > 0 in s of wall-clock time", positive).value_or(0);
        spec.joint_open = r.number("joint_open", false, "the opening of a dry joint that is recorded, > 0 in m", positive)
                              .value_or(spec.joint_open);
        spec.joint_slip = r.number("joint_slip", false, "the slip of a dry joint that is recorded, > 0 in m", positive)
                              .value_or(spec.joint_slip);
        if (const toml::table* c = r.table("curve", false, "a table { x = MONITOR, y = MONITOR, sign = 1 or -1 (optional) }")) {
            Reader cr(ctx, *c, "output.curve");
            spec.curve_x = cr.string("x", true, "the monitor of the control displacement").value_or("");
            spec.curve_y = cr.string("y", true, "the monitor of the load").value_or("");
            spec.curve_sign = static_cast<int>(
                cr.number("sign", false, "1 or -1: the factor that makes the load positive while loading (the tools' "
                                         "load sign; without it they take the sign of positive loading work)",
                          [](double v) { return v == 1.0 || v == -1.0; })
                    .value_or(0.0));
            cr.finish();
            for (const auto* n : {&spec.curve_x, &spec.curve_y})
                if (!n->empty() && !spec.find_monitor(*n))
                    ctx.error("output.curve", cr.line(), "no monitor named '" + *n + "' in [[monitors]]");
        }
        r.finish();
    }

    if (const toml::table* t = top.table("reference", false, "a [reference] table")) {
        Reader r(ctx, *t, "reference");
        ReferenceSpec& ref = spec.reference;
        ref.present = true;
        ref.monitor = r.string("monitor", true, "the monitor compared with the reference").value_or("");
        ref.quantity = r.string("quantity", false, "\"peak\", \"first_peak\" (before the first cohesive break) or \"final\"",
                                {"peak", "first_peak", "final"})
                           .value_or("peak");
        ref.value = r.number("value", true, "the reference value in the monitor's unit").value_or(0);
        ref.tolerance = r.number("tolerance", false, "a relative tolerance >= 0", [](double v) { return v >= 0; }).value_or(0);
        ref.source = r.string("source", true, "where the reference value comes from").value_or("");
        if (!ref.monitor.empty() && !spec.find_monitor(ref.monitor))
            ctx.error("reference.monitor", r.line(), "no monitor named '" + ref.monitor + "' in [[monitors]]");
        r.finish();
    }
}

// The case file's TOML tree with the overrides applied in order (load_case, resolved_case_tree).
static toml::table read_tree(const std::string& path, const std::vector<std::string>& overrides, Ctx& ctx) {
    if (!std::filesystem::exists(path)) throw InputError(path + ": no such case file");
    toml::table root;
    try {
        root = toml::parse_file(path);
    } catch (const toml::parse_error& e) {
        throw InputError(path + ":" + std::to_string(e.source().begin.line) + ": TOML syntax error: " +
                         std::string(e.description()));
    }
    for (const auto& o : overrides) apply_override(root, o, ctx);
    return root;
}

toml::table resolved_case_tree(const std::string& path, const std::vector<std::string>& overrides) {
    Ctx ctx;
    ctx.file = path;
    return read_tree(path, overrides, ctx);
}

CaseSpec load_case(const std::string& path, const std::vector<std::string>& overrides, std::vector<std::string>* keys_read) {
    namespace fs = std::filesystem;
    Ctx ctx;
    ctx.file = path;
    toml::table root = read_tree(path, overrides, ctx);
    CaseSpec spec;
    spec.file = path;
    spec.dir = fs::path(path).parent_path().string();
    for (const auto& o : overrides) {
        if (!o.empty() && o[0] == '!') {
            spec.overrides.emplace_back(o.substr(1), "(unset)");
            continue;
        }
        const auto eq = o.find('=');
        spec.overrides.emplace_back(o.substr(0, eq), o.substr(eq + 1));
    }
    {
        // The resolved case's hash (FNV-1a 64 of its TOML text without the checkpoint keys, which do not change the
        // results): a restart refuses a checkpoint of another case.
        toml::table hashed = root;
        if (toml::table* o = hashed["output"].as_table()) o->erase("checkpoint_interval"), o->erase("checkpoint_wall_interval");
        std::ostringstream text;
        text << toml::toml_formatter(hashed);
        std::uint64_t h = 1469598103934665603ull;
        for (const unsigned char c : text.str()) h = (h ^ c) * 1099511628211ull;
        spec.resolved_hash = h;
    }

    Reader top(ctx, root, "");

    read_case_table(ctx, top, spec);
    read_geometry(ctx, top, spec);
    read_materials(ctx, top, spec);
    read_interfaces(ctx, top, spec);
    read_monitors(ctx, top, spec);
    read_numerics(ctx, top, spec);
    read_stages(ctx, top, spec);
    top.finish();
    if (keys_read) keys_read->assign(ctx.keys_read.begin(), ctx.keys_read.end());
    if (!ctx.errors.empty()) throw InputError(ctx.errors);
    return spec;
}

std::vector<std::string> plausibility_warnings(const CaseSpec& spec) {
    std::vector<std::string> w;
    auto warn = [&](int line, const std::string& key, const std::string& what) {
        w.push_back(spec.file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": key '" + key + "': " + what);
    };
    for (const Material& m : spec.materials) {
        const std::string k = "materials." + m.name;
        if (m.E > 0 && m.E < 1e6)
            warn(m.line, k + ".E", "E = " + g4(m.E) + " Pa is below any masonry or rock (1e8-1e11 Pa): given in MPa? (" +
                                       g4(m.E) + " MPa = " + g4(m.E * 1e6) + " Pa)");
        else if (m.E > 1e12)
            warn(m.line, k + ".E", "E = " + g4(m.E) + " Pa is above any masonry, rock or steel (1e8-2.1e11 Pa)");
        if (m.density > 0 && m.density < 100)
            warn(m.line, k + ".density", "density = " + g4(m.density) + " kg/m^3 is below any masonry or rock "
                                         "(1500-3000 kg/m^3): given in t/m^3 or g/cm^3? (x 1000)");
        else if (m.density > 2e4)
            warn(m.line, k + ".density", "density = " + g4(m.density) + " kg/m^3 is above any solid (steel 7850)");
    }
    if (spec.thickness > 10)
        warn(0, "case.thickness", "thickness = " + g4(spec.thickness) + " m: given in mm? (" + g4(spec.thickness) +
                                      " mm = " + g4(spec.thickness * 1e-3) + " m)");
    const GeometrySpec& g = spec.geometry;
    auto length = [&](const std::string& key, double v) {
        if (v > 200)
            warn(g.line, "geometry." + key, key + " = " + g4(v) + " m is larger than any wall or building: given in mm? (" +
                                                g4(v * 1e-3) + " m)");
    };
    if (g.type == "rectangle") length("width", g.width), length("height", g.height), length("mesh_size", g.mesh_size);
    if (g.type == "wall") {
        length("length", g.wall.length), length("height", g.wall.height);
        const double unit = std::max(g.wall.unit_length, g.wall.unit_height);
        if (unit > 0 && g.wall.mesh_size > unit)
            warn(g.line, "geometry.mesh_size", "mesh_size = " + g4(g.wall.mesh_size) + " m is larger than the units (" +
                                                   g4(g.wall.unit_length) + " x " + g4(g.wall.unit_height) +
                                                   " m): each unit is meshed at its own size" +
                                                   (g.wall.mesh_size > 1 ? "; given in mm?" : ""));
    }
    return w;
}

void check_against_mesh(const CaseSpec& spec, const MeshNames& names) {
    std::vector<std::string> errors;
    auto has_group = [&](const std::string& g) {
        return std::find(names.groups.begin(), names.groups.end(), g) != names.groups.end();
    };
    std::string available;
    for (const auto& g : names.groups) available += (available.empty() ? "" : ", ") + g;
    auto missing = [&](const std::string& key, int line, const std::string& g) {
        std::string best;  // the nearest group name within two edits: a typo's likely intent
        std::size_t best_d = 3;
        for (const auto& cand : names.groups) {
            const std::size_t d = edit_distance(g, cand);
            if (d < best_d) best_d = d, best = cand;
        }
        errors.push_back(spec.file + ":" + std::to_string(line) + ": key '" + key + "': no group named '" + g +
                         "' in the mesh" + (best.empty() ? "" : "; did you mean '" + best + "'?") +
                         " (groups: " + available + ")");
    };
    for (const auto& r : names.regions)
        if (!spec.region_material.count(r))
            errors.push_back(spec.file + ": key 'regions." + r + "': missing; the mesh has a region '" + r +
                             "' and every region needs a material");
    for (const auto& [r, m] : spec.region_material)
        if (std::find(names.regions.begin(), names.regions.end(), r) == names.regions.end()) {
            std::string regs;
            for (const auto& x : names.regions) regs += (regs.empty() ? "" : ", ") + x;
            errors.push_back(spec.file + ": key 'regions." + r + "': the mesh has no region (2D physical group) named '" +
                             r + "' (regions: " + regs + ")");
        }
    for (std::size_t i = 0; i < spec.monitors.size(); ++i) {
        const auto& m = spec.monitors[i];
        if (m.type != "tilt" && !has_group(m.group)) missing("monitors." + std::to_string(i + 1) + ".group", m.line, m.group);
    }
    for (std::size_t i = 0; i < spec.initial.size(); ++i)
        if (!has_group(spec.initial[i].group))
            missing("initial." + std::to_string(i + 1) + ".group", spec.initial[i].line, spec.initial[i].group);
    for (std::size_t i = 0; i < spec.interfaces.size(); ++i)
        for (const auto* r : {&spec.interfaces[i].region_a, &spec.interfaces[i].region_b})
            if (std::find(names.regions.begin(), names.regions.end(), *r) == names.regions.end())
                errors.push_back(spec.file + ":" + std::to_string(spec.interfaces[i].line) + ": key 'interfaces." + std::to_string(i + 1) +
                                 ".regions': the mesh has no region named '" + *r + "'");
    for (std::size_t si = 0; si < spec.stages.size(); ++si) {
        const auto& s = spec.stages[si];
        for (std::size_t i = 0; i < s.loads.size(); ++i)
            if (!has_group(s.loads[i].group))
                missing("stages." + std::to_string(si + 1) + ".loads." + std::to_string(i + 1) + ".group", s.loads[i].line, s.loads[i].group);
        for (std::size_t i = 0; i < s.supports.size(); ++i)
            if (!has_group(s.supports[i].group))
                missing("stages." + std::to_string(si + 1) + ".supports." + std::to_string(i + 1) + ".group", s.supports[i].line,
                        s.supports[i].group);
        for (std::size_t i = 0; i < s.loads.size(); ++i) {
            const LoadKind* kind = find_load_kind(s.loads[i].kind);
            if (!kind || !kind->needs_edges()) continue;
            for (std::size_t g = 0; g < names.groups.size(); ++g)
                if (names.groups[g] == s.loads[i].group && names.group_dims[g] != 1)
                    errors.push_back(spec.file + ":" + std::to_string(s.loads[i].line) + ": key 'stages." + std::to_string(si + 1) +
                                     ".loads." + std::to_string(i + 1) + "." + kind->key() + "': group '" + s.loads[i].group +
                                     "' is not a curve (1D physical group); a " + kind->key() + " needs edges");
        }
    }
    if (!errors.empty()) throw InputError(errors);
}

}  // namespace fdem
