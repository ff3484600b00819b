// AnchorInterpolation_test.cpp — AnchorStore::interpolate, hierarchical bilinear (AnchorStore.h
// "Interpolation", AnchorField.h): exact at anchors, the fallback out of reach, missing corners
// from the coarser level in closed form, the coarsest level's reach into holes, reproduction of
// a bilinear field, partial presence, random walks within the scheme's Lipschitz bound, no
// change when an anchor is inserted, the pattern change of thesis 7.6, never NaN, batches.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "ShChecks.h"

#include "lighting/AnchorField.h"
#include "lighting/AnchorStore.h"

namespace amb {
namespace {

using testing_support::allFinite;
using testing_support::maxDiff;

ShRgb makeSh(float v) {
    ShRgb sh;
    for (int k = 0; k < kShCoefficients; ++k) {
        sh.c[k] = glm::vec3(v * (1.0f + k), v * (0.5f + 0.25f * k), v * (2.0f - 0.1f * k));
    }
    return sh;
}

// A store whose anchors are inserted at once at full weight (blend time 0); bilinear unless
// `smooth` (the tests of closed forms below are the bilinear ones).
AnchorStore instantStore(bool smooth = false) {
    AnchorStoreSettings s;
    s.blendTime_s = 0.0;
    s.smoothInterpolation = smooth;
    return AnchorStore(s);
}

// The closed forms of a level's own fill: its anchors reach 2 cells into its holes, and the
// finer levels' anchors do not count (the default reaches 1 cell and counts them).
AnchorStoreSettings ownLevelFill(AnchorStoreSettings s) {
    s.reachCells = 2;
    s.finerWeight = 0.0;
    return s;
}

void put(AnchorStore& store, const LatticeKey& key, float v) {
    ASSERT_NE(store.insert(key, makeSh(v), {store.keyX_m(key), 2.0, store.keyZ_m(key)}, 1e6),
              AnchorStore::InsertResult::Rejected);
}

// The value of a coefficient set the way makeSh builds it: c[0].x == v.
float scalarOf(const ShRgb& sh) {
    return sh.c[0].x;
}

TEST(AnchorInterpolation, ExactAtAnchors) {
  for (bool smooth : {false, true}) {
    SCOPED_TRACE(smooth ? "smooth" : "bilinear");
    AnchorStore store = instantStore(smooth);
    std::mt19937 rng(11);
    std::uniform_int_distribution<int> level(0, 4), coord(-12, 12);
    std::vector<LatticeKey> keys;
    for (int n = 0; n < 150; ++n) {
        const LatticeKey k = store.canonical({level(rng), coord(rng), coord(rng)});
        if (store.find(k)) continue;
        put(store, k, 0.5f + 0.01f * n);
        keys.push_back(k);
    }
    for (const LatticeKey& k : keys) {
        InterpolationDetail d;
        const ShRgb v = store.interpolate(store.keyX_m(k), store.keyZ_m(k), &d);
        EXPECT_TRUE(d.exact);
        ASSERT_EQ(d.used.size(), 1u);
        EXPECT_EQ(d.used[0].key, k);
        EXPECT_EQ(maxDiff(v, store.find(k)->current), 0.0);
    }
  }
}

TEST(AnchorInterpolation, AllEmptyGivesTheFallback) {
  for (bool smooth : {false, true}) {
    SCOPED_TRACE(smooth ? "smooth" : "bilinear");
    AnchorStore store = instantStore(smooth);
    store.setFallback(makeSh(0.125f));
    InterpolationDetail d;
    EXPECT_EQ(maxDiff(store.interpolate(12.0, -7.0, &d), makeSh(0.125f)), 0.0);
    EXPECT_TRUE(d.fallback);
    // A level-0 anchor reaches its neighbours within 2 cells (searchCells x 243 m, less than
    // 486 m): the cells beyond (486 m and more along its row) stay the fallback.
    put(store, {0, 0, 0}, 3.0f);
    EXPECT_EQ(maxDiff(store.interpolate(487.0, 0.0, &d), makeSh(0.125f)), 0.0);
    EXPECT_TRUE(d.fallback);
    EXPECT_FALSE(store.interpolate(485.0, 0.0, &d).c[0].x == makeSh(0.125f).c[0].x);
    EXPECT_FALSE(d.fallback);
  }
}

TEST(AnchorInterpolation, MissingCornersComeFromTheCoarserLevel) {
    // A complete 9 m cell (0..9)^2 of level-3 points ((0, 0) is a level-0 point) and one 3 m
    // anchor b at (3, 0). The query (1.2, 2.1) lies in the 3 m cell (0..3)^2: corners (0, 0) and
    // (3, 0) hold anchors; (0, 3) and (3, 3) are missing and take the 9 m cell's bilinear value
    // plus b's share of its residual r = b - (9 m value at (3, 0)): they are within b's reach
    // (2 cells, 6 m) with weights K = (1 - d^2 / 4)^2 = 0.25 and 0.5625, and take K /
    // coverageDivisor(K) of r: 0.25 / (0.25 + 0.25^2) = 0.8 and (K >= 0.5) all of it. (A
    // level's own fill, ownLevelFill.)
    AnchorStoreSettings s;
    s.blendTime_s = 0.0;
    s.smoothInterpolation = false;
    AnchorStore store(ownLevelFill(s));
    const float a00 = 1.0f, a10 = 2.0f, a01 = 4.0f, a11 = 5.5f, b = 3.0f;
    put(store, store.canonical({3, 0, 0}), a00);
    put(store, {3, 1, 0}, a10);
    put(store, {3, 0, 1}, a01);
    put(store, {3, 1, 1}, a11);
    put(store, {4, 1, 0}, b);
    auto coarse = [&](double x, double z) {  // bilinear in the 9 m cell
        const double u = x / 9.0, w = z / 9.0;
        return (1 - u) * (1 - w) * a00 + u * (1 - w) * a10 + (1 - u) * w * a01 + u * w * a11;
    };
    const double r = b - coarse(3.0, 0.0);
    const double c00 = a00, c10 = b, c01 = coarse(0.0, 3.0) + 0.8 * r, c11 = coarse(3.0, 3.0) + r;
    const double u = 1.2 / 3.0, w = 2.1 / 3.0;
    const double expected =
        (1 - u) * (1 - w) * c00 + u * (1 - w) * c10 + (1 - u) * w * c01 + u * w * c11;
    InterpolationDetail d;
    const ShRgb v = store.interpolate(1.2, 2.1, &d);
    EXPECT_LT(maxDiff(v, makeSh(float(expected))), 2e-5);
    // The finest cell answered; its two anchors carry their bilinear weights.
    EXPECT_EQ(d.level, 4);
    EXPECT_FALSE(d.exact);
    ASSERT_EQ(d.used.size(), 2u);
    for (const auto& used : d.used) {
        if (used.key == LatticeKey{4, 1, 0}) {
            EXPECT_NEAR(used.weight, u * (1 - w), 1e-12);
            EXPECT_EQ(used.quadrant, 3);  // south-east of the query
        } else {
            EXPECT_EQ(used.key, (LatticeKey{0, 0, 0}));
            EXPECT_NEAR(used.weight, (1 - u) * (1 - w), 1e-12);
        }
    }
    // In the 3 m cell (6..9, 3..6) only corner (6, 3) is in reach (d^2 = 2): 0.8 r x its weight
    // 1/3 at (7.5, 4); beyond z = 6 m (out of reach) the 9 m cell alone.
    EXPECT_LT(maxDiff(store.interpolate(7.5, 4.0),
                      makeSh(float(coarse(7.5, 4.0) + 0.8 * r / 3.0))),
              2e-5);
    EXPECT_LT(maxDiff(store.interpolate(4.5, 7.5), makeSh(float(coarse(4.5, 7.5)))), 2e-5);
}

TEST(AnchorInterpolation, FinerAnchorsFillTheCoarserLevelsHoles) {
    // One 3 m anchor b at (3, 0) over the fallback f, default reach (1 cell; 2 at level 0) with
    // the finer anchors counted. Level 0 (243 m) has no anchor of its own: its points take
    // f + K (b - f) / coverageDivisor(K) with K = (1 - d^2 / 4)^2 over b's distance d in 243 m
    // cells, so all of b where K >= 0.5. The coarser value at b is then b, so the finer levels
    // add nothing, and the 243 m cells are bilinear between those corners.
    AnchorStore store = instantStore();
    const float b = 3.0f, f = 0.5f;
    store.setFallback(makeSh(f));
    put(store, {4, 1, 0}, b);
    auto corner = [&](double x, double z) {  // G_0 at a 243 m point
        const double du = (3.0 - x) / 243.0, dw = -z / 243.0, t2 = (du * du + dw * dw) / 4.0;
        if (t2 >= 1.0) return double(f);
        const double K = (1.0 - t2) * (1.0 - t2);
        return f + K * (b - f) / AnchorField::coverageDivisor(K);
    };
    ASSERT_NEAR(corner(243.0, 0.0), b, 1e-12);   // K = 0.572: whole
    ASSERT_LT(corner(243.0, 243.0), b - 0.1);    // K = 0.256: in part
    auto cell = [&](double x, double z) {  // bilinear in the 243 m cell holding (x, z)
        const double x0 = std::floor(x / 243.0) * 243.0, z0 = std::floor(z / 243.0) * 243.0;
        const double u = (x - x0) / 243.0, w = (z - z0) / 243.0;
        return (1 - u) * (1 - w) * corner(x0, z0) + u * (1 - w) * corner(x0 + 243.0, z0) +
               (1 - u) * w * corner(x0, z0 + 243.0) + u * w * corner(x0 + 243.0, z0 + 243.0);
    };
    EXPECT_LT(maxDiff(store.interpolate(100.0, 100.0), makeSh(float(cell(100.0, 100.0)))), 1e-5);
    EXPECT_LT(maxDiff(store.interpolate(-100.0, 100.0), makeSh(float(cell(-100.0, 100.0)))), 1e-5);
    EXPECT_GT(cell(100.0, 100.0), f + 0.9 * (b - f));  // mostly b, 100 m from it
    EXPECT_LT(maxDiff(store.interpolate(3.0, 0.0), makeSh(b)), 1e-6);  // exact on the anchor
    // A level's own fill alone: b reaches 2 x 3 m, so (100, 100) shows the fallback.
    AnchorStoreSettings s;
    s.blendTime_s = 0.0;
    s.smoothInterpolation = false;
    AnchorStore own(ownLevelFill(s));
    own.setFallback(makeSh(f));
    put(own, {4, 1, 0}, b);
    EXPECT_LT(maxDiff(own.interpolate(100.0, 100.0), makeSh(f)), 1e-6);
}

TEST(AnchorInterpolation, CoverageDivisorIsAtLeastTheFloorAndSmooth) {
    // f + W^2 / (4 f) below 2 f = 0.5, W above: 0.25 at 0, 0.3125 at 0.25, 0.5 at 0.5, and the
    // slope continuous at 0.5 (1 on both sides).
    EXPECT_DOUBLE_EQ(AnchorField::coverageDivisor(0.0), 0.25);
    EXPECT_DOUBLE_EQ(AnchorField::coverageDivisor(-1.0), 0.25);
    EXPECT_DOUBLE_EQ(AnchorField::coverageDivisor(0.25), 0.3125);
    EXPECT_DOUBLE_EQ(AnchorField::coverageDivisor(0.5), 0.5);
    EXPECT_DOUBLE_EQ(AnchorField::coverageDivisor(2.0), 2.0);
    const double h = 1e-6;
    const double below = (AnchorField::coverageDivisor(0.5) - AnchorField::coverageDivisor(0.5 - h)) / h;
    const double above = (AnchorField::coverageDivisor(0.5 + h) - AnchorField::coverageDivisor(0.5)) / h;
    EXPECT_NEAR(below, 1.0, 1e-5);
    EXPECT_NEAR(above, 1.0, 1e-5);
    for (double W = 0.0; W < 3.0; W += 0.01) {
        EXPECT_GE(AnchorField::coverageDivisor(W), std::max(W, 0.25) - 1e-15) << W;
        EXPECT_LE(W / AnchorField::coverageDivisor(W), 1.0 + 1e-15) << W;  // never more than all
    }
}

TEST(AnchorInterpolation, CoarsestLevelReachesIntoHolesAndFadesToTheFallback) {
    // One level-0 anchor (value v) over the fallback f: its residual is v - f. A level-0 corner
    // at d cells takes f + K p (v - f) / coverageDivisor(K p), K = (1 - (d / 2)^2)^2 (reach 2
    // cells): all of v at d = 1 (K = 0.5625), 0.8 of it at d = sqrt 2 (K = 0.25: 0.25 / 0.3125),
    // f at d = 2; the 243 m cells are bilinear between corners.
    AnchorStore store = instantStore();
    const float v = 3.0f, f = 0.5f;
    store.setFallback(makeSh(f));
    put(store, {0, 0, 0}, v);
    EXPECT_LT(maxDiff(store.interpolate(243.0, 0.0), makeSh(v)), 1e-5);
    EXPECT_LT(maxDiff(store.interpolate(-243.0, 243.0), makeSh(f + 0.8f * (v - f))), 1e-5);
    EXPECT_LT(maxDiff(store.interpolate(486.0, 0.0), makeSh(f)), 1e-6);  // d = 2: out of reach
    EXPECT_LT(maxDiff(store.interpolate(364.5, 0.0), makeSh(0.5f * (v + f))), 1e-5);
    // The hole between two anchors 2 cells apart is filled from both (K = 0.5625 each).
    put(store, {0, 2, 0}, 1.0f);
    EXPECT_LT(maxDiff(store.interpolate(243.0, 0.0), makeSh(0.5f * (v + 1.0f))), 1e-5);

    // Fading in (presence 0.2 after 0.4 s of a 2 s blend; blends and fades are read through
    // smoothstep, so its weight is p = easeInOut(0.2) = 0.104 and its current f + p (v - f)),
    // the coverage at d = 1 is W = 0.5625 p < 0.5: the corner takes W / (0.25 + W^2) of the
    // residual.
    AnchorStoreSettings s;
    s.blendTime_s = 2.0;
    s.smoothInterpolation = false;
    AnchorStore fading(s);
    fading.setFallback(makeSh(f));
    fading.insert({0, 0, 0}, makeSh(v), {0, 2, 0}, 1e6);
    fading.advance(0.4);
    const Anchor* a = fading.find({0, 0, 0});
    ASSERT_NEAR(a->presence, 0.2f, 1e-6f);
    const double p = 0.2 * 0.2 * (3.0 - 2.0 * 0.2), residual = scalarOf(a->current) - f;
    EXPECT_NEAR(easeInOut(a->presence), p, 1e-6);
    EXPECT_NEAR(residual, p * (v - f), 1e-5);
    EXPECT_LT(maxDiff(fading.interpolate(243.0, 0.0),
                      makeSh(float(f + 0.5625 * p * residual /
                                   (0.25 + 0.5625 * p * 0.5625 * p)))),
              1e-5);
}

TEST(AnchorInterpolation, BilinearFieldIsReproducedInsideCompleteCells) {
    // Every point of the 27 m lattice over [-108, 108]^2 holds f(x, z), a field linear in x and
    // z plus an xz term, and random 9 m and 3 m points inside hold it too (the rest are holes).
    // Bilinear cells reproduce a bilinear field, and so do the coarser fills of the holes; the
    // smooth cells too where a cell's corners have their neighbours (central differences and
    // their limited form are exact for such a field). The result equals f over [-54, 54]^2
    // (cells and neighbours complete at every level), to float rounding (1e-6 of the largest
    // coefficient).
  for (bool smooth : {false, true}) {
    SCOPED_TRACE(smooth ? "smooth" : "bilinear");
    AnchorStore store = instantStore(smooth);
    auto f = [](double x, double z) { return 2.0 + 0.01 * x - 0.02 * z + 1e-4 * x * z; };
    auto putAt = [&](const LatticeKey& key) {
        const LatticeKey c = store.canonical(key);
        if (!store.find(c)) put(store, c, float(f(store.keyX_m(c), store.keyZ_m(c))));
    };
    for (int i = -4; i <= 4; ++i)
        for (int k = -4; k <= 4; ++k) putAt({2, i, k});
    std::mt19937 rng(17);
    std::uniform_int_distribution<int> fine3(-9, 9), fine4(-27, 27);
    for (int n = 0; n < 80; ++n) putAt({3, fine3(rng), fine3(rng)});
    for (int n = 0; n < 300; ++n) putAt({4, fine4(rng), fine4(rng)});
    std::uniform_real_distribution<double> q(-54.0, 54.0);
    double worst = 0.0, largest = 0.0;
    for (int n = 0; n < 5000; ++n) {
        const double x = q(rng), z = q(rng);
        const ShRgb expected = makeSh(float(f(x, z)));
        worst = std::max(worst, maxDiff(store.interpolate(x, z), expected));
        largest = std::max(largest, maxDiff(expected, ShRgb{}));
    }
    EXPECT_LT(worst, 1e-6 * largest) << "largest coefficient " << largest;
  }
}

// With measured slopes (AnchorStoreSettings::gradients), each anchor's own slope replaces the
// lattice's limited central differences, and the bicubic Hermite cells reproduce a field of
// degree 2 (their cubics are exact for it given exact values and slopes): on a complete 27 m
// lattice holding f(x, z) = 2 + 0.01 x - 0.02 z + 1e-4 (x z + x^2 - 0.5 z^2) with its exact
// gradient, the result equals f to float rounding. Without slopes the limited differences of
// the same anchors miss the curvature by far more; with slopes whose radius of validity is a
// third of the spacing they count a third (AnchorField.h), and the result lies between.
TEST(AnchorInterpolation, MeasuredSlopesReproduceAQuadraticField) {
    auto f = [](double x, double z) {
        return 2.0 + 0.01 * x - 0.02 * z + 1e-4 * (x * z + x * x - 0.5 * z * z);
    };
    auto fx = [](double x, double z) { return 0.01 + 1e-4 * (z + 2.0 * x); };
    auto fz = [](double x, double z) { return -0.02 + 1e-4 * (x - z); };
    auto worstError = [&](bool gradients, float validity_m) {
        AnchorStoreSettings settings;
        settings.blendTime_s = 0.0;
        settings.gradients = gradients;
        AnchorStore store(settings);
        for (int i = -4; i <= 4; ++i)
            for (int k = -4; k <= 4; ++k) {
                const LatticeKey c = store.canonical({2, i, k});
                const double x = store.keyX_m(c), z = store.keyZ_m(c);
                ShSlope slope{makeSh(float(fx(x, z))), makeSh(float(fz(x, z))), validity_m};
                // makeSh scales every coefficient linearly: the slope of makeSh(f) is makeSh(f').
                EXPECT_NE(store.insert(c, makeSh(float(f(x, z))), {x, 2.0, z}, 1e6, 0.0, &slope),
                          AnchorStore::InsertResult::Rejected);
            }
        std::mt19937 rng(5);
        std::uniform_real_distribution<double> q(-54.0, 54.0);
        double worst = 0.0;
        for (int n = 0; n < 3000; ++n) {
            const double x = q(rng), z = q(rng);
            worst = std::max(worst, maxDiff(store.interpolate(x, z), makeSh(float(f(x, z)))));
        }
        return worst;
    };
    const double largest = maxDiff(makeSh(float(f(54.0, 54.0))), ShRgb{});
    const double with = worstError(true, 100.0f), without = worstError(false, 100.0f);
    const double third = worstError(true, 9.0f);
    EXPECT_LT(with, 1e-5 * largest);
    EXPECT_GT(without, 100.0 * with);
    EXPECT_LT(third, without);
    EXPECT_GT(third, with);
}

// A slope that is not finite (or a negative radius of validity) is dropped, the capture kept:
// NaN never enters the store. A refresh blends the slope as it blends the value.
TEST(AnchorInterpolation, BadSlopesAreDroppedAndSlopesBlend) {
    AnchorStoreSettings settings;
    settings.gradients = true;
    settings.blendTime_s = 1.0;
    AnchorStore store(settings);
    const LatticeKey c{2, 1, 1};
    ShSlope nan{makeSh(std::numeric_limits<float>::quiet_NaN()), makeSh(1.0f), 10.0f};
    ASSERT_EQ(store.insert(c, makeSh(1.0f), {27.0, 2.0, 27.0}, 1e6, 0.0, &nan),
              AnchorStore::InsertResult::Inserted);
    EXPECT_FALSE(store.slope(c).has_value());
    ShSlope negative{makeSh(1.0f), makeSh(1.0f), -1.0f};
    store.advance(2.0);
    ASSERT_EQ(store.insert(c, makeSh(1.0f), {27.0, 2.0, 27.0}, 1e6, 0.0, &negative),
              AnchorStore::InsertResult::Refreshed);
    EXPECT_FALSE(store.slope(c).has_value());
    ShSlope a{makeSh(1.0f), makeSh(-1.0f), 10.0f}, b{makeSh(3.0f), makeSh(1.0f), 20.0f};
    store.advance(4.0);
    store.insert(c, makeSh(1.0f), {27.0, 2.0, 27.0}, 1e6, 0.0, &a);
    store.advance(6.0);  // blended to a
    ASSERT_TRUE(store.slope(c).has_value());
    EXPECT_LT(maxDiff(store.slope(c)->dx, a.dx), 1e-6);
    store.insert(c, makeSh(1.0f), {27.0, 2.0, 27.0}, 1e6, 0.0, &b);
    store.advance(6.5);  // halfway: smoothstep(0.5) = 0.5
    const ShSlope half = *store.slope(c);
    EXPECT_LT(maxDiff(half.dx, makeSh(2.0f)), 1e-5);
    EXPECT_LT(maxDiff(half.dz, makeSh(0.0f)), 1e-5);
    EXPECT_NEAR(half.validity_m, 15.0f, 1e-4f);
    EXPECT_TRUE(allFinite(store.interpolate(30.0, 20.0)));
}

TEST(AnchorInterpolation, NearestAnchorIsTheNearestPresentOneInReach) {
    AnchorStore store = instantStore();
    put(store, {4, 1, 1}, 1.0f);  // (3, 3)
    put(store, {4, 2, 1}, 9.0f);  // (6, 3)
    put(store, {1, -1, 0}, 5.0f);  // (-81, 0)
    const Anchor* a = store.nearestAnchor(5.0, 2.0);
    ASSERT_NE(a, nullptr);
    EXPECT_EQ(a->key, (LatticeKey{4, 2, 1}));
    EXPECT_EQ(store.nearestAnchor(4.0, 3.5)->key, (LatticeKey{4, 1, 1}));
    // Beyond the 3 m level's reach (2 cells) the coarser levels' search finds (-81, 0).
    EXPECT_EQ(store.nearestAnchor(-60.0, 0.0)->key, (LatticeKey{1, -1, 0}));
    // Out of every level's reach: none.
    EXPECT_EQ(store.nearestAnchor(5000.0, 0.0), nullptr);
    // An anchor fading in at presence 0 is not there yet.
    AnchorStoreSettings s;
    s.blendTime_s = 2.0;
    s.smoothInterpolation = false;
    AnchorStore fading(s);
    fading.insert({4, 1, 1}, makeSh(1.0f), {3, 2, 3}, 100.0);
    EXPECT_EQ(fading.nearestAnchor(3.0, 3.0), nullptr);
    fading.advance(0.5);
    EXPECT_NE(fading.nearestAnchor(3.0, 3.0), nullptr);
}

TEST(AnchorInterpolation, CoincidentPointsFarFromOrigin) {
  for (bool smooth : {false, true}) {
    SCOPED_TRACE(smooth ? "smooth" : "bilinear");
    AnchorStore store = instantStore(smooth);
    const LatticeKey k = store.keyNear(1.0e7, -1.0e7, 4);
    put(store, k, 2.0f);
    put(store, {k.level, k.i + 2, k.k + 1}, 4.0f);
    const double x = store.keyX_m(k), z = store.keyZ_m(k);
    InterpolationDetail d;
    EXPECT_EQ(maxDiff(store.interpolate(x, z, &d), makeSh(2.0f)), 0.0);
    EXPECT_TRUE(d.exact);
    // One double away (1.9e-9 m at 10^7 m): the same float value.
    EXPECT_EQ(maxDiff(store.interpolate(std::nextafter(x, 0.0), z, &d), makeSh(2.0f)), 0.0);
    // 1.4e-4 m away: continuous with it. The other anchor is D >= 9 m away, so the result moves
    // by at most (value difference) x distance / (D - distance); bound with D = 5 m.
    const ShRgb v = store.interpolate(x + 1e-4, z + 1e-4, &d);
    EXPECT_FALSE(d.exact);
    EXPECT_LT(maxDiff(v, makeSh(2.0f)), maxDiff(makeSh(4.0f), makeSh(2.0f)) * 1.5e-4 / 5.0);
  }
}

TEST(AnchorInterpolation, NeverNaN) {
  for (bool smooth : {false, true}) {
    AnchorStore store = instantStore(smooth);
    store.setFallback(makeSh(0.5f));
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double inf = std::numeric_limits<double>::infinity();
    for (double q : {nan, inf, -inf, 1e300, -1e12}) {
        EXPECT_TRUE(allFinite(store.interpolate(q, 0.0)));
        EXPECT_TRUE(allFinite(store.interpolate(0.0, q)));
    }
    put(store, {4, 0, 0}, 1.0f);
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-600.0, 600.0);
    for (int n = 0; n < 2000; ++n) EXPECT_TRUE(allFinite(store.interpolate(u(rng), u(rng))));
    EXPECT_EQ(maxDiff(store.interpolate(nan, 1.0), makeSh(0.5f)), 0.0);
  }
}

// A store of three levels (27, 9 and 3 m) with holes around the origin: anchors present,
// fading in, refreshed mid-blend, fading out at the end of their lifetime, relit.
AnchorStore randomStore(unsigned seed, bool smooth, std::vector<LatticeKey>* keys = nullptr) {
    AnchorStoreSettings s;
    s.blendTime_s = 2.0;
    s.smoothInterpolation = smooth;
    AnchorStore store(s);
    store.setFallback(makeSh(0.3f));
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> value(0.5f, 5.0f), u(0.0f, 1.0f);
    const std::pair<int, float> levels[] = {{2, 0.6f}, {3, 0.35f}, {4, 0.2f}};  // level, share
    auto fill = [&](float lifetime_s) {
        for (const auto& [L, share] : levels) {
            const int n = int(std::lround(72.0 / store.spacing_m(L)));  // +-72 m
            for (int i = -n; i <= n; ++i) {
                for (int k = -n; k <= n; ++k) {
                    if (u(rng) >= share) continue;
                    const LatticeKey key = store.canonical({L, i, k});
                    store.insert(key, makeSh(value(rng)),
                                 {store.keyX_m(key), 2.0, store.keyZ_m(key)},
                                 u(rng) < 0.1f ? 3.0 : lifetime_s);
                    if (keys) keys->push_back(key);
                }
            }
        }
    };
    fill(100.0f);
    store.advance(2.5);  // present, a few ending their 3 s lives
    fill(100.0f);        // refreshes and new anchors
    store.advance(3.5);  // some fading in or out, some mid-blend
    store.relight([&](const Anchor&) { return 0.75f + 0.5f * u(rng); });
    return store;
}

// Walks 200 random lines of 20 m at 1 cm steps through a random store; calls
// step(line, n, previous value, value) for every step.
template <class Step>
void walk(const AnchorStore& store, Step&& step) {
    std::mt19937 rng(43);
    std::uniform_real_distribution<double> start(-70.0, 70.0), angle(0.0, 2.0 * kPi);
    for (int line = 0; line < 200; ++line) {
        const double x0 = start(rng), z0 = start(rng), t = angle(rng);
        const double cx = std::cos(t), cz = std::sin(t);
        ShRgb prev = store.interpolate(x0, z0);
        for (int n = 1; n <= 2000; ++n) {
            const ShRgb v = store.interpolate(x0 + n * 0.01 * cx, z0 + n * 0.01 * cz);
            step(line, n, std::fabs(cx) + std::fabs(cz), prev, v);
            prev = v;
        }
    }
}

TEST(AnchorInterpolation, RandomWalksStayWithinTheLipschitzBound) {
    // Bound (AnchorStore::interpolationSlopeBound, AnchorField::slopeBound): per coefficient j,
    // |d f_j / dx| and |d f_j / dz| are at most g_j, from the cells' corner data (bilinear: the
    // larger edge difference / s_L; smooth: the Hermite basis' bound on values and slopes). A
    // step h along (cos t, sin t) then changes f_j by at most (|cos t| + |sin t|) g_j h, whatever
    // cells, lattice lines or levels it crosses; float rounding adds at most 2e-6 of the
    // largest coefficient. A jump (the old four-quadrant rule changed by 0.17 of the
    // neighbour-to-neighbour difference within 1 cm) would break it by two orders of magnitude.
    // Bilinear corner values are convex mixes of the anchors and the fallback, so there g_j is
    // also at most (their range) / 3 m, which is checked too.
  for (bool smooth : {false, true}) {
    SCOPED_TRACE(smooth ? "smooth" : "bilinear");
    AnchorStore store = randomStore(41, smooth);
    int fading = 0;
    std::array<double, 3 * kShCoefficients> lo, hi;
    lo.fill(1e300), hi.fill(-1e300);
    auto extend = [&](const ShRgb& sh) {
        for (int k = 0; k < kShCoefficients; ++k)
            for (int ch = 0; ch < 3; ++ch) {
                lo[3 * k + ch] = std::min(lo[3 * k + ch], double(sh.c[k][ch]));
                hi[3 * k + ch] = std::max(hi[3 * k + ch], double(sh.c[k][ch]));
            }
    };
    extend(store.fallback());
    store.forEach([&](const Anchor& a) {
        extend(a.current * a.relight);
        fading += a.presence > 0.0f && a.presence < 1.0f;
    });
    ASSERT_GT(fading, 20);  // the walk crosses fading anchors too
    double largest = 0.0;
    for (int j = 0; j < 3 * kShCoefficients; ++j) largest = std::max({largest, -lo[j], hi[j]});
    const std::array<double, 27> g = store.interpolationSlopeBound();
    const double h = 0.01, tol = 2e-6 * largest;
    if (!smooth) {
        for (int j = 0; j < 3 * kShCoefficients; ++j) EXPECT_LE(g[j], (hi[j] - lo[j]) / 3.0 + 1e-9);
    }
    double worstRatio = 0.0;  // largest step / bound seen
    walk(store, [&](int line, int n, double axes, const ShRgb& prev, const ShRgb& v) {
        for (int k = 0; k < kShCoefficients; ++k) {
            for (int ch = 0; ch < 3; ++ch) {
                const int j = 3 * k + ch;
                const double bound = axes * g[j] * h;
                const double step = std::fabs(double(v.c[k][ch]) - prev.c[k][ch]);
                ASSERT_LE(step, bound + tol)
                    << "line " << line << " step " << n << " coefficient " << j;
                worstRatio = std::max(worstRatio, step / bound);
            }
        }
    });
    // The walks do see real gradients (the bound is not vacuous).
    EXPECT_GT(worstRatio, 0.05);
  }
}

TEST(AnchorInterpolation, SmoothCellsHaveNoKinks) {
    // Along the same walks, the change of the step from one step to the next (the second
    // difference, what a moving object sees as a pop) is, for a C1 field with bounded curvature,
    // of order h^2, and only at a kink of order h: |d2 f_j| <= 0.1 x g_j h, g_j the slope bound,
    // at 1 cm steps. Bilinear cells kink at every lattice line; the smooth ones never.
    double worst[2] = {0.0, 0.0};
    for (bool smooth : {false, true}) {
        const AnchorStore store = randomStore(41, smooth);
        const std::array<double, 27> g = store.interpolationSlopeBound();
        std::vector<double> lastStep(27, 0.0);
        walk(store, [&](int, int n, double, const ShRgb& prev, const ShRgb& v) {
            for (int j = 0; j < 27; ++j) {
                const double step = double(v.c[j / 3][j % 3]) - prev.c[j / 3][j % 3];
                if (n > 1) worst[smooth] = std::max(worst[smooth], std::fabs(step - lastStep[j]) / (g[j] * 0.01));
                lastStep[j] = step;
            }
        });
    }
    EXPECT_LT(worst[1], 0.1) << "smooth";
    EXPECT_GT(worst[0], 0.1) << "bilinear (the test can tell a kink)";
}

TEST(AnchorInterpolation, InsertingAnAnchorChangesNothingAtItsInstant) {
    // New anchors (presence 0) anywhere in a busy store, and refreshes of existing ones: the
    // value at every point is bit for bit what it was.
    std::vector<LatticeKey> keys;
  for (bool smooth : {false, true}) {
    SCOPED_TRACE(smooth ? "smooth" : "bilinear");
    keys.clear();
    AnchorStore store = randomStore(47, smooth, &keys);
    std::mt19937 rng(49);
    std::uniform_real_distribution<double> q(-80.0, 80.0);
    std::vector<std::pair<double, double>> points;
    for (int n = 0; n < 3000; ++n) points.push_back({q(rng), q(rng)});
    for (const LatticeKey& k : keys) {  // the anchors' own positions too
        if (store.find(k)) points.push_back({store.keyX_m(k), store.keyZ_m(k)});
    }
    std::vector<ShRgb> before;
    for (auto [x, z] : points) before.push_back(store.interpolate(x, z));
    std::uniform_int_distribution<int> level(0, 4), coord(-30, 30);
    std::uniform_real_distribution<float> value(0.0f, 20.0f);
    int inserted = 0, refreshed = 0;
    for (int n = 0; n < 200; ++n) {
        const LatticeKey key = store.canonical({level(rng), coord(rng), coord(rng)});
        const auto r = store.insert(key, makeSh(value(rng)),
                                    {store.keyX_m(key), 2.0, store.keyZ_m(key)}, 50.0);
        inserted += r == AnchorStore::InsertResult::Inserted;
        refreshed += r == AnchorStore::InsertResult::Refreshed;
    }
    ASSERT_GT(inserted, 50);
    ASSERT_GT(refreshed, 10);
    store.setFallback(store.fallback());  // rebuild the cache from the anchors as they are now
    for (std::size_t p = 0; p < points.size(); ++p) {
        ASSERT_EQ(maxDiff(store.interpolate(points[p].first, points[p].second), before[p]), 0.0)
            << "at " << points[p].first << ", " << points[p].second;
    }
    // And they do take effect afterwards.
    store.advance(store.now_s() + 2.0);
    double moved = 0.0;
    for (std::size_t p = 0; p < points.size(); ++p)
        moved = std::max(moved, maxDiff(store.interpolate(points[p].first, points[p].second),
                                        before[p]));
    EXPECT_GT(moved, 1.0);
  }
}

TEST(AnchorInterpolation, ThesisPatternChangeExample) {
    // Thesis 7.6: corners 1, 2, 4, 5 of a square, a new point 8 on edge 1-4 carrying what the
    // structure interpolates there; in the thesis' scheme point 7 still changes, because the
    // interpolation pattern does. Here the square is the 27 m cell (0..27)^2, point 8 is the 9 m
    // point (0, 18) and point 7 lies 0.6 along 1-2 and 0.7 along 1-4.
    auto build = [](double blendTime_s) {
        AnchorStoreSettings s;
        s.blendTime_s = blendTime_s;
        s.smoothInterpolation = false;  // the closed forms below are bilinear
        AnchorStore store(ownLevelFill(s));
        for (auto [key, v] : {std::pair<LatticeKey, float>{{2, 0, 0}, 1.0f},
                              {{2, 1, 0}, 2.0f},
                              {{2, 0, 1}, 4.0f},
                              {{2, 1, 1}, 5.5f}}) {
            store.insert(key, makeSh(v), {0, 2, 0}, 1e6);
        }
        store.advance(blendTime_s + 1.0);  // all present and blended
        return store;
    };
    const LatticeKey k8{3, 0, 2};
    // Probes: 7, two points in the 9 m cells beside 8, a point two cells below it, one beyond
    // 8's reach (18 m); and, for a capture 3 above what the square shows at 8, the sum over the
    // probe's 9 m corners that are not corners of the square (present anchors keep their
    // values) of bilinear weight x the share of the residual 3 each takes: 1 at 8 itself and at
    // d^2 = 1 cell^2 (K = 0.5625), 0.8 at d^2 = 2 (K = 0.25: K / coverageDivisor(K)), 0 from
    // d^2 = 4 on. 7 (u = 0.8, w = 0.1 in cell (9..18, 18..27)): corners (9, 18) and (9, 27);
    // (2.7, 16.2) (u = 0.3, w = 0.8): all four, (9, 9) at d^2 = 2; (4.5, 21.6) (u = 0.5,
    // w = 0.4): 8, (9, 18) and (9, 27), (0, 27) being corner 4; (3, 4) (u = 1/3, w = 4/9):
    // (0, 9) and (9, 9); (25, 2): none.
    const std::vector<std::pair<double, double>> probes = {
        {0.6 * 27.0, 0.7 * 27.0}, {2.7, 16.2}, {4.5, 21.6}, {3.0, 4.0}, {25.0, 2.0}};
    const std::vector<double> share = {
        0.2 * 0.9 + 0.2 * 0.1 * 0.8, 1.0 - 0.3 * 0.2 * (1.0 - 0.8), 0.5 * 0.6 + 0.5 * 0.6 + 0.5 * 0.4 * 0.8,
        (4.0 / 9.0) * (2.0 / 3.0 + 0.8 / 3.0), 0.0};
    auto values = [&](const AnchorStore& store) {
        std::vector<ShRgb> out;
        for (auto [x, z] : probes) out.push_back(store.interpolate(x, z));
        return out;
    };

    // Hierarchical fill: point 8 carrying the interpolated value changes nothing, even inserted
    // at full weight (to float rounding): its residual is 0.
    AnchorStore naive = build(0.0);
    const std::vector<ShRgb> before = values(naive);
    const ShRgb at8 = naive.interpolate(0.0, 18.0);
    naive.insert(k8, at8, {0, 2, 18}, 1e6);
    std::vector<ShRgb> after = values(naive);
    for (std::size_t p = 0; p < probes.size(); ++p) EXPECT_LT(maxDiff(after[p], before[p]), 2e-5);

    // A capture that differs by 3, inserted at full weight, jumps by 3 x the share.
    const ShRgb captured = at8 + makeSh(3.0f);
    naive.insert(k8, captured, {0, 2, 18}, 1e6);
    after = values(naive);
    for (std::size_t p = 0; p < probes.size(); ++p) {
        EXPECT_LT(maxDiff(after[p], before[p] + makeSh(float(3.0 * share[p]))), 2e-5)
            << "probe " << p;
    }
    const double naiveJump = maxDiff(after[1], before[1]);

    // The store's insertion: nothing changes at the instant; then the pattern moves to the new
    // one over the blend time in small steps (60 Hz) and ends where the naive insertion jumped.
    AnchorStore store = build(2.0);
    store.insert(k8, captured, {0, 2, 18}, 1e6);
    const std::vector<ShRgb> still = values(store);
    for (std::size_t p = 0; p < probes.size(); ++p) EXPECT_EQ(maxDiff(still[p], before[p]), 0.0);
    double largestStep = 0.0;
    ShRgb prev = still[1];
    const double t0 = store.now_s();
    for (int f = 1; f <= 150; ++f) {
        store.advance(t0 + f / 60.0);
        const ShRgb v = store.interpolate(probes[1].first, probes[1].second);
        largestStep = std::max(largestStep, maxDiff(v, prev));
        prev = v;
    }
    EXPECT_LT(maxDiff(prev, after[1]), 1e-4);
    EXPECT_LT(largestStep, 0.05 * naiveJump);
}

TEST(AnchorInterpolation, ManyPointsInParallelEqualOneByOne) {
  for (bool smooth : {false, true}) {
    AnchorStore store = instantStore(smooth);
    std::mt19937 rng(8);
    std::uniform_int_distribution<int> level(1, 4), coord(-20, 20);
    for (int n = 0; n < 300; ++n)
        put(store, store.canonical({level(rng), coord(rng), coord(rng)}), 0.1f * (n % 17));
    std::uniform_real_distribution<double> u(-300.0, 300.0);
    std::vector<double> x(5000), z(5000);
    for (std::size_t i = 0; i < x.size(); ++i) {
        x[i] = u(rng);
        z[i] = u(rng);
    }
    std::vector<ShRgb> out(x.size());
    store.interpolateMany(x.size(), x.data(), z.data(), out.data());
    for (std::size_t i = 0; i < x.size(); ++i) {
        ASSERT_EQ(maxDiff(out[i], store.interpolate(x[i], z[i])), 0.0) << i;
    }
  }
}

TEST(AnchorInterpolation, FixedPointsReadTheBilinearCells) {
    // The same anchors (three levels with holes) in a smooth store and in a bilinear one: the
    // smooth store's fixed-point lookups are the bilinear store's lookups, bit for bit, one by
    // one and in batches; its moving-point lookups differ between lattice points. (Inserted at
    // once: a blended insertion starts from the value each store shows, which differs.)
    AnchorStore smooth = instantStore(true), bilinear = instantStore(false);
    std::mt19937 rng(9);
    std::uniform_int_distribution<int> level(2, 4), coord(-12, 12);
    std::uniform_real_distribution<float> value(0.5f, 5.0f);
    for (int n = 0; n < 400; ++n) {
        const LatticeKey key = smooth.canonical({level(rng), coord(rng), coord(rng)});
        const float v = value(rng);
        put(smooth, key, v);
        put(bilinear, key, v);
    }
    std::uniform_real_distribution<double> u(-90.0, 90.0);
    std::vector<double> x(3000), z(3000);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = u(rng), z[i] = u(rng);
    std::vector<ShRgb> batch(x.size());
    smooth.interpolateFixedMany(x.size(), x.data(), z.data(), batch.data());
    double apart = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
        const ShRgb fixed = smooth.interpolateFixed(x[i], z[i]);
        ASSERT_EQ(maxDiff(fixed, bilinear.interpolate(x[i], z[i])), 0.0) << i;
        ASSERT_EQ(maxDiff(batch[i], fixed), 0.0) << i;
        apart = std::max(apart, maxDiff(fixed, smooth.interpolate(x[i], z[i])));
    }
    EXPECT_GT(apart, 1e-3);
    // Without bilinearFixedPoints, fixed points read interpolate().
    AnchorStoreSettings s;
    s.blendTime_s = 0.0;
    s.bilinearFixedPoints = false;
    AnchorStore one(s);
    put(one, {4, 0, 0}, 1.0f);
    put(one, {4, 1, 1}, 3.0f);
    put(one, {3, 1, 0}, 2.0f);
    for (std::size_t i = 0; i < 500; ++i) {
        const double px = 0.01 * u(rng), pz = 0.01 * u(rng);
        ASSERT_EQ(maxDiff(one.interpolateFixed(px, pz), one.interpolate(px, pz)), 0.0);
    }
}

