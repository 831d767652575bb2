// tests/contact/bench_contact.cpp: hidden benchmark ("[.bench]"): a dry-joint wall of >= 50,000 triangles.
// Run: build/tests/test_contact "[.bench]". Prints and writes build/bench_contact.csv.
#include <catch2/catch.hpp>

#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <omp.h>
#include <string>

#include "block_sim.hpp"

using contact_test::BlockSim;
using fdem::contact::ContactLaw;
using fdem::contact::ContactLaws;

namespace {

// Running-bond wall of rows x cols bricks (0.2 m x 0.1 m), each meshed 8 x 4 cells (64 triangles), dry joints,
// on a fixed base; nodes duplicated between bricks (no shared nodes across joints).
void build_wall(BlockSim& s, int rows, int cols) {
    s.add_block(-0.2, -0.1, 0.2 * cols + 0.4, 0.1, 4 * cols, 1);
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) s.add_block(0.2 * c + (r % 2 ? 0.1 : 0.0), 0.1 * r, 0.2, 0.1, 8, 4);
}

struct Result {
    int threads;
    std::string capable;
    int n_tri, n_capable, pairs, active;
    long steps;
    double t_total, t_detect, t_forces, t_scatter, detections, t_cpu;
};

Result measure(int threads, bool boundary_only) {
    omp_set_num_threads(threads);
    BlockSim s;
    s.E = 1e10;
    build_wall(s, 24, 34);
    ContactLaws laws(1);
    laws.set_interface(0, 0, ContactLaw::stiffness(1e10, 4e9, 35.0));
    s.finish(laws);
    s.fix_body(0);
    if (boundary_only) {
        // contact-capable = triangles with an edge on their brick's boundary (fdem/README.md 'Contact')
        for (int e = 0; e < s.n_tri(); ++e) {
            const int* q = &s.tri[3 * e];
            const int b = s.tri_body[e];
            double xmin = 1e9, xmax = -1e9, ymin = 1e9, ymax = -1e9;
            for (int k = s.body_first_node[b]; k < s.body_last_node[b]; ++k) {
                xmin = std::min(xmin, s.x[2 * k]);
                xmax = std::max(xmax, s.x[2 * k]);
                ymin = std::min(ymin, s.x[2 * k + 1]);
                ymax = std::max(ymax, s.x[2 * k + 1]);
            }
            int on = 0;
            for (int k = 0; k < 3; ++k) {
                const double xx = s.x[2 * q[k]], yy = s.x[2 * q[k] + 1];
                on += (std::fabs(xx - xmin) < 1e-9 || std::fabs(xx - xmax) < 1e-9 || std::fabs(yy - ymin) < 1e-9 ||
                       std::fabs(yy - ymax) < 1e-9);
            }
            s.cs->set_capable(e, on >= 2);
        }
    }
    int n_capable = 0;
    for (int e = 0; e < s.n_tri(); ++e) n_capable += s.cs->capable(e);
    const double dt = 0.5 * s.stable_dt();
    s.alpha = 0.7;
    for (int i = 0; i < 100; ++i) s.step(dt);  // load the joints
    s.cs->set_compute_energy(false);  // energies only at output steps, as the engine would
    const auto st0 = s.cs->stats();
    // time the contact module alone on the loaded state, with a re-detection every 25 steps
    const long steps = 200;
    std::vector<double> f(s.f.size());
    const double t0 = omp_get_wtime();
    const std::clock_t c0 = std::clock();
    for (long i = 0; i < steps; ++i) {
        if (i % 25 == 0) s.cs->invalidate();
        std::fill(f.begin(), f.end(), 0.0);
        s.cs->step(s.x.data(), s.v.data(), dt, f.data());
    }
    const double t_total = omp_get_wtime() - t0;
    const double t_cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;  // all threads: shows machine load
    const auto st = s.cs->stats();
    return {threads,
            boundary_only ? "boundary" : "all",
            s.n_tri(),
            n_capable,
            st.candidate_pairs,
            st.active_pairs,
            steps,
            t_total,
            st.time_detection - st0.time_detection,
            st.time_forces - st0.time_forces,
            st.time_scatter - st0.time_scatter,
            static_cast<double>(st.detections - st0.detections),
            t_cpu};
}

}  // namespace

TEST_CASE("Benchmark: contact on a dry-joint wall of >= 50,000 triangles, 1 and 2 threads", "[.bench]") {
    const int saved = omp_get_max_threads();
    std::vector<Result> res;
    // FDEM_BENCH_THREADS=N measures N threads only (for profiling); default 1 and 2.
    std::vector<int> counts = {1, 2};
    if (const char* env = std::getenv("FDEM_BENCH_THREADS")) counts = {std::atoi(env)};
    for (bool boundary : {true, false})
        for (int th : counts) res.push_back(measure(th, boundary));
    omp_set_num_threads(saved);
    const std::string path = std::string(FDEM_TEST_TMP) + "/../../bench_contact.csv";
    std::ofstream csv(path);
    csv << "threads,capable,triangles,capable_triangles,pairs,active_pairs,steps,detections,seconds,"
           "triangle_steps_per_s,pair_evaluations_per_s,share_detection,share_forces,share_scatter,cpu_seconds,"
           "triangle_steps_per_s_without_detection\n";
    for (const Result& r : res) {
        const double tsps = r.n_tri * r.steps / r.t_total, pps = double(r.pairs) * r.steps / r.t_total;
        std::printf("[bench] %d thread(s), capable=%s: %d triangles (%d capable), %d pairs (%d active), "
                    "%.0f detections in %ld steps, %.3f s: %.2f M triangle-steps/s, %.2f M pairs/s, "
                    "detection %.1f %%, forces %.1f %% (of which serial scatter %.1f %%), cpu %.3f s; "
                    "steps without detection: %.2f M triangle-steps/s\n",
                    r.threads, r.capable.c_str(), r.n_tri, r.n_capable, r.pairs, r.active, r.detections, r.steps,
                    r.t_total, tsps / 1e6, pps / 1e6, 100 * r.t_detect / r.t_total, 100 * r.t_forces / r.t_total, 100 * r.t_scatter / r.t_total, r.t_cpu,
                    r.n_tri * r.steps / r.t_forces / 1e6);
        csv << r.threads << ',' << r.capable << ',' << r.n_tri << ',' << r.n_capable << ',' << r.pairs << ','
            << r.active << ',' << r.steps << ',' << r.detections << ',' << r.t_total << ',' << tsps << ',' << pps
            << ',' << r.t_detect / r.t_total << ',' << r.t_forces / r.t_total << ',' << r.t_scatter / r.t_total << ','
            << r.t_cpu << ',' << r.n_tri * r.steps / r.t_forces << '\n';
        CHECK(r.n_tri >= 50000);
    }
    std::printf("[bench] CSV written to %s\n", path.c_str());
}
