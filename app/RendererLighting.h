// RendererLighting.h — the few lighting/ functions the renderer needs, behind plain types.
// (lighting/SH.h and world/Sky.h both declare a DirectionalLight, so no renderer file includes
// both; RendererLighting.cpp includes only the lighting/ side.)
#pragma once

#include <array>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

namespace amb {

// R&H irradiance matrices (r, g, b) of a radiance that is `sky` over the upper hemisphere
// (y > 0) and `ground` over the lower one. The step function has only bands 0 and 1:
// L00 = sqrt(pi) (sky + ground), L1-1 = Y1 pi (sky - ground), all others zero.
std::array<glm::mat4, 3> hemisphereIrradianceMatrices(const glm::vec3& sky,
                                                      const glm::vec3& ground);
// Irradiance at a unit normal of the same hemisphere radiance (CPU side, for terrain corners).
glm::vec3 hemisphereIrradiance(const glm::vec3& sky, const glm::vec3& ground,
                               const glm::vec3& normal);

// Exact solid angle [sr] of texel (i, j) of an N x N cube face.
double cubeTexelSolidAngle_sr(int i, int j, int n);

}  // namespace amb