TEST(AnchorInterpolation, PartialPresenceBlendsWithTheValueBeneath) {
    // A fading-in anchor of presence weight p at a corner gives it p x current + (1 - p) x (the value
    // without it). Without it, (3, 0) shows the fallback f plus the residual 1 - f of the anchor
    // at (6, 0), one cell away (K = 0.5625, above the coverage floor: all of it): 1.
    AnchorStoreSettings s;
    s.blendTime_s = 2.0;
    s.smoothInterpolation = false;
    AnchorStore store(ownLevelFill(s));
    const float f = 0.5f;
    store.setFallback(makeSh(f));
    store.insert({4, 2, 0}, makeSh(1.0f), {6, 2, 0}, 1e6);  // (6, 0)
    store.advance(2.0);
    store.insert({4, 1, 0}, makeSh(3.0f), {3, 2, 0}, 1e6);  // (3, 0): starts from 1, shown there
    store.advance(2.5);  // a quarter of the blend time: presence 0.25, read as smoothstep(0.25)
    const Anchor* young = store.find({4, 1, 0});
    ASSERT_NEAR(young->presence, 0.25f, 1e-6f);
    const double p = 0.25 * 0.25 * (3.0 - 2.0 * 0.25);  // 0.15625
    const double v = scalarOf(young->current);
    EXPECT_NEAR(v, 1.0 + p * (3.0 - 1.0), 1e-6);
    const double corner = p * v + (1.0 - p) * 1.0;
    EXPECT_LT(maxDiff(store.interpolate(3.0, 0.0), makeSh(float(corner))), 1e-5);
    // Half-way to the present anchor at (6, 0).
    EXPECT_LT(maxDiff(store.interpolate(4.5, 0.0), makeSh(float(0.5 * corner + 0.5))), 1e-5);
    InterpolationDetail d;
    store.interpolate(4.5, 0.0, &d);
    ASSERT_EQ(d.used.size(), 2u);
    double w = 0.0;
    for (const auto& used : d.used) w += used.weight;
    EXPECT_NEAR(w, 0.5 * p + 0.5, 1e-6);  // bilinear weight x presence weight
}

}  // namespace
}  // namespace amb
