// ViewCommand_test.cpp — the viewer runs under Xvfb for a few frames and saves a screenshot that
// is not blank (the pixels vary: sky, terrain, road and trees, not one clear colour).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <string>

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

}  // namespace
}  // namespace amb
