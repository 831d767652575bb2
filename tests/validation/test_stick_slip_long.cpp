// tests/validation/test_stick_slip_long.cpp: long-horizon stick-slip near the friction limit (issue "Contact that is
// right wherever it is loaded", item 3): 20 s of F = 1.02 mu m g cos(t) on a rigid-group block, the force history
// given three ways (a sin time function, a table, 40 stages of 0.5 s each with its own table); every stop within 1 %
// of the exact whole slide whatever the form, books within 1 %. The scene and the closed form:
// tests/contact/near_limit_run.hpp. About 5.3 million steps per form (3 x 2-3 minutes on one core).
#include <catch2/catch.hpp>

#include <cmath>

#include "contact/near_limit_run.hpp"

TEST_CASE("stick-slip near the friction limit for 20 s: every stop within 1 % of the exact slide, whether the force "
          "is a sin function, a table or 40 stages",
          "[engine][regression]") {
    using contact_test::ForceForm;
    for (ForceForm form : {ForceForm::sin, ForceForm::table, ForceForm::stages}) {
        INFO("form " << static_cast<int>(form));
        const contact_test::NearLimitResult r = contact_test::run_near_limit(20.0, 0.0, form);
        REQUIRE(r.exact.size() == 7);
        REQUIRE(r.stops.size() == r.exact.size());
        for (std::size_t i = 0; i < r.exact.size(); ++i) CHECK(std::fabs(r.stops[i].x - r.exact[i].x) < 0.01 * r.amplitude);
        CHECK(std::fabs(r.books) < 0.01);
    }
}
