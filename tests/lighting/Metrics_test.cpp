// Metrics_test.cpp — the irradiance distance against its definition by quadrature, summaries,
// witness points, and the error meter with an oracle known in closed form.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "FakeCubeCapture.h"
#include "lighting/AmbienceMethod.h"
#include "lighting/Metrics.h"
#include "world/Error.h"

namespace amb {
namespace {

using testing_support::FakeCubeCapture;
using testing_support::FlatProbeEnvironment;

ShRgb randomSh(std::mt19937& rng) {
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    ShRgb sh;
    for (auto& c : sh.c) c = {u(rng), u(rng), u(rng)};
    sh.c[0] += glm::vec3(4.0f);
    return sh;
}

// ||E_a - E_b||^2 by quadrature over the sphere (a fine latitude-longitude midpoint rule) of the
// luminance-weighted squared channel differences of E(n) = sum_k Ahat_l L_k Y_k(n).
double distanceByQuadrature(const ShRgb& a, const ShRgb& b) {
    const int nt = 400, np = 800;
    double total = 0.0;
    for (int i = 0; i < nt; ++i) {
        const double theta = kPi * (i + 0.5) / nt;
        for (int j = 0; j < np; ++j) {
            const double phi = 2.0 * kPi * (j + 0.5) / np;
            const glm::dvec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                               std::cos(theta));
            const glm::vec3 d = shIrradiance(a, glm::vec3(n)) - shIrradiance(b, glm::vec3(n));
            const double w = std::sin(theta) * (kPi / nt) * (2.0 * kPi / np);
            for (int c = 0; c < 3; ++c) total += w * kLuminanceWeights[c] * double(d[c]) * d[c];
        }
    }
    return std::sqrt(total);
}

// The closed form equals the integral (quadrature error of this rule < 1e-4 relative).
TEST(Metrics, DistanceMatchesQuadrature) {
    std::mt19937 rng(7);
    for (int t = 0; t < 3; ++t) {
        const ShRgb a = randomSh(rng), b = randomSh(rng);
        const double exact = irradianceDistance(a, b);
        EXPECT_NEAR(exact, distanceByQuadrature(a, b), 1e-4 * exact);
    }
}

// Constant radiance c in every channel: E = pi c everywhere, so ||E|| = pi c sqrt(4 pi) (the
// weights sum to 1); two constants c1, c2 differ by pi |c1 - c2| sqrt(4 pi).
TEST(Metrics, ConstantRadianceClosedForm) {
    auto constant = [](float c) {
        ShRgb sh;
        sh.c[0] = glm::vec3(float(2.0 * std::sqrt(kPi)) * c);
        return sh;
    };
    const double s4pi = std::sqrt(4.0 * kPi);
    EXPECT_NEAR(irradianceNorm(constant(2.0f)), kPi * 2.0 * s4pi, 1e-5);
    EXPECT_NEAR(irradianceDistance(constant(2.0f), constant(1.5f)), kPi * 0.5 * s4pi, 1e-5);
    EXPECT_NEAR(relativeIrradianceError(constant(2.0f), constant(1.0f)), 1.0, 1e-6);
    EXPECT_EQ(relativeIrradianceError(constant(1.0f), constant(1.0f)), 0.0);
    // Scale invariance of the relative error.
    std::mt19937 rng(3);
    const ShRgb a = randomSh(rng), b = randomSh(rng);
    EXPECT_NEAR(relativeIrradianceError(a * 7.0f, b * 7.0f), relativeIrradianceError(a, b), 1e-5);
    // A black oracle gives a large finite number, not Inf or NaN.
    EXPECT_TRUE(std::isfinite(relativeIrradianceError(a, ShRgb{})));
}

// Pop: a change the oracle shares is no pop; a change it does not share is.
TEST(Metrics, PopSubtractsTheOraclesOwnChange) {
    std::mt19937 rng(11);
    const ShRgb o = randomSh(rng), change = randomSh(rng) * 0.1f;
    EXPECT_EQ(popValue(change, change, o), 0.0);
    EXPECT_NEAR(popValue(change, ShRgb{}, o), irradianceNorm(change) / irradianceNorm(o), 1e-9);
}

// Quantiles by linear interpolation: 0..100 gives p95 = 95, p99 = 99, mean 50.
TEST(Metrics, SummaryQuantiles) {
    std::vector<double> v;
    for (int i = 100; i >= 0; --i) v.push_back(i);
    const Summary s = summarize(v);
    EXPECT_EQ(s.count, 101u);
    EXPECT_DOUBLE_EQ(s.mean, 50.0);
    EXPECT_DOUBLE_EQ(s.p50, 50.0);
    EXPECT_DOUBLE_EQ(s.p95, 95.0);
    EXPECT_DOUBLE_EQ(s.p99, 99.0);
    EXPECT_DOUBLE_EQ(s.max, 100.0);
    EXPECT_EQ(summarize({}).count, 0u);
    EXPECT_TRUE(std::isinf(summarize({1.0, std::nan("")}).mean));  // never dropped silently
}

// Witnesses: ring 0 is the camera's point; ring r lies on the corner lattice, within its band
// widened by half a lattice diagonal; exact multiples of the spacing 10^6 m from the origin.
TEST(Metrics, WitnessRingsAndLattice) {
    MeasureSettings s;
    for (double cx : {0.0, 123.4, 1.0e6 + 17.25}) {
        const double cz = -cx * 0.5;
        for (int m = 0; m < 5; ++m) {
            const auto w = witnessPoints(s, cx, cz, m);
            ASSERT_EQ(w.size(), 1u + std::size_t(s.perRing) * (s.ringRadii.size() - 1));
            EXPECT_EQ(w[0].ring, 0);
            EXPECT_EQ(w[0].x_m, cx);
            for (std::size_t i = 1; i < w.size(); ++i) {
                const int r = w[i].ring;
                ASSERT_GE(r, 1);
                const double d = std::hypot(w[i].x_m - cx, w[i].z_m - cz);
                const double slack = s.cornerSpacing_m * std::sqrt(0.5);
                EXPECT_GE(d, s.ringRadii[std::size_t(r - 1)] - slack);
                EXPECT_LE(d, s.ringRadii[std::size_t(r)] + slack);
                EXPECT_EQ(std::fmod(w[i].x_m, s.cornerSpacing_m), 0.0);
                EXPECT_EQ(std::fmod(w[i].z_m, s.cornerSpacing_m), 0.0);
            }
        }
    }
}

// A method that applies a fixed multiple of the fake's own capture (the oracle) at every point.
class ScaledOracleMethod final : public AmbienceMethod {
  public:
    ScaledOracleMethod(FakeCubeCapture& capture, const FlatProbeEnvironment& env, float scale)
        : capture_(capture), env_(env), scale_(scale) {}
    std::string methodName() const override { return "scaled"; }
    void predictStage(const glm::dvec3&, const glm::dvec3&, double tod, double) override {
        tod_ = tod;
    }
    void captureStage() override {}
    void storeStage() override {}
    ShRgb shAt(double x, double z) const override {
        return oracleSh(capture_, env_, MeasureSettings{}, x, z, tod_) * scale_;
    }
    MethodStatistics methodStatistics() const override { return {}; }

