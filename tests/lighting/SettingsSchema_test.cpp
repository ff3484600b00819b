// SettingsSchema_test.cpp — the settings schema (lighting/SettingsSchema.h) against what is built
// on it: each reader takes every key with exactly the schema's range (its ends taken, the next
// doubles or integers beyond them refused with a message naming the key and the range), the
// writer's file reads back equal, equality and AmbienceVolume::retunable see every key (and only
// the rebuilding ones stop a retune), `KEY=VALUE` assignments go through the same checks, and
// the files the project ships still read.
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "lighting/AmbienceVolume.h"
#include "lighting/Baselines.h"
#include "lighting/JsonFields.h"
#include "lighting/SettingsSchema.h"
#include "world/Error.h"

namespace amb {
namespace {

using Kind = SettingSpec::Kind;

// The settings file holding `key` (a path, "store.levels") with the JSON value `value`, alone.
std::string document(const std::string& key, const nlohmann::json& value) {
    nlohmann::json root = nlohmann::json::object();
    nlohmann::json* at = &root;
    std::size_t start = 0;
    for (std::size_t dot; (dot = key.find('.', start)) != std::string::npos; start = dot + 1)
        at = &(*at)[key.substr(start, dot - start)];
    (*at)[key.substr(start)] = value;
    return root.dump();
}

std::string leaf(const std::string& key) {
    return key.substr(key.rfind('.') + 1);
}

// What the reader says about `doc`: "" when it takes it.
template <typename S>
std::string refusal(const SettingsSchema<S>& schema, const std::string& doc) {
    try {
        schema.read(doc, "t.json");
        return "";
    } catch (const InputError& e) {
        return e.what();
    }
}

// Each key: its ends are taken (or refused only by a check that binds keys together, never for
// the range or the type), and the first value beyond each end is refused naming the key and
// exactly the schema's range.
template <typename S>
void expectReaderTakesExactlyTheRanges(const SettingsSchema<S>& schema) {
    for (const auto& f : schema.fields()) {
        SCOPED_TRACE(f.key);
        if (f.kind == Kind::Boolean) {
            EXPECT_EQ(refusal(schema, document(f.key, true)), "");
            EXPECT_EQ(refusal(schema, document(f.key, false)), "");
            EXPECT_NE(refusal(schema, document(f.key, 1))
                          .find("'" + leaf(f.key) + "' must be true or false"),
                      std::string::npos);
            continue;
        }
        const std::string range =
            "'" + leaf(f.key) + "' must be in [" + jsonNumber(f.lo) + ", " + jsonNumber(f.hi) + "]";
        ASSERT_TRUE(std::isfinite(f.lo) && std::isfinite(f.hi) && f.lo < f.hi);
        for (const double end : {f.lo, f.hi}) {
            const nlohmann::json v =
                f.kind == Kind::Integer ? nlohmann::json((long long)end) : nlohmann::json(end);
            const std::string said = refusal(schema, document(f.key, v));
            EXPECT_EQ(said.find("must be"), std::string::npos) << said;
        }
        nlohmann::json below, above;
        if (f.kind == Kind::Integer) {
            below = (long long)f.lo - 1;
            above = (long long)f.hi + 1;
            // An integer key refuses a fraction within its range.
            EXPECT_NE(refusal(schema, document(f.key, (f.lo + f.hi) / 2.0 + 0.5))
                          .find("'" + leaf(f.key) + "' must be an integer"),
                      std::string::npos);
        } else {
            below = std::nextafter(f.lo, -std::numeric_limits<double>::infinity());
            above = std::nextafter(f.hi, std::numeric_limits<double>::infinity());
        }
        for (const nlohmann::json& v : {below, above}) {
            const std::string said = refusal(schema, document(f.key, v));
            EXPECT_NE(said.find(range), std::string::npos) << v.dump() << ": " << said;
            EXPECT_EQ(said.rfind("t.json", 0), 0u) << said;
        }
    }
}

TEST(SettingsSchema, TheVolumeReaderTakesExactlyTheSchemasRanges) {
    expectReaderTakesExactlyTheRanges(volumeSettingsSchema());
}

TEST(SettingsSchema, TheBaselineReaderTakesExactlyTheSchemasRanges) {
    expectReaderTakesExactlyTheRanges(baselineSettingsSchema());
}

TEST(SettingsSchema, KeysAreUniqueAndTheCaptureKeysAreShared) {
    const auto unique = [](const auto& fields) {
        for (std::size_t i = 0; i < fields.size(); ++i)
            for (std::size_t j = i + 1; j < fields.size(); ++j)
                EXPECT_NE(fields[i].key, fields[j].key);
    };
    unique(volumeSettingsSchema().fields());
    unique(baselineSettingsSchema().fields());
    // The keys every capturing method shares are the same key, with the same range, in both.
    int shared = 0;
    for (const auto& b : baselineSettingsSchema().fields()) {
        const auto* v = volumeSettingsSchema().find(b.key);
        if (!v) continue;
        ++shared;
        EXPECT_EQ(v->lo, b.lo) << b.key;
        EXPECT_EQ(v->hi, b.hi) << b.key;
        EXPECT_EQ(v->kind, b.kind) << b.key;
    }
    EXPECT_EQ(shared, 8 + 17);  // CaptureSettings' eight and the near field's seventeen
    // The files' defaults lie in their ranges.
    const AmbienceVolumeSettings v;
    for (const auto& f : volumeSettingsSchema().fields()) {
        const double x = volumeSettingsSchema().value(v, f);
        EXPECT_TRUE(x >= f.lo && x <= f.hi) << f.key << " " << x;
    }
    const BaselineSettings b;
    for (const auto& f : baselineSettingsSchema().fields()) {
        const double x = baselineSettingsSchema().value(b, f);
        EXPECT_TRUE(x >= f.lo && x <= f.hi) << f.key << " " << x;
    }
}

// Every key moved alone, to a value inside its range away from the default (switches flipped).
template <typename S>
std::vector<S> eachKeyMoved(const SettingsSchema<S>& schema) {
    std::vector<S> out;
    for (const auto& f : schema.fields()) {
        S s;
        const double x = schema.value(s, f);
        double y = f.kind == Kind::Boolean ? 1.0 - x : (x < f.hi ? std::min(f.hi, x + 1.0) : f.lo);
        if (f.kind == Kind::Number && x < f.hi && x + 1.0 > f.hi) y = (x + f.hi) / 2.0;
        schema.setValue(s, f, y);
        out.push_back(s);
    }
    return out;
}

TEST(SettingsSchema, EqualityAndRetuneSeeEveryKey) {
    const auto& schema = volumeSettingsSchema();
    const AmbienceVolumeSettings defaults;
    const std::vector<AmbienceVolumeSettings> moved = eachKeyMoved(schema);
    ASSERT_EQ(moved.size(), schema.fields().size());
    for (std::size_t i = 0; i < moved.size(); ++i) {
        const auto& f = schema.fields()[i];
        SCOPED_TRACE(f.key);
        EXPECT_FALSE(schema.equal(defaults, moved[i]));
        EXPECT_TRUE(schema.equal(moved[i], moved[i]));
        // AmbienceVolume::retunable is the schema's: only a key that rebuilds stops a retune.
        EXPECT_EQ(AmbienceVolume::retunable(defaults, moved[i]), !f.rebuilds);
        const std::string key = f.key;
        const bool builtWith = key == "store.coarsestSpacing_m" || key == "store.levels" ||
                               key == "sunThreshold" || key.rfind("nearField.", 0) == 0;
        EXPECT_EQ(f.rebuilds, builtWith);
    }
    const std::vector<BaselineSettings> movedB = eachKeyMoved(baselineSettingsSchema());
    for (const BaselineSettings& b : movedB)
        EXPECT_FALSE(baselineSettingsSchema().equal(BaselineSettings{}, b));
}

TEST(SettingsSchema, WhatTheWriterWritesReadsBackEqual) {
    for (const AmbienceVolumeSettings& s : eachKeyMoved(volumeSettingsSchema())) {
        const std::string text = volumeSettingsSchema().write(s);
        EXPECT_TRUE(volumeSettingsSchema().equal(ambienceSettingsFromJson(text, "w"), s)) << text;
    }
    for (const BaselineSettings& s : eachKeyMoved(baselineSettingsSchema())) {
        const std::string text = baselineSettingsSchema().write(s);
        EXPECT_TRUE(baselineSettingsSchema().equal(baselineSettingsFromJson(text, "w"), s)) << text;
    }
    // Nested as the file has always been: the store's, the scheduler's and the near field's keys
    // in their objects, the rest at the top level.
    const nlohmann::json j = nlohmann::json::parse(volumeSettingsSchema().write({}));
    EXPECT_EQ(j.at("store").at("blendTime_s").get<double>(), 1.0);
    EXPECT_EQ(j.at("scheduler").at("maxLevel").get<int>(), 2);
    EXPECT_EQ(j.at("nearField").at("radius_m").get<double>(), 20.0);
    EXPECT_EQ(j.at("facesPerFrame").get<int>(), 1);
    EXPECT_TRUE(j.at("relightBySkyLevel").get<bool>());
    EXPECT_EQ(j.size(), 3u + 8u + 3u);  // three objects, the capture keys, the volume's own
}

TEST(SettingsSchema, TheReadersKeepTheChecksThatBindKeys) {
    const auto says = [](const std::string& doc, const std::string& what) {
        const std::string said = refusal(volumeSettingsSchema(), doc);
        EXPECT_NE(said.find(what), std::string::npos) << doc << ": " << said;
    };
    says(R"({"store": {"minLifetime_s": 700}})",
         "t.json: 'store': minLifetime_s exceeds maxLifetime_s");
    says(R"({"store": {"coarsestSpacing_m": 1, "levels": 5}})",
         "t.json: 'store': the finest spacing coarsestSpacing_m / 3^(levels - 1) is 0.0123457 m, "
         "below 0.05 m");
    says(R"({"store": {"levels": 5, "nosuch": 1}})", "t.json: 'store': unknown key 'nosuch'");
    says(R"({"nearField": {"radius": 1}})", "t.json: 'nearField': unknown key 'radius'");
    says(R"({"radius_m": 1})", "t.json: unknown key 'radius_m'");
    const std::string said =
        refusal(baselineSettingsSchema(), R"({"objectSize_m": 10, "objectRange_m": 641})");
    EXPECT_NE(said.find("t.json: 'objectRange_m' may be at most 64 x objectSize_m"),
              std::string::npos)
        << said;
    EXPECT_EQ(refusal(baselineSettingsSchema(), R"({"objectSize_m": 10, "objectRange_m": 640})"),
              "");
}

TEST(SettingsSchema, AssignmentsGoThroughTheReadersChecks) {
    const auto& schema = volumeSettingsSchema();
    AmbienceVolumeSettings s;
    schema.assign(s, "store.blendTime_s=2.5", "--set");
    schema.assign(s, "facesPerFrame=3", "--set");
    schema.assign(s, "nearField.enabled=false", "--set");
    schema.assign(s, "scheduler.maxLevel= 3 ", "--set");
    EXPECT_EQ(s.store.blendTime_s, 2.5);
    EXPECT_EQ(s.capture.facesPerFrame, 3);
    EXPECT_FALSE(s.capture.nearField.enabled);
    EXPECT_EQ(s.scheduler.maxLevel, 3);
    const auto says = [&](const std::string& assignment, const std::string& what) {
        AmbienceVolumeSettings t = s;
        try {
            schema.assign(t, assignment, "--set");
            ADD_FAILURE() << assignment << " taken";
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()), what);
        }
        EXPECT_TRUE(schema.equal(t, s)) << assignment << " changed the settings";
    };
    says("store.levels=0", "--set: 'store.levels' must be in [1, 8]");
    says("store.levels=2.5", "--set: 'store.levels' must be an integer");
    says("store.blendTime_s=slow", "--set: 'store.blendTime_s' must be a number");
    says("store.blendTime_s=nan", "--set: 'store.blendTime_s' must be a number");
    says("store.blendTime_s=", "--set: 'store.blendTime_s' must be a number");
    says("nearField.enabled=1", "--set: 'nearField.enabled' must be true or false");
    says("store.blendtime_s=1",
         "--set: unknown setting 'store.blendtime_s' (`ambience settings` lists them)");
    says("blendTime_s=1", "--set: unknown setting 'blendTime_s' (`ambience settings` lists them)");
    says("store.blendTime_s", "--set: expected KEY=VALUE, got 'store.blendTime_s'");
    // A baseline key is not the volume's: assignIfKnown leaves it to the other schema.
    AmbienceVolumeSettings t;
    EXPECT_FALSE(schema.assignIfKnown(t, "gridSize=8", "--set"));
    BaselineSettings b;
    EXPECT_TRUE(baselineSettingsSchema().assignIfKnown(b, "gridSize=8", "--set"));
    EXPECT_EQ(b.gridSize, 8);
}

// The files the project ships with settings in them read as they always have.
TEST(SettingsSchema, TheShippedSweepsSettingsStillRead) {
    std::ifstream in(std::string(AMBIENCE_SOURCE_DIR) + "/sweeps/two-scale.json");
    ASSERT_TRUE(in);
    const nlohmann::json sweep = nlohmann::json::parse(in);
    int read = 0;
    for (const nlohmann::json& point : sweep.at("points")) {
        if (point.contains("volume")) {
            EXPECT_NO_THROW(ambienceSettingsFromJson(point.at("volume").dump(), "sweep"));
            ++read;
        }
        if (point.contains("baseline")) {
            EXPECT_NO_THROW(baselineSettingsFromJson(point.at("baseline").dump(), "sweep"));
            ++read;
        }
    }
    EXPECT_GT(read, 5);
}

}  // namespace
}  // namespace amb
