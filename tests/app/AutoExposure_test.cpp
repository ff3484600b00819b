// AutoExposure_test.cpp — eye adaptation: on a constant scene the adapted luminance approaches
// the scene's as exp(-t / tau) (to 1e-9 in log), and with darkening 0 the mean before the tone
// curve converges to the key; one metering per frame; a scene as bright as noon keeps the fixed
// noon exposure; and a rendered night frame (00:00, moonlit) is readable with it (mean above
// 12/255) where the fixed exposure leaves it black (below 3/255).
#include "app/render/AutoExposure.h"

#include <cmath>
#include <numeric>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "GlTestContext.h"
#include "app/frame/SkyLighting.h"
#include "app/render/Renderer.h"
#include "world/Error.h"
#include "world/World.h"

namespace amb {
namespace {

TEST(AutoExposure, ConvergesExponentiallyToTheKey) {
    AutoExposureSettings s;
    s.tau_s = 0.8;
    s.darkening = 0.0;
    const float noon = 2e-3f;
    AutoExposure ae(s, noon);
    const double l0 = 5.0 * ae.referenceLuminance(), l1 = 1e-3 * ae.referenceLuminance();
    ae.update(0.0, 12.0, false, [&] { return std::log(l0); });  // the first frame: at rest at l0
    EXPECT_NEAR(ae.adaptedLuminance(), l0, 1e-9 * l0);
    const double dt = 1.0 / 30.0;
    int meterCalls = 0;
    for (int i = 1; i <= 300; ++i) {
        const double t = i * dt;
        const float e = ae.update(t, 12.0, false, [&] {
            ++meterCalls;
            return std::log(l1);
        });
        // Twice in a frame: the same exposure, no second metering.
        EXPECT_EQ(ae.update(t, 12.0, false, [&] { return 0.0 * ++meterCalls; }), e);
        const double expected = std::log(l1) + (std::log(l0) - std::log(l1)) * std::exp(-t / s.tau_s);
        ASSERT_NEAR(std::log(ae.adaptedLuminance()), expected, 1e-9) << "t " << t;
        // The mean before the curve, exposure x scene, in log approaches log(key) the same way.
        ASSERT_NEAR(std::log(double(e) * l1) - std::log(s.key),
                    std::log(l1 / ae.adaptedLuminance()), 1e-6);
    }
    EXPECT_EQ(meterCalls, 300);
    // After 12.5 time constants the mean is the key to 1e-4 (relative).
    EXPECT_NEAR(double(ae.exposure()) * l1, s.key, 1e-4 * s.key);
    // A cut starts afresh at the metered scene.
    ae.update(100.0, 12.0, true, [&] { return std::log(l0); });
    EXPECT_NEAR(ae.adaptedLuminance(), l0, 1e-9 * l0);
}

TEST(AutoExposure, NoonSceneKeepsTheFixedExposureAndDarkScenesStayDarker) {
    AutoExposureSettings s;  // defaults, darkening > 0
    const float noon = 3e-3f;
    const AutoExposure ae(s, noon);
    EXPECT_NEAR(ae.exposureFor(ae.referenceLuminance()), noon, 1e-6 * noon);
    // A night 10^-6 as bright: brightened, but its mean before the curve stays below the key by
    // (10^-6)^darkening; the range is clamped.
    const double night = 1e-6 * ae.referenceLuminance();
    EXPECT_NEAR(ae.exposureFor(night) * night, s.key * std::pow(1e-6, s.darkening), 1e-9);
    EXPECT_EQ(ae.exposureFor(1e-30), ae.exposureFor(s.minRelative * ae.referenceLuminance()));
    EXPECT_TRUE(parseExposure("auto", "--exposure"));
    EXPECT_FALSE(parseExposure("fixed", "--exposure"));
    EXPECT_THROW(parseExposure("bright", "--exposure"), InputError);
}

// Mean of an 8-bit RGB image, in [0, 255].
double meanByte(const std::vector<unsigned char>& rgb) {
    return std::accumulate(rgb.begin(), rgb.end(), 0.0) / double(rgb.size());
}

TEST(AutoExposure, NightFrameIsReadable) {
    constexpr int kW = 160, kH = 96;
    AMB_REQUIRE_PLATFORM(platform, Backend::Egl, kW, kH);
    const World world(WorldSettings{});
    CameraSample c;
    c.position_m = test::openGround(world) + glm::dvec3(0.0, 2.0, 0.0);
    c.forward = glm::normalize(glm::dvec3(0.0, -0.15, -1.0));
    c.up = glm::normalize(glm::cross(glm::cross(c.forward, glm::dvec3(0, 1, 0)), c.forward));
    double mean[2] = {0.0, 0.0};
    for (int automatic = 0; automatic < 2; ++automatic) {
        RenderSettings rs;
        rs.width = kW;
        rs.height = kH;
        rs.exposure.enabled = automatic == 1;
        Renderer renderer(world, rs);
        const SkyLighting& sky = renderer.setTimeOfDay(0.0);
        const FixedAmbient ambient(AmbientMode::Hemisphere, sky);
        renderer.setViewState({0.0, true, std::nullopt});
        renderer.render(c, ambient);
        mean[automatic] = meanByte(renderer.readRgb8());
        // Tone mapping an image again uses the frame's exposure: the same bytes.
        const std::vector<unsigned char> again = renderer.tonemap(renderer.readHdr());
        EXPECT_NEAR(meanByte(again), mean[automatic], 0.5);
    }
    EXPECT_LT(mean[0], 3.0);   // fixed: black
    EXPECT_GT(mean[1], 12.0);  // auto: readable
}

}  // namespace
}  // namespace amb
