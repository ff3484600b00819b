// The reference oracle and the error budget (lighting/ReferenceOracle.h): exact on a constant
// environment, the sun left out as the methods leave it out, the quadrature equal to the closed
// form on SH inputs, budget terms that add up as squares on a synthetic case, and a cache that
// round-trips and refuses bad files.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "FakeCubeCapture.h"
#include "lighting/AmbienceMethod.h"
#include "lighting/Metrics.h"
#include "lighting/ReferenceOracle.h"
#include "lighting/SH.h"
#include "world/Conventions.h"
#include "world/Error.h"
#include "world/TerrainPatch.h"

using namespace amb;

namespace {

std::vector<float> constantCube(int n, glm::vec3 L) {
    std::vector<float> rgb(std::size_t(kCubeFaces) * n * n * 3);
    for (std::size_t t = 0; t < rgb.size(); t += 3) rgb[t] = L.x, rgb[t + 1] = L.y, rgb[t + 2] = L.z;
    return rgb;
}

ShRgb randomSh(std::mt19937& rng, float scale = 1.0f) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    ShRgb sh;
    for (int k = 0; k < kShCoefficients; ++k)
        for (int c = 0; c < 3; ++c) sh.c[k][c] = scale * u(rng);
    sh.c[0][0] += 3.0f, sh.c[0][1] += 3.0f, sh.c[0][2] += 3.0f;  // a positive mean
    return sh;
}

// A reference sample whose irradiance is E_sh(n) + extra(n) at the rule's directions.
ReferenceSample sampleOf(const ShRgb& sh, const SphereRule& rule,
                         double (*extra)(const glm::dvec3&) = nullptr) {
    ReferenceSample s;
    s.sh = sh;
    const ShRgbD d = toDouble(sh);
    for (const glm::dvec3& n : rule.directions) {
        glm::dvec3 e = shIrradiance(d, n);
        if (extra) e += glm::dvec3(extra(n));
        s.irradiance.emplace_back(e);
    }
    return s;
}

// A band-4 zonal harmonic (unnormalised P4(y)): orthogonal to every order-2 field.
double band4(const glm::dvec3& n) {
    const double y = n.y;
    return 0.5 * (35.0 * y * y * y * y - 30.0 * y * y + 3.0) / 8.0;
}

}  // namespace

// A constant environment L gives E = pi L at every direction of the rule, whatever the face
// size, and its P2 is the exact constant (truncation 0); the sun's texel, filled from its
// neighbours, stays L.
TEST(ReferenceOracle, ConstantEnvironmentIsExact) {
    const SphereRule rule = sphereProductRule(5);
    for (int n : {4, 16, 64}) {
        const ReferenceSample s = referenceSample(n, constantCube(n, {1.0f, 0.5f, 2.0f}),
                                                  glm::dvec3(0.3, 0.2, -1.0), rule);
        ASSERT_EQ(s.irradiance.size(), rule.directions.size());
        for (const glm::vec3& e : s.irradiance) {
            EXPECT_NEAR(e.x, kPi * 1.0, 1e-5);
            EXPECT_NEAR(e.y, kPi * 0.5, 1e-5);
            EXPECT_NEAR(e.z, kPi * 2.0, 1e-5);
        }
        EXPECT_LT(referenceDistance(s, s.sh, rule), 1e-5 * referenceNorm(s, rule)) << n;
    }
}

// The texel holding the sun direction is left out of both the irradiance and the SH, exactly as
// the methods' projection leaves it out: filled from its neighbours, the sample equals that of
// the cube without the sun. Without the direction the sun is kept: far brighter.
TEST(ReferenceOracle, SunTexelsAreLeftOutAsTheMethodsLeaveThemOut) {
    const SphereRule rule = sphereProductRule(5);
    const int n = 16;
    std::vector<float> cube = constantCube(n, {1.0f, 1.0f, 1.0f}), withoutSun = cube;
    const std::size_t sunTexel = (std::size_t(2) * n + 5) * n + 7;  // on +Y
    for (int c = 0; c < 3; ++c) cube[3 * sunTexel + c] = 1.0e6f;
    const glm::dvec3 sun = cubeTexelDirection(2, 7, 5, n);
    const ReferenceSample a = referenceSample(n, cube, sun, rule);
    const ReferenceSample b = referenceSample(n, withoutSun, std::nullopt, rule);
    for (std::size_t k = 0; k < a.irradiance.size(); ++k)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(a.irradiance[k][c], b.irradiance[k][c], 1e-5);
    EXPECT_LT(irradianceDistance(a.sh, b.sh), 1e-5 * irradianceNorm(b.sh));
    for (const glm::dvec3& d : {glm::dvec3(0, 1, 0), sun, glm::dvec3(1, 0, 0)})
        EXPECT_NEAR(referenceIrradianceAt(n, cube, sun, d).x, kPi, 1e-5);
    const ReferenceSample kept = referenceSample(n, cube, std::nullopt, rule);
    EXPECT_GT(referenceNorm(kept, rule), 10.0 * referenceNorm(b, rule));
}

