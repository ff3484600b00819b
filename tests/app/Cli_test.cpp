// Cli_test.cpp — the command line as a user meets it: help works, and bad input (unknown
// options, missing or malformed files, absurd values) gives exactly one line on stderr naming
// what and where, exit code 2, and no crash.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "RunAmbience.h"

namespace amb {
namespace {

using test::runAmbience;
using test::sourcePath;

// Exit code 2 and one line on stderr that contains every fragment.
void expectInputError(const std::string& args, std::initializer_list<const char*> fragments) {
    const test::CommandResult r = runAmbience(args);
    EXPECT_EQ(r.exitCode, 2) << args << "\nstderr: " << r.err;
    EXPECT_EQ(r.errLines(), 1) << args << "\nstderr: " << r.err;
    for (const char* f : fragments)
        EXPECT_NE(r.err.find(f), std::string::npos) << "'" << f << "' not in: " << r.err;
}

std::string writeTemp(const std::string& name, const std::string& text) {
    const std::string path = testing::TempDir() + name;
    std::ofstream(path) << text;
    return path;
}

// The test harness splits argument text as a shell would, without running one.
TEST(Cli, HarnessSplitsWordsWithShellQuoting) {
    EXPECT_EQ(test::splitWords("  a 'b c'  \"d\\\"e$\" f\\ g 'it'\\''s' "),
              (std::vector<std::string>{"a", "b c", "d\"e$", "f g", "it's"}));
    EXPECT_EQ(test::splitWords("'$(touch x); echo'"),
              (std::vector<std::string>{"$(touch x); echo"}));
    EXPECT_TRUE(test::splitWords("").empty());
    EXPECT_THROW(test::splitWords("'open"), std::invalid_argument);
}

TEST(Cli, HelpListsEverySubcommand) {
    const test::CommandResult r = runAmbience("--help");
    EXPECT_EQ(r.exitCode, 0);
    for (const char* sub : {"run", "view", "probe", "world", "replay", "sh"})
        EXPECT_NE(r.out.find(sub), std::string::npos) << sub;
    EXPECT_EQ(runAmbience("replay make --help").exitCode, 0);
    EXPECT_EQ(runAmbience("world --help").exitCode, 0);
}

TEST(Cli, UnknownOptionsAndSubcommands) {
    expectInputError("--frobnicate", {"frobnicate"});
    expectInputError("teleport", {"teleport"});
    expectInputError("replay info", {"file"});                       // missing positional
    expectInputError("replay make --mode swim --out x.json", {"swim"});
    expectInputError("", {"subcommand"});
}

TEST(Cli, ReplayInfoOnShippedReplay) {
    const test::CommandResult r = runAmbience("replay info " + sourcePath("replays/highway-drive.json"));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_NE(r.out.find("duration"), std::string::npos);
    EXPECT_NE(r.out.find("30.00"), std::string::npos) << r.out;  // the drive's speed
    const test::CommandResult j = runAmbience("replay info --json " + sourcePath("replays/stress-flight.json"));
    ASSERT_EQ(j.exitCode, 0) << j.err;
    EXPECT_NE(j.out.find("\"cuts\": 1"), std::string::npos) << j.out;
}

TEST(Cli, ReplayInfoBadFiles) {
    expectInputError("replay info /nonexistent/x.json", {"/nonexistent/x.json", "cannot open"});
    const std::string truncated = writeTemp("cli_truncated.json", "{\"format\": \"ambience-replay\", ");
    expectInputError("replay info " + truncated, {"cli_truncated.json", "not valid JSON"});
    const std::string wrongVersion = writeTemp(
        "cli_version.json", "{\"format\": \"ambience-replay\", \"version\": 99}");
    expectInputError("replay info " + wrongVersion, {"cli_version.json", "version", "99"});
}

TEST(Cli, ReplayMakeRoundTripsThroughInfo) {
    const std::string out = testing::TempDir() + "cli_static.json";
    const test::CommandResult r = runAmbience("replay make --mode static --at 100,200 --duration 2 --out " + out);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const test::CommandResult info = runAmbience("replay info --json " + out);
    ASSERT_EQ(info.exitCode, 0) << info.err;
    EXPECT_NE(info.out.find("\"samples\": 121"), std::string::npos) << info.out;  // 2 s at 60 Hz
    std::remove(out.c_str());
}

TEST(Cli, ReplayMakeBadSettings) {
    expectInputError("replay make --mode drive --road nowhere --out " + testing::TempDir() + "x.json",
                     {"nowhere"});
    expectInputError("replay make --mode drive --duration -5 --out x.json", {"duration"});
    expectInputError("replay make --mode drive --speed nan --out x.json", {"speed"});
    expectInputError("replay make --mode static --at 1,2 --duration 1 --out /nonexistent/dir/x.json",
                     {"/nonexistent/dir/x.json"});
}

TEST(Cli, WorldBadInput) {
    expectInputError("world --map " + testing::TempDir() + "m.png --size -1", {"size"});
    expectInputError("world --map " + testing::TempDir() + "m.png --replay /nonexistent/r.json",
                     {"/nonexistent/r.json"});
    expectInputError("world --map " + testing::TempDir() + "m.png --centre 1,nan", {"centre"});
}

TEST(Cli, WorldMapIsWritten) {
    const std::string map = testing::TempDir() + "cli_map.png";
    const test::CommandResult r = runAmbience("world --seed 3 --size 2000 --pixels 64 --map " + map);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    std::ifstream in(map, std::ios::binary);
    char sig[8] = {};
    in.read(sig, 8);
    EXPECT_EQ(std::string(sig + 1, 3), "PNG");
    std::remove(map.c_str());
}

// The reference oracle's options: unknown kinds and absurd sizes are one clear error.
TEST(Cli, ReferenceOracleBadOptions) {
    const std::string replay = sourcePath("replays/highway-drive.json");
    expectInputError("run --replay " + replay + " --no-frames --measure-every 10 --oracle-kind truth",
                     {"--oracle-kind", "truth"});
    expectInputError("run --replay " + replay + " --no-frames --oracle-kind reference",
                     {"--oracle-kind", "--measure-every"});
    expectInputError("run --replay " + replay +
                         " --no-frames --measure-every 10 --oracle-kind reference --reference-size 0",
                     {"--reference-size"});
    expectInputError("run --replay " + replay + " --no-frames --measure-every 10 --share 0",
                     {"--share"});
    // --capture-light: own or reference, and reference only with a bounce-lit reference.
    expectInputError("run --replay " + replay + " --no-frames --capture-light sky",
                     {"--capture-light", "own or reference"});
    expectInputError("run --replay " + replay + " --no-frames --capture-light reference",
                     {"--capture-light", "bounce field"});
    expectInputError("run --replay " + replay +
                         " --no-frames --measure-every 10 --oracle-kind reference "
                         "--reference-light hemisphere --capture-light reference",
                     {"--capture-light", "bounce field"});
    expectInputError("bench --capture-light reference --out " + testing::TempDir() + "b",
                     {"--capture-light", "--oracle reference"});
    expectInputError("probe --at 0,0 --scene detailed --out " + testing::TempDir() + "p.exr",
                     {"--scene", "detailed"});
    expectInputError("bench --oracle perfect --out " + testing::TempDir() + "b", {"--oracle"});
}

// `ambience compare`: a small frame with a coarse sample grid writes the three pictures side by
// side and a summary whose error is finite and positive; bad options are one clear error.
TEST(Cli, CompareWritesTheFrameTheReferenceAndTheHeatMap) {
    const std::string out = testing::TempDir() + "compare-test";
    const test::CommandResult r = runAmbience(
        "compare --replay " + sourcePath("replays/highway-drive.json") +
        " --frame 20 --size 96x54 --grid 12 --reference-size 16 --bounce-spacing 256 "
        "--bounce-reach 100 --bounce-face 8 --out " + out);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    for (const char* f : {"method.png", "reference.png", "error.png", "compare.png"})
        EXPECT_TRUE(std::filesystem::exists(out + "/" + f)) << f;
    std::ifstream in(out + "/compare.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_GT(j["samples"].get<int>(), 5);
    const double e = j["screenMeanError"].get<double>();
    EXPECT_TRUE(std::isfinite(e));
    EXPECT_GT(e, 0.0);
    EXPECT_LT(e, 2.0);
    // The reference lit by its own bounce field (the default), which converged.
    EXPECT_EQ(j["referenceLight"], "bounce");
    ASSERT_EQ(j["bounce"]["solves"].size(), 1u);
    EXPECT_TRUE(j["bounce"]["solves"][0]["converged"].get<bool>());
    EXPECT_GE(j["bounce"]["solves"][0]["points"].get<int>(), 1);
    expectInputError("compare --reference-light sky --out " + out, {"--reference-light", "sky"});
    expectInputError("compare --bounce-spacing 1 --out " + out, {"--bounce-spacing"});
    expectInputError("compare --grid 1 --out " + out, {"--grid"});
    expectInputError("compare --frame 999999 --out " + out, {"--frame"});
    expectInputError("compare --ambient magic --out " + out, {"--ambient"});
}

// `compare --frame` outside the replay is refused naming --frame: -1 is not "the middle" (that
// is --frame left out), and neither is any other negative frame; one past the last is refused.
TEST(Cli, CompareRefusesAFrameOutsideTheReplay) {
    const std::string args = "compare --replay " + sourcePath("replays/highway-drive.json") +
                             " --size 32x18 --grid 16 --reference-size 4 --out " +
                             testing::TempDir() + "compare-frame";
    // 90 s at 60 Hz and stride 2: frames 0 to 2700.
    expectInputError(args + " --frame -1", {"--frame", "0 to 2700", "got -1"});
    expectInputError(args + " --frame -2000", {"--frame", "got -2000"});
    expectInputError(args + " --frame 2701", {"--frame", "0 to 2700", "got 2701"});
    expectInputError(args + " --stride 3 --frame 1801", {"--frame", "0 to 1800", "stride 3"});
}

// The shadow options: anything but on or off, and absurd cascades, sizes or taps, are one clear
// error naming the option, before any work.
TEST(Cli, ShadowBadOptions) {
    const std::string replay = sourcePath("replays/highway-drive.json");
    const std::string out = testing::TempDir() + "cli_shadows";
    expectInputError("run --replay " + replay + " --shadows maybe --out " + out, {"--shadows", "maybe"});
    expectInputError("run --replay " + replay + " --shadow-cascades 9 --out " + out,
                     {"--shadow-cascades", "cascades"});
    expectInputError("run --replay " + replay + " --shadow-size 100000 --out " + out,
                     {"--shadow-size", "map size"});
    expectInputError("run --replay " + replay + " --shadow-pcf 0 --out " + out, {"PCF"});
    expectInputError("compare --shadows 1 --out " + out, {"--shadows"});
    expectInputError("view --shadows yes", {"--shadows"});
}

}  // namespace
}  // namespace amb
