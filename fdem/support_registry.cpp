// fdem/support_registry.cpp: the registered support kinds (fdem/support.hpp). A new kind: its file defines
// `const SupportKind& NAME_support_kind()` (and a DofMode of its own in fdem/case.hpp); declare it here and add it to
// the list.
#include "fdem/support.hpp"

namespace fdem {

const SupportKind& fixed_support_kind();     // fdem/support_fixed.cpp
const SupportKind& free_support_kind();      // fdem/support_free.cpp
const SupportKind& rigid_support_kind();     // fdem/support_rigid.cpp
const SupportKind& body_support_kind();      // fdem/support_body.cpp
const SupportKind& velocity_support_kind();  // fdem/support_velocity.cpp
const SupportKind& protocol_support_kind();  // fdem/support_protocol.cpp

// (the order in which a block's keys are read, and so its errors reported)
const std::vector<const SupportKind*>& support_kinds() {
    static const std::vector<const SupportKind*> kinds{&fixed_support_kind(), &free_support_kind(), &rigid_support_kind(),
                                                       &velocity_support_kind(), &protocol_support_kind(),
                                                       &body_support_kind()};
    return kinds;
}

const SupportKind* find_support_kind(DofMode mode) {
    for (const SupportKind* k : support_kinds())
        if (k->mode() == mode) return k;
    return nullptr;
}

const SupportKind* find_support_kind(const std::string& key) {
    for (const SupportKind* k : support_kinds())
        if (key == k->key()) return k;
    return nullptr;
}

}  // namespace fdem
