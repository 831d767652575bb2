// fdem_bench: step throughput (triangle-steps per second) for 1 and 2 threads (or --threads LIST), median of
// several runs, written to a CSV, with the time per step of each kernel (Simulation::profile and the contact
// statistics): triangle forces, cohesive elements, contact detection, contact forces (pair kernels), contact scatter
// (the sum in pair order, each thread its own nodes), integration (rigid groups, node update, books) and the rest
// (insertion, loads, damage, outputs). Without --case: triangle forces and integration of an elastic plate of about N
// triangles. With --case FILE: the first steps of that case's first stage (contact, joints and all), so that the
// thread scaling of a real scene is measured; --set key=value as for `fdem run`.
//   fdem_bench [--triangles N | --case FILE [--set k=v ...]] [--steps S] [--repeats R] [--threads 1,2] [--csv FILE]
// fdem_bench --nodes N [...]: the node update kernel (fdem/node_update.hpp) alone on N free nodes.
// fdem_bench --probe [--csv FILE]: what the machine gives each thread, to read the figures above by (Linux): per CPU
// of the process's set, the latency of a dependent load over 256 KB and 4 MB and a core-bound loop's time, and the
// round trip of a cache line between the first CPU and each other one. A shared or virtual machine can give its
// CPUs different cache latencies and a slow path between them (BENCHMARKS.md, "How to measure").
#ifdef __linux__
#include <pthread.h>
#include <sched.h>
#endif
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fdem/node_update.hpp"
#include "fdem/case.hpp"
#include "fdem/omp_env.hpp"
#include "fdem/model.hpp"
#include "fdem/scene.hpp"
#include "fdem/simulation.hpp"
#include "mesh/gmsh_source.hpp"

namespace {

#ifdef __linux__
// Pins the calling thread to one CPU; false when the system refuses.
bool pin_to(int cpu) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    return pthread_setaffinity_np(pthread_self(), sizeof set, &set) == 0;
}

// Nanoseconds per load of a chain of dependent loads through a random cycle over `bytes` (Sattolo's shuffle, fixed
// seed): the latency of the cache level that holds that many bytes. Best of three passes.
double chase_ns(std::size_t bytes) {
    const std::size_t n = bytes / sizeof(std::size_t);
    std::vector<std::size_t> next(n);
    for (std::size_t i = 0; i < n; ++i) next[i] = i;
    std::mt19937_64 rng(12345);
    for (std::size_t i = n - 1; i > 0; --i) std::swap(next[i], next[rng() % i]);  // one cycle through all
    std::size_t k = 0;
    for (std::size_t i = 0; i < n; ++i) k = next[k];  // warm
    const long loads = 4000000;
    double best = 1e30;
    for (int pass = 0; pass < 3; ++pass) {
        const auto t0 = std::chrono::steady_clock::now();
        for (long i = 0; i < loads; ++i) k = next[k];
        const double ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
        best = std::min(best, ns / loads);
    }
    if (k == n) std::printf(" ");  // (k is used: the chain is not optimised away)
    return best;
}

// Nanoseconds per iteration of eight independent multiply-add chains: the core's speed without memory.
double core_ns() {
    volatile double seed = 0.9999999;
    double a[8] = {1, 2, 3, 4, 5, 6, 7, 8};
    const double c = seed;
    const long iters = 20000000;
    const auto t0 = std::chrono::steady_clock::now();
    for (long i = 0; i < iters; ++i)
        for (double& q : a) q = q * c + 1e-7;
    const double ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
    volatile double sink = a[0] + a[7];
    (void)sink;
    return ns / iters;
}