// On SH inputs the quadrature distance equals irradianceDistance (Metrics.h) to 1e-6.
TEST(ReferenceOracle, QuadratureEqualsTheClosedFormOnSh) {
    std::mt19937 rng(5);
    const SphereRule rule = sphereProductRule(5);
    for (int trial = 0; trial < 100; ++trial) {
        const ShRgb a = randomSh(rng), b = randomSh(rng);
        const ReferenceSample ref = sampleOf(a, rule);
        const double closed = irradianceDistance(a, b);
        EXPECT_NEAR(referenceDistance(ref, b, rule), closed, 1e-6 * closed);
        EXPECT_NEAR(referenceNorm(ref, rule), irradianceNorm(a), 1e-6 * irradianceNorm(a));
    }
}

// Synthetic budget: the reference is P2 plus a band-4 part (truncation), and the coarse
// capture, the ideal volume and the applied value each move one different coefficient, so the
// four differences are orthogonal: a^2 + b^2 + c^2 + d^2 = total^2 (the rule of degree 9
// integrates the band-4 part's square, degree 8, exactly), and each term is what was put in.
TEST(ReferenceOracle, BudgetTermsOfASyntheticCaseAddUp) {
    std::mt19937 rng(9);
    const SphereRule rule = sphereProductRule(5);
    for (int trial = 0; trial < 20; ++trial) {
        const ShRgb p2 = randomSh(rng);
        const ReferenceSample ref = sampleOf(p2, rule, band4);
        ShRgb coarse = p2, ideal, applied;
        coarse.c[1][0] += 0.3f;   // b: band 1
        ideal = coarse;
        ideal.c[4][1] += 0.5f;    // c: band 2
        applied = ideal;
        applied.c[2][2] -= 0.4f;  // d: band 1, another coefficient
        const BudgetTerms t = budgetTerms(ref, coarse, ideal, applied, rule);
        const double norm = referenceNorm(ref, rule);
        EXPECT_NEAR(t.capture, irradianceDistance(p2, coarse) / norm, 1e-6);
        EXPECT_NEAR(t.spacing, irradianceDistance(coarse, ideal) / norm, 1e-6);
        EXPECT_NEAR(t.schedule, irradianceDistance(ideal, applied) / norm, 1e-6);
        EXPECT_GT(t.truncation, 0.0);
        const double squares = t.truncation * t.truncation + t.capture * t.capture +
                               t.spacing * t.spacing + t.schedule * t.schedule;
        EXPECT_NEAR(squares, t.total * t.total, 1e-6 * t.total * t.total);

        // Without an ideal volume, d holds c and d together and the squares still add up.
        const BudgetTerms merged = budgetTerms(ref, coarse, std::nullopt, applied, rule);
        EXPECT_TRUE(std::isnan(merged.spacing));
        EXPECT_NEAR(merged.schedule * merged.schedule, t.spacing * t.spacing + t.schedule * t.schedule,
                    1e-6);
    }
    // The summary: RMS per term; closure 1 for orthogonal terms.
    std::vector<BudgetTerms> terms;
    for (int trial = 0; trial < 10; ++trial) {
        const ShRgb p2 = randomSh(rng);
        const ReferenceSample ref = sampleOf(p2, rule, band4);
        ShRgb coarse = p2;
        coarse.c[3][0] += 0.2f * float(trial);
        terms.push_back(budgetTerms(ref, coarse, coarse, coarse, rule));
    }
    const BudgetSummary s = summarizeBudget(terms);
    EXPECT_EQ(s.count, terms.size());
    EXPECT_TRUE(s.hasSpacing);
    EXPECT_NEAR(s.spacing, 0.0, 1e-12);
    EXPECT_NEAR(s.closure(), 1.0, 1e-6);
}

