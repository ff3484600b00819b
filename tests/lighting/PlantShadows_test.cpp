// PlantShadows_test.cpp — the plants put back by the near field are lit by the light only where
// other plants and the terrain leave it (lighting/NearField.h "Plants' shadows"): the caps' one
// share weighs each cap by what it shows of the light, the light term scales with it and the
// ambient does not, the near field asks the scene once per sphere and light, and in the
// generated world a crown behind another or under a hill is shaded while one under open sky is
// not.
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

SphereOccluder sphere(const glm::dvec3& centre, double radius, double sunVisibility) {
    SphereOccluder o;
    o.centre_m = centre, o.radius_m = radius, o.albedo = glm::dvec3(0.3);
    o.sunVisibility = sunVisibility;
    return o;
}

// Two equal spheres seen from the origin at the same phase, one in shadow and one lit, share
// the light half and half; a third between the point and the light shows only its unlit side
// (phase 0) and does not count, whatever its share.
TEST(PlantShadows, TheCapsShareWeighsEachByWhatItShowsOfTheLight) {
    const glm::dvec3 light = glm::normalize(glm::dvec3(-1.0, 1.0, 0.0));
    const std::vector<SphereOccluder> two = {sphere({-1.0, 0.0, 10.0}, 2.0, 0.0),
                                             sphere({-1.0, 0.0, -10.0}, 2.0, 1.0)};
    EXPECT_NEAR(capSunVisibility(occluderCaps(glm::dvec3(0.0), two), light), 0.5, 1e-12);
    std::vector<SphereOccluder> three = two;
    three.push_back(sphere(light * 8.0, 1.0, 0.0));  // at new phase from the origin
    const std::vector<OccluderCap> caps = occluderCaps(glm::dvec3(0.0), three);
    ASSERT_EQ(caps.size(), 3u);
    EXPECT_NEAR(capSunVisibility(caps, light), 0.5, 1e-9);
    // All lit: exactly 1; a lone cap: its own share, however little it shows; no cap: 1.
    EXPECT_EQ(capSunVisibility(occluderCaps(glm::dvec3(0.0), {sphere({-1.0, 0.0, 10.0}, 2.0, 1.0)}),
                               light),
              1.0);
    EXPECT_NEAR(capSunVisibility(occluderCaps(glm::dvec3(0.0), {sphere({1.0, 0.5, 6.0}, 1.0, 0.7)}), light),
                0.7, 1e-12);
    EXPECT_EQ(capSunVisibility({}, light), 1.0);
}

// The share scales the light term S (and its value through a normal) and leaves T alone.
TEST(PlantShadows, TheLightTermScalesWithTheShareAndTheAmbientDoesNot) {
    const std::vector<OccluderCap> caps = occluderCaps(
        glm::dvec3(0.0), {sphere({3.0, 2.0, 1.0}, 1.5, 1.0), sphere({-4.0, 1.0, 2.0}, 2.0, 1.0)});
    const glm::dvec3 light = glm::normalize(glm::dvec3(-0.6, 0.7, -0.2));
    NearFieldTransfer lit = nearFieldTransfer(caps), shaded = lit;
    shaded.capSun = 0.25f;
    updateLightTerm(lit, light, {});
    updateLightTerm(shaded, light, {});
    for (int ch = 0; ch < 3; ++ch)
        for (int k = 0; k < kShCoefficients; ++k)
            EXPECT_NEAR(shaded.s[ch][k], 0.25f * lit.s[ch][k], 1e-7f) << ch << " " << k;
    EXPECT_EQ(shaded.columns, lit.columns);
    EXPECT_GT(std::fabs(lit.s[1][0]), 1e-4f);  // the sun does show
    const glm::dvec3 n = glm::normalize(glm::dvec3(0.2, 1.0, 0.1));
    NormalTransfer a = normalTransfer(&lit, n), b = normalTransfer(&shaded, n);
    updateLightTerm(a, light, {}, 1), updateLightTerm(b, light, {}, 1);
    EXPECT_NEAR(b.light.y, 0.25f * a.light.y, 1e-7f);
    EXPECT_EQ(a.show, b.show);
    // A patch mean's share is its samples' weighted mean.
    const NormalTransfer* samples[2] = {&a, &b};
    const double weights[2] = {0.75, 0.25};
    EXPECT_NEAR(meanNormalTransfer(samples, weights, 2).capSun, 0.75 + 0.25 * 0.25, 1e-7);
}

