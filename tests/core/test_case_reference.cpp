// The case file reference (cases/REFERENCE.md) and the case reader stay in step: every key the reader asks for
// while loading a shipped case (cases/**/*.toml, tests/fracture/cases, tools/tests/data) must have an entry there.
// Keys that no shipped case uses are checked by the source scan of tools/tests/test_case_reference.py.
#include <catch2/catch.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "fdem/case.hpp"

namespace {

namespace fs = std::filesystem;

// The documented key paths: every `code span` of a heading is a table path that the rows below it belong to (none:
// the top level); a table row whose first cell is a `code span` documents that key in each of those tables. The
// same rule as tools/tests/test_case_reference.py.
std::vector<std::string> code_spans(const std::string& s) {
    std::vector<std::string> out;
    for (std::size_t a = s.find('`'); a != std::string::npos; a = s.find('`', a)) {
        const auto b = s.find('`', a + 1);
        if (b == std::string::npos) break;
        out.push_back(s.substr(a + 1, b - a - 1));
        a = b + 1;
    }
    return out;
}

std::set<std::string> documented_keys(const fs::path& reference) {
    std::ifstream in(reference);
    REQUIRE(in.good());
    std::set<std::string> keys;
    std::vector<std::string> prefixes{""};
    std::string line;
    while (std::getline(in, line)) {
        if (line.rfind("#", 0) == 0) {
            prefixes = code_spans(line);
            if (prefixes.empty()) prefixes.push_back("");
        } else if (line.rfind("| `", 0) == 0) {
            const std::string key = code_spans(line).front();
            for (const auto& p : prefixes) keys.insert(p.empty() ? key : p + "." + key);
        }
    }
    return keys;
}

std::vector<fs::path> shipped_cases() {
    const fs::path cases = FDEM_CASES_DIR;
    const fs::path root = cases.parent_path();
    std::vector<fs::path> out;
    for (const auto& dir : {cases, root / "tests" / "fracture" / "cases", root / "tools" / "tests" / "data"}) {
        if (!fs::exists(dir)) continue;
        for (const auto& e : fs::recursive_directory_iterator(dir))
            if (e.is_regular_file() && e.path().extension() == ".toml") out.push_back(e.path());
    }
    std::sort(out.begin(), out.end());
    return out;
}

}  // namespace

TEST_CASE("every key the case reader reads in a shipped case is in cases/REFERENCE.md", "[unit]") {
    const auto documented = documented_keys(fs::path(FDEM_CASES_DIR) / "REFERENCE.md");
    REQUIRE(documented.size() > 100);
    const auto files = shipped_cases();
    REQUIRE(files.size() > 30);
    std::set<std::string> missing;
    for (const auto& f : files) {
        INFO(f.string());
        std::vector<std::string> keys_read;
        fdem::load_case(f.string(), {}, &keys_read);
        REQUIRE(!keys_read.empty());
        for (const auto& k : keys_read)
            if (!documented.count(k)) missing.insert(k + " (read in " + f.filename().string() + ")");
    }
    std::string list;
    for (const auto& m : missing) list += "\n  " + m;
    INFO("keys read but not documented in cases/REFERENCE.md:" << list);
    CHECK(missing.empty());
}

TEST_CASE("the case reader reports keys in the reference's notation", "[unit]") {
    const fs::path cases = FDEM_CASES_DIR;
    std::vector<std::string> keys_read;
    fdem::load_case((cases / "lourenco2005" / "k25_N100_quick.toml").string(), {}, &keys_read);
    const std::set<std::string> keys(keys_read.begin(), keys_read.end());
    CHECK(keys.count("case.thickness"));
    CHECK(keys.count("materials.NAME.E"));
    CHECK(keys.count("materials.NAME.fracture.GI"));
    CHECK(keys.count("stages[].supports[].group"));
    CHECK(keys.count("stages[].until.monitor"));
    CHECK(keys.count("geometry.mesh_size"));
}