// The meter with a reference: every reference frame adds its terrain witnesses with terms that
// are finite and below the constant method's; the cache round-trips, and a damaged cache is one
// InputError that leaves the loaded values alone.
TEST(ReferenceOracle, MeterCacheRoundTripsAndRefusesBadFiles) {
    using testing_support::FakeCubeCapture;
    using testing_support::FlatProbeEnvironment;
    FakeCubeCapture coarse(8), full(16);
    FlatProbeEnvironment environment;
    MeasureSettings ms;
    ms.every = 2;
    ErrorMeter meter(coarse, environment, ms);
    ReferenceSettings rs;
    rs.every = 2;
    meter.attachReference(full, rs, true);
    EXPECT_EQ(meter.oracleKind(), OracleKind::Reference);
    // A method that applies a constant: the budget still adds its terms.
    struct Constant final : AmbienceMethod {
        ShRgb value;
        std::string methodName() const override { return "c"; }
        void predictStage(const glm::dvec3&, const glm::dvec3&, double, double) override {}
        void captureStage() override {}
        void storeStage() override {}
        ShRgb shAt(double, double) const override { return value; }
        MethodStatistics methodStatistics() const override { return {}; }
    } method;
    method.value.c[0][0] = method.value.c[0][1] = method.value.c[0][2] = 1.0f;
    for (int f = 0; f < 9; ++f)
        meter.frame(f, f / 30.0, 12.0, {100.0 * f, 0.0, 50.0}, 10.0, method);
    ASSERT_FALSE(meter.referenceWitnesses().empty());
    const std::size_t captured = std::size_t(meter.referenceCaptures());
    EXPECT_GT(captured, 0u);
    for (const ReferenceWitness& r : meter.referenceWitnesses()) {
        EXPECT_TRUE(std::isfinite(r.terms.total));
        EXPECT_TRUE(std::isnan(r.terms.spacing));  // no lattice
    }
    EXPECT_EQ(meter.errors().size(), meter.terrainBudget().size());

    const std::string path = ::testing::TempDir() + "reference-cache.json";
    meter.saveReference(path, "sig");
    ErrorMeter again(coarse, environment, ms);
    again.attachReference(full, rs, true);
    again.loadReference(path, "sig");
    for (int f = 0; f < 9; ++f)
        again.frame(f, f / 30.0, 12.0, {100.0 * f, 0.0, 50.0}, 10.0, method);
    EXPECT_EQ(again.referenceCaptures(), 0);
    ASSERT_EQ(again.referenceWitnesses().size(), meter.referenceWitnesses().size());
    for (std::size_t i = 0; i < again.referenceWitnesses().size(); ++i)
        EXPECT_NEAR(again.referenceWitnesses()[i].terms.total,
                    meter.referenceWitnesses()[i].terms.total, 1e-5);

    EXPECT_THROW(again.loadReference(path, "other"), InputError);
    EXPECT_THROW(again.loadReferenceText("{", "bad", "sig"), InputError);
    EXPECT_THROW(again.loadReferenceText(
                     R"({"format":"ambience-reference","version":1,"signature":"sig",)"
                     R"("entries":[{"frame":0,"x":0,"y":1,"z":0,"sh":[1],"e":[]}]})",
                     "short", "sig"),
                 InputError);
    EXPECT_THROW(again.loadReferenceText(
                     R"({"format":"ambience-oracle","version":1,"signature":"sig","entries":[]})",
                     "kind", "sig"),
                 InputError);
    std::remove(path.c_str());
}

// The signed error: luminance ratio less one, so twice as bright is +1, half as bright -0.5, and
// a change of colour at the same luminance is no bias though it is an error.
TEST(DrawnBudget, BiasIsTheSignedLuminanceRatio) {
    const glm::dvec3 ref(2.0, 3.0, 1.0);
    EXPECT_NEAR(irradianceBias(2.0 * ref, ref), 1.0, 1e-12);
    EXPECT_NEAR(irradianceBias(0.5 * ref, ref), -0.5, 1e-12);
    EXPECT_NEAR(irradianceRelativeError(0.5 * ref, ref), 0.5, 1e-12);
    // Red up, blue down by the ratio of their weights: the same luminance.
    const glm::dvec3 shifted = ref + glm::dvec3(kLuminanceWeights[2], 0.0, -kLuminanceWeights[0]);
    EXPECT_NEAR(irradianceBias(shifted, ref), 0.0, 1e-12);
    EXPECT_GT(irradianceRelativeError(shifted, ref), 0.01);
}

// The drawn-normal budget's summary: each term is a step between two successive errors, so the
// means add up to the drawn mean exactly; witnesses without every step are left out.
TEST(DrawnBudget, TermsAreTheStepsAndAddUpToTheDrawnMean) {
    DrawnBudget a{0.5, 0.3, 0.2, 0.05, 0.25}, b{0.3, 0.3, 0.1, 0.05, 0.15}, partial;
    partial.drawn = 9.0;  // no fresh captures: left out
    const DrawnBudgetSummary s = summarizeDrawnBudget({a, b, partial});
    EXPECT_EQ(s.count, 2u);
    EXPECT_NEAR(s.drawn, 0.4, 1e-12);
    EXPECT_NEAR(s.farField, 0.1, 1e-12);    // (0.2 + 0.0) / 2
    EXPECT_NEAR(s.patch, 0.15, 1e-12);      // (0.1 + 0.2) / 2
    EXPECT_NEAR(s.model, 0.1, 1e-12);       // (0.15 + 0.05) / 2
    EXPECT_NEAR(s.truncation, 0.05, 1e-12);
    EXPECT_NEAR(s.perPoint, 0.2, 1e-12);  // beside the chain: its own mean
    EXPECT_TRUE(std::isnan(s.drawnBias));  // a and b lack it: said, not taken as 0
    EXPECT_NEAR(s.closure(), 1.0, 1e-12);
    EXPECT_FALSE(partial.complete());
    EXPECT_EQ(summarizeDrawnBudget({partial}).count, 0u);
}

namespace {

// A flat world whose drawn patches are `size` across with the witness at (u, v) inside.
class PatchedEnvironment final : public testing_support::FlatProbeEnvironment {
  public:
    PatchedEnvironment(double size_m, double u, double v) : size_m_(size_m), u_(u), v_(v) {}
    DrawnPatch drawnPatch(double x_m, double z_m, const glm::dvec3&) const override {
        DrawnPatch p;
        p.size_m = size_m_;
        p.x0_m = x_m - u_ * size_m_, p.z0_m = z_m - v_ * size_m_;
        for (int c = 0; c < 4; ++c) {
            p.corner_m[c] = {p.x0_m + (c & 1 ? size_m_ : 0.0), 0.0,
                             p.z0_m + (c & 2 ? size_m_ : 0.0)};
            p.cornerNormal[c] = {0.0, 1.0, 0.0};
        }
        p.surface_m = {x_m, 0.0, z_m};
        return p;
    }

