// tests/core/test_triangle_range.cpp: triangle_forces_range (fdem/triangle.hpp), four triangles at a time where the CPU
// has AVX, against triangle_forces one triangle at a time: the same bits, with viscous and inverted triangles mixed in.
#include <catch2/catch.hpp>

#include <cstring>
#include <random>
#include <tuple>
#include <vector>

#include "fdem/triangle.hpp"

TEST_CASE("triangle forces of a range: four at a time give the bits of one at a time", "[unit]") {
    const int nt = 203;  // (not a multiple of 4)
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    std::uniform_int_distribution<int> pick(0, 99);
    const std::vector<fdem::MaterialConst> mats{{4.0e9, 2.5e9}, {1.2e10, 3.0e9}};
    std::vector<fdem::TriangleRef> tris(nt);
    std::vector<double> x(6 * nt), v(6 * nt);
    for (int e = 0; e < nt; ++e) {
        fdem::TriangleRef& t = tris[e];
        // a right triangle of legs h, deformed by up to 1 %, its nodes numbered apart (as a split mesh does)
        const double h = 0.02 * (1 + 0.5 * u(rng)), X0 = u(rng), Y0 = u(rng);
        const double X[3] = {X0, X0 + h, X0}, Y[3] = {Y0, Y0, Y0 + h};
        for (int k = 0; k < 3; ++k) {
            t.n[k] = (3 * e + 2 * k) % (3 * nt);
            x[2 * t.n[k]] = X[k] + 0.01 * h * u(rng), x[2 * t.n[k] + 1] = Y[k] + 0.01 * h * u(rng);
            v[2 * t.n[k]] = u(rng), v[2 * t.n[k] + 1] = u(rng);
        }
        t.mat = pick(rng) % 2;
        t.Dinv[0] = 1 / h, t.Dinv[1] = 0, t.Dinv[2] = 0, t.Dinv[3] = 1 / h;
        t.A0t = 0.5 * h * h * 0.1;
        t.eta = pick(rng) < 10 ? 1e3 : 0.0;  // some viscous triangles (the scalar path)
    }
    // one inverted triangle: node 1 moved across the opposite edge
    x[2 * tris[57].n[1]] = x[2 * tris[57].n[0]] - 0.01;
    auto run = [&](int lanes, int e0, int e1) {
        std::vector<double> tf(6 * nt, 7.0);
        double power = 0;
        int bad = -1;
        fdem::triangle_forces_range(tris.data(), mats.data(), x.data(), v.data(), tf.data(), e0, e1, power, bad, lanes);
        return std::make_tuple(tf, power, bad);
    };
    for (int e0 : {0, 1, 58}) {
        const auto one = run(1, e0, nt), four = run(0, e0, nt);
        INFO("from triangle " << e0);
        CHECK(std::memcmp(std::get<0>(one).data(), std::get<0>(four).data(), 6 * nt * sizeof(double)) == 0);
        CHECK(std::memcmp(&std::get<1>(one), &std::get<1>(four), sizeof(double)) == 0);
        CHECK(std::get<1>(one) > 0);
        CHECK(std::get<2>(one) == (e0 <= 57 ? 57 : -1));
        CHECK(std::get<2>(four) == std::get<2>(one));
    }
}
