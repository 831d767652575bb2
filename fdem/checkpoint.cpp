// fdem/checkpoint.cpp: checkpoint and restart of a run (Simulation::save_state, load_state, write_checkpoint,
// restore). The state stream is fdem/common/state_io.hpp; each module writes its own part (Interactions, ContactSystem,
// CohesiveSystem).
//
// checkpoint.bin = header + payload:
//   "FDEMCKPT", format (u32), fdem version (string), build hash (u64: FNV-1a 64 of the executable), case hash (u64:
//   the resolved case and its mesh file), history.csv bytes at the checkpoint (u64), step (i64), time (f64),
//   payload size (u64), payload hash (u64), payload (Simulation::save_state).
// Written to checkpoint.bin.tmp, fsync'ed, renamed over checkpoint.bin, directory fsync'ed: a kill at any moment
// leaves the previous checkpoint or the new one, whole. The payload hash catches a damaged file.
//
// A restart rebuilds the model from the case (same build, same case: checked), then overwrites every piece of state
// that changes during a run with the checkpoint's. A field that is not saved shows up in tests/core/test_restart.cpp,
// which compares a restarted run with an uninterrupted one byte for byte; the sizeof guards below (x86-64
// libstdc++) fail the build when a class gains a field, so that its author decides whether it must be saved.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "fdem/common/errors.hpp"
#include "fdem/simulation.hpp"

namespace fdem {

namespace {

constexpr char kMagic[8] = {'F', 'D', 'E', 'M', 'C', 'K', 'P', 'T'};
constexpr std::uint32_t kFormat = 2;

std::uint64_t fnv1a(const char* p, std::size_t n, std::uint64_t h = 1469598103934665603ull) {
    for (std::size_t i = 0; i < n; ++i) h = (h ^ static_cast<unsigned char>(p[i])) * 1099511628211ull;
    return h;
}

std::string read_all(const std::string& path, bool& ok) {
    std::ifstream f(path, std::ios::binary);
    ok = static_cast<bool>(f);
    if (!ok) return {};
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}

// FNV-1a 64 of the running executable, once per process: a checkpoint is read back only by the build that wrote it
// (the raw state bytes depend on the code's layout and arithmetic). 0 when /proc/self/exe cannot be read.
std::uint64_t build_hash() {
    static const std::uint64_t h = [] {
        bool ok = false;
        const std::string exe = read_all("/proc/self/exe", ok);
        return ok ? fnv1a(exe.data(), exe.size()) : std::uint64_t{0};
    }();
    return h;
}

// The resolved case (its TOML after --set, CaseSpec::resolved_hash) and the contents of its mesh or geometry file.
std::uint64_t case_hash(const CaseSpec& spec) {
    std::uint64_t h = fnv1a(reinterpret_cast<const char*>(&spec.resolved_hash), sizeof spec.resolved_hash);
    if (!spec.geometry.file.empty()) {
        bool ok = false;
        const std::string text = read_all(spec.geometry.file, ok);
        if (ok) h = fnv1a(text.data(), text.size(), h);
    }
    return h;
}

double wall_clock_now() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

std::string hex(std::uint64_t v) {
    char b[24];
    std::snprintf(b, sizeof b, "%016llx", static_cast<unsigned long long>(v));
    return b;
}

// path.tmp, write, fsync, rename, fsync of the folder.
void write_durable(const std::string& path, const std::string& content) {
    const std::string tmp = path + ".tmp";
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) throw RunError("cannot write " + tmp + ": " + std::strerror(errno));
    const char* p = content.data();
    std::size_t left = content.size();
    while (left > 0) {
        const ssize_t n = ::write(fd, p, left);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int err = errno;
            ::close(fd);
            throw RunError("cannot write " + tmp + ": " + std::strerror(err));
        }
        p += n, left -= static_cast<std::size_t>(n);
    }
    if (::fsync(fd) != 0 || ::close(fd) != 0) throw RunError("cannot write " + tmp + ": " + std::strerror(errno));
    if (std::rename(tmp.c_str(), path.c_str()) != 0) throw RunError("cannot rename " + tmp + " to " + path + ": " + std::strerror(errno));
    const std::string dir = std::filesystem::path(path).parent_path().string();
    const int dfd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd >= 0) {
        ::fsync(dfd);
        ::close(dfd);
    }
}

