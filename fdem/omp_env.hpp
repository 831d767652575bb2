// fdem/omp_env.hpp: OpenMP settings that must be in place before libgomp loads.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdlib>

namespace fdem {

// How long an idle OpenMP thread spins before it sleeps. libgomp's default (300,000 spins) holds a core that other
// threads need when the cores are shared (a batch of runs, CI running tests in parallel): a step can then take a
// whole scheduler slice, measured 25x slower on 2 busy cores. Sleeping at once (OMP_WAIT_POLICY=passive) avoids
// that, but then every parallel loop of a step waits for a sleeping thread to be woken: a step has five of them.
// A short spin of 3,000 catches the next loop on an idle machine and gives the core back soon after; the same bits
// under every policy (measurements: BENCHMARKS.md, "OpenMP wait policy").
// libgomp reads its settings when it loads, so this program runs itself again with GOMP_SPINCOUNT=3000 unless the
// user chose a policy (OMP_WAIT_POLICY or GOMP_SPINCOUNT).
inline void ensure_wait_policy(char** argv) {
    if (std::getenv("OMP_WAIT_POLICY") || std::getenv("GOMP_SPINCOUNT") || std::getenv("FDEM_NO_REEXEC")) return;
    setenv("GOMP_SPINCOUNT", "3000", 1);
    setenv("FDEM_NO_REEXEC", "1", 1);
    // Exec the executable's real path, not /proc/self/exe: the kernel names the process after the path's last
    // component, so it stays `fdem` for ps, pgrep, pkill and job monitors (issue 26); argv[0] is passed on as given.
    char path[4096];
    const ssize_t n = readlink("/proc/self/exe", path, sizeof path - 1);
    if (n > 0 && static_cast<std::size_t>(n) < sizeof path - 1) {
        path[n] = '\0';
        execv(path, argv);
    }
    execv("/proc/self/exe", argv);
    // exec failed: carry on with the default policy.
}

}  // namespace fdem
