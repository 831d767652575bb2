// Seeded mutation fuzzers (issue 26).
// 1. Over the shipped cases: one numeric value of a case file is replaced by an extreme, denormal, negative,
//    non-finite or non-numeric value, and `fdem check` must answer with exit code 0 or 1 (never a crash, abort or
//    hang), every exit 1 naming the file, within 30 s of CPU per input. FDEM_FUZZ_N inputs (default 60, about 30 s on 1
//    core); the validation-labelled copy (tests/CMakeLists.txt) runs 10,000.
// 2. Short runs of a small case on a Gmsh .msh mesh written here: either one value of the case or the mesh file is
//    mutated (a number replaced, a line deleted or repeated, the file cut short), and `fdem run` (capped at 200 steps
//    by --stop-after-steps, exit 138) must exit 0, 1 or 2, name the case or mesh file in every exit 1, write no NaN
//    or inf in the history of a run that completed or was capped, and take at most 30 s of CPU. FDEM_FUZZ_RUN_N inputs
//    (default 160: 240 inputs took 46 s user + 26 s system CPU on a loaded machine); the validation copy runs 10,000.
#include <catch2/catch.hpp>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "engine_helpers.hpp"

namespace {

int fuzz_inputs(int fallback, const char* var = "FDEM_FUZZ_N") {
    const char* n = std::getenv(var);
    return n ? std::atoi(n) : fallback;
}

// A 0.2 x 0.1 m rectangle of 4 x 2 squares, each split into 2 triangles (Gmsh MSH 2.2): physical surface "body" (1),
// physical lines "bottom" (2) and "top" (3).
std::string small_msh() {
    std::string nodes, elems;
    int n = 0, e = 0;
    for (int j = 0; j <= 2; ++j)
        for (int i = 0; i <= 4; ++i)
            nodes += std::to_string(++n) + " " + std::to_string(0.05 * i) + " " + std::to_string(0.05 * j) + " 0\n";
    auto id = [](int i, int j) { return 1 + i + 5 * j; };
    for (int i = 0; i < 4; ++i) {
        elems += std::to_string(++e) + " 1 2 2 1 " + std::to_string(id(i, 0)) + " " + std::to_string(id(i + 1, 0)) + "\n";
        elems += std::to_string(++e) + " 1 2 3 3 " + std::to_string(id(i, 2)) + " " + std::to_string(id(i + 1, 2)) + "\n";
    }
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 4; ++i) {
            const int a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
            elems += std::to_string(++e) + " 2 2 1 5 " + std::to_string(a) + " " + std::to_string(b) + " " + std::to_string(c) + "\n";
            elems += std::to_string(++e) + " 2 2 1 5 " + std::to_string(a) + " " + std::to_string(c) + " " + std::to_string(d) + "\n";
        }
    return "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n1 2 \"bottom\"\n1 3 \"top\"\n2 1 \"body\"\n$EndPhysicalNames\n"
           "$Nodes\n" + std::to_string(n) + "\n" + nodes + "$EndNodes\n$Elements\n" + std::to_string(e) + "\n" + elems + "$EndElements\n";
}

const char* kSmallCase = R"([case]
name = "fuzz_small"
thickness = 0.1
[geometry]
type = "msh"
file = "small.msh"
[materials.m]
E = 1.0e9
nu = 0.2
density = 2000.0
viscous_damping = 0.1
[regions]
body = "m"
[[monitors]]
name = "uy"
type = "displacement"
group = "top"
component = "y"
[[monitors]]
name = "R"
type = "reaction"
group = "bottom"
component = "y"
[output]
history_interval = 2e-5
[[stages]]
name = "load"
duration = 5e-4
local_damping = 0.1
gravity = [0.0, -9.81]
  [[stages.supports]]
  group = "bottom"
  fix = "xy"
  [[stages.loads]]
  group = "top"
  force = [1000.0, -5000.0]
  ramp = 2e-4
)";

std::vector<std::string> split_lines(const std::string& text) {
    std::vector<std::string> lines;
    std::size_t pos = 0;
    while (pos < text.size()) {
        const auto e = text.find('\n', pos);
        lines.push_back(text.substr(pos, e == std::string::npos ? std::string::npos : e - pos));
        pos = e == std::string::npos ? text.size() : e + 1;
    }
    return lines;
}

std::string join_lines(const std::vector<std::string>& lines) {
    std::string out;
    for (const auto& l : lines) out += l + "\n";
    return out;
}

}  // namespace

