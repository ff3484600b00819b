// SettingsRanges_test.cpp — the settings readers' ranges are what works: every numeric setting of
// the volume (store, scheduler, top level) and of the baselines, alone at either end of the range
// its reader accepts, runs a flight at 120 m/s 10^6 m from the origin (the far-flight replay's
// distance) with a CPU capture — no abort, no hang, finite ambience — and the store at its
// smallest finest spacing still numbers points 10^8 m out (the largest replay coordinate). The
// ends are read from the readers' own error messages, so they are the ones enforced. And the
// readers throw nothing but InputError on documents that are not settings at all.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "FakeCubeCapture.h"
#include "lighting/AmbienceVolume.h"
#include "lighting/Baselines.h"
#include "lighting/JsonFields.h"
#include "world/Error.h"

namespace amb {
namespace {

using testing_support::FakeCubeCapture;
using testing_support::FlatProbeEnvironment;

struct Key {
    const char* object;  // "store", "scheduler" or nullptr (top level)
    const char* name;
    bool integer;
};

const Key kVolumeKeys[] = {
    {"store", "coarsestSpacing_m", false},
    {"store", "levels", true},
    {"store", "blendTime_s", false},
    {"store", "allowedSunAngle_rad", false},
    {"store", "minLifetime_s", false},
    {"store", "maxLifetime_s", false},
    {"store", "regenerateFraction", false},
    {"store", "searchCells", true},
    {"store", "reachCells", true},
    {"store", "coarseReachCells", true},
    {"store", "finerWeight", false},
    {"scheduler", "velocityTimeConstant_s", false},
    {"scheduler", "horizon_s", false},
    {"scheduler", "pathStep_s", false},
    {"scheduler", "historyLength_s", false},
    {"scheduler", "roadSnap_m", false},
    {"scheduler", "roadAlignment", false},
    {"scheduler", "corridorCells", false},
    {"scheduler", "maxLevel", true},
    {"scheduler", "finestRingCells", false},
    {"scheduler", "coarseRingCells", false},
    {"scheduler", "maxWiden", true},
    {"scheduler", "minReachSpeed_mps", false},
    {"scheduler", "gapBonus_s", false},
    {"scheduler", "coarseFirst_s", false},
    {"scheduler", "staleBias_s", false},
    {nullptr, "facesPerFrame", true},
    {nullptr, "nominalFrameTime_s", false},
    {nullptr, "defaultTimeRate_hPerS", false},
    {nullptr, "timeJump_h", false},
    {nullptr, "sunThreshold", false},
    {nullptr, "fallbackFaceSize", true},
    {nullptr, "fallbackRefresh_h", false},
    {nullptr, "asideFraction", false},
    {nullptr, "maxAside_m", false},
    {nullptr, "teleportDistance_m", false},
};

const Key kBaselineKeys[] = {
    {nullptr, "facesPerFrame", true},    {nullptr, "sunThreshold", false},
    {nullptr, "maxAside_m", false},      {nullptr, "defaultTimeRate_hPerS", false},
    {nullptr, "timeJump_h", false},      {nullptr, "teleportDistance_m", false},
    {nullptr, "gridSize", true},         {nullptr, "gridSpacing_m", false},
    {nullptr, "hysteresis", false},      {nullptr, "cacheSpacing_m", false},
    {nullptr, "unusedTimeout_s", false}, {nullptr, "objectSize_m", false},
    {nullptr, "objectRange_m", false},   {nullptr, "fallbackFaceSize", true},
    {nullptr, "fallbackRefresh_h", false},
};

// A JSON number that reads back as `v` (infinity as the largest double JSON can hold).
std::string number(double v) {
    if (std::isinf(v)) return v > 0 ? "1.7976931348623157e308" : "-1.7976931348623157e308";
    return nlohmann::json(v).dump();
}

// `v` as the JSON value of key `k` (integers without a fraction).
std::string number(const Key& k, double v) {
    return k.integer ? std::to_string((long long)v) : number(v);
}

std::string document(const Key& k, const std::string& value) {
    const std::string field = "\"" + std::string(k.name) + "\": " + value;
    return k.object ? "{\"" + std::string(k.object) + "\": {" + field + "}}" : "{" + field + "}";
}

template <typename Reader>
bool accepts(const Reader& read, const std::string& doc) {
    try {
        read(doc);
        return true;
    } catch (const InputError&) {
        return false;
    }
}

// The [lo, hi] the reader states when `k` is far out of range (numbers: +-1e300, integers: just
// outside int).
template <typename Reader>
std::pair<double, double> rangeOf(const Reader& read, const Key& k) {
    for (const char* probe : {"1e300", "-1e300", "2147483648", "-2147483649"}) {
        if (k.integer != (probe[1] != 'e' && probe[2] != 'e')) continue;
        try {
            read(document(k, probe));
        } catch (const InputError& e) {
            const std::string what = e.what();
            const std::size_t at = what.find("must be in [");
            if (at == std::string::npos) continue;
            char* end = nullptr;
            const double lo = std::strtod(what.c_str() + at + 12, &end);
            const double hi = std::strtod(end + 1, nullptr);
            return {lo, hi};
        }
    }
    ADD_FAILURE() << k.name << ": no range in the reader's messages";
    return {0.0, 0.0};
}

// The range end `end` (as printed, to 6 significant digits; infinity as the largest double)
// moved towards the inside (`direction` +1 or -1) by relative steps of 1e-9, 1e-8, ... until the
// reader takes it alone; `taken` is false when none is taken (a combined constraint refuses it).
template <typename Reader>
double rangeEnd(const Reader& read, const Key& k, double end, double direction, bool& taken) {
    double v = std::isinf(end) ? std::copysign(1.7976931348623157e308, end) : end;
    if (k.integer) {
        taken = accepts(read, document(k, number(k, v)));
        return v;
    }
    for (double step = 1e-9; step < 1e-1; step *= 10.0) {
        if (accepts(read, document(k, number(k, v)))) {
            taken = true;
            return v;
        }
        v = end + direction * step * std::max(std::fabs(v), 1e-6);
    }
    taken = false;
    return std::isinf(end) ? std::copysign(1.7976931348623157e308, end) : end;
}

bool finite(const ShRgb& sh) {
    for (const auto& c : sh.c)
        for (int ch = 0; ch < 3; ++ch)
            if (!std::isfinite(c[ch])) return false;
    return true;
}

// A 60-frame flight at 120 m/s along x from (x0, 80, z0), looking the ambience up around the
// camera every frame; returns whether every value was finite.
bool fly(AmbienceMethod& method, double x0, double z0) {
    bool ok = true;
    for (int f = 0; f < 60; ++f) {
        const glm::dvec3 camera{x0 + 2.0 * f, 80.0, z0};
        method.predictStage(camera, {120.0, 0.0, 0.0}, 12.0 + f / 3600.0, 1.0 / 60.0);
        method.captureStage();
        method.storeStage();
        const double x[4] = {camera.x, camera.x + 40.0, camera.x - 300.0, camera.x + 7.5};
        const double z[4] = {camera.z, camera.z - 40.0, camera.z + 150.0, camera.z + 1000.0};
        ShRgb out[4];
        method.shAt(4, x, z, out);
        method.noteLookups(4, x, z);
        for (const ShRgb& sh : out) ok &= finite(sh);
    }
    return ok;
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Each volume setting at each end of its range. A setting whose end is refused alone (by a
// combined rule: the finest spacing, or lifetimes min <= max) is flown with the combination that
// makes it valid. (Before: coarsestSpacing_m 0.01 aborted in the store, 0.001 threw OpenVDB's
// "Non-zero scale values required".)
TEST(SettingsRanges, EveryVolumeSettingAtBothEndsFliesFarFromTheOrigin) {
    const auto read = [](const std::string& doc) { return ambienceSettingsFromJson(doc, "r"); };
    const auto t0 = std::chrono::steady_clock::now();
    int flights = 0;
    for (const Key& k : kVolumeKeys) {
        const auto [lo, hi] = rangeOf(read, k);
        ASSERT_LE(lo, hi) << k.name;
        for (const double end : {lo, hi}) {
            bool taken = false;
            const double v = rangeEnd(read, k, end, end == lo ? 1.0 : -1.0, taken);
            std::string doc = document(k, number(k, v));
            if (!taken) {
                const std::string name = k.name;
                if (name == "coarsestSpacing_m") {
                    doc = R"({"store": {"coarsestSpacing_m": )" + number(v) + R"(, "levels": 1}})";
                } else if (name == "minLifetime_s") {
                    doc = R"({"store": {"minLifetime_s": )" + number(v) + R"(, "maxLifetime_s": )" +
                          number(v) + "}}";
                } else if (name == "maxLifetime_s") {
                    doc = R"({"store": {"maxLifetime_s": )" + number(v) + R"(, "minLifetime_s": )" +
                          number(v) + "}}";
                }
            }
            SCOPED_TRACE(doc);
            const AmbienceVolumeSettings s = ambienceSettingsFromJson(doc, "r");
            FakeCubeCapture capture(8);
            FlatProbeEnvironment environment;
            AmbienceVolume volume(capture, environment, s);
            EXPECT_TRUE(fly(volume, 1.0e6, -1.0e6));
            EXPECT_GT(volume.statistics().facesCaptured, 0);
            ++flights;
        }
    }
    EXPECT_EQ(flights, 2 * int(std::size(kVolumeKeys)));
    EXPECT_LT(secondsSince(t0), 300.0);
}

// The finest spacing is bounded so that every replay coordinate has a key: at the limit (4.05 m
// over 5 levels: 0.05 m) a flight 10^8 m out captures and stores anchors; just below it the
// reader refuses, naming the rule.
TEST(SettingsRanges, FinestSpacingLimitReachesTheLargestReplayCoordinate) {
    const AmbienceVolumeSettings s =
        ambienceSettingsFromJson(R"({"store": {"coarsestSpacing_m": 4.05, "levels": 5}})", "r");
    FakeCubeCapture capture(8);
    FlatProbeEnvironment environment;
    AmbienceVolume volume(capture, environment, s);
    EXPECT_TRUE(fly(volume, 1.0e8 - 200.0, -1.0e8 + 50.0));
    EXPECT_GT(volume.store().size(), 0u);
    EXPECT_EQ(volume.statistics().rejectedProbes, 0);
    for (const char* doc :
         {R"({"store": {"coarsestSpacing_m": 4.0, "levels": 5}})",
          R"({"store": {"coarsestSpacing_m": 0.01}})", R"({"store": {"coarsestSpacing_m": 0.001}})",
          R"({"store": {"coarsestSpacing_m": 243, "levels": 8}})"}) {
        try {
            ambienceSettingsFromJson(doc, "r.json");
            if (std::string(doc).find("\"levels\": 8") == std::string::npos)
                ADD_FAILURE() << doc << " accepted";
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_EQ(what.rfind("r.json: 'store'", 0), 0u) << what;
            EXPECT_NE(what.find("coarsestSpacing_m"), std::string::npos) << what;
        }
    }
}

// Each baseline setting at each end of its range, for the three capturing baselines. objectSize_m
// and objectRange_m are bound together (a probe choice scans (2 range / size + 1)^2 objects):
// (Before: objectSize_m 0.001 with the default range hung.)
TEST(SettingsRanges, EveryBaselineSettingAtBothEndsFliesFarFromTheOrigin) {
    const auto read = [](const std::string& doc) { return baselineSettingsFromJson(doc, "r"); };
    const auto t0 = std::chrono::steady_clock::now();
    for (const Key& k : kBaselineKeys) {
        const auto [lo, hi] = rangeOf(read, k);
        ASSERT_LE(lo, hi) << k.name;
        for (const double end : {lo, hi}) {
            bool taken = false;
            const double v = rangeEnd(read, k, end, end == lo ? 1.0 : -1.0, taken);
            std::string doc = document(k, number(k, v));
            if (!taken) {
                const std::string name = k.name;
                if (name == "objectSize_m") {
                    doc = "{\"objectSize_m\": " + number(v) +
                          ", \"objectRange_m\": " + number(64.0 * v) + "}";
                } else if (name == "objectRange_m") {
                    doc = "{\"objectRange_m\": " + number(v) +
                          ", \"objectSize_m\": " + number(v / 64.0) + "}";
                }
            }
            SCOPED_TRACE(doc);
            const BaselineSettings s = baselineSettingsFromJson(doc, "r");
            for (const char* method : {"grid", "reactive", "object"}) {
                SCOPED_TRACE(method);
                FakeCubeCapture capture(8);
                FlatProbeEnvironment environment;
                const auto m = makeCapturingMethod(method, capture, environment, {}, s, nullptr);
                EXPECT_TRUE(fly(*m, 1.0e6, 1.0e6));
                // (The reactive cache with a 1 ms timeout, or objects out of range, rightly
                // capture nothing; the grid always does.)
                if (std::string(method) == "grid") {
                    EXPECT_GT(m->methodStatistics().facesCaptured, 0);
                }
            }
        }
    }
    EXPECT_LT(secondsSince(t0), 300.0);
    for (const char* doc : {R"({"objectSize_m": 0.001})", R"({"objectRange_m": 1e6})"}) {
        try {
            baselineSettingsFromJson(doc, "b.json");
            ADD_FAILURE() << doc << " accepted";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("objectRange_m"), std::string::npos) << e.what();
        }
    }
}

// Documents that are not settings (syntax errors, wrong types, numbers beyond double, integers
// beyond long long, deep nesting, bytes that are not UTF-8): InputError naming the file, and
// nothing else, from both readers.
TEST(SettingsRanges, NastyDocumentsGiveOnlyInputError) {
    const std::vector<std::string> docs = {
        "",
        " ",
        "null",
        "0",
        "\"settings\"",
        "[]",
        "{",
        "}",
        "{\"a\" 1}",
        "{}}",
        "\xff\xfe{}",
        "{\"facesPerFrame\": \"\xc3\x28\"}",
        "{\"store\": 1}",
        "{\"store\": []}",
        "{\"store\": null}",
        "{\"scheduler\": \"x\"}",
        "{\"facesPerFrame\": 18446744073709551615}",
        "{\"facesPerFrame\": 9223372036854775808}",
        "{\"facesPerFrame\": -9223372036854775809}",
        "{\"facesPerFrame\": 1e400}",
        "{\"facesPerFrame\": 2.5}",
        "{\"facesPerFrame\": true}",
        "{\"facesPerFrame\": [1]}",
        "{\"sunThreshold\": -1e-320}",
        "{\"sunThreshold\": 1e999}",
        "{\"sunThreshold\": NaN}",
        "{\"sunThreshold\": Infinity}",
        "{\"maxAside_m\": -0.0001}",
        "{\"unknown\": 1}",
        "{\"maxAside_m\": {}}",
        std::string(100000, '[') + std::string(100000, ']'),
        std::string(50000, '{'),
        "{\"store\": {\"levels\": 340282366920938463463374607431768211456}}",
    };
    for (const std::string& doc : docs) {
        SCOPED_TRACE(doc.substr(0, 80));
        for (int reader = 0; reader < 2; ++reader) {
            try {
                if (reader == 0)
                    ambienceSettingsFromJson(doc, "nasty.json");
                else
                    baselineSettingsFromJson(doc, "nasty.json");
                // Only documents without a key the reader knows can be accepted: none here.
                ADD_FAILURE() << "accepted by reader " << reader;
            } catch (const InputError& e) {
                EXPECT_EQ(std::string(e.what()).rfind("nasty.json: ", 0), 0u) << e.what();
            }
        }
    }
}

// JsonFields::integer: an unsigned value above LLONG_MAX is out of range, not wrapped to a
// negative number that a range with negatives would take (18446744073709551615 used to read as
// -1).
TEST(SettingsRanges, HugeUnsignedIntegersAreOutOfRangeNotWrapped) {
    const nlohmann::json doc = nlohmann::json::parse(R"({"k": 18446744073709551615})");
    JsonFields fields(doc, "w");
    int value = 7;
    try {
        fields.integer("k", value, -5, 5);
        ADD_FAILURE() << "accepted as " << value;
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("'k' must be in [-5, 5]"), std::string::npos)
            << e.what();
    }
    EXPECT_EQ(value, 7);
}

}  // namespace
}  // namespace amb
