// fdem/case.cpp: TOML case file -> validated CaseSpec (toml++ from Debian; no hand-written parser).
#include "fdem/case.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <set>
#include <sstream>

#include "fdem/common/errors.hpp"

namespace fdem {

namespace {

std::string fmt_num(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// Edit distance counting a swap of two neighbouring letters as one edit (the commonest typo).
std::size_t edit_distance(const std::string& a, const std::string& b) {
    std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
    for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
    for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i)
        for (std::size_t j = 1; j <= b.size(); ++j) {
            d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
            if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
        }
    return d[a.size()][b.size()];
}

std::string describe(const toml::node& n) {
    std::ostringstream s;
    if (n.is_string()) s << '"' << *n.value<std::string>() << '"';
    else if (n.is_table()) s << "a table";
    else if (n.is_array()) s << "an array";
    else n.visit([&](auto&& v) { s << v; });
    return s.str();
}

// Where a problem is reported: the case file and the lines of its nodes, or --set for overridden keys.
std::string g4(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.4g", v);
    return b;
}

struct Ctx {
    std::string file;
    std::vector<std::string> errors;
    std::set<std::string> set_paths;

    std::string where(const std::string& path, int line) const {
        for (const auto& p : set_paths)
            if (path == p || path.rfind(p + ".", 0) == 0) return "--set " + p;
        if (line > 0) return file + ":" + std::to_string(line);
        // No line: a table that a --set made (it was not in the file), so its other keys are missing there.
        for (const auto& p : set_paths) {
            const auto dot = p.rfind('.');
            if (dot != std::string::npos && path.rfind(p.substr(0, dot + 1), 0) == 0)
                return "--set " + p + " (it makes the table '" + p.substr(0, dot) + "', which is not in " + file + ")";
        }
        return file;
    }
    void error(const std::string& path, int line, const std::string& msg) {
        errors.push_back(where(path, line) + ": key '" + path + "': " + msg);
    }
};

int line_of(const toml::node* n) { return n ? static_cast<int>(n->source().begin.line) : 0; }

// Reads the keys of one table; every key asked for is "known", and finish() reports the others.
class Reader {
public:
    Reader(Ctx& ctx, const toml::table& t, std::string path) : ctx_(ctx), t_(t), path_(std::move(path)) {}

