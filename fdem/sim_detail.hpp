// fdem/sim_detail.hpp: constants and small helpers shared by the files of Simulation (simulation.cpp, step.cpp,
// integrator.cpp, stages.cpp, run.cpp); internal to the engine, not part of its interface.
#pragma once

#include <chrono>
#include <cstdio>
#include <ctime>
#include <string>

namespace fdem::sim_detail {

// Items per block of the triangle and node loops. Small enough that a static schedule balances the blocks of a
// wall-sized mesh: with 4096, a 4620-triangle wall had two blocks (4096 + 524 triangles), so the second thread idled
// for most of the triangle loop. Changing it changes the order of the energy sums only, not the motion.
constexpr int kBlock = 256;
// First of the n items thread t of T takes in a static share (the first n % T threads one more): thread t takes
// [share_begin(n, T, t), share_begin(n, T, t + 1)). The node loop's shares, which the contact scatter is told.
inline int share_begin(int n, int T, int t) { return t * (n / T) + (t < n % T ? t : n % T); }
// First block of kBlock items that thread t of T takes when n items are shared by items, not blocks: each share
// ends at the block boundary nearest to an equal split. A static schedule of the blocks gave the first thread of two
// 10 of a 4620-triangle wall's 19 blocks (2560 triangles against 2060).
inline int block_share_begin(int n, int T, int t) {
    const int nb = (n + kBlock - 1) / kBlock;
    if (t >= T) return nb;
    const long long first = static_cast<long long>(n) * t / T;  // the item an equal split would start at
    const int b = static_cast<int>((first + kBlock / 2) / kBlock);
    return b < nb ? b : nb;
}
constexpr double kBalanceWarning = 0.05;  // relative energy balance error above which a run is flagged
constexpr double kPi = 3.14159265358979323846;

inline double wall_clock() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

// CPU time of the process (s), summed over its threads: on a machine shared with other jobs it stays near what the
// run would take alone, where the wall time grows with the load (summary.json cpu_time_s).
inline double cpu_clock() {
    return static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
}

inline std::string human_time(double s) {
    char b[64];
    if (s < 60) std::snprintf(b, sizeof b, "%.1f s", s);
    else if (s < 3600) std::snprintf(b, sizeof b, "%dm%02ds", static_cast<int>(s / 60), static_cast<int>(s) % 60);
    else std::snprintf(b, sizeof b, "%dh%02dm", static_cast<int>(s / 3600), (static_cast<int>(s) % 3600) / 60);
    return b;
}

inline std::string sci(double v, int prec = 4) {
    char b[48];
    std::snprintf(b, sizeof b, "%.*g", prec, v);
    return b;
}

}  // namespace fdem::sim_detail