  private:
    double size_m_, u_, v_;
};

// A method whose far field is a fresh coarse capture wherever it is asked (the ideal volume
// itself), or that scaled by 1 + `gain`.
struct FreshCaptureMethod final : AmbienceMethod {
    CubeCapture* capture = nullptr;
    const ProbeEnvironment* environment = nullptr;
    MeasureSettings settings;
    float gain = 0.0f;
    bool mirrorY = false;  // its SH mirrored top to bottom (the terms odd in y negated)
    const SurfaceLight* light = nullptr;  // what its captures light their surfaces with
    std::string methodName() const override { return "fresh"; }
    const SurfaceLight* captureSurfaceLight() const override { return light; }
    void predictStage(const glm::dvec3&, const glm::dvec3&, double, double) override {}
    void captureStage() override {}
    void storeStage() override {}
    ShRgb shAt(double x_m, double z_m) const override {
        ShRgb sh = oracleSh(*capture, *environment, settings, x_m, z_m, 12.0) * (1.0f + gain);
        if (mirrorY) {
            // Y_k(x, -y, z) = +-Y_k(x, y, z): the sign of each term, read off a generic direction.
            const glm::dvec3 d = glm::normalize(glm::dvec3(0.3, 0.5, 0.8));
            const auto up = shBasis(d), down = shBasis(glm::dvec3(d.x, -d.y, d.z));
            for (int k = 0; k < kShCoefficients; ++k)
                if (up[std::size_t(k)] * down[std::size_t(k)] < 0.0) sh.c[std::size_t(k)] *= -1.0f;
        }
        return sh;
    }
    MethodStatistics methodStatistics() const override { return {}; }
};

// Measuring every frame, for the meters below.
MeasureSettings everyFrame() {
    MeasureSettings ms;
    ms.every = 1;
    return ms;
}

// A meter over `coarse` measuring every frame, with `full` as the reference on every frame and
// `objectTrees` trees a frame among its object witnesses.
std::unique_ptr<ErrorMeter> referenceMeter(CubeCapture& coarse, CubeCapture& full,
                                           const ProbeEnvironment& environment,
                                           int objectTrees = ReferenceSettings{}.objectTrees) {
    auto meter = std::make_unique<ErrorMeter>(coarse, environment, everyFrame());
    ReferenceSettings rs;
    rs.every = 1;
    rs.objectTrees = objectTrees;
    meter->attachReference(full, rs, true);
    return meter;
}

// Three frames of a FreshCaptureMethod over `coarse` (its gain and surface light as given) on a
// meter with `full` as the reference and the witnesses on PatchedEnvironment(32, u, v): the
// drawn budget's summary.
DrawnBudgetSummary freshBudget(CubeCapture& coarse, CubeCapture& full, double u, double v,
                               float gain, const SurfaceLight* light = nullptr) {
    PatchedEnvironment environment(32.0, u, v);
    const MeasureSettings ms = everyFrame();
    const auto meterOwned = referenceMeter(coarse, full, environment, 0);
    ErrorMeter& meter = *meterOwned;
    FreshCaptureMethod method;
    method.capture = &coarse, method.environment = &environment, method.settings = ms;
    method.gain = gain;
    method.light = light;
    for (int f = 0; f < 3; ++f)
        meter.frame(f, f / 30.0, 12.0, {40.0 * f, 0.0, 25.0}, 10.0, method);
    return summarizeDrawnBudget(meter.drawnBudgets());
}

}  // namespace

// The budget on a meter: a method whose far field is the fresh capture has no far-field term;
// one that scales it by 1.5 has a far-field term of about 0.5 and the same later steps; with the
// witness on a patch corner the patch's blend costs nothing, inside a patch it costs something;
// the terms add up to the drawn mean.
TEST(DrawnBudget, FreshCapturesMakeTheFarFieldTermVanish) {
    using testing_support::FakeCubeCapture;
    const auto run = [](double u, double v, float gain) {
        FakeCubeCapture coarse(8), full(16);
        return freshBudget(coarse, full, u, v, gain);
    };
    const DrawnBudgetSummary exact = run(0.0, 0.0, 0.0f);
    ASSERT_GT(exact.count, 3u);
    EXPECT_NEAR(exact.farField, 0.0, 1e-6);
    EXPECT_NEAR(exact.patch, 0.0, 1e-6);  // the witness is corner 0: the blend is that corner
    EXPECT_NEAR(exact.closure(), 1.0, 1e-9);
    // The method at the point is the fresh capture at the point: the atPoint step itself.
    EXPECT_NEAR(exact.perPoint, exact.model + exact.truncation, 1e-6);
    EXPECT_GT(exact.truncation, 0.0);
    EXPECT_LT(exact.truncation, 0.05);  // a smooth fake sky: order 2 holds most of it

    const DrawnBudgetSummary inside = run(0.4, 0.7, 0.0f);
    EXPECT_NEAR(inside.farField, 0.0, 1e-6);
    EXPECT_GT(std::fabs(inside.patch), 1e-4);  // the fake's ground colour varies across 32 m
    EXPECT_NEAR(inside.closure(), 1.0, 1e-9);

    // The signed figures: with the witness on corner 0 the drawn answer is the one at the point
    // (the same bias); scaled by 1.5 it is 1.5 times as bright: 1 + bias scales by 1.5.
    EXPECT_NEAR(exact.drawnBias, exact.atPointBias, 1e-6);
    const DrawnBudgetSummary off = run(0.0, 0.0, 0.5f);
    EXPECT_NEAR(off.atPointBias, exact.atPointBias, 1e-6);
    EXPECT_NEAR(off.drawnBias + 1.0, 1.5 * (exact.atPointBias + 1.0), 1e-5);
    EXPECT_NEAR(off.farField, 0.5, 0.05);
    EXPECT_NEAR(off.model, exact.model, 1e-6);  // the steps after the far field do not see it
    EXPECT_NEAR(off.truncation, exact.truncation, 1e-9);
    EXPECT_NEAR(off.closure(), 1.0, 1e-9);

    // The model step's split: with no near field the answer at the point is the plain capture
    // where the probe stands; neither plain capture sees the method (its gain).
    EXPECT_NEAR(exact.placedBias, exact.atPointBias, 1e-6);
    EXPECT_TRUE(std::isfinite(exact.sceneBias));
    EXPECT_LT(std::fabs(exact.sceneBias), 0.05);  // the fakes differ only in face size
    EXPECT_NEAR(off.sceneBias, exact.sceneBias, 1e-9);
    EXPECT_NEAR(off.placedBias, exact.placedBias, 1e-9);
}

