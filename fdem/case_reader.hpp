// fdem/case_reader.hpp: the case reader's internals shared by its parts (fdem/case.cpp: the file, --set, the
// sections up to the interfaces, monitors, numerics and output; fdem/case_geometry.cpp: [geometry];
// fdem/case_stages.cpp: [[stages]]): the error context, the table reader that knows every key it was asked for,
// and the helpers they share. Not part of the engine's interface: include fdem/case.hpp.
#pragma once

#include <toml++/toml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "fdem/case.hpp"

namespace fdem::case_detail {

inline std::string fmt_num(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
}

// Edit distance counting a swap of two neighbouring letters as one edit (the commonest typo).
inline std::size_t edit_distance(const std::string& a, const std::string& b) {
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

inline std::string describe(const toml::node& n) {
    std::ostringstream s;
    if (n.is_string()) s << '"' << *n.value<std::string>() << '"';
    else if (n.is_table()) s << "a table";
    else if (n.is_array()) s << "an array";
    else n.visit([&](auto&& v) { s << v; });
    return s.str();
}

// Where a problem is reported: the case file and the lines of its nodes, or --set for overridden keys.
inline std::string g4(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.4g", v);
    return b;
}

struct Ctx {
    std::string file;
    std::vector<std::string> errors;
    std::set<std::string> set_paths;
    // Every key a Reader was asked for, as its documented path (cases/REFERENCE.md): an array element's index
    // becomes "[]" and the name of a material or group "NAME" ("stages[].supports[].vx", "materials.NAME.E").
    std::set<std::string> keys_read;

    void record(const std::string& path) {
        std::string out, part;
        std::stringstream ss(path);
        for (int i = 0; std::getline(ss, part, '.'); ++i) {
            if (!part.empty() && part.find_first_not_of("0123456789") == std::string::npos) {
                out += "[]";
                continue;
            }
            if (i == 1 && (out == "materials" || out == "groups")) part = "NAME";
            out += (out.empty() ? "" : ".") + part;
        }
        keys_read.insert(out);
    }

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

inline int line_of(const toml::node* n) { return n ? static_cast<int>(n->source().begin.line) : 0; }

// Reads the keys of one table; every key asked for is "known", and finish() reports the others.
class Reader {
public:
    Reader(Ctx& ctx, const toml::table& t, std::string path) : ctx_(ctx), t_(t), path_(std::move(path)) {}

    int line() const { return line_of(&t_); }
    std::string key_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
    bool has(const std::string& key) {
        known_.insert(key);
        ctx_.record(key_path(key));
        return t_.contains(key);
    }
    const toml::node* node(const std::string& key, bool required, const std::string& expect) {
        known_.insert(key);
        ctx_.record(key_path(key));
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

constexpr double kMinLength = 1e-6, kMaxLength = 1e4;  // m: bounds of every generated geometry's lengths

inline const std::vector<std::string> kComponents{"x", "y"};
inline int component_index(const std::string& c) { return c == "y" ? 1 : 0; }

// The sections read in their own files (each reports its problems into ctx, as load_case does).
void read_geometry(Ctx& ctx, Reader& top, CaseSpec& spec);  // fdem/case_geometry.cpp
void read_stages(Ctx& ctx, Reader& top, CaseSpec& spec);    // fdem/case_stages.cpp
// key = { type = "sin", ... } or { type = "table", points }: a time function (none: type ""); fdem/case_stages.cpp.
TimeFunction read_function(Ctx& ctx, Reader& r, const std::string& key);
// key = "x" | "y" | "xy" (fix, free, rigid): those components of s get `mode` (an error if one has a mode already).
void read_dof_set(Ctx& ctx, Reader& r, const std::string& key, DofMode mode, SupportSpec& s);

}  // namespace fdem::case_detail
