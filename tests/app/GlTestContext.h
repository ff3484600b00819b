// GlTestContext.h — a headless GL context for render tests; the test skips, with the platform's
// reason, when the backend is not available on this machine.
#pragma once

#include <cmath>
#include <memory>
#include <string>

#include "app/platform/Platform.h"
#include "world/Vegetation.h"
#include "world/World.h"

namespace amb::test {

inline std::unique_ptr<Platform> tryPlatform(Backend backend, int w, int h, std::string* why) {
    try {
        return createOffscreenPlatform(backend, w, h);
    } catch (const PlatformUnavailable& e) {
        *why = e.what();
        return nullptr;
    }
}

// An open, nearly flat, dry spot: no plant within `clear_m`, normal.y > 0.98, above the water.
inline glm::dvec3 openGround(const World& world, double clear_m = 25.0) {
    for (int r = 0; r < 60; ++r) {
        for (int a = 0; a < 8 * (r + 1); ++a) {
            const double angle = 2.0 * 3.14159265358979 * a / (8 * (r + 1));
            const double x = 50.0 * r * std::cos(angle), z = 50.0 * r * std::sin(angle);
            const GroundSample g = world.sample(x, z);
            if (g.normal.y < 0.97 || g.height_m < world.settings().waterLevel_m + 3.0) continue;
            if (g.material != Material::Grass) continue;
            if (!world.vegetation().inDisc(x, z, clear_m).empty()) continue;
            return {x, g.height_m, z};
        }
    }
    return {0.0, world.height(0.0, 0.0), 0.0};
}

}  // namespace amb::test

// Declares `platform` or skips the test.
#define AMB_REQUIRE_PLATFORM(platform, backend, w, h)                        \
    std::string platform##Why;                                               \
    auto platform = ::amb::test::tryPlatform(backend, w, h, &platform##Why); \
    if (!platform) GTEST_SKIP() << platform##Why
