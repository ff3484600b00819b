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

#include "world/TextFile.h"

namespace amb {

// A parameter point: settings files handed to `run`, and the methods it applies to.
struct SweepPoint {
    std::string label = "default";
    std::set<std::string> methods;  // empty: every method
    nlohmann::json volume = nlohmann::json::object(), baseline = nlohmann::json::object();
    int facesPerFrame = 1;
    std::string params;  // "key=value;..." for the CSV
    std::string family;  // the label before --budgets added "-f<faces>" (empty: the label)
};

// Deepest nesting of objects and arrays a sweep file may have: the settings are two levels
// deep, and a limit keeps a hostile file from exhausting the stack when a point is copied or
// flattened (both recurse).
constexpr int kMaxSweepJsonDepth = 32;
// Longest label (it becomes part of a run folder's name).
constexpr std::size_t kMaxSweepLabelBytes = 64;

// The points of a sweep file's text, after the default point (always first). `methodNames` are
// the names "methods" may list. Throws InputError(where, ...) for malformed JSON, unknown keys,
// wrong types, a bad label, a method not in `methodNames`, facesPerFrame outside 1-64, or
// nesting deeper than kMaxSweepJsonDepth.
std::vector<SweepPoint> parseSweep(const std::string& text, const std::string& where,
                                   const std::vector<std::string>& methodNames);

// Reads and parses a sweep file (bounded read, world/TextFile.h; `links` Refuse for the copy in
// a folder --emit wrote); an empty path gives the default point alone.
std::vector<SweepPoint> readSweep(const std::string& path,
                                  const std::vector<std::string>& methodNames,
                                  Links links = Links::Follow);

// The capture budgets of `ambience bench --budgets 1,3,6`: faces per frame, each 1 to
// kMaxFacesPerFrame, sorted, without repeats. Throws InputError(where, ...) for an empty list,
// a value that is not a whole number in range, or more than 16 budgets.
std::vector<int> parseBudgets(const std::string& list, const std::string& where);

// Every point at every budget: budget 1 keeps the point's label, budget b > 1 is labelled
// "<label>-f<b>"; `family` keeps the point's own label. A budget overrides the point's own
// facesPerFrame. Throws InputError(where, ...) when two points end with the same label.
std::vector<SweepPoint> withBudgets(const std::vector<SweepPoint>& points,
                                    const std::vector<int>& budgets, const std::string& where);

}  // namespace amb