// Nanoseconds for a cache line to go from CPU a to CPU b and back (two threads taking turns on one counter).
double round_trip_ns(int a, int b) {
    alignas(64) std::atomic<long> turn{0};
    const long trips = 100000;
    std::atomic<bool> pinned_ok{true};
    std::thread other([&] {
        if (!pin_to(b)) pinned_ok = false;
        for (long i = 1; i < 2 * trips; i += 2) {
            while (turn.load(std::memory_order_acquire) != i) {
            }
            turn.store(i + 1, std::memory_order_release);
        }
    });
    pin_to(a);
    const auto t0 = std::chrono::steady_clock::now();
    for (long i = 0; i < 2 * trips; i += 2) {
        turn.store(i + 1, std::memory_order_release);
        while (turn.load(std::memory_order_acquire) != i + 2) {
        }
    }
    const double ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0).count();
    other.join();
    return pinned_ok ? ns / trips : std::numeric_limits<double>::quiet_NaN();
}
#endif

int probe(const std::string& csv) {
#ifdef __linux__
    cpu_set_t set;
    CPU_ZERO(&set);
    if (sched_getaffinity(0, sizeof set, &set) != 0) {
        std::cerr << "fdem_bench --probe: cannot read the CPUs this process may run on\n";
        return 1;
    }
    std::vector<int> cpus;
    for (int c = 0; c < CPU_SETSIZE; ++c)
        if (CPU_ISSET(c, &set)) cpus.push_back(c);
    std::ofstream out(csv);
    if (!out) {
        std::cerr << "error: cannot write the CSV file '" << csv << "'\n";
        return 1;
    }
    out << "cpu,load_256k_ns,load_4m_ns,core_loop_ns,round_trip_with_first_ns\n";
    std::printf("cpu  load 256 KB (ns)  load 4 MB (ns)  core loop (ns)  round trip with cpu %d (ns)\n", cpus[0]);
    for (const int c : cpus) {
        const double nan = std::numeric_limits<double>::quiet_NaN();
        double l1 = nan, l2 = nan, cl = nan;  // (NaN: the system would not run a thread on that CPU)
        std::thread t([&] {
            if (!pin_to(c)) return;
            l1 = chase_ns(256 * 1024);
            l2 = chase_ns(4 * 1024 * 1024);
            cl = core_ns();
        });
        t.join();
        const double rt = c == cpus[0] ? nan : round_trip_ns(cpus[0], c);  // (NaN: itself, or not allowed)
        std::printf("%3d  %17.2f  %14.2f  %14.3f  %26.0f\n", c, l1, l2, cl, rt);
        out << c << "," << l1 << "," << l2 << "," << cl << "," << rt << "\n";
    }
    std::printf("CSV: %s\n", csv.c_str());
    return 0;
#else
    (void)csv;
    std::cerr << "fdem_bench --probe: only on Linux\n";
    return 1;
#endif
}

}  // namespace

// --nodes N: the node update kernel alone (fdem/node_update.hpp) on N free nodes with module forces, local damping
// and gravity, no triangles: ns per node and step, median of the repeats, per thread count; a CSV row per repeat.
int bench_nodes(long n, long steps, long repeats, const std::vector<int>& thread_counts, const std::string& csv) {
    std::ofstream out(csv);
    if (!out) {
        std::cerr << "error: cannot write the CSV file '" << csv << "'\n";
        return 1;
    }
    out << "kernel,threads,nodes,steps,repeat,seconds,ns_per_node_step\n";
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(-1, 1);
    const std::size_t n2 = 2 * static_cast<std::size_t>(n);
    std::vector<int> inc_ptr(n + 1, 0);
    std::vector<double> mass(n, 1.0), inv_mass(n, 1.0), f_ext(n2, 0.0), f_mod(n2), dof_vel(n2, 0.0), reaction(n2, 0.0);
    std::vector<double> x(n2), v(n2);
    std::vector<unsigned char> loaded(n, 0);
    std::vector<std::uint8_t> kind(n2, 0);
    for (std::size_t i = 0; i < n2; ++i) x[i] = u(rng), v[i] = 1e-3 * u(rng);
    fdem::NodeUpdate a;
    a.n_units = static_cast<int>(n);
    a.inc_ptr = inc_ptr.data();
    a.mass = mass.data(), a.grav_mass = mass.data(), a.inv_mass = inv_mass.data();
    a.f_ext = f_ext.data(), a.loaded = loaded.data(), a.f_mod = f_mod.data(), a.reset_fmod = true;
    a.dof_kind = kind.data(), a.dof_velocity = dof_vel.data(), a.reaction = reaction.data();
    a.x = x.data(), a.v = v.data();
    a.dt = a.dtv = 1e-6, a.local_damping = 0.1, a.gy = -9.81;
    std::vector<fdem::NodeBlockSums> sums((n + 255) / 256);
    std::printf("node update: %ld nodes; %ld steps x %ld repeats\n", n, steps, repeats);
    for (int nth : thread_counts) {
        omp_set_num_threads(nth);
        std::vector<double> ns;
        for (long r = 0; r < repeats; ++r) {
            double sec = 0;
            for (long st = 0; st < steps; ++st) {
                for (std::size_t i = 0; i < n2; ++i) f_mod[i] = 1e-3 * x[i];  // (refilled: the kernel resets f_mod)
                const double t0 = omp_get_wtime();
                fdem::update_nodes(a, sums);
                sec += omp_get_wtime() - t0;
            }
            ns.push_back(1e9 * sec / (static_cast<double>(steps) * n));
            out << "node_update," << nth << "," << n << "," << steps << "," << r << "," << sec << "," << ns.back() << "\n";
        }
        std::sort(ns.begin(), ns.end());
        std::printf("threads %d: median %.2f ns per node and step (min %.2f, max %.2f)\n", nth, ns[ns.size() / 2],
                    ns.front(), ns.back());
    }
    return 0;
}

