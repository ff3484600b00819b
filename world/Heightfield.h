// Heightfield.h — the endless natural terrain h(x, z) before roads: fBm plus ridged noise with
// domain warping, evaluated at any double-precision (x, z); normals; moisture.
#pragma once

#include <glm/vec3.hpp>

#include "world/WorldSettings.h"

namespace amb {

class Heightfield {
public:
    explicit Heightfield(const WorldSettings& settings);

    double height(double x_m, double z_m) const;          // metres above the datum
    glm::dvec3 normal(double x_m, double z_m) const;      // unit, +Y up
    double moisture(double x_m, double z_m) const;        // [0, 1]
};

}  // namespace amb
