// fdem/load_registry.cpp: the registered load kinds (fdem/load.hpp), in the order the case reader tries them and
// lists them in its messages. A new kind: its file defines `const LoadKind& NAME_load_kind()`; declare it here and
// add it to the list.
#include <stdexcept>

#include "fdem/load.hpp"

namespace fdem {

const LoadKind& force_load_kind();     // fdem/load_force.cpp
const LoadKind& pressure_load_kind();  // fdem/load_pressure.cpp
const LoadKind& spring_load_kind();    // fdem/load_spring.cpp
const LoadKind& foundation_load_kind();  // fdem/load_foundation.cpp

const std::vector<const LoadKind*>& load_kinds() {
    static const std::vector<const LoadKind*> kinds{&force_load_kind(), &pressure_load_kind(), &spring_load_kind(), &foundation_load_kind()};
    return kinds;
}

const LoadKind* find_load_kind(const std::string& key) {
    for (const LoadKind* k : load_kinds())
        if (key == k->key()) return k;
    return nullptr;
}

void check_load_node(int k, int n, const char* what) {
    if (k < 0 || k >= n) throw StateError(std::string(what) + " out of range");
}

}  // namespace fdem