namespace {

struct BenchOptions {
    long triangles = 120000, steps = 200, repeats = 5, nodes = 0;
    std::string csv = "bench.csv", case_file;
    std::vector<std::string> sets;
    std::vector<int> thread_counts;
};

// The command line (after --probe, which main handles); false after printing what is wrong. --help exits.
bool parse_options(int argc, char** argv, BenchOptions& o) {
    std::string threads_list = "1,2";
    const char* usage =
        "usage: fdem_bench [--triangles N | --case FILE [--set k=v ...] | --nodes N] [--steps S] [--repeats R] "
        "[--threads 1,2] [--csv FILE]\n"
        "       (--nodes N: the node update kernel alone on N free nodes, ns per node and step)\n"
        "       fdem_bench --probe [--csv FILE]   (per CPU: load latency over 256 KB and 4 MB, a core-bound loop, and\n"
        "                                        the round trip of a cache line with the first CPU)\n";
    for (int i = 1; i < argc; ++i)
        if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
            std::cout << usage;
            std::exit(0);
        }
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string a = argv[i], v = argv[i + 1];
        if (a == "--triangles") o.triangles = std::atol(v.c_str());
        else if (a == "--nodes") o.nodes = std::atol(v.c_str());
        else if (a == "--steps") o.steps = std::atol(v.c_str());
        else if (a == "--repeats") o.repeats = std::atol(v.c_str());
        else if (a == "--threads") threads_list = v;
        else if (a == "--csv") o.csv = v;
        else if (a == "--case") o.case_file = v;
        else if (a == "--set") o.sets.push_back(v);
        else {
            std::cerr << "fdem_bench: unknown option '" << a << "'\n" << usage;
            return false;
        }
    }
    if ((argc - 1) % 2 != 0) {
        std::cerr << "fdem_bench: option '" << argv[argc - 1] << "' has no value\n";
        return false;
    }
    {
        std::stringstream tl(threads_list);
        for (std::string tok; std::getline(tl, tok, ',');) o.thread_counts.push_back(std::atoi(tok.c_str()));
    }
    const bool bad_threads = o.thread_counts.empty() ||
                             std::any_of(o.thread_counts.begin(), o.thread_counts.end(), [](int n) { return n < 1; });
    if (o.steps < 1 || o.repeats < 1 || o.triangles < 1 || bad_threads) {
        std::cerr << "fdem_bench: --steps, --repeats and --triangles take positive integers and --threads a list of "
                     "positive integers such as 1,2 (got steps " << o.steps << ", repeats " << o.repeats << ", triangles "
                  << o.triangles << ", threads '" << threads_list << "')\n";
        return false;
    }
    return true;
}

