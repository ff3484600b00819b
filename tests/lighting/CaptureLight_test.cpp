// CaptureLight_test.cpp — the light a method with the near field gives its captures' surfaces
// (lighting/NearFieldMethod.cpp "Captures' light"): at a lattice point the near field of the
// captures' ambient there, bilinear between lattice points, the ambient alone out of range; off,
// the captures keep the light they had; an override (--capture-light reference) still wins.
#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "lighting/Baselines.h"
#include "lighting/CubeCapture.h"
#include "lighting/NearField.h"
#include "FakeCubeCapture.h"
#include "FixedLightScene.h"

namespace amb {
namespace {

using testing_support::FakeCubeCapture;
using testing_support::FlatProbeEnvironment;
using testing_support::FurnaceCapture;

// Flat ground at 0 under one light and a hemisphere ambient, with two trees near x = 40.
struct TwoTrees final : testing_support::FixedLightScene {
    void occludersNear(const glm::dvec3& p, double radius_m, double,
                       std::vector<SphereOccluder>& out) const override {
        for (const glm::dvec3 c : {glm::dvec3(40.0, 6.0, 2.0), glm::dvec3(46.0, 5.0, -5.0)})
            if (std::hypot(c.x - p.x, c.z - p.z) < radius_m)
                out.push_back({c, 3.5, glm::dvec3(0.15, 0.3, 0.1)});
    }
};

void expectShNear(const ShRgb& got, const ShRgb& want, const char* where) {
    for (int k = 0; k < kShCoefficients; ++k)
        for (int ch = 0; ch < 3; ++ch)
            EXPECT_NEAR(got.c[k][ch], want.c[k][ch], 1e-5 * (1.0 + std::fabs(want.c[0][ch])))
                << where << ": coefficient " << k << " channel " << ch;
}

struct UniformLight final : SurfaceLight {
    ShRgb shAt(const glm::dvec3&) const override {
        ShRgb sh;
        sh.c[0] = glm::vec3(7.0f);
        return sh;
    }
};

constexpr double kNoon = 12.0, kDt = 1.0 / 30.0;

std::unique_ptr<AmbienceMethod> ours(CubeCapture& capture, const ProbeEnvironment& environment,
                                     double range_m, bool ownLight = false) {
    AmbienceVolumeSettings vs;
    BaselineSettings bs;
    vs.capture.ownLight = ownLight;
    vs.capture.nearField.captureLightRange_m = range_m;
    vs.capture.nearField.captureLightCell_m = 16.0;
    vs.capture.nearField.captureLightPointsPerFrame = 0;
    return makeCapturingMethod("volume", capture, environment, vs, bs, nullptr,
                               [] { return std::make_unique<TwoTrees>(); });
}

}  // namespace

TEST(NearFieldCaptureLight, ALatticePointTakesTheNearFieldOfTheAmbientAndCellsBlendBilinearly) {
    FakeCubeCapture capture(8);
    FlatProbeEnvironment environment;
    const auto method = ours(capture, environment, 200.0);
    const glm::dvec3 camera(0.0, 2.0, 0.0);
    method->predictStage(camera, {10.0, 0.0, 0.0}, kNoon, kDt);
    method->captureStage();
    const SurfaceLight* light = method->captureSurfaceLight();
    ASSERT_NE(light, nullptr);

    // What the draw's corner path gives at a point kShadingHeight_m up, from a NearField of its
    // own with the same settings.
    const TwoTrees scene;
    NearFieldSettings settings;
    NearField near(scene, settings);
    near.setTimeOfDay(kNoon);
    near.setViewer(camera);
    const ShRgb hemisphere = hemisphereSh(scene.ambient(kNoon));
    const auto corner = [&](double x, double z) {
        return near.applyAbove(hemisphere, x, z, kShadingHeight_m);
    };

    // A lattice point beside the trees, well inside the range: exactly the near field there.
    const ShRgb atNode = light->shAt({48.0, 0.0, 0.0});
    expectShNear(atNode, corner(48.0, 0.0), "lattice point (48, 0)");
    // Beside the trees it is darker than the ambient in the open.
    EXPECT_LT(atNode.c[0].y, 0.98f * hemisphere.c[0].y);
    // Between lattice points: the bilinear blend of the four points' near fields (a change
    // added to the ambient, which is the same everywhere here).
    const double x = 41.0, z = 4.0;  // in the cell (32..48) x (0..16)
    const double tx = (x - 32.0) / 16.0, tz = z / 16.0;
    const ShRgb want = corner(32.0, 0.0) * float((1 - tx) * (1 - tz)) +
                       corner(48.0, 0.0) * float(tx * (1 - tz)) +
                       corner(32.0, 16.0) * float((1 - tx) * tz) + corner(48.0, 16.0) * float(tx * tz);
    expectShNear(light->shAt({x, 3.0, z}), want, "inside a cell");
    // In the open, no plant within the near field's radius: the ambient unchanged.
    expectShNear(light->shAt({-120.0, 0.0, 90.0}), hemisphere, "in the open");
    // Out of range the ambient alone, whatever stands there; nearer, fading in.
    expectShNear(light->shAt({540.0, 0.0, 0.0}), hemisphere, "out of range");
}

TEST(NearFieldCaptureLight, TheRangeFollowsTheCameraAndTheLatticeIsBuiltNearestFirst) {
    FakeCubeCapture capture(8);
    FlatProbeEnvironment environment;
    AmbienceVolumeSettings vs;
    BaselineSettings bs;
    vs.capture.nearField.captureLightRange_m = 120.0;
    vs.capture.nearField.captureLightCell_m = 16.0;
    vs.capture.nearField.captureLightPointsPerFrame = 4;  // the trees' points are not the nearest
    const auto method = makeCapturingMethod("volume", capture, environment, vs, bs, nullptr,
                                            [] { return std::make_unique<TwoTrees>(); });
    const TwoTrees scene;
    const ShRgb hemisphere = hemisphereSh(scene.ambient(kNoon));
    method->predictStage({-20.0, 2.0, 0.0}, {0.0, 0.0, 0.0}, kNoon, kDt);
    method->captureStage();
    const SurfaceLight* light = method->captureSurfaceLight();
    ASSERT_NE(light, nullptr);
    // Four new points this frame, those nearest the camera: the trees' are not among them yet.
    expectShNear(light->shAt({48.0, 0.0, 0.0}), hemisphere, "first frame");
    // Frames later every point in range is made, and the trees darken their lattice point;
    // reading the light changes nothing of it (only the method's capture stage does).
    const ShRgb before = light->shAt({48.0, 0.0, 0.0});
    for (int f = 0; f < 10; ++f) (void)light->shAt({48.0, 0.0, 0.0});
    expectShNear(light->shAt({48.0, 0.0, 0.0}), before, "read again");
    for (int f = 0; f < 60; ++f) {
        method->predictStage({-20.0, 2.0, 0.0}, {}, kNoon, kDt);
        method->captureStage();
    }
    const ShRgb later = light->shAt({48.0, 0.0, 0.0});
    EXPECT_LT(later.c[0].y, 0.98f * hemisphere.c[0].y);
    // The camera 1 km away: the point is out of range, the ambient alone.
    method->predictStage({1000.0, 2.0, 0.0}, {}, kNoon, kDt);
    method->captureStage();
    expectShNear(light->shAt({48.0, 0.0, 0.0}), hemisphere, "camera gone");
}

TEST(NearFieldCaptureLight, OffTheCapturesKeepTheirLightAndAnOverrideStillWins) {
    FakeCubeCapture capture(8);
    FlatProbeEnvironment environment;
    // Off: the hemisphere (no light) without ownLight, the method's own field with it.
    const auto off = ours(capture, environment, 0.0);
    off->predictStage({0.0, 2.0, 0.0}, {}, kNoon, kDt);
    EXPECT_EQ(off->captureSurfaceLight(), nullptr);
    const auto own = ours(capture, environment, 0.0, true);
    own->predictStage({0.0, 2.0, 0.0}, {}, kNoon, kDt);
    const auto& near = dynamic_cast<const NearFieldMethod&>(*own);
    EXPECT_NE(own->captureSurfaceLight(), nullptr);
    EXPECT_EQ(own->captureSurfaceLight(), near.far().captureSurfaceLight());

    // On: its own light; an override replaces it, an empty one gives it back.
    const auto on = ours(capture, environment, 200.0);
    on->predictStage({0.0, 2.0, 0.0}, {}, kNoon, kDt);
    const SurfaceLight* mine = on->captureSurfaceLight();
    ASSERT_NE(mine, nullptr);
    const UniformLight uniform;
    on->overrideCaptureLight([&](double) -> const SurfaceLight* { return &uniform; });
    EXPECT_EQ(on->captureSurfaceLight(), &uniform);
    on->overrideCaptureLight({});
    EXPECT_EQ(on->captureSurfaceLight(), mine);
}

TEST(NearFieldCaptureLight, EveryCaptureIsLitByIt) {
    // A furnace capture records whether a surface light was set: with the setting on, every
    // capture of every capturing method has one (none with it off and ownLight off).
    for (const char* name : {"volume", "nearest", "grid", "reactive", "object"}) {
        SCOPED_TRACE(name);
        for (const double range : {0.0, 200.0}) {
            AmbienceVolumeSettings vs;
            BaselineSettings bs;
            vs.capture.nearField.captureLightRange_m = bs.capture.nearField.captureLightRange_m =
                range;
            vs.capture.facesPerFrame = bs.capture.facesPerFrame = 6;
            FurnaceCapture capture(0.5, 100.0);
            FlatProbeEnvironment environment;
            const auto method = makeCapturingMethod(name, capture, environment, vs, bs, nullptr,
                                                    [] { return std::make_unique<TwoTrees>(); });
            glm::dvec3 camera(-7.0, 2.0, 11.0);
            for (int f = 0; f < 12; ++f) {
                camera.x += 0.5;
                method->predictStage(camera, {15.0, 0.0, 0.0}, kNoon, kDt);
                method->captureStage();
                method->storeStage();
                const double x[1] = {camera.x}, z[1] = {camera.z};
                method->noteLookups(1, x, z);
            }
            ASSERT_GT(capture.captures, 0);
            EXPECT_EQ(capture.litCaptures, range > 0.0 ? capture.captures : 0);
            EXPECT_EQ(capture.light(), nullptr);  // left without a light after each capture
        }
    }
}

}  // namespace amb