TEST_CASE("mutated shipped cases give fdem check exit code 0 or 1 naming the file", "[engine]") {
    const int n = fuzz_inputs(60);
    const auto dir = testing::tmp_dir("fuzz_" + std::to_string(n));
    const std::vector<std::string> cases = {"elastic/cantilever.toml", "tilting/tilting_wall.toml",
                                            "vermeltfoort/vermeltfoort_121.toml", "lourenco2005/k25_N30.toml",
                                            "settlement/bui2017_settlement.toml"};
    const std::vector<std::string> values = {"0", "-1", "5e-324", "1e-300", "1e-12", "1e300", "1.7976931348623157e308",
                                             "-1e308", "nan", "inf", "-inf", "\"text\"", "[]", "1e20", "1e10", "1e6"};
    std::mt19937 rng(26);
    const std::regex numeric_line(R"(^(\s*[A-Za-z_][A-Za-z0-9_]*\s*=\s*)(-?[0-9][0-9.eE+\-_]*)(.*)$)");
    int codes[4] = {0, 0, 0, 0};
    for (int i = 0; i < n; ++i) {
        const std::string name = cases[rng() % cases.size()];
        const std::string text = testing::read_text(std::filesystem::path(FDEM_CASES_DIR) / name);
        std::vector<std::string> lines;
        std::vector<std::size_t> numeric;
        std::size_t pos = 0;
        while (pos < text.size()) {
            const auto e = text.find('\n', pos);
            lines.push_back(text.substr(pos, e == std::string::npos ? std::string::npos : e - pos));
            if (std::regex_match(lines.back(), numeric_line)) numeric.push_back(lines.size() - 1);
            pos = e == std::string::npos ? text.size() : e + 1;
        }
        REQUIRE(!numeric.empty());
        const std::size_t li = numeric[rng() % numeric.size()];
        const std::string value = values[rng() % values.size()];
        const std::string mutated_line = std::regex_replace(lines[li], numeric_line, "$1" + value + "$3");
        std::string out;
        for (std::size_t k = 0; k < lines.size(); ++k) out += (k == li ? mutated_line : lines[k]) + "\n";
        const std::string file = "fuzz_" + std::to_string(i) + ".toml";
        testing::write_text(dir / file, out);
        // At most 30 s of CPU per input (`ulimit -t`: SIGXCPU or SIGKILL, exit 152 or 137) and 300 s of wall time (`timeout`, exit 124, for
        // a blocked process): either fails the input, as does a signal (code -1) or exit 2/3. A wall-clock bound alone
        // would fail an input that takes 1.6 s of CPU on a machine loaded by other jobs.
        testing::CliResult r;
        {
            const auto o = dir / "stdout.txt", e = dir / "stderr.txt";
            const std::string cmd = std::string("ulimit -t 30; timeout 300 \"") + FDEM_BIN + "\" check \"" + (dir / file).string() + "\" >\"" +
                                    o.string() + "\" 2>\"" + e.string() + "\"";
            const int status = std::system(cmd.c_str());
            r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
            r.err = testing::read_text(e);
        }
        INFO("input " << i << " from " << name << " line " << li + 1 << ": " << mutated_line << " -> exit " << r.code << ": " << r.err);
        CHECK((r.code == 0 || r.code == 1));
        if (r.code == 1) CHECK(r.err.find(file) != std::string::npos);
        if (r.code >= 0 && r.code <= 3) ++codes[r.code];
    }
    WARN("fuzz: " << n << " inputs, exit 0: " << codes[0] << ", exit 1: " << codes[1] << ", exit 2: " << codes[2]
                  << ", exit 3: " << codes[3]);
}

