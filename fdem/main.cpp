// fdem command line: run, check, mesh. Exit codes (ARCHITECTURE.md): 0 done, 1 bad input, 2 run failed,
// 3 internal error.
#include <omp.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "fdem/case.hpp"
#include "fdem/omp_env.hpp"
#include "fdem/errors.hpp"
#include "fdem/model.hpp"
#include "fdem/scene.hpp"
#include "fdem/simulation.hpp"
#include "mesh/mesh.hpp"
#include "mesh/quality.hpp"
#include "mesh/vtu.hpp"

namespace {

const char* kUsage =
    "fdem " FDEM_VERSION ": 2D combined finite-discrete element simulation of masonry\n"
    "\n"
    "usage:\n"
    "  fdem run CASE.toml [--out DIR] [--set KEY=VALUE ...] [--threads N] [--quiet]\n"
    "      run a case; results go to DIR (default runs/<case name>): history.csv, summary.json,\n"
    "      snapshots/*.vtu + run.pvd, run.log\n"
    "  fdem check CASE.toml [--set KEY=VALUE ...]\n"
    "      validate a case and its mesh without running\n"
    "  fdem mesh CASE.toml [--out DIR] [--set KEY=VALUE ...]\n"
    "      mesh only: writes DIR/mesh.vtu (regions, bodies, edge classes) and prints statistics\n"
    "  fdem --help | --version\n"
    "\n"
    "options:\n"
    "  --set KEY=VALUE  override any case value; KEY is dotted, arrays of tables by 0-based index,\n"
    "                   VALUE is TOML (e.g. --set materials.stone.E=1.5e10 --set stages.1.duration=2)\n"
    "  --threads N      OpenMP threads (results are bit-identical for any N)\n"
    "  --out DIR        run folder\n"
    "  --quiet          no log lines on stdout, no progress line\n"
    "\n"
    "exit codes: 0 done, 1 bad input, 2 run failed (instability, inverted element, NaN), 3 internal error\n";

struct Args {
    std::string command, case_file, out;
    std::vector<std::string> sets;
    int threads = 0;
    bool quiet = false;
};

Args parse_args(int argc, char** argv) {
    Args a;
    if (argc < 2) throw fdem::InputError(std::string("no command given\n\n") + kUsage);
    a.command = argv[1];
    for (int i = 2; i < argc; ++i) {
        const std::string s = argv[i];
        auto value = [&](const char* opt) {
            if (i + 1 >= argc) throw fdem::InputError(std::string(opt) + " needs a value");
            return std::string(argv[++i]);
        };
        if (s == "--out") a.out = value("--out");
        else if (s == "--set") a.sets.push_back(value("--set"));
        else if (s.rfind("--set=", 0) == 0) a.sets.push_back(s.substr(6));
        else if (s == "--threads") {
            const std::string v = value("--threads");
            char* end = nullptr;
            const long n = std::strtol(v.c_str(), &end, 10);
            if (*end || n < 1 || n > 1024) throw fdem::InputError("--threads: expected a whole number >= 1, got '" + v + "'");
            a.threads = static_cast<int>(n);
        } else if (s == "--quiet") a.quiet = true;
        else if (!s.empty() && s[0] == '-') throw fdem::InputError("unknown option '" + s + "' (see fdem --help)");
        else if (a.case_file.empty()) a.case_file = s;
        else throw fdem::InputError("unexpected argument '" + s + "' (see fdem --help)");
    }
    return a;
}

}  // namespace

int main(int argc, char** argv) {
    fdem::ensure_wait_policy(argv);
    try {
        if (argc >= 2 && (!std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help"))) {
            std::cout << kUsage;
            return 0;
        }
        if (argc >= 2 && !std::strcmp(argv[1], "--version")) {
            std::cout << "fdem " FDEM_VERSION "\n";
            return 0;
        }
        const Args a = parse_args(argc, argv);
        if (a.command != "run" && a.command != "check" && a.command != "mesh")
            throw fdem::InputError("unknown command '" + a.command + "' (commands: run, check, mesh; see fdem --help)");
        if (a.case_file.empty()) throw fdem::InputError("fdem " + a.command + ": no case file given");
        if (a.command == "check") {
            const fdem::CaseSpec spec = fdem::load_case(a.case_file, a.sets);
            fdem::RunOptions quiet;
            quiet.quiet = true;
            quiet.threads = a.threads;
            // Building the simulation validates the laws of contact and fracture too.
            const fdem::Simulation sim(spec, fdem::build_scene(spec), quiet);
            std::cout << a.case_file << ": ok: " << sim.model().n_triangles() << " triangles, " << sim.model().n_nodes()
                      << " nodes, " << sim.model().cohesive.size() << " cohesive elements, " << spec.stages.size()
                      << " stage(s), time step " << sim.dt() << " s\n";
            return 0;
        }
        if (a.command == "mesh") {
            const fdem::CaseSpec spec = fdem::load_case(a.case_file, a.sets);
            fdem::mesh::RoughnessStats rough;
            const fdem::mesh::Topology topo = fdem::build_topology_only(spec, &rough);
            const std::filesystem::path dir = a.out.empty() ? std::filesystem::path("runs") / spec.name : std::filesystem::path(a.out);
            std::filesystem::create_directories(dir);
            fdem::mesh::write_topology_vtu((dir / "mesh.vtu").string(), topo);
            std::cout << fdem::mesh::format_stats(fdem::mesh::mesh_stats(topo));
            if (rough.points > 0)
                std::cout << "joint roughness      " << rough.points << " face points moved inwards, mean " << rough.mean
                          << " m, largest " << rough.largest << " m\n";
            std::cout << "mesh written to " << (dir / "mesh.vtu").string() << "\n";
            return 0;
        }
        fdem::RunOptions opt;
        opt.out_dir = a.out;
        opt.threads = a.threads;
        opt.quiet = a.quiet;
        opt.progress = !a.quiet && isatty(2);
        return fdem::run_case(a.case_file, a.sets, opt);
    } catch (const fdem::InputError& e) {
        std::cerr << "error: " << e.what() << std::endl;
        return 1;
    } catch (const fdem::mesh::MeshError& e) {
        std::cerr << "error: " << e.what() << std::endl;
        return 1;
    } catch (const fdem::RunError& e) {
        std::cerr << "error: run failed: " << e.what() << std::endl;
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "internal error: " << e.what() << std::endl;
        return 3;
    } catch (...) {
        std::cerr << "internal error: unknown exception" << std::endl;
        return 3;
    }
}
