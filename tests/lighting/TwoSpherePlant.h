// TwoSpherePlant.h — a near-field scene of one plant for the near field's plant tests: two
// spheres beside the origin (2 m across at (5, 2, 0), 1.2 m across at (5, 5, 0)) of one albedo,
// on flat ground at y = 0, under the hemisphere ambient (0.5 sky, 0.2 ground). Its shares of the
// sky and of the light are given, and every question for them is counted. The light swings
// over the sky with the time of day: straight up at noon, at the horizon at 6 h and 18 h, on the
// -X side in the afternoon.
#pragma once

#include <cmath>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "lighting/NearField.h"
#include "world/Conventions.h"

namespace amb::testing_support {

struct TwoSpherePlant final : NearFieldScene {
    glm::dvec3 albedo{0.3};
    double skyShare = 1.0, sunShare = 1.0;
    double lightIrradiance = 1.0;  // 0: no light, the caps show their ambient alone
    mutable int skyAsked = 0, sunAsked = 0;

    void occludersNear(const glm::dvec3&, double, double,
                       std::vector<SphereOccluder>& out) const override {
        for (const auto& [centre, radius] : {std::pair{glm::dvec3(5.0, 2.0, 0.0), 2.0},
                                             std::pair{glm::dvec3(5.0, 5.0, 0.0), 1.2}}) {
            SphereOccluder o;
            o.centre_m = centre, o.radius_m = radius, o.albedo = albedo;
            out.push_back(o);
        }
    }
    DirectionalLight mainLight(double timeOfDay_h) const override {
        const double e = kPi / 2.0 - (timeOfDay_h - 12.0) * kPi / 12.0;
        DirectionalLight l;
        l.direction = glm::normalize(glm::dvec3(-std::cos(e), std::sin(e), 0.1));
        l.irradiance = glm::dvec3(lightIrradiance);
        return l;
    }
    HemisphereAmbient ambient(double) const override { return {glm::dvec3(0.5), glm::dvec3(0.2)}; }
    double groundHeight(double, double) const override { return 0.0; }
    double sphereSkyVisibility(const glm::dvec3&, double) const override {
        ++skyAsked;
        return skyShare;
    }
    double sphereLightVisibility(const glm::dvec3&, double, const glm::dvec3&) const override {
        ++sunAsked;
        return sunShare;
    }
};

}  // namespace amb::testing_support