    int line() const { return line_of(&t_); }
    std::string key_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
    bool has(const std::string& key) {
        known_.insert(key);
        return t_.contains(key);
    }
    const toml::node* node(const std::string& key, bool required, const std::string& expect) {
        known_.insert(key);
        const toml::node* n = t_.get(key);
        if (!n && required) ctx_.error(key_path(key), line(), "missing; expected " + expect);
        return n;
    }
    std::optional<double> number(const std::string& key, bool required, const std::string& expect,
                                 const std::function<bool(double)>& ok = nullptr) {
        const toml::node* n = node(key, required, expect);
        if (!n) return std::nullopt;
        if (!n->is_number()) {
            ctx_.error(key_path(key), line_of(n), "expected " + expect + ", got " + describe(*n));
            return std::nullopt;
        }
        const double v = *n->value<double>();
        if (!std::isfinite(v) || (ok && !ok(v))) {
            ctx_.error(key_path(key), line_of(n), "expected " + expect + ", got " + fmt_num(v));
            return std::nullopt;
        }
        return v;
    }
    std::optional<int> integer(const std::string& key, bool required, const std::string& expect,
                               const std::function<bool(long long)>& ok = nullptr) {
        const toml::node* n = node(key, required, expect);
        if (!n) return std::nullopt;
        if (!n->is_integer() || (ok && !ok(*n->value<long long>()))) {
            ctx_.error(key_path(key), line_of(n), "expected " + expect + ", got " + describe(*n));
            return std::nullopt;
        }
        return static_cast<int>(*n->value<long long>());
    }
    std::optional<bool> boolean(const std::string& key, bool required, const std::string& expect) {
        const toml::node* n = node(key, required, expect);
        if (!n) return std::nullopt;
        if (!n->is_boolean()) {
            ctx_.error(key_path(key), line_of(n), "expected " + expect + ", got " + describe(*n));
            return std::nullopt;
        }
        return *n->value<bool>();
    }
    std::optional<std::string> string(const std::string& key, bool required, const std::string& expect,
                                      const std::vector<std::string>& allowed = {}) {
        const toml::node* n = node(key, required, expect);
        if (!n) return std::nullopt;
        if (!n->is_string()) {
            ctx_.error(key_path(key), line_of(n), "expected " + expect + ", got " + describe(*n));
            return std::nullopt;
        }
        std::string v = *n->value<std::string>();
        if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), v) == allowed.end()) {
            std::string list;
            for (const auto& a : allowed) list += (list.empty() ? "\"" : ", \"") + a + "\"";
            ctx_.error(key_path(key), line_of(n), "expected one of " + list + ", got \"" + v + "\"");
            return std::nullopt;
        }
        return v;
    }
    std::optional<std::vector<double>> numbers(const std::string& key, bool required, const std::string& expect,
                                               std::size_t exact_size = 0) {
        const toml::node* n = node(key, required, expect);
        if (!n) return std::nullopt;
        const toml::array* a = n->as_array();
        std::vector<double> out;
        bool ok = a != nullptr;
        if (a)
            for (const auto& e : *a) {
                if (!e.is_number() || !std::isfinite(*e.value<double>())) ok = false;
                else out.push_back(*e.value<double>());
            }
        if (ok && exact_size && out.size() != exact_size) ok = false;
        if (!ok) {
            ctx_.error(key_path(key), line_of(n), "expected " + expect + ", got " + describe(*n));
            return std::nullopt;
        }
        return out;
    }
    std::optional<std::array<double, 2>> vec2(const std::string& key, bool required, const std::string& expect) {
        auto v = numbers(key, required, expect, 2);
        if (!v) return std::nullopt;
        return std::array<double, 2>{(*v)[0], (*v)[1]};
    }
    const toml::table* table(const std::string& key, bool required, const std::string& expect) {
        const toml::node* n = node(key, required, expect);
        if (!n) return nullptr;
        if (!n->is_table()) {
            ctx_.error(key_path(key), line_of(n), "expected " + expect + ", got " + describe(*n));
            return nullptr;
        }
        return n->as_table();
    }
    // An array of tables ([[name]] blocks).
    std::vector<const toml::table*> tables(const std::string& key, bool required, const std::string& expect) {
        std::vector<const toml::table*> out;
        const toml::node* n = node(key, required, expect);
        if (!n) return out;
        const toml::array* a = n->as_array();
        if (!a || !a->is_array_of_tables()) {
            ctx_.error(key_path(key), line_of(n), "expected " + expect + ", got " + describe(*n));
            return out;
        }
        for (const auto& e : *a) out.push_back(e.as_table());
        return out;
    }
    void finish() {
        for (const auto& [k, v] : t_) {
            const std::string key(k.str());
            if (known_.count(key)) continue;
            std::string best;
            std::size_t best_d = 3;
            for (const auto& cand : known_) {
                const std::size_t d = edit_distance(key, cand);
                if (d < best_d) best_d = d, best = cand;
            }
            std::string allowed;
            for (const auto& cand : known_) allowed += (allowed.empty() ? "" : ", ") + cand;
            ctx_.errors.push_back(ctx_.where(key_path(key), line_of(&v)) + ": unknown key '" + key_path(key) + "'" +
                                  (best.empty() ? "" : "; did you mean '" + best + "'?") +
                                  (allowed.empty() ? "" : " (allowed here: " + allowed + ")"));
        }
    }

private:
    Ctx& ctx_;
    const toml::table& t_;
    std::string path_;
    std::set<std::string> known_;
};

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

const std::vector<std::string> kComponents{"x", "y"};
int component_index(const std::string& c) { return c == "y" ? 1 : 0; }

