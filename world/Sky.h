// Sky.h — sun position from time of day and latitude; analytic HDR sky radiance, day and night.
//
// Axes: +Y up, -Z north, +X east (so +Z is south). Time of day is local apparent solar time
// (12:00 = sun due south or north, no equation of time, no time zone).
//
// Sun: declination from the day of year (Cooper 1969), hour angle 15 deg per hour from noon.
// Sky: Preetham, Shirley and Smits 1999, "A Practical Analytic Model for Daylight" — Perez
//   distribution of luminance Y and chromaticity (x, y) with the paper's turbidity fits,
//   converted xyY -> XYZ -> linear sRGB (D65). Units: luminance in cd/m^2 divided by a luminous
//   efficacy of 100 lm/W, i.e. roughly W sr^-1 m^-2; a clear noon sky zenith is ~50-150 and the
//   sun disc ~10^7, so the sun is ~10^5 x the sky (Sky_test measures sun disc luminance against
//   the zenith luminance).
// Twilight: for sun elevations below kTwilightStart_deg the Preetham sky of the sun at that
//   elevation (same azimuth) is dimmed by a decade every kTwilightDecade_deg of depression and
//   tinted blue (ozone absorption dominates the twilight sky colour).
// Night: a full moon at the antisolar point lights the sky like a sun 1 / kMoonToSun as bright
//   (same Preetham shape, same twilight dimming below the horizon), plus an airglow/starlight
//   floor brighter towards the horizon, so radiance is never zero.
// Below the horizon: the sky is mirrored (radiance(x, -y, z) == radiance(x, y, z)); the ground
//   is the renderer's business.
#pragma once

#include <glm/vec3.hpp>

#include "world/DirectionalLight.h"
#include "world/WorldSettings.h"

namespace amb {


// Everything radiance() needs for one time of day, computed once (cheap per-direction lookups).
struct SkyState {
    double timeOfDay_h = 12.0;
    glm::dvec3 sun{0.0, 1.0, 0.0};         // true sun direction
    glm::dvec3 moon{0.0, -1.0, 0.0};       // true moon direction
    struct Lobe {                          // one Preetham sky lit by a body (sun or moon)
        glm::dvec3 toward{0.0, 1.0, 0.0};  // body direction with elevation raised to >= 2 deg
        double cosThetaBody = 1.0;
        double perez[3][5] = {};  // A..E for Y, x, y
        double zenith[3] = {};    // Y (cd/m^2 * scale), x, y at the zenith over F(0, theta_s)
        glm::dvec3 tint{1.0};     // twilight colour and dimming
        bool active = false;
    } sunLobe, moonLobe;
};

class Sky {
  public:
    static constexpr double kTurbidity = 3.0;           // clear sky
    static constexpr double kLuminousEfficacy = 100.0;  // lm/W: cd/m^2 -> output units
    static constexpr double kTwilightStart_deg = 2.0;
    static constexpr double kTwilightDecade_deg = 2.7;
    static constexpr double kMoonToSun = 4.0e5;  // full moon luminance ratio (~1.6e9/4e3)

    explicit Sky(const WorldSettings& settings, double turbidity = kTurbidity);

    // Unit world direction towards the sun at a time of day in hours [0, 24) (wraps).
    glm::dvec3 sunDirection(double timeOfDay_h) const;
    // Unit world direction towards the (full) moon: the antisolar point.
    glm::dvec3 moonDirection(double timeOfDay_h) const;
    // Sky radiance (linear RGB, W sr^-1 m^-2-like units) arriving from direction `dir` (unit,
    // pointing away from the viewer), without the sun disc. Never exactly zero (night glow).
    glm::vec3 radiance(const glm::dvec3& dir, double timeOfDay_h) const;
    // The same with the per-time work done once: state(t) then radiance(dir, state).
    SkyState state(double timeOfDay_h) const;
    glm::vec3 radiance(const glm::dvec3& dir, const SkyState& state) const;
    // Radiance of the sun disc itself (about 10^5 x the sky at noon); ~0 below the horizon.
    glm::vec3 sunRadiance(double timeOfDay_h) const;
    // Radiance of the moon disc; ~0 below the horizon.
    glm::vec3 moonRadiance(double timeOfDay_h) const;
    // Angular radius of the sun disc (the moon's is taken equal).
    double sunAngularRadius_rad() const;
    // Angular speed of the sun across the sky [rad per hour of day-time]: (pi / 12) cos(decl).
    double sunAngularSpeed_radPerHour() const;

    // Direct light of the sun and of the moon (radiance x disc solid angle).
    DirectionalLight sunLight(double timeOfDay_h) const;
    DirectionalLight moonLight(double timeOfDay_h) const;
    // The dominant direct light: the sun by day, the moon at night (a night-time light for the
    // renderer). Its irradiance is never exactly zero.
    DirectionalLight mainLight(double timeOfDay_h) const;

    double latitude_rad() const { return latitude_rad_; }
    double declination_rad() const { return declination_rad_; }

  private:
    glm::dvec3 bodyDirection(double hourAngle_rad, double declination_rad) const;
    glm::dvec3 diskTransmittance(const glm::dvec3& dir) const;

    double latitude_rad_;
    double declination_rad_;
    double turbidity_;
};

}  // namespace amb
