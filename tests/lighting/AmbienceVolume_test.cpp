// AmbienceVolume_test.cpp — the per-frame pipeline with a CPU fake capture: the face budget,
// anchors equal to the projection of their own captures, NaN/Inf/negative captures never
// entering the store, insertion changing nothing at its instant, dt = 0, a 10 s hitch, the
// time-of-day wrap and jumps, the fallback, probe placement in the generated world, JSON settings,
// new settings applied to a running volume (retune).
#include "lighting/AmbienceVolume.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include "ShChecks.h"
#include <glm/geometric.hpp>

#include "FakeCubeCapture.h"
#include "lighting/CubeMapProjector.h"
#include "world/Error.h"

namespace amb {
namespace {

using testing_support::allFinite;
using testing_support::maxDiff;

using testing_support::FakeCubeCapture;
using testing_support::FlatProbeEnvironment;
using testing_support::Poison;

constexpr double kDt = 1.0 / 60.0;

// The budget alone: no prime (CaptureCore.h), but in the test of the prime itself.
AmbienceVolumeSettings withoutPrime(AmbienceVolumeSettings s) {
    s.capture.primeProbes = 0;
    return s;
}

bool bitwiseEqualSh(const ShRgb& a, const ShRgb& b) {
    return std::memcmp(&a, &b, sizeof(ShRgb)) == 0;
}

struct Rig {
    FakeCubeCapture capture;
    FlatProbeEnvironment environment;
    AmbienceVolume volume;
    explicit Rig(const AmbienceVolumeSettings& s = {}, bool skyModel = false)
        : capture(16, skyModel), volume(capture, environment, withoutPrime(s)) {}
    void run(int frames, const glm::dvec3& p, double timeOfDay_h = 12.0, double dt = kDt) {
        for (int f = 0; f < frames; ++f) volume.update(p, {0, 0, 0}, timeOfDay_h, dt);
    }
};

TEST(AmbienceVolume, OneFacePerFrameOneProbePerSixFrames) {
    Rig rig;
    rig.run(60, {10.0, 1.7, 20.0});
    const AmbienceStatistics& s = rig.volume.statistics();
    EXPECT_EQ(s.facesCaptured, 60);
    EXPECT_EQ(s.facesThisFrame, 1);
    EXPECT_EQ(s.probesCompleted, 10);
    EXPECT_EQ(rig.volume.store().size(), 10u);
    EXPECT_EQ(rig.capture.calls().size(), 60u);
    for (const auto& call : rig.capture.calls()) {
        EXPECT_EQ(__builtin_popcount(call.faces), 1);
    }
    // Three faces per frame: a probe every two frames.
    AmbienceVolumeSettings three;
    three.capture.facesPerFrame = 3;
    Rig fast(three);
    fast.run(20, {10.0, 1.7, 20.0});
    EXPECT_EQ(fast.volume.statistics().probesCompleted, 10);
    EXPECT_GT(s.store.bytes(), 0u);
}

// With ownLight the volume's captures light their surfaces with its own field: during every
// capture the surface light answers what the volume's shAt answers there at that moment (the
// fallback before any anchor, then the blended anchors), and the capture is left without a light
// after it. Off, no capture sees a light.
class LightRecordingCapture final : public FakeCubeCapture {
  public:
    LightRecordingCapture() : FakeCubeCapture(8) {}
    CubeCaptureStats capture(const glm::dvec3& p, double timeOfDay_h, CubeFaceMask faces,
                             std::vector<float>& cube) override {
        if (light_) {
            ++lit;
            worst = std::max(worst, maxDiff(light_->shAt(p), volume->shAt(p.x, p.z)));
            if (volume->store().size() == 0)
                worst = std::max(worst, maxDiff(light_->shAt(p), volume->store().fallback()));
        }
        return FakeCubeCapture::capture(p, timeOfDay_h, faces, cube);
    }
    void setSurfaceLight(const SurfaceLight* light) override { light_ = light; }
    const SurfaceLight* light_ = nullptr;
    const AmbienceVolume* volume = nullptr;
    int lit = 0;
    double worst = 0.0;
};

TEST(AmbienceVolume, OwnLightLightsItsCapturesWithItsOwnField) {
    for (const bool own : {false, true}) {
        SCOPED_TRACE(own);
        AmbienceVolumeSettings s;
        s.capture.ownLight = own;
        s.capture.primeProbes = 0;
        LightRecordingCapture capture;
        FlatProbeEnvironment environment;
        AmbienceVolume volume(capture, environment, s);
        capture.volume = &volume;
        EXPECT_EQ(volume.captureSurfaceLight() != nullptr, own);
        for (int f = 0; f < 120; ++f)
            volume.update({10.0 + 3.0 * f, 1.7, 20.0}, {180.0, 0.0, 0.0}, 12.0, kDt);
        EXPECT_EQ(volume.statistics().facesCaptured, 120);
        EXPECT_EQ(capture.lit, own ? 120 : 0);
        EXPECT_EQ(capture.worst, 0.0);  // the very same values
        EXPECT_EQ(capture.light_, nullptr);
        EXPECT_GE(volume.store().size(), 15u);
    }
}

TEST(AmbienceVolume, RetuneAppliesNewSettingsToTheRunningVolume) {
    Rig rig;
    rig.run(60, {10.0, 1.7, 20.0});
    ASSERT_EQ(rig.volume.store().size(), 10u);
    AmbienceVolumeSettings s = rig.volume.settings();
    s.capture.facesPerFrame = 3;
    s.store.blendTime_s = 4.0;
    s.scheduler.corridorCells = 6.0;
    ASSERT_TRUE(AmbienceVolume::retunable(rig.volume.settings(), s));
    rig.volume.retune(s);
    // The anchors stay; from the next frame on a probe takes two frames, not six.
    EXPECT_EQ(rig.volume.store().size(), 10u);
    rig.run(10, {10.0, 1.7, 20.0});
    EXPECT_EQ(rig.volume.statistics().facesCaptured, 60 + 30);
    EXPECT_EQ(rig.volume.statistics().probesCompleted, 10 + 5);
    EXPECT_EQ(rig.volume.store().settings().blendTime_s, 4.0);
    EXPECT_EQ(rig.volume.scheduler().settings().corridorCells, 6.0);
    EXPECT_EQ(rig.volume.settings().capture.facesPerFrame, 3);
    // What a volume is built with cannot change in place.
    const AmbienceVolumeSettings base;
    AmbienceVolumeSettings levels = base, spacing = base, sun = base, near = base;
    levels.store.levels = 4;
    spacing.store.coarsestSpacing_m = 81.0;
    sun.capture.sunThreshold = 1000.0;
    near.capture.nearField.radius_m = 30.0;
    for (const AmbienceVolumeSettings* t : {&levels, &spacing, &sun, &near})
        EXPECT_FALSE(AmbienceVolume::retunable(base, *t));
}

TEST(AmbienceVolume, AnchorsHoldTheProjectionOfTheirOwnCaptures) {
    // Time of day fixed, so each probe's six faces (captured over six frames) see the same scene:
    // the anchor's target must equal projecting a whole cube captured at its recorded position.
    Rig rig;
    rig.run(90, {-3.0e6, 1.7, 7.0e6});
    ASSERT_EQ(rig.volume.store().size(), 15u);
    FakeCubeCapture reference(16, false);
    double spread = 0.0;
    ShRgb first;
    bool haveFirst = false;
    rig.volume.store().forEach([&](const Anchor& a) {
        EXPECT_EQ(a.capturedPosition_m.y, 2.0);  // FlatProbeEnvironment: 2 m above y = 0
        const std::vector<float> cube = reference.captureAll(a.capturedPosition_m, 12.0);
        const ShRgb expected = toFloat(projectCubeMap(16, cube).sh);
        EXPECT_LT(maxDiff(a.target, expected), 1e-5 * std::fabs(expected.c[0].x));
        if (!haveFirst) {
            first = a.target;
            haveFirst = true;
        }
        spread = std::max(spread, maxDiff(a.target, first));
    });
    // The fake's ground colour varies with position: anchors differ.
    EXPECT_GT(spread, 1e-2 * std::fabs(first.c[0].x));
}

// The prime (lighting/CaptureCore.h): the first frame, and the frame of a teleport, show
// primeProbes anchors at once, each the projection of its own capture at full presence, so the
// camera's point reads them, not the sky fallback; without it the first frame shows the
// fallback and its anchors fade in.
TEST(AmbienceVolume, APrimeShowsTheFirstFramesProbesAtOnce) {
    for (const glm::dvec3& start : {glm::dvec3(10.0, 1.7, 20.0), glm::dvec3(-3.0e6, 1.7, 7.0e6)}) {
        FakeCubeCapture capture(16), plainCapture(16);
        FlatProbeEnvironment environment;
        AmbienceVolume primed(capture, environment, AmbienceVolumeSettings{});
        AmbienceVolume plain(plainCapture, environment, withoutPrime({}));
        glm::dvec3 p = start;
        for (int cut = 0; cut < 2; ++cut) {
            SCOPED_TRACE(cut ? "after a teleport" : "the first frame");
            const std::size_t before = primed.store().size();
            primed.update(p, {0, 0, 0}, 12.0, kDt);
            plain.update(p, {0, 0, 0}, 12.0, kDt);
            EXPECT_EQ(primed.store().size(), before + 4u);
            EXPECT_EQ(primed.statistics().primeFaces, 24 * (cut + 1));
            FakeCubeCapture reference(16, false);
            int shown = 0;
            primed.store().forEach([&](const Anchor& a) {
                if (glm::length(a.capturedPosition_m - p) > 1000.0) return;  // the old place's
                ++shown;
                EXPECT_EQ(a.presence, 1.0f);
                EXPECT_TRUE(bitwiseEqualSh(a.current, a.target));
                const ShRgb expected = toFloat(
                    projectCubeMap(16, reference.captureAll(a.capturedPosition_m, 12.0)).sh);
                EXPECT_LT(maxDiff(a.target, expected), 1e-5 * std::fabs(expected.c[0].x));
            });
            EXPECT_EQ(shown, 4);
            const ShRgb fallback = primed.store().fallback();
            EXPECT_GT(maxDiff(primed.shAt(p.x, p.z), fallback), 1e-3 * std::fabs(fallback.c[0].x));
            if (cut == 0) {
                EXPECT_EQ(maxDiff(plain.shAt(p.x, p.z), plain.store().fallback()), 0.0);
            }
            p += glm::dvec3(20000.0, 0.0, -15000.0);
        }
    }
}

TEST(AmbienceVolume, NanInfAndNegativeCapturesNeverEnterTheStore) {
    for (Poison kind : {Poison::NaN, Poison::Inf, Poison::Negative}) {
        Rig rig;
        rig.capture.poisonEvery(2, kind, 3);  // every second probe, one texel of face -Y
        rig.run(120, {0.0, 1.7, 0.0});
        const AmbienceStatistics& s = rig.volume.statistics();
        EXPECT_EQ(s.probesCompleted, 20);
        EXPECT_EQ(rig.capture.poisonedProbes(), 10);
        EXPECT_EQ(s.rejectedProbes, 10);
        EXPECT_EQ(rig.volume.store().size(), 10u);
        rig.volume.store().forEach([&](const Anchor& a) {
            EXPECT_TRUE(allFinite(a.current));
            EXPECT_TRUE(allFinite(a.target));
        });
        for (double x = -30.0; x <= 30.0; x += 1.7) {
            EXPECT_TRUE(allFinite(rig.volume.shAt(x, 0.5 * x)));
        }
    }
}

TEST(AmbienceVolume, InsertionChangesNothingAtItsInstant) {
    // With dt = 0 nothing ages, blends or fades, yet probes keep completing and entering the
    // store: what any point sees must not change at all. A camera standing still fills its
    // rings in 28 probes and then idles; widened rings keep it capturing past that.
    AmbienceVolumeSettings widening;
    widening.scheduler.maxWiden = 3;
    Rig rig(widening);
    const glm::dvec3 p(50.0, 1.7, 50.0);
    rig.run(120, p);
    std::vector<ShRgb> seen;
    for (double x = 20.0; x <= 80.0; x += 2.5) {
        for (double z = 20.0; z <= 80.0; z += 2.5) seen.push_back(rig.volume.shAt(x, z));
    }
    const std::size_t before = rig.volume.store().size();
    rig.run(60, p, 12.0, 0.0);
    EXPECT_EQ(rig.volume.store().size(), before + 10);
    std::size_t n = 0;
    for (double x = 20.0; x <= 80.0; x += 2.5) {
        for (double z = 20.0; z <= 80.0; z += 2.5) {
            ASSERT_EQ(maxDiff(rig.volume.shAt(x, z), seen[n++]), 0.0) << x << ", " << z;
        }
    }
    // Once time moves again, the new anchors fade in within the blend time (2 s).
    rig.run(121, p);
    rig.volume.store().forEach([&](const Anchor& a) {
        if (a.birth_s <= rig.volume.simulationTime_s() - 2.0) {
            EXPECT_EQ(a.presence, 1.0f);
        }
    });
}

TEST(AmbienceVolume, TenSecondHitch) {
    Rig rig;
    const glm::dvec3 p(0.0, 1.7, 0.0);
    rig.run(60, p, 12.0);
    const double t0 = rig.volume.simulationTime_s();
    rig.volume.update(p, {0, 0, 0}, 12.0 + 10.0 / 3600.0, 10.0);  // real time
    EXPECT_DOUBLE_EQ(rig.volume.simulationTime_s(), t0 + 10.0);
    EXPECT_NEAR(rig.volume.timeRate_hPerS(), 1.0 / 3600.0, 1e-12);
    rig.volume.store().forEach([&](const Anchor& a) {
        EXPECT_EQ(a.blendProgress, 1.0f);
        EXPECT_TRUE(allFinite(a.current));
    });
    rig.run(30, p, 12.0 + 10.0 / 3600.0);
    for (double x = -20.0; x <= 20.0; x += 3.3) EXPECT_TRUE(allFinite(rig.volume.shAt(x, x)));
}

TEST(AmbienceVolume, TimeOfDayWrapAndJump) {
    // One hour of day per minute, crossing midnight: the rate stays 1/60 h/s, lifetimes follow
    // anchorLifetime_s (0.0349 rad / (pi/12 rad/h x 1/60 h/s) = 8.0 s), nothing is cut short.
    Rig rig;
    const glm::dvec3 p(0.0, 1.7, 0.0);
    double tod = 23.95;
    for (int f = 0; f < 600; ++f) {
        rig.volume.update(p, {0, 0, 0}, tod, kDt);
        if (f > 0) {
            ASSERT_NEAR(rig.volume.timeRate_hPerS(), 1.0 / 60.0, 1e-9) << "frame " << f;
        }
        tod = std::fmod(tod + kDt / 60.0, 24.0);
    }
    const double expected = 0.0349 / (kPi / 12.0 / 60.0);
    EXPECT_NEAR(rig.volume.currentLifetime_s(), expected, 1e-6);
    int checked = 0;
    rig.volume.store().forEach([&](const Anchor& a) {
        if (a.captureTime_s > 0.1) {  // captured after the rate was first measured
            EXPECT_NEAR(a.lifetime_s, expected, 1e-6);
            ++checked;
        }
    });
    EXPECT_GT(checked, 0);
    // A jump of the time of day (06:00 -> noon) cuts every life to the blend time.
    const double now = rig.volume.simulationTime_s();
    rig.volume.update(p, {0, 0, 0}, 12.0, kDt);
    rig.volume.store().forEach([&](const Anchor& a) {
        EXPECT_LE(a.captureTime_s + a.lifetime_s, now + kDt + 2.0 + 1e-9);
        EXPECT_TRUE(a.regenerationRequested || a.captureTime_s > now);
    });
}

TEST(AmbienceVolume, FallbackWhereNoAnchorIs) {
    // FlatProbeEnvironment at noon: 40 above the horizon, 8 below, so
    // L00 = Y00 x (40 + 8) x 2 pi = 85.07 (the horizon lies on texel edges: exact to rounding).
    Rig rig;
    rig.volume.update({0, 1.7, 0}, {0, 0, 0}, 12.0, kDt);
    const ShRgb far = rig.volume.shAt(5000.0, 5000.0);
    EXPECT_NEAR(far.c[0].x, kShY00 * 48.0 * 2.0 * kPi, 1e-3);
    EXPECT_NEAR(far.c[0].z, far.c[0].x, 1e-4);
    // L10 (z-direction) is 0 by symmetry; L1-1 (y) is positive (brighter above).
    EXPECT_NEAR(far.c[2].x, 0.0, 1e-3);
    EXPECT_GT(far.c[1].x, 0.0);
    // At night the fallback is darker.
    Rig night;
    night.volume.update({0, 1.7, 0}, {0, 0, 0}, 0.0, kDt);
    EXPECT_LT(night.volume.shAt(5000.0, 5000.0).c[0].x, 0.1f * far.c[0].x);
}

TEST(AmbienceVolume, AnchorsOfTheFirstFrameStartFromTheSky) {
    // At six faces a frame a probe completes in the very first frame. A new anchor starts from
    // what the store shows at its point: the fallback of that frame, not zero (starting from
    // black made the first second of such a run pop by 0.17 of the irradiance).
    AmbienceVolumeSettings s;
    s.capture.facesPerFrame = 6;
    Rig rig(s);
    rig.volume.update({0, 1.7, 0}, {0, 0, 0}, 12.0, kDt);
    ASSERT_EQ(rig.volume.store().size(), 1u);
    const ShRgb fallback = rig.volume.shAt(5000.0, 5000.0);
    ASSERT_GT(fallback.c[0].x, 1.0f);
    rig.volume.store().forEach([&](const Anchor& a) {
        EXPECT_LT(maxDiff(a.blendFrom, fallback), 1e-4 * fallback.c[0].x);
        EXPECT_EQ(a.presence, 0.0f);
    });
}

TEST(AmbienceVolume, SaveAndWarmStart) {
    Rig rig;
    rig.run(60, {0.0, 1.7, 0.0});
    const std::string path = std::string(AMBIENCE_BINARY_DIR) + "/AmbienceVolume_warm.vdb";
    rig.volume.saveAnchors(path);
    Rig warm;
    warm.volume.loadAnchors(path);
    EXPECT_EQ(warm.volume.store().size(), rig.volume.store().size());
    std::remove(path.c_str());
}

TEST(AmbienceVolumeSettings, FromJson) {
    const AmbienceVolumeSettings s = ambienceSettingsFromJson(
        R"({"facesPerFrame": 2, "store": {"blendTime_s": 0.5, "levels": 4},
            "scheduler": {"horizon_s": 4.5}})",
        "test.json");
    EXPECT_EQ(s.capture.facesPerFrame, 2);
    EXPECT_EQ(s.store.blendTime_s, 0.5);
    EXPECT_EQ(s.store.levels, 4);
    EXPECT_EQ(s.scheduler.horizon_s, 4.5);
    EXPECT_EQ(s.store.coarsestSpacing_m, AnchorStoreSettings{}.coarsestSpacing_m);
    EXPECT_THROW(ambienceSettingsFromJson(R"({"facesPerFrames": 2})", "x"), InputError);
    EXPECT_THROW(ambienceSettingsFromJson(R"({"store": {"levels": 9}})", "x"), InputError);
    EXPECT_THROW(ambienceSettingsFromJson(R"({"store": {"levels": "4"}})", "x"), InputError);
    EXPECT_THROW(ambienceSettingsFromJson(R"({"facesPerFrame": 2.5})", "x"), InputError);
    EXPECT_THROW(ambienceSettingsFromJson(R"([1, 2])", "x"), InputError);
    EXPECT_THROW(ambienceSettingsFromJson("{", "x"), InputError);
}

}  // namespace
}  // namespace amb
