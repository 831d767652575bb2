// Checkpoint and restart (issue 26): a run stopped half way and continued from its checkpoint gives the same bytes
// as an uninterrupted run, with fracture and contact active; a SIGKILLed run leaves history.csv whole and continues
// from its last checkpoint; checkpoints of another case or build, or damaged ones, are refused (exit 1).
//
// The case: a 3-course running-bond wall of mortared units (bonded unit-unit and unit-base interfaces, one potential
// crack per unit: 42 cohesive elements) under a dry-jointed top beam, loaded vertically (gravity, force ramp,
// local damping, contact dashpots) and then sheared by the beam (velocity ramp, filtered local damping, mass
// damping): cohesive elements break before and after the half-way step and contact carries the broken joints.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "engine_helpers.hpp"

namespace {

const char* kWall = R"(
[case]
name = "restart_wall"
thickness = 0.1
plane = "stress"
[geometry]
type = "wall"
length = 0.42
courses = 3
unit_length = 0.2
unit_height = 0.1
bond = "running"
joint = "mortar"
joint_thickness = 0.01
beam_height = 0.05
base = "slab"
base_height = 0.05
mesh_size = 0.1
mesh_size_beam = 0.1
mesh_size_base = 0.1
unit_cracks = "middle"
[materials.brick]
E = 1.0e10
nu = 0.15
density = 2000.0
  [materials.brick.fracture]
  tensile_strength = 1.0e6
  cohesion = 1.4e6
  friction = 40.0
  GI = 20.0
  GII = 100.0
  penalty = 5e10
[materials.steel]
E = 2e10
nu = 0.3
density = 7850.0
[regions]
units = "brick"
beam = "steel"
base = "steel"
[[interfaces]]
regions = ["units", "units"]
kind = "bonded"
tensile_strength = 1e5
cohesion = 1.4e5
friction = 35.0
GI = 5.0
GII = 50
normal_stiffness = 8e10
shear_stiffness = 3.6e10
[[interfaces]]
regions = ["units", "base"]
kind = "bonded"
tensile_strength = 1e5
cohesion = 1.4e5
friction = 35.0
GI = 5.0
GII = 50
normal_stiffness = 8e10
shear_stiffness = 3.6e10
[[interfaces]]
regions = ["units", "beam"]
kind = "dry"
friction = 35.0
normal_stiffness = 8e10
[[monitors]]
name = "u_top"
type = "displacement"
group = "beam"
component = "x"
[[monitors]]
name = "H"
type = "reaction"
group = "beam"
component = "x"
[numerics]
mass_scale = 10
[output]
history_interval = 0.0001
snapshot_interval = 0.003
[[stages]]
name = "load"
duration = 0.004
local_damping = 0.7
gravity = [0.0, -9.81]
gravity_ramp = 0.002
contact_damping = 0.1
  [[stages.supports]]
  group = "base_bottom"
  fix = "xy"
  [[stages.loads]]
  group = "beam_top"
  force = [0.0, -20000.0]
  ramp = 0.002
[[stages]]
name = "shear"
duration = 0.008
local_damping = 0.05
local_damping_filter = 0.01
mass_damping = 1.0
  [[stages.supports]]
  group = "beam"
  vx = 1.0
  fix = "y"
  ramp = 0.002
)";

std::string fdem_cmd(const std::string& args, int threads) {
    return "env OMP_WAIT_POLICY=passive \"" + std::string(FDEM_BIN) + "\" " + args + " --threads " + std::to_string(threads) + " --quiet";
}

testing::CliResult run_cli(const std::string& args, int threads, const std::filesystem::path& dir) {
    return testing::run_fdem(args + " --threads " + std::to_string(threads) + " --quiet", dir);
}

long count_lines(const std::string& s) { return static_cast<long>(std::count(s.begin(), s.end(), '\n')); }

// Every line ends with a newline and has as many fields as the header.
bool whole_csv(const std::string& h) {
    if (h.empty() || h.back() != '\n') return false;
    const auto commas = std::count(h.begin(), h.begin() + static_cast<long>(h.find('\n')), ',');
    std::size_t pos = 0;
    while (pos < h.size()) {
        const auto e = h.find('\n', pos);
        if (std::count(h.begin() + static_cast<long>(pos), h.begin() + static_cast<long>(e), ',') != commas) return false;
        pos = e + 1;
    }
    return true;
}

