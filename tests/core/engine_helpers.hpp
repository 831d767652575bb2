// Helpers shared by the engine tests: temporary case files, running the fdem executable.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>

#include "fdem/case.hpp"
#include "fdem/model.hpp"
#include "fdem/scene.hpp"
#include "fdem/simulation.hpp"

namespace testing {

inline std::filesystem::path tmp_dir(const std::string& name) {
    auto d = std::filesystem::path(FDEM_TEST_TMP) / name;
    std::filesystem::remove_all(d);
    std::filesystem::create_directories(d);
    return d;
}

inline std::string write_text(const std::filesystem::path& p, const std::string& text) {
    std::ofstream f(p);
    f << text;
    return p.string();
}

inline std::string read_text(const std::filesystem::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::stringstream s;
    s << f.rdbuf();
    return s.str();
}

struct CliResult {
    int code = -1;
    std::string out, err;
};

// Runs the fdem executable with `args` (already quoted as needed) and captures its exit code and output.
inline CliResult run_fdem(const std::string& args, const std::filesystem::path& dir) {
    const auto out = dir / "stdout.txt", err = dir / "stderr.txt";
    const std::string cmd = std::string("\"") + FDEM_BIN + "\" " + args + " >\"" + out.string() + "\" 2>\"" + err.string() + "\"";
    const int status = std::system(cmd.c_str());
    CliResult r;
    r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = read_text(out);
    r.err = read_text(err);
    return r;
}

// The elastic column of the rigid-support and mass-damping tests: 0.2 m x 1.0 m, t = 0.1 m, 50 mm mesh,
// E = 1 GPa, nu = 0.2, 2000 kg/m^3, one region "body"; the caller appends its stages.
inline std::string column_case_head(const std::string& name) {
    return "\n[case]\nname = \"" + name + R"("
thickness = 0.1
plane = "stress"
[geometry]
type = "rectangle"
width = 0.2
height = 1.0
mesh_size = 0.05
[materials.m]
E = 1.0e9
nu = 0.2
density = 2000.0
[regions]
body = "m"
)";
}

// The elastic column with a monitor "F" of the x load on its left edge (the spring-load tests); stages follow.
inline std::string column_with_left_load_monitor(const std::string& name) {
    return column_case_head(name) + R"(
[[monitors]]
name = "F"
type = "load"
group = "left"
component = "x"
)";
}

// Mass-weighted mean vertical velocity of all nodes (m/s): the momentum of a body over its mass.
inline double mean_velocity_y(const fdem::Simulation& sim) {
    const auto& md = sim.model();
    double p = 0, m = 0;
    for (int k = 0; k < md.n_nodes(); ++k) p += md.mass[k] * md.v[2 * k + 1], m += md.mass[k];
    return p / m;
}

// Loads a case from text, builds its scene (mesh, topology, joints, contact) and returns a Simulation that
// writes no files. The case goes to a fresh tmp_dir(name)/case.toml (a mesh file it names lives elsewhere);
// threads > 0 sets the run's thread count.
inline fdem::Simulation make_simulation(const std::string& case_text, const std::string& name,
                                        const std::vector<std::string>& overrides = {}, int threads = 0) {
    const auto dir = tmp_dir(name);
    const std::string path = write_text(dir / "case.toml", case_text);
    fdem::CaseSpec spec = fdem::load_case(path, overrides);
    fdem::Model model = fdem::build_scene(spec);
    fdem::RunOptions opt;
    opt.quiet = true;
    if (threads > 0) opt.threads = threads;
    return fdem::Simulation(spec, std::move(model), opt);
}

}  // namespace testing
