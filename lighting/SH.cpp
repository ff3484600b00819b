// SH.cpp — order-2 SH basis, irradiance and deringing (see SH.h).
//
// [SECTION] Coefficient-set arithmetic
// [SECTION] Basis and irradiance (direct, R&H matrices, batch)
// [SECTION] Extrema of the irradiance over the sphere
// [SECTION] Windows and the automatic window
// [SECTION] Directional lights
#include "lighting/SH.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include "world/Error.h"
#include "world/SkyGround.h"

namespace amb {

// ---- Coefficient-set arithmetic --------------------------------------------------------------

ShRgb& ShRgb::operator+=(const ShRgb& o) {
    for (int k = 0; k < kShCoefficients; ++k) c[k] += o.c[k];
    return *this;
}
ShRgb& ShRgb::operator*=(float s) {
    for (auto& v : c) v *= s;
    return *this;
}
ShRgb operator+(ShRgb a, const ShRgb& b) {
    return a += b;
}
ShRgb operator-(const ShRgb& a, const ShRgb& b) {
    ShRgb r;
    for (int k = 0; k < kShCoefficients; ++k) r.c[k] = a.c[k] - b.c[k];
    return r;
}
ShRgb operator*(ShRgb a, float s) {
    return a *= s;
}
ShRgb lerp(const ShRgb& a, const ShRgb& b, float t) {
    ShRgb r;
    for (int k = 0; k < kShCoefficients; ++k) r.c[k] = a.c[k] + t * (b.c[k] - a.c[k]);
    return r;
}

ShRgb hemisphereSh(const HemisphereAmbient& ambient) {
    ShRgb sh;
    sh.c[0] = glm::vec3(ambient.shBand0());
    sh.c[1] = glm::vec3(ambient.shVertical());
    return sh;
}

ShRgbD& ShRgbD::operator+=(const ShRgbD& o) {
    for (int k = 0; k < kShCoefficients; ++k) c[k] += o.c[k];
    return *this;
}
ShRgbD& ShRgbD::operator*=(double s) {
    for (auto& v : c) v *= s;
    return *this;
}
ShRgbD operator+(ShRgbD a, const ShRgbD& b) {
    return a += b;
}
ShRgbD operator*(ShRgbD a, double s) {
    return a *= s;
}

ShRgb toFloat(const ShRgbD& sh) {
    ShRgb r;
    for (int k = 0; k < kShCoefficients; ++k) r.c[k] = glm::vec3(sh.c[k]);
    return r;
}
ShRgbD toDouble(const ShRgb& sh) {
    ShRgbD r;
    for (int k = 0; k < kShCoefficients; ++k) r.c[k] = glm::dvec3(sh.c[k]);
    return r;
}

// ---- Basis and irradiance --------------------------------------------------------------------

namespace {

template <typename T>
std::array<T, kShCoefficients> basis(T x, T y, T z) {
    return {T(kShY00),
            T(kShY1) * y,
            T(kShY1) * z,
            T(kShY1) * x,
            T(kShY2a) * x * y,
            T(kShY2a) * y * z,
            T(kShY20) * (T(3) * z * z - T(1)),
            T(kShY2a) * x * z,
            T(kShY22) * (x * x - y * y)};
}

// Ahat_l per coefficient index.
constexpr std::array<double, kShCoefficients> kAhat = {kShA0, kShA1, kShA1, kShA1, kShA2,
                                                       kShA2, kShA2, kShA2, kShA2};

// Ramamoorthi & Hanrahan's constants, derived from the basis constants and Ahat:
// c1 = Ahat2 Y22, c2 = Ahat1 Y1 / 2, c3 = 3 Ahat2 Y20, c4 = Ahat0 Y00, c5 = Ahat2 Y20
// (0.429043, 0.511664, 0.743125, 0.886227, 0.247708).
constexpr double kC1 = kShA2 * kShY22;
constexpr double kC2 = kShA1 * kShY1 / 2.0;
constexpr double kC3 = 3.0 * kShA2 * kShY20;
constexpr double kC4 = kShA0 * kShY00;
constexpr double kC5 = kShA2 * kShY20;

// The quadratic form of one channel: E(n) = n^T A n + 2 b.n + d (rows of the R&H matrix).
struct Quadratic {
    glm::dmat3 a;
    glm::dvec3 b;
    double d;
    double operator()(const glm::dvec3& n) const {
        return glm::dot(n, a * n) + 2.0 * glm::dot(b, n) + d;
    }
};

// Coefficients of one channel (L_0 .. L_8) to the R&H matrix.
glm::dmat4 rhMatrix(const std::array<double, kShCoefficients>& l) {
    glm::dmat4 m;
    m[0] = {kC1 * l[8], kC1 * l[4], kC1 * l[7], kC2 * l[3]};
    m[1] = {kC1 * l[4], -kC1 * l[8], kC1 * l[5], kC2 * l[1]};
    m[2] = {kC1 * l[7], kC1 * l[5], kC3 * l[6], kC2 * l[2]};
    m[3] = {kC2 * l[3], kC2 * l[1], kC2 * l[2], kC4 * l[0] - kC5 * l[6]};
    return m;
}

std::array<double, kShCoefficients> channel(const ShRgbD& sh, int ch) {
    std::array<double, kShCoefficients> l;
    for (int k = 0; k < kShCoefficients; ++k) l[k] = sh.c[k][ch];
    return l;
}

Quadratic quadratic(const ShRgbD& sh, int ch) {
    const glm::dmat4 m = rhMatrix(channel(sh, ch));
    Quadratic q;
    q.a = glm::dmat3(m);
    q.b = glm::dvec3(m[3]);
    q.d = m[3][3];
    return q;
}

}  // namespace

std::array<double, kShCoefficients> shBasis(const glm::dvec3& d) {
    return basis(d.x, d.y, d.z);
}
std::array<float, kShCoefficients> shBasis(const glm::vec3& d) {
    return basis(d.x, d.y, d.z);
}

glm::dvec3 shIrradiance(const ShRgbD& sh, const glm::dvec3& normal) {
    const auto y = shBasis(normal);
    glm::dvec3 e(0.0);
    for (int k = 0; k < kShCoefficients; ++k) e += (kAhat[k] * y[k]) * sh.c[k];
    return e;
}

glm::vec3 shIrradiance(const ShRgb& sh, const glm::vec3& normal) {
    const auto y = shBasis(normal);
    glm::vec3 e(0.0f);
    for (int k = 0; k < kShCoefficients; ++k) e += (float(kAhat[k]) * y[k]) * sh.c[k];
    return e;
}

ShIrradianceMatrices shIrradianceMatrices(const ShRgb& sh) {
    const ShRgbD d = toDouble(sh);
    return {glm::mat4(rhMatrix(channel(d, 0))), glm::mat4(rhMatrix(channel(d, 1))),
            glm::mat4(rhMatrix(channel(d, 2)))};
}

glm::vec3 shIrradiance(const ShIrradianceMatrices& m, const glm::vec3& normal) {
    const glm::vec4 n(normal, 1.0f);
    return {glm::dot(n, m.r * n), glm::dot(n, m.g * n), glm::dot(n, m.b * n)};
}

void shIrradianceBatch(const ShRgb& sh, std::size_t count, const float* nx, const float* ny,
                       const float* nz, float* er, float* eg, float* eb) {
    // Per channel, E = k0 + k1 x + k2 y + k3 z + k4 xy + k5 yz + k6 xz + k7 (x^2 - y^2) + k8 z^2,
    // the expanded R&H form.
    float k[3][9];
    for (int ch = 0; ch < 3; ++ch) {
        auto l = [&](int i) { return double(sh.c[i][ch]); };
        k[ch][0] = float(kC4 * l(0) - kC5 * l(6));
        k[ch][1] = float(2.0 * kC2 * l(3));
        k[ch][2] = float(2.0 * kC2 * l(1));
        k[ch][3] = float(2.0 * kC2 * l(2));
        k[ch][4] = float(2.0 * kC1 * l(4));
        k[ch][5] = float(2.0 * kC1 * l(5));
        k[ch][6] = float(2.0 * kC1 * l(7));
        k[ch][7] = float(kC1 * l(8));
        k[ch][8] = float(kC3 * l(6));
    }
    float* out[3] = {er, eg, eb};
    for (int ch = 0; ch < 3; ++ch) {
        const float* kc = k[ch];
        float* __restrict e = out[ch];
        for (std::size_t i = 0; i < count; ++i) {
            const float x = nx[i], y = ny[i], z = nz[i];
            e[i] = kc[0] + kc[1] * x + kc[2] * y + kc[3] * z + kc[4] * (x * y) + kc[5] * (y * z) +
                   kc[6] * (x * z) + kc[7] * (x * x - y * y) + kc[8] * (z * z);
        }
    }
}

// ---- Extrema of the irradiance over the sphere -----------------------------------------------

glm::dvec3 fibonacciDirection(int i, int n) {
    const double golden = kPi * (3.0 - std::sqrt(5.0));
    const double z = 1.0 - (2.0 * i + 1.0) / n;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {r * std::cos(golden * i), r * std::sin(golden * i), z};
}

namespace {

// Minimum of a quadratic form over the unit sphere: the best of a Fibonacci sampling, refined by
// Riemannian Newton steps with backtracking (a decrease is required at every step).
double sphereMinimum(const Quadratic& q) {
    constexpr int kSamples = 768;
    constexpr int kStarts = 3;
    std::array<std::pair<double, glm::dvec3>, kStarts> best;
    best.fill({std::numeric_limits<double>::infinity(), glm::dvec3(0, 1, 0)});
    for (int i = 0; i < kSamples; ++i) {
        const glm::dvec3 n = fibonacciDirection(i, kSamples);
        const double f = q(n);
        if (f < best[kStarts - 1].first) {
            best[kStarts - 1] = {f, n};
            std::sort(best.begin(), best.end(),
                      [](const auto& a, const auto& b) { return a.first < b.first; });
        }
    }
    double result = best[0].first;
    for (auto [f, x] : best) {
        for (int it = 0; it < 50; ++it) {
            const glm::dvec3 g = 2.0 * (q.a * x + q.b);  // Euclidean gradient
            const glm::dvec3 helper =
                std::abs(x.x) < 0.6 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
            const glm::dvec3 t1 = glm::normalize(glm::cross(x, helper));
            const glm::dvec3 t2 = glm::cross(x, t1);
            const double xg = glm::dot(x, g);
            const double g1 = glm::dot(t1, g), g2 = glm::dot(t2, g);
            if (std::hypot(g1, g2) < 1e-300) break;
            // Riemannian Hessian in the tangent basis: t_i^T (2A) t_j - (x.g) delta_ij.
            const double h11 = 2.0 * glm::dot(t1, q.a * t1) - xg;
            const double h22 = 2.0 * glm::dot(t2, q.a * t2) - xg;
            const double h12 = 2.0 * glm::dot(t1, q.a * t2);
            const double det = h11 * h22 - h12 * h12;
            double s1, s2;
            if (h11 > 0.0 && det > 0.0) {
                s1 = -(h22 * g1 - h12 * g2) / det;
                s2 = -(h11 * g2 - h12 * g1) / det;
            } else {  // not convex here: steepest descent, scaled to a modest angle
                const double gn = std::hypot(g1, g2);
                s1 = -0.1 * g1 / gn;
                s2 = -0.1 * g2 / gn;
            }
            bool improved = false;
            for (int half = 0; half < 40; ++half) {
                const glm::dvec3 xn = glm::normalize(x + s1 * t1 + s2 * t2);
                const double fn = q(xn);
                if (fn < f) {
                    improved = fn < f - 1e-17 * (std::abs(f) + 1e-300);
                    x = xn;
                    f = fn;
                    break;
                }
                s1 *= 0.5;
                s2 *= 0.5;
            }
            if (!improved) break;
        }
        result = std::min(result, f);
    }
    return result;
}

}  // namespace

glm::dvec3 shMinIrradiance(const ShRgbD& sh) {
    glm::dvec3 m;
    for (int ch = 0; ch < 3; ++ch) m[ch] = sphereMinimum(quadratic(sh, ch));
    return m;
}

glm::dvec3 shMaxIrradiance(const ShRgbD& sh) {
    glm::dvec3 m;
    for (int ch = 0; ch < 3; ++ch) {
        Quadratic q = quadratic(sh, ch);
        q.a = -q.a;
        q.b = -q.b;
        q.d = -q.d;
        m[ch] = -sphereMinimum(q);
    }
    return m;
}

// ---- Windows and the automatic window --------------------------------------------------------

std::array<double, 3> ShWindow::bandFactors() const {
    if (kind == Kind::None) return {1.0, 1.0, 1.0};
    AMB_CHECK(width > 0.0 && std::isfinite(width));
    std::array<double, 3> h{};
    for (int l = 0; l < 3; ++l) {
        if (l >= width) {
            h[l] = 0.0;
        } else if (kind == Kind::Hanning) {
            h[l] = 0.5 * (1.0 + std::cos(kPi * l / width));
        } else {
            const double a = kPi * l / width;
            h[l] = l == 0 ? 1.0 : std::sin(a) / a;
        }
    }
    return h;
}

std::string ShWindow::name() const {
    if (kind == Kind::None) return "none";
    char buf[64];
    std::snprintf(buf, sizeof buf, "%s:%.17g", kind == Kind::Hanning ? "hanning" : "lanczos",
                  width);
    return buf;
}

ShRgbD shApplyWindow(const ShRgbD& sh, const ShWindow& window) {
    const auto h = window.bandFactors();
    ShRgbD r = sh;
    for (int k = 0; k < kShCoefficients; ++k) r.c[k] *= h[shBand(k)];
    return r;
}

namespace {

bool nonNegative(const ShRgbD& sh, const ShWindow& w) {
    const glm::dvec3 m = shMinIrradiance(shApplyWindow(sh, w));
    return m.x >= 0.0 && m.y >= 0.0 && m.z >= 0.0;
}

// Squared L2 distance (over the sphere of normals) between windowed and unwindowed irradiance:
// sum_k Ahat_l^2 (1 - h_l)^2 |L_k|^2, by orthonormality of the basis.
double irradianceChange(const ShRgbD& sh, const ShWindow& w) {
    const auto h = w.bandFactors();
    double d = 0.0;
    for (int k = 0; k < kShCoefficients; ++k) {
        const double a = kAhat[k] * (1.0 - h[shBand(k)]);
        d += a * a * glm::dot(sh.c[k], sh.c[k]);
    }
    return d;
}

// The weakest window of one family that keeps E >= 0: scan t = 1/W from weak (t -> 0) to strong
// on a grid (the minimum is not monotone in W: a strong window that kills band 2 before band 1
// rings again), then bisect between the last negative and the first non-negative grid point.
ShWindow weakestNonNegative(const ShRgbD& sh, ShWindow::Kind kind, double tMax) {
    constexpr int kSteps = 48;
    auto make = [&](double t) { return ShWindow{kind, 1.0 / t}; };
    double lo = 0.0;
    for (int s = 1; s <= kSteps; ++s) {
        const double t = tMax * s / kSteps;
        if (nonNegative(sh, make(t))) {
            double hi = t;
            for (int it = 0; it < 30; ++it) {
                const double mid = 0.5 * (lo + hi);
                (nonNegative(sh, make(mid)) ? hi : lo) = mid;
            }
            return make(hi);
        }
        lo = t;
    }
    return make(tMax);
}

}  // namespace

ShWindow shAutoWindow(const ShRgbD& sh) {
    if (nonNegative(sh, ShWindow::none())) return ShWindow::none();
    // Hanning W = 2 (t = 1/2) and Lanczos W = 1.6 (t = 0.625, h_1 = 0.47, h_2 = 0) keep any
    // non-negative radiance non-negative (h_1 <= 1/2 with h_2 = 0 suffices).
    const ShWindow hanning = weakestNonNegative(sh, ShWindow::Kind::Hanning, 0.5);
    const ShWindow lanczos = weakestNonNegative(sh, ShWindow::Kind::Lanczos, 0.625);
    return irradianceChange(sh, lanczos) < irradianceChange(sh, hanning) ? lanczos : hanning;
}

// ---- Directional lights ----------------------------------------------------------------------

glm::dvec3 directionalIrradiance(const DirectionalLight& light, const glm::dvec3& normal) {
    return light.irradiance * std::max(0.0, glm::dot(normal, light.direction));
}

void shAddDirectional(ShRgbD& sh, const DirectionalLight& light, double scale) {
    const auto y = shBasis(glm::normalize(light.direction));
    for (int k = 0; k < kShCoefficients; ++k) sh.c[k] += (scale * y[k]) * light.irradiance;
}

}  // namespace amb
