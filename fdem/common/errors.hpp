// fdem/common/errors.hpp: the error types that map onto the command's exit codes (ARCHITECTURE.md).
//   InputError  -> exit 1: bad case file, bad option, bad mesh; the message names file, line, key, expectation.
//   RunError    -> exit 2: the run failed (instability, inverted element, NaN); says where and when.
//   anything else -> exit 3: an internal error (a bug in fdem).
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

namespace fdem {

struct InputError : std::runtime_error {
    explicit InputError(const std::string& what) : std::runtime_error(what) {}
    explicit InputError(const std::vector<std::string>& list) : std::runtime_error(join(list)), messages(list) {}
    std::vector<std::string> messages;

private:
    static std::string join(const std::vector<std::string>& m) {
        std::string s;
        for (std::size_t i = 0; i < m.size(); ++i) s += (i ? "\n" : "") + m[i];
        return s;
    }
};

struct RunError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

}  // namespace fdem
