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
// that changes during a run with the checkpoint's: the Model's positions, velocities and masses, the state structs
// of fdem/sim_state.hpp (each by its own io, fdem/sim_state.cpp, next to a check of the struct's field count that
// fails the build when the struct gains a field), the crushing state and the modules (their own save_state and
// load_state); the caches are rebuilt. A field that is not saved shows up in tests/core/test_restart.cpp, which
// compares a restarted run with an uninterrupted one byte for byte.
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
// 4: a seventh double per contact slot (restitution); 5: each load saved by its kind; 6: each support saved by its
// kind; 7: the module forces (zero between steps, a cache) no longer saved
constexpr std::uint32_t kFormat = 8;

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

}  // namespace

std::string Simulation::checkpoint_path() const { return (std::filesystem::path(opt_.out_dir) / "checkpoint.bin").string(); }

// Everything that changes during a run, in one list for both directions (state_io): the order is the format.
void Simulation::save_state(StateWriter& w) const {
    const_cast<Simulation*>(this)->state_io(w);  // (the writer only reads the fields)
}

void Simulation::load_state(StateReader& r) { state_io(r); }

// IO = StateWriter (save) or StateReader (load): the sections in order, each state struct by its io; what only a
// load does (check the mesh and the step, derive the caches that follow from the state) under IO::loading.
template <class IO>
void Simulation::state_io(IO& io) {
    constexpr bool load = IO::loading;
    const int nn = model_.n_nodes();
    const std::size_t nd = 2 * static_cast<std::size_t>(nn);
    io.section("model");
    int n_nodes = nn, n_tri = model_.n_triangles();
    io.pod(n_nodes), io.pod(n_tri);
    if constexpr (load)
        if (n_nodes != nn || n_tri != model_.n_triangles()) throw StateError("another mesh (node or triangle count)");
    io.vec_sized(model_.x, nd, "positions");
    io.vec_sized(model_.v, nd, "velocities");
    if constexpr (load) scratch_.v2max = -1.0;
    io.vec_sized(model_.mass, static_cast<std::size_t>(nn), "masses");
    io.vec_sized(model_.inv_mass, static_cast<std::size_t>(nn), "inverse masses");
    io.vec_sized(model_.grav_mass, static_cast<std::size_t>(nn), "gravitational masses");

    const StateShape shape{nn, static_cast<int>(spec_.monitors.size()), static_cast<int>(spec_.stages.size())};
    io.section("clock");
    double dt0 = limits_.dt_initial;  // the case's step at the start: a load checks it
    io.pod(dt0);
    if constexpr (load)
        if (dt0 != limits_.dt_initial)
            throw StateError("time step " + std::to_string(dt0) + " s, this case gives " +
                             std::to_string(limits_.dt_initial) + " s");
    clock_.io(io, shape);

    io.section("supports");
    supports_.io(io, shape);

    io.section("loads");
    loads_.io(io, shape);
    if constexpr (load) {
        scratch_.node_loaded.assign(nd / 2, 0);
        for (int d : loads_.loaded_dofs) scratch_.node_loaded[d / 2] = 1;
    }

    io.section("gravity");
    gravity_.io(io, shape);

    io.section("damping");
    damping_.io(io, shape);
    if constexpr (load) {
        set_step_limits(damping_.local, false);  // the current stage's limits (a later insertion compares against them)
        inter_.set_contact_dashpot(std::isfinite(limits_.dt_contact) ? damping_.contact * limits_.dt_contact
                                                                     : 0.0);  // the contact state holds it too
    }

    io.section("energy");
    books_.io(io, shape);

    io.section("stage");
    ending_.io(io, shape);

    io.section("outputs");
    out_.io(io, shape);

    // Crushing triangles (fdem/plasticity.hpp): plastic strain and softening variable per slot (the rest is set up
    // from the case).
    io.section("crushing");
    io.vec_sized(crush_.Ep, crush_.Ep.size(), "crushing plastic strains");
    io.vec_sized(crush_.kappa, crush_.kappa.size(), "crushing softening variables");

    if constexpr (load) {
        inter_.load_state(io);
        build_ties();  // derived from the cohesive elements still dormant
    } else {
        inter_.save_state(io);
    }
    io.section("end");
    if constexpr (load)
        if (!io.at_end()) throw StateError("data after the end of the state");
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
    head.pod(static_cast<std::int64_t>(clock_.steps));
    head.pod(clock_.time);
    head.pod(static_cast<std::uint64_t>(payload.data().size()));
    head.pod(fnv1a(payload.data().data(), payload.data().size()));
    write_durable(checkpoint_path(), head.data() + payload.data());
    last_checkpoint_wall_ = wall_clock_now();
}

void Simulation::checkpoint_if_due() {
    if (opt_.out_dir.empty()) return;
    bool due = false;
    if (spec_.checkpoint_interval > 0 && clock_.time + 1e-9 * clock_.dt >= out_.next_checkpoint) {
        const double ci = spec_.checkpoint_interval;
        out_.next_checkpoint += ci * std::max(1.0, std::floor((clock_.time - out_.next_checkpoint) / ci) + 1);
        due = true;
    }
    if (spec_.checkpoint_wall_interval > 0 && (clock_.steps & 15) == 0 &&
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
    for (const auto& s : out_.snapshots) {
        kept.insert(fs::path(s.second).filename().string());
        kept.insert(fs::path(contact_snapshot_name(s.second)).filename().string());
    }
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(fs::path(run_dir) / "snapshots", ec)) {
        const std::string name = entry.path().filename().string();
        long st = -1;
        const bool ours = std::sscanf(name.c_str(), "step_%ld.vtu", &st) == 1 || std::sscanf(name.c_str(), "contacts_%ld.vtu", &st) == 1;
        if (ours && st >= clock_.steps && !kept.count(name)) fs::remove(entry.path(), ec);
    }
    // The log goes on after the earlier run's.
    bool log_ok = false;
    log_ = read_all((fs::path(run_dir) / "run.log").string(), log_ok);
    resumed_ = true;
    log("restart: from " + path + " at step " + std::to_string(clock_.steps) + ", t = " + format_double(clock_.time) +
        " s, stage " + std::to_string(clock_.stage + 1) + " '" + spec_.stages[clock_.stage].name +
        "'; history.csv truncated to its first " + std::to_string(hist_bytes) + " bytes");
}

}  // namespace fdem
