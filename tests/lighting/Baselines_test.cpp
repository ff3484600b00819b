// Baselines_test.cpp — the baseline ambience methods with the CPU fake capture: each converges to
// the projection of the fake's own captures (bilinear for the grid and the cache, the object's
// capture for one-per-object, one anchor for nearest), the face budget, the grid's hysteresis
// closed form and exact integer scrolling 10^6 m from the origin, the cache's demand rule and
// timeout, poisoned captures never reaching shAt, the factory and the JSON settings.
#include "lighting/Baselines.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "ShChecks.h"

#include "FakeCubeCapture.h"
#include "lighting/CubeMapProjector.h"
#include "lighting/NearField.h"
#include "world/Error.h"

namespace amb {
namespace {

using testing_support::allFinite;
using testing_support::maxDiff;

using testing_support::FakeCubeCapture;
using testing_support::FlatProbeEnvironment;
using testing_support::FurnaceCapture;
using testing_support::Poison;

constexpr double kDt = 1.0 / 60.0;
constexpr int kFace = 8;              // small faces: the tests only need the fake's variation
constexpr double kProbeHeight = 2.0;  // FlatProbeEnvironment's default
// Incremental (face by face) and whole-cube projection of the same texels agree to float
// rounding; relative to the coefficient L00 of the red channel.
constexpr double kRelative = 1e-5;

// The layouts these tests state their closed forms for (finer than the defaults, which are tuned
// for one face per frame on the shipped replays).
// The budget alone: no prime (CaptureCore.h; Baselines.EveryMethodIsPrimed... tests it).
BaselineSettings testLayout() {
    BaselineSettings s;
    s.capture.primeProbes = 0;
    s.gridSpacing_m = 24.0;
    s.cacheSpacing_m = 12.0;
    s.objectSize_m = 32.0;
    s.objectRange_m = 150.0;
    return s;
}

bool identical(const ShRgb& a, const ShRgb& b) {
    return std::memcmp(&a, &b, sizeof(ShRgb)) == 0;
}

// The projection of the fake's whole cube at a probe over ground point (x, z).
ShRgb captureAt(double x_m, double z_m, double timeOfDay_h = 12.0) {
    FakeCubeCapture reference(kFace);
    const std::vector<float> cube = reference.captureAll({x_m, kProbeHeight, z_m}, timeOfDay_h);
    return toFloat(projectCubeMap(kFace, cube, {}, reference.sunDirection(timeOfDay_h)).sh);
}

// sum_j w_j v_j / sum_j w_j, in double.
ShRgb weighted(const std::vector<std::pair<double, ShRgb>>& terms) {
    double sum[kShCoefficients][3] = {};
    double weights = 0.0;
    for (const auto& [w, v] : terms) {
        weights += w;
        for (int k = 0; k < kShCoefficients; ++k) {
            for (int ch = 0; ch < 3; ++ch) sum[k][ch] += w * v.c[k][ch];
        }
    }
    ShRgb out;
    for (int k = 0; k < kShCoefficients; ++k) {
        for (int ch = 0; ch < 3; ++ch) out.c[k][ch] = float(sum[k][ch] / weights);
    }
    return out;
}

double tolerance(const ShRgb& reference) {
    return kRelative * std::fabs(double(reference.c[0].x));
}

void frame(AmbienceMethod& method, const glm::dvec3& camera, double timeOfDay_h = 12.0,
           double dt = kDt) {
    method.predictStage(camera, {0.0, 0.0, 0.0}, timeOfDay_h, dt);
    method.captureStage();
    method.storeStage();
}

// Positions of the probes started (calls that include face 0), in order.
std::vector<glm::dvec3> probeStarts(const FakeCubeCapture& capture) {
    std::vector<glm::dvec3> out;
    for (const auto& call : capture.calls()) {
        if (call.faces & cubeFaceBit(0)) out.push_back(call.position_m);
    }
    return out;
}

// ---- ScrollingGridMethod ------------------------------------------------------------------------

TEST(ScrollingGridMethod, ConvergesToCapturesBilinearly) {
    BaselineSettings s = testLayout();
    s.gridSize = 4;
    s.gridSpacing_m = 24.0;
    s.capture.facesPerFrame = 6;  // a whole probe per frame
    FakeCubeCapture capture(kFace);
    FlatProbeEnvironment environment;
    ScrollingGridMethod grid(capture, environment, s);
    const glm::dvec3 camera(5.0, 1.7, 7.0);
    for (int f = 0; f < 32; ++f) frame(grid, camera);  // 16 first captures, then 16 updates
    // Even G: the camera's cell is the central one, so the grid holds cells -1 .. 2.
    EXPECT_EQ(grid.gridOrigin(), (CellKey{-1, -1}));
    EXPECT_EQ(grid.methodStatistics().probes, 16u);
    const ShRgb c00 = captureAt(0, 0), c10 = captureAt(24, 0), c01 = captureAt(0, 24),
                c11 = captureAt(24, 24);
    // On a probe: that probe's capture (an update with the same value keeps it).
    ASSERT_TRUE(grid.probe({0, 0}));
    EXPECT_EQ(grid.probe({0, 0})->updates, 2);
    EXPECT_TRUE(identical(grid.shAt(0.0, 0.0), grid.probe({0, 0})->value));
    EXPECT_LT(maxDiff(grid.shAt(0.0, 0.0), c00), tolerance(c00));
    // At the cell centre the four weights are exactly 1/4.
    const ShRgb centre = weighted({{1, c00}, {1, c10}, {1, c01}, {1, c11}});
    EXPECT_LT(maxDiff(grid.shAt(12.0, 12.0), centre), tolerance(centre));
    // At the camera's ground point: bilinear weights (1 - tx)(1 - tz), tx (1 - tz), ...
    const double tx = 5.0 / 24.0, tz = 7.0 / 24.0;
    const ShRgb atCamera = weighted(
        {{(1 - tx) * (1 - tz), c00}, {tx * (1 - tz), c10}, {(1 - tx) * tz, c01}, {tx * tz, c11}});
    EXPECT_LT(maxDiff(grid.shAt(5.0, 7.0), atCamera), tolerance(atCamera));
    // The neighbouring probes differ (the fake's ground varies), so the test can tell them apart.
    EXPECT_GT(maxDiff(c00, c10), 100.0 * tolerance(c00));
    // Outside the grid (beyond cell 2 = 48 m): the fallback, for FlatProbeEnvironment at noon
    // L00 = Y00 x (40 + 8) x 2 pi.
    const ShRgb outside = grid.shAt(49.0, 0.0);
    EXPECT_TRUE(identical(outside, grid.fallback()));
    EXPECT_NEAR(outside.c[0].x, kShY00 * 48.0 * 2.0 * kPi, 1e-3);
}

TEST(ScrollingGridMethod, HysteresisClosedForm) {
    // G = 2: four probes, one captured per frame. Four frames at noon set them (value a), then
    // every four frames at 15:00 update each once with the constant capture c:
    // after k updates, value = c + (a - c) h^k.
    BaselineSettings s = testLayout();
    s.gridSize = 2;
    s.capture.facesPerFrame = 6;
    s.hysteresis = 0.9;
    FakeCubeCapture capture(kFace);
    FlatProbeEnvironment environment;
    ScrollingGridMethod grid(capture, environment, s);
    const glm::dvec3 camera(5.0, 1.7, 7.0);
    for (int f = 0; f < 4; ++f) frame(grid, camera, 12.0);
    ASSERT_EQ(grid.gridOrigin(), (CellKey{0, 0}));
    const int k = 20;
    for (int f = 0; f < 4 * k; ++f) frame(grid, camera, 15.0);
    for (const CellKey cell : {CellKey{0, 0}, CellKey{1, 0}, CellKey{0, 1}, CellKey{1, 1}}) {
        const double x = 24.0 * cell.i, z = 24.0 * cell.k;
        const ShRgb a = captureAt(x, z, 12.0), c = captureAt(x, z, 15.0);
        const double hk = std::pow(s.hysteresis, k);
        const ShRgb expected = weighted({{hk, a}, {1.0 - hk, c}});
        const auto p = grid.probe(cell);
        ASSERT_TRUE(p);
        EXPECT_EQ(p->updates, k + 1) << cell.i << ", " << cell.k;
        // Float rounding of each of the k updates and of the projections.
        EXPECT_LT(maxDiff(p->value, expected), 2.0 * tolerance(a)) << cell.i << ", " << cell.k;
        // Still visibly away from c: the closed form is not trivially met.
        EXPECT_GT(maxDiff(p->value, c), 10.0 * tolerance(a));
    }
}

// With ownLight the grid's captures light their surfaces with the grid's own field. In a furnace
// (FurnaceCapture: uniform albedo rho, direct irradiance E_d) an update of a probe that reads
// itself is one bounce more: with hysteresis h its upward irradiance v follows
// v' = h v + (1 - h) rho (E_d + v), a contraction by h + (1 - h) rho towards the geometric
// series' limit rho E_d / (1 - rho). Without it every capture holds one bounce, rho E_d.
TEST(ScrollingGridMethod, OwnLightConvergesToTheFurnacesBounces) {
    const double rho = 0.5, direct = 100.0;
    for (const bool own : {false, true}) {
        SCOPED_TRACE(own);
        BaselineSettings s = testLayout();
        s.gridSize = 2;
        s.capture.facesPerFrame = 6;
        s.hysteresis = 0.5;
        s.capture.ownLight = own;
        FurnaceCapture capture(rho, direct);
        FlatProbeEnvironment environment;
        ScrollingGridMethod grid(capture, environment, s);
        // Four probes, one a frame: 60 updates each (0.75^60 < 1e-7 of the start left).
        for (int f = 0; f < 4 * 61; ++f) frame(grid, {5.0, 1.7, 7.0});
        const auto p = grid.probe({0, 0});  // the probe at (0, 0) reads itself alone
        ASSERT_TRUE(p);
        const double up = double(luminance(shIrradiance(p->value, glm::vec3(0, 1, 0))));
        const double limit = own ? rho * direct / (1.0 - rho) : rho * direct;
        EXPECT_NEAR(up, limit, 1e-4 * limit);
        EXPECT_EQ(capture.litCaptures, own ? capture.captures : 0);
        EXPECT_EQ(capture.light(), nullptr);  // left as it was
    }
}

TEST(ScrollingGridMethod, ScrollingKeepsIntegerCellsExactFarFromTheOrigin) {
    BaselineSettings s = testLayout();
    s.gridSize = 4;
    s.capture.facesPerFrame = 6;
    const double spacing = s.gridSpacing_m;
    FakeCubeCapture capture(kFace);
    FlatProbeEnvironment environment;
    ScrollingGridMethod grid(capture, environment, s);
    glm::dvec3 camera(1.0e6 + 5.0, 1.7, -1.0e6 + 7.0);
    for (int f = 0; f < 16; ++f) frame(grid, camera);
    // Lowest cell: floor(camera / s) - (G / 2 - 1).
    const CellKey origin{std::int64_t(std::floor(camera.x / spacing)) - 1,
                         std::int64_t(std::floor(camera.z / spacing)) - 1};
    ASSERT_EQ(grid.gridOrigin(), origin);
    // Every probe was captured exactly at (i s, k s) of a grid cell.
    std::vector<std::pair<std::int64_t, std::int64_t>> seen;
    for (const glm::dvec3& p : probeStarts(capture)) {
        const double i = p.x / spacing, k = p.z / spacing;
        EXPECT_EQ(i, std::floor(i));
        EXPECT_EQ(k, std::floor(k));
        EXPECT_EQ(double(std::int64_t(i)) * spacing, p.x);
        EXPECT_GE(std::int64_t(i), origin.i);
        EXPECT_LT(std::int64_t(i), origin.i + 4);
        EXPECT_GE(std::int64_t(k), origin.k);
        EXPECT_LT(std::int64_t(k), origin.k + 4);
        seen.emplace_back(std::int64_t(i), std::int64_t(k));
    }
    std::sort(seen.begin(), seen.end());
    EXPECT_EQ(std::unique(seen.begin(), seen.end()), seen.end());
    EXPECT_EQ(seen.size(), 16u);
    std::vector<ShRgb> before;
    for (std::int64_t k = origin.k; k < origin.k + 4; ++k) {
        for (std::int64_t i = origin.i; i < origin.i + 4; ++i) {
            ASSERT_TRUE(grid.probe({i, k}));
            before.push_back(grid.probe({i, k})->value);
        }
    }

    // One cell to +X: the column origin.i leaves, origin.i + 4 enters invalid, the rest keep
    // their values bit for bit.
    camera.x += spacing;
    grid.predictStage(camera, {0, 0, 0}, 12.0, kDt);
    EXPECT_EQ(grid.gridOrigin(), (CellKey{origin.i + 1, origin.k}));
    for (std::int64_t k = origin.k; k < origin.k + 4; ++k) {
        EXPECT_FALSE(grid.probe({origin.i, k}));
        EXPECT_FALSE(grid.probe({origin.i + 4, k}));
        for (std::int64_t i = origin.i + 1; i < origin.i + 4; ++i) {
            const auto p = grid.probe({i, k});
            ASSERT_TRUE(p);
            EXPECT_TRUE(
                identical(p->value, before[std::size_t((k - origin.k) * 4 + (i - origin.i))]));
        }
    }
    EXPECT_EQ(grid.methodStatistics().probes, 12u);
    grid.captureStage();
    grid.storeStage();
    for (int f = 0; f < 3; ++f) frame(grid, camera);
    // The four entering probes were captured next, at their exact lattice positions.
    const std::vector<glm::dvec3> starts = probeStarts(capture);
    ASSERT_EQ(starts.size(), 20u);
    for (std::size_t n = 16; n < 20; ++n) {
        EXPECT_EQ(starts[n].x, double(origin.i + 4) * spacing);
    }
    EXPECT_EQ(grid.methodStatistics().probes, 16u);
    EXPECT_EQ(grid.methodStatistics().teleports, 0);

    // A jump of 1000 cells is a teleport; the grid moves by exactly 1000 cells, all invalid.
    camera.x += 1000.0 * spacing;
    grid.predictStage(camera, {0, 0, 0}, 12.0, kDt);
    EXPECT_EQ(grid.gridOrigin(), (CellKey{origin.i + 1001, origin.k}));
    EXPECT_EQ(grid.methodStatistics().probes, 0u);
    EXPECT_EQ(grid.methodStatistics().teleports, 1);
}

// ---- ReactiveCacheMethod ------------------------------------------------------------------------

// Without lookups nothing is wanted and nothing captured, but the prime: in the first frame the
// camera's own cell counts as looked up (lighting/CaptureCore.h), its four corners captured
// whole, and nothing after it.
TEST(ReactiveCacheMethod, NoLookupsNoCapturesButThePrime) {
    for (const int prime : {0, 4}) {
        SCOPED_TRACE(prime);
        FakeCubeCapture capture(kFace);
        FlatProbeEnvironment environment;
        BaselineSettings s;
        s.capture.primeProbes = prime;
        ReactiveCacheMethod cache(capture, environment, s);
        for (int f = 0; f < 60; ++f) frame(cache, {3.0, 1.7, 4.0});
        EXPECT_EQ(capture.calls().size(), std::size_t(prime));
        EXPECT_EQ(cache.methodStatistics().facesCaptured, 6 * prime);
        EXPECT_EQ(cache.methodStatistics().primeFaces, 6 * prime);
        EXPECT_EQ(cache.methodStatistics().probes, std::size_t(prime));
        EXPECT_EQ(identical(cache.shAt(3.0, 4.0), cache.fallback()), prime == 0);
    }
}

TEST(ReactiveCacheMethod, CapturesTheCornersOfLookupsNearestFirst) {
    BaselineSettings s = testLayout();
    s.capture.facesPerFrame = 6;
    const double spacing = s.cacheSpacing_m;  // 12 m
    FakeCubeCapture capture(kFace);
    FlatProbeEnvironment environment;
    ReactiveCacheMethod cache(capture, environment, s);
    const glm::dvec3 camera(40.0, 1.7, 3.0);
    // Cells (0, 0) and (1, 0): corners (0..2, 0..1), six lattice points.
    const double xs[] = {5.0, 20.0}, zs[] = {7.0, 7.0};
    for (int f = 0; f < 10; ++f) {
        frame(cache, camera);
        cache.noteLookups(2, xs, zs);
    }
    EXPECT_EQ(cache.wantedCount(), 6u);
    EXPECT_EQ(cache.presentCount(), 6u);
    const std::vector<glm::dvec3> starts = probeStarts(capture);
    ASSERT_EQ(starts.size(), 6u);  // nothing more once every wanted corner is present
    // Nearest the camera first.
    for (std::size_t n = 1; n < starts.size(); ++n) {
        const auto d = [&](const glm::dvec3& p) {
            return std::hypot(p.x - camera.x, p.z - camera.z);
        };
        EXPECT_LE(d(starts[n - 1]), d(starts[n]));
    }
    // Bilinear over the four corners.
    const double tx = 5.0 / spacing, tz = 7.0 / spacing;
    const ShRgb expected = weighted({{(1 - tx) * (1 - tz), captureAt(0, 0)},
                                     {tx * (1 - tz), captureAt(12, 0)},
                                     {(1 - tx) * tz, captureAt(0, 12)},
                                     {tx * tz, captureAt(12, 12)}});
    EXPECT_LT(maxDiff(cache.shAt(5.0, 7.0), expected), tolerance(expected));
    // On a lattice point: its capture.
    EXPECT_LT(maxDiff(cache.shAt(24.0, 12.0), captureAt(24, 12)), tolerance(expected));
    // Cell (2, 0) has only its corners x = 24 present: renormalised, linear along z there.
    const double tz2 = 7.0 / spacing;
    const ShRgb half = weighted({{1 - tz2, captureAt(24, 0)}, {tz2, captureAt(24, 12)}});
    EXPECT_LT(maxDiff(cache.shAt(30.0, 7.0), half), tolerance(half));
    // Where no corner is present: the fallback.
    EXPECT_TRUE(identical(cache.shAt(100.0, 100.0), cache.fallback()));
}

TEST(ReactiveCacheMethod, DroppedAfterTheTimeout) {
    BaselineSettings s = testLayout();
    s.capture.facesPerFrame = 6;
    FakeCubeCapture capture(kFace);
    FlatProbeEnvironment environment;
    ReactiveCacheMethod cache(capture, environment, s);
    const glm::dvec3 camera(5.0, 1.7, 5.0);
    const double x = 5.0, z = 7.0;
    for (int f = 0; f < 10; ++f) {
        frame(cache, camera);
        cache.noteLookups(1, &x, &z);
    }
    ASSERT_EQ(cache.presentCount(), 4u);
    const ShRgb held = cache.shAt(x, z);
    EXPECT_FALSE(identical(held, cache.fallback()));
    // Not looked up any more: kept for 4 s (240 frames), then dropped.
    for (int f = 0; f < 230; ++f) frame(cache, camera);
    EXPECT_EQ(cache.presentCount(), 4u);
    EXPECT_TRUE(identical(cache.shAt(x, z), held));
    for (int f = 0; f < 20; ++f) frame(cache, camera);
    EXPECT_EQ(cache.presentCount(), 0u);
    EXPECT_EQ(cache.wantedCount(), 0u);
    EXPECT_EQ(cache.methodStatistics().probes, 0u);
    EXPECT_TRUE(identical(cache.shAt(x, z), cache.fallback()));
    EXPECT_EQ(probeStarts(capture).size(), 4u);
}

TEST(ReactiveCacheMethod, MissingBeforeStale) {
    // The four probes around A are captured at noon; then the time of day jumps to 15:00, which
    // makes them stale, and B, further from the camera, is looked up too: B's four missing
    // probes are captured first, then A's four again.
    BaselineSettings s = testLayout();
    s.capture.facesPerFrame = 6;
    FakeCubeCapture capture(kFace);
    FlatProbeEnvironment environment;
    ReactiveCacheMethod cache(capture, environment, s);
    const glm::dvec3 camera(5.0, 1.7, 5.0);
    const double xs[] = {5.0, 60.0}, zs[] = {7.0, 7.0};  // A in cell (0, 0), B in cell (5, 0)
    for (int f = 0; f < 10; ++f) {
        frame(cache, camera, 12.0);
        cache.noteLookups(1, xs, zs);
    }
    cache.noteLookups(2, xs, zs);
    ASSERT_EQ(probeStarts(capture).size(), 4u);
    for (int f = 0; f < 10; ++f) {
        frame(cache, camera, 15.0);
        cache.noteLookups(2, xs, zs);
    }
    const std::vector<glm::dvec3> starts = probeStarts(capture);
    ASSERT_EQ(starts.size(), 12u);
    for (std::size_t n = 4; n < 8; ++n) EXPECT_GE(starts[n].x, 60.0) << n;   // B: x = 60, 72
    for (std::size_t n = 8; n < 12; ++n) EXPECT_LE(starts[n].x, 12.0) << n;  // A: x = 0, 12
    for (std::size_t n = 4; n < 12; ++n) EXPECT_EQ(capture.calls()[n].timeOfDay_h, 15.0);
    EXPECT_EQ(cache.presentCount(), 8u);
    // A now holds its 15:00 capture.
    EXPECT_LT(maxDiff(cache.shAt(0.0, 0.0), captureAt(0, 0, 15.0)), tolerance(captureAt(0, 0)));
}

// ---- PerObjectMethod ----------------------------------------------------------------------------

TEST(PerObjectMethod, EachPointGetsItsObjectsCaptureAndNothingElse) {
    BaselineSettings s = testLayout();
    s.capture.facesPerFrame = 6;
    s.objectRange_m = 40.0;
    FakeCubeCapture capture(kFace);
    FlatProbeEnvironment environment;
    PerObjectMethod objects(capture, environment, s);
    const glm::dvec3 camera(30.0, 1.7, 10.0);
    for (int f = 0; f < 30; ++f) frame(objects, camera);
    // Objects whose centre ((i + 1/2) 32, (k + 1/2) 32) lies within 40 m of the camera.
    std::size_t inRange = 0;
    for (int i = -3; i <= 3; ++i) {
        for (int k = -3; k <= 3; ++k) {
            if (std::hypot((i + 0.5) * 32.0 - camera.x, (k + 0.5) * 32.0 - camera.z) <= 40.0) {
                ++inRange;
            }
        }
    }
    EXPECT_EQ(objects.methodStatistics().probes, inRange);
    const std::vector<glm::dvec3> starts = probeStarts(capture);
    ASSERT_EQ(starts.size(), inRange);
    for (std::size_t n = 0; n < starts.size(); ++n) {
        // At object centres, nearest the camera first.
        EXPECT_EQ(std::fmod(starts[n].x + 16.0, 32.0), 0.0);
        EXPECT_EQ(std::fmod(starts[n].z + 16.0, 32.0), 0.0);
        if (n > 0) {
            EXPECT_LE(std::hypot(starts[n - 1].x - camera.x, starts[n - 1].z - camera.z),
                      std::hypot(starts[n].x - camera.x, starts[n].z - camera.z));
        }
    }
    // Across the border x = 32 between objects (0, 0) and (1, 0): each side its own capture,
    // the whole object the same value, no interpolation.
    const ShRgb left = captureAt(16.0, 16.0), right = captureAt(48.0, 16.0);
    const ShRgb justLeft = objects.shAt(31.999, 10.0), justRight = objects.shAt(32.0, 10.0);
    EXPECT_LT(maxDiff(justLeft, left), tolerance(left));
    EXPECT_LT(maxDiff(justRight, right), tolerance(right));
    EXPECT_GT(maxDiff(left, right), 100.0 * tolerance(left));
    EXPECT_TRUE(identical(objects.shAt(0.0, 0.0), justLeft));
    EXPECT_TRUE(identical(objects.shAt(31.9, 31.9), justLeft));
    // Outside every captured object: the fallback.
    EXPECT_TRUE(identical(objects.shAt(300.0, 10.0), objects.fallback()));
}

TEST(PerObjectMethod, RecapturedAfterTheLifetimeForgottenFarAway) {
    BaselineSettings s = testLayout();
    s.capture.facesPerFrame = 6;
    s.objectRange_m = 20.0;
    FakeCubeCapture capture(kFace);
    FlatProbeEnvironment environment;
    PerObjectMethod objects(capture, environment, s);
    // Only the centre (16, 16) lies within 20 m (5.7 m); the next ones are >= 28.8 m away.
    const glm::dvec3 near(20.0, 1.7, 20.0);
    // One hour of day per minute: lifetime 0.0349 rad / (pi/12 rad/h x 1/60 h/s) = 8.0 s.
    double tod = 12.0;
    const auto run = [&](int frames) {
        for (int f = 0; f < frames; ++f) {
            frame(objects, near, tod);
            tod += kDt / 60.0;
        }
    };
    run(60);
    EXPECT_NEAR(objects.currentLifetime_s(), 0.0349 / (kPi / 12.0 / 60.0), 1e-6);
    EXPECT_EQ(probeStarts(capture).size(), 1u);
    run(400);  // 7.7 s in all: still fresh
    EXPECT_EQ(probeStarts(capture).size(), 1u);
    run(60);  // 8.7 s: recaptured once
    EXPECT_EQ(probeStarts(capture).size(), 2u);
    EXPECT_EQ(objects.methodStatistics().probes, 1u);
    // 100 m away (beyond 2 x 20 m): the old object is forgotten.
    const ShRgb there = objects.shAt(20.0, 20.0);
    EXPECT_FALSE(identical(there, objects.fallback()));
    for (int f = 0; f < 2; ++f) frame(objects, near + glm::dvec3(100.0, 0.0, 0.0), tod);
    EXPECT_TRUE(identical(objects.shAt(20.0, 20.0), objects.fallback()));
}

// ---- NearestAnchorMethod ------------------------------------------------------------------------

TEST(NearestAnchorMethod, ValueIsTheNearestAnchorsWithoutBlending) {
    AmbienceVolumeSettings vs;
    vs.capture.facesPerFrame = 6;
    FakeCubeCapture capture(kFace);
    FlatProbeEnvironment environment;
    NearestAnchorMethod nearest(capture, environment, vs);
    const glm::dvec3 camera(10.0, 1.7, 20.0);
    for (int f = 0; f < 120; ++f) frame(nearest, camera);
    const AnchorStore& store = nearest.volume().store();
    ASSERT_GT(store.size(), 20u);
    std::vector<const Anchor*> anchors;
    store.forEach([&](const Anchor& a) {
        if (a.presence > 0.0f) anchors.push_back(&a);
    });
    // Anchors hold their own captures (blending is over within a frame).
    for (const Anchor* a : anchors) {
        const ShRgb c = captureAt(a->capturedPosition_m.x, a->capturedPosition_m.z);
        EXPECT_LT(maxDiff(a->current, c), tolerance(c));
        EXPECT_TRUE(
            identical(nearest.shAt(store.keyX_m(a->key), store.keyZ_m(a->key)), a->current));
    }
    // Between anchors: exactly the value of the nearest one (brute force over the store) when
    // it lies within the finest search radius (2 cells of 3 m), never a blend.
    int checked = 0;
    const double finest = store.spacing_m(store.finestLevel());
    for (double x = camera.x - 20.0; x <= camera.x + 20.0; x += 1.37) {
        for (double z = camera.z - 20.0; z <= camera.z + 20.0; z += 1.29) {
            const ShRgb v = nearest.shAt(x, z);
            const Anchor* best = nullptr;
            double bestD = 1e300, secondD = 1e300;
            for (const Anchor* a : anchors) {
                const double d = std::hypot(store.keyX_m(a->key) - x, store.keyZ_m(a->key) - z);
                if (d < bestD) {
                    secondD = bestD;
                    bestD = d;
                    best = a;
                } else if (d < secondD) {
                    secondD = d;
                }
            }
            if (!best || bestD > 2.0 * finest || secondD - bestD < 1e-6) continue;
            EXPECT_TRUE(identical(v, best->current)) << x << ", " << z;
            ++checked;
        }
    }
    EXPECT_GT(checked, 50);
    EXPECT_EQ(nearest.methodName(), "nearest");
    EXPECT_EQ(nearest.methodStatistics().probes, store.size());
}

// ---- All methods --------------------------------------------------------------------------------

const char* const kBaselineNames[] = {"nearest", "grid", "reactive", "object"};

// Lookups of a 60 m square around the camera every 3 m, as terrain corners would be.
struct Lookups {
    std::vector<double> x, z;
    explicit Lookups(const glm::dvec3& camera) {
        for (double dx = -30.0; dx <= 30.0; dx += 3.0) {
            for (double dz = -30.0; dz <= 30.0; dz += 3.0) {
                x.push_back(camera.x + dx);
                z.push_back(camera.z + dz);
            }
        }
    }
};

// Every capturing method is primed alike (lighting/CaptureCore.h): at the first frame it holds
// four whole probes and the camera's point reads them, not the fallback; the reactive cache,
// which names probes by the draw's lookups, at the first frame after its first lookups.
TEST(Baselines, EveryMethodIsPrimedAtItsFirstProbes) {
    for (const char* name : {"volume", "nearest", "grid", "reactive", "object"}) {
        SCOPED_TRACE(name);
        AmbienceVolumeSettings vs;
        BaselineSettings bs = testLayout();
        bs.capture.primeProbes = vs.capture.primeProbes = 4;
        FakeCubeCapture capture(kFace);
        FlatProbeEnvironment environment;
        auto method = makeCapturingMethod(name, capture, environment, vs, bs, nullptr);
        const bool byLookups = std::string(name) == "reactive";
        const glm::dvec3 camera(-7.0, 1.7, 11.0);
        for (int f = 0; f < (byLookups ? 2 : 1); ++f) {
            method->predictStage(camera, {0.0, 0.0, 0.0}, 12.0, kDt);
            method->captureStage();
            method->storeStage();
            const Lookups lookups(camera);
            method->noteLookups(lookups.x.size(), lookups.x.data(), lookups.z.data());
        }
        const MethodStatistics m = method->methodStatistics();
        EXPECT_EQ(m.primeFaces, 24);
        EXPECT_GE(m.probes, 4u);
        // What the camera's point reads is captured light, not the fallback (the sky over flat
        // ground, which the fake's ground colour differs from).
        std::vector<float> fallbackCube;
        environment.fallbackCubeMap(12.0, 16, fallbackCube);
        const ShRgb fallback = toFloat(projectCubeMap(16, fallbackCube).sh);
        EXPECT_GT(maxDiff(method->shAt(camera.x, camera.z), fallback),
                  1e-3 * std::fabs(fallback.c[0].x));
    }
}

// A surface light of uniform radiance: every surface's ambient the same.
class UniformLight final : public SurfaceLight {
  public:
    explicit UniformLight(float radiance) {
        // L00 = L x integral of Y00 over the sphere = L 4 pi / (2 sqrt(pi)).
        sh_.c[0] = glm::vec3(radiance * 2.0f * std::sqrt(float(kPi)));
    }
    ShRgb shAt(const glm::dvec3&) const override { return sh_; }