void save_fn(StateWriter& w, const TimeFunction& f) {
    w.str(f.type);
    w.pod(f.amplitude), w.pod(f.omega), w.pod(f.phase), w.pod(f.offset);
    w.vec(f.t), w.vec(f.f);
}

void load_fn(StateReader& r, TimeFunction& f) {
    r.str(f.type);
    r.pod(f.amplitude), r.pod(f.omega), r.pod(f.phase), r.pod(f.offset);
    r.vec(f.t), r.vec(f.f);
}

void check_index(int i, int n, const char* what) {
    if (i < -1 || i >= n) throw StateError(std::string(what) + " out of range");
}

}  // namespace

std::string Simulation::checkpoint_path() const { return (std::filesystem::path(opt_.out_dir) / "checkpoint.bin").string(); }

// Everything that changes during a run. The order is the format: load_state reads the same sequence.
void Simulation::save_state(StateWriter& w) const {
#if defined(__x86_64__) && defined(__GLIBCXX__)
    // (not saved: the energy audit's sums, a diagnostic of one process; after a restart it starts over; the node
    // loop's speeds block_v2_ and v2max_, which load_state marks unknown)
    static_assert(sizeof(Simulation) == 5168, "Simulation changed: update save_state/load_state (fdem/checkpoint.cpp) and this size");
    static_assert(sizeof(ActiveSupport) == 376, "ActiveSupport changed: update save_state/load_state and this size");
    static_assert(sizeof(ActiveLoad) == 296, "ActiveLoad changed: update save_state/load_state and this size");
#endif
    const int nn = model_.n_nodes();
    w.section("model");
    w.pod(nn), w.pod(model_.n_triangles());
    w.vec(model_.x), w.vec(model_.v), w.vec(model_.mass), w.vec(model_.inv_mass), w.vec(model_.grav_mass);

    w.section("clock");
    w.pod(dt_initial_), w.pod(dt_), w.pod(dt_limit_), w.pod(dt_springs_), w.pod(dt_logged_), w.pod(time_), w.pod(steps_), w.pod(stage_), w.pod(stage_t0_), w.pod(stage_steps0_), w.pod(broken_total_), w.pod(eq_since_);

    w.section("supports");
    w.vec(dof_kind_), w.vec(dof_owner_), w.vec(dof_vel_), w.vec(reaction_);
    w.pod(static_cast<std::uint64_t>(supports_.size()));
    for (const ActiveSupport& a : supports_) {
        w.vec(a.nodes);
        w.pod(a.comp), w.pod(a.mode);
        w.pod(a.v_start), w.pod(a.v_target), w.pod(a.ramp), w.pod(a.t0), w.pod(a.v_common), w.pod(a.v_ref);
        w.vec(a.pt), w.vec(a.pu), w.vec(a.pI);
        save_fn(w, a.fn);
        w.pod(a.servo_ratio), w.pod(a.servo_time), w.pod(a.servo_min), w.pod(a.servo_factor), w.pod(a.servo_rbar);
        w.pod(a.servo_t), w.pod(a.servo_r_int), w.pod(a.servo_f_int), w.pod(a.servo_r_max), w.pod(a.servo_f_min);
        w.str(a.group);
    }

    w.section("loads");
    w.pod(static_cast<std::uint64_t>(loads_.size()));
    for (const ActiveLoad& l : loads_) {
        w.vec(l.nodes), w.vec(l.weight), w.vec(l.edges);
        w.pod(l.is_pressure), w.pod(l.is_spring), w.pod(l.comp);
        w.pod(l.k), w.pod(l.v), w.pod(l.anchor0), w.pod(l.start), w.pod(l.target), w.pod(l.ramp), w.pod(l.t0);
        save_fn(w, l.fn);
        w.str(l.group);
    }
    w.vec(f_ext_), w.vec(loaded_dofs_);

    w.section("gravity");
    w.pod(gravity_), w.pod(gravity_start_), w.pod(gravity_target_), w.pod(applied_gravity_);
    w.pod(gravity_ramp_), w.pod(tilt_rate_), w.pod(tilt_deg_);
    save_fn(w, gravity_fn_);
    w.pod(gravity_fn_t0_);

    w.section("damping");
    w.pod(alpha_), w.pod(tau_ld_), w.vec(v_ref_), w.pod(beta_mass_), w.pod(xi_contact_);

    w.section("energy");
    w.vec(f_mod_);
    w.pod(kinetic_n_), w.pod(work_half_), w.pod(damp_half_), w.pod(mass_half_), w.pod(unbalanced_ratio_);
    w.pod(W_ext_), w.pod(D_damp_), w.pod(D_visc_), w.pod(D_mass_);

    w.section("stage");
    w.pod(until_start_), w.pod(until_monitor_), w.pod(stage_ramp_end_);
    w.pod(peak_load_monitor_), w.pod(peak_disp_monitor_), w.pod(peak_mean_), w.pod(peak_u_prev_), w.pod(peak_load_), w.pod(peak_disp_), w.pod(below_since_);
    w.pod(static_cast<std::uint64_t>(stage_results_.size()));
    for (const StageResult& r : stage_results_) {
        w.str(r.name), w.str(r.ended_by);
        w.pod(r.time), w.pod(r.steps);
    }

    w.section("outputs");
    w.pod(last_row_step_);
    w.vec(mon_ext_);
    w.pod(mon_ext_init_);
    w.vec(mon_first_peak_);
    w.pod(next_history_), w.pod(next_snapshot_), w.pod(history_every_steps_), w.pod(next_checkpoint_);
    w.pod(static_cast<std::uint64_t>(snapshots_.size()));
    for (const auto& [t, name] : snapshots_) w.pod(t), w.str(name);

    // Crushing triangles (fdem/plasticity.hpp): plastic strain and softening variable per slot (the rest is set up
    // from the case).
    w.section("crushing");
    w.vec(crush_.Ep), w.vec(crush_.kappa);

    inter_.save_state(w);
    w.section("end");
}

