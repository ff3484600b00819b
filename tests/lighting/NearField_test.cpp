// NearField_test.cpp — the near field's closed forms (lighting/NearField.h) against quadrature and
// against a captured cube: a cap's SH, one sphere in a constant sky (its SH and its light term),
// a sphere ray-traced into a cube map and projected as captures are, and overlapping caps
// (never darker twice, never negative irradiance).
#include "lighting/NearField.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lighting/CubeMapProjector.h"
#include "lighting/Metrics.h"
#include "FixedLightScene.h"
#include "world/Conventions.h"

namespace amb {
namespace {

// Midpoint quadrature over (cos theta, phi) about +Y: equal-area cells, `n` x 2n of them.
template <class F>
std::array<glm::dvec3, kShCoefficients> project(int n, F radiance) {
    std::array<glm::dvec3, kShCoefficients> sh{};
    const double cellArea = (2.0 / n) * (kPi / n);
    for (int a = 0; a < n; ++a) {
        const double y = -1.0 + (a + 0.5) * 2.0 / n;
        const double r = std::sqrt(1.0 - y * y);
        for (int b = 0; b < 2 * n; ++b) {
            const double phi = (b + 0.5) * kPi / n;
            const glm::dvec3 dir(r * std::cos(phi), y, r * std::sin(phi));
            const glm::dvec3 L = radiance(dir);
            const auto basis = shBasis(dir);
            for (int k = 0; k < kShCoefficients; ++k) sh[k] += L * basis[k] * cellArea;
        }
    }
    return sh;
}

ShRgbD constantSky(const glm::dvec3& radiance) {
    ShRgbD sh;
    sh.c[0] = radiance * (2.0 * std::sqrt(kPi));
    return sh;
}

// The unit vector from spherical angles.
glm::dvec3 unit(double theta, double phi) {
    return {std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)};
}

TEST(NearField, CapShMatchesQuadratureOfTheIndicator) {
    for (double t : {0.05, 0.4, 1.0, 1.5, 2.5}) {
        const glm::dvec3 d = unit(0.7, 2.1);
        const auto closed = capSh(d, std::cos(t));
        const auto q = project(800, [&](const glm::dvec3& w) {
            return glm::dvec3(glm::dot(w, d) >= std::cos(t) ? 1.0 : 0.0);
        });
        for (int k = 0; k < kShCoefficients; ++k)
            EXPECT_NEAR(closed[k], q[k].x, 2e-3) << "half-angle " << t << ", k " << k;
        // Solid angle: C_0 / Y_00.
        EXPECT_NEAR(closed[0] / kShY00, 2.0 * kPi * (1.0 - std::cos(t)), 1e-12);
    }
}

TEST(NearField, OneSphereInAConstantSkyMatchesQuadrature) {
    // A grey sphere of albedo rho in a constant sky L_s: by the model it shows rho L_s (its
    // visible disc's mean irradiance is pi L_s) where it hides L_s.
    const glm::dvec3 sky(1.0, 0.8, 0.6), rho(0.3, 0.2, 0.1);
    const glm::dvec3 point(0.0), centre(3.0, 4.0, -2.0);
    const double radius = 2.0;
    const SphereOccluder sphere{centre, radius, rho};
    DirectionalLight dark;
    dark.irradiance = glm::dvec3(0.0);
    const ShRgbD got = applyNearField(constantSky(sky), point, {sphere}, dark);

    const glm::dvec3 d = glm::normalize(centre - point);
    const double cosT = std::sqrt(1.0 - radius * radius / glm::dot(centre, centre));
    const auto q = project(1000, [&](const glm::dvec3& w) {
        return glm::dot(w, d) >= cosT ? rho * sky : sky;
    });
    ShRgbD expected;
    for (int k = 0; k < kShCoefficients; ++k) expected.c[k] = q[k];
    for (int k = 0; k < kShCoefficients; ++k)
        for (int ch = 0; ch < 3; ++ch)
            EXPECT_NEAR(got.c[k][ch], expected.c[k][ch], 2e-3) << "k " << k << " ch " << ch;
    // And as irradiance over the sphere of normals.
    EXPECT_LT(irradianceDistance(toFloat(got), toFloat(expected)) / irradianceNorm(toFloat(expected)),
              1e-3);
}

TEST(NearField, TheLightTermIsALambertSpheresMeanRadiance) {
    // A small far sphere lit by a light at phase angle alpha: the mean of rho/pi E max(0, n.l)
    // over its visible disc (by quadrature over the disc) is what the model shows, to the order-2
    // truncation of the phase law in the light's direction.
    const glm::dvec3 rho(0.5);
    for (double alpha : {0.0, 0.6, 1.4, 2.2, 3.0}) {
        const glm::dvec3 d(0.0, 0.0, 1.0);  // point -> sphere
        const glm::dvec3 toViewer = -d;
        const glm::dvec3 light = glm::normalize(std::cos(alpha) * toViewer +
                                                std::sin(alpha) * glm::dvec3(1.0, 0.0, 0.0));
        // Disc quadrature: normals n = (x, y, -sqrt(1 - x^2 - y^2)) facing the viewer.
        double sum = 0.0, count = 0.0;
        const int n = 600;
        for (int a = 0; a < n; ++a)
            for (int b = 0; b < n; ++b) {
                const double x = -1.0 + (a + 0.5) * 2.0 / n, y = -1.0 + (b + 0.5) * 2.0 / n;
                if (x * x + y * y >= 1.0) continue;
                const glm::dvec3 normal(x, y, -std::sqrt(1.0 - x * x - y * y));
                sum += std::max(0.0, glm::dot(normal, light));
                count += 1.0;
            }
        const double discMean = 0.5 / kPi * sum / count;  // rho / pi x E=1 x mean cos
        DirectionalLight sun;
        sun.direction = light;
        sun.irradiance = glm::dvec3(1.0);
        const ShRgbD none;  // a black far field: only the light term remains
        const ShRgbD got = applyNearField(none, glm::dvec3(0.0), {{d * 1000.0, 20.0, rho}}, sun);
        const double omega = 2.0 * kPi * (1.0 - std::sqrt(1.0 - 400.0 / 1e6));
        // The law is kept to order 2 in the light's direction: within 1 % of its full-phase
        // value (2/3) rho / pi (0.78 % by quadrature of the truncation).
        EXPECT_NEAR(got.c[0].x / kShY00 / omega, discMean, 0.01 * (2.0 / 3.0) * 0.5 / kPi)
            << "phase " << alpha;
    }
}

TEST(NearField, ACapturedCubeWithOneSphereMatchesTheAnalyticResult) {
    // A cube map as a capture sees it: a constant sky and one Lambertian sphere lit by that sky
    // and a light, every texel ray-traced; projected as captures are.
    const glm::dvec3 sky(0.6, 0.7, 1.0), rho(0.35, 0.3, 0.2);
    const glm::dvec3 centre(2.0, 3.0, 1.5);
    const double radius = 1.8;
    DirectionalLight sun;
    sun.direction = glm::normalize(glm::dvec3(0.3, 0.8, -0.5));
    sun.irradiance = glm::dvec3(4.0, 3.8, 3.5);
    const int n = 96;
    std::vector<float> cube(6 * n * n * 3);
    for (int f = 0; f < 6; ++f)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const glm::dvec3 w = glm::normalize(cubeTexelDirection(f, i, j, n));
                glm::dvec3 L = sky;
                // Ray from the origin: |t w - c|^2 = r^2.
                const double b = glm::dot(w, centre);
                const double disc = b * b - glm::dot(centre, centre) + radius * radius;
                if (disc >= 0.0 && b > 0.0) {
                    const glm::dvec3 hit = (b - std::sqrt(disc)) * w;
                    const glm::dvec3 normal = glm::normalize(hit - centre);
                    // Lit by the whole constant sky (E = pi L_s) and the light.
                    L = rho / kPi *
                        (kPi * sky + sun.irradiance * std::max(0.0, glm::dot(normal, sun.direction)));
                }
                for (int c = 0; c < 3; ++c) cube[(size_t(f) * n * n + size_t(j) * n + i) * 3 + c] = float(L[c]);
            }
    CubeMapProjector::Options keepAll;
    keepAll.sunThreshold = std::numeric_limits<double>::infinity();
    const ShRgb captured = toFloat(projectCubeMap(n, cube, keepAll).sh);
    const ShRgb analytic =
        toFloat(applyNearField(constantSky(sky), glm::dvec3(0.0), {{centre, radius, rho}}, sun));
    const double rel = irradianceDistance(analytic, captured) / irradianceNorm(captured);
    EXPECT_LT(rel, 0.01);
    // The sphere matters: the sky alone is further off than the tolerance.
    EXPECT_GT(irradianceDistance(toFloat(constantSky(sky)), captured) / irradianceNorm(captured),
              5.0 * rel);
}

