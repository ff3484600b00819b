// Road.h — long roads routed along gentle slopes (least-cost path over the heightfield),
// smoothed as a spline; queries for flattening the terrain and keeping trees off.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "world/WorldSettings.h"

namespace amb {

class Heightfield;

struct Road {
    std::string name;                    // "highway", "mountain"
    std::vector<glm::dvec3> centreline;  // resampled every few metres; y = road surface height
    double halfWidth_m = 4.0;
    double length_m = 0.0;
    glm::dvec3 pointAt(double s_m) const;    // arc length s along the centreline, clamped
    glm::dvec3 tangentAt(double s_m) const;  // unit
};

struct RoadQuery {
    double distance_m;        // horizontal (XZ) distance to the centreline
    double surfaceHeight_m;   // road surface height at the closest centreline point
    double halfWidth_m;
    int roadIndex;
};

class RoadNetwork {
public:
    RoadNetwork(const WorldSettings& settings, const Heightfield& heightfield);
    const std::vector<Road>& roads() const;
    // The nearest road point within maxDistance_m (XZ), if any.
    std::optional<RoadQuery> nearest(double x_m, double z_m, double maxDistance_m) const;
};

}  // namespace amb
