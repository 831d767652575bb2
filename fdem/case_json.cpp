// fdem/case_json.cpp: the resolved case as JSON (fdem check --json; fdem/case_json.hpp). Numbers are written by
// fdem::Json (fdem/output.hpp): the shortest text that reads back to the same double, non-finite values as null.
#include "fdem/case_json.hpp"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <sstream>

namespace fdem {

namespace {

Json num_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(); }
Json opt(const std::optional<double>& v) { return v ? Json(*v) : Json(); }
Json pair(const std::array<double, 2>& v) {
    Json a = Json::array();
    a.push_back(v[0]);
    a.push_back(v[1]);
    return a;
}
Json component(int c) { return Json(c == 0 ? "x" : "y"); }


Json time_function(const TimeFunction& f) {
    if (!f.present()) return Json();
    Json o = Json::object();
    o["type"] = f.type;
    if (f.type == "sin") {
        o["amplitude"] = f.amplitude, o["omega_rad_s"] = f.omega, o["phase_rad"] = f.phase, o["offset"] = f.offset;
    } else {
        Json pts = Json::array();
        for (std::size_t i = 0; i < f.t.size(); ++i) pts.push_back(pair({f.t[i], f.f[i]}));
        o["points"] = pts;
    }
    return o;
}

Json joint(const JointSpec& j) {
    if (!j.present) return Json();
    Json o = Json::object();
    o["law"] = j.mohr_coulomb ? "mohr_coulomb" : j.composite ? "composite" : "k25";
    o["tensile_strength_Pa"] = num_or_null(j.tensile_strength);
    o["cohesion_Pa"] = num_or_null(j.cohesion);
    o["friction_deg"] = num_or_null(j.friction);
    o["residual_friction_deg"] = num_or_null(j.residual_friction);
    o["GI_J_m2"] = num_or_null(j.GI);
    o["GII_J_m2"] = num_or_null(j.GII);
    // penalty: "auto" (p_j from the element size, at most penalty_ref) or the given p_j in Pa
    o["penalty"] = j.penalty_auto ? Json("auto") : num_or_null(j.penalty);
    o["penalty_ref_Pa"] = num_or_null(j.penalty_ref);
    o["normal_stiffness_Pa_m"] = num_or_null(j.normal_stiffness);
    o["shear_stiffness_Pa_m"] = num_or_null(j.shear_stiffness);
    o["shear_softening"] = j.keep_friction ? "cohesion" : "strength";
    o["compressive_strength_Pa"] = num_or_null(j.compressive_strength);
    o["compressive_energy_J_m2"] = num_or_null(j.compressive_energy);
    o["cap_shear_factor"] = num_or_null(j.cap_shear_factor);
    o["insertion"] = j.extrinsic ? "extrinsic" : "intrinsic";
    o["contact_penalty_Pa"] = num_or_null(j.contact_penalty);
    return o;
}

// The mesh sizes of the generated geometries: target size, and the beam's and base's (null when the geometry has no
// beam or base; their 0 = the target size resolved).
void mesh_sizes(Json& o, double size, double beam_size, double base_size, bool beam, bool base) {
    o["mesh_size_m"] = size;
    o["mesh_size_beam_m"] = beam ? Json(beam_size > 0 ? beam_size : size) : Json();
    o["mesh_size_base_m"] = base ? Json(base_size > 0 ? base_size : size) : Json();
}

Json geometry(const GeometrySpec& g) {
    Json o = Json::object();
    o["type"] = g.type;
    if (g.type == "rectangle") {
        mesh_sizes(o, g.mesh_size, 0, 0, false, false);
        o["origin_m"] = pair({g.x0, g.y0}), o["width_m"] = g.width, o["height_m"] = g.height;
    } else if (g.type == "wall") {
        mesh_sizes(o, g.wall.mesh_size, g.wall.mesh_size_beam, g.wall.mesh_size_base, g.wall.beam_height > 0,
                   g.wall.base == "slab");
    } else if (g.type == "macro") {
        mesh_sizes(o, g.macro.mesh_size, g.macro.mesh_size_beam, g.macro.mesh_size_base, g.macro.beam_height > 0,
                   g.macro.base_height > 0);
    } else if (g.type == "macro_wall") {
        mesh_sizes(o, g.macro_wall.mesh_size, g.macro_wall.mesh_size_beam, g.macro_wall.mesh_size_base,
                   g.macro_wall.beam_height > 0, g.macro_wall.base_height > 0);
    } else {  // gmsh, msh: the sizes are the file's
        o["mesh_size_m"] = Json(), o["mesh_size_beam_m"] = Json(), o["mesh_size_base_m"] = Json();
    }
    o["file"] = g.file.empty() ? Json() : Json(g.file);  // the .geo script or .msh mesh, as the engine opens it
    o["size_factor"] = g.size_factor;
    o["min_angle_deg"] = g.min_angle;
    o["split_all"] = g.split_all;
    o["joint_roughness_m"] = g.joint_roughness;
    return o;
}

Json support(const SupportSpec& s) {
    Json o = Json::object();
    o["group"] = s.group;
    o["x"] = to_string(s.mode[0]);
    o["y"] = to_string(s.mode[1]);
    o["vx_m_s"] = s.mode[0] == DofMode::velocity ? Json(s.velocity[0]) : Json();
    o["vy_m_s"] = s.mode[1] == DofMode::velocity ? Json(s.velocity[1]) : Json();
    o["ramp_s"] = s.ramp;
    if (!s.protocol_t.empty()) {
        Json pts = Json::array();
        for (std::size_t i = 0; i < s.protocol_t.size(); ++i) pts.push_back(pair({s.protocol_t[i], s.protocol_u[i]}));
        o["protocol"] = pts;  // [t (s from the stage start), u (m from the stage start)] of the protocol component
    } else {
        o["protocol"] = Json();
    }
    o["function"] = time_function(s.function);
    o["servo_ratio"] = s.servo_ratio;
    return o;
}

Json load(const LoadSpec& l) {
    Json o = Json::object();
    o["group"] = l.group;
    o["kind"] = l.kind;
    o["force_N"] = l.kind == "force" ? pair(l.force) : Json();
    o["pressure_Pa"] = l.is_pressure ? Json(l.pressure) : Json();
    if (l.is_spring) {
        o["spring_component"] = component(l.spring_component);
        o["spring_stiffness_N_m"] = l.spring_stiffness;
        o["spring_velocity_m_s"] = l.spring_velocity;
    }
    if (!l.param.empty()) {  // a kind's own parameters (fdem/load.hpp), SI units
        Json p = Json::object();
        for (const auto& [k, v] : l.param) p[k] = v;
        o["parameters"] = p;
    }
    o["ramp_s"] = l.ramp;
    o["function"] = time_function(l.function);
    return o;
}

Json numerics_json(const CaseSpec& spec) {
    Json num = Json::object();
    num["dt_fixed_s"] = opt(spec.dt_override);  // null: the time step is automatic, safety x the stable limit
    num["dt_automatic"] = !spec.dt_override.has_value();
    num["safety"] = spec.safety;
    num["mass_scale"] = spec.mass_scale;
    num["mass_scaling"] = spec.per_node_mass ? "per_node" : "uniform";
    num["energy_audit"] = spec.energy_audit;
    return num;
}

// The materials, and the regions' materials.
Json materials_json(const CaseSpec& spec, Json& regions) {
    Json mats = Json::object();
    for (const Material& m : spec.materials) {
        Json o = Json::object();
        o["E_Pa"] = m.E;
        o["nu"] = m.nu;
        o["density_kg_m3"] = m.density;
        o["viscous_damping"] = m.viscous_damping;
        o["fracture"] = joint(m.fracture);
        if (m.crushing.present) {
            Json c = Json::object();
            c["compressive_strength_Pa"] = m.crushing.compressive_strength;
            c["Gc_J_m2"] = m.crushing.Gc;
            o["crushing"] = c;
        } else {
            o["crushing"] = Json();
        }
        mats[m.name] = o;
    }
    regions = Json::object();
    for (const auto& [reg, mat] : spec.region_material) regions[reg] = mat;
    return mats;

}

Json interfaces_json(const CaseSpec& spec) {
    Json itfs = Json::array();
    for (const InterfaceSpec& in : spec.interfaces) {
        Json o = Json::object();
        Json regs = Json::array();
        regs.push_back(in.region_a);
        regs.push_back(in.region_b);
        o["regions"] = regs;
        o["kind"] = in.kind;
        o["friction_deg"] = num_or_null(in.friction);
        o["normal_penalty_Pa"] = num_or_null(in.normal_penalty);
        o["normal_stiffness_Pa_m"] = num_or_null(in.normal_stiffness);
        o["tangential_penalty_Pa"] = num_or_null(in.tangential_penalty);
        o["shear_stiffness_Pa_m"] = num_or_null(in.shear_stiffness);
        o["restitution"] = in.kind == "dry" ? Json(in.restitution) : Json();
        o["bond"] = joint(in.bond);
        itfs.push_back(o);
    }
    return itfs;

}

Json monitors_json(const CaseSpec& spec) {
    Json mons = Json::array();
    for (const MonitorSpec& m : spec.monitors) {
        Json o = Json::object();
        o["name"] = m.name;
        o["type"] = m.type;
        o["group"] = m.group.empty() ? Json() : Json(m.group);
        o["component"] = m.type == "tilt" || m.type == "rotation" ? Json() : component(m.component);
        o["unit"] = m.unit();
        mons.push_back(o);
    }
    return mons;

}

Json stages_json(const CaseSpec& spec) {
    // The damping a stage runs with: its own, else the stage before's (Simulation::stage_damping_and_gravity), from 0.
    double alpha = 0, tau = 0, xi = 0, beta = 0;
    Json stages = Json::array();
    for (const StageSpec& s : spec.stages) {
        if (s.local_damping) alpha = *s.local_damping;
        if (s.local_damping_filter) tau = *s.local_damping_filter;
        if (s.contact_damping) xi = *s.contact_damping;
        if (s.mass_damping) beta = *s.mass_damping;
        Json o = Json::object();
        o["name"] = s.name;
        o["duration_s"] = opt(s.duration);
        if (s.until_monitor) {
            Json u = Json::object();
            u["monitor"] = *s.until_monitor;
            u["value"] = s.until_value;
            o["until"] = u;
        } else {
            o["until"] = Json();
        }
        o["equilibrium"] = opt(s.equilibrium);
        o["equilibrium_reactions"] = s.equilibrium_reactions;
        o["max_duration_s"] = opt(s.max_duration);
        if (s.past_peak) {
            Json p = Json::object();
            p["load"] = s.past_peak->load, p["displacement"] = s.past_peak->displacement;
            p["drop"] = s.past_peak->drop, p["travel"] = s.past_peak->travel, p["smooth"] = s.past_peak->smooth;
            o["past_peak"] = p;
        } else {
            o["past_peak"] = Json();
        }
        o["gravity_m_s2"] = s.gravity ? pair(*s.gravity) : Json();  // null: the stage before's is kept
        o["gravity_ramp_s"] = s.gravity_ramp;
        o["tilt_rate_deg_s"] = s.tilt_rate;
        o["local_damping"] = alpha;
        o["local_damping_filter_s"] = tau;
        o["contact_damping"] = xi;
        o["mass_damping_1_s"] = beta;
        o["history_interval_s"] = s.history_interval ? *s.history_interval : spec.history_interval;
        o["snapshot_interval_s"] = s.snapshot_interval ? *s.snapshot_interval : spec.snapshot_interval;
        Json sup = Json::array();
        for (const SupportSpec& x : s.supports) sup.push_back(support(x));
        o["supports"] = sup;
        Json loads = Json::array();
        for (const LoadSpec& x : s.loads) loads.push_back(load(x));
        o["loads"] = loads;
        stages.push_back(o);
    }
    return stages;

}

// The output settings, the curve the tools read and the reference result.
void output_json(const CaseSpec& spec, Json& r) {
    Json out = Json::object();
    out["history_interval_s"] = spec.history_interval;    // 0: every 100 steps
    out["snapshot_interval_s"] = spec.snapshot_interval;  // 0: at the end of each stage
    out["checkpoint_interval_s"] = spec.checkpoint_interval;
    out["checkpoint_wall_interval_s"] = spec.checkpoint_wall_interval;
    out["joint_open_m"] = spec.joint_open;
    out["joint_slip_m"] = spec.joint_slip;
    r["output"] = out;
    if (!spec.curve_x.empty()) {
        Json c = Json::object();
        c["x"] = spec.curve_x;
        c["y"] = spec.curve_y;
        c["sign"] = spec.curve_sign != 0 ? Json(spec.curve_sign) : Json();  // null: not stated (the tools' own rule)
        r["curve"] = c;
    } else {
        r["curve"] = Json();
    }
    if (spec.reference.present) {
        const ReferenceSpec& ref = spec.reference;
        Json o = Json::object();
        o["monitor"] = ref.monitor;
        o["quantity"] = ref.quantity;
        o["value"] = ref.value;
        o["tolerance"] = ref.tolerance;
        o["source"] = ref.source;
        r["reference"] = o;
    } else {
        r["reference"] = Json();
    }
}

}  // namespace

