// Sky.h — sun position from time of day and latitude; analytic HDR sky radiance, day and night.
#pragma once

#include <glm/vec3.hpp>

#include "world/WorldSettings.h"

namespace amb {

class Sky {
public:
    explicit Sky(const WorldSettings& settings);

    // Unit world direction towards the sun at a time of day in hours [0, 24) (wraps).
    glm::dvec3 sunDirection(double timeOfDay_h) const;
    // Sky radiance (linear RGB, W sr^-1 m^-2-like units) arriving from direction `dir` (unit,
    // pointing away from the viewer), without the sun disc. Never exactly zero (night glow).
    glm::vec3 radiance(const glm::dvec3& dir, double timeOfDay_h) const;
    // Radiance of the sun disc itself (about 10^5 x the sky at noon); ~0 below the horizon.
    glm::vec3 sunRadiance(double timeOfDay_h) const;
    // Angular radius of the sun disc.
    double sunAngularRadius_rad() const;
    // Angular speed of the sun across the sky [rad per hour of day-time].
    double sunAngularSpeed_radPerHour() const;
};

}  // namespace amb
