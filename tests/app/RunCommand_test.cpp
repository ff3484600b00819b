// RunCommand_test.cpp — `ambience run` and `ambience probe` end to end: a short headless run
// writes frames, a report whose numbers are consistent, and bad input gives exit code 2 with one
// line on stderr.
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "RunAmbience.h"
#include "GlTestContext.h"
#include "lighting/CubeMapFile.h"

namespace amb {
namespace {

namespace fs = std::filesystem;

const std::string kReplay = std::string(AMBIENCE_SOURCE_DIR) + "/replays/highway-drive.json";

TEST(RunCommand, ShortRunWritesFramesAndAConsistentReport) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, 16, 16);
    platform.reset();
    const fs::path dir = test::scratchDir("run");
    const auto r = test::runAmbience("run --replay " + kReplay +
                                     " --size 160x90 --max-frames 6 "
                                     "--every 3 --no-video --out " +
                                     dir.string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_TRUE(fs::exists(dir / "frames/frame-00000.png"));
    EXPECT_TRUE(fs::exists(dir / "frames/frame-00003.png"));
    EXPECT_FALSE(fs::exists(dir / "frames/frame-00001.png"));
    std::ifstream in(dir / "report.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j["frameCount"], 6);
    EXPECT_EQ(j["size"]["width"], 160);
    EXPECT_FALSE(j["GL_RENDERER"].get<std::string>().empty());
    ASSERT_EQ(j["frames"].size(), 6u);
    // Stage times add up to no more than the frame time; statistics are ordered.
    for (const auto& row : j["frames"]) {
        double sum = 0.0;
        for (const char* s : {"advance_ms", "predict_ms", "capture_ms", "store_ms",
                              "interpolate_ms", "draw_ms", "measure_ms"}) {
            sum += row[s].get<double>();
        }
        EXPECT_LE(sum, row["frame_ms"].get<double>() * 1.0001 + 1e-3);
        EXPECT_GT(row["triangles"].get<double>(), 0.0);
    }
    const auto& f = j["frame_ms"];
    EXPECT_LE(f["median"].get<double>(), f["p95"].get<double>());
    EXPECT_LE(f["p95"].get<double>(), f["max"].get<double>());
    EXPECT_TRUE(fs::exists(dir / "report.csv"));
}

TEST(RunCommand, VideoThroughFfmpeg) {
    if (!test::onPath("ffmpeg")) GTEST_SKIP() << "no ffmpeg";
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, 16, 16);
    platform.reset();
    const fs::path dir = test::scratchDir("video");
    const auto r = test::runAmbience("run --replay " + kReplay +
                                     " --size 64x36 --max-frames 4 "
                                     "--frames none --out " +
                                     dir.string() + " --video " + (dir / "v.mp4").string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    EXPECT_GT(fs::file_size(dir / "v.mp4"), 100u);
}

void expectInputError(const std::string& args, const std::string& mentions) {
    const auto r = test::runAmbience(args);
    EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.err;
    EXPECT_EQ(test::lineCount(r.err), 1) << args << "\n" << r.err;
    EXPECT_NE(r.err.find(mentions), std::string::npos) << args << "\n" << r.err;
}

TEST(RunCommand, BadInputIsOneLineAndExitCode2) {
    const fs::path dir = test::scratchDir("bad");
    expectInputError("run --replay " + kReplay + " --backend vulkan", "vulkan");
    expectInputError("run --replay " + kReplay + " --size 0x0", "--size");
    expectInputError("run --replay " + kReplay + " --size 100000x100000", "--size");
    expectInputError("run --replay " + kReplay + " --size banana", "--size");
    expectInputError("run --replay " + kReplay + " --ambient purple", "purple");
    expectInputError("run --replay " + (dir / "missing.json").string(), "missing.json");
    std::ofstream(dir / "broken.json") << "{\"format\": \"ambience-replay\", \"version\": 1, ";
    expectInputError("run --replay " + (dir / "broken.json").string(), "broken.json");
    expectInputError("run --replay " + kReplay + " --out /proc/ambience-cannot-write", "--out");
    expectInputError("run --no-such-option", "no-such-option");
    expectInputError("run --replay " + kReplay + " --camera drone", "--camera");
    expectInputError("run --replay " + kReplay + " --exposure bright", "--exposure");
    expectInputError("compare --replay " + kReplay + " --camera drone", "--camera");
    expectInputError("probe --at 1,2 --out " + (dir / "p.exr").string() + " --time 30", "--time");
    expectInputError("probe --at nowhere --out " + (dir / "p.exr").string(), "--at");
}

TEST(ProbeCommand, WritesAVerticalStripExr) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, 16, 16);
    platform.reset();
    const fs::path dir = test::scratchDir("probe");
    const fs::path out = dir / "probe.exr";
    const auto r = test::runAmbience("probe --at 100,-250 --height 3 --time 12 --size 8 --out " +
                                     out.string());
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const CubeMapImage cube = readCubeMap(out.string());
    EXPECT_EQ(cube.n, 8);
    ASSERT_EQ(cube.rgb.size(), size_t(6 * 8 * 8 * 3));
    // +Y (face 2) holds the noon sky and the sun: brighter on average than -Y (face 3).
    double up = 0.0, down = 0.0;
    for (int t = 0; t < 64; ++t) {
        up += cube.rgb[(2 * 64 + t) * 3 + 1];
        down += cube.rgb[(3 * 64 + t) * 3 + 1];
    }
    EXPECT_GT(up, down);
}

// An --out no image format writes is refused before any work: with an empty shader folder, the
// capture (or the GL context before it) would fail first with another error.
TEST(ProbeCommand, OutputFormatIsCheckedBeforeAnyWork) {
    const fs::path dir = test::scratchDir("probe-out");
    fs::create_directories(dir / "no-shaders");
    const std::string shaders = " --shaders " + (dir / "no-shaders").string();
    const auto r = test::runAmbience("probe --at 1,2 --size 4" + shaders + " --out " +
                                     (dir / "p.txt").string());
    EXPECT_EQ(r.exitCode, 2) << r.err;
    EXPECT_EQ(test::lineCount(r.err), 1) << r.err;
    EXPECT_EQ(r.err.rfind("ambience: error: --out: ", 0), 0u) << r.err;
    EXPECT_NE(r.err.find("'.txt'"), std::string::npos) << r.err;
    expectInputError("probe --at 1,2 --size 4" + shaders + " --out " + (dir / "probe").string(),
                     "--out");
    // A missing folder, and a replay that cannot be read: the output is named first.
    expectInputError("probe --at 1,2" + shaders + " --out " + (dir / "none" / "p.exr").string(),
                     "--out");
    expectInputError("probe --at 1,2 --replay " + (dir / "missing.json").string() + shaders +
                         " --out " + (dir / "p.txt").string(),
                     "--out");
    EXPECT_FALSE(fs::exists(dir / "p.txt"));
    EXPECT_FALSE(fs::exists(dir / "probe"));
}

}  // namespace
}  // namespace amb