// The step a checkpoint holds (header: magic, format, version string, build hash, case hash, history bytes, step).
long checkpoint_step(const std::filesystem::path& p) {
    const std::string d = testing::read_text(p);
    std::size_t o = 8 + 4;
    std::uint64_t n = 0;
    std::memcpy(&n, d.data() + o, 8);
    o += 8 + n + 8 + 8 + 8;
    std::int64_t step = 0;
    std::memcpy(&step, d.data() + o, 8);
    return static_cast<long>(step);
}

// Runs the stages of an in-memory simulation from stage `first` (begun here unless begin_first is false: after
// load_state the current stage goes on), stopping after step stop_at (0: at the end).
void run_on(fdem::Simulation& sim, int first, bool begin_first, long stop_at = 0) {
    for (int s = first; s < static_cast<int>(sim.spec().stages.size()); ++s) {
        if (s != first || begin_first) sim.begin_stage(s);
        while (!sim.stage_finished()) {
            sim.step();
            if (stop_at > 0 && sim.steps() == stop_at) return;
        }
    }
}

// (time, step) of every row of a history.csv.
std::vector<std::pair<double, long>> history_rows(const std::string& h) {
    std::vector<std::pair<double, long>> rows;
    std::size_t pos = h.find('\n') + 1;
    while (pos < h.size()) {
        const auto c1 = h.find(',', pos), c2 = h.find(',', c1 + 1);
        rows.emplace_back(std::stod(h.substr(pos, c1 - pos)), std::stol(h.substr(c1 + 1, c2 - c1 - 1)));
        pos = h.find('\n', pos) + 1;
    }
    return rows;
}

std::string state_of(const fdem::Simulation& sim) {
    fdem::StateWriter w;
    sim.save_state(w);
    return w.data();
}

// The run of case_file stopped after step `half` and restarted, with 1 and 2 threads, must reproduce the uninterrupted
// run in `full` byte for byte (history, cracks, the final snapshot, run.pvd).
void check_restart_identity(const std::string& case_file, const std::filesystem::path& dir, const std::filesystem::path& full,
                            long half, const std::string& final_snapshot) {
    const std::string history = testing::read_text(full / "history.csv"), cracks = testing::read_text(full / "cracks.csv");
    for (int threads : {1, 2}) {
        const auto part = dir / ("part_" + std::to_string(threads));
        const auto r1 = run_cli("run \"" + case_file + "\" -o \"" + part.string() + "\" --stop-after-steps " + std::to_string(half),
                                threads, dir);
        INFO(threads << " thread(s): " << r1.err);
        CHECK(r1.code == 138);  // stopped as by SIGUSR1, checkpoint written
        REQUIRE(std::filesystem::exists(part / "checkpoint.bin"));
        CHECK(checkpoint_step(part / "checkpoint.bin") == half);
        CHECK(testing::read_text(part / "summary.json").find("\"interrupted\"") != std::string::npos);
        const auto r2 = run_cli("run \"" + case_file + "\" --restart \"" + part.string() + "\"", threads, dir);
        INFO(r2.err);
        REQUIRE(r2.code == 0);
        CHECK(testing::read_text(part / "history.csv") == history);
        CHECK(testing::read_text(part / "cracks.csv") == cracks);
        CHECK(testing::read_text(part / final_snapshot) == testing::read_text(full / final_snapshot));
        CHECK(testing::read_text(part / "run.pvd") == testing::read_text(full / "run.pvd"));
        CHECK(testing::read_text(part / "summary.json").find("\"completed\"") != std::string::npos);
        CHECK(testing::read_text(part / "run.log").find("restart: from") != std::string::npos);
    }
}

}  // namespace

