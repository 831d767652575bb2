// fracture/value_checks.hpp: the messages every law's check() gives for a missing or non-physical property, so that
// the [K25] law, the composite law and the Mohr-Coulomb layers word them the same way.
#pragma once

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

namespace fdem::fracture {

// A value for a message: 6 significant digits.
inline std::string fmt(double v) {
    std::ostringstream os;
    os.precision(6);
    os << v;
    return os.str();
}

// Adds "missing" (NaN) or "not physical" for one value that must be finite and > 0.
inline void need_positive(std::vector<std::string>& out, const char* name, const char* unit, double v) {
    if (std::isnan(v)) {
        out.push_back(std::string(name) + " is missing (" + unit + ")");
    } else if (!std::isfinite(v) || v <= 0.0) {
        out.push_back(std::string(name) + " = " + fmt(v) + " " + unit + " is not physical: it must be finite and > 0");
    }
}

// Adds "missing" (NaN) or "not physical" for an angle that must lie in [0, 90) degrees.
inline void need_angle(std::vector<std::string>& out, const char* name, double v) {
    if (std::isnan(v)) {
        out.push_back(std::string(name) + " is missing (degrees)");
    } else if (!(v >= 0.0 && v < 90.0)) {
        out.push_back(std::string(name) + " = " + fmt(v) + " deg is not physical: it must be in [0, 90)");
    }
}

}  // namespace fdem::fracture
