// fdem command line: run, check, mesh. Exit codes (ARCHITECTURE.md): 0 done, 1 bad input, 2 run failed,
// 3 internal error.
#include <cstdio>
#include <omp.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "fdem/version.hpp"
#include "fdem/case.hpp"
#include "fdem/case_json.hpp"
#include "fdem/omp_env.hpp"
#include "fdem/common/errors.hpp"
#include "fdem/limit_export.hpp"
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
    "  fdem run CASE.toml [-o DIR] [-s KEY=VALUE ...] [-t N] [-q]\n"
    "      run a case; results go to DIR (default runs/<case name>): history.csv, summary.json,\n"
    "      snapshots/*.vtu + run.pvd, run.log, checkpoint.bin\n"
    "  fdem run CASE.toml --restart DIR [-s KEY=VALUE ...] [-t N] [-q]\n"
    "      continue the run in DIR from its checkpoint.bin (same case, same --set options, same fdem build)\n"
    "  fdem check CASE.toml [-s KEY=VALUE ...] [--json]\n"
    "      validate a case and its mesh without running; with --json, print the resolved case as one JSON object\n"
    "  fdem mesh CASE.toml [-o DIR] [-s KEY=VALUE ...]\n"
    "      mesh only: writes DIR/mesh.vtu (regions, bodies, edge classes) and DIR/limit_model.json (the rigid\n"
    "      bodies, joints, supports and loads of the last stage, for fdem-tools limit) and prints statistics\n"
    "  fdem --help | --version       (fdem COMMAND -h prints this too)\n"
    "\n"
    "options (long forms also as --option=VALUE):\n"
    "  -s, --set KEY=VALUE  override any case value; KEY is dotted, elements of arrays of tables count from 1,\n"
    "                       VALUE is TOML (e.g. --set materials.stone.E=1.5e10 --set stages.1.duration=2:\n"
    "                       the duration of the first stage)\n"
    "  --unset KEY          remove a key of the case, so that its default applies (e.g. --unset numerics.dt);\n"
    "                       applied in order with the --set options\n"
    "  -t, -j, --threads N  OpenMP threads (results are bit-identical for any N)\n"
    "  -o, --out DIR        run folder\n"
    "  -q, --quiet          nothing on stdout and no progress lines; errors and warnings still go to stderr,\n"
    "                       and run.log in the run folder has the whole log\n"
    "  --restart DIR        continue the run in DIR from its last checkpoint; history.csv and cracks.csv go on\n"
    "                       from the checkpoint's row\n"
    "  --progress S         when stderr is not a terminal (batch, cluster), a progress line in the log every\n"
    "                       S seconds of wall time (default 10): stage, time, steps/s, stage and run time left\n"
    "  --json               fdem check: instead of the summary line, one JSON object on stdout (nothing else there):\n"
    "                       case_file, case_hash (as in summary.json), overrides, case (the TOML after --set and\n"
    "                       --unset), resolved (the values the run uses, defaults applied: geometry and mesh sizes,\n"
    "                       numerics and the time step, materials, interfaces, monitors, stages with the damping each\n"
    "                       runs with, output, curve and its sign, reference, the files the case reads; SI units,\n"
    "                       null where nothing is given and nothing applies), mesh (counts), notes, warnings. Bad\n"
    "                       input: the message on stderr, exit 1, nothing on stdout\n"
    "  -h, --help           this text\n"
    "\n"
    "signals: SIGINT, SIGTERM and SIGUSR1 (Slurm's --signal=USR1@SECONDS) finish the step, write a checkpoint and\n"
    "  the outputs with status \"interrupted\"\n"
    "exit codes: 0 done, 1 bad input, 2 run failed (instability, inverted element, NaN), 3 internal error,\n"
    "  130 / 143 / 138 stopped by SIGINT / SIGTERM / SIGUSR1 (128 + the signal number)\n";

struct Args {
    std::string command, case_file, out, restart;
    long stop_after_steps = 0;  // hidden testing option --stop-after-steps N
    std::vector<std::string> sets;
    int threads = 0;
    bool quiet = false;
    bool help = false;
    bool json = false;  // fdem check --json
    double progress_interval = 10.0;  // s
};

