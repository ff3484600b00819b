// BounceReference_test.cpp — the reference lit by its own bounce field (lighting/BounceField.h)
// through the GL capture: on a small patch of the real world the bounces converge below 1 %
// within a few passes, the field lights the reference's surfaces, and without a field the
// full-scene capture is today's hemisphere-lit reference to the bit.
#include <cmath>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include "GlTestContext.h"
#include "app/render/CubeCaptureGl.h"
#include "lighting/BounceField.h"
#include "lighting/CubeMapProjector.h"
#include "lighting/Metrics.h"
#include "lighting/ProbeEnvironment.h"
#include "lighting/SH.h"
#include "world/Conventions.h"
#include "world/Vegetation.h"
#include "world/World.h"

namespace amb {
namespace {

constexpr double kNoon_h = 12.0;

double irradiance(const ShRgb& sh, const glm::vec3& n) {
    return double(luminance(shIrradiance(sh, n)));
}

// Five lattice nodes 64 m apart around open ground at noon (two layers), faces of 8: the change between
// bounces falls below 1 % within 6 passes, falls from one pass to the next from the second on,
// and the bounces add light: the converged field's irradiance of a downward surface (the lit
// ground below) is above pass 1's, and an upward surface's changes by less than a tenth.
TEST(BounceReference, ConvergesWithinAFewBouncesOnASmallScene) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, 16, 16);
    const World world{WorldSettings{}};
    const glm::dvec3 ground = test::openGround(world);
    const WorldProbeEnvironment env(world);
    CubeCaptureGl lattice(world, 8, CaptureScene::Full);
    BounceSettings s;
    s.spacing_m = 64.0;
    s.reach_m = 64.0;
    s.faceSize = 8;
    BounceField field(s);
    const double cx = std::round(ground.x / 64.0) * 64.0, cz = std::round(ground.z / 64.0) * 64.0;
    field.layOut({{cx, cz}}, [&](double x, double z) { return env.placeProbe(x, z, 4.0); });
    ASSERT_EQ(field.points(), 10u);  // 5 nodes, two layers (the default canopy)
    // Pass 1 alone: surfaces lit by the sun, no ambient.
    BounceSettings one = s;
    one.maxBounces = 1;
    BounceField first(one);
    first.layOut({{cx, cz}}, [&](double x, double z) { return env.placeProbe(x, z, 4.0); });
    first.solve(lattice, kNoon_h);

    const BounceSolve& solve = field.solve(lattice, kNoon_h);
    EXPECT_TRUE(solve.converged);
    EXPECT_LE(solve.bounces, 6);
    EXPECT_GE(solve.bounces, 2);
    EXPECT_LT(solve.changes.back(), 0.01);
    for (std::size_t k = 2; k < solve.changes.size(); ++k)
        EXPECT_LT(solve.changes[k], solve.changes[k - 1]) << "pass " << k + 1;
    EXPECT_EQ(lattice.surfaceLight(), nullptr);
    const glm::dvec3 centre(cx, 0.0, cz);
    const double down1 = irradiance(first.shAt(centre), {0, -1, 0});
    const double downN = irradiance(field.shAt(centre), {0, -1, 0});
    const double up1 = irradiance(first.shAt(centre), {0, 1, 0});
    const double upN = irradiance(field.shAt(centre), {0, 1, 0});
    EXPECT_GT(downN, down1);
    EXPECT_NEAR(upN, up1, 0.1 * up1);
    for (std::size_t i = 0; i < field.points(); ++i)
        for (const glm::vec3& c : field.pointSh(i).c)
            ASSERT_TRUE(std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z));
}

