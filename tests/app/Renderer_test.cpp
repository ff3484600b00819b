// Renderer_test.cpp — the main view on EGL and OSMesa: sky above the horizon and terrain below by
// pixel statistics against the sky model, and the two platforms agree (PSNR >= 40 dB).
#include "app/Renderer.h"

#include <cmath>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "GlTestContext.h"
#include "world/Conventions.h"
#include "world/Error.h"
#include "world/World.h"

namespace amb {
namespace {

constexpr int kW = 160, kH = 96;

// A camera 2 m above open ground, looking north and tilted by `pitch`.
CameraSample viewAt(const World& world, double pitch_rad) {
    CameraSample c;
    c.position_m = test::openGround(world) + glm::dvec3(0.0, 2.0, 0.0);
    c.forward = glm::dvec3(0.0, std::sin(pitch_rad), -std::cos(pitch_rad));
    c.up = glm::dvec3(0.0, std::cos(pitch_rad), std::sin(pitch_rad));
    return c;
}

struct Frame {
    std::vector<float> hdr;
    std::vector<unsigned char> ldr;
    SkyLighting sky;
};

Frame renderView(const World& world, double pitch_rad, double time_h) {
    RenderSettings rs;
    rs.width = kW;
    rs.height = kH;
    Renderer renderer(world, rs);
    Frame f;
    f.sky = renderer.setTimeOfDay(time_h);
    const FixedAmbient ambient(AmbientMode::Hemisphere, f.sky);
    renderer.render(viewAt(world, pitch_rad), ambient);
    f.hdr = renderer.readHdr();
    f.ldr = renderer.readRgb8();
    return f;
}

// Direction through the centre of pixel (x, y), y = 0 the top row, for the view above.
glm::dvec3 pixelDirection(const CameraSample& c, int x, int y) {
    const double tanHalf = std::tan(0.5 * 1.0471976);
    const double aspect = double(kW) / kH;
    const double sx = (2.0 * (x + 0.5) / kW - 1.0) * tanHalf * aspect;
    const double sy = (1.0 - 2.0 * (y + 0.5) / kH) * tanHalf;
    const glm::dvec3 right = glm::cross(c.forward, c.up);
    return glm::normalize(c.forward + sx * right + sy * c.up);
}

void expectSkyAboveTerrainBelow(Backend backend) {
    AMB_REQUIRE_PLATFORM(platform, backend, kW, kH);
    const World world(WorldSettings{});
    // Looking up 46 degrees: the top rows (64 to 76 degrees up) see only sky.
    {
        const double pitch = 0.8;
        const Frame f = renderView(world, pitch, 12.0);
        const CameraSample cam = viewAt(world, pitch);
        const SkyState state = world.sky().state(12.0);
        double maxRel = 0.0;
        int n = 0;
        for (int y = 0; y < kH / 5; ++y) {
            for (int x = 0; x < kW; x += 7) {
                const glm::dvec3 d = pixelDirection(cam, x, y);
                const glm::vec3 expected = world.sky().radiance(d, state);
                const float* got = &f.hdr[(size_t(y) * kW + x) * 3];
                for (int c = 0; c < 3; ++c) {
                    const double rel = std::abs(got[c] - expected[c]) / expected[c];
                    maxRel = std::max(maxRel, rel);
                }
                ++n;
            }
        }
        // The sky texture is 64 x 32 texels, bilinear; the model varies slowly away from the
        // sun (not in view here), so 10 % bounds the resampling error.
        EXPECT_LT(maxRel, 0.10) << "over " << n << " sky pixels";
    }
    // Looking down 35 degrees: the bottom rows see the ground, whose radiance is at most that of
    // a white Lambertian surface under the sun and the whole sky, and much less than the sky.
    {
        const double pitch = -0.6;
        const Frame f = renderView(world, pitch, 12.0);
        const glm::vec3 maxIrr = f.sky.lightIrradiance + f.sky.skyIrradianceUp * 2.0f;
        const float bound = (maxIrr.r + maxIrr.g + maxIrr.b) / float(kPi);
        double g = 0.0, b = 0.0;
        int above = 0;
        for (int y = kH - kH / 5; y < kH; ++y) {
            for (int x = 0; x < kW; ++x) {
                const float* p = &f.hdr[(size_t(y) * kW + x) * 3];
                if (p[0] + p[1] + p[2] > bound) ++above;
                g += p[1];
                b += p[2];
            }
        }
        EXPECT_EQ(above, 0) << "ground pixels brighter than a white Lambertian surface";
        // Grass: green over blue, unlike the sky (blue over green at noon).
        EXPECT_GT(g, b) << "the bottom band looks like sky";
        EXPECT_GT(g, 0.0);
    }
}

TEST(Renderer, EglSkyAboveTerrainBelow) {
    expectSkyAboveTerrainBelow(Backend::Egl);
}
TEST(Renderer, OsMesaSkyAboveTerrainBelow) {
    expectSkyAboveTerrainBelow(Backend::OsMesa);
}

double psnr(const std::vector<unsigned char>& a, const std::vector<unsigned char>& b) {
    double se = 0.0;
    for (size_t i = 0; i < a.size(); ++i) se += (double(a[i]) - b[i]) * (double(a[i]) - b[i]);
    const double mse = se / double(a.size());
    return mse == 0.0 ? 99.0 : 10.0 * std::log10(255.0 * 255.0 / mse);
}

TEST(Renderer, EglAndOsMesaAgree) {
    const World world(WorldSettings{});
    std::vector<unsigned char> egl, osmesa;
    {
        AMB_REQUIRE_PLATFORM(platform, Backend::Egl, kW, kH);
        egl = renderView(world, -0.1, 16.0).ldr;
    }
    {
        AMB_REQUIRE_PLATFORM(platform, Backend::OsMesa, kW, kH);
        osmesa = renderView(world, -0.1, 16.0).ldr;
    }
    ASSERT_EQ(egl.size(), osmesa.size());
    EXPECT_GE(psnr(egl, osmesa), 40.0);
}

TEST(Renderer, RejectsAbsurdSizes) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, 16, 16);
    const World world(WorldSettings{});
    RenderSettings rs;
    rs.width = 100000;
    rs.height = 100000;
    EXPECT_THROW(Renderer(world, rs), InputError);
    rs.width = 0;
    rs.height = 0;
    EXPECT_THROW(Renderer(world, rs), InputError);
}

}  // namespace
}  // namespace amb
