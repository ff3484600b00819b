// ShGradient.cpp — the translational gradient of a probe's SH (see ShGradient.h).
#include "lighting/ShGradient.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "lighting/CubeMapProjector.h"
#include "world/Conventions.h"
#include "world/Error.h"

namespace amb {

namespace {

bool usable(const float* rgb, float distance) {
    for (int c = 0; c < 3; ++c)
        if (!(rgb[c] >= 0.0f) || !std::isfinite(rgb[c])) return false;
    return std::isfinite(distance) && distance > 0.0f;
}

}  // namespace

ShSlope toFloat(const ShGroundGradient& g) {
    return {toFloat(g.dx), toFloat(g.dz), float(std::min(g.harmonicDistance_m, 1e15))};
}

ShGroundGradient shGroundGradient(int n, const std::vector<float>& rgb,
                                  const std::vector<float>& distance_m,
                                  const ShGradientOptions& options) {
    const std::size_t texels = std::size_t(kCubeFaces) * std::size_t(n) * std::size_t(n);
    AMB_CHECK(n >= 1 && rgb.size() == 3 * texels && distance_m.size() == texels);
    ShGroundGradient g;
    const glm::dvec3 axes[2] = {{1.0, 0.0, 0.0}, {0.0, 0.0, 1.0}};
    ShRgbD* out[2] = {&g.dx, &g.dz};
    double inverseSum = 0.0;
    for (int f = 0; f < kCubeFaces; ++f) {
        const std::size_t face = std::size_t(f) * n * n;
        // The surface point a texel shows, when it shows one.
        auto point = [&](int i, int j, glm::dvec3& p) {
            if (i < 0 || j < 0 || i >= n || j >= n) return false;
            const std::size_t t = face + std::size_t(j) * n + i;
            if (!usable(&rgb[3 * t], distance_m[t])) return false;
            p = glm::normalize(cubeTexelDirection(f, i, j, n)) * double(distance_m[t]);
            return true;
        };
        // The difference towards the neighbour along (di, dj) whose distance differs least
        // from the texel's, signed as from -1 to +1.
        auto tangent = [&](int i, int j, int di, int dj, const glm::dvec3& p, double r,
                           glm::dvec3& out) {
            glm::dvec3 a(0.0), b(0.0);
            const bool ha = point(i + di, j + dj, a), hb = point(i - di, j - dj, b);
            if (!ha && !hb) return false;
            const bool useA = ha && (!hb || std::fabs(glm::length(a) - r) <=
                                                std::fabs(glm::length(b) - r));
            out = useA ? a - p : p - b;
            return true;
        };
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                const std::size_t t = face + std::size_t(j) * n + i;
                glm::dvec3 p(0.0);
                if (!point(i, j, p)) continue;
                const double r = double(distance_m[t]);
                const glm::dvec3 w = p / r;
                glm::dvec3 normal = -w;  // facing the probe unless the neighbours say otherwise
                glm::dvec3 tu(0.0), tv(0.0);
                if (tangent(i, j, 1, 0, p, r, tu) && tangent(i, j, 0, 1, p, r, tv)) {
                    const glm::dvec3 c = glm::cross(tu, tv);
                    const double len = glm::length(c);
                    if (len > 0.0 && std::isfinite(len)) normal = c / len;
                }
                double wn = glm::dot(w, normal);
                if (wn > 0.0) normal = -normal, wn = -wn;
                wn = std::min(wn, -options.minCosine);
                const double inverseR = 1.0 / std::max(r, options.minDistance_m);
                inverseSum += inverseR;
                const double weight = cubeTexelSolidAngle(i, j, n) * inverseR;
                const auto y = shBasis(w);
                for (int a = 0; a < 2; ++a) {
                    const glm::dvec3& d = axes[a];
                    // The direction moves by -(d - (w.d) w) per unit of motion x 1/r; the basis
                    // is quadratic, so its central difference is its exact derivative.
                    const glm::dvec3 dw = -(d - glm::dot(w, d) * w);
                    constexpr double e = 1e-3;
                    const auto yp = shBasis(w + e * dw), ym = shBasis(w - e * dw);
                    const double area = 3.0 * glm::dot(w, d) - glm::dot(normal, d) / wn;
                    for (int k = 0; k < kShCoefficients; ++k) {
                        const double s = weight * ((yp[k] - ym[k]) / (2.0 * e) + y[k] * area);
                        out[a]->c[k] += s * glm::dvec3(rgb[3 * t], rgb[3 * t + 1], rgb[3 * t + 2]);
                    }
                }
            }
        }
    }
    if (inverseSum > 0.0) g.harmonicDistance_m = double(texels) / inverseSum;
    return g;
}

}  // namespace amb
