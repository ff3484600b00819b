// ReferenceIrradiance_test.cpp — the irradiance taken straight from a cube map, and the
// quadrature over the sphere of normals, against closed forms.
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "lighting/Metrics.h"
#include "lighting/ReferenceIrradiance.h"
#include "world/Conventions.h"

namespace amb {
namespace {

constexpr double kPi = 3.14159265358979323846;

glm::dvec3 randomUnit(std::mt19937& rng) {
    std::normal_distribution<double> g;
    return glm::normalize(glm::dvec3(g(rng), g(rng), g(rng)));
}

std::vector<float> constantCube(int n, glm::vec3 L) {
    std::vector<float> rgb(std::size_t(kCubeFaces) * n * n * 3);
    for (std::size_t t = 0; t < rgb.size() / 3; ++t)
        rgb[3 * t] = L.x, rgb[3 * t + 1] = L.y, rgb[3 * t + 2] = L.z;
    return rgb;
}

// A constant environment L gives E = pi L at every normal, exactly (each texel's cosine
// integral is exact, the horizon-clipped ones included), for any face size.
TEST(ReferenceIrradiance, ConstantEnvironmentIsExact) {
    std::mt19937 rng(7);
    for (int n : {1, 2, 3, 16, 64}) {
        const CubeIrradiance cube(n, constantCube(n, {1.0f, 0.5f, 2.0f}));
        for (int k = 0; k < 40; ++k) {
            const glm::dvec3 normal = k == 0 ? glm::dvec3(0, 1, 0) : randomUnit(rng);
            const glm::dvec3 e = cube.at(normal);
            EXPECT_NEAR(e.x, kPi * 1.0, 1e-10) << "n=" << n;
            EXPECT_NEAR(e.y, kPi * 0.5, 1e-10) << "n=" << n;
            EXPECT_NEAR(e.z, kPi * 2.0, 1e-10) << "n=" << n;
        }
    }
}

// Only the +Y face lit with L = 1, seen by the upward normal: the form factor of a 2 x 2 square
// at unit distance, centred above the point, is (4 / pi) (1 / sqrt 2) atan(1 / sqrt 2), so
// E = 2 sqrt(2) atan(1 / sqrt(2)) = 1.740830...; each side face then gives (pi - E) / 4.
TEST(ReferenceIrradiance, OneFaceMatchesTheSquareFormFactor) {
    const double top = 2.0 * std::sqrt(2.0) * std::atan(1.0 / std::sqrt(2.0));
    for (int n : {1, 4, 32}) {
        for (int lit = 0; lit < kCubeFaces; ++lit) {
            std::vector<float> rgb(std::size_t(kCubeFaces) * n * n * 3, 0.0f);
            for (std::size_t t = std::size_t(lit) * n * n; t < std::size_t(lit + 1) * n * n; ++t)
                rgb[3 * t] = rgb[3 * t + 1] = rgb[3 * t + 2] = 1.0f;
            const CubeIrradiance cube(n, rgb);
            const double e = cube.at({0.0, 1.0, 0.0}).y;
            const double expected = lit == int(CubeFace::PosY)   ? top
                                    : lit == int(CubeFace::NegY) ? 0.0
                                                                 : (kPi - top) / 4.0;
            EXPECT_NEAR(e, expected, 1e-10) << "n=" << n << " face " << lit;
        }
    }
}

// The texel integrals over a whole cube add up to the hemisphere's pi at any normal, and a
// texel's integral never exceeds its solid angle.
TEST(ReferenceIrradiance, TexelIntegralsTileTheHemisphere) {
    std::mt19937 rng(3);
    const int n = 5;
    for (int k = 0; k < 20; ++k) {
        const glm::dvec3 normal = randomUnit(rng);
        double sum = 0.0;
        for (int f = 0; f < kCubeFaces; ++f)
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    const double w = texelCosineIntegral(f, i, j, n, normal);
                    EXPECT_GE(w, 0.0);
                    EXPECT_LE(w, 4.0 * kPi / (kCubeFaces * n * n) * 3.0);
                    sum += w;
                }
        EXPECT_NEAR(sum, kPi, 1e-10);
    }
}

// The product rule integrates polynomials up to its degree exactly: 1 -> 4 pi, x^2 -> 4 pi / 3,
// x^2 y^2 -> 4 pi / 15, and odd monomials -> 0.
TEST(ReferenceIrradiance, SphereRuleIsExactToItsDegree) {
    for (int m = 3; m <= 8; ++m) {
        const SphereRule rule = sphereProductRule(m);
        EXPECT_EQ(rule.degree, 2 * m - 1);
        double one = 0, x2 = 0, x2y2 = 0, odd = 0, y4 = 0;
        for (std::size_t k = 0; k < rule.directions.size(); ++k) {
            const glm::dvec3 d = rule.directions[k];
            const double w = rule.weights[k];
            EXPECT_NEAR(glm::length(d), 1.0, 1e-12);
            one += w;
            x2 += w * d.x * d.x;
            x2y2 += w * d.x * d.x * d.y * d.y;
            y4 += w * d.y * d.y * d.y * d.y;
            odd += w * d.x * d.y * d.z;
        }
        EXPECT_NEAR(one, 4 * kPi, 1e-12);
        EXPECT_NEAR(x2, 4 * kPi / 3, 1e-12);
        EXPECT_NEAR(x2y2, 4 * kPi / 15, 1e-12);
        EXPECT_NEAR(y4, 4 * kPi / 5, 1e-12);
        EXPECT_NEAR(odd, 0.0, 1e-12);
    }
}

// On order-2 SH inputs the quadrature equals the closed form of Metrics.h (the squared
// difference is a polynomial of degree 4; the rule of degree 5 is exact for it).
TEST(ReferenceIrradiance, QuadratureEqualsClosedFormOnSh) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (int m : {3, 5}) {
        const SphereRule rule = sphereProductRule(m);
        for (int trial = 0; trial < 50; ++trial) {
            ShRgb a, b;
            for (int k = 0; k < kShCoefficients; ++k)
                for (int c = 0; c < 3; ++c) a.c[k][c] = u(rng), b.c[k][c] = u(rng);
            const double closed = irradianceDistance(a, b);
            const double quad = irradianceDistance(shField(a), shField(b), rule);
            EXPECT_NEAR(quad, closed, 1e-6 * closed) << "m=" << m;
            EXPECT_NEAR(irradianceNorm(shField(a), rule), irradianceNorm(a),
                        1e-6 * irradianceNorm(a));
        }
    }
}

}  // namespace
}  // namespace amb