void Simulation::load_state(StateReader& r) {
    const int nn = model_.n_nodes();
    const std::size_t nd = 2 * static_cast<std::size_t>(nn);
    r.section("model");
    if (r.get<int>() != nn || r.get<int>() != model_.n_triangles()) throw StateError("another mesh (node or triangle count)");
    r.vec_sized(model_.x, nd, "positions");
    r.vec_sized(model_.v, nd, "velocities");
    v2max_ = -1.0;
    r.vec_sized(model_.mass, static_cast<std::size_t>(nn), "masses");
    r.vec_sized(model_.inv_mass, static_cast<std::size_t>(nn), "inverse masses");
    r.vec_sized(model_.grav_mass, static_cast<std::size_t>(nn), "gravitational masses");

    r.section("clock");
    const double dt = r.get<double>();
    if (dt != dt_initial_)
        throw StateError("time step " + std::to_string(dt) + " s, this case gives " + std::to_string(dt_initial_) + " s");
    r.pod(dt_), r.pod(dt_limit_), r.pod(dt_springs_), r.pod(dt_logged_);  // smaller than at the start after insertions
    r.pod(time_), r.pod(steps_), r.pod(stage_), r.pod(stage_t0_), r.pod(stage_steps0_), r.pod(broken_total_), r.pod(eq_since_);
    if (stage_ < 0 || stage_ >= static_cast<int>(spec_.stages.size())) throw StateError("stage index out of range");

    r.section("supports");
    r.vec_sized(dof_kind_, nd, "DOF kinds");
    r.vec_sized(dof_owner_, nd, "DOF owners");
    r.vec_sized(dof_vel_, nd, "prescribed velocities");
    r.vec_sized(reaction_, nd, "reactions");
    supports_.assign(static_cast<std::size_t>(r.get<std::uint64_t>()), ActiveSupport{});
    for (ActiveSupport& a : supports_) {
        r.vec(a.nodes);
        for (int k : a.nodes) check_index(k, nn, "support node");
        r.pod(a.comp), r.pod(a.mode);
        r.pod(a.v_start), r.pod(a.v_target), r.pod(a.ramp), r.pod(a.t0), r.pod(a.v_common), r.pod(a.v_ref);
        r.vec(a.pt), r.vec(a.pu), r.vec(a.pI);
        load_fn(r, a.fn);
        r.pod(a.servo_ratio), r.pod(a.servo_time), r.pod(a.servo_min), r.pod(a.servo_factor), r.pod(a.servo_rbar);
        r.pod(a.servo_t), r.pod(a.servo_r_int), r.pod(a.servo_f_int), r.pod(a.servo_r_max), r.pod(a.servo_f_min);
        r.str(a.group);
    }
    for (int o : dof_owner_) check_index(o, static_cast<int>(supports_.size()), "DOF owner");

    r.section("loads");
    loads_.assign(static_cast<std::size_t>(r.get<std::uint64_t>()), ActiveLoad{});
    for (ActiveLoad& l : loads_) {
        r.vec(l.nodes), r.vec(l.weight), r.vec(l.edges);
        for (int k : l.nodes) check_index(k, nn, "load node");
        for (const auto& e : l.edges) check_index(e[0], nn, "load edge node"), check_index(e[1], nn, "load edge node");
        r.pod(l.is_pressure), r.pod(l.is_spring), r.pod(l.comp);
        r.pod(l.k), r.pod(l.v), r.pod(l.anchor0), r.pod(l.start), r.pod(l.target), r.pod(l.ramp), r.pod(l.t0);
        load_fn(r, l.fn);
        r.str(l.group);
    }
    r.vec_sized(f_ext_, nd, "applied loads");
    r.vec(loaded_dofs_);
    for (int d : loaded_dofs_) check_index(d, static_cast<int>(nd), "loaded DOF");
    node_loaded_.assign(nd / 2, 0);
    for (int d : loaded_dofs_) node_loaded_[d / 2] = 1;

    r.section("gravity");
    r.pod(gravity_), r.pod(gravity_start_), r.pod(gravity_target_), r.pod(applied_gravity_);
    r.pod(gravity_ramp_), r.pod(tilt_rate_), r.pod(tilt_deg_);
    load_fn(r, gravity_fn_);
    r.pod(gravity_fn_t0_);

    r.section("damping");
    r.pod(alpha_), r.pod(tau_ld_), r.vec(v_ref_), r.pod(beta_mass_), r.pod(xi_contact_);
    set_step_limits(alpha_, false);  // the current stage's limits (a later insertion compares against them)
    if (!v_ref_.empty() && v_ref_.size() != nd) throw StateError("velocity filter of another mesh");
    if (tau_ld_ > 0 && v_ref_.size() != nd) throw StateError("velocity filter missing");
    inter_.set_contact_dashpot(std::isfinite(dt_contact_) ? xi_contact_ * dt_contact_ : 0.0);  // the contact state holds it too

    r.section("energy");
    r.vec_sized(f_mod_, nd, "module forces");
    r.pod(kinetic_n_), r.pod(work_half_), r.pod(damp_half_), r.pod(mass_half_), r.pod(unbalanced_ratio_);
    r.pod(W_ext_), r.pod(D_damp_), r.pod(D_visc_), r.pod(D_mass_);

    r.section("stage");
    r.pod(until_start_), r.pod(until_monitor_), r.pod(stage_ramp_end_);
    check_index(until_monitor_, static_cast<int>(spec_.monitors.size()), "until monitor");
    r.pod(peak_load_monitor_), r.pod(peak_disp_monitor_), r.pod(peak_mean_), r.pod(peak_u_prev_), r.pod(peak_load_), r.pod(peak_disp_), r.pod(below_since_);
    check_index(peak_load_monitor_, static_cast<int>(spec_.monitors.size()), "past_peak load monitor");
    check_index(peak_disp_monitor_, static_cast<int>(spec_.monitors.size()), "past_peak displacement monitor");
    stage_results_.assign(static_cast<std::size_t>(r.get<std::uint64_t>()), StageResult{});
    for (StageResult& s : stage_results_) {
        r.str(s.name), r.str(s.ended_by);
        r.pod(s.time), r.pod(s.steps);
    }

    r.section("outputs");
    r.pod(last_row_step_);
    r.vec_sized(mon_ext_, spec_.monitors.size(), "monitor extrema");
    r.pod(mon_ext_init_);
    r.vec_sized(mon_first_peak_, spec_.monitors.size(), "monitor first peaks");
    r.pod(next_history_), r.pod(next_snapshot_), r.pod(history_every_steps_), r.pod(next_checkpoint_);
    snapshots_.assign(static_cast<std::size_t>(r.get<std::uint64_t>()), {});
    for (auto& [t, name] : snapshots_) r.pod(t), r.str(name);

    r.section("crushing");
    r.vec_sized(crush_.Ep, crush_.Ep.size(), "crushing plastic strains");
    r.vec_sized(crush_.kappa, crush_.kappa.size(), "crushing softening variables");

    inter_.load_state(r);
    build_ties();  // derived from the cohesive elements still dormant
    r.section("end");
    if (!r.at_end()) throw StateError("data after the end of the state");
}

