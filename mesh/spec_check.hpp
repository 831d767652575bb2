// mesh/spec_check.hpp: the key checks the geometry generators (mesh/wall.cpp, mesh/macro.cpp) share: a number for a
// message, and the "must be > 0" / ">= 0" checks of a length key, each adding one line to a list of problems.
#pragma once

#include <sstream>
#include <string>
#include <vector>

namespace fdem::mesh::spec_check {

// v with 6 significant digits, for messages.
inline std::string num(double v) {
    std::ostringstream s;
    s.precision(6);
    s << v;
    return s.str();
}

// Problems of geometry keys, one line each ("geometry.KEY must be ... (m), got V").
struct Lengths {
    std::vector<std::string>& bad;
    void positive(double v, const char* key) const {
        if (!(v > 0)) bad.push_back(std::string("geometry.") + key + " must be > 0 (m), got " + num(v));
    }
    void nonnegative(double v, const char* key) const {
        if (!(v >= 0)) bad.push_back(std::string("geometry.") + key + " must be >= 0 (m), got " + num(v));
    }
};

// The keys of the beam on top and the mesh sizes of beam and base, which the wall and the macro pier share, in the
// order both report them: mesh_size_beam, mesh_size_base, beam_height, beam_overhang (each >= 0; 0 = default / none).
template <class Spec>
void beam_and_sizes(const Lengths& len, const Spec& s) {
    len.nonnegative(s.mesh_size_beam, "mesh_size_beam");
    len.nonnegative(s.mesh_size_base, "mesh_size_base");
    len.nonnegative(s.beam_height, "beam_height");
    len.nonnegative(s.beam_overhang, "beam_overhang");
}

}  // namespace fdem::mesh::spec_check
