// Hostile_test.cpp — regression tests for what a hostile or careless user can do with the
// command line and with files people exchange (replays): no shell command from a file, no
// writes outside the output folder, no output overwriting an input, outputs checked before the
// work, and one line with exit code 2 for nonsense that used to be accepted or crash.
#include <sys/stat.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "RunAmbience.h"

namespace amb {
namespace {

namespace fs = std::filesystem;
using test::runAmbience;
using test::scratchDir;
using test::slurp;
using test::sourcePath;

// Exit code 2 and one line on stderr that contains every fragment.
void expectInputError(const std::string& args, std::initializer_list<const char*> fragments,
                      const std::string& prefix = "") {
    const test::CommandResult r = runAmbience(args, prefix);
    EXPECT_EQ(r.exitCode, 2) << args << "\nstderr: " << r.err;
    EXPECT_EQ(r.errLines(), 1) << args << "\nstderr: " << r.err;
    for (const char* f : fragments)
        EXPECT_NE(r.err.find(f), std::string::npos) << "'" << f << "' not in: " << r.err;
}

std::string quoted(const std::string& s) {
    std::string out = "'";
    for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

// A one-second drive replay with the given name.
std::string makeReplay(const fs::path& dir, const std::string& name) {
    const std::string path = (dir / "r.json").string();
    const auto r = runAmbience("replay make --duration 1 --name " + quoted(name) + " --out " +
                               quoted(path));
    EXPECT_EQ(r.exitCode, 0) << r.err;
    return path;
}

// A replay's name ends up in the default video path; ffmpeg used to be started through a shell
// with that path in single quotes, so a quote in the name ran a command.
TEST(Hostile, ReplayNameRunsNoShellCommand) {
    const fs::path dir = scratchDir("inject");
    const fs::path marker = dir / "PWNED";
    const std::string replay =
        makeReplay(dir, "x'; touch " + marker.string() + "; echo '");
    const auto r = runAmbience("run --replay " + quoted(replay) +
                               " --max-frames 5 --frames none --out " + quoted((dir / "o").string()));
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_FALSE(fs::exists(marker)) << "a command in the replay's name was run";
    // The video is written under a safe name in the output folder, and nowhere else.
    int videos = 0;
    for (const auto& e : fs::directory_iterator(dir / "o")) {
        if (e.path().extension() == ".mp4") {
            ++videos;
            EXPECT_GT(fs::file_size(e.path()), 0u);
            EXPECT_EQ(e.path().filename().string().find('\''), std::string::npos);
        }
    }
    EXPECT_EQ(videos, 1);
}

// A quote in a legitimate --video path used to fail ("Unterminated quoted string").
TEST(Hostile, VideoPathWithQuotesAndSpaces) {
    const fs::path dir = scratchDir("video-quote");
    const fs::path video = dir / "it's a \"video\" $(x).mp4";
    const auto r = runAmbience("run --replay " + sourcePath("replays/highway-drive.json") +
                               " --max-frames 5 --frames none --out " + quoted((dir / "o").string()) +
                               " --video " + quoted(video.string()));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    ASSERT_TRUE(fs::exists(video));
    EXPECT_GT(fs::file_size(video), 0u);
}

// A replay named "x/../../../../evil" made `run` write above the working directory.
TEST(Hostile, ReplayNameCannotLeaveTheOutputFolder) {
    const fs::path dir = scratchDir("traversal");
    const fs::path cwd = dir / "a" / "b" / "c";
    fs::create_directories(cwd);
    const std::string replay = makeReplay(dir, "x/../../../../evil");
    const auto r =
        runAmbience("run --replay " + quoted(replay) + " --max-frames 3 --no-video", "", cwd);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    // Everything went under <cwd>/out/run-<safe name>/.
    for (const fs::path& p : {dir / "evil", dir / "a" / "evil", dir / "a" / "b" / "evil",
                              cwd / "evil", cwd / "out" / "evil"})
        EXPECT_FALSE(fs::exists(p)) << p;
    ASSERT_TRUE(fs::exists(cwd / "out")) << r.out;
    int runs = 0;
    for (const auto& e : fs::directory_iterator(cwd / "out")) {
        ++runs;
        const std::string name = e.path().filename().string();
        EXPECT_EQ(name.rfind("run-", 0), 0u) << name;
        EXPECT_EQ(name.find(".."), std::string::npos) << name;
        EXPECT_TRUE(fs::exists(e.path() / "report.json")) << name;
    }
    EXPECT_EQ(runs, 1);
}

// An output equal to an input (or to another output) is refused before any work, and the input
// is left as it was.
TEST(Hostile, OutputsNeverOverwriteInputs) {
    const fs::path dir = scratchDir("overwrite");
    const std::string replay = makeReplay(dir, "keep");
    const std::string before = slurp(replay);
    const std::string run = "run --replay " + quoted(replay) + " --max-frames 3 --no-video --out " +
                            quoted((dir / "o").string());
    expectInputError(run + " --report " + quoted(replay), {"--report", "--replay"});
    expectInputError(run + " --save-anchors " + quoted(replay), {"--save-anchors", "--replay"});
    // Through another spelling of the same file.
    expectInputError(run + " --report " + quoted((dir / "o" / ".." / "r.json").string()),
                     {"--report"});
    // The report's CSV is written beside it: r.json as report makes r.csv; a CSV input clashes.
    {
        std::ofstream(dir / "settings.json") << "{}";
        const std::string config = (dir / "settings.json").string();
        expectInputError(run + " --config " + quoted(config) + " --report " + quoted(config),
                         {"--report", "--config"});
    }
    expectInputError(run + " --report " + quoted((dir / "same.json").string()) +
                         " --save-anchors " + quoted((dir / "same.json").string()),
                     {"--save-anchors", "--report"});
    EXPECT_EQ(slurp(replay), before);
    const std::string map = (dir / "map.png").string();
    expectInputError("world --pixels 16 --map " + quoted(map) + " --heightmap " + quoted(map),
                     {"--heightmap", "--map"});
    EXPECT_FALSE(fs::exists(map));
    expectInputError("world --pixels 16 --replay " + quoted(replay) + " --map " + quoted(replay),
                     {"--map"});
    EXPECT_EQ(slurp(replay), before);
}

// Unwritable outputs were reported only after the whole run; now before the first frame. (A
// folder that does not exist, or a file where a folder should be: permission bits do not stop
// root.) The whole default replay would take minutes; the check must come first.
TEST(Hostile, UnwritableOutputsFailBeforeTheRun) {
    const fs::path dir = scratchDir("unwritable");
    std::ofstream(dir / "file") << "x";
    const std::string run = "run --no-frames --out " + quoted((dir / "o").string());
    const std::string nowhere = (dir / "file" / "x").string();
    expectInputError(run + " --report " + quoted(nowhere + ".json"), {"--report"}, "timeout 60");
    expectInputError(run + " --save-anchors " + quoted(nowhere + ".vdb"), {"--save-anchors"},
                     "timeout 60");
    expectInputError("run --frames none --out " + quoted((dir / "o").string()) + " --video " +
                         quoted((dir / "missing" / "v.mp4").string()),
                     {"--video"}, "timeout 60");
    EXPECT_FALSE(fs::exists(dir / "o" / "report.json"));
}

TEST(Hostile, NegativeSeedsAreRefused) {
    const fs::path dir = scratchDir("seed");
    expectInputError("world --seed -1 --map " + quoted((dir / "m.png").string()), {"--seed"});
    expectInputError("probe --seed -1 --at 0,0 --out " + quoted((dir / "p.exr").string()),
                     {"--seed"});
    expectInputError("replay make --seed -1 --out " + quoted((dir / "r.json").string()),
                     {"--seed"});
    expectInputError("replay make --seed 18446744073709551616 --out " +
                         quoted((dir / "r.json").string()),
                     {"--seed"});
    EXPECT_EQ(runAmbience("replay make --duration 1 --seed 18446744073709551615 --out " +
                          quoted((dir / "r.json").string()))
                  .exitCode,
              0);
}

TEST(Hostile, ViewRefusesNonsenseTimesAndExplainsAMissingDisplay) {
    for (const char* t : {"nan", "1e308", "-1", "24.5", "inf"})
        expectInputError(std::string("view --frames 1 --time ") + t, {"--time"});
    // No display: one line, exit 2, and what to do instead.
    expectInputError("view --frames 1", {"xvfb-run", "ambience run"},
                     "env -u DISPLAY -u WAYLAND_DISPLAY");
}

TEST(Hostile, UnknownSubcommandWithHelpIsAnError) {
    expectInputError("bogus --help", {"bogus"});
    expectInputError("replay bogus --help", {"bogus"});
    EXPECT_EQ(runAmbience("replay --help").exitCode, 0);
    EXPECT_EQ(runAmbience("replay info --help").exitCode, 0);
}

TEST(Hostile, BenchWithNothingToRunOrOnlyFailuresDoesNotSucceed) {
    const fs::path dir = scratchDir("bench-fail");
    const std::string out = " --out " + quoted((dir / "out").string());
    expectInputError("bench --backend bogus --replays highway-drive --methods constant" + out,
                     {"--backend", "bogus"});
    expectInputError("bench --replays ',,,' --methods constant" + out, {"--replays"});
    expectInputError("bench --replays highway-drive --methods ',,'" + out, {"--methods"});
    // Every run fails (a replay the runs cannot read): exit 1, one line, results still written.
    std::ofstream(dir / "broken.json") << "{\"format\": \"ambience-replay\"}";
    const auto r = runAmbience("bench --replays " + quoted((dir / "broken.json").string()) +
                               " --methods constant --max-frames 10" + out);
    EXPECT_EQ(r.exitCode, 1) << r.err;
    EXPECT_NE(r.err.find("every run failed"), std::string::npos) << r.err;
    EXPECT_TRUE(fs::exists(dir / "out" / "results.csv"));
}

TEST(Hostile, BrokenShaderIsOneLineAndExitTwo) {
    const fs::path dir = scratchDir("shaders");
    fs::copy(std::string(AMBIENCE_BINARY_DIR) + "/shaders", dir / "shaders",
             fs::copy_options::recursive);
    {
        std::ofstream f(dir / "shaders" / "terrain.frag", std::ios::app);
        f << "\nthis is not GLSL;\n";
    }
    expectInputError("run --max-frames 1 --frames none --no-video --shaders " +
                         quoted((dir / "shaders").string()) + " --out " +
                         quoted((dir / "o").string()),
                     {"terrain.frag", "compile"});
}

TEST(Hostile, DevicesAndHugeFilesAreRefused) {
    expectInputError("replay info /dev/zero", {"/dev/zero", "regular file"}, "timeout 60");
    expectInputError("run --config /dev/zero --max-frames 1", {"/dev/zero"}, "timeout 60");
    expectInputError("run --baseline-config /dev/zero --ambient grid --max-frames 1",
                     {"/dev/zero"}, "timeout 60");
}

// `world --size 1e-4` hung (a line across a map a fraction of a millimetre wide was stepped
// pixel by pixel) and 1e-300 overflowed an int; sizes below a metre are refused, and a 1 m map
// with roads far outside it finishes at once.
TEST(Hostile, WorldMapSizes) {
    const fs::path dir = scratchDir("world-size");
    const std::string map = " --pixels 16 --map " + quoted((dir / "m.png").string());
    expectInputError("world --size 1e-4" + map, {"--size"});
    expectInputError("world --size 1e-300" + map, {"--size"});
    expectInputError("world --size nan" + map, {"--size"});
    const auto r = runAmbience("world --size 1 --replay " +
                                   sourcePath("replays/highway-drive.json") + map,
                               "timeout 60");
    EXPECT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(fs::exists(dir / "m.png"));
}

// `replay make --mode fly --start <far> --cuts N` landed the first cut near (6000, -6000): the
// cut was clamped to a square around the origin. Each cut now jumps --cut-jump metres.
TEST(Hostile, FarFlightCutsJumpTheirDistance) {
    const fs::path dir = scratchDir("far-cuts");
    const std::string path = (dir / "far.json").string();
    const auto r = runAmbience(
        "replay make --mode fly --start 1000000,-2000000 --duration 30 --cuts 3 --cut-jump 500 "
        "--out " + quoted(path));
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto doc = nlohmann::json::parse(slurp(path));
    const auto& samples = doc.at("samples");
    int cuts = 0, flagged = 0;
    // A sample row is [t_s, x_m, y_m, z_m, forward (3), up (3), cut] (replays/README.md).
    for (std::size_t i = 1; i < samples.size(); ++i) {
        const auto& a = samples[i - 1];
        const auto& b = samples[i];
        const double dx = b[1].get<double>() - a[1].get<double>();
        const double dz = b[3].get<double>() - a[3].get<double>();
        const double jump = std::hypot(dx, dz);
        EXPECT_LT(std::abs(b[1].get<double>() - 1000000.0), 20000.0);
        EXPECT_LT(std::abs(b[3].get<double>() + 2000000.0), 20000.0);
        flagged += b[10].get<bool>();
        if (jump > 100.0) {
            ++cuts;
            EXPECT_TRUE(b[10].get<bool>()) << "sample " << i;
            // 500 m, plus at most one step of flight (80 m/s / 60 Hz) either way.
            EXPECT_NEAR(jump, 500.0, 2.0) << "sample " << i;
        }
    }
    // The plan spreads its cuts over a length longer than the flight; some fall inside it.
    EXPECT_GE(cuts, 1);
    EXPECT_EQ(cuts, flagged);
}

// A NUL byte ends the input for the JSON library: a settings file "{}<NUL>anything" was read
// as "{}" and the rest ignored. Every JSON reader now refuses it (world/JsonText.h).
TEST(Hostile, JsonFilesWithANulByteAreRefused) {
    const fs::path dir = scratchDir("hostile-nul");
    std::ofstream(dir / "settings.json", std::ios::binary)
        << std::string("{\"store\": {}}\0{\"store\": {\"levels\": 99}}", 43);
    expectInputError("run --no-frames --max-frames 1 --config " +
                         quoted((dir / "settings.json").string()),
                     {"settings.json", "NUL byte at offset 13"});
    std::string replay = slurp(sourcePath("replays/highway-drive.json"));
    replay += std::string("\0junk", 5);
    std::ofstream(dir / "replay.json", std::ios::binary) << replay;
    expectInputError("run --no-frames --max-frames 1 --replay " +
                         quoted((dir / "replay.json").string()),
                     {"replay.json", "NUL byte"});
}

}  // namespace
}  // namespace amb