// The benchmark's scene: the case file, or a 2 x 1 m plate of unstructured triangles of size h (about
// o.triangles of them) fixed at its left end under gravity.
bool bench_scene(const BenchOptions& o, fdem::CaseSpec& spec, fdem::Model& model) {
    try {
        if (!o.case_file.empty()) {
            spec = fdem::load_case(o.case_file, o.sets);
            model = fdem::build_scene(spec);
        } else {
            // A 2 x 1 m plate of unstructured triangles of size h (about `triangles` of them).
            const double h = std::sqrt(2.0 * 2.0 / (o.triangles * 0.866));
            spec.file = "bench";
            spec.name = "plate";
            spec.thickness = 0.1;
            spec.geometry.type = "rectangle";
            fdem::Material mat;
            mat.name = "m", mat.E = 1e9, mat.nu = 0.25, mat.density = 1000;
            spec.materials.push_back(mat);
            spec.region_material["body"] = "m";
            fdem::StageSpec st;
            st.name = "shake";
            st.duration = 1e9;
            st.gravity = std::array<double, 2>{0, -9.81};
            st.local_damping = 0.1;
            fdem::SupportSpec sup;
            sup.group = "left";
            sup.mode = {fdem::DofMode::fixed, fdem::DofMode::fixed};
            st.supports.push_back(sup);
            spec.stages.push_back(st);
            model = fdem::build_model(spec, fdem::mesh::mesh_rectangle(0, 0, 2.0, 1.0, h));
        }
    } catch (const std::exception& e) {
        std::cerr << "error: " << e.what() << "\n";
        return false;
    }
    return true;
}