TEST_CASE("a run stopped half way through its fracture and restarted gives byte-identical history, cracks and final snapshot for 1 and 2 threads",
          "[engine][regression]") {
    const auto dir = testing::tmp_dir("restart_identity");
    const std::string case_file = testing::write_text(dir / "wall.toml", kWall);
    const auto full = dir / "full";
    const auto r0 = run_cli("run \"" + case_file + "\" -o \"" + full.string() + "\"", 1, dir);
    INFO(r0.err);
    REQUIRE(r0.code == 0);
    const std::string history = testing::read_text(full / "history.csv"), cracks = testing::read_text(full / "cracks.csv");
    const auto rows = history_rows(history);
    REQUIRE(!rows.empty());
    const long steps = rows.back().second;
    REQUIRE(steps > 1000);
    // Stopped half way through the fracture: at the last history row before the median break of a cohesive element
    // (cracks.csv rows of cohesive elements; dry joint records are class interface-dry), so that elements break
    // before and after the stop and contact carries the broken joints: the restored cohesive and contact states
    // decide the second half.
    std::vector<double> break_times;
    for (std::size_t pos = cracks.find('\n') + 1; pos < cracks.size(); pos = cracks.find('\n', pos) + 1) {
        const std::string line = cracks.substr(pos, cracks.find('\n', pos) - pos);
        if (line.find(",interface-dry,") == std::string::npos) break_times.push_back(std::stod(line));
    }
    REQUIRE(break_times.size() >= 6);
    std::sort(break_times.begin(), break_times.end());
    const double t_median = break_times[break_times.size() / 2];
    long half = 0;
    for (const auto& [t, st] : rows)
        if (t < t_median) half = st;
    long breaks_before = 0, breaks_after = 0;
    double t_stop = 0;
    for (const auto& [t, st] : rows)
        if (st == half) t_stop = t;
    for (double t : break_times) (t <= t_stop ? breaks_before : breaks_after) += 1;
    INFO("steps " << steps << ", stop after step " << half << ", breaks before the stop " << breaks_before << ", after " << breaks_after);
    CHECK(breaks_before >= 3);
    CHECK(breaks_after >= 3);
    const std::string final_snapshot = "snapshots/step_" + std::string(9 - std::to_string(steps).size(), '0') + std::to_string(steps) + ".vtu";
    REQUIRE(std::filesystem::exists(full / final_snapshot));

    check_restart_identity(case_file, dir, full, half, final_snapshot);
}

// The wall of kWall with the bricks' crack elements extrinsic (fracture/cohesive_system.hpp) and weaker bricks, so that
// all 10 are inserted in the shear stage, some before the stop and some after it: the restored dormant flags,
// offsets and tied copies decide the second half. per_node: with [numerics] mass_scaling = "per_node" too (the raised
// masses of tied groups that the insertions then untie).
void check_extrinsic_restart(bool per_node) {
    std::string wall = kWall;
    for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
             {"  penalty = 5e10\n", "  penalty = 5e10\n  insertion = \"extrinsic\"\n"},
             {"tensile_strength = 1.0e6\n  cohesion = 1.4e6", "tensile_strength = 2.0e5\n  cohesion = 3.0e5"},
             {"mass_scale = 10\n", per_node ? "mass_scale = 10\nmass_scaling = \"per_node\"\n" : "mass_scale = 10\n"}}) {
        const auto p = wall.find(from);
        REQUIRE(p != std::string::npos);
        wall.replace(p, from.size(), to);
    }
    const auto dir = testing::tmp_dir(per_node ? "restart_extrinsic_per_node" : "restart_extrinsic");
    const std::string case_file = testing::write_text(dir / "wall.toml", wall);
    const auto full = dir / "full";
    const auto r0 = run_cli("run \"" + case_file + "\" -o \"" + full.string() + "\"", 1, dir);
    INFO(r0.err);
    REQUIRE(r0.code == 0);
    const std::string history = testing::read_text(full / "history.csv"), cracks = testing::read_text(full / "cracks.csv");
    if (per_node) {  // the scaling did raise masses (else this test would repeat the one without it)
        const std::string summary = testing::read_text(full / "summary.json");
        const std::string key = "\"mass_scaling_nodes_raised\": ";
        const auto at = summary.find(key);
        REQUIRE(at != std::string::npos);
        const long raised = std::stol(summary.substr(at + key.size()));
        INFO("nodes raised: " << raised);
        CHECK(raised > 0);
    }
    // The "inserted" column: stop at the first row with at least half of the final count.
    const std::string header = history.substr(0, history.find('\n'));
    long col = 0;
    {
        std::stringstream hs(header);
        std::string name;
        long i = 0;
        col = -1;
        while (std::getline(hs, name, ',')) {
            if (name == "inserted") col = i;
            ++i;
        }
    }
    REQUIRE(col >= 0);
    std::vector<std::pair<long, long>> ins;  // (step, inserted) per row
    for (std::size_t pos = history.find('\n') + 1; pos < history.size(); pos = history.find('\n', pos) + 1) {
        std::stringstream ls(history.substr(pos, history.find('\n', pos) - pos));
        std::string field;
        long step = 0, n = 0;
        for (long i = 0; std::getline(ls, field, ','); ++i) {
            if (i == 1) step = std::stol(field);
            if (i == col) n = std::stol(field);
        }
        ins.emplace_back(step, n);
    }
    const long total = ins.back().second, steps = ins.back().first;
    // All 10 without per-node scaling; with it the heavier nodes reach fewer strengths in the stage's 0.004 s (2): a
    // stop between two insertions needs at least 2.
    if (per_node)
        REQUIRE(total >= 2);
    else
        REQUIRE(total == 10);
    long half = 0, at_stop = 0;
    for (const auto& [st, n] : ins)
        if (n >= total / 2) {
            half = st, at_stop = n;
            break;
        }
    INFO("stop after step " << half << " with " << at_stop << " of " << total << " inserted");
    CHECK(at_stop > 0);
    CHECK(at_stop < total);
    const std::string final_snapshot = "snapshots/step_" + std::string(9 - std::to_string(steps).size(), '0') + std::to_string(steps) + ".vtu";
    REQUIRE(std::filesystem::exists(full / final_snapshot));
    check_restart_identity(case_file, dir, full, half, final_snapshot);
}

