// fdem_bench: step throughput (triangle-steps per second) for 1 and 2 threads (or --threads LIST), median of
// several runs, written to a CSV, with the time per step of each kernel (Simulation::step_times and the contact
// statistics): triangle forces, cohesive elements, contact detection, contact forces (pair kernels), contact scatter
// (the sum in pair order, each thread its own nodes), integration (node loop) and the rest (loads, damage update, outputs). Without --case: triangle forces and integration of an elastic plate of about N
// triangles. With --case FILE: the first steps of that case's first stage (contact, joints and all), so that the
// thread scaling of a real scene is measured; --set key=value as for `fdem run`.
//   fdem_bench [--triangles N | --case FILE [--set k=v ...]] [--steps S] [--repeats R] [--threads 1,2] [--csv FILE]
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "fdem/case.hpp"
#include "fdem/omp_env.hpp"
#include "fdem/model.hpp"
#include "fdem/scene.hpp"
#include "fdem/simulation.hpp"
#include "mesh/gmsh_source.hpp"

int main(int argc, char** argv) {
    fdem::ensure_wait_policy(argv);
    long triangles = 120000, steps = 200, repeats = 5;
    std::string csv = "bench.csv", threads_list = "1,2", case_file;
    std::vector<std::string> sets;
    const char* usage =
        "usage: fdem_bench [--triangles N | --case FILE [--set k=v ...]] [--steps S] [--repeats R] [--threads 1,2] "
        "[--csv FILE]\n";
    for (int i = 1; i < argc; ++i)
        if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) {
            std::cout << usage;
            return 0;
        }
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string a = argv[i], v = argv[i + 1];
        if (a == "--triangles") triangles = std::atol(v.c_str());
        else if (a == "--steps") steps = std::atol(v.c_str());
        else if (a == "--repeats") repeats = std::atol(v.c_str());
        else if (a == "--threads") threads_list = v;
        else if (a == "--csv") csv = v;
        else if (a == "--case") case_file = v;
        else if (a == "--set") sets.push_back(v);
        else {
            std::cerr << "fdem_bench: unknown option '" << a << "'\n" << usage;
            return 1;
        }
    }
    if ((argc - 1) % 2 != 0) {
        std::cerr << "fdem_bench: option '" << argv[argc - 1] << "' has no value\n";
        return 1;
    }
    std::vector<int> thread_counts;
    {
        std::stringstream tl(threads_list);
        for (std::string tok; std::getline(tl, tok, ',');) thread_counts.push_back(std::atoi(tok.c_str()));
    }
    const bool bad_threads = thread_counts.empty() ||
                             std::any_of(thread_counts.begin(), thread_counts.end(), [](int n) { return n < 1; });
    if (steps < 1 || repeats < 1 || triangles < 1 || bad_threads) {
        std::cerr << "fdem_bench: --steps, --repeats and --triangles take positive integers and --threads a list of "
                     "positive integers such as 1,2 (got steps " << steps << ", repeats " << repeats << ", triangles "
                  << triangles << ", threads '" << threads_list << "')\n";
        return 1;
    }
    fdem::CaseSpec spec;
    fdem::Model model;
    std::string label;
    try {
        if (!case_file.empty()) {
            spec = fdem::load_case(case_file, sets);
            model = fdem::build_scene(spec);
        } else {
            // A 2 x 1 m plate of unstructured triangles of size h (about `triangles` of them).
            const double h = std::sqrt(2.0 * 2.0 / (triangles * 0.866));
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
        label = spec.name;
    } catch (const std::exception& e) {
        std::cerr << "error: " << e.what() << "\n";
        return 1;
    }
    std::printf("%s: %d triangles, %d nodes, %zu cohesive elements; %ld steps x %ld repeats\n", label.c_str(),
                model.n_triangles(), model.n_nodes(), model.cohesive.size(), steps, repeats);
    std::ofstream out(csv);
    if (!out) {
        std::cerr << "error: cannot write the CSV file '" << csv << "'\n";
        return 1;
    }
    out << "case,threads,triangles,nodes,steps,repeat,seconds,triangle_steps_per_s,steps_per_s,us_triangles,us_cohesive,"
           "us_contact_detection,us_contact_forces,us_contact_scatter,us_integration,us_other,cpu_seconds\n";
    // Microseconds per step of each kernel over one repeat, from the cumulative timers before and after it.
    constexpr int kKernels = 7;
    const char* kernel_names[kKernels] = {"triangles", "cohesive", "contact detection", "contact forces",
                                          "contact scatter", "integration", "other"};
    auto kernel_clock = [](const fdem::Simulation& sim, double* t) {
        const fdem::StepTimes& st = sim.step_times();
        const fdem::contact::ContactSystem* cs = sim.interactions().contact();
        const double det = cs ? cs->stats().time_detection : 0.0;
        const double frc = cs ? cs->stats().time_forces : 0.0;  // includes the scatter
        const double sct = cs ? cs->stats().time_scatter : 0.0;
        t[0] = st.triangles;
        t[1] = st.interactions - det - frc;  // what add_forces spent outside contact: the cohesive elements
        t[2] = det;
        t[3] = frc - sct;
        t[4] = sct;
        t[5] = st.integration;
        t[6] = st.other;
    };
    std::vector<std::pair<int, double>> medians;
    std::vector<double> first_x;  // end state of the first thread count: every count runs the same steps
    bool same_bits = true;
    for (const int nth : thread_counts) {
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
        for (long r = 0; r < repeats; ++r) {
            double k0[kKernels], k1[kKernels];
            kernel_clock(sim, k0);
            const std::clock_t c0 = std::clock();
            const auto t0 = std::chrono::steady_clock::now();
            for (long s = 0; s < steps; ++s) sim.step();
            const double sec = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            const double cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
            cpu_rates.push_back(static_cast<double>(steps) / cpu);
            kernel_clock(sim, k1);
            const double rate = static_cast<double>(steps) * model.n_triangles() / sec;
            rates.push_back(rate);
            out << label << "," << nth << "," << model.n_triangles() << "," << model.n_nodes() << "," << steps << "," << r
                << "," << sec << "," << rate << "," << steps / sec;
            for (int k = 0; k < kKernels; ++k) {
                const double us = 1e6 * (k1[k] - k0[k]) / static_cast<double>(steps);
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
    std::printf("CSV: %s\n", csv.c_str());
    return 0;
}
