// BounceField_test.cpp — the reference's bounce field (lighting/BounceField.h): the iteration
// against the closed form of a closed scene (the geometric series), the lattice's lay-out, the
// interpolation, the surface light's lifetime, and the lazy per-epoch solves.
#include "lighting/BounceField.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "FakeCubeCapture.h"
#include "lighting/Metrics.h"
#include "lighting/SH.h"
#include "world/Conventions.h"
#include "world/Error.h"

namespace amb {
namespace {

using testing_support::FurnaceCapture;

// A capture whose uniform radiance is 1 + x / 100 of its position (ignores the surface light):
// converges on its second pass, and shows where the field reads.
class RampCapture final : public CubeCapture {
  public:
    int faceSize() const override { return 4; }
    CubeCaptureStats capture(const glm::dvec3& p, double, CubeFaceMask,
                             std::vector<float>& cube) override {
        cube.assign(6 * 4 * 4 * 3, float(1.0 + p.x / 100.0));
        return {};
    }
};

glm::dvec3 onGround(double x, double z) {
    return {x, 2.0, z};
}

double upIrradiance(const ShRgb& sh) {
    return double(luminance(shIrradiance(sh, glm::vec3(0, 1, 0))));
}

// The furnace converges to the geometric series rho E_d / (1 - rho): the bounce count and every
// pass's change are the closed form's (change_k = rho^(k-1) (1 - rho) / (1 - rho^k)), and the
// last pass is within rho^k of the limit, below 1 % / (1 - rho) as the stopping rule promises.
TEST(BounceField, AClosedSceneConvergesToTheGeometricSeries) {
    for (const double rho : {0.2, 0.5}) {
        SCOPED_TRACE(rho);
        const double direct = 100.0;
        FurnaceCapture capture(rho, direct);
        BounceSettings s;
        s.canopy_m = 0.0;  // one layer (the two: TwoLayersAreReadByTheSurfacesHeight)
        s.spacing_m = 100.0;
        s.reach_m = 0.0;
        BounceField field(s);
        field.layOut({{0.0, 0.0}}, onGround);
        ASSERT_EQ(field.points(), 1u);
        const BounceSolve& solve = field.solve(capture, 12.0);
        const int expected = rho == 0.2 ? 4 : 7;  // first k with change_k < 0.01
        EXPECT_TRUE(solve.converged);
        EXPECT_EQ(solve.bounces, expected);
        ASSERT_EQ(int(solve.changes.size()), expected);
        for (int k = 1; k <= expected; ++k) {
            const double closed = std::pow(rho, k - 1) * (1.0 - rho) / (1.0 - std::pow(rho, k));
            EXPECT_NEAR(solve.changes[std::size_t(k - 1)], closed, 1e-4 * closed + 1e-6) << k;
        }
        const double limit = rho * direct / (1.0 - rho);
        const double partial = limit * (1.0 - std::pow(rho, expected));
        const double e = upIrradiance(field.pointSh(0));
        EXPECT_NEAR(e, partial, 1e-4 * partial);
        EXPECT_NEAR(e, limit, s.tolerance / (1.0 - rho) * limit);
        EXPECT_EQ(capture.captures, expected);
        EXPECT_EQ(capture.light(), nullptr);  // the capture is left as it was
    }
}

// A field that never settles within maxBounces says so.
TEST(BounceField, StopsAtMaxBouncesAndSaysItDidNotConverge) {
    FurnaceCapture capture(0.9, 1.0);
    BounceSettings s;
    s.canopy_m = 0.0;  // one layer (the two: TwoLayersAreReadByTheSurfacesHeight)
    s.reach_m = 0.0;
    s.maxBounces = 5;
    BounceField field(s);
    field.layOut({{10.0, 10.0}}, onGround);
    const BounceSolve& solve = field.solve(capture, 12.0);
    EXPECT_FALSE(solve.converged);
    EXPECT_EQ(solve.bounces, 5);
    EXPECT_GT(solve.changes.back(), 0.01);
    for (std::size_t k = 1; k < solve.changes.size(); ++k)
        EXPECT_LT(solve.changes[k], solve.changes[k - 1]);
}

// The lattice: the nodes within reach of the path, on the global lattice, placed by the caller.
TEST(BounceField, LaysTheNodesWithinReachOfThePath) {
    BounceSettings s;
    s.canopy_m = 0.0;  // one layer (the two: TwoLayersAreReadByTheSurfacesHeight)
    s.spacing_m = 100.0;
    s.reach_m = 150.0;  // (0,0), 4 edge neighbours at 100 m and 4 diagonal ones at 141 m
    BounceField a(s);
    a.layOut({{0.0, 0.0}}, onGround);
    EXPECT_EQ(a.points(), 9u);
    s.reach_m = 120.0;
    BounceField b(s);
    b.layOut({{0.0, 0.0}}, onGround);
    EXPECT_EQ(b.points(), 5u);
    // A path along x: the union of the discs, each node once.
    s.reach_m = 100.0;
    BounceField c(s);
    c.layOut({{0.0, 0.0}, {50.0, 0.0}, {100.0, 0.0}}, onGround);
    EXPECT_EQ(c.points(), 8u);  // (-1..2, 0), (0..1, +-1)
    for (std::size_t i = 0; i < c.points(); ++i)
        EXPECT_DOUBLE_EQ(c.pointPosition(i).y, 2.0);
}

// Reading the field: exact at a node, bilinear between nodes, the nearest node's value where no
// node was captured, the box's edge beyond it, zero before any solve.
TEST(BounceField, InterpolatesBilinearlyAndHoldsTheNearestValueOutside) {
    BounceSettings s;
    s.canopy_m = 0.0;  // one layer (the two: TwoLayersAreReadByTheSurfacesHeight)
    s.spacing_m = 100.0;
    s.reach_m = 100.0;
    BounceField field(s);
    field.layOut({{0.0, 0.0}, {100.0, 0.0}}, onGround);
    EXPECT_EQ(upIrradiance(field.shAt({0.0, 0.0, 0.0})), 0.0);
    RampCapture ramp;
    const BounceSolve& solve = field.solve(ramp, 12.0);
    EXPECT_TRUE(solve.converged);
    EXPECT_EQ(solve.bounces, 2);
    const auto e = [&](double x, double z) { return upIrradiance(field.shAt({x, 50.0, z})); };
    const double at0 = kPi * 1.0, at100 = kPi * 2.0;  // E = pi L of the uniform radiance
    EXPECT_NEAR(e(0.0, 0.0), at0, 1e-4 * at0);
    EXPECT_NEAR(e(100.0, 0.0), at100, 1e-4 * at100);
    EXPECT_NEAR(e(50.0, 0.0), 0.5 * (at0 + at100), 1e-4 * at100);
    EXPECT_NEAR(e(25.0, 100.0), 0.75 * at0 + 0.25 * at100, 1e-4 * at100);  // row k = 1
    // Node (2, 1) was not captured: it takes its nearest captured node's value, (1, 0) or (1, 1).
    EXPECT_NEAR(e(200.0, 100.0), at100, 1e-4 * at100);
    // Beyond the box: its edge, node (-1, 0), whose radiance is 1 - 100 / 100 = 0.
    EXPECT_NEAR(e(-5000.0, 0.0), 0.0, 1e-6);
    EXPECT_TRUE(std::isfinite(e(1e9, -1e9)));
    EXPECT_TRUE(std::isfinite(upIrradiance(field.shAt({std::nan(""), 0.0, 0.0}))));
}

// A capture whose uniform radiance is its position's height in metres / 10 (a field that grows
// with height, as the sky a point sees past a canopy does).
class HeightCapture final : public CubeCapture {
  public:
    int faceSize() const override { return 4; }
    CubeCaptureStats capture(const glm::dvec3& p, double, CubeFaceMask,
                             std::vector<float>& cube) override {
        cube.assign(6 * 4 * 4 * 3, float(p.y / 10.0));
        return {};
    }
};

// Two layers: every node gets a second point canopy_m above its first, both solved; a surface
// reads the lower layer at or below it, the upper at or above it, and in between the linear
// blend by its height (closed form: the capture's radiance is linear in height, so the blend
// is exact there). One layer ignores height, and keeps its cache key.
TEST(BounceField, TwoLayersAreReadByTheSurfacesHeight) {
    BounceSettings s;
    s.spacing_m = 100.0;
    s.reach_m = 100.0;
    s.canopy_m = 10.0;
    BounceField field(s);
    const auto sloped = [](double x, double z) { return glm::dvec3(x, 2.0 + x / 100.0, z); };
    field.layOut({{0.0, 0.0}}, sloped);
    ASSERT_EQ(field.points(), 10u);  // 5 nodes, two layers
    for (std::size_t i = 0; i < 5; ++i) {
        EXPECT_DOUBLE_EQ(field.pointPosition(i + 5).y, field.pointPosition(i).y + 10.0);
        EXPECT_DOUBLE_EQ(field.pointPosition(i + 5).x, field.pointPosition(i).x);
    }
    HeightCapture capture;
    const BounceSolve& solve = field.solve(capture, 12.0);
    EXPECT_EQ(solve.points, 10u);
    EXPECT_EQ(solve.captures, 20);  // both layers in each of the two passes
    const auto e = [&](double x, double y) { return upIrradiance(field.shAt({x, y, 0.0})); };
    // At x = 50 the lower layer stands at 2.5 m (radiance 0.25), the upper at 12.5 m (1.25).
    const double low = kPi * 0.25, high = kPi * 1.25;
    EXPECT_NEAR(e(50.0, 0.0), low, 1e-4 * high);    // the ground, below the lower layer
    EXPECT_NEAR(e(50.0, 2.5), low, 1e-4 * high);
    EXPECT_NEAR(e(50.0, 6.0), kPi * 0.6, 1e-4 * high);  // 3.5 m of 10 up: 0.25 + 0.35
    EXPECT_NEAR(e(50.0, 12.5), high, 1e-4 * high);
    EXPECT_NEAR(e(50.0, 400.0), high, 1e-4 * high);  // above the canopy: the upper layer
    EXPECT_TRUE(std::isfinite(e(50.0, std::nan(""))));
    // One layer: height is not a coordinate.
    BounceSettings one = s;
    one.canopy_m = 0.0;
    BounceField flat(one);
    flat.layOut({{0.0, 0.0}}, sloped);
    ASSERT_EQ(flat.points(), 5u);
    flat.solve(capture, 12.0);
    EXPECT_NEAR(upIrradiance(flat.shAt({50.0, 400.0, 0.0})), low, 1e-4 * high);
    // The cache key names the second layer only when there is one.
    EXPECT_EQ(describeBounceSettings(one).find("canopy"), std::string::npos);
    EXPECT_NE(describeBounceSettings(s).find("canopy=10"), std::string::npos);
    for (const double bad : {0.5, -1.0, 200.0, std::nan("")}) {
        BounceSettings b = s;
        b.canopy_m = bad;
        EXPECT_THROW(checkBounceSettings(b), InputError) << bad;
    }
}

// The reference capture is lit by the field of its epoch: solved on the first capture that needs
// it (none before), once per epoch, and the reference is left without a surface light after.
TEST(BounceField, LitCaptureSolvesLazilyOncePerEpoch) {
    FurnaceCapture lattice(0.5, 10.0), reference(0.5, 10.0);
    BounceSettings s;
    s.canopy_m = 0.0;  // one layer (the two: TwoLayersAreReadByTheSurfacesHeight)
    s.spacing_m = 100.0;
    s.reach_m = 0.0;
    s.epoch_h = 0.25;
    BounceLitCapture lit(reference, lattice, s, {{0.0, 0.0}}, onGround, 12.0);
    EXPECT_EQ(lattice.captures, 0);
    std::vector<float> cube;
    lit.capture({0.0, 2.0, 0.0}, 12.01, kAllCubeFaces, cube);
    EXPECT_EQ(lattice.captures, 7);
    ASSERT_EQ(lit.solves().size(), 1u);
    EXPECT_DOUBLE_EQ(lit.solves()[0].timeOfDay_h, 12.0);
    // The reference saw the converged field: rho / pi (E_d + E_7).
    const double e7 = 0.5 * 10.0 * (1.0 - std::pow(0.5, 7)) / 0.5;
    EXPECT_NEAR(cube[0], 0.5 / kPi * (10.0 + e7), 1e-4);
    EXPECT_EQ(reference.light(), nullptr);
    lit.capture({0.0, 2.0, 0.0}, 12.2, kAllCubeFaces, cube);
    EXPECT_EQ(lattice.captures, 7);  // same epoch
    lit.capture({0.0, 2.0, 0.0}, 12.3, kAllCubeFaces, cube);
    EXPECT_EQ(lattice.captures, 14);  // the next one, solved at 12.25 h
    ASSERT_EQ(lit.solves().size(), 2u);
    EXPECT_DOUBLE_EQ(lit.solves()[1].timeOfDay_h, 12.25);
}

TEST(BounceField, RefusesSettingsOutOfRange) {
    BounceSettings s;
    s.spacing_m = 0.0;
    EXPECT_THROW(BounceField{s}, InputError);
    s = {};
    s.faceSize = 1;
    EXPECT_THROW(checkBounceSettings(s), InputError);
    s = {};
    s.reach_m = -1.0;
    EXPECT_THROW(checkBounceSettings(s), InputError);
    s = {};
    s.reach_m = std::nan("");
    EXPECT_THROW(checkBounceSettings(s), InputError);
    EXPECT_THROW(parseReferenceLight("sky", "--reference-light"), InputError);
    EXPECT_EQ(parseReferenceLight("bounce", "x"), ReferenceLight::Bounce);
    EXPECT_EQ(parseReferenceLight("hemisphere", "x"), ReferenceLight::Hemisphere);
    EXPECT_NE(describeBounceSettings(BounceSettings{}).find("spacing=256"), std::string::npos);
}

}  // namespace
}  // namespace amb