TEST_CASE("mutated small cases and meshes give fdem run exit code 0 1 or 2 with no NaN and the file named", "[engine]") {
    const int n = fuzz_inputs(160, "FDEM_FUZZ_RUN_N");
    const auto dir = testing::tmp_dir("fuzz_run_" + std::to_string(n));
    const std::string msh = small_msh();
    const std::vector<std::string> values = {"0", "-1", "5e-324", "1e-300", "1e-12", "1e300", "-1e308", "nan", "inf",
                                             "\"text\"", "[]", "1e20", "1e6", "3", "0.5", "-0.05"};
    const std::vector<std::string> mesh_values = {"0", "-1", "1e300", "nan", "inf", "99999", "3", "1e-300", "0.025",
                                                  "-0.05", "2147483648", "x", ""};
    const std::regex numeric_line(R"(^(\s*[A-Za-z_][A-Za-z0-9_]*\s*=\s*)(-?[0-9][0-9.eE+\-_]*)(.*)$)");
    std::mt19937 rng(2026);
    int codes[4] = {0, 0, 0, 0}, capped = 0, mesh_inputs = 0, named_mesh = 0;
    double slowest = 0;
    for (int i = 0; i < n; ++i) {
        const auto in = dir / ("in_" + std::to_string(i));
        std::filesystem::create_directories(in);
        std::string case_text = kSmallCase, mesh_text = msh, what;
        const bool mutate_mesh = (i % 2) == 1;
        if (mutate_mesh) {
            ++mesh_inputs;
            std::vector<std::string> lines = split_lines(msh);
            const int kind = static_cast<int>(rng() % 4);
            const std::size_t li = rng() % lines.size();
            if (kind == 0) {  // one whitespace-separated token replaced
                std::vector<std::string> tok;
                std::istringstream ls(lines[li]);
                for (std::string t; ls >> t;) tok.push_back(t);
                if (!tok.empty()) tok[rng() % tok.size()] = mesh_values[rng() % mesh_values.size()];
                std::string l;
                for (const auto& t : tok) l += (l.empty() ? "" : " ") + t;
                what = "mesh line " + std::to_string(li + 1) + " -> '" + l + "'";
                lines[li] = l;
            } else if (kind == 1) {
                what = "mesh line " + std::to_string(li + 1) + " deleted";
                lines.erase(lines.begin() + static_cast<long>(li));
            } else if (kind == 2) {
                what = "mesh line " + std::to_string(li + 1) + " repeated";
                lines.insert(lines.begin() + static_cast<long>(li), lines[li]);
            }
            mesh_text = join_lines(lines);
            if (kind == 3) {
                const std::size_t cut = rng() % msh.size();
                what = "mesh cut at byte " + std::to_string(cut);
                mesh_text = msh.substr(0, cut);
            }
        } else {
            std::vector<std::string> lines = split_lines(case_text);
            std::vector<std::size_t> numeric;
            for (std::size_t k = 0; k < lines.size(); ++k)
                if (std::regex_match(lines[k], numeric_line)) numeric.push_back(k);
            const std::size_t li = numeric[rng() % numeric.size()];
            lines[li] = std::regex_replace(lines[li], numeric_line, "$1" + values[rng() % values.size()] + "$3");
            what = "case line " + std::to_string(li + 1) + " -> '" + lines[li] + "'";
            case_text = join_lines(lines);
        }
        testing::write_text(in / "case.toml", case_text);
        testing::write_text(in / "small.msh", mesh_text);
        const auto o = in / "stdout.txt", e = in / "stderr.txt";
        const std::string cmd = std::string("ulimit -t 30; timeout 300 env OMP_WAIT_POLICY=passive \"") + FDEM_BIN + "\" run \"" + (in / "case.toml").string() +
                                "\" -o \"" + (in / "run").string() + "\" --threads 1 --quiet --stop-after-steps 200 >\"" + o.string() +
                                "\" 2>\"" + e.string() + "\"";
        const auto t0 = std::chrono::steady_clock::now();
        const int status = std::system(cmd.c_str());
        slowest = std::max(slowest, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        const std::string err = testing::read_text(e);
        INFO("input " << i << ": " << what << " -> exit " << code << ": " << err);
        CHECK((code == 0 || code == 1 || code == 2 || code == 138));
        if (code == 1) {
            const bool names = err.find(mutate_mesh ? "small.msh" : "case.toml") != std::string::npos ||
                               err.find("case.toml") != std::string::npos;
            CHECK(names);
            if (mutate_mesh && err.find("small.msh") != std::string::npos) ++named_mesh;
        }
        if (code == 0 || code == 138) {
            std::string h = testing::read_text(in / "run" / "history.csv");
            std::transform(h.begin(), h.end(), h.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
            CHECK(!h.empty());
            CHECK(h.find("nan") == std::string::npos);
            CHECK(h.find("inf") == std::string::npos);
        }
        if (code >= 0 && code <= 3) ++codes[code];
        if (code == 138) ++capped;
        // Keep the folder of a failing input only.
        if (code == 0 || code == 1 || code == 2 || code == 138) std::filesystem::remove_all(in);
    }
    WARN("fuzz runs: " << n << " inputs (" << mesh_inputs << " mutated meshes), exit 0: " << codes[0] << ", exit 1: " << codes[1]
                       << " (" << named_mesh << " naming the mesh file), exit 2: " << codes[2] << ", exit 3: " << codes[3]
                       << ", capped at 200 steps: " << capped << ", slowest input " << slowest << " s");
}
