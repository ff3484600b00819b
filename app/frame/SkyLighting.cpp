// SkyLighting.cpp — the sky for a time of day, the exposure and the fixed ambients.
#include "app/frame/SkyLighting.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "world/Conventions.h"
#include "world/Error.h"
#include "world/Sky.h"
#include "world/SkyGround.h"

namespace amb {

// ---- Sky -------------------------------------------------------------------------------------

SkyLighting evaluateSky(const Sky& sky, double timeOfDay_h) {
    SkyLighting s;
    s.timeOfDay_h = timeOfDay_h;
    const SkyState state = sky.state(timeOfDay_h);
    const DirectionalLight light = sky.mainLight(timeOfDay_h);
    s.lightDir = glm::vec3(light.direction);
    s.lightIrradiance = light.irradiance;
    s.sunDiscRadiance = sky.sunRadiance(timeOfDay_h);
    s.sunCosRadius = float(std::cos(sky.sunAngularRadius_rad()));
    const glm::dvec3 sunDir = sky.sunDirection(timeOfDay_h);
    glm::dvec3 az(sunDir.x, 0.0, sunDir.z);
    az = glm::length(az) > 1e-9 ? glm::normalize(az) : glm::dvec3(0.0, 0.0, 1.0);
    s.sunAzimuth = glm::vec3(az);
    const double up = std::sin(2.0 * kPi / 180.0), across = std::cos(2.0 * kPi / 180.0);
    s.horizonToward = sky.radiance(glm::dvec3(az.x * across, up, az.z * across), state);
    s.horizonAway = sky.radiance(glm::dvec3(-az.x * across, up, -az.z * across), state);

    // The texture's texels as directions with their solid angles: the sky model above the
    // horizon, the flat ground of kGroundAlbedo below it (world/SkyGround.h, the scene the
    // probes' fallback shows too).
    const SkyGrid& grid = skyGrid();
    const SkyGround ground = evaluateSkyGround(sky, timeOfDay_h, grid.directions, grid.solidAngles_sr, s.texture);
    s.skyMean = glm::vec3(ground.skyMean);
    s.skyIrradianceUp = glm::vec3(ground.skyIrradianceUp);
    s.groundMean = glm::vec3(ground.ground);
    return s;
}

float exposureFor(const SkyLighting& now, const SkyLighting& noon) {
    auto white = [](const SkyLighting& s) {
        const glm::vec3 e = s.skyIrradianceUp + s.lightIrradiance * std::max(0.0f, s.lightDir.y);
        return luminance(e) / float(kPi);
    };
    const float reference = std::max(white(noon), 1e-6f);
    return 0.6f / std::max(white(now), reference * 1e-3f);
}

// ---- Ambient ---------------------------------------------------------------------------------

AmbientMode parseAmbientMode(const std::string& text, const std::string& where) {
    if (text == "constant") return AmbientMode::Constant;
    if (text == "hemisphere") return AmbientMode::Hemisphere;
    throw InputError(where, "unknown ambient '" + text + "' (expected constant or hemisphere)");
}

const char* toString(AmbientMode mode) {
    return mode == AmbientMode::Constant ? "constant" : "hemisphere";
}

FixedAmbient::FixedAmbient(AmbientMode mode, const SkyLighting& sky) {
    // The sky's mean over the upper hemisphere (y > 0) and the ground's below, or their mean
    // everywhere.
    const glm::dvec3 mean = 0.5 * glm::dvec3(sky.skyMean + sky.groundMean);
    sh_ = mode == AmbientMode::Constant
              ? hemisphereSh(HemisphereAmbient{mean, mean})
              : hemisphereSh(HemisphereAmbient{glm::dvec3(sky.skyMean), glm::dvec3(sky.groundMean)});
    const ShIrradianceMatrices m = shIrradianceMatrices(sh_);
    set_ = {m.r, m.g, m.b};
}

glm::vec3 FixedAmbient::cornerIrradiance(const glm::dvec3&, const glm::dvec3& normal) const {
    return shIrradiance(sh_, glm::vec3(normal));
}

std::uint32_t FixedAmbient::objectSet(const glm::dvec3&, std::vector<AmbientSet>& sets) const {
    if (sets.empty()) sets.push_back(set_);
    return 0;
}

}  // namespace amb
