// Seeded mutation fuzzer over the shipped cases (issue 26): one numeric value of a case file is replaced by an
// extreme, denormal, negative, non-finite or non-numeric value, and `fdem check` must answer with exit code 0 or 1
// (never a crash, abort or hang), every exit 1 naming the file, within 30 s per input. FDEM_FUZZ_N inputs (default
// 60, about 30 s on 1 core); the validation-labelled copy in tests/validation runs more.
#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <random>
#include <regex>
#include <string>
#include <vector>

#include "engine_helpers.hpp"

namespace {

int fuzz_inputs(int fallback) {
    const char* n = std::getenv("FDEM_FUZZ_N");
    return n ? std::atoi(n) : fallback;
}

}  // namespace

TEST_CASE("mutated shipped cases give fdem check exit code 0 or 1 naming the file", "[engine]") {
    const int n = fuzz_inputs(60);
    const auto dir = testing::tmp_dir("fuzz_" + std::to_string(n));
    const std::vector<std::string> cases = {"elastic/cantilever.toml", "tilting/tilting_wall.toml",
                                            "vermeltfoort/vermeltfoort_121.toml", "lourenco2005/k25_N30.toml",
                                            "settlement/bui2017_settlement.toml"};
    const std::vector<std::string> values = {"0", "-1", "5e-324", "1e-300", "1e-12", "1e300", "1.7976931348623157e308",
                                             "-1e308", "nan", "inf", "-inf", "\"text\"", "[]", "1e20", "1e10", "1e6"};
    std::mt19937 rng(26);
    const std::regex numeric_line(R"(^(\s*[A-Za-z_][A-Za-z0-9_]*\s*=\s*)(-?[0-9][0-9.eE+\-_]*)(.*)$)");
    int codes[4] = {0, 0, 0, 0};
    for (int i = 0; i < n; ++i) {
        const std::string name = cases[rng() % cases.size()];
        const std::string text = testing::read_text(std::filesystem::path(FDEM_CASES_DIR) / name);
        std::vector<std::string> lines;
        std::vector<std::size_t> numeric;
        std::size_t pos = 0;
        while (pos < text.size()) {
            const auto e = text.find('\n', pos);
            lines.push_back(text.substr(pos, e == std::string::npos ? std::string::npos : e - pos));
            if (std::regex_match(lines.back(), numeric_line)) numeric.push_back(lines.size() - 1);
            pos = e == std::string::npos ? text.size() : e + 1;
        }
        REQUIRE(!numeric.empty());
        const std::size_t li = numeric[rng() % numeric.size()];
        const std::string value = values[rng() % values.size()];
        const std::string mutated_line = std::regex_replace(lines[li], numeric_line, "$1" + value + "$3");
        std::string out;
        for (std::size_t k = 0; k < lines.size(); ++k) out += (k == li ? mutated_line : lines[k]) + "\n";
        const std::string file = "fuzz_" + std::to_string(i) + ".toml";
        testing::write_text(dir / file, out);
        // At most 30 s per input: `timeout` exits 124 and fails the input, as does a signal (code -1) or exit 2/3.
        testing::CliResult r;
        {
            const auto o = dir / "stdout.txt", e = dir / "stderr.txt";
            const std::string cmd = std::string("timeout 30 \"") + FDEM_BIN + "\" check \"" + (dir / file).string() + "\" >\"" +
                                    o.string() + "\" 2>\"" + e.string() + "\"";
            const int status = std::system(cmd.c_str());
            r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
            r.err = testing::read_text(e);
        }
        INFO("input " << i << " from " << name << " line " << li + 1 << ": " << mutated_line << " -> exit " << r.code << ": " << r.err);
        CHECK((r.code == 0 || r.code == 1));
        if (r.code == 1) CHECK(r.err.find(file) != std::string::npos);
        if (r.code >= 0 && r.code <= 3) ++codes[r.code];
    }
    WARN("fuzz: " << n << " inputs, exit 0: " << codes[0] << ", exit 1: " << codes[1] << ", exit 2: " << codes[2]
                  << ", exit 3: " << codes[3]);
}
