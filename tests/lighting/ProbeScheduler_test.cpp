// ProbeScheduler_test.cpp — motion model (inertia, history, teleports), resolution against speed,
// candidate choice, and the scheduler driving an AmbienceVolume with a CPU fake capture: a camera
// at 30 m/s finds anchors where it will be 2 s later before it arrives, 10x faster uses a coarser
// finest level, and after a teleport the work moves to the new place within a few frames.
#include "lighting/ProbeScheduler.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <optional>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "FakeCubeCapture.h"
#include "lighting/AmbienceVolume.h"
#include "world/Heightfield.h"
#include "world/Road.h"

namespace amb {
namespace {

using testing_support::FakeCubeCapture;
using testing_support::FlatProbeEnvironment;

constexpr double kDt = 1.0 / 60.0;

TEST(ProbeScheduler, FinestLevelFallsAsSpeedRises) {
    AnchorStore store;  // 243, 81, 27, 9, 3 m
    ProbeScheduler scheduler;
    const double rate = 10.0;  // probes per second: one face per frame at 60 Hz
    ProbeSchedulerSettings two;
    two.corridorCells = 2.0;  // the rule with a corridor two cells wide (the default is wider)
    two.maxLevel = kMaxAnchorLevels - 1;  // and the whole hierarchy (the default stops at 27 m)
    auto levelAt = [&](double speed) {
        ProbeScheduler s(two);
        s.observe({0, 0, 0}, {speed, 0, 0}, 0.0);
        return s.finestLevel(store, rate);
    };
    // Needed spacing = speed x corridorCells (2) / rate.
    EXPECT_EQ(levelAt(0.0), 4);     // 0 m
    EXPECT_EQ(levelAt(15.0), 4);    // 3 m -> 3 m
    EXPECT_EQ(levelAt(15.01), 3);   // just over 3 m -> 9 m
    EXPECT_EQ(levelAt(30.0), 3);    // 6 m -> 9 m
    EXPECT_EQ(levelAt(300.0), 1);   // 60 m -> 81 m
    EXPECT_EQ(levelAt(3000.0), 0);  // 600 m -> the coarsest
    // A cap on the finest level is respected.
    ProbeSchedulerSettings capped;
    capped.maxLevel = 2;
    ProbeScheduler c(capped);
    c.observe({0, 0, 0}, {0, 0, 0}, 0.0);
    EXPECT_EQ(c.finestLevel(store, rate), 2);
}

TEST(ProbeScheduler, PredictionWithInertia) {
    ProbeSchedulerSettings settings;
    settings.velocityTimeConstant_s = 0.3;
    ProbeScheduler s(settings);
    glm::dvec3 p(100.0, 5.0, -40.0);
    const glm::dvec3 v(30.0, 0.0, 0.0);
    for (int f = 0; f < 60; ++f) {
        s.observe(p, v, f * kDt);
        p += v * kDt;
    }
    p -= v * kDt;
    EXPECT_NEAR(glm::length(s.predict(2.0) - (p + 2.0 * v)), 0.0, 1e-9);
    // A sharp turn: the filtered velocity follows with time constant 0.3 s,
    // v_old x exp(-t / 0.3) + v_new x (1 - exp(-t / 0.3)).
    const glm::dvec3 w(0.0, 0.0, 30.0);
    for (int f = 1; f <= 30; ++f) {
        p += w * kDt;
        s.observe(p, w, (59 + f) * kDt);
        const double keep = std::exp(-f * kDt / 0.3);
        ASSERT_NEAR(s.velocity_mps().x, 30.0 * keep, 1e-9);
        ASSERT_NEAR(s.velocity_mps().z, 30.0 * (1.0 - keep), 1e-9);
    }
    const auto path = s.predictedPath();
    ASSERT_EQ(path.size(), 13u);  // 0, 0.25, ..., 3 s
    EXPECT_EQ(path.front().position_m, p);
    EXPECT_NEAR(glm::length(path.back().position_m - (p + 3.0 * s.velocity_mps())), 0.0, 1e-9);
}

TEST(ProbeScheduler, VelocityFromHistoryWhenNotGiven) {
    ProbeScheduler s;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    // The history gives 20 m/s from the second frame on; the filter (0.3 s) starts from 0, so
    // after 4 s it is within 20 exp(-13) of it.
    for (int f = 0; f < 240; ++f) s.observe({20.0 * f * kDt, 0, 0}, {nan, nan, nan}, f * kDt);
    EXPECT_NEAR(s.velocity_mps().x, 20.0, 1e-4);
    EXPECT_NEAR(s.velocity_mps().z, 0.0, 1e-9);
}

TEST(ProbeScheduler, ResetStartsThePredictionOverAtTheNewPlace) {
    // After a teleport (the rule is CaptureCore's, tested in CaptureCore_test.cpp) the owner
    // resets the scheduler: the next observation starts the prediction at the new place.
    ProbeScheduler s;
    glm::dvec3 p(0.0);
    const glm::dvec3 v(30.0, 0.0, 0.0);
    for (int f = 0; f < 30; ++f, p += v * kDt) s.observe(p, v, f * kDt);
    const glm::dvec3 q = p + glm::dvec3(5000.0, 0.0, 3000.0);
    const glm::dvec3 u(0.0, 0.0, -12.0);
    s.reset();
    s.observe(q, u, 31 * kDt + 10.0);
    EXPECT_EQ(s.predict(0.0), q);
    EXPECT_EQ(s.velocity_mps(), u);
    EXPECT_NEAR(glm::length(s.predict(1.0) - (q + u)), 0.0, 1e-12);
}

TEST(ProbeScheduler, FollowsTheRoadAhead) {
    const WorldSettings ws;
    const Heightfield heightfield(ws);
    const RoadNetwork roads(ws, heightfield);
    ASSERT_FALSE(roads.roads().empty());
    const Road& road = roads.roads().front();
    // Pick the most curved 100 m stretch in the first kilometres, so the road ahead and the
    // straight line through the velocity differ clearly.
    double bestS = 0.0, bestBend = -1.0;
    for (double s0 = 100.0; s0 + 100.0 < std::min(road.length_m, 4000.0); s0 += 25.0) {
        const glm::dvec3 a = road.tangentAt(s0), b = road.tangentAt(s0 + 100.0);
        const double bend =
            1.0 - (a.x * b.x + a.z * b.z) / (std::hypot(a.x, a.z) * std::hypot(b.x, b.z));
        if (bend > bestBend) {
            bestBend = bend;
            bestS = s0;
        }
    }
    ASSERT_GT(bestBend, 1e-3) << "no bend found";
    ProbeScheduler s;
    s.setRoads(&roads);
    const double speed = 25.0;
    for (int f = 0; f <= 30; ++f) {
        const double along = bestS - speed * (30 - f) * kDt;
        const glm::dvec3 t = road.tangentAt(along);
        const glm::dvec3 v = speed * glm::normalize(glm::dvec3(t.x, 0.0, t.z));
        s.observe(road.pointAt(along) + glm::dvec3(0, 1.5, 0), v, f * kDt);
    }
    ASSERT_TRUE(s.onRoad());
    // The prediction 4 s ahead lies on the road 100 m further (within the 3 m resampling), and
    // not on the straight line.
    const glm::dvec3 onRoad = road.pointAt(bestS + 4.0 * speed);
    const glm::dvec3 predicted = s.predict(4.0);
    EXPECT_LT(std::hypot(predicted.x - onRoad.x, predicted.z - onRoad.z), 3.0);
    const glm::dvec3 straight = s.position_m() + 4.0 * s.velocity_mps();
    EXPECT_GT(std::hypot(straight.x - onRoad.x, straight.z - onRoad.z), 3.0);
    // Driving across the road (perpendicular) does not follow it.
    ProbeScheduler across;
    across.setRoads(&roads);
    const glm::dvec3 t = road.tangentAt(bestS);
    const glm::dvec3 v = speed * glm::normalize(glm::dvec3(-t.z, 0.0, t.x));
    across.observe(road.pointAt(bestS), v, 0.0);
    EXPECT_FALSE(across.onRoad());
    EXPECT_NEAR(glm::length(across.predict(2.0) - (road.pointAt(bestS) + 2.0 * v)), 0.0, 1e-9);
}

TEST(ProbeScheduler, ChoosesNearTheCameraFirstSkipsFreshAndReturnsToStale) {
    AnchorStoreSettings storeSettings;
    storeSettings.blendTime_s = 0.0;
    storeSettings.regenerateFraction = 0.5;
    AnchorStore store(storeSettings);
    ProbeSchedulerSettings settings;
    settings.maxWiden = 0;
    settings.maxLevel = kMaxAnchorLevels - 1;  // the whole hierarchy, down to 3 m
    ProbeScheduler s(settings);
    const glm::dvec3 cam(100.4, 0.0, 50.2);
    EXPECT_FALSE(s.choose(store, 10.0).has_value());  // nothing observed yet
    s.observe(cam, {0, 0, 0}, 0.0);
    // Empty store: the finest-level point nearest the camera (99, 51).
    auto first = s.choose(store, 10.0);
    ASSERT_TRUE(first.has_value());
    EXPECT_EQ(store.keyX_m(first->key), 99.0);
    EXPECT_EQ(store.keyZ_m(first->key), 51.0);
    EXPECT_FALSE(first->refresh);
    // Busy points are skipped; captured (fresh) points are skipped; the choice moves outwards.
    auto second = s.choose(store, 10.0, {first->key});
    ASSERT_TRUE(second.has_value());
    EXPECT_NE(second->key, first->key);
    int chosen = 0;
    while (auto c = s.choose(store, 10.0)) {
        EXPECT_EQ(store.find(c->key), nullptr);  // never a fresh anchor
        store.insert(c->key, ShRgb{}, {store.keyX_m(c->key), 2.0, store.keyZ_m(c->key)}, 100.0);
        if (++chosen > 500) break;
    }
    EXPECT_GT(chosen, 5);
    EXPECT_LT(chosen, 500);  // the rings are finite: then it idles
    // Past half their lifetime the anchors ask for regeneration: chosen again, as refreshes.
    store.advance(60.0);
    auto again = s.choose(store, 10.0);
    ASSERT_TRUE(again.has_value());
    EXPECT_TRUE(again->refresh);
}

// coarseFirst_s ranks a new point of level L s_L / s_0 x that many seconds earlier: with it
// large, an empty store is filled coarsest level first (every level-0 point in its ring before
// any finer one), then near the camera as before.
TEST(ProbeScheduler, CoarseFirstFillsTheCoarseLatticeFirst) {
    AnchorStoreSettings storeSettings;
    storeSettings.blendTime_s = 0.0;
    AnchorStore store(storeSettings);
    ProbeSchedulerSettings settings;
    settings.coarseFirst_s = 100.0;
    ProbeScheduler s(settings);
    s.observe({100.4, 0.0, 50.2}, {0, 0, 0}, 0.0);
    std::vector<int> levels;
    while (auto c = s.choose(store, 10.0)) {
        levels.push_back(c->key.level);
        store.insert(c->key, ShRgb{}, {store.keyX_m(c->key), 2.0, store.keyZ_m(c->key)}, 100.0);
        if (levels.size() > 500) break;
    }
    ASSERT_GT(levels.size(), 5u);
    EXPECT_EQ(levels.front(), 0);
    EXPECT_TRUE(std::is_sorted(levels.begin(), levels.end()));  // coarse to fine
    EXPECT_GT(std::count(levels.begin(), levels.end(), 0), 1);
    EXPECT_GT(levels.back(), 0);
    // Off (the default): the first choice is the finest point nearest the camera.
    ProbeScheduler plain{ProbeSchedulerSettings{}};
    AnchorStore empty(storeSettings);
    plain.observe({100.4, 0.0, 50.2}, {0, 0, 0}, 0.0);
    EXPECT_GT(plain.choose(empty, 10.0)->key.level, 0);
}

TEST(ProbeScheduler, IdlesOnceTheRingsAreFreshUnlessToldToWiden) {
    // A camera standing still: by default the scheduler fills each level's ring around it
    // (finestRingCells, coarseRingCells of the level's spacing) and then idles; with maxWiden 2
    // it goes on to points up to four times as far out before it idles.
    AnchorStoreSettings storeSettings;
    storeSettings.blendTime_s = 0.0;
    const glm::dvec3 cam(100.4, 0.0, 50.2);
    EXPECT_EQ(ProbeSchedulerSettings{}.maxWiden, 0);
    int counts[2] = {0, 0};
    double farthest[2] = {0.0, 0.0};  // in ring radii of the point's level
    for (int widen : {0, 2}) {
        ProbeSchedulerSettings settings;
        settings.maxWiden = widen;
        AnchorStore store(storeSettings);
        ProbeScheduler s(settings);
        s.observe(cam, {0, 0, 0}, 0.0);
        const int finest = s.finestLevel(store, 10.0);
        const int slot = widen ? 1 : 0;
        while (auto c = s.choose(store, 10.0)) {
            const double ring = (c->key.level == finest ? settings.finestRingCells
                                                        : settings.coarseRingCells) *
                                store.spacing_m(c->key.level);
            const double d = std::hypot(store.keyX_m(c->key) - cam.x, store.keyZ_m(c->key) - cam.z);
            farthest[slot] = std::max(farthest[slot], d / ring);
            store.insert(c->key, ShRgb{}, {store.keyX_m(c->key), 2.0, store.keyZ_m(c->key)}, 100.0);
            if (++counts[slot] > 5000) break;
        }
    }
    EXPECT_GT(counts[0], 0);
    EXPECT_LE(farthest[0], 1.0 + 1e-9);  // never beyond the rings
    EXPECT_LT(counts[1], 5000);           // widening is bounded too: then it idles
    EXPECT_GT(counts[1], 4 * counts[0]);  // rings twice and four times as wide
    EXPECT_GT(farthest[1], 2.0);
    EXPECT_LE(farthest[1], 4.0 + 1e-9);
}

// A frame's choices share its candidates (found at the first, kept until the next observe):
// several choices a frame, with points busy and anchors stored between them, come out exactly
// as a scheduler that searches afresh for each; and a new frame's motion is seen.
TEST(ProbeScheduler, ManyChoicesAFrameChooseAsIfEachSearchedAfresh) {
    AnchorStoreSettings storeSettings;
    storeSettings.blendTime_s = 0.0;
    storeSettings.regenerateFraction = 0.3;
    AnchorStore store(storeSettings);
    ProbeSchedulerSettings settings;
    settings.maxWiden = 2;
    settings.maxLevel = kMaxAnchorLevels - 1;
    settings.horizon_s = 6.0;
    settings.pathStep_s = 0.1;
    ProbeScheduler kept(settings), afresh(settings);
    int choices = 0, moved = 0;
    std::optional<LatticeKey> previousFirst;
    for (int frame = 0; frame < 40; ++frame) {
        const double t = frame * 0.25;
        const glm::dvec3 cam(30.0 * t, 0.0, 5.0 * std::sin(t));
        const glm::dvec3 velocity(30.0, 0.0, 5.0 * std::cos(t));
        kept.observe(cam, velocity, t);
        afresh.observe(cam, velocity, t);
        store.advance(t);
        std::vector<LatticeKey> busy;
        for (int k = 0; k < 8; ++k) {
            afresh.setSettings(afresh.settings());  // forgets its candidates
            const auto a = kept.choose(store, 40.0, busy);
            const auto b = afresh.choose(store, 40.0, busy);
            ASSERT_EQ(a.has_value(), b.has_value()) << frame << " " << k;
            if (!a) break;
            EXPECT_EQ(a->key, b->key) << frame << " " << k;
            EXPECT_EQ(a->cost_s, b->cost_s);
            EXPECT_EQ(a->timeToReach_s, b->timeToReach_s);
            EXPECT_EQ(a->refresh, b->refresh);
            if (k == 0) {
                moved += previousFirst && *previousFirst != a->key;
                previousFirst = a->key;
            }
            // Every other choice becomes an anchor at once, the others stay busy.
            if (k % 2) {
                store.insert(a->key, ShRgb{}, {store.keyX_m(a->key), 2.0, store.keyZ_m(a->key)},
                             3.0);
            } else {
                busy.push_back(a->key);
            }
            ++choices;
        }
    }
    EXPECT_GT(choices, 200);
    EXPECT_GT(moved, 5);  // the candidates follow the camera from frame to frame
}

TEST(ProbeScheduler, AdaptiveDensityLeavesUniformCellsCoarse) {
    // Fill every level but the finest around the camera, then ask for the finest level's new
    // points: with uniform coarse anchors none is taken; where one coarse corner differs, the
    // points of the cells it bounds are.
    AnchorStoreSettings storeSettings;
    storeSettings.blendTime_s = 0.0;
    ProbeSchedulerSettings settings;
    settings.maxWiden = 0;
    settings.maxLevel = 2;
    settings.adaptiveThreshold = 0.1;
    const glm::dvec3 cam(100.4, 0.0, 50.2);
    ShRgb sky;
    sky.c[0] = glm::vec3(3.0f);
    sky.c[2] = glm::vec3(1.0f);
    for (bool uniform : {true, false}) {
        AnchorStore store(storeSettings);
        ProbeScheduler s(settings);
        s.observe(cam, {0, 0, 0}, 0.0);
        const double coarse = store.spacing_m(1);
        for (int i = -8; i <= 8; ++i)
            for (int k = -8; k <= 8; ++k) {
                const LatticeKey key = store.canonical(
                    {1, std::int32_t(std::floor(cam.x / coarse)) + i,
                     std::int32_t(std::floor(cam.z / coarse)) + k});
                // One corner darker by half where the field is not uniform.
                const bool odd = !uniform && i == 0 && k == 0;
                store.insert(key, odd ? sky * 0.5f : sky,
                             {store.keyX_m(key), 2.0, store.keyZ_m(key)}, 100.0);
            }
        int finest = 0;
        while (auto c = s.choose(store, 1e6)) {
            if (c->key.level == 2) ++finest;
            store.insert(c->key, sky, {store.keyX_m(c->key), 2.0, store.keyZ_m(c->key)}, 100.0);
            if (finest > 500) break;
        }
        if (uniform) {
            EXPECT_EQ(finest, 0);
        } else {
            EXPECT_GT(finest, 0);
            EXPECT_LE(finest, 4 * 8);  // only the four cells around the odd corner
        }
    }
}

// ---- Driving an AmbienceVolume ----------------------------------------------------------------

struct Drive {
    FakeCubeCapture capture{16, false};
    FlatProbeEnvironment environment;
    AmbienceVolume volume;
    // The drives below state their spacings for a corridor two cells wide and the whole
    // hierarchy (the defaults: four cells, finest level 27 m).
    static AmbienceVolumeSettings twoCellCorridor(AmbienceVolumeSettings s) {
        s.scheduler.corridorCells = 2.0;
        s.scheduler.maxLevel = kMaxAnchorLevels - 1;
        return s;
    }
    explicit Drive(const AmbienceVolumeSettings& s = {})
        : volume(capture, environment, twoCellCorridor(s)) {}
};

// Nearest anchor (horizontal distance) to p, or nullptr.
const Anchor* nearestAnchor(const AnchorStore& store, const glm::dvec3& p, double* distance) {
    const Anchor* best = nullptr;
    *distance = std::numeric_limits<double>::infinity();
    store.forEach([&](const Anchor& a) {
        const double d = std::hypot(store.keyX_m(a.key) - p.x, store.keyZ_m(a.key) - p.z);
        if (d < *distance) {
            *distance = d;
            best = &a;
        }
    });
    return best;
}

TEST(ProbeSchedulerDrive, AnchorsAwaitTheCameraTwoSecondsAhead) {
    Drive drive;
    const glm::dvec3 v = 30.0 * glm::dvec3(std::cos(0.3), 0.0, std::sin(0.3));
    const glm::dvec3 start(1234.5, 1.7, -876.25);
    auto position = [&](double t) { return start + v * t; };
    const int frames = int(8.0 / kDt);
    double minLead = 1e9, sumLead = 0.0;
    double predict = 0.0, project = 0.0, store = 0.0;
    int checked = 0;
    for (int f = 0; f < frames; ++f) {
        const double t = f * kDt;
        drive.volume.update(position(t), v, 12.0, f == 0 ? 0.0 : kDt);
        predict += drive.volume.statistics().predict_s;
        project += drive.volume.statistics().project_s;
        store += drive.volume.statistics().store_s;
        EXPECT_EQ(drive.volume.statistics().finestLevel, 3);  // 9 m at 30 m/s
        // Just before arriving at the point that was 2 s ahead at t - 2 s (t - 2 >= 1 s warm-up):
        // an anchor within one finest spacing (9 m) of it exists.
        const double arrival = t + kDt;
        if (arrival - 2.0 >= 1.0) {
            double d;
            const Anchor* a = nearestAnchor(drive.volume.store(), position(arrival), &d);
            ASSERT_NE(a, nullptr);
            ASSERT_LE(d, 9.0) << "no anchor near the arrival point at t = " << arrival;
            const double lead = arrival - a->birth_s;
            minLead = std::min(minLead, lead);
            sumLead += lead;
            ++checked;
        }
    }
    std::cout << "[ measure  ] 30 m/s: anchors near the arrival point were captured " << minLead
              << " s (min), " << sumLead / checked << " s (mean) before arrival; "
              << drive.volume.store().size() << " anchors held, "
              << drive.volume.store().statistics().bytes() << " bytes; per frame: predict "
              << 1e6 * predict / frames << " us, project " << 1e6 * project / frames
              << " us, store " << 1e6 * store / frames << " us\n";
    EXPECT_GT(minLead, 0.0);
    EXPECT_GT(checked, 200);
}

int finestLevelCreated(double speed_mps, double seconds) {
    Drive drive;
    const glm::dvec3 v = speed_mps * glm::dvec3(std::cos(0.3), 0.0, std::sin(0.3));
    int finest = 0;
    for (int f = 0; f < int(seconds / kDt); ++f) {
        drive.volume.update(v * (f * kDt), v, 12.0, f == 0 ? 0.0 : kDt);
    }
    drive.volume.store().forEach([&](const Anchor& a) { finest = std::max(finest, a.key.level); });
    return finest;
}

TEST(ProbeSchedulerDrive, TenTimesFasterUsesACoarserFinestLevel) {
    const int at30 = finestLevelCreated(30.0, 3.0);
    const int at300 = finestLevelCreated(300.0, 3.0);
    EXPECT_EQ(at30, 3);
    EXPECT_EQ(at300, 1);
    EXPECT_LT(at300, at30);
}

TEST(ProbeSchedulerDrive, AfterATeleportTheWorkMovesWithinAFewFrames) {
    Drive drive;
    const glm::dvec3 v(30.0, 0.0, 0.0);
    glm::dvec3 p(0.0, 1.7, 0.0);
    int f = 0;
    for (; f < 63; ++f, p += v * kDt) drive.volume.update(p, v, 12.0, kDt);  // mid-probe
    ASSERT_TRUE(drive.volume.probeInProgress().has_value());
    ASSERT_GT(drive.volume.probeInProgress()->facesDone, 0);
    const glm::dvec3 q = p + glm::dvec3(8000.0, 0.0, -6000.0);
    const std::size_t callsBefore = drive.capture.calls().size();
    drive.volume.update(q, v, 12.0, kDt);
    EXPECT_EQ(drive.volume.statistics().teleports, 1);
    EXPECT_EQ(drive.volume.statistics().abortedProbes, 1);
    // The teleport frame's face is already captured at the new place...
    ASSERT_GT(drive.capture.calls().size(), callsBefore);
    EXPECT_LT(glm::length(drive.capture.calls().back().position_m - q), 30.0);
    // ...and within 6 more frames a probe there is complete and in the store.
    glm::dvec3 r = q;
    for (int g = 0; g < 6; ++g) {
        r += v * kDt;
        drive.volume.update(r, v, 12.0, kDt);
    }
    double d;
    ASSERT_NE(nearestAnchor(drive.volume.store(), r, &d), nullptr);
    EXPECT_LT(d, 30.0);
}

}  // namespace
}  // namespace amb
