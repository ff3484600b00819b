// Sky.cpp — sun and moon positions, Preetham daylight with twilight and night (see Sky.h).
//
// [SECTION] Index
//   Sun and moon positions
//   Preetham lobes (per time) and their evaluation (per direction)
//   Sun and moon discs, direct lights
#include "world/Sky.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "world/Conventions.h"

namespace amb {

namespace {

constexpr double kDeg = kPi / 180.0;
constexpr double kSunAngularRadius_rad = 0.2666 * kDeg;  // mean apparent solar radius
// Extraterrestrial solar luminance ~2.0e9 cd/m^2 (1361 W/m^2 over 6.8e-5 sr at ~98 lm/W).
constexpr double kSunLuminance_cdm2 = 2.0e9;
// Night floor (airglow + starlight), ~2e-4 cd/m^2 at the zenith of a dark site.
constexpr double kNightGlow_cdm2 = 2.0e-4;

double wrapHours(double t_h) {
    if (!std::isfinite(t_h)) return 12.0;
    double t = std::fmod(t_h, 24.0);
    if (t < 0.0) t += 24.0;
    return t;
}

// CIE XYZ -> linear sRGB (D65).
glm::dvec3 xyzToRgb(double X, double Y, double Z) {
    return {3.2404542 * X - 1.5371385 * Y - 0.4985314 * Z,
            -0.9692660 * X + 1.8760108 * Y + 0.0415560 * Z,
            0.0556434 * X - 0.2040259 * Y + 1.0572252 * Z};
}

// Perez et al. sky distribution F(theta, gamma) with coefficients A..E (Preetham 1999, eq. 3).
double perez(const double c[5], double cosTheta, double gamma, double cosGamma) {
    return (1.0 + c[0] * std::exp(c[1] / cosTheta)) *
           (1.0 + c[2] * std::exp(c[3] * gamma) + c[4] * cosGamma * cosGamma);
}

// One Preetham sky lit by a body at `dir` whose brightness is `scale` times the sun's.
SkyState::Lobe makeLobe(const glm::dvec3& dir, double turbidity, double scale) {
    SkyState::Lobe lobe;
    const double elevation_deg = std::asin(std::clamp(dir.y, -1.0, 1.0)) / kDeg;
    if (elevation_deg < -30.0) return lobe;  // dimmed by > 10^-11: nothing left to add
    lobe.active = true;

    // Sky shape of the body at elevation >= kTwilightStart_deg, same azimuth.
    const double e = std::max(elevation_deg, Sky::kTwilightStart_deg) * kDeg;
    glm::dvec2 horizontal(dir.x, dir.z);
    const double hl = glm::length(horizontal);
    horizontal = hl > 1e-12 ? horizontal / hl : glm::dvec2(0.0, 1.0);
    lobe.toward = {horizontal.x * std::cos(e), std::sin(e), horizontal.y * std::cos(e)};
    const double thetaS = 0.5 * kPi - e;
    lobe.cosThetaBody = std::cos(thetaS);

    const double T = turbidity;
    const double coeff[3][5] = {{0.1787 * T - 1.4630, -0.3554 * T + 0.4275, -0.0227 * T + 5.3251,
                                 0.1206 * T - 2.5771, -0.0670 * T + 0.3703},
                                {-0.0193 * T - 0.2592, -0.0665 * T + 0.0008, -0.0004 * T + 0.2125,
                                 -0.0641 * T - 0.8989, -0.0033 * T + 0.0452},
                                {-0.0167 * T - 0.2608, -0.0950 * T + 0.0092, -0.0079 * T + 0.2102,
                                 -0.0441 * T - 1.6537, -0.0109 * T + 0.0529}};
    // Zenith luminance [kcd/m^2] and chromaticity (Preetham 1999, appendix A.2).
    const double chi = (4.0 / 9.0 - T / 120.0) * (kPi - 2.0 * thetaS);
    const double Yz = (4.0453 * T - 4.9710) * std::tan(chi) - 0.2155 * T + 2.4192;
    const double t2 = thetaS * thetaS, t3 = t2 * thetaS, T2 = T * T;
    const double xz = T2 * (0.00166 * t3 - 0.00375 * t2 + 0.00209 * thetaS) +
                      T * (-0.02903 * t3 + 0.06377 * t2 - 0.03202 * thetaS + 0.00394) +
                      (0.11693 * t3 - 0.21196 * t2 + 0.06052 * thetaS + 0.25886);
    const double yz = T2 * (0.00275 * t3 - 0.00610 * t2 + 0.00317 * thetaS) +
                      T * (-0.04214 * t3 + 0.08970 * t2 - 0.04153 * thetaS + 0.00516) +
                      (0.15346 * t3 - 0.26756 * t2 + 0.06670 * thetaS + 0.26688);
    const double zenith[3] = {std::max(Yz, 0.0) * 1000.0 / Sky::kLuminousEfficacy * scale, xz, yz};
    for (int c = 0; c < 3; ++c) {
        for (int k = 0; k < 5; ++k) lobe.perez[c][k] = coeff[c][k];
        // Divide by F(0, theta_s) once here (the zenith normalisation of eq. 3).
        lobe.zenith[c] = zenith[c] / perez(coeff[c], 1.0, thetaS, std::cos(thetaS));
    }

    // Twilight: a decade of dimming every kTwilightDecade_deg below kTwilightStart_deg, and a
    // blue shift (Chappuis ozone absorption) over the first ~8 degrees, luminance-preserving.
    const double depression = Sky::kTwilightStart_deg - elevation_deg;
    if (depression > 0.0) {
        const double dim = std::pow(10.0, -depression / Sky::kTwilightDecade_deg);
        const glm::dvec3 blue(0.45, 0.65, 1.0);
        const double t = std::clamp(depression / 8.0, 0.0, 1.0);
        lobe.tint = dim * glm::mix(glm::dvec3(1.0), blue / luminance(blue), t);
    }
    return lobe;
}

glm::dvec3 evalLobe(const SkyState::Lobe& lobe, const glm::dvec3& d) {
    const double cosTheta = std::max(d.y, 1e-3);
    const double cosGamma = std::clamp(glm::dot(d, lobe.toward), -1.0, 1.0);
    const double gamma = std::acos(cosGamma);
    const double Y = lobe.zenith[0] * perez(lobe.perez[0], cosTheta, gamma, cosGamma);
    const double x = lobe.zenith[1] * perez(lobe.perez[1], cosTheta, gamma, cosGamma);
    const double y =
        std::max(lobe.zenith[2] * perez(lobe.perez[2], cosTheta, gamma, cosGamma), 1e-4);
    const double Yc = std::max(Y, 0.0);
    const glm::dvec3 rgb = xyzToRgb(x / y * Yc, Yc, (1.0 - x - y) / y * Yc);
    return glm::max(rgb, glm::dvec3(0.0)) * lobe.tint;
}

}  // namespace

// ---- Sun and moon positions -----------------------------------------------------------------

Sky::Sky(const WorldSettings& settings, double turbidity)
    : latitude_rad_(std::clamp(settings.latitude_deg, -90.0, 90.0) * kDeg),
      // Cooper (1969): declination = 23.44 deg sin(2 pi (284 + N) / 365).
      declination_rad_(23.44 * kDeg * std::sin(2.0 * kPi * (284.0 + settings.dayOfYear) / 365.0)),
      turbidity_(std::clamp(turbidity, 1.7, 10.0)) {}

glm::dvec3 Sky::bodyDirection(double hourAngle_rad, double declination_rad) const {
    // Horizontal coordinates (east, north, up) of a body at hour angle H and declination d.
    const double sp = std::sin(latitude_rad_), cp = std::cos(latitude_rad_);
    const double sd = std::sin(declination_rad), cd = std::cos(declination_rad);
    const double up = sp * sd + cp * cd * std::cos(hourAngle_rad);
    const double east = -cd * std::sin(hourAngle_rad);
    const double north = cp * sd - sp * cd * std::cos(hourAngle_rad);
    // World axes: +X east, +Y up, -Z north.
    return glm::normalize(glm::dvec3(east, up, -north));
}

glm::dvec3 Sky::sunDirection(double timeOfDay_h) const {
    const double hourAngle = (wrapHours(timeOfDay_h) - 12.0) * (kPi / 12.0);
    return bodyDirection(hourAngle, declination_rad_);
}

glm::dvec3 Sky::moonDirection(double timeOfDay_h) const {
    return -sunDirection(timeOfDay_h);
}

double Sky::sunAngularRadius_rad() const {
    return kSunAngularRadius_rad;
}

double Sky::sunAngularSpeed_radPerHour() const {
    return (kPi / 12.0) * std::cos(declination_rad_);
}

// ---- Sky radiance ---------------------------------------------------------------------------

SkyState Sky::state(double timeOfDay_h) const {
    SkyState s;
    s.timeOfDay_h = wrapHours(timeOfDay_h);
    s.sun = sunDirection(s.timeOfDay_h);
    s.moon = -s.sun;
    s.sunLobe = makeLobe(s.sun, turbidity_, 1.0);
    s.moonLobe = makeLobe(s.moon, turbidity_, 1.0 / kMoonToSun);
    return s;
}

glm::vec3 Sky::radiance(const glm::dvec3& dir, const SkyState& state) const {
    const double len = glm::length(dir);
    glm::dvec3 d = (len > 0.0 && std::isfinite(len)) ? dir / len : glm::dvec3(0.0, 1.0, 0.0);
    d.y = std::abs(d.y);  // below the horizon: the sky mirrored (Sky.h)
    glm::dvec3 rgb(0.0);
    if (state.sunLobe.active) rgb += evalLobe(state.sunLobe, d);
    if (state.moonLobe.active) rgb += evalLobe(state.moonLobe, d);
    // Airglow and starlight: a faint blue floor, about 3x brighter at the horizon.
    const double horizon = 1.0 + 2.0 * std::pow(1.0 - d.y, 4.0);
    rgb += (kNightGlow_cdm2 / kLuminousEfficacy) * horizon * glm::dvec3(0.75, 0.85, 1.2);
    return glm::vec3(rgb);
}

glm::vec3 Sky::radiance(const glm::dvec3& dir, double timeOfDay_h) const {
    return radiance(dir, state(timeOfDay_h));
}

// ---- Sun and moon discs, direct lights ------------------------------------------------------

glm::dvec3 Sky::diskTransmittance(const glm::dvec3& dir) const {
    // Beer-Lambert along the Kasten-Young (1989) air mass: Rayleigh (Leckner) and aerosol
    // (Angstrom, beta from turbidity as in Preetham 1999) optical depths at red, green, blue.
    const double elevation_deg = std::asin(std::clamp(dir.y, -1.0, 1.0)) / kDeg;
    const double zenith_deg = 90.0 - std::max(elevation_deg, 0.0);
    const double airMass =
        1.0 / (std::cos(zenith_deg * kDeg) + 0.50572 * std::pow(96.07995 - zenith_deg, -1.6364));
    const double beta = 0.04608 * turbidity_ - 0.04586;
    const double lambda_um[3] = {0.65, 0.57, 0.475};
    glm::dvec3 t;
    for (int c = 0; c < 3; ++c) {
        const double tauRayleigh = 0.008735 * std::pow(lambda_um[c], -4.08);
        const double tauAerosol = beta * std::pow(lambda_um[c], -1.3);
        t[c] = std::exp(-(tauRayleigh + tauAerosol) * airMass);
    }
    // The disc sets smoothly as it crosses the horizon.
    const double r = kSunAngularRadius_rad;
    const double e = std::asin(std::clamp(dir.y, -1.0, 1.0));
    const double u = std::clamp((e + r) / (2.0 * r), 0.0, 1.0);
    return t * (u * u * (3.0 - 2.0 * u));
}

glm::vec3 Sky::sunRadiance(double timeOfDay_h) const {
    // Extraterrestrial solar colour in linear sRGB (~5800 K), luminance 1.
    const glm::dvec3 colour(1.0, 0.95, 0.90);
    const glm::dvec3 l0 = colour / luminance(colour) * (kSunLuminance_cdm2 / kLuminousEfficacy);
    return glm::vec3(l0 * diskTransmittance(sunDirection(timeOfDay_h)));
}

glm::vec3 Sky::moonRadiance(double timeOfDay_h) const {
    const glm::dvec3 colour(1.0, 0.93, 0.85);  // lunar regolith reddens sunlight slightly
    const glm::dvec3 l0 =
        colour / luminance(colour) * (kSunLuminance_cdm2 / kLuminousEfficacy / kMoonToSun);
    return glm::vec3(l0 * diskTransmittance(moonDirection(timeOfDay_h)));
}

DirectionalLight Sky::sunLight(double timeOfDay_h) const {
    const double solidAngle = 2.0 * kPi * (1.0 - std::cos(kSunAngularRadius_rad));
    return {sunDirection(timeOfDay_h), sunRadiance(timeOfDay_h) * float(solidAngle)};
}

DirectionalLight Sky::moonLight(double timeOfDay_h) const {
    const double solidAngle = 2.0 * kPi * (1.0 - std::cos(kSunAngularRadius_rad));
    return {moonDirection(timeOfDay_h), moonRadiance(timeOfDay_h) * float(solidAngle)};
}

DirectionalLight Sky::mainLight(double timeOfDay_h) const {
    const DirectionalLight sun = sunLight(timeOfDay_h);
    const DirectionalLight moon = moonLight(timeOfDay_h);
    DirectionalLight light =
        luminance(glm::dvec3(sun.irradiance)) >= luminance(glm::dvec3(moon.irradiance)) ? sun
                                                                                        : moon;
    // Never exactly zero (the night-time light must stay usable for exposure and shading).
    light.irradiance = glm::max(light.irradiance, glm::dvec3(1e-9));
    return light;
}

}  // namespace amb
