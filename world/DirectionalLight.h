// DirectionalLight.h — a distant light (sun, moon): used by the sky model, which produces it,
// and by the SH code, which can take it out of a captured radiance and light it exactly.
#pragma once

#include <glm/vec3.hpp>

namespace amb {

struct DirectionalLight {
    glm::dvec3 direction{0.0, 1.0, 0.0};  // unit vector towards the light
    glm::dvec3 irradiance{0.0};           // on a surface facing the light (radiance x sr)
};

}  // namespace amb