  private:
    ShRgb sh_;
};

// A capture light override (AmbienceMethod::overrideCaptureLight, what `run --capture-light
// reference` passes) lights every capture of every capturing method, the prime's too, in place
// of the method's own light (ownLight on here), and is asked with the frame's time of day; where
// it answers null the method's own light is back. In the furnace a capture lit by a uniform
// radiance L holds rho (E_d + pi L) on an upward surface.
TEST(Baselines, EveryCapturingMethodTakesACaptureLightOverride) {
    const double rho = 0.5, direct = 100.0;
    const float radiance = 20.0f;
    const UniformLight override(radiance);
    for (const char* name : {"volume", "nearest", "grid", "reactive", "object"}) {
        SCOPED_TRACE(name);
        AmbienceVolumeSettings vs;
        BaselineSettings bs = testLayout();
        bs.capture.primeProbes = vs.capture.primeProbes = 1;
        bs.capture.ownLight = vs.capture.ownLight = true;
        bs.capture.facesPerFrame = vs.capture.facesPerFrame = 6;
        FurnaceCapture capture(rho, direct);
        FlatProbeEnvironment environment;
        auto method = makeCapturingMethod(name, capture, environment, vs, bs, nullptr);
        std::vector<double> asked;
        method->overrideCaptureLight([&](double timeOfDay_h) -> const SurfaceLight* {
            asked.push_back(timeOfDay_h);
            return timeOfDay_h < 13.0 ? &override : nullptr;
        });
        glm::dvec3 camera(-7.0, 1.7, 11.0);
        const auto step = [&](double timeOfDay_h) {
            camera.x += 0.4;
            method->predictStage(camera, {24.0, 0.0, 0.0}, timeOfDay_h, kDt);
            method->captureStage();
            method->storeStage();
            const Lookups lookups(camera);
            method->noteLookups(lookups.x.size(), lookups.x.data(), lookups.z.data());
        };
        for (int f = 0; f < 10; ++f) step(12.0);
        EXPECT_GT(capture.captures, 0);
        EXPECT_EQ(capture.litCaptures, capture.captures);
        EXPECT_NEAR(capture.lastAmbient, kPi * radiance, 1e-4 * kPi * radiance);
        EXPECT_EQ(method->captureSurfaceLight(), &override);
        ASSERT_FALSE(asked.empty());
        for (const double t : asked) EXPECT_EQ(t, 12.0);
        // What the captures held: the furnace's closed form at the camera.
        const double up =
            double(luminance(shIrradiance(method->shAt(camera.x, camera.z), glm::vec3(0, 1, 0))));
        const double lit = rho * (direct + kPi * radiance);
        EXPECT_NEAR(up, lit, 1e-3 * lit);
        // The override answers null from 13 h on: the method's own field lights them again.
        const int before = capture.captures;
        for (int f = 0; f < 10; ++f) step(14.0);
        EXPECT_GT(capture.captures, before);
        EXPECT_NE(method->captureSurfaceLight(), nullptr);
        EXPECT_NE(method->captureSurfaceLight(), &override);
        EXPECT_EQ(asked.back(), 14.0);
        EXPECT_EQ(capture.light(), nullptr);  // left without a light after each capture
    }
}

TEST(Baselines, FaceBudgetAndWholeProbesPerPosition) {
    for (const char* name : kBaselineNames) {
        AmbienceVolumeSettings vs;
        vs.capture.facesPerFrame = 2;
        vs.capture.primeProbes = 0;
        BaselineSettings bs = testLayout();
        bs.capture.facesPerFrame = 2;
        FakeCubeCapture capture(kFace);
        FlatProbeEnvironment environment;
        auto method = makeCapturingMethod(name, capture, environment, vs, bs, nullptr);
        glm::dvec3 camera(-7.0, 1.7, 11.0);
        std::int64_t total = 0;
        for (int f = 0; f < 90; ++f) {
            camera.x += 0.4;  // 24 m/s
            const std::size_t callsBefore = capture.calls().size();
            method->predictStage(camera, {24.0, 0.0, 0.0}, 12.0, kDt);
            method->captureStage();
            method->storeStage();
            const Lookups lookups(camera);
            method->noteLookups(lookups.x.size(), lookups.x.data(), lookups.z.data());
            int faces = 0;
            for (std::size_t c = callsBefore; c < capture.calls().size(); ++c) {
                faces += __builtin_popcount(capture.calls()[c].faces);
            }
            EXPECT_LE(faces, 2) << name << " frame " << f;
            EXPECT_EQ(faces, method->methodStatistics().facesThisFrame) << name;
            total += faces;
        }
        EXPECT_EQ(method->methodStatistics().facesCaptured, total) << name;
        EXPECT_GT(total, 60) << name;
        // Faces come in order 0..5, each probe's six at one position.
        int next = 0;
        glm::dvec3 position(0.0);
        for (const auto& call : capture.calls()) {
            for (int face = 0; face < kCubeFaces; ++face) {
                if (!(call.faces & cubeFaceBit(face))) continue;
                ASSERT_EQ(face, next) << name;
                if (face == 0) position = call.position_m;
                EXPECT_EQ(call.position_m, position) << name;
                next = (next + 1) % kCubeFaces;
            }
        }
        EXPECT_EQ(method->methodName(), name);
        EXPECT_GT(method->methodStatistics().bytes, 0u) << name;
    }
}

TEST(Baselines, PoisonedProbesNeverReachShAt) {
    for (const Poison kind : {Poison::NaN, Poison::Inf, Poison::Negative}) {
        for (const char* name : kBaselineNames) {
            AmbienceVolumeSettings vs;
            vs.capture.facesPerFrame = 6;  // whole probes per frame: none left half done at the end
            BaselineSettings bs = testLayout();
            bs.capture.facesPerFrame = 6;
            FakeCubeCapture capture(kFace);
            capture.poisonEvery(2, kind, 3);
            FlatProbeEnvironment environment;
            auto method = makeCapturingMethod(name, capture, environment, vs, bs, nullptr);
            const glm::dvec3 camera(13.0, 1.7, -29.0);
            const Lookups lookups(camera);
            for (int f = 0; f < 40; ++f) {
                frame(*method, camera);
                method->noteLookups(lookups.x.size(), lookups.x.data(), lookups.z.data());
            }
            const MethodStatistics m = method->methodStatistics();
            EXPECT_GT(capture.poisonedProbes(), 5) << name;
            EXPECT_EQ(m.rejectedProbes, capture.poisonedProbes()) << name;
            EXPECT_GT(m.probes, 0u) << name;
            for (double x = camera.x - 60.0; x <= camera.x + 60.0; x += 1.7) {
                for (double z = camera.z - 60.0; z <= camera.z + 60.0; z += 2.3) {
                    ASSERT_TRUE(allFinite(method->shAt(x, z))) << name << " " << x << ", " << z;
                }
            }
        }
    }
}

TEST(Baselines, FactoryNamesAndUnknownName) {
    FakeCubeCapture capture(kFace);
    FlatProbeEnvironment environment;
    for (const char* name : {"volume", "nearest", "grid", "reactive", "object"}) {
        const auto method = makeCapturingMethod(name, capture, environment, {}, {}, nullptr);
        ASSERT_TRUE(method);
        EXPECT_EQ(method->methodName(), name);
    }
    EXPECT_THROW(makeCapturingMethod("ddgi", capture, environment, {}, {}, nullptr), InputError);
    try {
        makeCapturingMethod("", capture, environment, {}, {}, nullptr);
        ADD_FAILURE() << "no error for an empty name";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("--ambient"), std::string::npos);
    }
}

// A scene with nothing near: the near field's wrapping, not what it puts back, is on trial.
struct EmptyNearScene final : NearFieldScene {
    void occludersNear(const glm::dvec3&, double, double, std::vector<SphereOccluder>&) const override {}
    DirectionalLight mainLight(double) const override { return {}; }
    HemisphereAmbient ambient(double) const override {
        return {glm::dvec3(1.0, 1.1, 1.3), glm::dvec3(0.3, 0.3, 0.2)};
    }
    double groundHeight(double, double) const override { return 0.0; }
};

TEST(Baselines, FactoryWrapsTheNearFieldWhereTheMethodsOwnSettingsAskForIt) {
    FakeCubeCapture capture(kFace);
    FlatProbeEnvironment environment;
    int scenesMade = 0;
    const NearFieldSceneMaker scene = [&scenesMade] {
        ++scenesMade;
        return std::make_unique<EmptyNearScene>();
    };
    for (const char* name : {"volume", "nearest", "grid", "reactive", "object"}) {
        const bool ours = std::string(name) == "volume" || std::string(name) == "nearest";
        for (const bool volumeAsks : {false, true}) {
            for (const bool baselineAsks : {false, true}) {
                AmbienceVolumeSettings vs;
                BaselineSettings bs;
                vs.capture.nearField.enabled = volumeAsks;
                bs.capture.nearField.enabled = baselineAsks;
                // The sky detail follows the near field's terrain switch: the two settings
                // differ there, so the wrapper shows whose settings it was given.
                vs.capture.nearField.terrain = true;
                vs.capture.nearField.vertexDetail = true;
                bs.capture.nearField.terrain = false;
                const bool asks = ours ? volumeAsks : baselineAsks;
                const std::string where = std::string(name) + (volumeAsks ? " volume asks" : "") +
                                          (baselineAsks ? " baseline asks" : "");
                const int before = scenesMade;
                const auto method =
                    makeCapturingMethod(name, capture, environment, vs, bs, nullptr, scene);
                ASSERT_TRUE(method) << where;
                EXPECT_EQ(method->methodName(), name) << where;
                const auto* near = dynamic_cast<const NearFieldMethod*>(method.get());
                EXPECT_EQ(near != nullptr, asks) << where;
                EXPECT_EQ(scenesMade - before, asks ? 1 : 0) << where;
                if (near) {
                    EXPECT_EQ(near->far().methodName(), name) << where;
                    EXPECT_EQ(dynamic_cast<const NearFieldMethod*>(&near->far()), nullptr) << where;
                    EXPECT_EQ(near->terrainSkyDetail(), ours) << where;
                    // The vertex range and its bound are the near field's defaults unless the
                    // settings ask otherwise.
                    EXPECT_EQ(near->terrainVertexRange_m(), NearFieldSettings{}.vertexAmbient_m)
                        << where;
                    EXPECT_EQ(near->terrainVertexPointsPerFrame(),
                              NearFieldSettings{}.vertexPointsPerFrame)
                        << where;
                }
                // Without a scene to read, the bare method whatever the settings.
                const auto bare = makeCapturingMethod(name, capture, environment, vs, bs, nullptr);
                EXPECT_EQ(dynamic_cast<const NearFieldMethod*>(bare.get()), nullptr) << where;
            }
        }
    }
}

// The terrain's vertex range (nearField.vertexAmbient_m) reaches the draw through the method
// with the near field whose settings name it (ours from the volume's file, a baseline from the
// baselines'), and only while that near field is enabled; a bare method has none.
TEST(Baselines, TheVertexRangeIsTheNearFieldsSetting) {
    FakeCubeCapture capture(kFace);
    FlatProbeEnvironment environment;
    const NearFieldSceneMaker scene = [] { return std::make_unique<EmptyNearScene>(); };
    for (const char* name : {"volume", "grid"}) {
        const bool ours = std::string(name) == "volume";
        AmbienceVolumeSettings vs;
        BaselineSettings bs;
        vs.capture.nearField.vertexAmbient_m = 64.0;
        bs.capture.nearField.vertexAmbient_m = 160.0;
        const auto method = makeCapturingMethod(name, capture, environment, vs, bs, nullptr, scene);
        EXPECT_EQ(method->terrainVertexRange_m(), ours ? 64.0 : 160.0) << name;
        vs.capture.nearField.enabled = bs.capture.nearField.enabled = false;
        const auto without =
            makeCapturingMethod(name, capture, environment, vs, bs, nullptr, scene);
        EXPECT_EQ(without->terrainVertexRange_m(), 0.0) << name;
    }
}

TEST(BaselineSettings, FromJson) {
    const BaselineSettings s = baselineSettingsFromJson(
        R"({"facesPerFrame": 2, "gridSize": 8, "gridSpacing_m": 12.5, "hysteresis": 0.9,
            "cacheSpacing_m": 6, "unusedTimeout_s": 1.5, "objectRange_m": 80})",
        "baselines.json");
    EXPECT_EQ(s.capture.facesPerFrame, 2);
    EXPECT_EQ(s.gridSize, 8);
    EXPECT_EQ(s.gridSpacing_m, 12.5);
    EXPECT_EQ(s.hysteresis, 0.9);
    EXPECT_EQ(s.cacheSpacing_m, 6.0);
    EXPECT_EQ(s.unusedTimeout_s, 1.5);
    EXPECT_EQ(s.objectRange_m, 80.0);
    EXPECT_EQ(s.objectSize_m, BaselineSettings{}.objectSize_m);  // missing keys keep defaults
    EXPECT_EQ(s.capture.sunThreshold, 5000.0);
    const auto failsNaming = [](const std::string& json, const std::string& key) {
        try {
            baselineSettingsFromJson(json, "b.json");
        } catch (const InputError& e) {
            const std::string what = e.what();
            return what.find(key) != std::string::npos && what.find("b.json") != std::string::npos;
        }
        return false;
    };
    EXPECT_TRUE(failsNaming(R"({"gridSpacing": 12})", "gridSpacing"));       // unknown key
    EXPECT_TRUE(failsNaming(R"({"gridSize": "8"})", "gridSize"));            // wrong type
    EXPECT_TRUE(failsNaming(R"({"facesPerFrame": 1.5})", "facesPerFrame"));  // not an integer
    EXPECT_TRUE(failsNaming(R"({"hysteresis": 1.5})", "hysteresis"));        // out of range
    EXPECT_TRUE(failsNaming(R"({"gridSpacing_m": 0})", "gridSpacing_m"));    // out of range
    EXPECT_TRUE(failsNaming(R"({"objectRange_m": -1})", "objectRange_m"));   // out of range
    EXPECT_THROW(baselineSettingsFromJson("[1]", "x"), InputError);
    EXPECT_THROW(baselineSettingsFromJson("{", "x"), InputError);
}

}  // namespace
}  // namespace amb
