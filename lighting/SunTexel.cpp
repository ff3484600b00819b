// SunTexel.cpp — the texel holding the sun, and that texel filled from its neighbours (see the
// header).
#include "lighting/SunTexel.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <glm/geometric.hpp>

#include "lighting/CubeMapProjector.h"
#include "world/Conventions.h"
#include "world/Error.h"

namespace amb {

namespace {

bool usable(float x) {
    return x >= 0.0f && std::isfinite(x);
}

// Column or row whose interval of [-1, 1] holds face coordinate c.
int texelIndex(double c, int n) {
    const double t = std::floor((c + 1.0) * 0.5 * n);
    return int(std::clamp(t, 0.0, double(n - 1)));
}

}  // namespace

CubeTexel sunTexel(const glm::dvec3& dir, int n) {
    AMB_CHECK(n >= 1);
    // The face whose axis the direction is most along: the largest of the six dot products.
    int face = 0;
    double best = -1.0;
    for (int f = 0; f < kCubeFaces; ++f) {
        const double along = glm::dot(dir, cubeFaceDirection(f, 0.0, 0.0));
        if (along > best) {
            best = along;
            face = f;
        }
    }
    AMB_CHECK(best > 0.0);  // a zero or non-finite direction has no texel
    const glm::dvec3 forward = cubeFaceDirection(face, 0.0, 0.0);
    const glm::dvec3 u = cubeFaceDirection(face, 1.0, 0.0) - forward;
    const glm::dvec3 v = cubeFaceDirection(face, 0.0, 1.0) - forward;
    return {face, texelIndex(glm::dot(dir, u) / best, n), texelIndex(glm::dot(dir, v) / best, n)};
}

glm::vec3 sunTexelRadiance(const glm::vec3& discRadiance, double discSolidAngle_sr,
                           const CubeTexel& texel, int n) {
    const float scale = float(discSolidAngle_sr / cubeTexelSolidAngle(texel.i, texel.j, n));
    return discRadiance * scale;
}

bool fillSunTexel(float* faceRgb, int face, int n, const glm::dvec3& sunDirection,
                  glm::vec3* removed, glm::vec3* filled) {
    const CubeTexel s = sunTexel(sunDirection, n);
    if (s.face != face) return false;
    float* p = faceRgb + 3 * (std::size_t(s.j) * n + s.i);
    if (!(usable(p[0]) && usable(p[1]) && usable(p[2]))) return false;
    const auto texel = [&](int i, int j) -> const float* {
        if (i < 0 || j < 0 || i >= n || j >= n) return nullptr;
        const float* q = faceRgb + 3 * (std::size_t(j) * n + i);
        return usable(q[0]) && usable(q[1]) && usable(q[2]) ? q : nullptr;
    };
    const auto lum = [](const float* q) { return luminance(glm::dvec3(q[0], q[1], q[2])); };
    // Of the opposite pairs across the texel (row, column, the two diagonals) whose texels are
    // both usable, the pair that differs least: along an edge (the horizon is a row boundary of
    // the side faces), not across it.
    static constexpr int kPairs[4][2] = {{1, 0}, {0, 1}, {1, 1}, {1, -1}};
    const float* best[2] = {nullptr, nullptr};
    double bestDifference = 0.0;
    for (const auto& d : kPairs) {
        const float* a = texel(s.i - d[0], s.j - d[1]);
        const float* b = texel(s.i + d[0], s.j + d[1]);
        if (!a || !b) continue;
        const double difference = std::fabs(lum(a) - lum(b));
        if (!best[0] || difference < bestDifference) {
            best[0] = a, best[1] = b;
            bestDifference = difference;
        }
    }
    glm::dvec3 sum(0.0);
    int count = 0;
    if (best[0]) {
        for (const float* q : best) sum += glm::dvec3(q[0], q[1], q[2]);
        count = 2;
    } else {
        // No whole pair (a face's corner, a face of 2 x 2 or less): the usable neighbours' mean.
        for (int j = s.j - 1; j <= s.j + 1; ++j)
            for (int i = s.i - 1; i <= s.i + 1; ++i) {
                const float* q = (i == s.i && j == s.j) ? nullptr : texel(i, j);
                if (!q) continue;
                sum += glm::dvec3(q[0], q[1], q[2]);
                ++count;
            }
    }
    const glm::vec3 mean = count > 0 ? glm::vec3(sum / double(count)) : glm::vec3(0.0f);
    if (removed) *removed = glm::vec3(p[0], p[1], p[2]);
    if (filled) *filled = mean;
    p[0] = mean.x;
    p[1] = mean.y;
    p[2] = mean.z;
    return true;
}

bool fillSunTexel(float* cubeRgb, int n, const glm::dvec3& sunDirection) {
    const int face = sunTexel(sunDirection, n).face;
    return fillSunTexel(cubeRgb + 3 * std::size_t(face) * n * n, face, n, sunDirection);
}

}  // namespace amb
