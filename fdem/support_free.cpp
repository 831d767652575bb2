// fdem/support_free.cpp: support kind `free` (free = "x" | "y" | "xy" in a [[stages.supports]] block): the group's
// DOFs in the component are released from the support they had; no active support (the node loop integrates them).
#include "fdem/case_reader.hpp"
#include "fdem/support.hpp"

namespace fdem {

namespace {

class FreeKind final : public SupportKind {
public:
    const char* key() const override { return "free"; }
    DofMode mode() const override { return DofMode::free; }
    void read(case_detail::Ctx& ctx, case_detail::Reader& r, SupportSpec& s) const override {
        case_detail::read_dof_set(ctx, r, "free", DofMode::free, s);
    }
    std::unique_ptr<Support> begin(const SupportSpec&, int, const SupportStart&) const override { return nullptr; }
    std::unique_ptr<Support> restore() const override { return nullptr; }
};

}  // namespace

const SupportKind& free_support_kind() {
    static const FreeKind kind;
    return kind;
}

}  // namespace fdem