namespace {

// A flat world with two object witnesses 10 m from the camera's ground point: the car (its roof,
// facing up) and a tree's trunk facing the camera (horizontally).
class ObjectEnvironment final : public testing_support::FlatProbeEnvironment {
  public:
    double trunkShare = 1.0;  // what the trunk's crown leaves of its ambient
    std::vector<ObjectWitness> objectWitnesses(double cx, double cz, int, double, double, double,
                                               int) const override {
        ObjectWitness car;
        car.groundX_m = cx, car.groundZ_m = cz;
        car.position_m = {cx, 1.0, cz};
        ObjectWitness trunk;
        trunk.kind = ObjectKind::TreeBase;
        trunk.groundX_m = cx + 10.0, trunk.groundZ_m = cz;
        trunk.normal = {-1.0, 0.0, 0.0};  // towards the camera
        trunk.position_m = {cx + 9.0, 1.0, cz};
        trunk.ambientShare = trunkShare;
        return {car, trunk};
    }
};

struct ObjectFigures {
    double carDrawn, carBias, trunkDrawn, trunkBias, trunkSphere;
    std::size_t count;
};

ObjectFigures objectFigures(float gain, bool mirrorY, double trunkShare = 1.0) {
    testing_support::FakeCubeCapture coarse(8), full(16);
    ObjectEnvironment environment;
    environment.trunkShare = trunkShare;
    const MeasureSettings ms = everyFrame();
    const auto meterOwned = referenceMeter(coarse, full, environment);
    ErrorMeter& meter = *meterOwned;
    FreshCaptureMethod method;
    method.capture = &coarse, method.environment = &environment, method.settings = ms;
    method.gain = gain, method.mirrorY = mirrorY;
    for (int f = 0; f < 3; ++f) meter.frame(f, f / 30.0, 12.0, {40.0 * f, 0.0, 25.0}, 10.0, method);
    const auto mean = [](const std::vector<double>& v) {
        double s = 0.0;
        for (double x : v) s += x;
        return v.empty() ? std::nan("") : s / double(v.size());
    };
    double sphere = 0.0;
    const auto trunk = meter.objectBudget(ObjectKind::TreeBase);
    for (const BudgetTerms& t : trunk) sphere += t.total / double(trunk.size());
    return {mean(meter.objectDrawnErrors(ObjectKind::Car)),
            mean(meter.objectDrawnErrors(ObjectKind::Car, true)),
            mean(meter.objectDrawnErrors(ObjectKind::TreeBase)),
            mean(meter.objectDrawnErrors(ObjectKind::TreeBase, true)),
            sphere,
            meter.objectDrawnErrors(ObjectKind::TreeBase).size()};
}

}  // namespace

namespace {
// Flat ground with a wall of plants over x > 100 m: no reference may stand there.
class WalledEnvironment final : public testing_support::FlatProbeEnvironment {
  public:
    bool inTheOpen(const glm::dvec3& point_m, double, const glm::dvec3*) const override {
        return point_m.x <= 100.0;
    }
};
}  // namespace

// Screen witnesses whose reference would stand inside something (a plant the view left out) are
// left out of the screen error and counted; the others are graded.
TEST(ReferenceOracle, ScreenWitnessesInsideThingsAreLeftOut) {
    testing_support::FakeCubeCapture coarse(8), full(16);
    WalledEnvironment environment;
    const auto meterOwned = referenceMeter(coarse, full, environment);
    ErrorMeter& meter = *meterOwned;
    std::vector<ScreenWitness> pixels;
    for (int i = 0; i < 6; ++i) {
        ScreenWitness w;
        w.position_m = {40.0 * i, 0.0, 5.0};  // 0, 40, 80 in the open; 120, 160, 200 walled
        w.applied = glm::dvec3(1.0);
        pixels.push_back(w);
    }
    ScreenWitness leaf = pixels.back();  // a plant's own pixel is not asked
    leaf.kind = SurfaceKind::Object;
    pixels.push_back(leaf);
    meter.screenFrame(0, 12.0, pixels);
    EXPECT_EQ(meter.screenResults().size(), 4u);
    EXPECT_EQ(meter.screenLeftOut(), 3u);
    for (const ScreenResult& r : meter.screenResults()) EXPECT_TRUE(std::isfinite(r.error));
}