void read_dof_set(Ctx& ctx, Reader& r, const std::string& key, DofMode mode, SupportSpec& s) {
    if (auto v = r.string(key, false, "\"x\", \"y\" or \"xy\"", {"x", "y", "xy"}))
        for (char c : *v) {
            const int comp = c == 'y' ? 1 : 0;
            if (s.mode[comp] != DofMode::inherit)
                ctx.error(r.key_path(key), r.line(), "component " + kComponents[comp] + " already has a support in this block");
            else
                s.mode[comp] = mode;
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

SupportSpec read_support(Ctx& ctx, const toml::table& t, const std::string& path) {
    Reader r(ctx, t, path);
    SupportSpec s;
    s.line = r.line();
    s.group = r.string("group", true, "the name of a group (Gmsh physical group)").value_or("");
    read_dof_set(ctx, r, "fix", DofMode::fixed, s);
    read_dof_set(ctx, r, "free", DofMode::free, s);
    read_dof_set(ctx, r, "rigid", DofMode::rigid, s);
    for (int c = 0; c < 2; ++c) {
        const std::string key = c == 0 ? "vx" : "vy";
        if (auto v = r.number(key, false, "a velocity in m/s")) {
            if (s.mode[c] != DofMode::inherit)
                ctx.error(r.key_path(key), r.line(), "component " + kComponents[c] + " is already fixed or freed in this support");
            s.mode[c] = DofMode::velocity;
            s.velocity[c] = *v;
        }
    }
    s.ramp = r.number("ramp", false, "a ramp-up time >= 0 in s", [](double v) { return v >= 0; }).value_or(0.0);
    s.function = read_function(ctx, r, "function");
    if (s.function.present() && s.mode[0] != DofMode::velocity && s.mode[1] != DofMode::velocity)
        ctx.error(r.key_path("function"), r.line(), "a time function multiplies a prescribed velocity: give vx or vy");
    if (const toml::table* p = r.table("servo", false, "a table { ratio = target unbalanced-force ratio, time = response time s, "
                                                       "min_factor = smallest velocity factor }")) {
        Reader sr(ctx, *p, r.key_path("servo"));
        s.servo_ratio = sr.number("ratio", true, "a target unbalanced-force ratio in (0, 1)", [](double v) { return v > 0 && v < 1; })
                            .value_or(0.0);
        s.servo_time = sr.number("time", true, "a response time > 0 in s", [](double v) { return v > 0; }).value_or(0.0);
        s.servo_min = sr.number("min_factor", false, "a smallest velocity factor in (0, 1]", [](double v) { return v > 0 && v <= 1; })
                          .value_or(0.01);
        sr.finish();
        if (s.mode[0] != DofMode::velocity && s.mode[1] != DofMode::velocity)
            ctx.error(r.key_path("servo"), r.line(), "a servo controls a prescribed velocity: give vx or vy");
    }
    auto add_protocol = [&](int comp, std::vector<double> t_pts, std::vector<double> u_pts, const std::string& key, int line) {
        if (s.mode[comp] != DofMode::inherit) {
            ctx.error(r.key_path(key), line, "component " + kComponents[comp] + " already has a support in this block");
            return;
        }
        s.mode[comp] = DofMode::protocol;
        s.protocol_t = std::move(t_pts);
        s.protocol_u = std::move(u_pts);
    };
    if (const toml::table* p = r.table("protocol", false, "a table { component = \"x\", points = [[t, u], ...] }")) {
        Reader pr(ctx, *p, r.key_path("protocol"));
        const int comp = component_index(pr.string("component", true, "\"x\" or \"y\"", kComponents).value_or("x"));
        const toml::node* pts = pr.node("points", true, "an array of [time s, displacement m] pairs");
        std::vector<double> tt, uu;
        bool ok = pts && pts->is_array() && pts->as_array()->size() >= 2;
        if (ok)
            for (const auto& e : *pts->as_array()) {
                const toml::array* pair = e.as_array();
                if (!pair || pair->size() != 2 || !(*pair)[0].is_number() || !(*pair)[1].is_number()) { ok = false; break; }
                tt.push_back(*(*pair)[0].value<double>());
                uu.push_back(*(*pair)[1].value<double>());
            }
        for (std::size_t i = 1; ok && i < tt.size(); ++i)
            if (!(tt[i] > tt[i - 1])) ok = false;
        if (pts && !ok)
            ctx.error(pr.key_path("points"), line_of(pts),
                      "expected at least two [time s, displacement m] pairs with strictly increasing times");
        pr.finish();
        if (ok) add_protocol(comp, tt, uu, "protocol", pr.line());
    }
    if (const toml::table* p = r.table("cyclic", false, "a table { component, amplitudes, cycles, rate }")) {
        Reader pr(ctx, *p, r.key_path("cyclic"));
        const int comp = component_index(pr.string("component", true, "\"x\" or \"y\"", kComponents).value_or("x"));
        auto amps = pr.numbers("amplitudes", true, "an array of displacement amplitudes > 0 in m");
        const int cycles = pr.integer("cycles", false, "a whole number of cycles per amplitude >= 1",
                                      [](long long v) { return v >= 1; }).value_or(1);
        auto rate = pr.number("rate", true, "a loading rate > 0 in m/s", [](double v) { return v > 0; });
        pr.finish();
        if (amps && rate) {
            bool ok = !amps->empty();
            for (double a : *amps) ok = ok && a > 0;
            if (!ok) {
                ctx.error(pr.key_path("amplitudes"), pr.line(), "expected a non-empty array of amplitudes > 0 in m");
            } else {
                // Each cycle: 0 -> +a -> 0 -> -a -> 0 at the constant rate.
                std::vector<double> tt{0}, uu{0};
                for (double a : *amps)
                    for (int c = 0; c < cycles; ++c)
                        for (double target : {a, 0.0, -a, 0.0}) {
                            tt.push_back(tt.back() + std::abs(target - uu.back()) / *rate);
                            uu.push_back(target);
                        }
                add_protocol(comp, tt, uu, "cyclic", pr.line());
            }
        }
    }
    if (s.mode[0] == DofMode::inherit && s.mode[1] == DofMode::inherit)
        ctx.error(path, s.line, "a support needs fix, free, rigid, vx, vy, protocol or cyclic");
    r.finish();
    return s;
}

LoadSpec read_load(Ctx& ctx, const toml::table& t, const std::string& path) {
    Reader r(ctx, t, path);
    LoadSpec l;
    l.line = r.line();
    l.group = r.string("group", true, "the name of a group (Gmsh physical group)").value_or("");
    auto force = r.vec2("force", false, "[Fx, Fy], the total force on the group in N");
    auto pressure = r.number("pressure", false, "a pressure in Pa");
    const bool spring = r.has("spring");
    if (int(bool(force)) + int(bool(pressure)) + int(spring) > 1)
        ctx.error(path, l.line, "give one of force, pressure or spring");
    if (!r.has("force") && !r.has("pressure") && !spring)
        ctx.error(path, l.line, "missing; expected force = [Fx, Fy] (N), pressure (Pa) or spring = { component, stiffness, velocity }");
    if (const toml::table* p = r.table("spring", false, "a table { component = \"x\", stiffness = k (N/m), velocity = v (m/s) }")) {
        Reader sr(ctx, *p, r.key_path("spring"));
        l.is_spring = true;
        l.spring_component = component_index(sr.string("component", true, "\"x\" or \"y\"", kComponents).value_or("x"));
        l.spring_stiffness = sr.number("stiffness", true, "a spring stiffness > 0 in N/m", [](double v) { return v > 0; }).value_or(1.0);
        l.spring_velocity = sr.number("velocity", true, "the anchor's velocity in m/s").value_or(0.0);
        sr.finish();
    }
    if (force) l.force = *force;
    if (pressure) l.is_pressure = true, l.pressure = *pressure;
    l.ramp = r.number("ramp", false, "a ramp time >= 0 in s", [](double v) { return v >= 0; }).value_or(0.0);
    l.function = read_function(ctx, r, "function");
    if (l.function.present() && l.is_spring)
        ctx.error(r.key_path("function"), r.line(), "a time function multiplies a force or pressure, not a spring");
    r.finish();
    return l;
}

constexpr double kMinLength = 1e-6, kMaxLength = 1e4;  // m: bounds of every generated geometry's lengths

// Expected triangle count of a generated wall before meshing: area / (sqrt(3)/4 h^2) for each part meshed at size
// h (equilateral triangles of edge h), and at least 2 triangles per unit. 0 when the sizes are not known here.
double wall_triangle_estimate(const mesh::WallSpec& w) {
    const double per = 4.0 / std::sqrt(3.0);
    const double H = w.height > 0 ? w.height : w.courses * (w.unit_height + w.joint_thickness);
    const double L = w.length;
    if (!(L > 0) || !(H > 0) || !(w.mesh_size > 0)) return 0;
    double n = per * L * H / (w.mesh_size * w.mesh_size);
    if (w.unit_length > 0 && w.unit_height > 0) n = std::max(n, 2.0 * (L / w.unit_length + 1) * (H / w.unit_height + 1));
    const double hb = w.mesh_size_base > 0 ? w.mesh_size_base : w.mesh_size;
    const double hm = w.mesh_size_beam > 0 ? w.mesh_size_beam : w.mesh_size;
    if (w.base == "slab") n += per * (L + 2 * w.base_overhang) * w.base_height / (hb * hb);
    n += per * (L + 2 * w.beam_overhang) * w.beam_height / (hm * hm);
    for (const auto& rf : w.refine)
        if (rf.size > 0) n += per * rf.width * rf.height / (rf.size * rf.size);
    return n;
}

// [geometry] max_triangles: the size guard of generated meshes (rectangle, wall), checked before meshing.
void check_triangle_count(Ctx& ctx, Reader& r, int line, double expected) {
    const double limit = r.number("max_triangles", false, "a triangle limit >= 1 for generated meshes",
                                  [](double v) { return v >= 1; }).value_or(2e6);
    if (!(expected <= limit))
        ctx.error("geometry.max_triangles", line, "the generated mesh would have about " + fmt_num(expected) +
                  " triangles, more than the limit of " + fmt_num(limit) +
                  "; expected a coarser geometry.mesh_size (or larger units), or raise geometry.max_triangles");
}

// [[geometry.openings]] blocks { x, y, width, height } of the wall and the macro-block wall (mesh::WallOpening,
// mesh::MacroWallOpening), in file order.
template <class Opening>
void read_openings(Ctx& ctx, Reader& r, std::vector<Opening>& out, bool required) {
    auto positive = [](double v) { return v >= kMinLength && v <= kMaxLength; };
    for (const toml::table* t : r.tables("openings", required, "[[geometry.openings]] blocks { x, y, width, height }")) {
        Reader o(ctx, *t, r.key_path("openings." + std::to_string(out.size() + 1)));
        Opening op;
        op.x = o.number("x", true, "the opening's left edge in m").value_or(0);
        op.y = o.number("y", true, "the opening's bottom edge (sill) in m").value_or(0);
        op.width = o.number("width", true, "a width > 0 in m", positive).value_or(0);
        op.height = o.number("height", true, "a height > 0 in m", positive).value_or(0);
        o.finish();
        out.push_back(op);
    }
}

// [geometry] type = "wall": keys named after mesh::WallSpec's fields; the generator's own check() runs later,
// with the mesh, and its messages are reported against the [geometry] table.
void read_wall(Ctx& ctx, Reader& r, mesh::WallSpec& w) {
    // Lengths are bounded to [1e-6, 1e4] m: beyond them Gmsh aborts or hangs (issue 26), and no masonry wall needs them.
    auto nonneg = [](double v) { return v == 0 || (v >= kMinLength && v <= kMaxLength); };
    auto positive = [](double v) { return v >= kMinLength && v <= kMaxLength; };
    w.length = r.number("length", false, "a wall length > 0 in m", positive).value_or(0);
    w.height = r.number("height", false, "a wall height > 0 in m", positive).value_or(0);
    w.courses = r.integer("courses", false, "a whole number of courses >= 1", [](long long v) { return v >= 1; }).value_or(0);
    w.unit_length = r.number("unit_length", false, "a unit length > 0 in m", positive).value_or(0);
    w.unit_height = r.number("unit_height", false, "a unit height > 0 in m", positive).value_or(0);
    w.bond = r.string("bond", false, "the bond pattern", {"running", "stack", "offsets"}).value_or("running");
    if (auto o = r.numbers("offsets", false, "an array of course offsets in m")) w.offsets = *o;
    if (const toml::node* n = r.node("stones", false, "an array of polygons [[x, y], ...] in m")) {
        bool ok = n->is_array();
        if (ok)
            for (const auto& poly : *n->as_array()) {
                std::vector<std::array<double, 2>> pts;
                if (!poly.is_array()) { ok = false; break; }
                for (const auto& pt : *poly.as_array()) {
                    const toml::array* a = pt.as_array();
                    if (!a || a->size() != 2 || !(*a)[0].is_number() || !(*a)[1].is_number()) { ok = false; break; }
                    pts.push_back({*(*a)[0].value<double>(), *(*a)[1].value<double>()});
                }
                if (pts.size() < 3) ok = false;
                w.stones.push_back(pts);
            }
        if (!ok) ctx.error(r.key_path("stones"), line_of(n), "expected an array of polygons, each at least 3 [x, y] points in m");
    }
    w.joint = r.string("joint", false, "the joint type", {"dry", "mortar"}).value_or("dry");
    w.joint_thickness = r.number("joint_thickness", false, "a mortar joint thickness of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    w.unit_cracks = r.string("unit_cracks", false, "where crackable units may crack",
                             {"anywhere", "middle"}).value_or("anywhere");
    w.beam_height = r.number("beam_height", false, "a beam depth of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    w.beam_overhang = r.number("beam_overhang", false, "a beam overhang of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    w.base = r.string("base", false, "the base", {"none", "fixed", "slab"}).value_or("none");
    w.base_height = r.number("base_height", false, "a base depth of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    w.base_overhang = r.number("base_overhang", false, "a base overhang of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    w.mesh_size = r.number("mesh_size", true, "a mesh size > 0 in m", positive).value_or(1);
    w.mesh_size_beam = r.number("mesh_size_beam", false, "a mesh size > 0 in m", positive).value_or(0);
    w.mesh_size_base = r.number("mesh_size_base", false, "a mesh size > 0 in m", positive).value_or(0);
    read_openings(ctx, r, w.openings, false);
    for (const toml::table* t : r.tables("refine", false, "[[geometry.refine]] blocks { x, y, width, height, size }")) {
        Reader o(ctx, *t, r.key_path("refine." + std::to_string(w.refine.size() + 1)));
        mesh::WallRefinement rf;
        rf.x = o.number("x", true, "the box's left edge in m").value_or(0);
        rf.y = o.number("y", true, "the box's bottom edge in m").value_or(0);
        rf.width = o.number("width", true, "a width > 0 in m", positive).value_or(0);
        rf.height = o.number("height", true, "a height > 0 in m", positive).value_or(0);
        rf.size = o.number("size", true, "a mesh size > 0 in m", positive).value_or(0);
        o.finish();
        w.refine.push_back(rf);
    }
}

// The [geometry] keys of the macro-block pier and wall (mesh::MacroPierSpec, mesh::MacroWallSpec); `what` names the
// length and height ("pier", "wall").
template <class Spec>
void read_macro_common(Reader& r, Spec& m, const std::string& what) {
    auto nonneg = [](double v) { return v == 0 || (v >= kMinLength && v <= kMaxLength); };
    auto positive = [](double v) { return v >= kMinLength && v <= kMaxLength; };
    m.length = r.number("length", true, "a " + what + " length > 0 in m", positive).value_or(1);
    m.height = r.number("height", true, "a " + what + " height > 0 in m", positive).value_or(1);
    m.texture_angle = r.number("texture_angle", true, "a texture angle in (0, 90) deg",
                               [](double v) { return v > 0 && v < 90; }).value_or(45);
    m.horizontal_joint = r.number("horizontal_joint", false, "a horizontal joint length > 0 in m (below half the panel)",
                                  positive).value_or(0.05);
    m.mesh_size = r.number("mesh_size", true, "a mesh size > 0 in m", positive).value_or(1);
    m.beam_height = r.number("beam_height", false, "a beam depth of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    m.beam_overhang = r.number("beam_overhang", false, "a beam overhang of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    m.base_height = r.number("base_height", false, "a base depth of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    m.base_overhang = r.number("base_overhang", false, "a base overhang of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    m.mesh_size_beam = r.number("mesh_size_beam", false, "a mesh size > 0 in m", positive).value_or(0);
    m.mesh_size_base = r.number("mesh_size_base", false, "a mesh size > 0 in m", positive).value_or(0);
}

// [geometry] type = "macro": the macro-block pier (M-DEM); keys named after mesh::MacroPierSpec's fields. The
// generator's check() (diagonals that would cross) runs later, with the mesh, reported against [geometry].
void read_macro(Reader& r, mesh::MacroPierSpec& m) { read_macro_common(r, m, "pier"); }

// Expected triangle count of a macro-block pier (equilateral triangles of edge h, as wall_triangle_estimate).
double macro_triangle_estimate(const mesh::MacroPierSpec& m) {
    const double per = 4.0 / std::sqrt(3.0);
    if (!(m.mesh_size > 0)) return 0;
    const double hb = m.mesh_size_base > 0 ? m.mesh_size_base : m.mesh_size;
    const double hm = m.mesh_size_beam > 0 ? m.mesh_size_beam : m.mesh_size;
    return per * m.length * m.height / (m.mesh_size * m.mesh_size) + 12 +
           per * (m.length + 2 * m.beam_overhang) * m.beam_height / (hm * hm) +
           per * (m.length + 2 * m.base_overhang) * m.base_height / (hb * hb);
}

// [geometry] type = "macro_wall": the macro-block wall with one row of openings (mesh/macro.hpp); keys named after
// mesh::MacroWallSpec's fields, the openings as in read_wall. The generator's check() (one row, piers of positive
// length, the keys fitting every panel) runs later, with the mesh, reported against [geometry].
void read_macro_wall(Ctx& ctx, Reader& r, mesh::MacroWallSpec& m) {
    read_macro_common(r, m, "wall");
    auto nonneg = [](double v) { return v == 0 || (v >= kMinLength && v <= kMaxLength); };
    m.lintel_height = r.number("lintel_height", false, "a lintel depth of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    m.lintel_bearing = r.number("lintel_bearing", false, "a lintel bearing of 0 or in [1e-6, 1e4] m", nonneg).value_or(0);
    read_openings(ctx, r, m.openings, true);
}

// Expected triangle count of a macro-block wall: the masonry area less the openings, beam and base.
double macro_wall_triangle_estimate(const mesh::MacroWallSpec& m) {
    const double per = 4.0 / std::sqrt(3.0);
    if (!(m.mesh_size > 0)) return 0;
    const double hb = m.mesh_size_base > 0 ? m.mesh_size_base : m.mesh_size;
    const double hm = m.mesh_size_beam > 0 ? m.mesh_size_beam : m.mesh_size;
    double area = m.length * m.height;
    for (const auto& o : m.openings) area -= o.width * o.height;
    return per * std::max(area, 0.0) / (m.mesh_size * m.mesh_size) + 12.0 * (2 * m.openings.size() + 1) +
           per * (m.length + 2 * m.beam_overhang) * m.beam_height / (hm * hm) +
           per * (m.length + 2 * m.base_overhang) * m.base_height / (hb * hb);
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

CaseSpec load_case(const std::string& path, const std::vector<std::string>& overrides) {
    namespace fs = std::filesystem;
    if (!fs::exists(path)) throw InputError(path + ": no such case file");
    toml::table root;
    try {
        root = toml::parse_file(path);
    } catch (const toml::parse_error& e) {
        throw InputError(path + ":" + std::to_string(e.source().begin.line) + ": TOML syntax error: " +
                         std::string(e.description()));
    }
    Ctx ctx;
    ctx.file = path;
    CaseSpec spec;
    spec.file = path;
    spec.dir = fs::path(path).parent_path().string();
    for (const auto& o : overrides) {
        apply_override(root, o, ctx);
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
    auto positive = [](double v) { return v > 0; };

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

    if (const toml::table* t = top.table("geometry", true, "a [geometry] table")) {
        Reader r(ctx, *t, "geometry");
        GeometrySpec& g = spec.geometry;
        g.line = r.line();
        g.type = r.string("type", true, "the geometry source", {"rectangle", "gmsh", "msh", "wall", "macro", "macro_wall"}).value_or("");
        if (g.type == "rectangle") {
            auto origin = r.vec2("origin", false, "[x0, y0] in m");
            if (origin) g.x0 = (*origin)[0], g.y0 = (*origin)[1];
            g.width = r.number("width", true, "a width > 0 in m", positive).value_or(1);
            g.height = r.number("height", true, "a height > 0 in m", positive).value_or(1);
            g.mesh_size = r.number("mesh_size", true, "a mesh size > 0 in m", positive).value_or(1);
            check_triangle_count(ctx, r, g.line, 2.31 * g.width * g.height / (g.mesh_size * g.mesh_size));
            if (g.mesh_size > 0 && std::min(g.width, g.height) / g.mesh_size > 5000)
                ctx.error("geometry.mesh_size", g.line, "a mesh size of " + fmt_num(g.mesh_size) +
                          " m gives more than 5000 elements across the rectangle; expected a coarser size");
        } else if (g.type == "gmsh" || g.type == "msh") {
            if (auto f = r.string("file", true, g.type == "gmsh" ? "the path of a .geo script" : "the path of a .msh file")) {
                fs::path p(*f);
                if (p.is_relative()) p = fs::path(spec.dir) / p;
                g.file = p.string();
                if (!fs::exists(p)) ctx.error("geometry.file", line_of(t->get("file")), "no such file '" + g.file + "'");
            }
            if (g.type == "gmsh")
                g.size_factor = r.number("size_factor", false, "a factor > 0 on the script's mesh sizes", positive).value_or(1.0);
        } else if (g.type == "wall") {
            read_wall(ctx, r, g.wall);
            check_triangle_count(ctx, r, g.line, wall_triangle_estimate(g.wall));
        } else if (g.type == "macro") {
            read_macro(r, g.macro);
            check_triangle_count(ctx, r, g.line, macro_triangle_estimate(g.macro));
        } else if (g.type == "macro_wall") {
            read_macro_wall(ctx, r, g.macro_wall);
            check_triangle_count(ctx, r, g.line, macro_wall_triangle_estimate(g.macro_wall));
        }
        g.min_angle = r.number("min_angle", false, "a minimum triangle angle in [0, 60) deg (sliver check)",
                               [](double v) { return v >= 0 && v < 60; }).value_or(10.0);
        g.split_all = r.string("split", false, "\"joints\" (default) or \"all\" (every edge crackable, the classic FDEM limit)",
                               {"joints", "all"}).value_or("joints") == "all";
        g.joint_roughness = r.number("joint_roughness", false, "the largest inward offset of a dry-joint face, >= 0 in m",
                                     [](double v) { return v >= 0; }).value_or(0.0);
        g.roughness_wavelength = r.number("roughness_wavelength", g.joint_roughness > 0,
                                          "the wavelength of the joint roughness, > 0 in m (needed with joint_roughness > 0)",
                                          positive).value_or(0.0);
        g.roughness_seed = r.integer("roughness_seed", false, "a whole number >= 0 that seeds the joint roughness",
                                     [](long long v) { return v >= 0 && v <= 2147483647; }).value_or(1);
        r.finish();
    }

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
    top.finish();

    // Until-targets on a driven displacement must lie in the direction of the velocity (from zero for stage 1).
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
            if (!s.loads[i].is_pressure) continue;
            for (std::size_t g = 0; g < names.groups.size(); ++g)
                if (names.groups[g] == s.loads[i].group && names.group_dims[g] != 1)
                    errors.push_back(spec.file + ":" + std::to_string(s.loads[i].line) + ": key 'stages." + std::to_string(si + 1) +
                                     ".loads." + std::to_string(i + 1) + ".pressure': group '" + s.loads[i].group +
                                     "' is not a curve (1D physical group); a pressure needs edges");
        }
    }
    if (!errors.empty()) throw InputError(errors);
}

}  // namespace fdem
