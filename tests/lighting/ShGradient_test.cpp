// ShGradient_test.cpp — the translational SH gradient from a capture's distances
// (lighting/ShGradient.h) on scenes whose answer is known: what does not change as the probe
// moves along it gives no gradient, and a lit sphere approached gives its closed form.
#include "lighting/ShGradient.h"

#include <cmath>
#include <functional>
#include <limits>
#include <utility>

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include "lighting/CubeMapProjector.h"
#include "world/Conventions.h"

namespace amb {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A cube of N^2 faces from a scene: for a unit direction, the distance to what it sees
// (infinite: sky) and that surface's radiance (grey).
struct Seen {
    double distance_m, radiance;
};
void cubeOf(int n, const std::function<Seen(const glm::dvec3&)>& scene, std::vector<float>& rgb,
            std::vector<float>& distance) {
    rgb.assign(std::size_t(18) * n * n, 0.0f);
    distance.assign(std::size_t(6) * n * n, 0.0f);
    for (int f = 0; f < kCubeFaces; ++f)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const std::size_t t = (std::size_t(f) * n + j) * n + i;
                const Seen s = scene(glm::normalize(cubeTexelDirection(f, i, j, n)));
                distance[t] = float(s.distance_m);
                for (int c = 0; c < 3; ++c) rgb[3 * t + c] = float(s.radiance);
            }
}

double largest(const ShRgbD& sh) {
    double m = 0.0;
    for (const auto& c : sh.c) m = std::max(m, std::max({std::fabs(c.x), std::fabs(c.y), std::fabs(c.z)}));
    return m;
}

// The size of a gradient that matters: c_0 of radiance L over half the sphere, per metre at
// distance d (what moving d metres off a half-sphere of that light would change).
double scale(double radiance, double d_m) {
    return radiance * 2.0 * kPi * kShY00 / d_m;
}

TEST(ShGradient, SkyAloneHasNone) {
    std::vector<float> rgb, distance;
    cubeOf(16, [](const glm::dvec3&) { return Seen{kInf, 3.0}; }, rgb, distance);
    const ShGroundGradient g = shGroundGradient(16, rgb, distance);
    EXPECT_EQ(largest(g.dx), 0.0);
    EXPECT_EQ(largest(g.dz), 0.0);
}

// Flat ground of one radiance 2 m below, sky above: moving along the ground changes nothing.
// (Taking every piece to face the probe, instead of its normal from the distances, gives a
// gradient of about a quarter of scale() here.)
TEST(ShGradient, FlatGroundHasNoneAlongIt) {
    for (int n : {16, 64}) {
        std::vector<float> rgb, distance;
        cubeOf(n,
               [](const glm::dvec3& w) {
                   return w.y < 0.0 ? Seen{2.0 / -w.y, 1.0} : Seen{kInf, 0.5};
               },
               rgb, distance);
        const ShGroundGradient g = shGroundGradient(n, rgb, distance);
        EXPECT_LT(largest(g.dx), 0.01 * scale(1.0, 2.0)) << "N = " << n;
        EXPECT_LT(largest(g.dz), 0.01 * scale(1.0, 2.0)) << "N = " << n;
    }
}

// An endless wall 5 m off along +x: walking towards it or along it, it fills the same half of
// the sphere with the same light. Every piece near its horizon is grazing, so the test lowers
// the cosine guard to see the formula itself.
TEST(ShGradient, EndlessWallHasNone) {
    std::vector<float> rgb, distance;
    const int n = 64;
    cubeOf(n,
           [](const glm::dvec3& w) { return w.x > 0.0 ? Seen{5.0 / w.x, 1.0} : Seen{kInf, 0.0}; },
           rgb, distance);
    ShGradientOptions options;
    options.minCosine = 1e-3;
    const ShGroundGradient g = shGroundGradient(n, rgb, distance, options);
    EXPECT_LT(largest(g.dx), 0.03 * scale(1.0, 5.0));
    EXPECT_LT(largest(g.dz), 0.01 * scale(1.0, 5.0));
}

// A sphere of radius R and radiance L whose centre is D away along +x: c_0 = L Y00 2 pi (1 -
// sqrt(1 - R^2 / D^2)), so approaching it (D falls as x rises) d c_0 / dx =
// L Y00 2 pi (R^2 / D^3) / sqrt(1 - R^2 / D^2); along z, nothing. The texels on the outline,
// part sphere and part sky, count whole: the estimate is 12 % high at 32^2, 10 % at 64^2, 6 % at
// 128^2 and 5 % at 256^2 (measured here).
TEST(ShGradient, ApproachedSphereMatchesClosedForm) {
    const double R = 3.0, D = 6.0, L = 2.0;
    const double expected = L * kShY00 * 2.0 * kPi * (R * R / (D * D * D)) /
                            std::sqrt(1.0 - R * R / (D * D));
    for (const auto& [n, tolerance] : {std::pair{32, 0.15}, std::pair{256, 0.06}}) {
        std::vector<float> rgb, distance;
        cubeOf(n,
               [&](const glm::dvec3& w) {
                   // |t w - c|^2 = R^2 with c = (D, 0, 0): t = D w.x - sqrt(...)
                   const double b = D * w.x, disc = b * b - (D * D - R * R);
                   if (disc < 0.0 || b <= 0.0) return Seen{kInf, 0.0};
                   return Seen{b - std::sqrt(disc), L};
               },
               rgb, distance);
        ShGradientOptions options;
        options.minCosine = 0.05;
        const ShGroundGradient g = shGroundGradient(n, rgb, distance, options);
        EXPECT_NEAR(g.dx.c[0].x, expected, tolerance * expected) << "N = " << n;
        EXPECT_LT(std::fabs(g.dz.c[0].x), 1e-3 * expected) << "N = " << n;
        // The sphere's light moves towards +x as it is approached only in size, not direction:
        // the x band-1 coefficient grows, the z one stays.
        EXPECT_GT(g.dx.c[3].x, 0.0) << "N = " << n;
        EXPECT_LT(std::fabs(g.dz.c[3].x), 1e-3 * expected) << "N = " << n;
    }
}

// Bad texels (NaN colour, negative distance) count as sky: the gradient stays finite and is
// that of the scene without them.
TEST(ShGradient, BadTexelsAreSky) {
    std::vector<float> rgb, distance;
    const int n = 16;
    cubeOf(n, [](const glm::dvec3& w) { return w.y < 0.0 ? Seen{2.0 / -w.y, 1.0} : Seen{kInf, 0.5}; },
           rgb, distance);
    const ShGroundGradient clean = shGroundGradient(n, rgb, distance);
    // Spoil texels of the sky: a NaN colour where the distance is infinite changes nothing.
    rgb[3 * (2 * n * n + 5)] = std::numeric_limits<float>::quiet_NaN();
    distance[2 * n * n + 6] = -1.0f;
    const ShGroundGradient spoiled = shGroundGradient(n, rgb, distance);
    for (int k = 0; k < kShCoefficients; ++k) {
        EXPECT_EQ(spoiled.dx.c[k], clean.dx.c[k]);
        EXPECT_EQ(spoiled.dz.c[k], clean.dz.c[k]);
    }
    // A NaN on the ground: finite.
    rgb[3 * (3 * n * n + 7)] = std::numeric_limits<float>::quiet_NaN();
    const ShGroundGradient ground = shGroundGradient(n, rgb, distance);
    EXPECT_TRUE(std::isfinite(largest(ground.dx)) && std::isfinite(largest(ground.dz)));
}

}  // namespace
}  // namespace amb
