// fdem/omp_env.hpp: OpenMP settings that must be in place before libgomp loads.
#pragma once

#include <unistd.h>

#include <cstdlib>

namespace fdem {

// libgomp's default is to spin at barriers; when the cores are shared (a batch of runs, CI running tests in
// parallel) a spinning thread holds a core the other threads need and a step can take a whole scheduler slice:
// measured 25x slower on 2 busy cores. libgomp reads its settings when it loads, so the policy is set by
// running this program again with OMP_WAIT_POLICY=passive unless the user chose a policy.
inline void ensure_passive_wait(char** argv) {
    if (std::getenv("OMP_WAIT_POLICY") || std::getenv("GOMP_SPINCOUNT") || std::getenv("FDEM_NO_REEXEC")) return;
    setenv("OMP_WAIT_POLICY", "passive", 1);
    setenv("FDEM_NO_REEXEC", "1", 1);
    execv("/proc/self/exe", argv);
    // exec failed: carry on with the default policy.
}

}  // namespace fdem
