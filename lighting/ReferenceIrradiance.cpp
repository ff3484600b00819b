// ReferenceIrradiance.cpp — see ReferenceIrradiance.h.
#include "lighting/ReferenceIrradiance.h"

#include <algorithm>
#include <cmath>

#include <boost/math/quadrature/gauss.hpp>
#include <glm/geometric.hpp>

#include "lighting/Metrics.h"
#include "world/Conventions.h"
#include "world/Error.h"

namespace amb {

namespace {


template <int M>
void legendre(std::vector<double>& x, std::vector<double>& w) {
    using G = boost::math::quadrature::gauss<double, M>;
    const auto& a = G::abscissa();
    const auto& b = G::weights();
    for (std::size_t k = 0; k < a.size(); ++k) {
        x.push_back(a[k]), w.push_back(b[k]);
        if (a[k] != 0.0) x.push_back(-a[k]), w.push_back(b[k]);
    }
}

// The four corners of a texel on its face (z = +-1 plane etc.), counter-clockwise as seen from
// outside the cube or not: the sign is fixed by the caller.
std::array<glm::dvec3, 4> texelCorners(int face, int i, int j, int n) {
    const double u0 = 2.0 * i / n - 1.0, u1 = 2.0 * (i + 1) / n - 1.0;
    const double v0 = 2.0 * j / n - 1.0, v1 = 2.0 * (j + 1) / n - 1.0;
    return {cubeFaceDirection(face, u0, v0), cubeFaceDirection(face, u1, v0),
            cubeFaceDirection(face, u1, v1), cubeFaceDirection(face, u0, v1)};
}

// Integral of w dw over the spherical polygon seen through a planar polygon (Lambert):
// 1/2 sum_i theta_i (v_i x v_{i+1}) / |v_i x v_{i+1}|, with the sign that makes it point
// towards the polygon.
glm::dvec3 polygonVector(const glm::dvec3* v, int count) {
    glm::dvec3 sum(0.0), centre(0.0);
    for (int k = 0; k < count; ++k) {
        const glm::dvec3 a = glm::normalize(v[k]), b = glm::normalize(v[(k + 1) % count]);
        centre += a;
        const glm::dvec3 c = glm::cross(a, b);
        const double s = glm::length(c);
        if (s < 1e-300) continue;
        const double theta = std::atan2(s, glm::dot(a, b));
        sum += (theta / s) * c;
    }
    sum *= 0.5;
    return glm::dot(sum, centre) < 0.0 ? -sum : sum;
}

}  // namespace

SphereRule sphereProductRule(int m) {
    if (m < 1 || m > 8) throw InputError("sphere rule", "expected 1 to 8 Legendre nodes");
    std::vector<double> x, w;
    switch (m) {
        case 1: legendre<1>(x, w); break;
        case 2: legendre<2>(x, w); break;
        case 3: legendre<3>(x, w); break;
        case 4: legendre<4>(x, w); break;
        case 5: legendre<5>(x, w); break;
        case 6: legendre<6>(x, w); break;
        case 7: legendre<7>(x, w); break;
        default: legendre<8>(x, w); break;
    }
    SphereRule rule;
    rule.degree = 2 * m - 1;
    const int azimuths = 2 * m;
    for (std::size_t k = 0; k < x.size(); ++k) {
        const double r = std::sqrt(std::max(0.0, 1.0 - x[k] * x[k]));
        for (int a = 0; a < azimuths; ++a) {
            const double phi = 2.0 * kPi * (a + 0.5) / azimuths;
            rule.directions.emplace_back(r * std::cos(phi), x[k], r * std::sin(phi));
            rule.weights.push_back(w[k] * 2.0 * kPi / azimuths);
        }
    }
    return rule;
}

double texelCosineIntegral(int face, int i, int j, int n, const glm::dvec3& normal) {
    const auto c = texelCorners(face, i, j, n);
    double d[4];
    int above = 0;
    for (int k = 0; k < 4; ++k) above += (d[k] = glm::dot(normal, c[k])) >= 0.0;
    if (above == 0) return 0.0;
    if (above == 4) return std::max(0.0, glm::dot(normal, polygonVector(c.data(), 4)));
    // Clip the planar quad by the plane n . x = 0 (Sutherland-Hodgman, one plane).
    glm::dvec3 clipped[8];
    int count = 0;
    for (int k = 0; k < 4; ++k) {
        const int l = (k + 1) % 4;
        if (d[k] >= 0.0) clipped[count++] = c[k];
        if ((d[k] >= 0.0) != (d[l] >= 0.0)) {
            const double t = d[k] / (d[k] - d[l]);
            clipped[count++] = c[k] + t * (c[l] - c[k]);
        }
    }
    if (count < 3) return 0.0;
    return std::max(0.0, glm::dot(normal, polygonVector(clipped, count)));
}

CubeIrradiance::CubeIrradiance(int n, const std::vector<float>& rgb) : n_(n) {
    AMB_CHECK(n >= 1 && rgb.size() == std::size_t(kCubeFaces) * n * n * 3);
    radiance_.resize(std::size_t(kCubeFaces) * n * n);
    vector_.resize(radiance_.size());
    for (int f = 0; f < kCubeFaces; ++f)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const std::size_t t = (std::size_t(f) * n + j) * n + i;
                radiance_[t] = glm::dvec3(rgb[3 * t], rgb[3 * t + 1], rgb[3 * t + 2]);
                const auto c = texelCorners(f, i, j, n);
                vector_[t] = polygonVector(c.data(), 4);
            }
}

glm::dvec3 CubeIrradiance::at(const glm::dvec3& normal) const {
    const glm::dvec3 nrm = glm::normalize(normal);
    glm::dvec3 e(0.0);
    const int n = n_;
    for (int f = 0; f < kCubeFaces; ++f)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const std::size_t t = (std::size_t(f) * n + j) * n + i;
                const glm::dvec3& L = radiance_[t];
                if (L.x == 0.0 && L.y == 0.0 && L.z == 0.0) continue;
                // Wholly above the horizon when the corners are; the corners' signs decide.
                const auto c = texelCorners(f, i, j, n);
                bool allAbove = true, allBelow = true;
                for (const auto& corner : c) {
                    const double d = glm::dot(nrm, corner);
                    allAbove &= d >= 0.0;
                    allBelow &= d <= 0.0;
                }
                if (allBelow) continue;
                const double w =
                    allAbove ? glm::dot(nrm, vector_[t]) : texelCosineIntegral(f, i, j, n, nrm);
                e += L * w;
            }
    return e;
}

double irradianceDistance(const IrradianceField& a, const IrradianceField& b,
                          const SphereRule& rule) {
    double sum = 0.0;
    for (std::size_t k = 0; k < rule.directions.size(); ++k) {
        const glm::dvec3 d = a(rule.directions[k]) - (b ? b(rule.directions[k]) : glm::dvec3(0.0));
        sum += rule.weights[k] * (kLuminanceWeights[0] * d.x * d.x +
                                  kLuminanceWeights[1] * d.y * d.y +
                                  kLuminanceWeights[2] * d.z * d.z);
    }
    return std::sqrt(std::max(sum, 0.0));
}

double irradianceNorm(const IrradianceField& a, const SphereRule& rule) {
    return irradianceDistance(a, IrradianceField(), rule);
}

IrradianceField shField(const ShRgb& sh) {
    const ShRgbD d = toDouble(sh);
    return [d](const glm::dvec3& n) { return shIrradiance(d, n); };
}

}  // namespace amb