// Object witnesses are graded at the normal of the surface they stand for (ObjectWitness::normal)
// as well as over the sphere: a method 1.5 times too bright is 1.5 times as bright there; one
// whose field is mirrored top to bottom keeps every horizontal normal's irradiance (the terms odd
// in y vanish there), so the trunk facing the camera is graded as before while the car's roof and
// the sphere figure see the mirror.
TEST(ReferenceOracle, ObjectWitnessesAreGradedAtTheirDrawnNormal) {
    const ObjectFigures exact = objectFigures(0.0f, false);
    ASSERT_EQ(exact.count, 3u);       // one a frame
    EXPECT_LT(exact.carDrawn, 0.05);  // the fakes differ in face size only
    EXPECT_LT(exact.trunkDrawn, 0.05);
    const ObjectFigures bright = objectFigures(0.5f, false);
    EXPECT_NEAR(bright.carBias + 1.0, 1.5 * (exact.carBias + 1.0), 1e-4);
    EXPECT_NEAR(bright.trunkBias + 1.0, 1.5 * (exact.trunkBias + 1.0), 1e-4);
    const ObjectFigures mirrored = objectFigures(0.0f, true);
    EXPECT_NEAR(mirrored.trunkDrawn, exact.trunkDrawn, 1e-4);
    EXPECT_NEAR(mirrored.trunkBias, exact.trunkBias, 1e-4);
    EXPECT_GT(mirrored.carDrawn, exact.carDrawn + 0.1);  // the roof now sees the ground's light
    EXPECT_GT(mirrored.trunkSphere, exact.trunkSphere + 0.1);
}

// A trunk under its crown is drawn with the share of the tree's ambient its crown leaves it
// (ObjectWitness::ambientShare, world/Vegetation.h crownSkyShare): graded at that share, 1 + its
// bias scales by it, while the car and the sphere figure (the tree's SH itself) do not move.
TEST(ReferenceOracle, TrunkWitnessesAreGradedWithTheirCrownsShare) {
    const ObjectFigures whole = objectFigures(0.0f, false);
    const ObjectFigures shaded = objectFigures(0.0f, false, 0.6);
    ASSERT_EQ(shaded.count, whole.count);
    EXPECT_NEAR(shaded.trunkBias + 1.0, 0.6 * (whole.trunkBias + 1.0), 1e-4);
    EXPECT_GT(shaded.trunkDrawn, 0.3);  // the fakes agree, so a share of 0.6 is 40 % too dark
    EXPECT_NEAR(shaded.carBias, whole.carBias, 1e-9);
    EXPECT_NEAR(shaded.trunkSphere, whole.trunkSphere, 1e-9);
}

// The model step's split lights its coarse captures as the method's own captures light their
// surfaces (captureSurfaceLight): in a furnace of albedo rho lit by E_d, a capture whose surfaces
// also take a light of irradiance E_L is (E_d + E_L) / E_d times as bright, so 1 + each split
// figure scales by that against the same method without a light; the reference does not change.
TEST(DrawnBudget, TheModelSplitLightsItsCapturesAsTheMethodDoes) {
    using testing_support::FakeCubeCapture;
    using testing_support::FurnaceCapture;
    struct Constant final : SurfaceLight {
        ShRgb sh;
        ShRgb shAt(const glm::dvec3&) const override { return sh; }
    } field;
    for (int c = 0; c < 3; ++c) field.sh.c[0][c] = 40.0f;
    constexpr double kDirect = 100.0;
    const double lit = double(luminance(shIrradiance(field.sh, glm::vec3(0.0f, 1.0f, 0.0f))));
    ASSERT_GT(lit, 10.0);
    const auto run = [&](const SurfaceLight* light, int* litCaptures) {
        FurnaceCapture coarse(0.5, kDirect);
        FakeCubeCapture full(16);
        const DrawnBudgetSummary s = freshBudget(coarse, full, 0.0, 0.0, 0.0f, light);
        *litCaptures = coarse.litCaptures;
        return s;
    };
    int plainLit = 0, withLit = 0;
    const DrawnBudgetSummary plain = run(nullptr, &plainLit);
    const DrawnBudgetSummary with = run(&field, &withLit);
    ASSERT_GT(plain.count, 3u);
    ASSERT_EQ(with.count, plain.count);
    EXPECT_EQ(plainLit, 0);
    EXPECT_GT(withLit, 0);
    const double scale = (kDirect + lit) / kDirect;
    EXPECT_NEAR(with.sceneBias + 1.0, scale * (plain.sceneBias + 1.0), 1e-4 * scale);
    EXPECT_NEAR(with.placedBias + 1.0, scale * (plain.placedBias + 1.0), 1e-4 * scale);
}

