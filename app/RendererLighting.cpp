// RendererLighting.cpp — adapters from the renderer to lighting/ (SH and cube-map projection).
#include "app/RendererLighting.h"

#include <cmath>

#include "lighting/CubeMapProjector.h"
#include "lighting/SH.h"

namespace amb {

static ShRgb hemisphereSh(const glm::vec3& sky, const glm::vec3& ground) {
    // L_k = integral of L Y_k: the constant part gives L00 = Y00 4 pi (s + g) / 2; the odd part
    // (s - g)/2 sign(y) gives L1-1 = Y1 (s - g)/2 * 2 * integral_{y>0} y dw = Y1 pi (s - g).
    ShRgb sh;
    sh.c[0] = glm::vec3(float(kShY00 * 2.0 * kPi)) * (sky + ground);
    sh.c[1] = glm::vec3(float(kShY1 * kPi)) * (sky - ground);
    return sh;
}

std::array<glm::mat4, 3> hemisphereIrradianceMatrices(const glm::vec3& sky,
                                                      const glm::vec3& ground) {
    const ShIrradianceMatrices m = shIrradianceMatrices(hemisphereSh(sky, ground));
    return {m.r, m.g, m.b};
}

glm::vec3 hemisphereIrradiance(const glm::vec3& sky, const glm::vec3& ground,
                               const glm::vec3& normal) {
    return shIrradiance(hemisphereSh(sky, ground), normal);
}

double cubeTexelSolidAngle_sr(int i, int j, int n) {
    return cubeTexelSolidAngle(i, j, n);
}

}  // namespace amb