TEST_CASE("a run with extrinsic insertion stopped between insertions and restarted gives byte-identical history, cracks and final snapshot",
          "[engine][regression]") {
    check_extrinsic_restart(false);
}

TEST_CASE("the same with per-node mass scaling: byte-identical history, cracks and final snapshot after the restart",
          "[engine][regression]") {
    check_extrinsic_restart(true);
}

TEST_CASE("the whole state after a save and load and the rest of the run equals the uninterrupted run's byte for byte",
          "[engine][regression]") {
    // In memory, without files: the saved state of the uninterrupted run at the end against that of a run saved at
    // the step where the cohesive elements are breaking, loaded into a fresh simulation and run on. Covers the state
    // the output files do not show (energy books, filters, friction histories, the cohesive node gather).
    auto a = testing::make_simulation(kWall, "restart_state_a");
    run_on(a, 0, true);
    const std::string end_a = state_of(a);
    const long half = a.steps() / 2;

    auto b = testing::make_simulation(kWall, "restart_state_b");
    run_on(b, 0, true, half);
    REQUIRE(b.steps() == half);
    const std::string mid = state_of(b);
    auto c = testing::make_simulation(kWall, "restart_state_c");
    fdem::StateReader r(mid.data(), mid.size());
    c.load_state(r);
    CHECK(state_of(c) == mid);  // load_state reads every byte save_state wrote, into the same fields
    run_on(c, static_cast<int>(c.stage_results().size()), false);
    CHECK(c.steps() == a.steps());
    CHECK(state_of(c) == end_a);
}

TEST_CASE("a state loaded into a simulation that has run on past it (extrinsic elements inserted since) goes on as a fresh load does",
          "[engine][regression]") {
    // The extrinsic wall of check_extrinsic_restart: the insertion check lists the dormant elements once and again
    // after each insertion; a load must have them listed anew from the loaded state, or the elements inserted after the
    // saved step are never checked again.
    std::string wall = kWall;
    for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
             {"  penalty = 5e10\n", "  penalty = 5e10\n  insertion = \"extrinsic\"\n"},
             {"tensile_strength = 1.0e6\n  cohesion = 1.4e6", "tensile_strength = 2.0e5\n  cohesion = 3.0e5"}}) {
        const auto p = wall.find(from);
        REQUIRE(p != std::string::npos);
        wall.replace(p, from.size(), to);
    }
    auto a = testing::make_simulation(wall, "reload_used_a");
    run_on(a, 0, true);
    const std::string end_a = state_of(a);
    const long inserted_a = a.interactions().joints()->extrinsic_count() - a.interactions().joints()->dormant_count();
    REQUIRE(inserted_a >= 2);
    // b: saved where some are inserted and not all, then run to the end (the rest inserted), then the saved state
    // loaded into b itself and run on again
    auto b = testing::make_simulation(wall, "reload_used_b");
    const int dormant0 = b.interactions().joints()->dormant_count();
    long half = 0;
    std::string mid;
    int stage_at_mid = 0;
    for (int s = 0; s < static_cast<int>(b.spec().stages.size()) && mid.empty(); ++s) {
        b.begin_stage(s);
        while (!b.stage_finished()) {
            b.step();
            const int inserted = dormant0 - b.interactions().joints()->dormant_count();
            if (inserted > 0 && inserted < inserted_a) {
                half = b.steps(), mid = state_of(b), stage_at_mid = s;
                break;
            }
        }
    }
    REQUIRE(!mid.empty());
    run_on(b, stage_at_mid, false);
    CHECK(b.interactions().joints()->dormant_count() == dormant0 - inserted_a);
    fdem::StateReader r(mid.data(), mid.size());
    b.load_state(r);
    CHECK(b.steps() == half);
    run_on(b, static_cast<int>(b.stage_results().size()), false);
    CHECK(b.steps() == a.steps());
    CHECK(b.interactions().joints()->dormant_count() == dormant0 - inserted_a);
    CHECK(state_of(b) == end_a);
}