TEST(NearField, CoincidentOccludersDarkenOnce) {
    const ShRgbD far = constantSky(glm::dvec3(1.0));
    DirectionalLight sun;
    sun.irradiance = glm::dvec3(2.0);
    const SphereOccluder s{{0.0, 3.0, 1.0}, 1.5, glm::dvec3(0.1)};
    const ShRgbD one = applyNearField(far, glm::dvec3(0.0), {s}, sun);
    const ShRgbD three = applyNearField(far, glm::dvec3(0.0), {s, s, s}, sun);
    for (int k = 0; k < kShCoefficients; ++k)
        EXPECT_NEAR(glm::length(one.c[k] - three.c[k]), 0.0, 1e-9) << "k " << k;
    // A small sphere inside a large one's cap adds nothing.
    const SphereOccluder inner{{0.0, 3.0, 1.0}, 0.4, glm::dvec3(0.9)};
    const ShRgbD both = applyNearField(far, glm::dvec3(0.0), {s, inner}, sun);
    for (int k = 0; k < kShCoefficients; ++k)
        EXPECT_NEAR(glm::length(one.c[k] - both.c[k]), 0.0, 1e-9) << "k " << k;
}

TEST(NearField, OverlappingCapsNeverGiveNegativeIrradiance) {
    // Dense clusters of black and bright spheres around the point, some holding it, over a
    // constant sky and over a sky-and-ground field: the irradiance stays >= 0 for every normal
    // (the far fields' own minima are >= 0), and a black cluster never brightens the mean.
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    ShRgbD skyGround;  // bright above, dim below: L = 1 + 0.8 y
    skyGround.c[0] = glm::dvec3(2.0 * std::sqrt(kPi));
    skyGround.c[2] = glm::dvec3(0.8 * std::sqrt(4.0 * kPi / 3.0));
    const ShRgbD skies[2] = {constantSky(glm::dvec3(1.0)), skyGround};
    int guardedCases = 0;
    for (int trial = 0; trial < 300; ++trial) {
        const ShRgbD& far = skies[trial % 2];
        ASSERT_GE(shMinIrradiance(far).x, -1e-12);
        std::vector<SphereOccluder> occ;
        const int count = 2 + int(u(rng) * 40);
        const glm::dvec3 clusterAt = unit(u(rng) * kPi, u(rng) * 2 * kPi) * (0.5 + 4.0 * u(rng));
        const bool black = trial % 3 == 0;
        for (int i = 0; i < count; ++i) {
            const glm::dvec3 jitter(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
            occ.push_back({clusterAt + 4.0 * jitter, 0.3 + 2.5 * u(rng),
                           black ? glm::dvec3(0.0) : glm::dvec3(u(rng), u(rng), u(rng))});
        }
        DirectionalLight sun;
        sun.direction = unit(u(rng) * kPi, u(rng) * 2 * kPi);
        sun.irradiance = glm::dvec3(black ? 0.0 : 5.0 * u(rng));
        const ShRgbD got = applyNearField(far, glm::dvec3(0.0), occ, sun);
        const glm::dvec3 m = shMinIrradiance(got);
        EXPECT_GE(std::min({m.x, m.y, m.z}), -1e-9) << "trial " << trial;
        if (black) {
            EXPECT_LE(got.c[0].x, far.c[0].x + 1e-12) << "trial " << trial;
        }
        // Count the cases the guard had to scale (what the caps hide alone would go negative).
        const NearFieldTransfer t = nearFieldTransfer(occluderCaps(glm::dvec3(0.0), occ));
        ShRgbD raw = far;
        for (int j = 0; j < kShCoefficients; ++j)
            for (int k = 0; k < kShCoefficients; ++k)
                raw.c[j] += double(t.hide[j * kShCoefficients + k]) * far.c[k];
        const glm::dvec3 rawMin = shMinIrradiance(raw);
        if (std::min({rawMin.x, rawMin.y, rawMin.z}) < -1e-9) ++guardedCases;
    }
    ::testing::Test::RecordProperty("guarded", guardedCases);
}

// Flat ground 2 m below the origin under one light and a hemisphere ambient, no plants of its
// own (the through-normal test's ground).
struct GroundBelow final : NearFieldScene {
    void occludersNear(const glm::dvec3&, double, double, std::vector<SphereOccluder>&) const override {}
    DirectionalLight mainLight(double) const override { return {}; }
    HemisphereAmbient ambient(double) const override {
        return {glm::dvec3(1.0, 1.1, 1.3), glm::dvec3(0.3, 0.3, 0.2)};
    }
    double groundHeight(double, double) const override { return -2.0; }
    bool groundAt(double x, double, GroundPoint& out, const GroundPoint*) const override {
        out.height_m = -2.0;
        out.normal = {0.0, 1.0, 0.0};
        out.albedo = glm::dvec3(0.2 + 0.1 * std::sin(x), 0.3, 0.1);
        return true;
    }
};

TEST(NearField, ThroughOneNormalEqualsTheShPathAndStaysNonNegative) {
    // The draw's path (the transfer seen through the point's normal) against the SH path
    // evaluated at that normal: equal (float rounding, 1e-4 of the far irradiance) wherever the
    // SH path's guard left the hidden part whole; where the caps would take the irradiance at
    // the normal below zero, >= 0 and never above what the caps alone would give unhidden.
    // Every other trial has a ground 2 m below, lit by the light and the ambient.
    const GroundBelow scene;
    const HemisphereAmbient ambient = scene.ambient(12.0);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    ShRgbD skyGround;
    skyGround.c[0] = glm::dvec3(2.0 * std::sqrt(kPi), 1.8 * std::sqrt(kPi), 1.5 * std::sqrt(kPi));
    skyGround.c[2] = glm::dvec3(0.8 * std::sqrt(4.0 * kPi / 3.0));
    int compared = 0, guarded = 0;
    for (int trial = 0; trial < 300; ++trial) {
        std::vector<SphereOccluder> occ;
        const int count = 1 + int(u(rng) * 30);
        const glm::dvec3 at = unit(u(rng) * kPi, u(rng) * 2 * kPi) * (1.0 + 6.0 * u(rng));
        for (int i = 0; i < count; ++i) {
            const glm::dvec3 jitter(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
            occ.push_back({at + 4.0 * jitter, 0.3 + 2.0 * u(rng),
                           trial % 4 == 0 ? glm::dvec3(0.0) : glm::dvec3(u(rng), u(rng), u(rng))});
        }
        DirectionalLight sun;
        sun.direction = unit(u(rng) * 0.5 * kPi, u(rng) * 2 * kPi);
        sun.irradiance = glm::dvec3(4.0 * u(rng));
        const glm::dvec3 n = unit(u(rng) * 0.6 * kPi, u(rng) * 2 * kPi);
        const GroundTerm ground =
            trial % 2 ? groundTerm(glm::dvec3(0.0), scene, occ, occ, 16.0, sun.direction) : GroundTerm{};
        NearFieldTransfer t = nearFieldTransfer(occluderCaps(glm::dvec3(0.0), occ), &ground);
        updateLightTerm(t, sun.direction, ambient);
        NormalTransfer nt = normalTransfer(&t, n);
        updateLightTerm(nt, sun.direction, ambient, 1);
        const ShRgb far = toFloat(skyGround);
        const glm::vec3 got = applyNormalTransfer(normalApply(nt, n), far, glm::vec3(n), sun);
        EXPECT_GE(std::min({got.x, got.y, got.z}), 0.0f) << "trial " << trial;
        const glm::vec3 farE = shIrradiance(far, glm::vec3(n));
        const ShRgb viaSh = applyTransfer(t, far, sun);
        if (t.guardScale == glm::dvec3(1.0)) {
            const glm::vec3 want = glm::max(shIrradiance(viaSh, glm::vec3(n)), glm::vec3(0.0f));
            for (int ch = 0; ch < 3; ++ch)
                EXPECT_NEAR(got[ch], want[ch], 1e-4f * farE[ch]) << "trial " << trial;
            ++compared;
        } else {
            ++guarded;
        }
    }
    // Both branches are exercised (about 180 compared, 120 guarded with this seed).
    EXPECT_GT(compared, 150);
    EXPECT_GT(guarded, 50);
}

using testing_support::FixedLightScene;  // the cache tests add their plants

TEST(NearField, CachedBatchesEqualUncachedWhateverTheOrder) {
    // A scene of a few plants; the same points asked as batches in changing orders (points
    // dropped, added, moved) answer exactly what a fresh NearField answers for each point.
    struct Scene final : FixedLightScene {
        void occludersNear(const glm::dvec3& p, double radius_m, double,
                           std::vector<SphereOccluder>& out) const override {
            for (int i = 0; i < 6; ++i) {
                const glm::dvec3 c(8.0 * i - 20.0, 6.0, 3.0 * (i % 3) - 3.0);
                if (std::hypot(c.x - p.x, c.z - p.z) < radius_m)
                    out.push_back({c, 2.5, glm::dvec3(0.2, 0.4, 0.1)});
            }
        }
    } scene;
    NearFieldSettings settings;
    settings.cacheEntries = 50;  // forces the cache to empty mid-batch
    NearField cached(scene, settings);
    cached.setTimeOfDay(12.0);
    std::vector<glm::dvec3> points, normals;
    for (int i = 0; i < 40; ++i) {
        points.push_back(glm::dvec3(2.0 * i - 40.0, 2.0, 0.5 * (i % 5)));
        normals.push_back(glm::normalize(glm::dvec3(0.1 * (i % 3), 1.0, -0.05 * (i % 4))));
    }
    const ShRgb far = toFloat(constantSky(glm::dvec3(1.0, 0.9, 0.8)));
    std::mt19937 rng(3);
    for (int round = 0; round < 12; ++round) {
        std::vector<std::size_t> order;
        for (std::size_t i = 0; i < points.size(); ++i)
            if (rng() % 5 != 0) order.push_back(i);
        if (round % 3 == 2) std::shuffle(order.begin(), order.end(), rng);
        std::vector<glm::dvec3> p, n;
        for (std::size_t i : order) p.push_back(points[i]), n.push_back(normals[i]);
        std::vector<ShRgb> farAll(p.size(), far);
        std::vector<glm::vec3> got(p.size());
        cached.irradianceMany(p.size(), farAll.data(), p.data(), n.data(), got.data());
        for (std::size_t i = 0; i < p.size(); ++i) {
            NearField fresh(scene, settings);
            fresh.setTimeOfDay(12.0);
            glm::vec3 want;
            fresh.irradianceMany(1, &far, &p[i], &n[i], &want);
            EXPECT_EQ(got[i], want) << "round " << round << " point " << order[i];
        }
    }
}

TEST(NearField, AFullCacheKeepsThePointsInUse) {
    // A view of 24 corners and 24 objects asked every frame, and 8 of each new every frame (an
    // edge moving on), through caches of 64 entries: the caches overflow every few frames, and
    // only the new points are ever built after the first frame (emptying the caches instead
    // would build the whole view again). At the end the view answers what a fresh NearField
    // answers, exactly.
    struct Scene final : FixedLightScene {
        void occludersNear(const glm::dvec3& p, double radius_m, double,
                           std::vector<SphereOccluder>& out) const override {
            for (int i = -30; i <= 30; ++i) {
                const glm::dvec3 c(9.0 * i, 5.0, 4.0 * (i % 3));
                if (std::hypot(c.x - p.x, c.z - p.z) < radius_m)
                    out.push_back({c, 2.0, glm::dvec3(0.2, 0.4, 0.1)});
            }
        }
        bool groundAt(double x, double, GroundPoint& out, const GroundPoint*) const override {
            out.height_m = 0.0, out.normal = {0.0, 1.0, 0.0};
            out.albedo = glm::dvec3(0.1 + 0.2 * (std::fmod(std::abs(x), 7.0) > 3.5));
            return true;
        }
    } scene;
    NearFieldSettings settings;
    settings.cacheEntries = 64;
    NearField cached(scene, settings);
    cached.setTimeOfDay(12.0);
    const ShRgb far = toFloat(constantSky(glm::dvec3(1.0, 0.9, 0.8)));
    std::vector<glm::dvec3> view, normals;
    for (int i = 0; i < 24; ++i) {
        view.push_back(glm::dvec3(3.0 * i - 36.0, 2.0, 1.5 * (i % 4)));
        normals.push_back(glm::normalize(glm::dvec3(0.05 * (i % 3), 1.0, 0.0)));
    }
    const auto frame = [&](const NearField& near, int f, std::vector<glm::vec3>& corners,
                           std::vector<ShRgb>& objects) {
        std::vector<glm::dvec3> points = view, n = normals;
        for (int k = 0; k < 8; ++k) {
            points.push_back(glm::dvec3(40.0 + 8.0 * f + k, 2.0, -3.0)), n.push_back(normals[0]);
        }
        std::vector<ShRgb> fars(points.size(), far);
        corners.resize(points.size());
        near.irradianceMany(points.size(), fars.data(), points.data(), n.data(), corners.data());
        objects.clear();
        for (const glm::dvec3& p : points)
            objects.push_back(near.apply(far, p + glm::dvec3(0.0, 0.5, 0.0), 0.05));
    };
    std::vector<glm::vec3> corners;
    std::vector<ShRgb> objects;
    int overflowed = 0;
    std::size_t before = 0;
    for (int f = 0; f < 40; ++f) {
        cached.resetCounters();
        frame(cached, f, corners, objects);
        if (f > 0) {
            EXPECT_EQ(cached.builds(), 16u) << "frame " << f;
        }
        if (cached.cachedPoints() < before) ++overflowed;
        before = cached.cachedPoints();
        EXPECT_LE(cached.cachedPoints(), 3u * 64u);
    }
    EXPECT_GE(overflowed, 5);
    NearField fresh(scene, settings);
    fresh.setTimeOfDay(12.0);
    std::vector<glm::vec3> freshCorners;
    std::vector<ShRgb> freshObjects;
    frame(fresh, 39, freshCorners, freshObjects);
    for (std::size_t i = 0; i < corners.size(); ++i) {
        EXPECT_EQ(corners[i], freshCorners[i]) << "corner " << i;
        for (int k = 0; k < kShCoefficients; ++k)
            EXPECT_EQ(objects[i].c[k], freshObjects[i].c[k]) << "object " << i << " k " << k;
    }
}

TEST(NearField, ALargeBatchAnswersAsPointByPoint) {
    // A frame's worth of corners (sums on several threads) against the same points asked one by
    // one of a fresh NearField: equal exactly.
    struct Scene final : FixedLightScene {
        void occludersNear(const glm::dvec3& p, double radius_m, double,
                           std::vector<SphereOccluder>& out) const override {
            for (int i = -6; i <= 6; ++i)
                for (int k = -6; k <= 6; ++k) {
                    const glm::dvec3 c(11.0 * i, 5.0, 9.0 * k + 2.0 * (i % 2));
                    if (std::hypot(c.x - p.x, c.z - p.z) < radius_m)
                        out.push_back({c, 2.0 + 0.1 * ((i + k) % 3), glm::dvec3(0.2, 0.4, 0.1)});
                }
        }
    } scene;
    const NearFieldSettings settings;
    NearField batch(scene, settings), single(scene, settings);
    batch.setTimeOfDay(12.0), single.setTimeOfDay(12.0);
    std::vector<glm::dvec3> points, normals;
    std::vector<ShRgb> fars;
    for (int i = 0; i < 80; ++i)
        for (int k = 0; k < 64; ++k) {
            points.push_back(glm::dvec3(1.5 * i - 60.0, 2.0, 1.5 * k - 48.0));
            normals.push_back(glm::normalize(glm::dvec3(0.02 * (i % 5), 1.0, -0.03 * (k % 4))));
            fars.push_back(toFloat(constantSky(glm::dvec3(1.0 + 0.01 * (i % 7), 0.9, 0.8))));
        }
    std::vector<glm::vec3> got(points.size());
    for (int round = 0; round < 2; ++round)  // built, then cached
        batch.irradianceMany(points.size(), fars.data(), points.data(), normals.data(), got.data());
    for (std::size_t i = 0; i < points.size(); ++i) {
        glm::vec3 want;
        single.irradianceMany(1, &fars[i], &points[i], &normals[i], &want);
        ASSERT_EQ(got[i], want) << "point " << i;
    }
}

TEST(NearField, AnObjectBatchAnswersAsPointByPoint) {
    // New objects asked in one batch (built together, their ground's lattice terms first)
    // against the same objects asked one by one of a fresh NearField: equal exactly, with the
    // ground term on (its lattice shared by neighbours) and plants near.
    struct Scene final : FixedLightScene {
        void occludersNear(const glm::dvec3& p, double radius_m, double,
                           std::vector<SphereOccluder>& out) const override {
            for (int i = -4; i <= 4; ++i) {
                const glm::dvec3 c(7.0 * i, 4.0, 2.0 * (i % 2));
                if (std::hypot(c.x - p.x, c.z - p.z) < radius_m)
                    out.push_back({c, 1.8, glm::dvec3(0.2, 0.4, 0.1)});
            }
        }
        bool groundAt(double x, double, GroundPoint& out, const GroundPoint*) const override {
            out.height_m = 0.0, out.normal = {0.0, 1.0, 0.0};
            out.albedo = glm::dvec3(0.1 + 0.2 * (std::fmod(std::abs(x), 5.0) > 2.5));
            return true;
        }
    } scene;
    const NearFieldSettings settings;
    NearField batch(scene, settings), single(scene, settings);
    batch.setTimeOfDay(12.0), single.setTimeOfDay(12.0);
    const ShRgb far = toFloat(constantSky(glm::dvec3(1.0, 0.9, 0.8)));
    std::vector<double> x, z;
    for (int i = 0; i < 30; ++i) x.push_back(1.3 * i - 19.0), z.push_back(0.7 * (i % 6) - 2.0);
    x.push_back(x[3]), z.push_back(z[3]);  // one object asked twice
    std::vector<ShRgb> got(x.size(), far);
    batch.applyAboveMany(x.size(), got.data(), x.data(), z.data(), 1.0, 0.05);
    EXPECT_EQ(batch.builds(), 30u);
    for (std::size_t i = 0; i < x.size(); ++i) {
        const ShRgb want = single.applyAbove(far, x[i], z[i], 1.0, 0.05);
        for (int k = 0; k < kShCoefficients; ++k)
            ASSERT_EQ(got[i].c[k], want.c[k]) << "object " << i << " k " << k;
    }
    // The near field did something: a plant's neighbour is darker than the sky alone.
    EXPECT_LT(got[0].c[0].x, far.c[0].x);
}

TEST(NearField, RangeWeightFadesOverTheLastQuarter) {
    EXPECT_EQ(rangeWeight(0.0, 100.0), 1.0);
    EXPECT_EQ(rangeWeight(75.0, 100.0), 1.0);
    EXPECT_EQ(rangeWeight(100.0, 100.0), 0.0);
    EXPECT_EQ(rangeWeight(1e9, 100.0), 0.0);
    EXPECT_EQ(rangeWeight(5.0, 0.0), 0.0);
    EXPECT_DOUBLE_EQ(rangeWeight(87.5, 100.0), 0.5);  // smoothstep's middle
    EXPECT_EQ(rangeWeight(std::nan(""), 100.0), 0.0);
    // Monotone, and without a step: neighbouring distances differ by at most the slope's bound
    // (smoothstep's 1.5 over the fade's 25 m).
    double last = 1.0;
    for (double d = 0.0; d <= 110.0; d += 0.01) {
        const double w = rangeWeight(d, 100.0);
        EXPECT_LE(w, last);
        EXPECT_LE(last - w, 1.5 / 25.0 * 0.01 + 1e-12) << d;
        last = w;
    }
}

TEST(NearField, AWeightFadesACornersNearFieldAndZeroAsksNothing) {
    struct Scene final : FixedLightScene {
        void occludersNear(const glm::dvec3& p, double radius_m, double,
                           std::vector<SphereOccluder>& out) const override {
            const glm::dvec3 c(2.0, 5.0, 0.0);
            if (std::hypot(c.x - p.x, c.z - p.z) < radius_m)
                out.push_back({c, 2.5, glm::dvec3(0.2, 0.4, 0.1)});
        }
    } scene;
    const NearFieldSettings settings;
    NearField near(scene, settings);
    near.setTimeOfDay(12.0);
    const ShRgb far = toFloat(constantSky(glm::dvec3(1.0, 0.9, 0.8)));
    const glm::dvec3 p(0.0, 2.0, 0.0), n = glm::normalize(glm::dvec3(0.1, 1.0, 0.0));
    glm::vec3 full, zero, half;
    const double w0 = 0.0, w1 = 1.0, wh = 0.25;
    near.irradianceMany(1, &far, &p, &n, &zero, &w0);
    EXPECT_EQ(near.builds(), 0u);  // weight 0: not asked of the cache
    EXPECT_EQ(near.cachedPoints(), 0u);
    const glm::vec3 farOnly = glm::max(shIrradiance(far, glm::vec3(n)), glm::vec3(0.0f));
    EXPECT_EQ(zero, farOnly);
    near.irradianceMany(1, &far, &p, &n, &full, &w1);
    glm::vec3 unweighted;
    near.irradianceMany(1, &far, &p, &n, &unweighted);
    EXPECT_EQ(full, unweighted);
    EXPECT_LT(full.x, 0.95f * farOnly.x);  // the sphere overhead darkens
    near.irradianceMany(1, &far, &p, &n, &half, &wh);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(half[c], 0.75f * farOnly[c] + 0.25f * full[c], 1e-5f);
    EXPECT_EQ(near.builds(), 1u);
}

TEST(NearField, CapOverlapClosedCases) {
    EXPECT_EQ(capOverlap(0.2, 0.3, 0.6), 0.0);
    EXPECT_NEAR(capOverlap(0.2, 0.5, 0.1), 2.0 * kPi * (1.0 - std::cos(0.2)), 1e-12);
    const double mid = capOverlap(0.3, 0.3, 0.3);
    EXPECT_GT(mid, 0.0);
    EXPECT_LT(mid, 2.0 * kPi * (1.0 - std::cos(0.3)));
    EXPECT_NEAR(lambertSpherePhase(0.0), 1.0, 1e-12);
    EXPECT_NEAR(lambertSpherePhase(kPi), 0.0, 1e-12);
    EXPECT_NEAR(lambertSpherePhase(kPi / 2), 1.0 / kPi, 1e-12);
}


TEST(NearField, BandShMatchesQuadratureAndTheCaps) {
    // A wedge of the horizon by quadrature.
    for (const auto& [p0, p1, e1, e2] : {std::array<double, 4>{0.3, 1.1, -0.2, 0.4},
                                        std::array<double, 4>{5.0, 6.0, 0.1, 1.2},
                                        std::array<double, 4>{2.0, 2.785, -1.0, -0.3}}) {
        const auto closed = bandSh(p0, p1, e1, e2);
        const auto q = project(1200, [&](const glm::dvec3& w) {
            double phi = std::atan2(w.z, w.x);
            if (phi < 0.0) phi += 2.0 * kPi;
            const double e = std::asin(w.y);
            return glm::dvec3(phi >= p0 && phi <= p1 && e >= e1 && e <= e2 ? 1.0 : 0.0);
        });
        for (int k = 0; k < kShCoefficients; ++k)
            EXPECT_NEAR(closed[k], q[k].x, 3e-3) << "band " << p0 << ", k " << k;
    }
    // The whole ring above elevation e is the cap of half-angle pi/2 - e about +Y.
    for (double e : {-0.4, 0.0, 0.7}) {
        const auto ring = bandSh(0.0, 2.0 * kPi, e, 0.5 * kPi);
        const auto cap = capSh({0.0, 1.0, 0.0}, std::cos(0.5 * kPi - e));
        for (int k = 0; k < kShCoefficients; ++k) EXPECT_NEAR(ring[k], cap[k], 1e-12) << k;
    }
}

TEST(NearField, AGullyDarkensAndTakesTheGroundsColour) {
    // A point between two walls rising to 30 degrees on the east and west: less sky, and the
    // walls' colour in its light.
    ShRgbD sky;  // bright above, dim below
    sky.c[0] = glm::dvec3(2.0 * std::sqrt(kPi));
    sky.c[2] = glm::dvec3(0.8 * std::sqrt(4.0 * kPi / 3.0));
    std::vector<HorizonWedge> walls;
    const glm::dvec3 red(0.4, 0.1, 0.05);
    for (double centre : {0.0, kPi}) walls.push_back({centre - 0.6, centre + 0.6, 0.0, 0.52, red});
    for (HorizonWedge& w : walls)
        if (w.azimuth0 < 0.0) w.azimuth0 += 2.0 * kPi, w.azimuth1 += 2.0 * kPi;
    DirectionalLight none;
    none.irradiance = glm::dvec3(0.0);
    const ShRgbD got = applyNearField(sky, glm::dvec3(0.0), {}, none, walls);
    const glm::dvec3 up(0.0, 1.0, 0.0), east(1.0, 0.0, 0.0);
    EXPECT_LT(shIrradiance(got, east).y, 0.9 * shIrradiance(sky, east).y);
    EXPECT_LT(shIrradiance(got, up).y, shIrradiance(sky, up).y);
    // Redder than the sky's grey.
    const glm::dvec3 e = shIrradiance(got, east);
    EXPECT_GT(e.x / e.z, 1.05);
    const glm::dvec3 m = shMinIrradiance(got);
    EXPECT_GE(std::min({m.x, m.y, m.z}), 0.0);
}

// A point seen through its own normal keeps of each band only what rises above its tangent
// plane: with the ground rising 30 degrees towards +x, a band up to 20 degrees that way goes, one
// up to 40 degrees keeps 30..40, and the band the other way (the plane falls) is untouched.
TEST(NearField, ABandBelowTheTangentPlaneIsLeftOut) {
    const double t = 30.0 * kPi / 180.0;
    const glm::dvec3 n(-std::sin(t), std::cos(t), 0.0);  // the ground rises towards +x
    const double deg = kPi / 180.0;
    const auto wedge = [](double phi0, double phi1, double lower, double upper) {
        HorizonWedge w;
        w.azimuth0 = phi0, w.azimuth1 = phi1, w.lower = lower, w.upper = upper;
        return w;
    };
    std::vector<HorizonWedge> h = {wedge(-0.1, 0.1, 0.0, 20.0 * deg),
                                   wedge(-0.1, 0.1, 0.0, 40.0 * deg),
                                   wedge(kPi - 0.1, kPi + 0.1, 0.0, 10.0 * deg)};
    belowTangentPlaneOut(n, h);
    ASSERT_EQ(h.size(), 2u);
    EXPECT_NEAR(h[0].lower, 30.0 * deg, 1e-12);
    EXPECT_NEAR(h[0].upper, 40.0 * deg, 1e-12);
    EXPECT_NEAR(h[1].lower, 0.0, 1e-12);
    EXPECT_NEAR(h[1].upper, 10.0 * deg, 1e-12);
}

}  // namespace
}  // namespace amb