void Simulation::write_checkpoint() {
    if (opt_.out_dir.empty()) return;
    StateWriter payload;
    save_state(payload);
    const std::string hist = (std::filesystem::path(opt_.out_dir) / "history.csv").string();
    const std::uint64_t hist_bytes = history_out_.is_open() ? static_cast<std::uint64_t>(std::filesystem::file_size(hist)) : 0;
    StateWriter head;
    head.data().append(kMagic, sizeof kMagic);
    head.pod(kFormat);
    head.str(FDEM_VERSION);
    head.pod(build_hash());
    head.pod(case_hash(spec_));
    head.pod(hist_bytes);
    head.pod(static_cast<std::int64_t>(steps_));
    head.pod(time_);
    head.pod(static_cast<std::uint64_t>(payload.data().size()));
    head.pod(fnv1a(payload.data().data(), payload.data().size()));
    write_durable(checkpoint_path(), head.data() + payload.data());
    last_checkpoint_wall_ = wall_clock_now();
    ++checkpoints_written_;
}

void Simulation::checkpoint_if_due() {
    if (opt_.out_dir.empty()) return;
    bool due = false;
    if (spec_.checkpoint_interval > 0 && time_ + 1e-9 * dt_ >= next_checkpoint_) {
        const double ci = spec_.checkpoint_interval;
        next_checkpoint_ += ci * std::max(1.0, std::floor((time_ - next_checkpoint_) / ci) + 1);
        due = true;
    }
    if (spec_.checkpoint_wall_interval > 0 && (steps_ & 15) == 0 &&
        wall_clock_now() - last_checkpoint_wall_ >= spec_.checkpoint_wall_interval)
        due = true;
    if (due) write_checkpoint();
}

