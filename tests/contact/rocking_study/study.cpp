// tests/contact/rocking_study/study.cpp: the driver of the rocking-block study in RESULTS.md (issue 54 item 2): the
// scene of tests/contact/rocking_run.hpp (the tests' own code) with its settings from the command line; prints the
// impacts against the rigid block, r per impact, the hop and the books.
// Not built by CMake (it has its own main); build it against a build tree, e.g.
//   B=build; c++ -O2 -ffp-contract=off -fopenmp -DTOML_HEADER_ONLY=0 -DTOML_SHARED_LIB=1 -DFDEM_VERSION=\"0.1.0\" -I. -Itests \
//     -DFDEM_TEST_TMP=\"/tmp/rockstudy\" -DFDEM_BIN=\"fdem\" -isystem /usr/include/eigen3 -std=c++17 tests/contact/rocking_study/study.cpp \
//     -o /tmp/rocking $B/fdem/libfdem_core.a $B/mesh/libfdem_mesh.a $B/contact/libfdem_contact.a \
//     $B/fracture/libfdem_fracture.a -lgmsh -lgomp -lpthread -ltomlplusplus
//   /tmp/rocking E 1e11 kn 1e11 e 0.2 foot 0.01 T 3
// Keys (value after each): bw bh foot (0: flat) h E kn e mu T theta (theta0 as a fraction of atan(bw / bh)) body (1: the
// block one rigid body)
#include <cstdio>
#include <string>
#include <unistd.h>

#include "contact/rocking_run.hpp"

int main(int argc, char** argv) {
    contact_test::RockingSetup s;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string k = argv[i];
        const double v = std::stod(argv[i + 1]);
        if (k == "bw") s.bw = v; else if (k == "bh") s.bh = v; else if (k == "foot") s.foot = v; else if (k == "h") s.h = v;
        else if (k == "E") s.E = v; else if (k == "kn") s.kn = v; else if (k == "e") s.e = v; else if (k == "mu") s.mu = v;
        else if (k == "T") s.T = v; else if (k == "theta") s.theta0_of_alpha = v; else if (k == "body") s.body = v != 0;
        else { std::fprintf(stderr, "unknown key %s\n", k.c_str()); return 1; }
    }
    const contact_test::RockingResult r = contact_test::rock(s, "run_" + std::to_string(getpid()));
    std::vector<double> rt, ra;
    contact_test::print_rocking(r, s, rt, ra);
    for (std::size_t i = 0; i + 1 < r.amplitudes.size(); ++i) {
        const double ri = contact_test::measured_r(r, i);
        std::printf("[rocking]   r of impact %zu: %.5f (impulse at x_p %+.2f %%, Housner %+.2f %%)\n", i + 1, ri,
                    100 * (ri / r.rigid.r(r.x_p) - 1), 100 * (ri / r.rigid.r(r.rigid.b) - 1));
    }
}