namespace {

// A flat-lattice world whose drawn patches are 32 m across with 16 x 16 quads, placed so that the
// witness falls at (u, v) of its patch, u and v varying from witness to witness; the vertices
// rise and tilt with a closed-form relief, so each has its own point and normal.
class VertexGridEnvironment final : public testing_support::FlatProbeEnvironment {
  public:
    static constexpr double kSize_m = 32.0;
    static constexpr int kQuads = 16;
    static double fraction(double s) { return s - std::floor(s); }
    static double u(double x, double z) { return fraction(0.37 + 0.0131 * x + 0.0077 * z); }
    static double v(double x, double z) { return fraction(0.61 + 0.0059 * x - 0.0113 * z); }
    static double height(double x, double z) {
        return 0.4 * std::sin(x / 5.0) + 0.3 * std::cos(z / 3.0);
    }
    static glm::dvec3 normal(double x, double z) {
        return glm::normalize(glm::dvec3(-0.08 * std::cos(x / 5.0), 1.0, 0.1 * std::sin(z / 3.0)));
    }
    DrawnPatch drawnPatch(double x_m, double z_m, const glm::dvec3&) const override {
        DrawnPatch p;
        p.size_m = kSize_m;
        p.quads = kQuads;
        p.x0_m = x_m - u(x_m, z_m) * kSize_m, p.z0_m = z_m - v(x_m, z_m) * kSize_m;
        for (int c = 0; c < 4; ++c) {
            const double x = p.x0_m + (c & 1 ? kSize_m : 0.0), z = p.z0_m + (c & 2 ? kSize_m : 0.0);
            p.corner_m[c] = {x, height(x, z), z};
            p.cornerNormal[c] = normal(x, z);
        }
        p.surface_m = {x_m, 0.0, z_m};
        return p;
    }
    DrawnCell drawnCell(double x_m, double z_m, const glm::dvec3& camera_m) const override {
        const DrawnPatch p = drawnPatch(x_m, z_m, camera_m);
        const double s = kSize_m / kQuads;
        const double fu = (x_m - p.x0_m) / s, fw = (z_m - p.z0_m) / s;
        const int a = std::min(int(fu), kQuads - 1), b = std::min(int(fw), kQuads - 1);
        DrawnCell cell;
        cell.known = true;
        cell.spacing_m = s;
        for (int c = 0; c < 4; ++c) {
            const double x = p.x0_m + (a + (c & 1)) * s, z = p.z0_m + (b + (c >> 1)) * s;
            cell.vertex_m[c] = {x, height(x, z), z};
            cell.normal[c] = normal(x, z);
        }
        cell.weight = quadTriangleWeights(fu - a, fw - b);
        return cell;
    }
};

// A method whose far field is the fresh capture at the point, and whose answer at a terrain
// point varies with the point and with the size it is averaged over (patch_m), so that a value
// at a vertex, at a corner and averaged over another size all differ. Patches nearer the camera
// than range_m are lit per vertex.
struct VertexLitMethod final : AmbienceMethod {
    CubeCapture* capture = nullptr;
    const ProbeEnvironment* environment = nullptr;
    MeasureSettings settings;
    double range_m = 0.0;
    static double factor(const glm::dvec3& p, double patch_m) {
        return 1.0 + 0.3 * std::sin(p.x / 3.0) * std::cos(p.z / 5.0) + 0.01 * patch_m +
               0.05 * (p.y - kShadingHeight_m);
    }
    std::string methodName() const override { return "vertex-lit"; }
    void predictStage(const glm::dvec3&, const glm::dvec3&, double, double) override {}
    void captureStage() override {}
    void storeStage() override {}
    ShRgb shAt(double x_m, double z_m) const override {
        return oracleSh(*capture, *environment, settings, x_m, z_m, 12.0);
    }
    void cornerIrradianceAtPoints(std::size_t count, const glm::dvec3* points_m,
                                  const glm::dvec3* normals, glm::vec3* out,
                                  const double* patch_m) const override {
        std::vector<ShRgb> far(count);
        cornerShAtPoints(count, points_m, far.data());
        irradianceFromFar(count, points_m, normals, far.data(), out, patch_m);
    }
    void irradianceFromFar(std::size_t count, const glm::dvec3* points_m, const glm::dvec3* normals,
                           const ShRgb* far, glm::vec3* out, const double* patch_m) const override {
        for (std::size_t i = 0; i < count; ++i)
            out[i] = glm::max(shIrradiance(far[i], glm::vec3(normals[i])), glm::vec3(0.0f)) *
                     float(factor(points_m[i], patch_m ? patch_m[i] : 0.0));
    }
    double terrainVertexRange_m() const override { return range_m; }
    MethodStatistics methodStatistics() const override { return {}; }
};

}  // namespace

