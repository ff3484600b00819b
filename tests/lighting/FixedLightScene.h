// FixedLightScene.h — a near-field scene under one fixed light and a hemisphere ambient over flat
// ground at height 0, without plants of its own: the near field's cache tests and the captures'
// light tests derive their scenes from it and add their plants.
#pragma once

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "lighting/NearField.h"

namespace amb::testing_support {

struct FixedLightScene : NearFieldScene {
    DirectionalLight mainLight(double) const override {
        DirectionalLight l;
        l.direction = glm::normalize(glm::dvec3(0.3, 0.8, 0.2));
        l.irradiance = glm::dvec3(3.0);
        return l;
    }
    HemisphereAmbient ambient(double) const override {
        return {glm::dvec3(0.8, 0.9, 1.0), glm::dvec3(0.25)};
    }
    double groundHeight(double, double) const override { return 0.0; }
};

}  // namespace amb::testing_support
