// PlantSky_test.cpp — the plants put back by the near field take only the share of the sky the
// other plants leave them (lighting/NearField.h "Plants' sky"): a cap's ambient scales with its
// share while its light term does not, the near field asks the scene once per sphere, and in the
// generated world a crown's lowest sphere under its own upper tiers or among neighbours sees
// less sky than a lone crown's top.
#include "lighting/NearField.h"

#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "TwoSpherePlant.h"
#include "world/Conventions.h"
#include "world/Vegetation.h"
#include "world/World.h"

namespace amb {
namespace {

SphereOccluder sphere(const glm::dvec3& centre, double radius, double sky) {
    SphereOccluder o;
    o.centre_m = centre, o.radius_m = radius, o.albedo = glm::dvec3(0.3, 0.4, 0.2);
    o.skyVisibility = sky;
    return o;
}

// Two caps with a sky share V: what T shows (T_c - hide) is V times what it showed and the light
// term S is the same as with full shares; with unequal shares the light's total is kept.
TEST(PlantSky, TheAmbientScalesWithTheShareAndTheLightTermDoesNot) {
    const glm::dvec3 light = glm::normalize(glm::dvec3(-0.6, 0.7, -0.2));
    const auto build = [&](double va, double vb) {
        NearFieldTransfer t = nearFieldTransfer(occluderCaps(
            glm::dvec3(0.0), {sphere({6.0, 2.0, 1.0}, 1.5, va), sphere({-7.0, 1.0, 2.0}, 2.0, vb)}));
        const std::vector<OccluderCap> caps = occluderCaps(
            glm::dvec3(0.0), {sphere({6.0, 2.0, 1.0}, 1.5, va), sphere({-7.0, 1.0, 2.0}, 2.0, vb)});
        t.capSun = float(capSunVisibility(caps, light));
        updateLightTerm(t, light, {});
        return t;
    };
    const NearFieldTransfer full = build(1.0, 1.0), half = build(0.5, 0.5), one = build(0.25, 1.0);
    constexpr int K = kShCoefficients;
    for (int ch = 0; ch < 3; ++ch) {
        for (int k = 0; k < K; ++k) {
            EXPECT_NEAR(half.s[ch][k], full.s[ch][k], 1e-5f + 1e-4f * std::fabs(full.s[ch][k]));
            for (int j = 0; j < K; ++j) {
                const std::size_t at = std::size_t((k * K + j) * 4 + ch);
                const float showFull = full.columns[at] - full.hide[std::size_t(j * K + k)];
                const float showHalf = half.columns[at] - half.hide[std::size_t(j * K + k)];
                EXPECT_NEAR(showHalf, 0.5f * showFull, 1e-6f);
            }
        }
    }
    // Unequal shares: the one share keeps the light's total (band 0, each cap's f_i being its
    // light's band 0 within the phase law's order-2 projection), not how it splits between caps.
    for (int ch = 0; ch < 3; ++ch)
        EXPECT_NEAR(one.s[ch][0], full.s[ch][0], 0.03f * std::fabs(full.s[ch][0]));
    EXPECT_EQ(half.hide, full.hide);  // what the caps hide does not depend on their light
    EXPECT_GT(std::fabs(full.s[1][0]), 1e-4f);  // the sun does show
    // With different shares the caps' one share of the light is sum f s / sum f V.
    EXPECT_GT(capSunVisibility(occluderCaps(glm::dvec3(0.0), {sphere({6.0, 2.0, 1.0}, 1.5, 0.25)}),
                               light),
              3.99);
}

// With no light, what the caps add through the normal facing them is their ambient: with a share
// of 0.4 it is 0.4 of what it is with the share off; the scene is asked once a sphere.
TEST(PlantSky, TheNearFieldTakesEachSpheresShareOnce) {
    NearFieldSettings on, off;
    on.ground = off.ground = false;
    off.plantSky = false;
    const glm::dvec3 p(0.0, 2.0, 0.0);
    ShRgb far{};
    far.c[0] = glm::vec3(2.0f);
    far.c[2] = glm::vec3(0.8f);  // brighter above
    const glm::vec3 n(1.0f, 0.0f, 0.0f);
    const auto shown = [&](const NearFieldSettings& s, testing_support::TwoSpherePlant& scene) {
        NearField field(scene, s);
        field.setTimeOfDay(12.0);
        const ShRgb out = field.apply(far, p);
        field.apply(far, p + glm::dvec3(0.0, 0.0, 0.5));  // another point: the spheres are known
        // What the caps show: the answer less the far field with the caps' hide alone, i.e. the
        // answer with albedo 0 (the share scales the albedo's part only).
        return double(shIrradiance(out, n).y);
    };
    testing_support::TwoSpherePlant a, b, dark;
    for (testing_support::TwoSpherePlant* plant : {&a, &b, &dark}) {
        plant->albedo = glm::dvec3(0.3, 0.4, 0.2);
        plant->skyShare = 0.4;
        plant->lightIrradiance = 0.0;  // the caps show their ambient alone
    }
    const double withShare = shown(on, a), without = shown(off, b);
    EXPECT_EQ(a.skyAsked, 2);  // two spheres, two points: asked once each
    EXPECT_EQ(b.skyAsked, 0);  // off: never asked
    // The part the albedo adds, with and without the share: a plant of the same spheres lit by
    // nothing (share 0) gives the hidden far field alone.
    dark.skyShare = 0.0;
    NearFieldSettings darkOn = on;
    const double hidden = shown(darkOn, dark);
    // kMinSkyVisibility keeps a little: compare the parts the albedo adds.
    const double partWith = withShare - hidden, partWithout = without - hidden;
    EXPECT_GT(partWithout, 1e-3);
    EXPECT_NEAR(partWith / partWithout, (0.4 - 0.0) / (1.0 - 0.0), 0.03);
}

const World& defaultWorld() {
    static const World world(WorldSettings{});
    return world;
}

// In the generated world: every share lies in [kMinSkyVisibility, 1]; a conifer's lowest crown
// sphere, under its own upper tiers, sees less sky than its top sphere; trunks under their crowns
// see little of it.
TEST(PlantSky, LowerTiersAndTrunksSeeLessSkyThanTops) {
    const World& world = defaultWorld();
    const WorldNearFieldScene scene(world);
    int conifers = 0, trunks = 0;
    for (const Plant& p : world.vegetation().inDisc(0.0, 0.0, 600.0)) {
        const std::vector<PlantSphere>& s = Vegetation::spheres(p.kind);
        const auto share = [&](std::size_t i) {
            return scene.sphereSkyVisibility(p.position_m + double(p.scale) * s[i].centre_m,
                                             double(p.scale) * s[i].radius_m);
        };
        if (p.kind == PlantKind::Conifer && conifers < 8) {
            const double low = share(0), top = share(2), trunk = share(3);
            EXPECT_GE(low, WorldNearFieldScene::kMinSkyVisibility);
            EXPECT_LE(top, 1.0);
            EXPECT_LT(low, top) << conifers;
            EXPECT_LT(trunk, 0.5) << conifers;
            ++conifers, ++trunks;
        }
    }
    EXPECT_EQ(conifers, 8);
    EXPECT_EQ(trunks, 8);
}

}  // namespace
}  // namespace amb
