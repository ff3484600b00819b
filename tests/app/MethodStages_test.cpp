// MethodStages_test.cpp — `ambience run` with the dynamic ambience volume: probes are
// captured at the budget, anchors enter the store, the report accounts for them, the store
// saves to .vdb and warm-starts a later run, and bad volume options are input errors.
#include <cmath>
#include <fstream>
#include <string>

#include <OpenImageIO/imagebuf.h>
#include <glm/geometric.hpp>
#include <glm/vec3.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "RunAmbience.h"
#include "app/frame/MethodStages.h"

namespace amb {
namespace {

using test::runAmbience;
using test::sourcePath;

nlohmann::json readJson(const std::string& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in);
}

const std::string kReplay = sourcePath("replays/highway-drive.json");

// A method whose SH varies with the point, to compare the batch with single lookups.
class SlopedMethod final : public AmbienceMethod {
  public:
    std::string methodName() const override { return "sloped"; }
    void predictStage(const glm::dvec3&, const glm::dvec3&, double, double) override {}
    void captureStage() override {}
    void storeStage() override {}
    ShRgb shAt(double x, double z) const override {
        ShRgb sh;
        for (int k = 0; k < kShCoefficients; ++k)
            sh.c[k] = glm::vec3(float(1.0 + 0.01 * x), float(0.5 - 0.002 * z), 0.1f * float(k));
        return sh;
    }
    MethodStatistics methodStatistics() const override { return {}; }
};

// The renderer's terrain corners go through the batch: the same values as one by one, and the
// same lookup count.
TEST(MethodAmbient, CornerBatchEqualsSingleLookups) {
    SlopedMethod method;
    MethodAmbient single(method), batch(method);
    std::vector<glm::dvec3> at, normal;
    for (int i = 0; i < 50; ++i) {
        at.push_back({3.7 * i, 1.0, -2.1 * i});
        normal.push_back(glm::normalize(glm::dvec3(0.1 * (i % 5), 1.0, -0.05 * i)));
    }
    std::vector<glm::vec3> out(at.size());
    batch.cornerIrradianceBatch(at.size(), at.data(), normal.data(), out.data());
    for (std::size_t i = 0; i < at.size(); ++i) {
        const glm::vec3 e = single.cornerIrradiance(at[i], normal[i]);
        EXPECT_EQ(e, out[i]) << i;
    }
    EXPECT_EQ(batch.lookups(), at.size());
    EXPECT_EQ(single.lookups(), at.size());
}

TEST(VolumeRun, CapturesStoresAndReports) {
    const std::string dir = testing::TempDir() + "volume_run";
    const std::string vdb = dir + "/anchors.vdb";
    // 60 frames at one face per frame: 10 complete probes, and the first frame's prime of four
    // whole probes (lighting/CaptureCore.h).
    const test::CommandResult r =
        runAmbience("run --replay " + kReplay + " --ambient volume --max-frames 60 --size 160x90"
                    " --frames none --no-video --out " + dir + " --save-anchors " + vdb);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto report = readJson(dir + "/report.json");
    EXPECT_EQ(report["ambient"], "volume");
    const auto& a = report["ambience"];
    EXPECT_EQ(a["primeFaces"].get<int>(), 24);
    EXPECT_EQ(a["facesCaptured"].get<int>(), 60 + 24);
    EXPECT_EQ(a["probesCompleted"].get<int>(), 10 + 4);
    EXPECT_EQ(a["rejectedProbes"].get<int>(), 0);
    EXPECT_EQ(a["anchorsEnd"].get<int>(), 10 + 4);  // nothing expires within 2 s at time rate 1
    EXPECT_GT(a["bytesEnd"].get<double>(), 0.0);
    EXPECT_GT(a["captureTrianglesPerFace"].get<int>(), 0);
    const double share = a["shareOfFrameTime"].get<double>();
    EXPECT_GT(share, 0.0);
    EXPECT_LT(share, 1.0);
    // Per frame: one face each (the first, the prime's 24 besides), anchors never decrease on
    // this short drive, all finite; the anchors per level add up to the anchors held.
    std::size_t previous = 0;
    bool first = true;
    for (const auto& row : report["frames"]) {
        EXPECT_EQ(row["facesCaptured"].get<int>(), first ? 25 : 1);
        first = false;
        const std::size_t anchors = row["anchors"].get<std::size_t>();
        EXPECT_GE(anchors, previous);
        previous = anchors;
        EXPECT_TRUE(std::isfinite(row["frame_ms"].get<double>()));
        std::size_t sum = 0;
        for (const auto& n : row["anchorsPerLevel"]) sum += n.get<std::size_t>();
        EXPECT_EQ(sum, anchors);
        EXPECT_GE(row["volumeProject_ms"].get<double>(), 0.0);
    }
    std::ifstream file(vdb, std::ios::binary);
    ASSERT_TRUE(file.good()) << "no anchor file " << vdb;
    char magic[4] = {};
    file.read(magic, 4);
    EXPECT_EQ(static_cast<unsigned char>(magic[0]), 0x20);  // OpenVDB's magic number 0x56444220
    EXPECT_EQ(std::string(magic + 1, 3), "BDV");

    // Warm start: the loaded anchors are there from the first frame.
    const std::string dir2 = testing::TempDir() + "volume_run_warm";
    const test::CommandResult w =
        runAmbience("run --replay " + kReplay + " --max-frames 2 --size 160x90 --frames none"
                    " --no-video --out " + dir2 + " --load-anchors " + vdb);
    ASSERT_EQ(w.exitCode, 0) << w.err;
    const auto warm = readJson(dir2 + "/report.json");
    EXPECT_GE(warm["frames"][0]["anchors"].get<int>(), 10);
}

// Reads frame 60 of a short drive at 320x180 (RGB, top row first).
std::vector<unsigned char> driveFrame(const std::string& name, const std::string& extra) {
    const std::string dir = testing::TempDir() + name;
    const test::CommandResult r = runAmbience(
        "run --replay " + kReplay + " --max-frames 61 --every 60 --size 320x180 --no-video"
        " --out " + dir + " " + extra);
    EXPECT_EQ(r.exitCode, 0) << r.err;
    OIIO::ImageBuf image(dir + "/frames/frame-00060.png");
    std::vector<unsigned char> px(320 * 180 * 3);
    EXPECT_TRUE(image.get_pixels(OIIO::ROI(0, 320, 0, 180, 0, 1, 0, 3), OIIO::TypeDesc::UINT8,
                                 px.data()))
        << dir;
    return px;
}

// On a drive the camera's own blue car shows, lit by the volume (not black, not saturated): seen
// from behind at the middle of the image with the chase camera (the default), as the bonnet at
// the bottom centre with --camera hood; without it the grey road is there.
TEST(VolumeRun, DriveShowsTheLitVehicle) {
    auto at = [](const std::vector<unsigned char>& px, int x, int y) {
        const std::size_t i = (std::size_t(y) * 320 + x) * 3;
        return glm::ivec3(px[i], px[i + 1], px[i + 2]);
    };
    auto expectBlue = [](const glm::ivec3& c) {
        EXPECT_GT(c.b, 2 * c.r) << c.r << "," << c.g << "," << c.b;
        EXPECT_GT(c.b, c.g) << c.r << "," << c.g << "," << c.b;
        EXPECT_GT(c.b, 30);
        EXPECT_LT(c.b, 255);
    };
    auto expectGrey = [](const glm::ivec3& c) {
        EXPECT_LT(std::abs(c.r - c.g), 30) << c.r << "," << c.g << "," << c.b;
        EXPECT_LT(std::abs(c.b - c.g), 30) << c.r << "," << c.g << "," << c.b;
    };
    const std::vector<unsigned char> chase = driveFrame("vehicle_chase", "");
    expectBlue(at(chase, 160, 118));  // the car's back, under its rear window
    expectGrey(at(chase, 160, 172));  // the road behind it
    expectBlue(at(driveFrame("vehicle_hood", "--camera hood"), 160, 172));  // the bonnet
    const std::vector<unsigned char> none = driveFrame("vehicle_off", "--no-vehicle");
    expectGrey(at(none, 160, 118));
    expectGrey(at(none, 160, 172));
}

// The overlay marks anchors on the frame and changes nothing else: the same run with and
// without it differs only in a small share of pixels.
TEST(VolumeRun, DebugOverlayMarksAnchors) {
    const auto plain = driveFrame("overlay_off", "");
    const auto marked = driveFrame("overlay_on", "--debug-overlay");
    int differing = 0;
    for (std::size_t p = 0; p < plain.size(); p += 3) {
        differing += plain[p] != marked[p] || plain[p + 1] != marked[p + 1] ||
                     plain[p + 2] != marked[p + 2];
    }
    EXPECT_GT(differing, 9);               // at least one marker (3 x 3 px or more)
    EXPECT_LT(differing, 320 * 180 / 20);  // markers, not a different picture
}

// The stress flight's camera cut (at 37.37 s) lies between two frames when frames are 30 replay
// steps apart; the volume must still see it as a teleport, and stay finite through it.
TEST(VolumeRun, CutBetweenFramesIsATeleport) {
    const std::string dir = testing::TempDir() + "volume_cut";
    const test::CommandResult r = runAmbience(
        "run --replay " + sourcePath("replays/stress-flight.json") +
        " --stride 30 --max-frames 80 --size 160x90 --frames none --no-video --out " + dir);
    ASSERT_EQ(r.exitCode, 0) << r.err;
    const auto report = readJson(dir + "/report.json");
    EXPECT_EQ(report["ambience"]["teleports"].get<int>(), 1);
    EXPECT_EQ(report["ambience"]["rejectedProbes"].get<int>(), 0);
}

TEST(VolumeRun, BadVolumeOptionsAreInputErrors) {
    const std::string dir = testing::TempDir() + "volume_bad";
    auto expect2 = [&](const std::string& args, const char* fragment) {
        const test::CommandResult r = runAmbience("run --replay " + kReplay +
                                                  " --max-frames 1 --frames none --no-video --out " +
                                                  dir + " " + args);
        EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.err;
        EXPECT_EQ(r.errLines(), 1) << r.err;
        EXPECT_NE(r.err.find(fragment), std::string::npos) << r.err;
    };
    expect2("--load-anchors /nonexistent/a.vdb", "/nonexistent/a.vdb");
    expect2("--faces-per-frame 25", "expected 1 to 24");
    expect2("--faces-per-frame 0", "--faces-per-frame");
    const std::string config = testing::TempDir() + "volume_bad_config.json";
    std::ofstream(config) << "{\"facesPerFrame\": 1, \"noSuchSetting\": 3}";
    expect2("--ambience-config " + config, "noSuchSetting");
    expect2("--ambient hemisphere --save-anchors x.vdb", "--ambient volume");
}

}  // namespace
}  // namespace amb
