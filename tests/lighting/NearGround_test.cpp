// NearGround_test.cpp — the near field's ground term (lighting/NearField.h "Ground"): a white
// ground under a uniform far field changes nothing, a sunlit disc of ground matches the closed
// form of a cap, a sphere's shadow on the ground darkens what the ground shows, a cached
// point follows the light as a fresh one does, and a terrain corner's patch mean is the tent's
// mean of its ground's points.
#include "lighting/NearField.h"

#include <cmath>
#include <functional>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "world/Conventions.h"

namespace amb {
namespace {

// Flat ground at height 0 with an albedo that may vary, spheres as plants, and a light whose
// elevation follows the time of day (90 degrees at noon).
struct FlatGround final : NearFieldScene {
    std::function<glm::dvec3(double, double)> albedo = [](double, double) { return glm::dvec3(0.3); };
    std::vector<SphereOccluder> plants;
    glm::dvec3 lightIrradiance{0.0};
    void occludersNear(const glm::dvec3& p, double radius_m, double,
                       std::vector<SphereOccluder>& out) const override {
        for (const SphereOccluder& o : plants)
            if (std::hypot(o.centre_m.x - p.x, o.centre_m.z - p.z) < radius_m) out.push_back(o);
    }
    DirectionalLight mainLight(double timeOfDay_h) const override {
        const double e = kPi / 2.0 - (timeOfDay_h - 12.0) * kPi / 12.0;
        DirectionalLight l;
        l.direction = glm::normalize(glm::dvec3(std::cos(e), std::sin(e), 0.1 * std::cos(e)));
        l.irradiance = lightIrradiance;
        return l;
    }
    // The ambient brightens through the day, so cached terms must follow it too.
    HemisphereAmbient ambient(double timeOfDay_h) const override {
        return {glm::dvec3(0.5, 0.6, 0.8) * (1.0 + 0.05 * (timeOfDay_h - 12.0)), glm::dvec3(0.2)};
    }
    double groundHeight(double, double) const override { return 0.0; }
    bool groundAt(double x, double z, GroundPoint& out, const GroundPoint* = nullptr) const override {
        out.height_m = 0.0;
        out.normal = {0.0, 1.0, 0.0};
        out.albedo = albedo(x, z);
        return true;
    }
};

ShRgbD constantSky(const glm::dvec3& radiance) {
    ShRgbD sh;
    sh.c[0] = radiance * (2.0 * std::sqrt(kPi));
    return sh;
}

DirectionalLight zenithSun(double irradiance) {
    DirectionalLight l;
    l.direction = {0.0, 1.0, 0.0};
    l.irradiance = glm::dvec3(irradiance);
    return l;
}

// The irradiance of `sh` at `n`, green channel.
double irradianceG(const ShRgbD& sh, const glm::dvec3& n) {
    return double(shIrradiance(toFloat(sh), glm::vec3(n)).g);
}

// A white ground lit by a hemisphere ambient of sky radiance s sends s back (E_amb(up) = pi s,
// whatever the distant ground's radiance): under a far field of s all round, removing what the
// probes saw below and putting the ground's own in its place is the identity (to float
// rounding).
TEST(NearGround, AWhiteGroundUnderAUniformFarFieldChangesNothing) {
    FlatGround scene;
    scene.albedo = [](double, double) { return glm::dvec3(1.0); };
    const glm::dvec3 p(3.0, 2.0, -1.0);
    const GroundTerm ground = groundTerm(p, scene, {}, {}, 16.0, {0.0, 1.0, 0.0});
    ASSERT_TRUE(ground.any);
    EXPECT_EQ(ground.samples, 32);
    const glm::dvec3 s(1.0, 0.8, 0.6);
    const ShRgbD far = constantSky(s);
    const HemisphereAmbient ambient{s, glm::dvec3(0.1, 0.3, 0.2)};
    const ShRgbD got = applyNearField(far, p, {}, zenithSun(0.0), {}, &ground, ambient);
    for (int k = 0; k < kShCoefficients; ++k)
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(got.c[k][c], far.c[k][c], 1e-5) << k << " " << c;
}

// A dark far field, the sun at the zenith and a hemisphere ambient of sky radiance s: the
// ground within R of the foot, of albedo rho, sends rho (E + pi s) / pi up; its SH is that
// radiance times the closed-form SH of the cap about -Y of half-angle atan(R / h). The 32
// directions give it within 2 % of the constant coefficient, and a downward surface's
// irradiance within 2 %. Each channel takes its own albedo and its own ambient.
TEST(NearGround, ASunlitDiscOfGroundMatchesTheCapsClosedForm) {
    FlatGround scene;
    const glm::dvec3 rho(0.1, 0.3, 0.2);
    scene.albedo = [&](double, double) { return rho; };
    const double h = 2.0, R = 16.0, E = 500.0;
    const HemisphereAmbient ambient{glm::dvec3(20.0, 30.0, 45.0), glm::dvec3(5.0)};
    const glm::dvec3 p(0.0, h, 0.0);
    const GroundTerm ground = groundTerm(p, scene, {}, {}, R, {0.0, 1.0, 0.0});
    const ShRgbD got = applyNearField(ShRgbD{}, p, {}, zenithSun(E), {}, &ground, ambient);
    const auto cap = capSh({0.0, -1.0, 0.0}, h / std::hypot(h, R));
    const glm::dvec3 lit = rho * (E + kPi * ambient.sky) / kPi;  // the ground's radiance
    for (int c = 0; c < 3; ++c) {
        for (int k = 0; k < kShCoefficients; ++k)
            EXPECT_NEAR(got.c[k][c], lit[c] * cap[k], 0.02 * lit[c] * cap[0])
                << "k " << k << " channel " << c;
    }
    ShRgbD want;
    for (int k = 0; k < kShCoefficients; ++k) want.c[k] = glm::dvec3(lit.g * cap[k]);
    const double down = irradianceG(got, {0.0, -1.0, 0.0});
    EXPECT_NEAR(down, irradianceG(want, {0.0, -1.0, 0.0}), 0.02 * down);
    EXPECT_GT(down, 0.9 * kPi * lit.g);  // nearly the whole lower hemisphere at that radiance
}

// A crown of radius 3 m, 8 m above the foot, with the sun at the zenith: its shadow is the disc
// of radius 3 m under it, which holds 9 / 13 of a downward normal's irradiance from the ground
// (r^2 / (r^2 + h^2) at h = 2 m), so that irradiance drops to about 0.3 of the open ground's
// (0.2-0.42 for 32 directions). The crown also hides the sky above: the ground's ambient, as
// the point's caps leave it, is dimmed with it.
TEST(NearGround, AShadowOnTheGroundDarkensWhatTheGroundShows) {
    FlatGround scene;
    const glm::dvec3 p(0.0, 2.0, 0.0);
    const SphereOccluder crown{{0.0, 8.0, 0.0}, 3.0, glm::dvec3(0.2), 1.0};
    const GroundTerm open = groundTerm(p, scene, {}, {}, 16.0, {0.0, 1.0, 0.0});
    const GroundTerm shaded = groundTerm(p, scene, {crown}, {crown}, 16.0, {0.0, 1.0, 0.0});
    EXPECT_EQ(shaded.samples, open.samples);  // nothing stands between the point and the ground
    const DirectionalLight sun = zenithSun(500.0);
    const double a = irradianceG(applyNearField(ShRgbD{}, p, {}, sun, {}, &open), {0, -1, 0});
    const double b = irradianceG(applyNearField(ShRgbD{}, p, {}, sun, {}, &shaded), {0, -1, 0});
    EXPECT_GT(b, 0.2 * a);
    EXPECT_LT(b, 0.42 * a);
    // The ambient part: a dark far field, no light; the crown's cap dims the ground's ambient.
    const HemisphereAmbient ambient{glm::dvec3(1.0), glm::dvec3(0.3)};
    const double skyOpen =
        irradianceG(applyNearField(ShRgbD{}, p, {}, zenithSun(0.0), {}, &open, ambient), {0, -1, 0});
    const double skyShaded = irradianceG(
        applyNearField(ShRgbD{}, p, {crown}, zenithSun(0.0), {}, &shaded, ambient), {0, -1, 0});
    EXPECT_GT(skyOpen, 0.9 * 0.3 * kPi * ambient.sky.g);  // nearly all the ground at rho s
    EXPECT_LT(skyShaded, skyOpen);
    EXPECT_GT(skyShaded, 0.5 * skyOpen);
}

// Points cached at 10 h and asked again at 13 h (the light has moved; no plant, so nothing
// depends on the light the point was built in) answer what a NearField built at 13 h answers,
// through the SH path and through normals facing up and down (the light and the ambient on the
// ground reach the downward ones), and the ground changes the answer.
TEST(NearGround, ACachedPointFollowsTheLightAsAFreshOne) {
    FlatGround scene;
    scene.lightIrradiance = glm::dvec3(400.0, 380.0, 350.0);
    scene.albedo = [](double x, double z) {
        return glm::dvec3(0.1 + 0.05 * std::sin(x), 0.2 + 0.1 * std::cos(0.3 * z), 0.15);
    };
    NearFieldSettings settings;
    NearField cached(scene, settings);
    cached.setTimeOfDay(10.0);
    const ShRgb far = toFloat(constantSky(glm::dvec3(0.9, 1.0, 1.1)));
    std::vector<glm::dvec3> points, normals;
    for (int i = 0; i < 12; ++i) {
        points.push_back({3.0 * i, 2.0, -2.0 * i});
        normals.push_back(glm::normalize(glm::dvec3(0.2 * std::sin(i), i % 2 ? -1.0 : 1.0, 0.1 * i - 0.6)));
    }
    std::vector<ShRgb> fars(points.size(), far);
    std::vector<glm::vec3> before(points.size()), after(points.size()), fresh(points.size());
    cached.irradianceMany(points.size(), fars.data(), points.data(), normals.data(), before.data());
    for (const glm::dvec3& p : points) cached.apply(far, p);
    cached.setTimeOfDay(13.0);
    cached.irradianceMany(points.size(), fars.data(), points.data(), normals.data(), after.data());
    NearField rebuilt(scene, settings);
    rebuilt.setTimeOfDay(13.0);
    rebuilt.irradianceMany(points.size(), fars.data(), points.data(), normals.data(), fresh.data());
    NearFieldSettings noGround = settings;
    noGround.ground = false;
    NearField without(scene, noGround);
    without.setTimeOfDay(13.0);
    for (std::size_t i = 0; i < points.size(); ++i) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(after[i][c], fresh[i][c], 1e-4 * fresh[i][c]);
        if (i % 2) {
            EXPECT_GT(std::abs(after[i].g - before[i].g), 1e-2f * after[i].g);  // the light moved
        }
        const ShRgb a = cached.apply(far, points[i]), b = rebuilt.apply(far, points[i]);
        for (int k = 0; k < kShCoefficients; ++k)
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(a.c[k][c], b.c[k][c], 1e-4f * std::abs(b.c[0][c])) << i << " " << k;
        const ShRgb plain = without.apply(far, points[i]);
        EXPECT_GT(std::abs(plain.c[0].g - a.c[0].g), 0.1f * std::abs(a.c[0].g));
    }
}

// A point asked through the ground's own normal (a terrain corner, a road vertex) takes no
// ground term: its region lies below that normal's horizon (NearField.h "Through one normal").
// Through a normal tilted 40 degrees, which sees part of it, the ground changes the answer.
TEST(NearGround, APointSeenThroughTheGroundsNormalTakesNoGroundTerm) {
    FlatGround scene;
    scene.lightIrradiance = glm::dvec3(400.0, 380.0, 350.0);
    scene.plants = {{{3.0, 6.0, 1.0}, 3.0, glm::dvec3(0.1, 0.25, 0.08)}};
    NearFieldSettings settings, noGround;
    settings.patchMean = noGround.patchMean = false;
    noGround.ground = false;
    const ShRgb far = toFloat(constantSky(glm::dvec3(0.9, 1.0, 1.1)));
    const glm::dvec3 p(0.0, kShadingHeight_m, 0.0);
    const glm::dvec3 up(0.0, 1.0, 0.0), slightly = glm::normalize(glm::dvec3(0.1, 1.0, 0.05));
    const glm::dvec3 tilted = glm::normalize(glm::dvec3(std::sin(0.7), std::cos(0.7), 0.0));
    const auto answer = [&](const NearFieldSettings& s, const glm::dvec3& n) {
        NearField near(scene, s);
        near.setTimeOfDay(10.0);
        glm::vec3 e;
        near.irradianceMany(1, &far, &p, &n, &e);
        return e;
    };
    for (const glm::dvec3& n : {up, slightly}) {
        const glm::vec3 with = answer(settings, n), without = answer(noGround, n);
        for (int c = 0; c < 3; ++c) EXPECT_EQ(with[c], without[c]) << c;
    }
    const glm::vec3 with = answer(settings, tilted), without = answer(noGround, tilted);
    EXPECT_GT(std::abs(with.g - without.g), 0.01f * without.g);
}

// An object (the car) walks 30 m across a checkerboard of 3 m squares, albedo 0.1 and 0.4, in
// 0.1 m steps under a dark far field and the sun. Its downward irradiance's second difference
// (what the pop along a moving object measures) stays below 0.5 % of its value: the objects'
// ground term is the B-spline blend of a 2 m lattice's, C1 in the position. A point's own
// term (what a fixed corner takes), asked along the same walk, steps by more than 2 % where a
// square's edge crosses one of its 32 directions: that is what the blend is for.
TEST(NearGround, AMovingObjectsGroundTermChangesSmoothly) {
    FlatGround scene;
    scene.lightIrradiance = glm::dvec3(500.0);
    scene.albedo = [](double x, double z) {
        const bool odd = (int(std::floor(x / 3.0)) + int(std::floor(z / 3.0))) % 2 != 0;
        return glm::dvec3(odd ? 0.4 : 0.1);
    };
    NearFieldSettings settings;
    NearField object(scene, settings), point(scene, settings);
    object.setTimeOfDay(12.0), point.setTimeOfDay(12.0);
    const ShRgb far{};
    std::vector<double> blended, own;
    for (int i = 0; i <= 300; ++i) {
        const double x = 0.1 * i + 0.05, z = 0.37 * 0.1 * i + 1.3;
        const ShRgb a = object.applyAbove(far, x, z, 2.0, NearFieldMethod::kSelfRadius_m);
        const ShRgb b = point.apply(far, glm::dvec3(x, 2.0, z));
        blended.push_back(shIrradiance(a, glm::vec3(0, -1, 0)).g);
        own.push_back(shIrradiance(b, glm::vec3(0, -1, 0)).g);
    }
    double worstBlended = 0.0, worstOwn = 0.0;
    for (std::size_t i = 2; i < blended.size(); ++i) {
        worstBlended = std::max(worstBlended,
                                std::abs(blended[i] - 2 * blended[i - 1] + blended[i - 2]) / blended[i]);
        worstOwn = std::max(worstOwn, std::abs(own[i] - 2 * own[i - 1] + own[i - 2]) / own[i]);
    }
    ::testing::Test::RecordProperty("worstBlended", std::to_string(worstBlended));
    ::testing::Test::RecordProperty("worstOwn", std::to_string(worstOwn));
    EXPECT_LT(worstBlended, 0.005);
    EXPECT_GT(worstOwn, 0.02);
    // The blend keeps the level: the walk's mean within 3 % of the points' own.
    double meanA = 0.0, meanB = 0.0;
    for (std::size_t i = 0; i < own.size(); ++i) meanA += blended[i], meanB += own[i];
    EXPECT_NEAR(meanA, meanB, 0.03 * meanB);
}

TEST(NearGround, AnObjectFirstBuiltFarFromTheCameraTakesItsOwnGroundTerm) {
    // A plant entering the objects' range stands still: it takes the ground term of its own
    // point, as a corner there does (exactly: no plants, so nothing of its own to leave out).
    // The car, near the camera, blends the lattice instead, which differs on a checkered ground.
    FlatGround scene;
    scene.lightIrradiance = glm::dvec3(500.0);
    scene.albedo = [](double x, double z) {
        const bool odd = (int(std::floor(x / 3.0)) + int(std::floor(z / 3.0))) % 2 != 0;
        return glm::dvec3(odd ? 0.4 : 0.1);
    };
    const NearFieldSettings settings;
    NearField still(scene, settings), moving(scene, settings), point(scene, settings),
        below(scene, settings);
    for (NearField* n : {&still, &moving, &point, &below}) n->setTimeOfDay(12.0);
    const double x = 4.3, z = 1.9;
    still.setViewer({x + 60.0, 0.0, z});  // beyond latticeRange_m
    moving.setViewer({x + 5.0, 0.0, z});
    // A flight's camera 60 m straight above: the point below it is not the car.
    below.setViewer({x, 62.0, z});
    const ShRgb far{};
    const ShRgb s = still.applyAbove(far, x, z, 2.0, NearFieldMethod::kSelfRadius_m);
    const ShRgb m = moving.applyAbove(far, x, z, 2.0, NearFieldMethod::kSelfRadius_m);
    const ShRgb b = below.applyAbove(far, x, z, 2.0, NearFieldMethod::kSelfRadius_m);
    const ShRgb p = point.apply(far, glm::dvec3(x, 2.0, z));
    for (int k = 0; k < kShCoefficients; ++k) EXPECT_EQ(s.c[k], p.c[k]) << k;
    for (int k = 0; k < kShCoefficients; ++k) EXPECT_EQ(b.c[k], p.c[k]) << k;
    const float own = shIrradiance(s, glm::vec3(0, -1, 0)).g;
    const float blended = shIrradiance(m, glm::vec3(0, -1, 0)).g;
    EXPECT_GT(own, 0.0f);
    EXPECT_GT(std::abs(own - blended), 0.01f * own);
}

// A terrain corner of patch size P takes the tent-weighted mean of the near field at 3 x 3
// ground points P / 2 apart (NearField.h "Patch mean"). On flat ground every sample's normal is
// the corner's, so the mean irradiance is the mean of the points' own answers, each asked of a
// fresh NearField as a point: 1D weights 1/4, 1/2, 1/4. A tree right over the corner changes
// the corner's point by far more than its mean, where it is one sample of nine (weight 1/4).
// After the light moves, a cached mean follows it as its points, cached, do (the samples'
// ground light terms are kept). Four corners of one patch size share their samples: 25 builds, not 36.
TEST(NearGround, ACornersPatchMeanIsTheTentMeanOfItsGroundsPoints) {
    FlatGround scene;
    scene.lightIrradiance = glm::dvec3(40.0, 38.0, 35.0);
    scene.albedo = [](double x, double z) {
        return glm::dvec3(0.1 + 0.05 * std::sin(0.2 * x), 0.2 + 0.1 * std::cos(0.1 * z), 0.15);
    };
    const double P = 32.0;
    scene.plants = {{{0.5, 6.0, -0.5}, 4.0, glm::dvec3(0.1, 0.25, 0.08)},
                    {{14.0, 5.0, 17.0}, 3.0, glm::dvec3(0.1, 0.25, 0.08)},
                    {{-20.0, 7.0, 3.0}, 5.0, glm::dvec3(0.1, 0.25, 0.08)}};
    NearFieldSettings settings;
    const ShRgb far = toFloat(constantSky(glm::dvec3(0.9, 1.0, 1.1)));
    const glm::dvec3 up(0.0, 1.0, 0.0);
    const glm::dvec3 corner(0.0, kShadingHeight_m, 0.0);
    // A point's answer at a time of day; with `builtAt`, from a point built then and kept in
    // its cache since (a cached point keeps its ground's shadows from the light it was built
    // in: NearField.h "Ground").
    const auto pointAnswer = [&](double x, double z, double timeOfDay_h, double builtAt = -1.0) {
        NearField fresh(scene, settings);
        const glm::dvec3 p(x, kShadingHeight_m, z);
        glm::vec3 e;
        if (builtAt >= 0.0) {
            fresh.setTimeOfDay(builtAt);
            fresh.irradianceMany(1, &far, &p, &up, &e);
        }
        fresh.setTimeOfDay(timeOfDay_h);
        fresh.irradianceMany(1, &far, &p, &up, &e);
        return glm::dvec3(e);
    };
    const auto tentMean = [&](double timeOfDay_h, double builtAt = -1.0) {
        const double w[3] = {0.25, 0.5, 0.25};
        glm::dvec3 sum(0.0);
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                sum += w[a] * w[b] *
                       pointAnswer((a - 1) * P / 2.0, (b - 1) * P / 2.0, timeOfDay_h, builtAt);
        return sum;
    };
    NearField cached(scene, settings);
    cached.setTimeOfDay(9.0);
    glm::vec3 got;
    cached.irradianceMany(1, &far, &corner, &up, &got, nullptr, &P);
    const glm::dvec3 want = tentMean(9.0), point = pointAnswer(0.0, 0.0, 9.0);
    const glm::dvec3 open = glm::dvec3(shIrradiance(far, glm::vec3(up)));
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(got[c], want[c], 1e-4 * want[c]) << c;
        // The tree changes its point by more than twice what it changes the mean.
        EXPECT_GT(std::abs(open[c] - point[c]), 2.0 * std::abs(open[c] - want[c])) << c;
    }
    // Switched off, or with no patch size, the corner takes its point's answer.
    NearFieldSettings off = settings;
    off.patchMean = false;
    NearField pointwise(scene, off);
    pointwise.setTimeOfDay(9.0);
    glm::vec3 asPoint;
    pointwise.irradianceMany(1, &far, &corner, &up, &asPoint, nullptr, &P);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(asPoint[c], point[c], 1e-6 * point[c]);
    // The light moves: the cached mean follows it as its cached points do.
    cached.setTimeOfDay(12.0);
    cached.irradianceMany(1, &far, &corner, &up, &got, nullptr, &P);
    const glm::dvec3 later = tentMean(12.0, 9.0);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(got[c], later[c], 1e-4 * later[c]) << c;
        EXPECT_GT(std::abs(later[c] - want[c]), 1e-3 * later[c]) << c;  // the light did move
    }
    // Four corners of one patch size: the 5 x 5 lattice of P / 2 they read, each point built once.
    NearField shared(scene, settings);
    shared.setTimeOfDay(10.0);
    std::vector<glm::dvec3> corners, normals(4, up);
    for (int i = 0; i < 4; ++i) corners.push_back({(i % 2) * P, kShadingHeight_m, (i / 2) * P});
    std::vector<ShRgb> fars(4, far);
    std::vector<double> patch(4, P);
    std::vector<glm::vec3> four(4);
    shared.irradianceMany(4, fars.data(), corners.data(), normals.data(), four.data(), nullptr,
                          patch.data());
    EXPECT_EQ(shared.builds(), 25u);
}

}  // namespace
}  // namespace amb

