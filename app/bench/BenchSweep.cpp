// BenchSweep.cpp — the sweep file of `ambience bench` (see BenchSweep.h).
#include "app/bench/BenchSweep.h"

#include <algorithm>
#include <cstdint>

#include "lighting/AmbienceMethod.h"
#include "world/Error.h"
#include "world/JsonText.h"
#include "world/TextFile.h"

namespace amb {

namespace {

using nlohmann::json;

void checkMethod(const std::string& name, const std::vector<std::string>& methodNames,
                 const std::string& where) {
    if (std::find(methodNames.begin(), methodNames.end(), name) != methodNames.end()) return;
    std::string list;
    for (const auto& n : methodNames) list += (list.empty() ? "" : ", ") + n;
    throw InputError(where, "unknown ambience method '" + name + "' (expected one of " + list + ")");
}

SweepPoint parsePoint(const json& p, const std::string& where,
                      const std::vector<std::string>& methodNames) {
    if (!p.is_object()) throw InputError(where, "expected an object");
    SweepPoint point;
    for (auto it = p.begin(); it != p.end(); ++it) {
        const std::string& key = it.key();
        if (key == "label" && it->is_string()) {
            point.label = it->get<std::string>();
        } else if (key == "methods" && it->is_array()) {
            for (const auto& m : *it) {
                if (!m.is_string()) throw InputError(where, "methods: expected names");
                checkMethod(m.get<std::string>(), methodNames, where + ": methods");
                point.methods.insert(m.get<std::string>());
            }
        } else if (key == "volume" && it->is_object()) {
            point.volume = *it;
        } else if (key == "baseline" && it->is_object()) {
            point.baseline = *it;
        } else if (key == "facesPerFrame" && it->is_number_integer()) {
            // Range-check at full width before narrowing, so 4294967297 does not become 1.
            const std::uint64_t u = it->is_number_unsigned() ? it->get<std::uint64_t>() : 0;
            const std::int64_t n =
                it->is_number_unsigned()
                    ? (u > std::uint64_t(kMaxFacesPerFrame) ? kMaxFacesPerFrame + 1 : std::int64_t(u))
                    : it->get<std::int64_t>();
            if (n < 1 || n > kMaxFacesPerFrame)
                throw InputError(where, "facesPerFrame: expected 1 to " +
                                            std::to_string(kMaxFacesPerFrame));
            point.facesPerFrame = int(n);
        } else {
            throw InputError(where, "unknown key or wrong type: '" + key +
                                        "' (label, methods, volume, baseline, facesPerFrame)");
        }
    }
    // A label names run folders and goes into the emitted command lines (one line each).
    bool control = false;
    for (const char c : point.label) control |= static_cast<unsigned char>(c) < 0x20 || c == 0x7f;
    if (point.label.empty() || point.label.size() > kMaxSweepLabelBytes ||
        point.label.find_first_of("/ _,;") != std::string::npos || control)
        throw InputError(where, "label: a short name (at most " +
                                    std::to_string(kMaxSweepLabelBytes) +
                                    " bytes) without '/', ' ', '_', ',', ';' or a control "
                                    "character");
    return point;
}

}  // namespace

std::vector<SweepPoint> parseSweep(const std::string& text, const std::string& where,
                                   const std::vector<std::string>& methodNames) {
    std::vector<SweepPoint> points(1);  // the default point always runs
    json j;
    try {
        j = parseJsonText(text, where, kMaxSweepJsonDepth);
    } catch (const json::exception& e) {
        throw InputError(where, std::string("malformed JSON: ") + e.what());
    }
    if (!j.is_object() || !j.contains("points") || !j["points"].is_array())
        throw InputError(where, "expected {\"points\": [ {\"label\": ..., ...}, ... ]}");
    std::set<std::string> labels{"default"};
    const json& list = j["points"];
    for (std::size_t i = 0; i < list.size(); ++i) {
        const std::string pointWhere = where + ": points[" + std::to_string(i) + "]";
        SweepPoint point = parsePoint(list[i], pointWhere, methodNames);
        if (!labels.insert(point.label).second)
            throw InputError(pointWhere, "label '" + point.label + "' is used twice");
        points.push_back(std::move(point));
    }
    return points;
}

std::vector<int> parseBudgets(const std::string& list, const std::string& where) {
    std::vector<int> budgets;
    std::size_t start = 0;
    while (start <= list.size()) {
        const std::size_t end = std::min(list.find(',', start), list.size());
        const std::string item = list.substr(start, end - start);
        std::size_t used = 0;
        long n = 0;
        try {
            n = std::stol(item, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (item.empty() || used != item.size() || n < 1 || n > kMaxFacesPerFrame)
            throw InputError(where, "'" + item + "': expected faces per frame, 1 to " +
                                        std::to_string(kMaxFacesPerFrame));
        budgets.push_back(int(n));
        if (budgets.size() > 16) throw InputError(where, "at most 16 budgets");
        start = end + 1;
    }
    std::sort(budgets.begin(), budgets.end());
    budgets.erase(std::unique(budgets.begin(), budgets.end()), budgets.end());
    return budgets;
}

std::vector<SweepPoint> withBudgets(const std::vector<SweepPoint>& points,
                                    const std::vector<int>& budgets, const std::string& where) {
    std::vector<SweepPoint> out;
    std::set<std::string> labels;
    for (const SweepPoint& p : points) {
        for (int b : budgets) {
            SweepPoint q = p;
            q.family = p.family.empty() ? p.label : p.family;
            q.facesPerFrame = b;
            if (b != 1) q.label = p.label + "-f" + std::to_string(b);
            if (!labels.insert(q.label).second)
                throw InputError(where, "label '" + q.label + "' would be used twice");
            out.push_back(std::move(q));
        }
    }
    return out;
}

std::vector<SweepPoint> readSweep(const std::string& path,
                                  const std::vector<std::string>& methodNames, Links links) {
    if (path.empty()) return std::vector<SweepPoint>(1);
    return parseSweep(readTextFile(path, "sweep file", kMaxSettingsFileBytes, links), path,
                      methodNames);
}

}  // namespace amb
