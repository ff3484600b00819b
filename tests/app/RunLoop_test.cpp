// RunLoop_test.cpp — `ambience run --loop N`: the replay played N times back to back with one
// clock, the time of day moving at the replay's rate throughout, each jump back to the start a
// camera cut the volume sees as a teleport; the report's memory column and store scan; and bad
// loop counts refused before any work (one line, exit code 2).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "GlTestContext.h"
#include "RunAmbience.h"

namespace amb {
namespace {

namespace fs = std::filesystem;

nlohmann::json readJson(const fs::path& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in);
}

void expectLoopRefused(const std::string& args, const std::string& mentions,
                       const fs::path& out) {
    const auto r = test::runAmbience(args + " --out " + out.string());
    EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.err;
    EXPECT_EQ(r.errLines(), 1) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("--loop"), std::string::npos) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(mentions), std::string::npos) << args << "\n" << r.err;
    // Refused before any work: no report.
    EXPECT_FALSE(fs::exists(out / "report.json")) << args;
}

TEST(RunLoop, BadLoopCountsAreOneLineAndExitCode2) {
    const fs::path dir = test::scratchDir("loop-bad");
    const std::string run = "run --replay " + test::sourcePath("replays/stress-flight.json") +
                            " --no-frames --no-video";
    expectLoopRefused(run + " --loop 0", "1 to 10000", dir);
    expectLoopRefused(run + " --loop -3", "1 to 10000", dir);
    expectLoopRefused(run + " --loop 10001", "1 to 10000", dir);
    expectLoopRefused(run + " --loop many", "many", dir);
    // Within the range but too long a run: 5401 frames per pass at stride 1, x 10000.
    expectLoopRefused("run --replay " + test::sourcePath("replays/highway-drive.json") +
                          " --no-frames --stride 1 --loop 10000",
                      "frames", dir);
}

// A 2 s flight at 250 m/s, played three times: the run's clock and the time of day go on
// across the jumps, the camera restarts at the replay's start, and each jump is a cut.
TEST(RunLoop, LoopsKeepTheClockAndTimeOfDayAndCutAtEachRestart) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, 16, 16);
    platform.reset();
    const fs::path dir = test::scratchDir("loop-run");
    const fs::path replay = dir / "short.json";
    constexpr double kStart_h = 6.0, kRate = 3600.0;  // one hour of day per second
    const auto made = test::runAmbience(
        "replay make --mode fly --speed 250 --duration 2 --cuts 0 --time 6 --time-rate 3600 "
        "--out " + replay.string());
    ASSERT_EQ(made.exitCode, 0) << made.err;
    const auto r = test::runAmbience("run --replay " + replay.string() +
                                     " --loop 3 --stride 2 --no-frames --out " +
                                     (dir / "out").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto j = readJson(dir / "out" / "report.json");

    // 60 Hz samples at stride 2: a frame every 1/30 s, 61 frames per 2 s pass.
    constexpr int kPerPass = 61;
    constexpr double kStep_s = 2.0 / 60.0;
    EXPECT_EQ(j["loops"], 3);
    ASSERT_EQ(j["frameCount"], 3 * kPerPass);
    const auto& rows = j["frames"];
    ASSERT_EQ(rows.size(), std::size_t(3 * kPerPass));
    int cuts = 0;
    for (int i = 0; i < 3 * kPerPass; ++i) {
        const auto& row = rows[std::size_t(i)];
        const double t = row["time_s"].get<double>();
        EXPECT_NEAR(t, i * kStep_s, 1e-9) << "frame " << i;  // one clock, constant step
        EXPECT_EQ(row["loop"], i / kPerPass) << "frame " << i;
        EXPECT_NEAR(row["replayTime_s"].get<double>(), (i % kPerPass) * kStep_s, 1e-9)
            << "frame " << i;
        // The time of day moves at the replay's rate through every pass (no jump back).
        const double expected_h = std::fmod(kStart_h + kRate * i * kStep_s / 3600.0, 24.0);
        EXPECT_NEAR(row["timeOfDay_h"].get<double>(), expected_h, 1e-6) << "frame " << i;
        const bool restart = i > 0 && i % kPerPass == 0;
        EXPECT_EQ(row["cut"].get<bool>(), restart) << "frame " << i;
        cuts += row["cut"].get<bool>() ? 1 : 0;
        EXPECT_GT(row["rss_kB"].get<double>(), 1000.0) << "frame " << i;  // at least 1 MB
        // The heap in use is part of the resident memory (glibc reports it).
        EXPECT_GT(row["heap_kB"].get<double>(), 100.0) << "frame " << i;
        EXPECT_LT(row["heap_kB"].get<double>(), row["rss_kB"].get<double>()) << "frame " << i;
    }
    EXPECT_EQ(cuts, 2);
    EXPECT_EQ(j["cameraCuts"], 2);
    // The jump back is 500 m in one frame: the volume's motion model sees both as teleports.
    EXPECT_EQ(j["ambience"]["teleports"], 2);
    // Every frame's store scanned, nothing non-finite.
    EXPECT_EQ(j["ambience"]["storeScans"], 3 * kPerPass);
    EXPECT_EQ(j["ambience"]["storeFinite"], true);
    EXPECT_EQ(j["ambience"]["nonFiniteAnchorsMax"], 0);
    const auto& m = j["memory"];
    EXPECT_GE(m["rssPeak_kB"].get<double>(), m["rss_kB"]["max"].get<double>());
    EXPECT_GT(m["rssStart_kB"].get<double>(), 1000.0);

    // The CSV carries the same memory and cut columns.
    std::ifstream csv(dir / "out" / "report.csv");
    std::string header;
    std::getline(csv, header);
    EXPECT_NE(header.find(",rss_kB,heap_kB,cut,loop"), std::string::npos) << header;
}

}  // namespace
}  // namespace amb
