// SkyGround_test.cpp — the sky over flat ground: straight up sees the sky, straight down the
// albedo x the light on the ground / pi, the horizon belongs to the sky, E_sky(up) does not
// depend on the quadrature.
#include "world/SkyGround.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "world/Conventions.h"
#include "world/Sky.h"

namespace amb {
namespace {

Sky testSky() {
    WorldSettings s;
    s.latitude_deg = 45.0;
    s.dayOfYear = 172;
    return Sky(s);
}

// Midpoint rule in (theta, phi) over the sphere: rows x 2 rows directions.
void sphereQuadrature(int rows, std::vector<glm::dvec3>& dirs, std::vector<double>& omega) {
    const int cols = 2 * rows;
    const double dTheta = kPi / rows, dPhi = 2.0 * kPi / cols;
    for (int r = 0; r < rows; ++r) {
        const double theta = (r + 0.5) * dTheta;
        for (int c = 0; c < cols; ++c) {
            const double phi = (c + 0.5) * dPhi;
            dirs.push_back({std::sin(theta) * std::cos(phi), std::cos(theta),
                            std::sin(theta) * std::sin(phi)});
            omega.push_back(std::sin(theta) * dTheta * dPhi);
        }
    }
}

// Cube-map texels, as the fallback cube map uses them.
void cubeQuadrature(int n, std::vector<glm::dvec3>& dirs, std::vector<double>& omega) {
    for (int f = 0; f < kCubeFaces; ++f) {
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                const glm::dvec3 d = cubeTexelDirection(f, i, j, n);
                const double len2 = glm::dot(d, d);
                dirs.push_back(d / std::sqrt(len2));
                omega.push_back((4.0 / (double(n) * n)) / (len2 * std::sqrt(len2)));
            }
        }
    }
}

glm::dvec3 texel(const std::vector<float>& rgb, std::size_t i) {
    return {rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]};
}

void expectNearRel(const glm::dvec3& a, const glm::dvec3& b, double rel) {
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], rel * std::abs(b[c])) << "channel " << c;
}

// Straight up, straight down and either side of the horizon, appended with zero solid angle so
// they do not change the integrals.
struct Probe {
    std::size_t up, down, horizon, belowHorizon;
};
Probe appendProbes(std::vector<glm::dvec3>& dirs, std::vector<double>& omega) {
    Probe p{};
    auto add = [&](const glm::dvec3& d) {
        dirs.push_back(glm::normalize(d));
        omega.push_back(0.0);
        return dirs.size() - 1;
    };
    p.up = add({0.0, 1.0, 0.0});
    p.down = add({0.0, -1.0, 0.0});
    p.horizon = add({0.6, 0.0, 0.8});
    p.belowHorizon = add({0.6, -1e-9, 0.8});
    return p;
}

TEST(SkyGround, UpSeesSkyDownSeesLitGround) {
    const Sky sky = testSky();
    for (double t_h : {6.5, 9.0, 12.0, 17.0, 0.0}) {
        SCOPED_TRACE(t_h);
        std::vector<glm::dvec3> dirs;
        std::vector<double> omega;
        sphereQuadrature(64, dirs, omega);
        const Probe p = appendProbes(dirs, omega);
        std::vector<float> rgb;
        const SkyGround s = evaluateSkyGround(sky, t_h, dirs, omega, rgb);
        ASSERT_EQ(rgb.size(), dirs.size() * 3);

        // Up: the sky model itself.
        const glm::vec3 zenith = sky.radiance(glm::dvec3(0.0, 1.0, 0.0), t_h);
        EXPECT_EQ(glm::vec3(texel(rgb, p.up)), zenith);

        // Down: albedo / pi x (sky irradiance + sun and moon on the horizontal ground).
        const DirectionalLight sun = sky.sunLight(t_h), moon = sky.moonLight(t_h);
        const glm::dvec3 onGround = s.skyIrradianceUp +
                                    sun.irradiance * std::max(0.0, sun.direction.y) +
                                    moon.irradiance * std::max(0.0, moon.direction.y);
        expectNearRel(s.groundIrradiance, onGround, 1e-12);
        expectNearRel(s.ground, double(kGroundAlbedo) / kPi * onGround, 1e-12);
        expectNearRel(texel(rgb, p.down), s.ground, 1e-6);
        // Every direction below the horizon sees the same ground; above it, never the ground.
        for (std::size_t i = 0; i < dirs.size(); ++i) {
            if (dirs[i].y < 0.0) {
                ASSERT_EQ(texel(rgb, i), texel(rgb, p.down)) << i;
            }
        }
        // The horizon belongs to the sky; just below it is the ground (a step: sky and ground
        // differ there, as they do in the world).
        EXPECT_EQ(glm::vec3(texel(rgb, p.horizon)),
                  sky.radiance(glm::dvec3(0.6, 0.0, 0.8), t_h));
        EXPECT_EQ(texel(rgb, p.belowHorizon), texel(rgb, p.down));

        // E_up = integral of L cos over the upper hemisphere < integral of L = 2 pi x the mean.
        EXPECT_GT(luminance(s.skyIrradianceUp), 0.0);
        EXPECT_LT(luminance(s.skyIrradianceUp), 2.0 * kPi * luminance(s.skyMean));
    }
}

TEST(SkyGround, SunLightsTheGroundByDayOnly) {
    const Sky sky = testSky();
    const SkyGround noon = groundUnder(sky, 12.0, glm::dvec3(10.0));
    const DirectionalLight sun = sky.sunLight(12.0);
    ASSERT_GT(sun.direction.y, 0.5);
    expectNearRel(noon.groundIrradiance, glm::dvec3(10.0) + sun.irradiance * sun.direction.y, 1e-12);
    // At midnight the sun is below the horizon; the (full, antisolar) moon lights the ground.
    const SkyGround night = groundUnder(sky, 0.0, glm::dvec3(0.0));
    const DirectionalLight moon = sky.moonLight(0.0);
    ASSERT_GT(moon.direction.y, 0.0);
    expectNearRel(night.groundIrradiance, moon.irradiance * moon.direction.y, 1e-12);
    EXPECT_LT(luminance(night.groundIrradiance), 1e-4 * luminance(noon.groundIrradiance));
}

// E_sky(up) is an integral: the cube texels of the fallback and a fine (theta, phi) grid agree.
TEST(SkyGround, SkyIrradianceIndependentOfQuadrature) {
    const Sky sky = testSky();
    for (double t_h : {8.0, 12.0}) {
        std::vector<glm::dvec3> dA, dB;
        std::vector<double> wA, wB;
        std::vector<float> rgb;
        sphereQuadrature(256, dA, wA);
        cubeQuadrature(32, dB, wB);
        const SkyGround a = evaluateSkyGround(sky, t_h, dA, wA, rgb);
        const SkyGround b = evaluateSkyGround(sky, t_h, dB, wB, rgb);
        expectNearRel(b.skyIrradianceUp, a.skyIrradianceUp, 0.02);
        expectNearRel(b.ground, a.ground, 0.02);
    }
}

}  // namespace
}  // namespace amb
