// BenchSweep.h — the parameter points of `ambience bench --sweep FILE.json` (no GL, so the
// parser can be tested and fuzzed on its own).
//
//   {"points": [{"label": "b1", "methods": ["volume"], "volume": {...}, "baseline": {...},
//                "facesPerFrame": 2}, ...]}
#pragma once

#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace amb {

// A parameter point: settings files handed to `run`, and the methods it applies to.
struct SweepPoint {
    std::string label = "default";
    std::set<std::string> methods;  // empty: every method
    nlohmann::json volume = nlohmann::json::object(), baseline = nlohmann::json::object();
    int facesPerFrame = 1;
    std::string params;  // "key=value;..." for the CSV
};

// Deepest nesting of objects and arrays a sweep file may have: the settings are two levels
// deep, and a limit keeps a hostile file from exhausting the stack when a point is copied or
// flattened (both recurse).
constexpr int kMaxSweepJsonDepth = 32;

// The points of a sweep file's text, after the default point (always first). `methodNames` are
// the names "methods" may list. Throws InputError(where, ...) for malformed JSON, unknown keys,
// wrong types, a bad label, a method not in `methodNames`, facesPerFrame outside 1-64, or
// nesting deeper than kMaxSweepJsonDepth.
std::vector<SweepPoint> parseSweep(const std::string& text, const std::string& where,
                                   const std::vector<std::string>& methodNames);

// Reads and parses a sweep file (bounded read); an empty path gives the default point alone.
std::vector<SweepPoint> readSweep(const std::string& path,
                                  const std::vector<std::string>& methodNames);

}  // namespace amb