TEST_CASE("a run killed with SIGKILL leaves history.csv whole and continues from its last checkpoint", "[engine]") {
    const auto dir = testing::tmp_dir("restart_sigkill");
    const std::string case_file = testing::write_text(dir / "wall.toml", kWall);
    const auto run = dir / "run";
    // A long second stage (the restart stops it with --stop-after-steps), a checkpoint every 0.5 ms of simulated
    // time; killed once a checkpoint and 20 history rows exist (or after 60 s).
    const std::string sets = " --set stages.1.duration=1.0 --set output.checkpoint_interval=0.0005";
    const std::string script = fdem_cmd("run \"" + case_file + "\" -o \"" + run.string() + "\"" + sets, 1) + " >/dev/null 2>&1 & p=$!; i=0; " +
                               "while { [ ! -f \"" + (run / "checkpoint.bin").string() + "\" ] || [ \"$(cat \"" + (run / "history.csv").string() +
                               "\" 2>/dev/null | wc -l)\" -lt 20 ]; } && [ $i -lt 600 ]; do sleep 0.1; i=$((i+1)); done; kill -KILL $p; wait $p; echo $? >\"" +
                               (dir / "code.txt").string() + "\"";
    REQUIRE(std::system(("sh -c '" + script + "'").c_str()) == 0);
    CHECK(std::stoi(testing::read_text(dir / "code.txt")) == 128 + 9);
    const std::string killed = testing::read_text(run / "history.csv");
    CHECK(whole_csv(killed));
    CHECK(testing::read_text(run / "summary.json").find("\"running\"") != std::string::npos);
    const long ck = checkpoint_step(run / "checkpoint.bin");
    REQUIRE(ck > 0);
    // Continued from the checkpoint and stopped 300 steps later; the same stop from a fresh run gives the same files.
    const std::string stop = " --stop-after-steps " + std::to_string(ck + 300);
    const auto r1 = run_cli("run \"" + case_file + "\" --restart \"" + run.string() + "\"" + sets + stop, 1, dir);
    INFO("checkpoint at step " << ck << ": " << r1.err);
    CHECK(r1.code == 138);
    const auto fresh = dir / "fresh";
    const auto r2 = run_cli("run \"" + case_file + "\" -o \"" + fresh.string() + "\"" + sets + stop, 1, dir);
    CHECK(r2.code == 138);
    const std::string continued = testing::read_text(run / "history.csv");
    CHECK(whole_csv(continued));
    CHECK(count_lines(continued) > 20);
    CHECK(continued == testing::read_text(fresh / "history.csv"));
    CHECK(testing::read_text(run / "cracks.csv") == testing::read_text(fresh / "cracks.csv"));
}