// Options of every command: long forms "--out DIR" and "--out=DIR", short forms "-o DIR" (also "-oDIR" is not
// accepted: one form per option keeps the messages plain). -h/--help anywhere after the command prints the usage.
Args parse_args(int argc, char** argv) {
    Args a;
    if (argc < 2) throw fdem::InputError(std::string("no command given\n\n") + kUsage);
    a.command = argv[1];
    for (int i = 2; i < argc; ++i) {
        std::string s = argv[i];
        std::string inline_value;
        bool has_inline = false;
        if (s.rfind("--", 0) == 0) {
            if (const auto eq = s.find('='); eq != std::string::npos) {
                inline_value = s.substr(eq + 1);
                s = s.substr(0, eq);
                has_inline = true;
            }
        }
        auto value = [&](const std::string& opt) {
            if (has_inline) return inline_value;
            if (i + 1 >= argc) throw fdem::InputError(opt + " needs a value (see fdem --help)");
            return std::string(argv[++i]);
        };
        auto no_value = [&](const std::string& opt) {
            if (has_inline) throw fdem::InputError(opt + " takes no value, got '" + opt + "=" + inline_value + "'");
        };
        if (s == "--out" || s == "-o") a.out = value(s);
        else if (s == "--restart") a.restart = value(s);
        else if (s == "--stop-after-steps") {
            const std::string v = value(s);
            char* end = nullptr;
            const long n = std::strtol(v.c_str(), &end, 10);
            if (v.empty() || *end || n < 1) throw fdem::InputError(s + ": expected a whole number of steps >= 1, got '" + v + "'");
            a.stop_after_steps = n;
        }
        else if (s == "--set" || s == "-s") a.sets.push_back(value(s));
        else if (s == "--unset") a.sets.push_back("!" + value(s));  // load_case: '!' KEY removes the key
        else if (s == "--threads" || s == "-t" || s == "-j") {
            const std::string v = value(s);
            char* end = nullptr;
            const long n = std::strtol(v.c_str(), &end, 10);
            if (v.empty() || *end || n < 1 || n > 1024)
                throw fdem::InputError(s + ": expected a whole number >= 1, got '" + v + "'");
            a.threads = static_cast<int>(n);
        } else if (s == "--progress") {
            const std::string v = value(s);
            char* end = nullptr;
            const double p = std::strtod(v.c_str(), &end);
            if (v.empty() || *end || !(p > 0) || !std::isfinite(p))
                throw fdem::InputError("--progress: expected seconds > 0, got '" + v + "'");
            a.progress_interval = p;
        } else if (s == "--quiet" || s == "-q") {
            no_value(s);
            a.quiet = true;
        } else if (s == "--json") {
            no_value(s);
            a.json = true;
        } else if (s == "--help" || s == "-h") {
            no_value(s);
            a.help = true;
        } else if (!s.empty() && s[0] == '-') throw fdem::InputError("unknown option '" + s + "' (see fdem --help)");
        else if (a.case_file.empty()) a.case_file = s;
        else throw fdem::InputError("unexpected argument '" + s + "' (see fdem --help)");
    }
    return a;
}

// summary.json case_hash: the resolved case (its TOML after --set), as fdem check prints it.
std::string hash_hex(const fdem::CaseSpec& spec) {
    char hex[17];
    std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(spec.resolved_hash));
    return hex;
}

