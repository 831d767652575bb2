// fdem/common/state_io.hpp: the byte stream of a checkpoint (fdem/checkpoint.hpp). Header-only and without
// dependencies, so that the contact and fracture modules (leaves) serialise their own state with it: each subsystem has
// save_state(StateWriter&) const and load_state(StateReader&), which write and read the same fields in the same order.
//
// Format: a sequence of tagged sections. section("name") writes the name; the reader checks it, so a load that
// reads a different sequence of fields than the save wrote stops at the first section that disagrees instead of
// reading garbage. Values are raw bytes of trivially copyable types (the same build on the same machine reads
// them: a checkpoint from another build is refused before any state is read); vectors and strings carry their length.
//
// Adding a field to a subsystem: write it in save_state and read it in load_state at the same place. The guards
// next to each (the field counts of the engine's state structs, fdem/sim_state.cpp; the sizeof guards of
// contact/contact_system.cpp and fracture/cohesive_system.cpp) fail the build when a state grows, to make a
// forgotten field visible; the restart test (tests/core/test_restart.cpp) compares a restarted run with an
// uninterrupted one byte for byte.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace fdem {

// Thrown by StateReader on a stream that does not match what load_state expects (std::runtime_error: the engine
// turns it into an input error naming the checkpoint file).
struct StateError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// One function can save and load a state (one list of fields: template <class IO> void io(IO&), called with a
// StateWriter or a StateReader): pod, vec, vec_sized, str and section have the same names on both, and `loading`
// tells the two apart where a load must check or resize (if constexpr (IO::loading)).
class StateWriter {
public:
    static constexpr bool loading = false;
    void section(const char* name) { str(name); }
    template <class T>
    void pod(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>, "pod(): trivially copyable types only");
        const auto* p = reinterpret_cast<const char*>(&v);
        buf_.append(p, sizeof(T));
    }
    template <class T>
    void vec(const std::vector<T>& v) {
        static_assert(std::is_trivially_copyable_v<T>, "vec(): trivially copyable elements only");
        pod(static_cast<std::uint64_t>(v.size()));
        if (!v.empty()) buf_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    }
    void vec(const std::vector<bool>&) = delete;
    // (the reader checks the length; the writer writes the vector as vec does)
    template <class T>
    void vec_sized(const std::vector<T>& v, std::size_t, const char*) {
        vec(v);
    }
    void str(const std::string& s) {
        pod(static_cast<std::uint64_t>(s.size()));
        buf_.append(s);
    }
    const std::string& data() const { return buf_; }
    std::string& data() { return buf_; }

private:
    std::string buf_;
};

class StateReader {
public:
    static constexpr bool loading = true;
    StateReader(const char* data, std::size_t size) : p_(data), end_(data + size) {}
    void section(const char* name) {
        std::string got;
        str(got);
        if (got != name)
            throw StateError(std::string("expected the section '") + name + "', found '" + got.substr(0, 64) + "'");
    }
    template <class T>
    void pod(T& v) {
        static_assert(std::is_trivially_copyable_v<T>, "pod(): trivially copyable types only");
        need(sizeof(T));
        std::memcpy(reinterpret_cast<char*>(&v), p_, sizeof(T));
        p_ += sizeof(T);
    }
    template <class T>
    T get() {
        T v{};
        pod(v);
        return v;
    }
    template <class T>
    void vec(std::vector<T>& v) {
        static_assert(std::is_trivially_copyable_v<T>, "vec(): trivially copyable elements only");
        const auto n = get<std::uint64_t>();
        if (n > static_cast<std::uint64_t>(end_ - p_) / (sizeof(T) ? sizeof(T) : 1)) throw StateError("truncated vector");
        v.resize(static_cast<std::size_t>(n));
        if (n) std::memcpy(reinterpret_cast<char*>(v.data()), p_, static_cast<std::size_t>(n) * sizeof(T));
        p_ += static_cast<std::size_t>(n) * sizeof(T);
    }
    void vec(std::vector<bool>&) = delete;
    void str(std::string& s) {
        const auto n = get<std::uint64_t>();
        need(static_cast<std::size_t>(std::min<std::uint64_t>(n, static_cast<std::uint64_t>(end_ - p_) + 1)));
        s.assign(p_, static_cast<std::size_t>(n));
        p_ += n;
    }
    // A vector whose length the loader knows (per node, per triangle): a different length is an error.
    template <class T>
    void vec_sized(std::vector<T>& v, std::size_t expected, const char* what) {
        std::vector<T> tmp;
        vec(tmp);
        if (tmp.size() != expected)
            throw StateError(std::string(what) + ": " + std::to_string(tmp.size()) + " entries, expected " +
                             std::to_string(expected));
        v.swap(tmp);
    }
    bool at_end() const { return p_ == end_; }
    std::size_t remaining() const { return static_cast<std::size_t>(end_ - p_); }

private:
    void need(std::size_t n) const {
        if (n > static_cast<std::size_t>(end_ - p_)) throw StateError("the checkpoint ends early (truncated)");
    }
    const char* p_;
    const char* end_;
};

// The length of a list of records, then (the caller) each record: written from v; read, v holds that many
// default records to be filled.
template <class IO, class C>
void io_count(IO& io, C& v) {
    std::uint64_t n = v.size();
    io.pod(n);
    if constexpr (IO::loading) v.assign(static_cast<std::size_t>(n), typename C::value_type{});
}

}  // namespace fdem
