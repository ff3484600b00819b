// SettingsSchema_test.cpp — the settings schema (lighting/SettingsSchema.h) against what is built
// on it: each reader takes every key with exactly the schema's range (its ends taken, the next
// doubles or integers beyond them refused with a message naming the key and the range), the
// writer's file reads back equal, equality and AmbienceVolume::retunable see every key (and only
// the rebuilding ones stop a retune), `KEY=VALUE` assignments go through the same checks, and
// the files the project ships still read.
#include <cmath>
#include <filesystem>
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
    EXPECT_EQ(shared, 10 + 25);  // CaptureSettings' ten and the near field's twenty-five
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
    EXPECT_EQ(j.at("nearField").at("radius_m").get<double>(), NearFieldSettings{}.radius_m);
    EXPECT_EQ(j.at("facesPerFrame").get<int>(), 1);
    EXPECT_TRUE(j.at("relightBySkyLevel").get<bool>());
    EXPECT_EQ(j.size(), 3u + 10u + 3u);  // three objects, the capture keys, the volume's own
}

// nearField.vertexAmbient_m (terrain patches lit per vertex near the eye): in both files, in
// metres over [0, 2000], 320 m by default (the new vertices a frame bounded at 600); a file with
// it reads into the near field's settings, writes back with it and reads back equal, as does a
// KEY=VALUE assignment; beyond the range it is refused naming the key.
TEST(SettingsSchema, TheVertexAmbientRangeRoundTrips) {
    for (const auto* f :
         {static_cast<const SettingSpec*>(volumeSettingsSchema().find("nearField.vertexAmbient_m")),
          static_cast<const SettingSpec*>(
              baselineSettingsSchema().find("nearField.vertexAmbient_m"))}) {
        ASSERT_NE(f, nullptr);
        EXPECT_EQ(f->kind, Kind::Number);
        EXPECT_EQ(f->unit, "m");
        EXPECT_EQ(f->lo, 0.0);
        EXPECT_EQ(f->hi, 2000.0);
        EXPECT_TRUE(f->rebuilds);
        EXPECT_FALSE(f->help.empty());
    }
    EXPECT_EQ(AmbienceVolumeSettings{}.capture.nearField.vertexAmbient_m, 320.0);
    EXPECT_EQ(BaselineSettings{}.capture.nearField.vertexAmbient_m, 320.0);
    EXPECT_EQ(AmbienceVolumeSettings{}.capture.nearField.vertexPointsPerFrame, 600);
    EXPECT_EQ(BaselineSettings{}.capture.nearField.vertexPointsPerFrame, 600);
    const std::string file = R"({"nearField": {"vertexAmbient_m": 64}})";
    const AmbienceVolumeSettings v = ambienceSettingsFromJson(file, "v.json");
    EXPECT_EQ(v.capture.nearField.vertexAmbient_m, 64.0);
    const std::string written = volumeSettingsSchema().write(v);
    EXPECT_EQ(nlohmann::json::parse(written).at("nearField").at("vertexAmbient_m").get<double>(),
              64.0);
    EXPECT_TRUE(volumeSettingsSchema().equal(ambienceSettingsFromJson(written, "w"), v));
    EXPECT_FALSE(volumeSettingsSchema().equal(v, AmbienceVolumeSettings{}));
    const BaselineSettings b = baselineSettingsFromJson(file, "b.json");
    EXPECT_EQ(b.capture.nearField.vertexAmbient_m, 64.0);
    EXPECT_TRUE(baselineSettingsSchema().equal(
        baselineSettingsFromJson(baselineSettingsSchema().write(b), "w"), b));
    AmbienceVolumeSettings assigned;
    volumeSettingsSchema().assign(assigned, "nearField.vertexAmbient_m=96", "--set");
    EXPECT_EQ(assigned.capture.nearField.vertexAmbient_m, 96.0);
    volumeSettingsSchema().assign(assigned, "nearField.vertexPointsPerFrame=0", "--set");
    EXPECT_EQ(assigned.capture.nearField.vertexPointsPerFrame, 0);
    const std::string negative =
        refusal(volumeSettingsSchema(), R"({"nearField": {"vertexPointsPerFrame": -1}})");
    EXPECT_NE(negative.find("vertexPointsPerFrame"), std::string::npos) << negative;
    const std::string said =
        refusal(volumeSettingsSchema(), R"({"nearField": {"vertexAmbient_m": 2000.5}})");
    EXPECT_NE(said.find("'vertexAmbient_m' must be in [0, 2000]"), std::string::npos) << said;
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

// The worst case the ranges were measured at (docs/TUNING.md "Settings keys"): every costly key
// at its costly end, at once, is a settings file the readers take, and it reads back as built.
template <typename S>
void expectTheWorstCaseIsTaken(const SettingsSchema<S>& schema) {
    const S worst = schema.worstCase();
    const S defaults{};
    int costly = 0;
    for (const auto& f : schema.fields()) {
        SCOPED_TRACE(f.key);
        const double v = schema.value(worst, f);
        if (f.cost == SettingSpec::Cost::None) {
            EXPECT_EQ(v, schema.value(defaults, f));
            continue;
        }
        ++costly;
        EXPECT_EQ(v, f.kind == Kind::Boolean               ? 1.0
                     : f.cost == SettingSpec::Cost::AtHigh ? f.hi
                                                           : f.lo);
    }
    EXPECT_GT(costly, 5);
    const std::string text = schema.write(worst);
    EXPECT_EQ(refusal(schema, text), "") << text;
    EXPECT_TRUE(schema.equal(schema.read(text, "worst"), worst));
}

TEST(SettingsSchema, TheWorstCaseIsAFileTheReadersTake) {
    expectTheWorstCaseIsTaken(volumeSettingsSchema());
    expectTheWorstCaseIsTaken(baselineSettingsSchema());
    // The keys whose cost the ranges bound (docs/TUNING.md "Settings keys"), among them the
    // scheduler's search (the path samples, the rings and their widening) and the near field's
    // reach.
    for (const char* key :
         {"scheduler.horizon_s", "scheduler.pathStep_s", "scheduler.finestRingCells",
          "scheduler.coarseRingCells", "scheduler.maxWiden", "facesPerFrame", "fallbackFaceSize",
          "fallbackRefresh_h", "nearField.radius_m", "nearField.objectRange_m",
          "nearField.cornerRange_m", "nearField.patchSamples", "nearField.cacheEntries",
          "store.reachCells"})
        EXPECT_NE(volumeSettingsSchema().find(key)->cost, SettingSpec::Cost::None) << key;
    EXPECT_EQ(volumeSettingsSchema().find("scheduler.pathStep_s")->cost, SettingSpec::Cost::AtLow);
}

// The text between the lines of `path` that start with `begin` and `end`, without the blank
// lines around it ("" and a failure when either marker is missing).
std::string between(const std::string& path, const std::string& begin, const std::string& end) {
    std::ifstream in(path);
    EXPECT_TRUE(in) << path;
    std::string line, text;
    int state = 0;  // 0 before the block, 1 in it, 2 after it
    while (std::getline(in, line)) {
        if (state == 0 && line.rfind(begin, 0) == 0) {
            state = 1;
        } else if (state == 1 && line.rfind(end, 0) == 0) {
            state = 2;
        } else if (state == 1) {
            text += line + "\n";
        }
    }
    EXPECT_EQ(state, 2) << path << ": no '" << begin << "' ... '" << end << "' block";
    const std::size_t first = text.find_first_not_of('\n');
    if (first == std::string::npos) return "";
    return text.substr(first, text.find_last_not_of('\n') - first + 1) + "\n";
}

std::string trimmed(const std::string& text) {
    return text.substr(0, text.find_last_not_of('\n') + 1) + "\n";
}

// docs/TUNING.md's key tables are what the schema generates (scripts/update-settings-tables.sh
// writes them): a key added, renamed or given another range fails here until they are.
TEST(SettingsSchema, TheDocsKeyTablesAreTheSchemas) {
    const std::string docs = between(std::string(AMBIENCE_SOURCE_DIR) + "/docs/TUNING.md",
                                     "<!-- settings-schema: begin", "<!-- settings-schema: end");
    EXPECT_EQ(docs, trimmed(settingsMarkdown()))
        << "docs/TUNING.md's key tables differ from the settings schema: run "
           "scripts/update-settings-tables.sh";
    // A row per key of each file.
    for (const auto& f : volumeSettingsSchema().fields())
        EXPECT_NE(docs.find("| `" + f.key + "` |"), std::string::npos) << f.key;
    for (const auto& f : baselineSettingsSchema().fields())
        EXPECT_NE(docs.find("| `" + f.key + "` |"), std::string::npos) << f.key;
}

// The fuzz dictionary names every key and object of the settings files, so that mutations of
// the settings targets reach every key (tests/fuzz/json.dict).
TEST(SettingsSchema, TheFuzzDictionaryHasEveryKey) {
    const std::string dict = between(std::string(AMBIENCE_SOURCE_DIR) + "/tests/fuzz/json.dict",
                                     "# settings-schema: begin", "# settings-schema: end");
    EXPECT_EQ(dict, settingsFuzzDictionary())
        << "tests/fuzz/json.dict differs from the settings schema: run "
           "scripts/update-settings-tables.sh";
    for (const char* name : {"store", "scheduler", "nearField", "cacheEntries", "gridSize",
                             "facesPerFrame", "objectRange_m"})
        EXPECT_NE(dict.find(std::string("settings_") + name + "=\"\\\"" + name + "\\\"\"\n"),
                  std::string::npos)
            << name;
}

// The settings targets' seeds (tests/fuzz/make-corpus.sh) are settings files the readers take,
// and every-key.json holds every key the schema knows, at its default: a seed the reader
// refused would only ever exercise its errors.
TEST(SettingsSchema, TheFuzzSeedsAreFilesTheReadersTake) {
    namespace fs = std::filesystem;
    const fs::path corpus = fs::path(AMBIENCE_SOURCE_DIR) / "tests/fuzz/corpus";
    int seeds = 0;
    for (const char* target : {"fuzz_volume_settings", "fuzz_baseline_settings"}) {
        const bool volume = std::string(target) == "fuzz_volume_settings";
        for (const auto& entry : fs::directory_iterator(corpus / target)) {
            std::ifstream in(entry.path());
            std::stringstream text;
            text << in.rdbuf();
            SCOPED_TRACE(entry.path().string());
            const std::string said = volume ? refusal(volumeSettingsSchema(), text.str())
                                            : refusal(baselineSettingsSchema(), text.str());
            EXPECT_EQ(said, "");
            if (entry.path().filename() == "every-key.json") {
                EXPECT_EQ(text.str(), volume ? volumeSettingsSchema().write({})
                                             : baselineSettingsSchema().write({}));
            }
            ++seeds;
        }
    }
    EXPECT_GE(seeds, 4);
}

// The files the project ships with settings in them read as they always have.
TEST(SettingsSchema, TheShippedSweepsSettingsStillRead) {
    // Every sweep the repository ships: a key renamed or a range narrowed shows here first.
    int read = 0, files = 0;
    for (const auto& entry :
         std::filesystem::directory_iterator(std::string(AMBIENCE_SOURCE_DIR) + "/sweeps")) {
        if (entry.path().extension() != ".json") continue;
        const std::string file = entry.path().filename().string();
        ++files;
        std::ifstream in(entry.path());
        ASSERT_TRUE(in) << file;
        const nlohmann::json sweep = nlohmann::json::parse(in);
        for (const nlohmann::json& point : sweep.at("points")) {
            if (point.contains("volume")) {
                EXPECT_NO_THROW(ambienceSettingsFromJson(point.at("volume").dump(), file));
                ++read;
            }
            if (point.contains("baseline")) {
                EXPECT_NO_THROW(baselineSettingsFromJson(point.at("baseline").dump(), file));
                ++read;
            }
        }
    }
    EXPECT_GE(files, 12);
    EXPECT_GT(read, 20);
}

}  // namespace
}  // namespace amb