// What the near field adds of the light at `p` (green, through the normal facing the plant):
// the answer with the light less the one without.
double lightPart(const NearFieldSettings& settings, const glm::dvec3& p, double share, int* asked) {
    testing_support::TwoSpherePlant withLight, dark;
    withLight.sunShare = dark.sunShare = share;
    dark.lightIrradiance = 0.0;
    NearField a(withLight, settings), b(dark, settings);
    a.setTimeOfDay(16.0), b.setTimeOfDay(16.0);  // 30 degrees up, behind the point
    ShRgb far{};
    far.c[0] = glm::vec3(2.0f);
    const glm::vec3 n(1.0f, 0.0f, 0.0f);
    const double e = double(shIrradiance(a.apply(far, p), n).y - shIrradiance(b.apply(far, p), n).y);
    if (asked) {
        a.apply(far, p + glm::dvec3(0.5, 0.0, 0.0));  // another point: the spheres are known
        *asked = withLight.sunAsked;
    }
    return e;
}

TEST(PlantShadows, TheNearFieldTakesEachSpheresShareOnceForALight) {
    NearFieldSettings on, off;
    on.ground = off.ground = false;
    off.plantShadows = false;
    const glm::dvec3 p(0.0, 2.0, 0.0);
    int asked = 0;
    const double shaded = lightPart(on, p, 0.3, &asked);
    const double open = lightPart(off, p, 0.3, nullptr);
    EXPECT_GT(std::fabs(open), 1e-3) << shaded;
    EXPECT_NEAR(shaded, 0.3 * open, 1e-4 * std::fabs(open) + 1e-6);
    EXPECT_EQ(asked, 2);  // two spheres, two points: asked once each
    // The light moved by more than half a degree: asked again.
    testing_support::TwoSpherePlant scene;
    scene.sunShare = 0.3;
    NearField field(scene, on);
    ShRgb far{};
    far.c[0] = glm::vec3(1.0f);
    field.setTimeOfDay(16.0);
    field.apply(far, p);
    field.setTimeOfDay(16.5);
    field.apply(far, p + glm::dvec3(0.0, 0.0, 0.5));
    EXPECT_EQ(scene.sunAsked, 4);
}

const World& defaultWorld() {
    static const World world(WorldSettings{});
    return world;
}

// In the generated world: a broadleaf crown whose light passes through another crown first is
// mostly shaded, the top sphere of a conifer under a high sun with nothing above it is lit, and
// a light below the terrain's horizon leaves every sphere dark.
TEST(PlantShadows, ACrownBehindAnotherIsShadedAndOneUnderOpenSkyIsLit) {
    const World& world = defaultWorld();
    const WorldNearFieldScene scene(world);
    const std::vector<Plant> plants = world.vegetation().inDisc(0.0, 0.0, 600.0);
    const auto crown = [](const Plant& p) {
        const PlantSphere& s = Vegetation::spheres(p.kind)[0];
        return std::make_pair(p.position_m + double(p.scale) * s.centre_m, double(p.scale) * s.radius_m);
    };
    int pairs = 0, conifers = 0;
    for (const Plant& a : plants) {
        if (a.kind != PlantKind::Broadleaf && a.kind != PlantKind::Conifer) continue;
        const auto [ca, ra] = crown(a);
        // High sun over a conifer's top sphere (3 spheres: the last crown one is the top).
        if (a.kind == PlantKind::Conifer && conifers < 5) {
            const PlantSphere& top = Vegetation::spheres(a.kind)[2];
            const glm::dvec3 c = a.position_m + double(a.scale) * top.centre_m;
            const glm::dvec3 l = glm::normalize(glm::dvec3(0.05, 1.0, 0.03));
            EXPECT_GT(scene.sphereLightVisibility(c, double(a.scale) * top.radius_m, l), 0.9);
            ++conifers;
        }
        for (const Plant& b : plants) {
            if (pairs >= 5) break;
            if (&a == &b || b.kind != PlantKind::Broadleaf || a.kind != PlantKind::Broadleaf) continue;
            const auto [cb, rb] = crown(b);
            const double d = glm::length(cb - ca);
            if (d < 6.0 || d > 14.0) continue;
            // The light from b's crown centre through a's, raised a little: a's lit side faces b.
            const glm::dvec3 l = glm::normalize(cb - ca + glm::dvec3(0.0, 0.15 * d, 0.0));
            if (scene.terrainLightVisibility(ca + l * ra, l) < 1.0) continue;
            EXPECT_LT(scene.sphereLightVisibility(ca, ra, l), 0.5) << "pair " << pairs;
            ++pairs;
        }
    }
    EXPECT_EQ(pairs, 5);
    EXPECT_EQ(conifers, 5);
    // The light 1 degree under the horizon: dark.
    const auto [c0, r0] = crown(plants.front());
    EXPECT_EQ(scene.sphereLightVisibility(c0, r0, glm::dvec3(std::cos(0.0175), -0.0175, 0.0)), 0.0);
}

}  // namespace
}  // namespace amb
