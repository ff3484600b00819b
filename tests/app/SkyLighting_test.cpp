// SkyLighting_test.cpp — the sky a frame draws with (app/frame/SkyLighting.h) and the scene the
// probes' fallback shows (lighting/ProbeEnvironment.h) are one sky over one ground: the
// texture's lower half is the flat ground of albedo kGroundAlbedo lit by the sky, the sun and the
// moon (world/SkyGround.h), its upper half the sky model, and the fallback cube map's downward
// face shows the same ground to within the two quadratures' difference; the hemisphere ambient
// is built from those means.
#include "app/frame/SkyLighting.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "lighting/ProbeEnvironment.h"
#include "world/Conventions.h"
#include "world/Sky.h"
#include "world/SkyGround.h"
#include "world/World.h"

namespace amb {
namespace {

double relative(const glm::dvec3& a, const glm::dvec3& b) {
    return glm::length(a - b) / std::max(glm::length(b), 1e-30);
}

TEST(SkyLighting, LowerHalfIsTheGroundOfTheConventionsAlbedo) {
    const World world(WorldSettings{});
    for (double t_h : {7.0, 12.0, 17.5, 23.0}) {
        const SkyLighting s = evaluateSky(world.sky(), t_h);
        const SkyGround g = groundUnder(world.sky(), t_h, glm::dvec3(s.skyIrradianceUp));
        // The ground radiance is kGroundAlbedo / pi of what lights it, to float rounding.
        EXPECT_LT(relative(glm::dvec3(s.groundMean), g.ground), 1e-5) << t_h;
        EXPECT_LT(relative(g.ground, g.groundIrradiance * (double(kGroundAlbedo) / kPi)), 1e-12);
        // Every texel below the horizon shows it; every texel above it, the sky model.
        const int w = SkyLighting::kWidth, h = SkyLighting::kHeight;
        const SkyState state = world.sky().state(t_h);
        for (int r = 0; r < h; ++r) {
            const double theta = (r + 0.5) * kPi / h;
            for (int c = 0; c < w; c += 9) {
                const double phi = ((c + 0.5) / w - 0.5) * 2.0 * kPi;
                const glm::dvec3 d(std::sin(theta) * std::sin(phi), std::cos(theta),
                                   -std::sin(theta) * std::cos(phi));
                const float* texel = &s.texture[(std::size_t(r) * w + c) * 3];
                const glm::dvec3 got(texel[0], texel[1], texel[2]);
                const glm::dvec3 want =
                    r < h / 2 ? glm::dvec3(world.sky().radiance(d, state)) : g.ground;
                EXPECT_LT(relative(got, want), 1e-6) << "row " << r << " at " << t_h << " h";
            }
        }
    }
}

TEST(SkyLighting, TheFallbackSeesTheSameGround) {
    const World world(WorldSettings{});
    const WorldProbeEnvironment environment(world);
    for (double t_h : {9.0, 12.0, 16.0}) {
        const SkyLighting s = evaluateSky(world.sky(), t_h);
        const int n = 16;
        std::vector<float> cube;
        environment.fallbackCubeMap(t_h, n, cube);
        // Face -Y (3) looks straight down: all ground.
        const float* texel = &cube[std::size_t(3 * n * n + n * n / 2 + n / 2) * 3];
        const glm::dvec3 fallbackGround(texel[0], texel[1], texel[2]);
        // The two E_sky(up) come from different quadratures (a 64 x 32 equirect against a
        // 16 x 16 cube): they agree to about a per cent.
        EXPECT_LT(relative(glm::dvec3(s.groundMean), fallbackGround), 0.02) << t_h << " h";
    }
}

TEST(SkyLighting, HemisphereAmbientIsSkyAboveGroundBelow) {
    const World world(WorldSettings{});
    const SkyLighting s = evaluateSky(world.sky(), 12.0);
    const FixedAmbient hemisphere(AmbientMode::Hemisphere, s);
    // E(n) = pi/2 ((sky + ground) + (sky - ground) n.y): up sees pi x sky, down pi x ground.
    const glm::vec3 up = hemisphere.cornerIrradiance({}, {0, 1, 0});
    const glm::vec3 down = hemisphere.cornerIrradiance({}, {0, -1, 0});
    EXPECT_LT(relative(glm::dvec3(up), glm::dvec3(s.skyMean) * kPi), 0.02);
    EXPECT_LT(relative(glm::dvec3(down), glm::dvec3(s.groundMean) * kPi), 0.02);
}

}  // namespace
}  // namespace amb