// --reference-light hemisphere is today's reference: a full-scene capture with no surface light
// is the same to the bit before and after a field lit it, and the field's light differs.
TEST(BounceReference, HemisphereReproducesTodaysReferenceExactly) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, 16, 16);
    const World world{WorldSettings{}};
    const glm::dvec3 probe = test::openGround(world) + glm::dvec3(0.0, 2.0, 0.0);
    CubeCaptureGl reference(world, 16, CaptureScene::Full);
    const std::vector<float> today = reference.captureAll(probe, kNoon_h);

    // A field brighter than the hemisphere: surfaces lit by it are brighter.
    struct Bright final : SurfaceLight {
        ShRgb sh;
        ShRgb shAt(const glm::dvec3&) const override { return sh; }
    } bright;
    for (int c = 0; c < 3; ++c) bright.sh.c[0][c] = 1e5f;
    reference.setSurfaceLight(&bright);
    const std::vector<float> lit = reference.captureAll(probe, kNoon_h);
    reference.setSurfaceLight(nullptr);
    const std::vector<float> again = reference.captureAll(probe, kNoon_h);

    ASSERT_EQ(today.size(), again.size());
    EXPECT_EQ(std::memcmp(today.data(), again.data(), today.size() * sizeof(float)), 0);
    const auto down = [&](const std::vector<float>& cube) {
        return irradiance(toFloat(projectCubeMap(16, cube, {}, reference.sunDirection(kNoon_h)).sh),
                          {0, -1, 0});
    };
    EXPECT_GT(down(lit), 1.5 * down(today));
}

// The full-scene capture asks a plant's surface light at its spheres' area-weighted centre (a
// field with two layers lights a crown by the canopy's layer), the coarse capture at its base.
TEST(BounceReference, FullCapturesAskPlantsAtTheirCrowns) {
    AMB_REQUIRE_PLATFORM(platform, Backend::Auto, 16, 16);
    const World world{WorldSettings{}};
    struct Recording final : SurfaceLight {
        mutable std::vector<glm::dvec3> asked;
        ShRgb shAt(const glm::dvec3& p) const override {
            asked.push_back(p);
            return ShRgb{};
        }
    } light;
    // A tree near the probe, from the world's own tiles.
    const glm::dvec3 ground = test::openGround(world);
    const Vegetation& veg = world.vegetation();
    std::vector<Plant> trees;
    for (std::int64_t k = -4; k <= 4; ++k)
        for (std::int64_t i = -4; i <= 4; ++i)
            for (const Plant& p : *veg.tile(Vegetation::tileIndex(ground.x) + i,
                                            Vegetation::tileIndex(ground.z) + k))
                if (p.kind == PlantKind::Conifer || p.kind == PlantKind::Broadleaf)
                    trees.push_back(p);
    ASSERT_FALSE(trees.empty());
    const auto centre = [](PlantKind kind) {
        double sum = 0.0, weight = 0.0;
        for (const PlantSphere& s : Vegetation::spheres(kind))
            sum += s.centre_m.y * s.radius_m * s.radius_m, weight += s.radius_m * s.radius_m;
        return sum / weight;
    };
    EXPECT_GT(centre(PlantKind::Conifer), 4.0);  // above the trunk, within the crown
    EXPECT_GT(centre(PlantKind::Broadleaf), 5.0);
    // 30 m east of the first tree, 2 m up: the tree stands in the -X face.
    const double px = trees.front().position_m.x + 30.0, pz = trees.front().position_m.z;
    const glm::dvec3 probe(px, world.height(px, pz) + 2.0, pz);
    for (const CaptureScene scene : {CaptureScene::Full, CaptureScene::Coarse}) {
        SCOPED_TRACE(scene == CaptureScene::Full ? "full" : "coarse");
        CubeCaptureGl capture(world, 16, scene);
        capture.setSurfaceLight(&light);
        light.asked.clear();
        capture.captureAll(probe, kNoon_h);
        capture.setSurfaceLight(nullptr);
        int matched = 0;
        for (const Plant& t : trees) {
            const double lift = scene == CaptureScene::Full ? t.scale * centre(t.kind) : 0.0;
            for (const glm::dvec3& a : light.asked)
                if (std::fabs(a.x - t.position_m.x) < 1e-9 && std::fabs(a.z - t.position_m.z) < 1e-9) {
                    EXPECT_NEAR(a.y, t.position_m.y + lift, 1e-6);
                    ++matched;
                    break;
                }
        }
        EXPECT_GT(matched, 0) << "no tree's own lookup among " << light.asked.size();
    }
}

}  // namespace
}  // namespace amb
