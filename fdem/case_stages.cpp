// fdem/case_stages.cpp: the [[stages]] blocks of a case: duration and termination, gravity, damping, supports and
// loads (each block's group and common keys; each kind reads its own keys in its file: fdem/support.hpp,
// fdem/load.hpp) and time functions. Part of the case reader (fdem/case_reader.hpp).

#include "fdem/case_reader.hpp"
#include "fdem/common/errors.hpp"
#include "fdem/load.hpp"
#include "fdem/support.hpp"

namespace fdem::case_detail {

// fix, free, rigid = "x" | "y" | "xy": the components given get `mode`.
void read_dof_set(Ctx& ctx, Reader& r, const std::string& key, DofMode mode, SupportSpec& s) {
    const bool rigid = mode == DofMode::rigid;
    const std::vector<std::string> allowed = rigid ? std::vector<std::string>{"x", "y", "xy", "body"} : std::vector<std::string>{"x", "y", "xy"};
    if (auto v = r.string(key, false, rigid ? "\"x\", \"y\", \"xy\" or \"body\"" : "\"x\", \"y\" or \"xy\"", allowed)) {
        if (*v == "body") {  // one rigid body: both components, and the rotation
            for (int comp = 0; comp < 2; ++comp) {
                if (s.mode[comp] != DofMode::inherit)
                    ctx.error(r.key_path(key), r.line(), "component " + kComponents[comp] + " already has a support in this block");
                else
                    s.mode[comp] = DofMode::body;
            }
            return;
        }
        for (char c : *v) {
            const int comp = c == 'y' ? 1 : 0;
            if (s.mode[comp] != DofMode::inherit)
                ctx.error(r.key_path(key), r.line(), "component " + kComponents[comp] + " already has a support in this block");
            else
                s.mode[comp] = mode;
        }
    }
}

// key = { type = "sin", amplitude, omega, phase, offset } or { type = "table", points = [[t, f], ...] }.
TimeFunction read_function(Ctx& ctx, Reader& r, const std::string& key) {
    TimeFunction fn;
    const toml::table* p = r.table(key, false, "a table { type = \"sin\", amplitude, omega (rad/s), phase (rad), offset } or "
                                               "{ type = \"table\", points = [[t (s), factor], ...] }");
    if (!p) return fn;
    Reader fr(ctx, *p, r.key_path(key));
    fn.type = fr.string("type", true, "\"sin\" or \"table\"", {"sin", "table"}).value_or("");
    if (fn.type == "sin") {
        fn.amplitude = fr.number("amplitude", false, "an amplitude factor").value_or(1.0);
        fn.omega = fr.number("omega", true, "an angular frequency in rad/s").value_or(0.0);
        fn.phase = fr.number("phase", false, "a phase in rad").value_or(0.0);
        fn.offset = fr.number("offset", false, "a constant factor added").value_or(0.0);
    } else if (fn.type == "table") {
        const toml::node* pts = fr.node("points", true, "an array of [time s, factor] pairs");
        bool ok = pts && pts->is_array() && !pts->as_array()->empty();
        if (ok)
            for (const auto& e : *pts->as_array()) {
                const toml::array* pair = e.as_array();
                if (!pair || pair->size() != 2 || !(*pair)[0].is_number() || !(*pair)[1].is_number() ||
                    !std::isfinite(*(*pair)[0].value<double>()) || !std::isfinite(*(*pair)[1].value<double>())) {
                    ok = false;
                    break;
                }
                fn.t.push_back(*(*pair)[0].value<double>());
                fn.f.push_back(*(*pair)[1].value<double>());
            }
        for (std::size_t i = 1; ok && i < fn.t.size(); ++i)
            if (!(fn.t[i] > fn.t[i - 1])) ok = false;
        if (pts && !ok)
            ctx.error(fr.key_path("points"), line_of(pts), "expected [time s, factor] pairs with strictly increasing times");
        if (!ok) fn.type.clear();
    }
    fr.finish();
    return fn;
}

namespace {

// A [[stages.supports]] block: its group and ramp, then each support kind reads its own keys (fdem/support.hpp:
// fix, free, rigid, vx/vy with function and servo, protocol and cyclic), setting the components' modes.
SupportSpec read_support(Ctx& ctx, const toml::table& t, const std::string& path) {
    Reader r(ctx, t, path);
    SupportSpec s;
    s.line = r.line();
    s.group = r.string("group", true, "the name of a group (Gmsh physical group)").value_or("");
    s.ramp = r.number("ramp", false, "a ramp-up time >= 0 in s", [](double v) { return v >= 0; }).value_or(0.0);
    for (const SupportKind* k : support_kinds()) k->read(ctx, r, s);
    if (s.mode[0] == DofMode::inherit && s.mode[1] == DofMode::inherit)
        ctx.error(path, s.line, "a support needs fix, free, rigid, vx, vy, protocol or cyclic");
    r.finish();
    return s;
}

// A [[stages.loads]] block: its group, then the one kind it gives (fdem/load.hpp), which reads its own keys.
LoadSpec read_load(Ctx& ctx, const toml::table& t, const std::string& path) {
    Reader r(ctx, t, path);
    LoadSpec l;
    l.line = r.line();
    l.group = r.string("group", true, "the name of a group (Gmsh physical group)").value_or("");
    const LoadKind* kind = nullptr;
    int given = 0;
    std::vector<std::string> keys, expects;
    for (const LoadKind* k : load_kinds()) {
        const std::string key = k->key();
        if (r.has(key)) kind = k, ++given;
        keys.push_back(key);
        expects.push_back(k->expect());
    }
    auto one_of = [](const std::vector<std::string>& v) {
        std::string s;
        for (std::size_t i = 0; i < v.size(); ++i) s += (i == 0 ? "" : i + 1 == v.size() ? " or " : ", ") + v[i];
        return s;
    };
    if (given > 1) ctx.error(path, l.line, "give one of " + one_of(keys));
    if (given == 0) ctx.error(path, l.line, "missing; expected " + one_of(expects));
    if (given == 1) {
        l.kind = kind->key();
        kind->read(ctx, r, l);
    } else {
        // (the common keys, not read: no kind to read them for)
        r.has("ramp"), r.has("function");
    }
    r.finish();
    return l;
}

}  // namespace

void read_stages(Ctx& ctx, Reader& top, CaseSpec& spec) {
    auto positive = [](double v) { return v > 0; };
    const auto stage_tables = top.tables("stages", true, "at least one [[stages]] block");
    for (std::size_t si = 0; si < stage_tables.size(); ++si) {
        const std::string p = "stages." + std::to_string(si + 1);
        Reader r(ctx, *stage_tables[si], p);
        StageSpec s;
        s.line = r.line();
        s.name = r.string("name", false, "a stage name").value_or("stage " + std::to_string(si + 1));
        s.duration = r.number("duration", false, "a duration > 0 in s", positive);
        s.max_duration = r.number("max_duration", false, "a time limit > 0 in s", positive);
        s.equilibrium = r.number("equilibrium", false, "an unbalanced-force ratio in (0, 1)", [](double v) { return v > 0 && v < 1; });
        if (const auto er = r.number("equilibrium_reactions", false,
                                     "a relative imbalance of reactions and applied loads in (0, 1)",
                                     [](double v) { return v > 0 && v < 1; })) {
            s.equilibrium_reactions = *er;
            if (!s.equilibrium)
                ctx.error(p + ".equilibrium_reactions", s.line, "equilibrium_reactions needs equilibrium (an unbalanced-force ratio) in the same stage");
        }
        if (const toml::table* u = r.table("until", false, "a table { monitor = NAME, value = V }")) {
            Reader ur(ctx, *u, p + ".until");
            s.until_monitor = ur.string("monitor", true, "the name of a monitor");
            s.until_value = ur.number("value", true, "the monitor value that ends the stage").value_or(0);
            ur.finish();
            if (s.until_monitor && !spec.find_monitor(*s.until_monitor))
                ctx.error(p + ".until.monitor", ur.line(), "no monitor named '" + *s.until_monitor + "' in [[monitors]]");
        }
        if (const toml::table* u = r.table("past_peak", false,
                                           "a table { load = NAME, displacement = NAME, drop = FRACTION, travel = D[, smooth = L] }")) {
            Reader pr(ctx, *u, p + ".past_peak");
            StageSpec::PastPeak pp;
            pp.line = pr.line();
            pp.load = pr.string("load", true, "the name of the load monitor (a reaction or load)").value_or("");
            pp.displacement = pr.string("displacement", true, "the name of the displacement monitor").value_or("");
            pp.drop = pr.number("drop", true, "a fraction of the largest load in (0, 1)", [](double v) { return v > 0 && v < 1; })
                          .value_or(0.2);
            pp.travel = pr.number("travel", true, "a travel > 0 of the displacement monitor, in its unit", positive).value_or(0);
            pp.smooth = pr.number("smooth", false, "an averaging length > 0 of the displacement monitor, in its unit", positive)
                            .value_or(pp.travel / 4);
            pr.finish();
            const MonitorSpec* ml = pp.load.empty() ? nullptr : spec.find_monitor(pp.load);
            const MonitorSpec* md = pp.displacement.empty() ? nullptr : spec.find_monitor(pp.displacement);
            if (!pp.load.empty() && !ml)
                ctx.error(p + ".past_peak.load", pp.line, "no monitor named '" + pp.load + "' in [[monitors]]");
            else if (ml && ml->type != "reaction" && ml->type != "load")
                ctx.error(p + ".past_peak.load", pp.line, "monitor '" + pp.load + "' is a " + ml->type +
                                                              " monitor; expected a reaction or load monitor");
            if (!pp.displacement.empty() && !md)
                ctx.error(p + ".past_peak.displacement", pp.line, "no monitor named '" + pp.displacement + "' in [[monitors]]");
            else if (md && md->type != "displacement" && md->type != "rotation" && md->type != "tilt")
                ctx.error(p + ".past_peak.displacement", pp.line, "monitor '" + pp.displacement + "' is a " + md->type +
                                                                      " monitor; expected a displacement, rotation or tilt monitor");
            s.past_peak = pp;
        }
        s.gravity = r.vec2("gravity", false, "[gx, gy] in m/s^2");
        s.gravity_ramp = r.number("gravity_ramp", false, "a ramp time >= 0 in s", [](double v) { return v >= 0; }).value_or(0);
        s.tilt_rate = r.number("tilt_rate", false, "a rotation rate of gravity in deg/s").value_or(0);
        s.gravity_function = read_function(ctx, r, "gravity_function");
        s.local_damping = r.number("local_damping", false, "a local damping coefficient in [0, 1)", [](double v) { return v >= 0 && v < 1; });
        s.local_damping_filter = r.number("local_damping_filter", false, "a filter time constant >= 0 in s (0: absolute velocity)",
                                          [](double v) { return v >= 0 && std::isfinite(v); });
        s.contact_damping = r.number("contact_damping", false, "a fraction of critical damping of the contact springs in [0, 0.5]",
                                     [](double v) { return v >= 0 && v <= 0.5; });
        s.mass_damping = r.number("mass_damping", false, "a mass-proportional damping coefficient >= 0 in 1/s",
                                  [](double v) { return v >= 0 && std::isfinite(v); });
        s.history_interval = r.number("history_interval", false, "an interval > 0 in s", positive);
        s.snapshot_interval = r.number("snapshot_interval", false, "an interval > 0 in s", positive);
        const auto loads = r.tables("loads", false, "[[stages.loads]] blocks");
        for (std::size_t i = 0; i < loads.size(); ++i) s.loads.push_back(read_load(ctx, *loads[i], p + ".loads." + std::to_string(i + 1)));
        const auto sups = r.tables("supports", false, "[[stages.supports]] blocks");
        for (std::size_t i = 0; i < sups.size(); ++i)
            s.supports.push_back(read_support(ctx, *sups[i], p + ".supports." + std::to_string(i + 1)));
        r.finish();

        // A protocol (or cyclic) support's history ends at its last point: a stage with no other end ends there, and
        // a stage whose duration or max_duration ends before it would cut the protocol short (an error: the
        // protocol's amplitudes are what the user asked for).
        double protocol_end = 0;
        std::string protocol_key;
        for (std::size_t i = 0; i < s.supports.size(); ++i)
            if (!s.supports[i].protocol_t.empty() && s.supports[i].protocol_t.back() > protocol_end)
                protocol_end = s.supports[i].protocol_t.back(), protocol_key = p + ".supports." + std::to_string(i + 1);
        if (protocol_end > 0) {
            const double tol = 1e-9 * protocol_end;
            if (!s.duration && !s.until_monitor && !s.equilibrium) s.duration = protocol_end;
            else if (s.duration && *s.duration < protocol_end - tol)
                ctx.error(p + ".duration", s.line, "the stage ends at " + g4(*s.duration) + " s, before the protocol of " +
                                                       protocol_key + " (its last point at " + g4(protocol_end) +
                                                       " s): expected a duration >= " + g4(protocol_end) +
                                                       " s, or none (the stage then ends with its protocol)");
            else if (!s.duration && s.max_duration && *s.max_duration < protocol_end - tol)
                ctx.error(p + ".max_duration", s.line, "the stage may stop at " + g4(*s.max_duration) +
                                                           " s, before the protocol of " + protocol_key +
                                                           " ends (its last point at " + g4(protocol_end) + " s)");
        }

        // A stage must be able to end.
        if (!s.duration && !s.until_monitor && !s.equilibrium)
            ctx.error(p, s.line, "this stage can never end: give duration (s), until = { monitor, value } or equilibrium");
        bool driven = false;
        if (s.until_monitor) {
            const MonitorSpec* m = spec.find_monitor(*s.until_monitor);
            if (m && m->type == "displacement")
                for (const auto& sup : s.supports)
                    if (sup.group == m->group &&
                        ((sup.mode[m->component] == DofMode::velocity && sup.velocity[m->component] != 0) ||
                         sup.mode[m->component] == DofMode::protocol))
                        driven = true;
            if (m && m->type == "displacement")
                for (const auto& sup : s.supports)
                    if (sup.group == m->group && sup.mode[m->component] == DofMode::velocity && sup.velocity[m->component] == 0)
                        ctx.error(p + ".until", s.line, "this stage can never end: monitor '" + m->name +
                                  "' is held by a zero velocity in this stage");
        }
        if ((s.until_monitor || s.equilibrium) && !s.duration && !s.max_duration && !driven)
            ctx.error(p, s.line, "this stage may never end: with until (on a monitor not driven by a prescribed velocity) or "
                                 "equilibrium, give max_duration (s) as a bound");
        spec.stages.push_back(std::move(s));
    }
}

}  // namespace fdem::case_detail
