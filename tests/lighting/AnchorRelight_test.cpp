// AnchorRelight_test.cpp — the relight factor of anchors (AnchorStore::relight): interpolation
// reads current x relight, both on an anchor and between anchors; bad factors count as 1; and a
// refresh of a relit anchor starts its blend from what was shown, so refreshing is no pop.
#include <cmath>

#include <gtest/gtest.h>

#include "lighting/AnchorStore.h"

namespace amb {
namespace {

ShRgb constantSh(float v) {
    ShRgb sh;
    for (int k = 0; k < kShCoefficients; ++k) sh.c[k] = glm::vec3(v, 0.5f * v, 2.0f * v);
    return sh;
}

void expectNear(const ShRgb& a, const ShRgb& b, double tol) {
    for (int k = 0; k < kShCoefficients; ++k)
        for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(a.c[k][ch], b.c[k][ch], tol) << k << "," << ch;
}

TEST(AnchorRelight, ScalesWhatInterpolationReads) {
    AnchorStoreSettings s;
    s.blendTime_s = 0.0;             // at full weight at once
    s.smoothInterpolation = false;  // bilinear: half-way between two anchors is their mean
    AnchorStore store(s);
    const LatticeKey a{4, 0, 0}, b{4, 1, 0};
    const auto at = [&](const LatticeKey& k) {
        return glm::dvec3(store.keyX_m(k), 2.0, store.keyZ_m(k));
    };
    ASSERT_NE(store.insert(a, constantSh(1.0f), at(a), 100.0), AnchorStore::InsertResult::Rejected);
    ASSERT_NE(store.insert(b, constantSh(3.0f), at(b), 100.0), AnchorStore::InsertResult::Rejected);
    const double midX = 0.5 * (store.keyX_m(a) + store.keyX_m(b));
    expectNear(store.interpolate(midX, 0.0), constantSh(2.0f), 1e-5);  // equal distances

    // Anchor a read at 0.5, b at 2: on a -> 0.5; half-way -> (0.5 + 6) / 2 = 3.25.
    store.relight([&](const Anchor& x) { return x.key == store.find(a)->key ? 0.5f : 2.0f; });
    expectNear(store.interpolate(store.keyX_m(a), store.keyZ_m(a)), constantSh(0.5f), 1e-6);
    expectNear(store.interpolate(midX, 0.0), constantSh(3.25f), 1e-5);

    // NaN, infinite or non-positive factors are ignored (read as 1): never NaN in the output.
    store.relight([](const Anchor&) { return std::nanf(""); });
    expectNear(store.interpolate(midX, 0.0), constantSh(2.0f), 1e-5);
    store.relight([](const Anchor&) { return -1.0f; });
    expectNear(store.interpolate(midX, 0.0), constantSh(2.0f), 1e-5);
}

TEST(AnchorRelight, RefreshOfARelitAnchorIsNoPop) {
    AnchorStoreSettings s;
    s.blendTime_s = 2.0;
    AnchorStore store(s);
    const LatticeKey a{4, 0, 0};
    const glm::dvec3 p(store.keyX_m(a), 2.0, store.keyZ_m(a));
    store.insert(a, constantSh(4.0f), p, 100.0);
    store.advance(10.0);  // fully faded in and blended
    store.relight([](const Anchor&) { return 0.25f; });
    const ShRgb shown = store.interpolate(p.x, p.z);
    expectNear(shown, constantSh(1.0f), 1e-6);
    // A new capture of 3: at the refresh instant the anchor still shows 1, then blends to 3.
    store.insert(a, constantSh(3.0f), p, 100.0);
    expectNear(store.interpolate(p.x, p.z), shown, 1e-6);
    store.advance(11.0);  // half-way
    expectNear(store.interpolate(p.x, p.z), constantSh(2.0f), 1e-5);
    store.advance(12.0);
    expectNear(store.interpolate(p.x, p.z), constantSh(3.0f), 1e-5);
}

}  // namespace
}  // namespace amb