// Steps of the scene on each thread count: throughput, steps per CPU second and per-kernel times (median of the
// repeats), one CSV row per repeat, and whether the end positions have the same bits on every thread count.
int run_bench(const BenchOptions& o, const fdem::CaseSpec& spec, const fdem::Model& model, const std::string& label) {
    std::printf("%s: %d triangles, %d nodes, %zu cohesive elements; %ld steps x %ld repeats\n", label.c_str(),
                model.n_triangles(), model.n_nodes(), model.cohesive.size(), o.steps, o.repeats);
    std::ofstream out(o.csv);
    if (!out) {
        std::cerr << "error: cannot write the CSV file '" << o.csv << "'\n";
        return 1;
    }
    out << "case,threads,triangles,nodes,steps,repeat,seconds,triangle_steps_per_s,steps_per_s,us_triangles,us_cohesive,"
           "us_contact_detection,us_contact_forces,us_contact_scatter,us_integration,us_other,cpu_seconds\n";
    // Microseconds per step of each kernel over one repeat, from the cumulative timers before and after it.
    constexpr int kKernels = 7;
    const char* kernel_names[kKernels] = {"triangles", "cohesive", "contact detection", "contact forces",
                                          "contact scatter", "integration", "other"};
    auto kernel_clock = [](const fdem::Simulation& sim, double* t) {
        const fdem::StepProfile& st = sim.profile();
        const fdem::contact::ContactSystem* cs = sim.interactions().contact();
        const double det = cs ? cs->stats().time_detection : 0.0;
        const double frc = cs ? cs->stats().time_forces : 0.0;  // includes the scatter
        const double sct = cs ? cs->stats().time_scatter : 0.0;
        t[0] = st.triangles;
        t[1] = st.interactions - det - frc;  // what add_forces spent outside contact: the cohesive elements
        t[2] = det;
        t[3] = frc - sct;
        t[4] = sct;
        t[5] = st.integration();  // rigid groups, node update, books
        t[6] = st.other();        // insertion, loads, damage, observers
    };
    std::vector<std::pair<int, double>> medians;
    std::vector<double> first_x;  // end state of the first thread count: every count runs the same steps
    bool same_bits = true;
    for (const int nth : o.thread_counts) {
        fdem::RunOptions opt;
        opt.quiet = true;
        opt.threads = nth;
        fdem::Simulation sim(spec, model, opt);
        sim.begin_stage(0);
        for (int i = 0; i < 20; ++i) sim.step();  // warm-up
        std::vector<double> rates;
        std::vector<std::vector<double>> kernel_us(kKernels);
        // Process CPU time per step (all threads): on a shared machine a thread that waits for a core is not
        // charged, so on 1 thread steps / cpu_seconds is the rate of a quiet core (spin-waits count on 2).
        std::vector<double> cpu_rates;
        for (long r = 0; r < o.repeats; ++r) {
            double k0[kKernels], k1[kKernels];
            kernel_clock(sim, k0);
            const std::clock_t c0 = std::clock();
            const auto t0 = std::chrono::steady_clock::now();
            for (long s = 0; s < o.steps; ++s) sim.step();
            const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            const double cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
            cpu_rates.push_back(static_cast<double>(o.steps) / cpu);
            kernel_clock(sim, k1);
            const double rate = static_cast<double>(o.steps) * model.n_triangles() / sec;
            rates.push_back(rate);
            out << label << "," << nth << "," << model.n_triangles() << "," << model.n_nodes() << "," << o.steps << "," << r
                << "," << sec << "," << rate << "," << o.steps / sec;
            for (int k = 0; k < kKernels; ++k) {
                const double us = 1e6 * (k1[k] - k0[k]) / static_cast<double>(o.steps);
                kernel_us[k].push_back(us);
                out << "," << us;
            }
            out << "," << cpu << "\n";
        }
        const std::vector<double>& xe = sim.model().x;
        if (first_x.empty()) first_x = xe;
        else same_bits = same_bits && first_x.size() == xe.size() &&
                         std::memcmp(first_x.data(), xe.data(), xe.size() * sizeof(double)) == 0;
        std::sort(rates.begin(), rates.end());
        const double med = rates[rates.size() / 2];
        medians.emplace_back(nth, med);
        std::printf("threads %d: median %.3g triangle-steps/s, %.4g steps/s (min %.3g, max %.3g)\n", nth, med,
                    med / model.n_triangles(), rates.front(), rates.back());
        std::sort(cpu_rates.begin(), cpu_rates.end());
        std::printf("  steps per CPU second (median): %.4g\n", cpu_rates[cpu_rates.size() / 2]);
        std::printf("  us/step (median):");
        for (int k = 0; k < kKernels; ++k) {
            std::sort(kernel_us[k].begin(), kernel_us[k].end());
            std::printf(" %s %.1f%s", kernel_names[k], kernel_us[k][kernel_us[k].size() / 2], k + 1 < kKernels ? "," : "\n");
        }
    }
    if (medians.size() > 1) {
        std::printf("speed-up %d -> %d threads: %.2f\n", medians.front().first, medians.back().first,
                    medians.back().second / medians.front().second);
        std::printf("end positions bit-identical across thread counts: %s\n", same_bits ? "yes" : "NO");
    }
    std::printf("CSV: %s\n", o.csv.c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    // --probe [--csv FILE]: the machine, not a model
    for (int i = 1; i < argc; ++i)
        if (std::strcmp(argv[i], "--probe") == 0) {
            std::string csv = "probe.csv";
            for (int j = 1; j < argc; ++j) {
                if (j == i) continue;
                if (std::strcmp(argv[j], "--csv") == 0 && j + 1 < argc) {
                    csv = argv[++j];
                } else {
                    std::cerr << "fdem_bench --probe: takes only --csv FILE (got '" << argv[j] << "')\n";
                    return 1;
                }
            }
            return probe(csv);
        }
    fdem::ensure_wait_policy(argv);
    BenchOptions o;
    if (!parse_options(argc, argv, o)) return 1;
    if (o.nodes > 0) return bench_nodes(o.nodes, o.steps, o.repeats, o.thread_counts, o.csv);
    fdem::CaseSpec spec;
    fdem::Model model;
    if (!bench_scene(o, spec, model)) return 1;
    return run_bench(o, spec, model, spec.name);
}
