// Replay_test.cpp — replay format v1: round trip, interpolation, and every malformed input we
// could think of gives an InputError that names the field or sample and what was expected.
#include "world/Replay.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "world/Error.h"

namespace amb {
namespace {

Replay makeReplay(int n) {
    Replay rp;
    rp.name = "test";
    rp.description = "a circle";
    rp.world.seed = 12345678901234ull;
    rp.world.latitude_deg = 57.7;
    rp.mode = ReplayMode::Fly;
    rp.timeOfDayStart_h = 23.5;
    rp.timeRate = 600.0;
    rp.step_s = 1.0 / 60.0;
    for (int i = 0; i < n; ++i) {
        CameraSample s;
        s.time_s = i * rp.step_s;
        const double a = 0.01 * i;
        // Far from the origin, with digits that need full double precision.
        s.position_m = {1.0e6 + 100.0 * std::cos(a) + 1e-7, 123.456789012345, -1.0e6 + 100.0 * std::sin(a)};
        s.forward = {-std::sin(a), 0.0, std::cos(a)};
        s.up = {0.0, 1.0, 0.0};
        s.cut = (i == n / 2);
        rp.samples.push_back(s);
    }
    return rp;
}

// Expects parseReplay to throw an InputError whose message contains every fragment given.
void expectError(const std::string& text, std::initializer_list<const char*> fragments) {
    try {
        parseReplay(text, "case.json");
        ADD_FAILURE() << "no error for: " << text.substr(0, 200);
    } catch (const InputError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("case.json"), std::string::npos) << msg;
        for (const char* f : fragments) EXPECT_NE(msg.find(f), std::string::npos) << "'" << f << "' not in: " << msg;
    }
}

nlohmann::json validDoc() { return nlohmann::json::parse(formatReplay(makeReplay(5))); }

TEST(Replay, RoundTripIsBitExact) {
    const Replay a = makeReplay(200);
    const std::string path = testing::TempDir() + "replay_roundtrip.json";
    writeReplay(a, path);
    const Replay b = readReplay(path);
    EXPECT_EQ(b.name, a.name);
    EXPECT_EQ(b.description, a.description);
    EXPECT_EQ(b.world.seed, a.world.seed);
    EXPECT_EQ(b.world.latitude_deg, a.world.latitude_deg);
    EXPECT_EQ(b.world.dayOfYear, a.world.dayOfYear);
    EXPECT_EQ(b.mode, a.mode);
    EXPECT_EQ(b.timeOfDayStart_h, a.timeOfDayStart_h);
    EXPECT_EQ(b.timeRate, a.timeRate);
    EXPECT_EQ(b.step_s, a.step_s);
    ASSERT_EQ(b.samples.size(), a.samples.size());
    for (std::size_t i = 0; i < a.samples.size(); ++i) {
        EXPECT_EQ(b.samples[i].time_s, a.samples[i].time_s) << i;
        EXPECT_EQ(b.samples[i].position_m, a.samples[i].position_m) << i;
        EXPECT_EQ(b.samples[i].forward, a.samples[i].forward) << i;
        EXPECT_EQ(b.samples[i].up, a.samples[i].up) << i;
        EXPECT_EQ(b.samples[i].cut, a.samples[i].cut) << i;
    }
    // Writing what was read gives the same bytes.
    EXPECT_EQ(formatReplay(b), formatReplay(a));
    std::remove(path.c_str());
}

TEST(Replay, TimeOfDayWraps) {
    const Replay rp = makeReplay(2);  // starts 23:30, 600x
    EXPECT_NEAR(rp.timeOfDayAt_h(0.0), 23.5, 1e-12);
    // 6 s at 600x = 1 hour of day: 00:30 next day.
    EXPECT_NEAR(rp.timeOfDayAt_h(6.0), 0.5, 1e-12);
    EXPECT_NEAR(rp.timeOfDayAt_h(6.0 + 144.0), 0.5, 1e-9);  // 144 s = one full day
}

TEST(Replay, SampleAtInterpolatesAndNeverAcrossCut) {
    const Replay rp = makeReplay(10);
    const double t = 2.5 * rp.step_s;
    const CameraSample s = rp.sampleAt(t);
    const glm::dvec3 mid = 0.5 * (rp.samples[2].position_m + rp.samples[3].position_m);
    EXPECT_NEAR(glm::length(s.position_m - mid), 0.0, 1e-9);
    EXPECT_NEAR(glm::length(s.forward), 1.0, 1e-12);
    EXPECT_NEAR(glm::dot(s.forward, s.up), 0.0, 1e-12);
    // Sample 5 is a cut: between 4 and 5 the camera stays at 4.
    const CameraSample c = rp.sampleAt(4.5 * rp.step_s);
    EXPECT_EQ(c.position_m, rp.samples[4].position_m);
    EXPECT_EQ(rp.sampleAt(-1.0).position_m, rp.samples.front().position_m);
    EXPECT_EQ(rp.sampleAt(1e9).position_m, rp.samples.back().position_m);
}

TEST(ReplayErrors, MissingFile) {
    try {
        readReplay("/nonexistent/dir/replay.json");
        ADD_FAILURE();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/replay.json"), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos);
    }
}

TEST(ReplayErrors, NotJsonOrTruncated) {
    const std::string good = formatReplay(makeReplay(5));
    expectError("", {"not valid JSON"});
    expectError(good.substr(0, good.size() / 2), {"not valid JSON"});
    expectError("[1, 2, 3]", {"top level"});
    // JSON has no NaN literal; a NaN written by a careless tool is a syntax error.
    std::string withNan = good;
    const std::string rate = "\"rate\":600.0";
    ASSERT_NE(withNan.find(rate), std::string::npos);
    withNan.replace(withNan.find(rate), rate.size(), "\"rate\": NaN");
    expectError(withNan, {"not valid JSON"});
}

TEST(ReplayErrors, WrongFormatAndVersion) {
    auto d = validDoc();
    d["version"] = 2;
    expectError(d.dump(), {"version", "unsupported version 2"});
    d = validDoc();
    d["version"] = "1";
    expectError(d.dump(), {"version", "expected an integer"});
    d = validDoc();
    d.erase("version");
    expectError(d.dump(), {"version", "missing"});
    d = validDoc();
    d["format"] = "something-else";
    expectError(d.dump(), {"format", "ambience-replay"});
}

TEST(ReplayErrors, WrongTypesAndRanges) {
    auto d = validDoc();
    d["step_s"] = "fast";
    expectError(d.dump(), {"step_s", "expected a number, got string"});
    d = validDoc();
    d["step_s"] = 0.0;
    expectError(d.dump(), {"step_s", "out of range"});
    d = validDoc();
    d["mode"] = "swim";
    expectError(d.dump(), {"mode", "drive"});
    d = validDoc();
    d["world"]["seed"] = -3;
    expectError(d.dump(), {"world.seed", "non-negative integer"});
    d = validDoc();
    d["world"]["seed"] = 1.5;
    expectError(d.dump(), {"world.seed"});
    d = validDoc();
    d["world"]["latitude_deg"] = 91.0;
    expectError(d.dump(), {"world.latitude_deg", "out of range"});
    d = validDoc();
    d["timeOfDay"]["start_h"] = 25.0;
    expectError(d.dump(), {"timeOfDay.start_h"});
    d = validDoc();
    d["timeOfDay"]["rate"] = 1e300;
    expectError(d.dump(), {"timeOfDay.rate"});
    d = validDoc();
    d["world"] = 7;
    expectError(d.dump(), {"world", "expected an object"});
    d = validDoc();
    d["sampleFields"][1] = "y_m";
    expectError(d.dump(), {"sampleFields"});
}

TEST(ReplayErrors, BadSamplesNameTheIndex) {
    auto d = validDoc();
    d["samples"] = nlohmann::json::array();
    expectError(d.dump(), {"samples", "at least one"});
    d = validDoc();
    d["samples"][3][1] = "x";
    expectError(d.dump(), {"samples[3].x_m", "expected a number"});
    d = validDoc();
    d["samples"][2].erase(d["samples"][2].end() - 1);
    expectError(d.dump(), {"samples[2]", "11 values"});
    d = validDoc();
    d["samples"][4][10] = 1;
    expectError(d.dump(), {"samples[4].cut", "true or false"});
    d = validDoc();
    d["samples"][1][2] = 1e300;  // huge: parses, but absurd for a coordinate
    expectError(d.dump(), {"samples[1].y_m", "absurd"});
    d = validDoc();
    d["samples"][2][4] = 3.0;  // forward not unit
    expectError(d.dump(), {"samples[2].forward", "unit"});
    d = validDoc();
    d["samples"][2][7] = d["samples"][2][4];
    d["samples"][2][8] = d["samples"][2][5];
    d["samples"][2][9] = d["samples"][2][6];  // up == forward
    expectError(d.dump(), {"samples[2].up", "orthogonal"});
}

TEST(ReplayErrors, TimeMustIncreaseAtTheFixedStep) {
    auto d = validDoc();
    d["samples"][3][0] = d["samples"][1][0];  // goes back in time
    expectError(d.dump(), {"samples[3].t_s", "not increasing"});
    d = validDoc();
    d["samples"][3][0] = d["samples"][3][0].get<double>() + 0.001;  // off the fixed step
    expectError(d.dump(), {"samples[3].t_s", "step_s"});
}

TEST(ReplayErrors, OverflowingNumberIsRejected) {
    // 1e400 overflows a double; the reader must not let an infinity through.
    auto text = validDoc().dump();
    const std::string from = "\"rate\":600.0";
    ASSERT_NE(text.find(from), std::string::npos) << text.substr(0, 300);
    text.replace(text.find(from), from.size(), "\"rate\":1e400");
    try {
        parseReplay(text, "case.json");
        ADD_FAILURE() << "accepted 1e400";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("case.json"), std::string::npos);
    }
}

}  // namespace
}  // namespace amb
