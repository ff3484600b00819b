// Sky_test.cpp — sun path against closed forms, sky radiance day/twilight/night.
#include "world/Sky.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "world/Conventions.h"

namespace amb {
namespace {

constexpr double kDeg = kPi / 180.0;

Sky makeSky(double latitude_deg, int dayOfYear) {
    WorldSettings s;
    s.latitude_deg = latitude_deg;
    s.dayOfYear = dayOfYear;
    return Sky(s);
}

double elevation_deg(const glm::dvec3& d) {
    return std::asin(d.y) / kDeg;
}

double luminance(const glm::vec3& c) {
    return amb::luminance(glm::dvec3(c));
}

// Time in [lo, hi] where the sun's centre crosses the horizon (one sign change), by bisection.
double horizonCrossing(const Sky& sky, double lo, double hi) {
    const bool riseAtLo = sky.sunDirection(lo).y < 0.0;
    for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (lo + hi);
        ((sky.sunDirection(mid).y < 0.0) == riseAtLo ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

std::vector<glm::dvec3> sphereDirections(int n) {  // Fibonacci sphere plus the poles and horizon
    std::vector<glm::dvec3> dirs = {{0, 1, 0}, {0, -1, 0}, {1, 0, 0}, {0, 0, -1}, {0, 0, 0}};
    const double golden = kPi * (3.0 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {
        const double y = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - y * y);
        dirs.push_back({r * std::cos(golden * i), y, r * std::sin(golden * i)});
    }
    return dirs;
}

TEST(Sky, SolarNoonIsHighestAndDueSouthInTheNorth) {
    const Sky sky = makeSky(45.0, 172);
    const glm::dvec3 noon = sky.sunDirection(12.0);
    EXPECT_NEAR(glm::length(noon), 1.0, 1e-12);
    // Closed form: noon elevation = 90 deg - |latitude - declination|.
    EXPECT_NEAR(elevation_deg(noon), 90.0 - std::abs(45.0 - sky.declination_rad() / kDeg), 1e-9);
    EXPECT_NEAR(sky.declination_rad() / kDeg, 23.44, 0.05);  // June solstice
    EXPECT_NEAR(noon.x, 0.0, 1e-12);                         // no east-west component
    EXPECT_GT(noon.z, 0.0);                                  // +Z is south
    for (double t = 0.0; t < 24.0; t += 0.05)
        EXPECT_LE(sky.sunDirection(t).y, noon.y + 1e-15) << "t = " << t;
    // Morning sun in the east (+X), afternoon in the west.
    EXPECT_GT(sky.sunDirection(9.0).x, 0.0);
    EXPECT_LT(sky.sunDirection(15.0).x, 0.0);
    // Symmetric about noon, and 24 h periodic.
    const glm::dvec3 a = sky.sunDirection(10.0), b = sky.sunDirection(14.0);
    EXPECT_NEAR(a.x, -b.x, 1e-12);
    EXPECT_NEAR(a.y, b.y, 1e-12);
    EXPECT_NEAR(a.z, b.z, 1e-12);
    EXPECT_NEAR(glm::length(sky.sunDirection(-2.0) - sky.sunDirection(22.0)), 0.0, 1e-12);
}

TEST(Sky, SouthernHemisphereNoonSunIsDueNorth) {
    const Sky sky = makeSky(-30.0, 172);
    const glm::dvec3 noon = sky.sunDirection(12.0);
    EXPECT_LT(noon.z, 0.0);
    EXPECT_NEAR(elevation_deg(noon), 90.0 - std::abs(-30.0 - sky.declination_rad() / kDeg), 1e-9);
}

TEST(Sky, SunriseAndSunsetAtTheEquatorOnTheEquinox) {
    const Sky sky = makeSky(0.0, 80);
    EXPECT_NEAR(horizonCrossing(sky, 3.0, 9.0), 6.0, 1.0 / 60.0);
    EXPECT_NEAR(horizonCrossing(sky, 15.0, 21.0), 18.0, 1.0 / 60.0);
}

TEST(Sky, DayLengthAtMidLatitudeSummer) {
    // cos H0 = -tan(latitude) tan(declination): day length 2 H0 / 15 deg per hour.
    const Sky sky = makeSky(45.0, 172);
    const double h0 = std::acos(-std::tan(45.0 * kDeg) * std::tan(sky.declination_rad()));
    const double expected_h = 2.0 * h0 / kDeg / 15.0;
    const double length_h = horizonCrossing(sky, 12.0, 23.0) - horizonCrossing(sky, 1.0, 12.0);
    EXPECT_NEAR(length_h, expected_h, 1e-6);
    EXPECT_NEAR(length_h, 15.4, 0.1);
}

TEST(Sky, AngularSpeedMatchesTheSunPath) {
    const Sky sky = makeSky(52.0, 30);
    const double dt = 1e-4;
    for (double t : {3.0, 8.0, 12.0, 17.5}) {
        const double angle = std::acos(
            std::clamp(glm::dot(sky.sunDirection(t), sky.sunDirection(t + dt)), -1.0, 1.0));
        EXPECT_NEAR(angle / dt, sky.sunAngularSpeed_radPerHour(),
                    1e-4 * sky.sunAngularSpeed_radPerHour());
    }
    EXPECT_NEAR(sky.sunAngularRadius_rad(), 0.2666 * kDeg, 1e-4);
}

TEST(Sky, SunIsAbout1e5TimesTheZenithSkyAtNoon) {
    // Measured as the luminance of the sun disc over the luminance of the sky at the zenith,
    // and over the mean sky radiance over the upper hemisphere (sky irradiance / pi).
    const Sky sky = makeSky(45.0, 172);
    const double sun = luminance(sky.sunRadiance(12.0));
    const double zenith = luminance(sky.radiance({0.0, 1.0, 0.0}, 12.0));
    EXPECT_GT(sun / zenith, 3.0e4);
    EXPECT_LT(sun / zenith, 3.0e5);
    const SkyState state = sky.state(12.0);
    double mean = 0.0;
    int n = 0;
    for (const glm::dvec3& d : sphereDirections(4000))
        if (d.y > 0.0) mean += luminance(sky.radiance(d, state)), ++n;
    mean /= n;
    EXPECT_GT(sun / mean, 3.0e4);
    EXPECT_LT(sun / mean, 3.0e5);
    // Physical scale: ~1000 W/m^2 of direct sun at a high sun, sky zenith of order 10-300.
    const double direct = luminance(sky.sunLight(12.0).irradiance);
    EXPECT_GT(direct, 600.0);
    EXPECT_LT(direct, 1200.0);
    EXPECT_GT(zenith, 10.0);
    EXPECT_LT(zenith, 300.0);
}

TEST(Sky, ClearNoonSkyIsBlueAndBrightestNearTheSun) {
    const Sky sky = makeSky(45.0, 172);
    const glm::vec3 zenith = sky.radiance({0.0, 1.0, 0.0}, 12.0);
    EXPECT_GT(zenith.b, zenith.r);
    const glm::dvec3 sun = sky.sunDirection(12.0);
    const glm::dvec3 nearSun = glm::normalize(sun + glm::dvec3(0.05, 0.0, 0.0));
    const glm::dvec3 away = glm::normalize(glm::dvec3(-sun.x, sun.y, -sun.z));
    EXPECT_GT(luminance(sky.radiance(nearSun, 12.0)), 2.0 * luminance(sky.radiance(away, 12.0)));
}

TEST(Sky, RadianceIsFinitePositiveEverywhereAndMirroredBelowTheHorizon) {
    for (double latitude : {-89.0, -45.0, 0.0, 45.0, 89.9}) {
        const Sky sky = makeSky(latitude, 355);
        for (double t = 0.0; t < 24.0; t += 0.25) {
            const SkyState state = sky.state(t);
            for (const glm::dvec3& d : sphereDirections(300)) {
                const glm::vec3 l = sky.radiance(d, state);
                for (int c = 0; c < 3; ++c) {
                    ASSERT_TRUE(std::isfinite(l[c])) << latitude << " " << t;
                    ASSERT_GT(l[c], 0.0f) << latitude << " " << t;
                }
                const glm::vec3 mirrored = sky.radiance({d.x, -d.y, d.z}, state);
                ASSERT_EQ(l, mirrored);
            }
            const glm::vec3 sun = sky.sunRadiance(t), moon = sky.moonRadiance(t);
            for (int c = 0; c < 3; ++c) {
                ASSERT_TRUE(std::isfinite(sun[c]) && sun[c] >= 0.0f);
                ASSERT_TRUE(std::isfinite(moon[c]) && moon[c] >= 0.0f);
            }
        }
    }
    // Non-finite times and zero-length directions are handled, not propagated.
    const Sky sky = makeSky(45.0, 172);
    EXPECT_TRUE(std::isfinite(sky.radiance({0.0, 0.0, 0.0}, 12.0).g));
    EXPECT_TRUE(std::isfinite(sky.radiance({0.0, 1.0, 0.0}, std::nan("")).g));
}

TEST(Sky, StateOverloadMatchesTheDirectCall) {
    const Sky sky = makeSky(45.0, 172);
    const SkyState state = sky.state(17.3);
    for (const glm::dvec3& d : sphereDirections(50))
        EXPECT_EQ(sky.radiance(d, state), sky.radiance(d, 17.3));
}

TEST(Sky, NightIsDimButNotBlack) {
    const Sky sky = makeSky(45.0, 172);
    ASSERT_LT(sky.sunDirection(0.0).y, -0.3);
    const double noon = luminance(sky.radiance({0.0, 1.0, 0.0}, 12.0));
    const double night = luminance(sky.radiance({0.0, 1.0, 0.0}, 0.0));
    EXPECT_GT(night, 0.0);
    EXPECT_LT(night, 1e-4 * noon);
    // Full-moon sky (~0.01 cd/m^2 = 1e-4 units) is well above the airglow floor (2e-6 units).
    EXPECT_GT(night, 1e-5);
    EXPECT_LT(night, 1e-3);
    // The night-time light is the moon, faint but not zero, and in the sky.
    const DirectionalLight light = sky.mainLight(0.0);
    EXPECT_GT(light.direction.y, 0.0);
    EXPECT_GT(luminance(light.irradiance), 0.0);
    EXPECT_LT(luminance(light.irradiance), 1e-4 * luminance(sky.mainLight(12.0).irradiance));
    EXPECT_GT(sky.mainLight(12.0).direction.y, 0.5);
}

TEST(Sky, TwilightFadesSmoothly) {
    const Sky sky = makeSky(45.0, 172);
    const double sunset = horizonCrossing(sky, 12.0, 23.0);
    // Zenith luminance falls monotonically from 10 deg above to 10 deg below the horizon,
    // without jumps (at most 2 % per 0.001 h step, i.e. 3.6 s).
    double previous = luminance(sky.radiance({0.0, 1.0, 0.0}, sunset - 1.5));
    int steps = 0;
    for (double t = sunset - 1.5; t < sunset + 2.0; t += 0.001) {
        const double e = elevation_deg(sky.sunDirection(t));
        const double l = luminance(sky.radiance({0.0, 1.0, 0.0}, t));
        if (e < 10.0 && e > -10.0) {
            EXPECT_LE(l, previous * (1.0 + 1e-9)) << "elevation " << e;
            ++steps;
        }
        EXPECT_NEAR(l / previous, 1.0, 0.02) << "elevation " << e;
        previous = l;
    }
    EXPECT_GT(steps, 1000);
    // Ten degrees below the horizon the sky is at least 1000x darker than at sunset.
    const double atSunset = luminance(sky.radiance({0.0, 1.0, 0.0}, sunset));
    double t10 = sunset;
    while (elevation_deg(sky.sunDirection(t10)) > -10.0) t10 += 0.001;
    EXPECT_LT(luminance(sky.radiance({0.0, 1.0, 0.0}, t10)), 1e-3 * atSunset);
    // The sun disc is gone once the whole disc is below the horizon.
    double below = sunset;
    while (sky.sunDirection(below).y > -std::sin(sky.sunAngularRadius_rad())) below += 0.0005;
    EXPECT_EQ(luminance(sky.sunRadiance(below + 0.001)), 0.0);
}

}  // namespace
}  // namespace amb