  private:
    FakeCubeCapture& capture_;
    const FlatProbeEnvironment& env_;
    float scale_;
    double tod_ = 12.0;
};

// The meter against an exact method reads 0 error and 0 pop; against 1.25 x the oracle it reads
// 0.25 everywhere (scale invariance of the relative norm). The oracle file round-trips, and one
// made for other settings or malformed is refused with InputError.
TEST(Metrics, ErrorMeterClosedFormsAndOracleFile) {
    FakeCubeCapture capture(8);
    FlatProbeEnvironment env;
    MeasureSettings s;
    s.every = 4;
    s.ringRadii = {16.0, 48.0, 144.0};
    s.perRing = 2;
    for (float scale : {1.0f, 1.25f}) {
        ScaledOracleMethod method(capture, env, scale);
        ErrorMeter meter(capture, env, s);
        for (int f = 0; f < 13; ++f) {
            const double tod = 12.0 + 0.01 * f;
            method.predictStage({}, {}, tod, 0.1);
            meter.frame(f, 0.1 * f, tod, glm::dvec3(10.0 * f, 5.0, 3.0 * f), 10.0, method);
        }
        ASSERT_EQ(meter.measured().size(), 4u);  // frames 0, 4, 8, 12
        for (double e : meter.errors()) EXPECT_NEAR(e, scale - 1.0, 1e-5);
        // The pops: the applied value follows the oracle, whose change is linear in between
        // only approximately, so a small residue remains; it is far below a real pop.
        EXPECT_EQ(meter.pops().size(), 12u * std::size_t(s.popPoints));
        for (double p : meter.pops()) EXPECT_LT(p, 2e-3);
    }
    // Oracle file: save, load into a new meter, no captures needed.
    ScaledOracleMethod method(capture, env, 1.0f);
    ErrorMeter first(capture, env, s);
    for (int f = 0; f < 9; ++f) first.frame(f, 0.1 * f, 12.0, glm::dvec3(f, 0, 0), 1.0, method);
    const auto dir =
        std::filesystem::temp_directory_path() / ("amb-metrics-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    const std::string file = (dir / "oracle.json").string();
    first.saveOracle(file, "sig-a");
    ErrorMeter second(capture, env, s);
    second.loadOracle(file, "sig-a");
    for (int f = 0; f < 9; ++f) second.frame(f, 0.1 * f, 12.0, glm::dvec3(f, 0, 0), 1.0, method);
    EXPECT_EQ(second.oracleCaptures(), 0);
    EXPECT_EQ(second.oracleCacheHits(), first.oracleCaptures());
    EXPECT_EQ(second.errors(), first.errors());
    EXPECT_THROW(second.loadOracle(file, "sig-b"), InputError);
    std::ofstream(dir / "bad.json") << "{\"format\": \"ambience-oracle\", \"version\": 1, ";
    EXPECT_THROW(second.loadOracle((dir / "bad.json").string(), "sig-a"), InputError);
    std::ofstream(dir / "nan.json")
        << "{\"format\":\"ambience-oracle\",\"version\":1,\"signature\":\"s\",\"entries\":"
           "[{\"frame\":0,\"x\":0,\"z\":0,\"sh\":[1,2]}]}";
    EXPECT_THROW(second.loadOracle((dir / "nan.json").string(), "s"), InputError);
    EXPECT_THROW(second.loadOracle((dir / "missing.json").string(), "s"), InputError);
    std::filesystem::remove_all(dir);
}

// A field g(x) c along x (c a fixed coefficient set): linear, with a step of 0.5 at x = 50.5 m.
class StepFieldMethod final : public AmbienceMethod {
  public:
    std::string methodName() const override { return "step"; }
    void predictStage(const glm::dvec3&, const glm::dvec3&, double, double) override {}
    void captureStage() override {}
    void storeStage() override {}
    ShRgb shAt(double x, double) const override { return c() * float(g(x)); }
    MethodStatistics methodStatistics() const override { return {}; }
    static double g(double x) { return 2.0 + 0.01 * x + (x > 50.5 ? 0.5 : 0.0); }
    static ShRgb c() {
        ShRgb sh;
        for (int k = 0; k < kShCoefficients; ++k) sh.c[k] = glm::vec3(1.0f, 0.8f - 0.05f * k, 0.3f);
        return sh;
    }
};

// Pop along the moving point: a linear field crossed at 1 m a frame reads 0; the step reads
// 0.5 / g at the frame it is crossed and once more at the next (Metrics.h: the second
// difference); a camera cut restarts the path instead of reading as a pop.
TEST(Metrics, PopAlongTheMovingPointIsTheSecondDifference) {
    FakeCubeCapture capture(8);
    FlatProbeEnvironment env;
    MeasureSettings s;
    s.every = 1000;  // one measured frame: the moving pop does not need the oracle
    StepFieldMethod method;
    ErrorMeter meter(capture, env, s);
    for (int f = 0; f < 100; ++f) meter.frame(f, f / 30.0, 12.0, {double(f), 2.0, 7.0}, 30.0, method);
    const auto& pops = meter.movingPops();
    ASSERT_EQ(pops.size(), 98u);  // from the third frame on
    for (std::size_t i = 0; i < pops.size(); ++i) {
        const int f = int(i) + 2;  // pops[i] is frame f's
        if (f == 51) {
            EXPECT_NEAR(pops[i], 0.5 / StepFieldMethod::g(50.0), 1e-5);
        } else if (f == 52) {
            EXPECT_NEAR(pops[i], 0.5 / StepFieldMethod::g(51.0), 1e-5);
        } else {
            EXPECT_LT(pops[i], 1e-5) << "frame " << f;
        }
    }
    // A cut 500 m away: two frames to restart, no pop from the jump.
    for (int f = 100; f < 104; ++f)
        meter.frame(f, f / 30.0, 12.0, {600.0 + f, 2.0, 7.0}, 30.0, method);
    ASSERT_EQ(meter.movingPops().size(), 98u + 2u);
    for (std::size_t i = 98; i < 100; ++i) EXPECT_LT(meter.movingPops()[i], 1e-5);
}

// 27 comma-separated coefficients, the n-th replaced by `value`.
std::string shList(int n = -1, const std::string& value = "") {
    std::string out;
    for (int i = 0; i < 27; ++i) out += (i ? "," : "") + (i == n ? value : std::to_string(i));
    return "[" + out + "]";
}

// A wrong type anywhere, a missing field, an out-of-range frame, a coefficient beyond
// +-kMaxOracleCoefficient or not fitting a float: InputError naming the field (before: raw JSON
// library exceptions, exit 1; 1e300 loaded and became inf in the error figures). The cache keeps
// what it held, and the file reader refuses what is not a regular file.
TEST(Metrics, OracleReaderNamesTheBadField) {
    FakeCubeCapture capture(8);
    FlatProbeEnvironment env;
    MeasureSettings s;
    s.every = 1;
    ErrorMeter meter(capture, env, s);
    const std::string head = R"({"format":"ambience-oracle","version":1,"signature":"s",)";
    const auto one = [&](const std::string& entry) {
        return head + "\"entries\":[" + entry + "]}";
    };
    const std::string good = R"({"frame":0,"x":0,"z":0,"sh":)" + shList() + "}";
    meter.loadOracleText(one(good), "o.json", "s");

    struct Case {
        std::string doc, expected;
    };
    const std::vector<Case> cases = {
        {"[]", "not an ambience oracle file"},
        {R"({"format":1,"version":1})", "'format'"},
        {R"({"format":"ambience-oracle","version":"1","signature":"s","entries":[]})",
         "format/version"},
        {R"({"format":"ambience-oracle","version":1,"signature":5,"entries":[]})", "'signature'"},
        {R"({"format":"ambience-oracle","version":1,"signature":"s"})", "'entries' is missing"},
        {head + R"("entries":{}})", "'entries' must be an array"},
        {one("5"), "entries[0]: expected an object"},
        {one(R"({"frame":"x","x":0,"z":0,"sh":)" + shList() + "}"), "frame"},
        {one(R"({"frame":-1,"x":0,"z":0,"sh":)" + shList() + "}"), "frame"},
        {one(R"({"frame":1.5,"x":0,"z":0,"sh":)" + shList() + "}"), "frame"},
        {one(R"({"frame":4294967296,"x":0,"z":0,"sh":)" + shList() + "}"), "frame"},
        {one(R"({"frame":18446744073709551615,"x":0,"z":0,"sh":)" + shList() + "}"), "frame"},
        {one(R"({"frame":0,"x":"1","z":0,"sh":)" + shList() + "}"), "x: expected a number"},
        {one(R"({"frame":0,"x":0,"sh":)" + shList() + "}"), "'z' is missing"},
        {one(R"({"frame":0,"x":0,"z":0})"), "'sh' is missing"},
        {one(R"({"frame":0,"x":0,"z":0,"sh":{}})"), "sh: expected 27 numbers"},
        {one(R"({"frame":0,"x":0,"z":0,"sh":)" + shList(5, "\"a\"") + "}"), "sh[5]"},
        {one(R"({"frame":0,"x":0,"z":0,"sh":)" + shList(0, "1e300") + "}"), "sh[0]"},
        {one(R"({"frame":0,"x":0,"z":0,"sh":)" + shList(26, "-2e9") + "}"), "sh[26]"},
        {one(R"({"frame":0,"x":0,"z":0,"sh":)" + shList(3, "null") + "}"), "sh[3]"},
        {one(good + "," + good), "entries[1]: repeats"},
        {one(good) + "x", "malformed"},
        {head + R"("entries":[)" + good + ",", "malformed"},
    };
    for (const Case& c : cases) {
        try {
            meter.loadOracleText(c.doc, "o.json", "s");
            ADD_FAILURE() << "accepted: " << c.doc;
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_EQ(what.rfind("o.json", 0), 0u) << what;
            EXPECT_NE(what.find(c.expected), std::string::npos) << what << " / " << c.expected;
        }
    }
    // The bound itself is accepted.
    meter.loadOracleText(one(R"({"frame":0,"x":0,"z":0,"sh":)" + shList(4, "-1e9") + "}"), "o.json",
                         "s");
    meter.loadOracleText(one(good), "o.json", "s");
    // The good cache survived the failures: the camera's ground point at frame 0 is a hit.
    ScaledOracleMethod method(capture, env, 1.0f);
    meter.frame(0, 0.0, 12.0, glm::dvec3(0.0), 0.0, method);
    EXPECT_EQ(meter.oracleCacheHits(), 1);
    EXPECT_THROW(meter.loadOracle(std::filesystem::temp_directory_path().string(), "s"),
                 InputError);
    EXPECT_THROW(meter.loadOracle("/dev/zero", "s"), InputError);
}

}  // namespace
}  // namespace amb
