// fdem/support_fixed.cpp: support kind `fixed` (fix = "x" | "y" | "xy" in a [[stages.supports]] block): the group's
// DOFs in the component are held (velocity 0); the node loop books their reactions.
#include "fdem/case_reader.hpp"
#include "fdem/support.hpp"

namespace fdem {

namespace {

class FixedSupport final : public Support {
public:
    using Support::Support;
    std::uint8_t dof_kind() const override { return 1; }
    void save(StateWriter& w) const override { const_cast<FixedSupport*>(this)->io_common(w, 0); }
    void load(StateReader& r, int nn) override { io_common(r, nn); }
};

class FixedKind final : public SupportKind {
public:
    const char* key() const override { return "fixed"; }
    DofMode mode() const override { return DofMode::fixed; }
    void read(case_detail::Ctx& ctx, case_detail::Reader& r, SupportSpec& s) const override {
        case_detail::read_dof_set(ctx, r, "fix", DofMode::fixed, s);
    }
    std::unique_ptr<Support> begin(const SupportSpec&, int, const SupportStart&) const override {
        return std::make_unique<FixedSupport>(*this);
    }
    std::unique_ptr<Support> restore() const override { return std::make_unique<FixedSupport>(*this); }
};

}  // namespace

const SupportKind& fixed_support_kind() {
    static const FixedKind kind;
    return kind;
}

}  // namespace fdem