// fdem check --json: the case as the engine resolved it (fdem/case_json.hpp), with what building the model found.
fdem::Json check_json(const Args& a, const fdem::CaseSpec& spec, const fdem::Simulation& sim,
                      const std::vector<std::string>& warnings) {
    fdem::Json j = fdem::Json::object();
    j["case_file"] = a.case_file;
    j["case_hash"] = hash_hex(spec);
    fdem::Json ov = fdem::Json::array();
    for (const auto& [k, v] : spec.overrides) {  // in order; an --unset KEY as [KEY, "(unset)"]
        fdem::Json kv = fdem::Json::array();
        kv.push_back(k);
        kv.push_back(v);
        ov.push_back(kv);
    }
    j["overrides"] = ov;
    j["case"] = fdem::toml_to_json(fdem::resolved_case_tree(a.case_file, a.sets));
    fdem::Json r = fdem::resolved_values_json(spec);
    r["numerics"]["dt_s"] = sim.dt();  // the time step the run starts with
    j["resolved"] = r;
    fdem::Json mesh = fdem::Json::object();
    mesh["triangles"] = static_cast<long long>(sim.model().n_triangles());
    mesh["nodes"] = static_cast<long long>(sim.model().n_nodes());
    mesh["cohesive_elements"] = static_cast<long long>(sim.model().cohesive.size());
    j["mesh"] = mesh;
    fdem::Json notes = fdem::Json::array();
    for (const std::string& n : sim.interactions().penalty_notes()) notes.push_back(n);
    j["notes"] = notes;
    fdem::Json warn = fdem::Json::array();
    for (const std::string& w : warnings) warn.push_back(w);
    j["warnings"] = warn;
    return j;
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
            std::cout << "fdem " FDEM_VERSION " (build " << fdem::build_id() << ")\n";
            return 0;
        }
        const Args a = parse_args(argc, argv);
        if (a.help) {
            std::cout << kUsage;
            return 0;
        }
        if (a.command != "run" && a.command != "check" && a.command != "mesh")
            throw fdem::InputError("unknown command '" + a.command + "' (commands: run, check, mesh; see fdem --help)");
        if (a.case_file.empty()) throw fdem::InputError("fdem " + a.command + ": no case file given");
        if (a.command != "run" && (!a.restart.empty() || a.stop_after_steps > 0))
            throw fdem::InputError("fdem " + a.command + ": --restart and --stop-after-steps belong to fdem run");
        if (a.command != "check" && a.json) throw fdem::InputError("fdem " + a.command + ": --json belongs to fdem check");
        if (a.command == "check") {
            const fdem::CaseSpec spec = fdem::load_case(a.case_file, a.sets);
            const std::vector<std::string> warnings = fdem::plausibility_warnings(spec);
            for (const std::string& w : warnings) std::cerr << "warning: " << w << "\n";
            fdem::RunOptions quiet;
            quiet.quiet = true;
            quiet.threads = a.threads;
            // Building the simulation validates the laws of contact and fracture too.
            const fdem::Simulation sim(spec, fdem::build_scene(spec), quiet);
            if (a.json) {  // built whole before anything is written: an error leaves stdout empty
                std::cout << check_json(a, spec, sim, warnings).dump();
                return 0;
            }
            std::cout << a.case_file << ": ok: " << sim.model().n_triangles() << " triangles, " << sim.model().n_nodes()
                      << " nodes, " << sim.model().cohesive.size() << " cohesive elements, " << spec.stages.size()
                      << " stage(s), time step " << sim.dt() << " s, case hash " << hash_hex(spec) << "\n";
            for (const std::string& note : sim.interactions().penalty_notes()) std::cout << note << "\n";
            return 0;
        }
        if (a.command == "mesh") {
            const fdem::CaseSpec spec = fdem::load_case(a.case_file, a.sets);
            for (const std::string& w : fdem::plausibility_warnings(spec)) std::cerr << "warning: " << w << "\n";
            fdem::mesh::RoughnessStats rough;
            const fdem::mesh::Topology topo = fdem::build_topology_only(spec, &rough);
            const std::filesystem::path dir = a.out.empty() ? std::filesystem::path("runs") / spec.name : std::filesystem::path(a.out);
            std::filesystem::create_directories(dir);
            fdem::mesh::write_topology_vtu((dir / "mesh.vtu").string(), topo);
            fdem::write_limit_model((dir / "limit_model.json").string(), spec, topo);
            std::cout << fdem::mesh::format_stats(fdem::mesh::mesh_stats(topo));
            if (rough.points > 0)
                std::cout << "joint roughness      " << rough.points << " face points moved inwards, mean " << rough.mean
                          << " m, largest " << rough.largest << " m\n";
            std::cout << "mesh written to " << (dir / "mesh.vtu").string() << "\n";
            std::cout << "limit model written to " << (dir / "limit_model.json").string() << "\n";
            return 0;
        }
        fdem::RunOptions opt;
        opt.out_dir = a.out;
        opt.restart_dir = a.restart;
        opt.stop_after_steps = a.stop_after_steps;
        opt.threads = a.threads;
        opt.quiet = a.quiet;
        // On a terminal, a progress line rewritten in place on stderr; otherwise (batch and cluster logs) a progress
        // line on stdout and in run.log every progress_interval seconds.
        opt.progress = !a.quiet && isatty(2);
        opt.progress_log = !a.quiet && !isatty(2);
        opt.progress_interval = a.progress_interval;
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