Json toml_to_json(const toml::node& n) {
    if (const toml::table* t = n.as_table()) {
        Json o = Json::object();
        for (const auto& [k, v] : *t) o[std::string(k.str())] = toml_to_json(v);
        return o;
    }
    if (const toml::array* a = n.as_array()) {
        Json o = Json::array();
        for (const toml::node& v : *a) o.push_back(toml_to_json(v));
        return o;
    }
    if (const auto* v = n.as_string()) return Json(v->get());
    if (const auto* v = n.as_integer()) return Json(static_cast<long long>(v->get()));
    if (const auto* v = n.as_floating_point()) return Json::real(v->get());  // 1.0 stays 1.0; non-finite: null
    if (const auto* v = n.as_boolean()) return Json(v->get());
    std::ostringstream s;  // date, time, date-time
    n.visit([&](const auto& x) { s << x; });
    return Json(s.str());
}

Json resolved_values_json(const CaseSpec& spec) {
    Json r = Json::object();
    r["name"] = spec.name;
    r["description"] = spec.description;
    r["thickness_m"] = spec.thickness;
    r["plane"] = spec.plane == Plane::stress ? "stress" : "strain";
    r["geometry"] = geometry(spec.geometry);
    r["numerics"] = numerics_json(spec);
    Json regions;
    r["materials"] = materials_json(spec, regions);
    r["regions"] = regions;
    r["interfaces"] = interfaces_json(spec);
    r["contact_buffer_m"] = spec.contact_buffer;  // 0: the smallest contact edge / 5
    r["monitors"] = monitors_json(spec);
    r["stages"] = stages_json(spec);
    output_json(spec, r);
    // Every file the case reads besides itself, as the engine opens it (relative paths from the case's folder).
    Json files = Json::array();
    if (!spec.geometry.file.empty()) files.push_back(spec.geometry.file);
    r["files"] = files;
    return r;
}

}  // namespace fdem
