// SkyGround.cpp — the sky model over a flat Lambertian ground (see SkyGround.h).
#include "world/SkyGround.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "world/Conventions.h"
#include "world/Error.h"
#include "world/Sky.h"

namespace amb {

SkyGround groundUnder(const Sky& sky, double timeOfDay_h, const glm::dvec3& skyIrradianceUp) {
    SkyGround s;
    s.skyIrradianceUp = skyIrradianceUp;
    const DirectionalLight sun = sky.sunLight(timeOfDay_h);
    const DirectionalLight moon = sky.moonLight(timeOfDay_h);
    s.groundIrradiance = skyIrradianceUp +
                         glm::dvec3(sun.irradiance) * std::max(0.0, sun.direction.y) +
                         glm::dvec3(moon.irradiance) * std::max(0.0, moon.direction.y);
    s.ground = s.groundIrradiance * (double(kGroundAlbedo) / kPi);
    return s;
}

SkyGround evaluateSkyGround(const Sky& sky, double timeOfDay_h, const std::vector<glm::dvec3>& dirs,
                            const std::vector<double>& solidAngles_sr, std::vector<float>& rgb) {
    AMB_CHECK(dirs.size() == solidAngles_sr.size());
    const SkyState state = sky.state(timeOfDay_h);
    rgb.assign(dirs.size() * 3, 0.0f);
    // Sky over the upper hemisphere, and the irradiance of a horizontal surface from it.
    glm::dvec3 skyUp(0.0), skySum(0.0);
    double skyWeight = 0.0;
    for (std::size_t t = 0; t < dirs.size(); ++t) {
        const glm::dvec3& dir = dirs[t];
        if (dir.y < 0.0) continue;
        const glm::vec3 l = sky.radiance(dir, state);
        const double omega = solidAngles_sr[t];
        skyUp += glm::dvec3(l) * dir.y * omega;
        skySum += glm::dvec3(l) * omega;
        skyWeight += omega;
        rgb[3 * t + 0] = l.r;
        rgb[3 * t + 1] = l.g;
        rgb[3 * t + 2] = l.b;
    }
    // Flat Lambertian ground below the horizon, lit by that sky, the sun and the moon.
    SkyGround s = groundUnder(sky, timeOfDay_h, skyUp);
    s.skyMean = skyWeight > 0.0 ? skySum / skyWeight : glm::dvec3(0.0);
    for (std::size_t t = 0; t < dirs.size(); ++t) {
        if (!(dirs[t].y < 0.0)) continue;
        rgb[3 * t + 0] = float(s.ground.x);
        rgb[3 * t + 1] = float(s.ground.y);
        rgb[3 * t + 2] = float(s.ground.z);
    }
    return s;
}

const SkyGrid& skyGrid() {
    static const SkyGrid grid = [] {
        const int w = SkyGrid::kWidth, h = SkyGrid::kHeight;
        const double dTheta = kPi / h, dPhi = 2.0 * kPi / w;
        SkyGrid g;
        for (int r = 0; r < h; ++r) {
            const double theta = (r + 0.5) * dTheta;
            for (int c = 0; c < w; ++c) {
                const double phi = ((c + 0.5) / w - 0.5) * 2.0 * kPi;
                g.directions.emplace_back(std::sin(theta) * std::sin(phi), std::cos(theta),
                                          -std::sin(theta) * std::cos(phi));
                g.solidAngles_sr.push_back(std::sin(theta) * dTheta * dPhi);
            }
        }
        return g;
    }();
    return grid;
}

glm::dvec3 HemisphereAmbient::shBand0() const {
    return kShY00 * 2.0 * kPi * (sky + ground);
}

glm::dvec3 HemisphereAmbient::shVertical() const {
    return kShY1 * kPi * (sky - ground);
}

HemisphereAmbient hemisphereAmbient(const Sky& sky, double timeOfDay_h) {
    const SkyGrid& grid = skyGrid();
    std::vector<float> rgb;
    const SkyGround s = evaluateSkyGround(sky, timeOfDay_h, grid.directions, grid.solidAngles_sr, rgb);
    return {s.skyMean, s.ground};
}

}  // namespace amb