TEST_CASE("SIGUSR1 writes a checkpoint and stops with exit code 138", "[engine]") {
    const auto dir = testing::tmp_dir("restart_sigusr1");
    const std::string case_file = testing::write_text(dir / "wall.toml", kWall);
    const auto run = dir / "run";
    const std::string script = fdem_cmd("run \"" + case_file + "\" -o \"" + run.string() + "\" --set stages.1.duration=1.0", 1) +
                               " >/dev/null 2>\"" + (dir / "err.txt").string() + "\" & p=$!; i=0; while [ \"$(cat \"" +
                               (run / "history.csv").string() + "\" 2>/dev/null | wc -l)\" -lt 3 ] && [ $i -lt 600 ]; do sleep 0.1; i=$((i+1)); done; kill -USR1 $p; wait $p; echo $? >\"" +
                               (dir / "code.txt").string() + "\"";
    REQUIRE(std::system(("sh -c '" + script + "'").c_str()) == 0);
    INFO(testing::read_text(dir / "err.txt"));
    CHECK(std::stoi(testing::read_text(dir / "code.txt")) == 138);
    CHECK(std::filesystem::exists(run / "checkpoint.bin"));
    CHECK(testing::read_text(run / "run.log").find("interrupted by SIGUSR1") != std::string::npos);
    CHECK(testing::read_text(run / "run.log").find("--restart") != std::string::npos);
    CHECK(testing::read_text(run / "summary.json").find("\"interrupted\"") != std::string::npos);
}

TEST_CASE("a checkpoint of another case or build, a damaged one or none is refused with exit code 1", "[engine]") {
    const auto dir = testing::tmp_dir("restart_refused");
    const std::string case_file = testing::write_text(dir / "wall.toml", kWall);
    const auto run = dir / "run";
    REQUIRE(run_cli("run \"" + case_file + "\" -o \"" + run.string() + "\" --stop-after-steps 200", 1, dir).code == 138);
    const std::string good = testing::read_text(run / "checkpoint.bin");
    // Another case: a --set changes the resolved case.
    auto r = run_cli("run \"" + case_file + "\" --restart \"" + run.string() + "\" --set materials.brick.E=1.1e10", 1, dir);
    INFO(r.err);
    CHECK(r.code == 1);
    CHECK(r.err.find("checkpoint.bin") != std::string::npos);
    CHECK(r.err.find("another case") != std::string::npos);
    // The checkpoint keys are not part of the case: changing them is allowed.
    r = run_cli("run \"" + case_file + "\" --restart \"" + run.string() + "\" --set output.checkpoint_interval=0.001 --stop-after-steps 250", 1, dir);
    CHECK(r.code == 138);
    testing::write_text(run / "checkpoint.bin", good);
    // Another build: the build hash in the header differs.
    {
        std::string other = good;
        std::uint64_t n = 0;
        std::memcpy(&n, other.data() + 12, 8);
        other[12 + 8 + n] ^= 0x5a;
        testing::write_text(run / "checkpoint.bin", other);
        r = run_cli("run \"" + case_file + "\" --restart \"" + run.string() + "\"", 1, dir);
        INFO(r.err);
        CHECK(r.code == 1);
        CHECK(r.err.find("another build") != std::string::npos);
    }
    // Damaged: one byte of the state changed, or the file cut short.
    {
        std::string bad = good;
        bad[bad.size() - 100] ^= 0x01;
        testing::write_text(run / "checkpoint.bin", bad);
        r = run_cli("run \"" + case_file + "\" --restart \"" + run.string() + "\"", 1, dir);
        INFO(r.err);
        CHECK(r.code == 1);
        CHECK(r.err.find("damaged") != std::string::npos);
        testing::write_text(run / "checkpoint.bin", good.substr(0, good.size() / 2));
        r = run_cli("run \"" + case_file + "\" --restart \"" + run.string() + "\"", 1, dir);
        CHECK(r.code == 1);
        CHECK(r.err.find("damaged") != std::string::npos);
    }
    // None.
    std::filesystem::remove(run / "checkpoint.bin");
    r = run_cli("run \"" + case_file + "\" --restart \"" + run.string() + "\"", 1, dir);
    INFO(r.err);
    CHECK(r.code == 1);
    CHECK(r.err.find("no checkpoint") != std::string::npos);
    // Bad keys.
    r = run_cli("check \"" + case_file + "\" --set output.checkpoint_interval=-1", 1, dir);
    CHECK(r.code == 1);
    CHECK(r.err.find("output.checkpoint_interval") != std::string::npos);
    r = run_cli("check \"" + case_file + "\" --set output.checkpoint_wall_interval=0", 1, dir);
    CHECK(r.code == 1);
    CHECK(r.err.find("output.checkpoint_wall_interval") != std::string::npos);
}