void Simulation::restore(const std::string& run_dir) {
    namespace fs = std::filesystem;
    const std::string path = (fs::path(run_dir) / "checkpoint.bin").string();
    const std::string again = "run the case from the start instead (fdem run CASE -o DIR)";
    bool ok = false;
    const std::string data = read_all(path, ok);
    if (!ok)
        throw InputError(path + ": no checkpoint to restart from (a run writes one every [output] checkpoint_interval s "
                                "of simulated time or checkpoint_wall_interval s of wall time, and when SIGINT, SIGTERM or "
                                "SIGUSR1 stops it)");
    StateReader h(data.data(), data.size());
    std::string version;
    std::uint64_t build = 0, chash = 0, hist_bytes = 0, size = 0, phash = 0;
    std::int64_t step = 0;
    double t = 0;
    try {
        char magic[sizeof kMagic];
        for (char& c : magic) h.pod(c);
        if (std::memcmp(magic, kMagic, sizeof kMagic) != 0) throw StateError("not an fdem checkpoint");
        const auto format = h.get<std::uint32_t>();
        if (format != kFormat) throw StateError("checkpoint format " + std::to_string(format) + ", this build reads format " + std::to_string(kFormat));
        h.str(version);
        h.pod(build), h.pod(chash), h.pod(hist_bytes), h.pod(step), h.pod(t), h.pod(size), h.pod(phash);
    } catch (const StateError& e) {
        throw InputError(path + ": cannot restart: " + e.what());
    }
    if (version != FDEM_VERSION || build != build_hash())
        throw InputError(path + ": cannot restart: the checkpoint was written by another build of fdem (version " + version +
                         ", build " + hex(build) + "; this is version " FDEM_VERSION ", build " + hex(build_hash()) +
                         "): restart with the executable that wrote it, or " + again);
    if (chash != case_hash(spec_))
        throw InputError(path + ": cannot restart: the checkpoint was written for another case (" + spec_.file +
                         " as resolved with its --set overrides, or its mesh file, differs from the run's): restart with "
                         "the same case file and --set options, or " + again);
    const std::size_t head_size = data.size() - static_cast<std::size_t>(h.remaining());
    if (size != static_cast<std::uint64_t>(h.remaining()) || fnv1a(data.data() + head_size, size) != phash)
        throw InputError(path + ": cannot restart: the checkpoint is damaged (its size or checksum does not match); " + again);
    try {
        StateReader r(data.data() + head_size, static_cast<std::size_t>(size));
        load_state(r);
    } catch (const StateError& e) {
        throw InputError(path + ": cannot restart: " + e.what());
    }
    // history.csv: back to the checkpoint's row, then appended to.
    const std::string hist = (fs::path(run_dir) / "history.csv").string();
    if (hist_bytes > 0) {
        std::error_code ec;
        const auto have = fs::file_size(hist, ec);
        if (ec || have < hist_bytes)
            throw InputError(hist + ": cannot restart: the file has " + (ec ? std::string("gone") : std::to_string(have) + " bytes") +
                             ", the checkpoint needs its first " + std::to_string(hist_bytes) + " bytes; " + again);
        fs::resize_file(hist, hist_bytes);
        history_.clear();
        history_out_.open(hist, std::ios::binary | std::ios::app);
        if (!history_out_) throw RunError("cannot write " + hist);
    }
    // Snapshots written after the checkpoint (the one of the stop itself, or those of a run killed later) are not in
    // run.pvd any more; the continued run writes its own.
    std::set<std::string> kept;
    for (const auto& s : snapshots_) kept.insert(fs::path(s.second).filename().string());
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(fs::path(run_dir) / "snapshots", ec)) {
        const std::string name = entry.path().filename().string();
        long st = -1;
        if (std::sscanf(name.c_str(), "step_%ld.vtu", &st) == 1 && st >= steps_ && !kept.count(name)) fs::remove(entry.path(), ec);
    }
    // The log goes on after the earlier run's.
    bool log_ok = false;
    log_ = read_all((fs::path(run_dir) / "run.log").string(), log_ok);
    resumed_ = true;
    log("restart: from " + path + " at step " + std::to_string(steps_) + ", t = " + format_double(time_) + " s, stage " +
        std::to_string(stage_ + 1) + " '" + spec_.stages[stage_].name + "'; history.csv truncated to its first " +
        std::to_string(hist_bytes) + " bytes");
}

}  // namespace fdem
