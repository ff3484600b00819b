// ViewCommand_test.cpp — the viewer runs under Xvfb for a few frames and saves a screenshot that
// is not blank (the pixels vary: sky, terrain, road and trees, not one clear colour); its tuning
// panel shows in the window (and not with --no-panel), and --config reads the settings file.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>
#include <filesystem>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>

#include "RunAmbience.h"

namespace amb {
namespace {

namespace fs = std::filesystem;

TEST(ViewCommand, RunsUnderXvfbAndSavesANonBlankScreenshot) {
    if (!test::onPath("xvfb-run")) {
        GTEST_SKIP() << "xvfb-run is not installed";
    }
    const fs::path dir = test::scratchDir("view");
    const fs::path shot = dir / "shot.png";
    const std::string replay = std::string(AMBIENCE_SOURCE_DIR) + "/replays/highway-drive.json";
    const auto r = test::runAmbience("view --replay " + replay +
                                         " --size 200x120 --frames 4 "
                                         "--screenshot " +
                                         shot.string(),
                                     "xvfb-run -a -s '-screen 0 640x480x24'");
    if (r.exitCode == 1 && r.err.find("glfw") != std::string::npos) {
        GTEST_SKIP() << "no GL window under Xvfb: " << r.err;
    }
    ASSERT_EQ(r.exitCode, 0) << r.err;
    auto in = OIIO::ImageInput::open(shot.string());
    ASSERT_TRUE(in);
    const OIIO::ImageSpec spec = in->spec();
    EXPECT_EQ(spec.width, 200);
    EXPECT_EQ(spec.height, 120);
    std::vector<unsigned char> px(size_t(spec.width) * spec.height * spec.nchannels);
    ASSERT_TRUE(in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::UINT8, px.data()));
    double mean = 0.0, var = 0.0;
    for (unsigned char v : px) mean += v;
    mean /= double(px.size());
    for (unsigned char v : px) var += (v - mean) * (v - mean);
    const double stddev = std::sqrt(var / double(px.size()));
    EXPECT_GT(mean, 10.0);
    EXPECT_LT(mean, 245.0);
    EXPECT_GT(stddev, 10.0) << "a blank image has (nearly) one value";
}

std::vector<unsigned char> readRgb(const fs::path& path, int& width, int& height) {
    auto in = OIIO::ImageInput::open(path.string());
    if (!in) return {};
    const OIIO::ImageSpec spec = in->spec();
    width = spec.width, height = spec.height;
    std::vector<unsigned char> px(size_t(spec.width) * spec.height * 3);
    if (!in->read_image(0, 0, 0, 3, OIIO::TypeDesc::UINT8, px.data())) return {};
    return px;
}

// Mean absolute difference over the columns [x0, x1).
double columnsDifference(const std::vector<unsigned char>& a, const std::vector<unsigned char>& b,
                         int width, int height, int x0, int x1) {
    double sum = 0.0;
    for (int y = 0; y < height; ++y)
        for (int x = x0; x < x1; ++x)
            for (int c = 0; c < 3; ++c) {
                const size_t i = (size_t(y) * width + x) * 3 + c;
                sum += std::abs(int(a[i]) - int(b[i]));
            }
    return sum / (double(x1 - x0) * height * 3.0);
}

TEST(ViewCommand, ThePanelShowsInTheWindowAndConfigReadsTheSettingsFile) {
    if (!test::onPath("xvfb-run")) {
        GTEST_SKIP() << "xvfb-run is not installed";
    }
    const fs::path dir = test::scratchDir("view-panel");
    const fs::path config = dir / "settings.json";
    std::ofstream(config) << "{\"store\": {\"blendTime_s\": 2}, \"facesPerFrame\": 2}";
    const std::string replay = std::string(AMBIENCE_SOURCE_DIR) + "/replays/highway-drive.json";
    const std::string common = "view --replay " + replay + " --size 640x360 --frames 3 ";
    const std::string xvfb = "xvfb-run -a -s '-screen 0 800x600x24'";
    const auto with = test::runAmbience(
        common + "--config " + config.string() + " --window-shot " + (dir / "with.png").string(),
        xvfb);
    if (with.exitCode == 1 && with.err.find("glfw") != std::string::npos) {
        GTEST_SKIP() << "no GL window under Xvfb: " << with.err;
    }
    ASSERT_EQ(with.exitCode, 0) << with.err;
    const auto without = test::runAmbience(
        common + "--no-panel --window-shot " + (dir / "without.png").string(), xvfb);
    ASSERT_EQ(without.exitCode, 0) << without.err;
    int w = 0, h = 0, w2 = 0, h2 = 0;
    const auto a = readRgb(dir / "with.png", w, h), b = readRgb(dir / "without.png", w2, h2);
    ASSERT_EQ(w, 640);
    ASSERT_EQ(h, 360);
    ASSERT_EQ(a.size(), b.size());
    // The panel is 400 px wide at the top left: there the windows differ; right of it both are
    // the same scene (the settings file changes the ambience, not the first frames' geometry,
    // so allow a little).
    EXPECT_GT(columnsDifference(a, b, w, h, 16, 380), 15.0);
    EXPECT_LT(columnsDifference(a, b, w, h, 430, 640), 3.0);

    // A settings file the reader refuses: one line naming it, exit code 2, before any window.
    const fs::path bad = dir / "bad.json";
    std::ofstream(bad) << "{\"store\": {\"levels\": 99}}";
    const auto refused = test::runAmbience(common + "--config " + bad.string(), xvfb);
    EXPECT_EQ(refused.exitCode, 2) << refused.err;
    EXPECT_NE(refused.err.find("bad.json"), std::string::npos) << refused.err;
    EXPECT_EQ(refused.errLines(), 1) << refused.err;
}

}  // namespace
}  // namespace amb
