// CliChecks.h — CLI11 validators shared by the subcommands. CLI11's Range lets NaN through
// (every comparison with NaN is false), so numeric options use FiniteRange instead. Also the
// items of a comma-separated option (splitList).
#pragma once

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace amb {

// A number that is finite and within [lo, hi].
class FiniteRange : public CLI::Validator {
public:
    FiniteRange(double lo, double hi) {
        std::ostringstream d;
        d << "FINITE in [" << lo << " - " << hi << "]";
        description(d.str());
        func_ = [lo, hi](std::string& text) -> std::string {
            double v = 0.0;
            if (!CLI::detail::lexical_cast(text, v)) return "not a number: " + text;
            if (!std::isfinite(v)) return "not a finite number: " + text;
            if (v < lo || v > hi) {
                std::ostringstream s;
                s << "value " << text << " not in range [" << lo << ", " << hi << "]";
                return s.str();
            }
            return {};
        };
    }
};

// A world seed: a whole number in [0, 2^64 - 1]. CLI11 would otherwise wrap "-1" to 2^64 - 1.
class SeedValidator : public CLI::Validator {
public:
    SeedValidator() {
        description("INTEGER in [0 - 18446744073709551615]");
        func_ = [](std::string& text) -> std::string {
            if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos)
                return "a seed is a whole number >= 0, got '" + text + "'";
            if (text.size() > 20 || (text.size() == 20 && text > "18446744073709551615"))
                return "a seed is at most 18446744073709551615, got '" + text + "'";
            return {};
        };
    }
};

// The items of a comma-separated list ("a, b,,c" -> a, b, c): blanks around each trimmed,
// empty ones dropped.
inline std::vector<std::string> splitList(const std::string& text) {
    std::vector<std::string> out;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
        item.erase(0, item.find_first_not_of(" \t"));
        item.erase(item.find_last_not_of(" \t") + 1);
        if (!item.empty()) out.push_back(item);
    }
    return out;
}

}  // namespace amb
