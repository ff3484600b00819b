// AnchorInterpolation_test.cpp — the four-quadrant rule (thesis 9.3) of AnchorStore::interpolate:
// exact at anchors, closed-form weights, empty quadrants, all empty, coarser levels, coincident
// points, a continuity sweep, never NaN, and the pattern-change example of thesis 7.6.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "lighting/AnchorStore.h"

namespace amb {
namespace {

ShRgb makeSh(float v) {
    ShRgb sh;
    for (int k = 0; k < kShCoefficients; ++k) {
        sh.c[k] = glm::vec3(v * (1.0f + k), v * (0.5f + 0.25f * k), v * (2.0f - 0.1f * k));
    }
    return sh;
}

// Largest absolute coefficient difference.
double maxDiff(const ShRgb& a, const ShRgb& b) {
    double m = 0.0;
    for (int k = 0; k < kShCoefficients; ++k) {
        for (int ch = 0; ch < 3; ++ch) m = std::max(m, std::fabs(double(a.c[k][ch]) - b.c[k][ch]));
    }
    return m;
}

bool allFinite(const ShRgb& sh) {
    for (int k = 0; k < kShCoefficients; ++k) {
        for (int ch = 0; ch < 3; ++ch) {
            if (!std::isfinite(sh.c[k][ch])) return false;
        }
    }
    return true;
}

// A store whose anchors are inserted at once at full weight (blend time 0).
AnchorStore instantStore() {
    AnchorStoreSettings s;
    s.blendTime_s = 0.0;
    return AnchorStore(s);
}

void put(AnchorStore& store, const LatticeKey& key, float v) {
    ASSERT_NE(store.insert(key, makeSh(v), {store.keyX_m(key), 2.0, store.keyZ_m(key)}, 1e6),
              AnchorStore::InsertResult::Rejected);
}

// Inverse-distance weighted mix of scalar multipliers of makeSh: the closed form of the rule.
ShRgb idw(const std::vector<std::pair<double, float>>& distanceAndValue) {
    double num = 0.0, den = 0.0;
    for (const auto& [d, v] : distanceAndValue) {
        num += v / d;
        den += 1.0 / d;
    }
    return makeSh(float(num / den));
}

TEST(AnchorInterpolation, ExactAtAnchors) {
    AnchorStore store = instantStore();
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

TEST(AnchorInterpolation, AllEmptyGivesTheFallback) {
    AnchorStore store = instantStore();
    store.setFallback(makeSh(0.125f));
    InterpolationDetail d;
    EXPECT_EQ(maxDiff(store.interpolate(12.0, -7.0, &d), makeSh(0.125f)), 0.0);
    EXPECT_TRUE(d.fallback);
    // An anchor out of every level's reach (2 x 243 m) changes nothing.
    put(store, {0, 0, 0}, 3.0f);
    EXPECT_EQ(maxDiff(store.interpolate(487.0, 0.0, &d), makeSh(0.125f)), 0.0);
    EXPECT_TRUE(d.fallback);
    EXPECT_FALSE(store.interpolate(485.0, 0.0, &d).c[0].x == makeSh(0.125f).c[0].x);
    EXPECT_FALSE(d.fallback);
}

TEST(AnchorInterpolation, EmptyQuadrantsUseTheOthers) {
    AnchorStore store = instantStore();
    // One anchor, north-east of the query: the result is that anchor.
    put(store, {4, 1, 1}, 2.0f);  // (3, 3)
    InterpolationDetail d;
    ShRgb v = store.interpolate(0.5, 0.0, &d);
    ASSERT_EQ(d.used.size(), 1u);
    EXPECT_EQ(d.used[0].quadrant, 0);
    EXPECT_LT(maxDiff(v, makeSh(2.0f)), 1e-5);
    // A second one, south-west: inverse-distance weights of the two (closed form).
    put(store, {4, -1, -1}, 6.0f);  // (-3, -3)
    v = store.interpolate(0.5, 0.0, &d);
    ASSERT_EQ(d.used.size(), 2u);
    const double d1 = std::hypot(2.5, 3.0), d2 = std::hypot(3.5, 3.0);
    EXPECT_LT(maxDiff(v, idw({{d1, 2.0f}, {d2, 6.0f}})), 1e-4);
    double wsum = 0.0;
    for (const auto& u : d.used) wsum += u.weight;
    EXPECT_NEAR(wsum, 1.0, 1e-12);
}

TEST(AnchorInterpolation, FullLatticeUsesTheFourCellCorners) {
    AnchorStore store = instantStore();
    for (int i = -5; i <= 5; ++i) {
        for (int k = -5; k <= 5; ++k)
            put(store, store.canonical({4, i, k}), 1.0f + 0.1f * i + 0.03f * k * k);
    }
    auto value = [](int i, int k) { return 1.0f + 0.1f * i + 0.03f * k * k; };
    // Query (1.2, 2.1) lies in the cell with corners (0..3) x (0..3).
    InterpolationDetail d;
    const ShRgb v = store.interpolate(1.2, 2.1, &d);
    std::set<std::tuple<std::int64_t, std::int64_t, int>> used;
    for (const auto& u : d.used) used.insert({store.fineI(u.key), store.fineK(u.key), u.quadrant});
    const std::set<std::tuple<std::int64_t, std::int64_t, int>> corners = {
        {1, 1, 0}, {0, 1, 1}, {0, 0, 2}, {1, 0, 3}};
    EXPECT_EQ(used, corners);
    const ShRgb expected = idw({{std::hypot(1.8, 0.9), value(1, 1)},
                                {std::hypot(1.2, 0.9), value(0, 1)},
                                {std::hypot(1.2, 2.1), value(0, 0)},
                                {std::hypot(1.8, 2.1), value(1, 0)}});
    EXPECT_LT(maxDiff(v, expected), 2e-5);
}

TEST(AnchorInterpolation, NearestInAQuadrantOnly) {
    AnchorStore store = instantStore();
    put(store, {4, 1, 1}, 1.0f);  // (3, 3): nearest north-east
    put(store, {4, 2, 1}, 9.0f);  // (6, 3): same quadrant, farther
    InterpolationDetail d;
    const ShRgb v = store.interpolate(0.0, 0.0 - 0.5, &d);
    ASSERT_EQ(d.used.size(), 1u);
    EXPECT_EQ(d.used[0].key, (LatticeKey{4, 1, 1}));
    EXPECT_LT(maxDiff(v, makeSh(1.0f)), 1e-5);
}

TEST(AnchorInterpolation, CoarserLevelsFillQuadrantsTheFinestLeavesEmpty) {
    AnchorStore store = instantStore();
    put(store, {4, 1, 1}, 1.0f);   // (3, 3) north-east, found at the finest pass (radius 6 m)
    put(store, {1, -1, 0}, 5.0f);  // (-81, 0) west: only the level-1 pass (radius 162 m) sees it
    put(store, {2, -4, 0}, 7.0f);  // (-108, 0): also west but farther; not used
    InterpolationDetail d;
    const ShRgb v = store.interpolate(0.5, -0.5, &d);
    ASSERT_EQ(d.used.size(), 2u);
    std::set<int> quadrants;
    for (const auto& u : d.used) quadrants.insert(u.quadrant);
    EXPECT_EQ(quadrants, (std::set<int>{0, 1}));
    const ShRgb expected = idw({{std::hypot(2.5, 3.5), 1.0f}, {std::hypot(81.5, 0.5), 5.0f}});
    EXPECT_LT(maxDiff(v, expected), 1e-4);
    // A finer anchor in that quadrant, nearer, takes over (finest level first).
    put(store, {3, -1, 1}, 3.0f);  // (-9, 9)
    store.interpolate(0.5, -0.5, &d);
    bool sawFine = false, sawCoarse = false;
    for (const auto& u : d.used) {
        sawFine |= u.key == LatticeKey{3, -1, 1};
        sawCoarse |= u.key == LatticeKey{1, -1, 0};
    }
    EXPECT_TRUE(sawFine);
    EXPECT_FALSE(sawCoarse);
}

TEST(AnchorInterpolation, CoincidentPointsFarFromOrigin) {
    AnchorStore store = instantStore();
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

TEST(AnchorInterpolation, NeverNaN) {
    AnchorStore store = instantStore();
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

// Identity of a selection: which anchor in which quadrant.
std::vector<std::tuple<int, int, int, int>> selection(const InterpolationDetail& d) {
    std::vector<std::tuple<int, int, int, int>> s;
    for (const auto& u : d.used) s.push_back({u.key.level, u.key.i, u.key.k, u.quadrant});
    std::sort(s.begin(), s.end());
    return s;
}

TEST(AnchorInterpolation, ContinuitySweep) {
    // Mixed levels, random values. Sweeping the query in 1 mm steps, the result may only jump
    // where the selection changes (AnchorStore.h "Where the result may jump"); elsewhere each
    // step changes it by at most (value range) x step / (nearest used distance) — the Lipschitz
    // bound of inverse-distance weights — with a factor 2 for the step.
    AnchorStore store = instantStore();
    std::mt19937 rng(21);
    std::uniform_int_distribution<int> level(2, 4), coord(-9, 9);
    std::uniform_real_distribution<float> value(0.5f, 5.0f);
    for (int n = 0; n < 120; ++n)
        put(store, store.canonical({level(rng), coord(rng), coord(rng)}), value(rng));
    const double range = 5.0 * 9.0;  // makeSh spread: largest coefficient multiplier is 9
    const double h = 1e-3;
    InterpolationDetail prevD, d;
    ShRgb prev = store.interpolate(-40.0, -13.3, &prevD);
    int jumps = 0, selectionChanges = 0;
    for (int s = 1; s <= 80000; ++s) {
        const double t = s * h;
        const ShRgb v = store.interpolate(-40.0 + t, -13.3 + 0.37 * t, &d);
        ASSERT_TRUE(allFinite(v));
        double dmin = 1e300;
        for (const auto& u : d.used) dmin = std::min(dmin, u.distance_m);
        for (const auto& u : prevD.used) dmin = std::min(dmin, u.distance_m);
        const bool same = selection(d) == selection(prevD);
        const double change = maxDiff(v, prev);
        if (same) {
            ASSERT_LE(change, 2.0 * range * h / dmin + 1e-5) << "unexplained jump at t = " << t;
        } else {
            ++selectionChanges;
            if (change > 2.0 * range * h / dmin + 1e-5) ++jumps;
        }
        prev = v;
        prevD = d;
    }
    // The rule does change along the way, and some of its changes are real jumps.
    EXPECT_GT(selectionChanges, 0);
    EXPECT_GT(jumps, 0);
}

TEST(AnchorInterpolation, OnAFullLatticeTheRuleChangesOnlyOnLatticeLines) {
    // One level, every point present: the selection is a cell's four corners, so it changes
    // exactly where the sweep crosses x = 3i or z = 3k (the documented quadrant changes).
    AnchorStore store = instantStore();
    for (int i = -8; i <= 8; ++i) {
        for (int k = -8; k <= 8; ++k)
            put(store, store.canonical({4, i, k}), 1.0f + 0.05f * ((i * 7 + k * 3) % 11));
    }
    // With the half-open quadrants (dx >= 0 east, dz >= 0 north) the corners are those of cell
    // (ceil(x / 3), ceil(z / 3)): the selection changes exactly when that index changes.
    const double h = 1.0 / 512.0;  // exact in binary, so lattice lines are hit exactly
    InterpolationDetail prevD, d;
    store.interpolate(-10.0, -7.0, &prevD);
    int changes = 0;
    for (int s = 1; s <= 8192; ++s) {
        const double x = -10.0 + s * h, z = -7.0 + 0.5 * s * h;
        store.interpolate(x, z, &d);
        const double xp = x - h, zp = z - 0.5 * h;
        const bool cellChanged =
            std::ceil(x / 3.0) != std::ceil(xp / 3.0) || std::ceil(z / 3.0) != std::ceil(zp / 3.0);
        if (!d.exact && !prevD.exact) {
            EXPECT_EQ(selection(d) != selection(prevD), cellChanged) << "at x = " << x;
            changes += cellChanged;
        }
        prevD = d;
    }
    EXPECT_GE(changes, 8);
}

TEST(AnchorInterpolation, ThesisPatternChangeExample) {
    // Thesis 7.6: corners 1, 2, 4, 5 of a square, point 7 at 0.6 along 1-2 and 0.7 along 1-4.
    // A new point 8 on edge 1-4 whose value is what the structure interpolates there still
    // changes point 7, because the interpolation pattern changes. Here the square is the
    // level-2 cell (0..27 m)^2 and point 8 is (0, 18) on edge 1-4 (a level-3 point, nearer to 7
    // than corner 1, so it replaces 1 in 7's south-west quadrant).
    auto build = [](double blendTime_s) {
        AnchorStoreSettings s;
        s.blendTime_s = blendTime_s;
        AnchorStore store(s);
        for (auto [key, v] : {std::pair<LatticeKey, float>{{2, 0, 0}, 1.0f},
                              {{2, 1, 0}, 2.0f},
                              {{2, 0, 1}, 4.0f},
                              {{2, 1, 1}, 5.0f}}) {
            store.insert(key, makeSh(v), {0, 2, 0}, 1e6);
        }
        store.advance(blendTime_s + 1.0);  // all present and blended
        return store;
    };
    const double x7 = 0.6 * 27.0, z7 = 0.7 * 27.0;
    const LatticeKey k8{3, 0, 2};

    // Naive insertion (no fade): the value at 7 jumps although 8 carries the interpolated value.
    AnchorStore naive = build(0.0);
    const ShRgb before = naive.interpolate(x7, z7);
    const ShRgb at8 = naive.interpolate(0.0, 18.0);
    naive.insert(k8, at8, {0, 2, 18}, 1e6);
    const double naiveJump = maxDiff(naive.interpolate(x7, z7), before);
    EXPECT_GT(naiveJump, 0.02 * maxDiff(before, ShRgb{}));  // > 2 % of the value: visible

    // The store's insertion: nothing changes at the instant, at 7 or at 8 or anywhere.
    AnchorStore store = build(2.0);
    ASSERT_EQ(maxDiff(store.interpolate(x7, z7), before), 0.0);
    std::vector<std::pair<double, double>> probes = {
        {x7, z7}, {0.0, 18.0}, {3.0, 4.0}, {20.0, 1.0}};
    std::vector<ShRgb> old;
    for (auto [x, z] : probes) old.push_back(store.interpolate(x, z));
    store.insert(k8, store.interpolate(0.0, 18.0), {0, 2, 18}, 1e6);
    EXPECT_TRUE(maxDiff(store.find(k8)->current, at8) == 0.0);
    for (std::size_t p = 0; p < probes.size(); ++p) {
        EXPECT_EQ(maxDiff(store.interpolate(probes[p].first, probes[p].second), old[p]), 0.0);
    }
    // Then the pattern moves to the new one over the blend time in small steps (60 Hz), and
    // ends where the naive insertion jumped to.
    double largestStep = 0.0;
    ShRgb prev = store.interpolate(x7, z7);
    const double t0 = store.now_s();
    for (int f = 1; f <= 150; ++f) {
        store.advance(t0 + f / 60.0);
        const ShRgb v = store.interpolate(x7, z7);
        largestStep = std::max(largestStep, maxDiff(v, prev));
        prev = v;
    }
    EXPECT_LT(maxDiff(prev, naive.interpolate(x7, z7)), 1e-4);
    EXPECT_LT(largestStep, 0.05 * naiveJump);
}

TEST(AnchorInterpolation, ManyPointsInParallelEqualOneByOne) {
    AnchorStore store = instantStore();
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

TEST(AnchorInterpolation, PartialPresenceSharesTheQuadrant) {
    // A fading-in anchor with presence p nearest in its quadrant takes the share p; the rest goes
    // to the next anchor of that quadrant: weights p / d1 and (1 - p) / d2.
    AnchorStoreSettings s;
    s.blendTime_s = 2.0;
    AnchorStore store(s);
    store.insert({4, 2, 0}, makeSh(1.0f), {6, 2, 0}, 1e6);  // (6, 0)
    store.advance(2.0);
    store.insert({4, 1, 0}, makeSh(3.0f), {3, 2, 0}, 1e6);  // (3, 0), starts from 1.0
    store.advance(2.5);                                     // presence 0.25, value 1.5
    const Anchor* young = store.find({4, 1, 0});
    ASSERT_NEAR(young->presence, 0.25f, 1e-6f);
    const double p = young->presence;
    const double v = young->current.c[0].x;  // makeSh(x).c[0].x == x
    InterpolationDetail d;
    const ShRgb r = store.interpolate(0.5, 0.0, &d);
    const double w1 = p / 2.5, w2 = (1.0 - p) / 5.5;
    EXPECT_NEAR(r.c[0].x, (w1 * v + w2 * 1.0) / (w1 + w2), 1e-5);
    EXPECT_EQ(d.used.size(), 2u);
}

}  // namespace
}  // namespace amb