// With the method's vertex range on, a terrain witness on a patch nearer the camera than the
// range is graded as a patch lit per vertex draws it: the method at the four vertices of the grid
// cell holding it (2 m up, their normals, each as a point: no size to average over),
// interpolated as the cell's two triangles interpolate, here computed apart from the meter. Witnesses on patches
// beyond the range keep the corner blend exactly; the budget still closes, and with the far
// field the fresh capture it has no far-field term (fresh captures at the same vertices).
TEST(DrawnBudget, PatchesLitPerVertexAreGradedAtTheirCellsVertices) {
    using testing_support::FakeCubeCapture;
    constexpr double kRange_m = 40.0;
    const auto camera = [](int f) { return glm::dvec3(40.0 * f, 0.0, 25.0); };
    struct Run {
        std::vector<ReferenceWitness> witnesses;
        std::vector<double> expected;  // per witness: the per-vertex value's error, or NaN
        DrawnBudgetSummary budget;
    };
    const auto run = [&](double range_m) {
        FakeCubeCapture coarse(8), full(16);
        VertexGridEnvironment environment;
        const MeasureSettings ms = everyFrame();
        const auto meterOwned = referenceMeter(coarse, full, environment, 0);
        ErrorMeter& meter = *meterOwned;
        VertexLitMethod method;
        method.capture = &coarse, method.environment = &environment, method.settings = ms;
        method.range_m = range_m;
        for (int f = 0; f < 3; ++f) meter.frame(f, f / 30.0, 12.0, camera(f), 10.0, method);
        Run r;
        r.witnesses = meter.referenceWitnesses();
        r.budget = summarizeDrawnBudget(meter.drawnBudgets());
        for (const ReferenceWitness& w : r.witnesses) {
            double expected = std::nan("");
            const double x = w.position_m.x, z = w.position_m.z;
            const glm::dvec3 cam = camera(w.frame);
            const double x0 = x - VertexGridEnvironment::u(x, z) * 32.0;
            const double z0 = z - VertexGridEnvironment::v(x, z) * 32.0;
            const double dx = std::max({x0 - cam.x, 0.0, cam.x - x0 - 32.0});
            const double dz = std::max({z0 - cam.z, 0.0, cam.z - z0 - 32.0});
            if (w.ring >= 0 && std::hypot(dx, dz) < range_m) {
                // The cell (a, b) of 2 m holding the witness and its triangle: (v00, v01, v10)
                // where fu + fw <= 1, else (v10, v01, v11).
                const double gu = (x - x0) / 2.0, gw = (z - z0) / 2.0;
                const int a = std::min(int(gu), 15), b = std::min(int(gw), 15);
                const double fu = gu - a, fw = gw - b;
                glm::dvec3 sum(0.0);
                for (int c = 0; c < 4; ++c) {
                    const double vx = x0 + 2.0 * (a + (c & 1)), vz = z0 + 2.0 * (b + (c >> 1));
                    const glm::dvec3 at(
                        vx, VertexGridEnvironment::height(vx, vz) + kShadingHeight_m, vz);
                    const glm::dvec3 n = VertexGridEnvironment::normal(vx, vz);
                    const double point = 0.0;  // asked as a point, as the draw asks a vertex
                    glm::vec3 e;
                    method.cornerIrradianceAtPoints(1, &at, &n, &e, &point);
                    const bool upper = fu + fw > 1.0;
                    const double weight = c == 0   ? (upper ? 0.0 : 1.0 - fu - fw)
                                          : c == 1 ? (upper ? 1.0 - fw : fu)
                                          : c == 2 ? (upper ? 1.0 - fu : fw)
                                                   : (upper ? fu + fw - 1.0 : 0.0);
                    sum += glm::dvec3(e) * weight;
                }
                expected = irradianceRelativeError(
                    sum, meter.surfaceReference(w.frame, {x, 0.0, z}, {0.0, 1.0, 0.0}, 12.0));
            }
            r.expected.push_back(expected);
        }
        return r;
    };
    const Run off = run(0.0), on = run(kRange_m);
    ASSERT_EQ(off.witnesses.size(), on.witnesses.size());
    int perVertex = 0, beyond = 0, changed = 0;
    for (std::size_t i = 0; i < on.witnesses.size(); ++i) {
        const ReferenceWitness& w = on.witnesses[i];
        if (w.ring < 0) continue;
        SCOPED_TRACE("witness " + std::to_string(i) + " ring " + std::to_string(w.ring));
        EXPECT_TRUE(std::isnan(off.expected[i]));
        ASSERT_TRUE(std::isfinite(w.drawnError));
        if (std::isfinite(on.expected[i])) {
            ++perVertex;
            EXPECT_NEAR(w.drawnError, on.expected[i], 1e-6);
            changed += std::fabs(w.drawnError - off.witnesses[i].drawnError) > 1e-4;
        } else {
            ++beyond;
            EXPECT_EQ(w.drawnError, off.witnesses[i].drawnError);
            EXPECT_EQ(w.drawnBudget.freshFar, off.witnesses[i].drawnBudget.freshFar);
        }
        // The steps at the point do not depend on how the patch is drawn.
        EXPECT_EQ(w.drawnBudget.atPoint, off.witnesses[i].drawnBudget.atPoint);
        EXPECT_EQ(w.drawnBudget.perPoint, off.witnesses[i].drawnBudget.perPoint);
    }
    EXPECT_GE(perVertex, 6);
    EXPECT_GE(beyond, 12);
    EXPECT_GE(changed, perVertex / 2);
    // The method's far field is the fresh capture wherever it is asked, per vertex too.
    EXPECT_NEAR(on.budget.farField, 0.0, 1e-6);
    EXPECT_NEAR(on.budget.closure(), 1.0, 1e-9);
    EXPECT_NE(on.budget.drawn, off.budget.drawn);
}
