// CubeMapProjector_test.cpp — cube-map projection against closed forms: solid angles, constant
// radiance, sky/ground, face orientation, a bright disc (Funk-Hecke), accumulation over a wide
// dynamic range, incremental faces, bad texels and sun extraction. Tolerances stated per test.
#include "lighting/CubeMapProjector.h"

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

namespace amb {
namespace {

using RadianceFn = std::function<glm::dvec3(const glm::dvec3& dir)>;

// A cube map sampled at texel centres from a radiance function of the unit direction.
std::vector<float> makeMap(int n, const RadianceFn& radiance) {
    std::vector<float> rgb(std::size_t(6) * n * n * 3);
    for (int f = 0; f < 6; ++f)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const glm::dvec3 l = radiance(glm::normalize(cubeTexelDirection(f, i, j, n)));
                const std::size_t t = (std::size_t(f) * n + j) * n + i;
                for (int c = 0; c < 3; ++c) rgb[3 * t + c] = float(l[c]);
            }
    return rgb;
}

// The same with each texel the solid-angle-weighted mean of s x s sub-samples (what a renderer
// with s^2 samples per texel gives), so a hard edge is not aliased by centre sampling.
std::vector<float> makeMapSupersampled(int n, int s, const RadianceFn& radiance) {
    std::vector<float> rgb(std::size_t(6) * n * n * 3);
    for (int f = 0; f < 6; ++f)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                glm::dvec3 sum(0.0);
                double weight = 0.0;
                for (int b = 0; b < s; ++b)
                    for (int a = 0; a < s; ++a) {
                        const double u = 2.0 * (i + (a + 0.5) / s) / n - 1.0;
                        const double v = 2.0 * (j + (b + 0.5) / s) / n - 1.0;
                        const glm::dvec3 d = cubeFaceDirection(f, u, v);
                        const double w = 1.0 / std::pow(glm::dot(d, d), 1.5);  // d omega / du dv
                        sum += w * radiance(glm::normalize(d));
                        weight += w;
                    }
                const std::size_t t = (std::size_t(f) * n + j) * n + i;
                for (int c = 0; c < 3; ++c) rgb[3 * t + c] = float(sum[c] / weight);
            }
    return rgb;
}

ShRgbD project(int n, const std::vector<float>& rgb) {
    return projectCubeMap(n, rgb).sh;
}

// Texel solid angles sum to 4 pi (1e-12 relative); N = 1 gives 4 pi / 6 per texel; the corner
// texel of a large face is smaller than the centre texel by the cube's 3 sqrt(3) distortion.
TEST(CubeMapProjector, SolidAnglesSumToSphere) {
    for (int n : {1, 2, 3, 16, 255}) {
        double sum = 0.0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) sum += cubeTexelSolidAngle(i, j, n);
        EXPECT_NEAR(6.0 * sum, 4.0 * kPi, 1e-12 * 4.0 * kPi) << n;
    }
    EXPECT_NEAR(cubeTexelSolidAngle(0, 0, 1), 4.0 * kPi / 6.0, 1e-14);
    const int n = 10001;  // the ratio tends to 3 sqrt(3) as O(1/N)
    EXPECT_NEAR(cubeTexelSolidAngle(5000, 5000, n) / cubeTexelSolidAngle(0, 0, n),
                3.0 * std::sqrt(3.0), 3e-3);
}

// Constant radiance c: L00 = 2 sqrt(pi) c (1e-6 relative), other coefficients below 1e-6 L00,
// E = pi c for every normal (1e-6 relative), for N = 1, 2, 16, 256 (table and streaming paths).
TEST(CubeMapProjector, ConstantRadiance) {
    const glm::dvec3 c(0.5, 1.0, 2.0);
    for (int n : {1, 2, 16, 256}) {
        const ShRgbD sh = project(n, makeMap(n, [&](const glm::dvec3&) { return c; }));
        for (int ch = 0; ch < 3; ++ch) {
            EXPECT_NEAR(sh.c[0][ch], 2.0 * std::sqrt(kPi) * c[ch], 1e-6 * sh.c[0][ch]) << n;
            for (int k = 1; k < 9; ++k) EXPECT_NEAR(sh.c[k][ch], 0.0, 1e-6 * sh.c[0][ch]) << n;
        }
        std::mt19937 rng(n);
        std::normal_distribution<double> g;
        for (int i = 0; i < 20; ++i) {
            const glm::dvec3 normal = glm::normalize(glm::dvec3(g(rng), g(rng), g(rng)));
            const glm::dvec3 e = shIrradiance(sh, normal);
            for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(e[ch], kPi * c[ch], 1e-6 * kPi * c[ch]);
        }
    }
}

// Sky S above the horizon, ground G = S / 10 below: exactly L00 = sqrt(pi) (S + G) and L1,-1 =
// Y1 pi (S - G), all else 0, and E(n) = pi (S (1 + n_y) + G (1 - n_y)) / 2. The error is the
// largest over normals of |E - E_exact| / E_exact. With exact solid angles a 16 x 16 map is within
// 0.7 %; with the thesis' equal weights (4 pi / 6N^2) it is > 10 % off (facing the ground).
TEST(CubeMapProjector, SkyAndGround) {
    const double S = 1.0, G = 0.1;
    const int n = 16;
    const auto rgb = makeMap(n, [&](const glm::dvec3& d) { return glm::dvec3(d.y > 0 ? S : G); });
    const ShRgbD sh = project(n, rgb);
    EXPECT_NEAR(sh.c[0].x, std::sqrt(kPi) * (S + G), 1e-6);
    EXPECT_NEAR(sh.c[1].x, kShY1 * kPi * (S - G), 5e-3 * kShY1 * kPi * (S - G));
    for (int k : {2, 3, 4, 5, 6, 7, 8}) EXPECT_NEAR(sh.c[k].x, 0.0, 1e-6) << k;

    // The same projection with the thesis' equal weights, in double.
    ShRgbD equal;
    for (int f = 0; f < 6; ++f)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const glm::dvec3 d = glm::normalize(cubeTexelDirection(f, i, j, n));
                const auto y = shBasis(d);
                const double l = rgb[3 * ((std::size_t(f) * n + j) * n + i)];
                for (int k = 0; k < 9; ++k)
                    equal.c[k] += glm::dvec3(4.0 * kPi / (6 * n * n) * l * y[k]);
            }

    double worstExact = 0.0, worstEqual = 0.0;
    for (int a = 0; a <= 180; ++a) {
        const double t = a * kPi / 180.0;
        const glm::dvec3 normal(std::sin(t) * 0.6, std::cos(t), std::sin(t) * 0.8);
        const double exact = kPi * (S * (1 + normal.y) + G * (1 - normal.y)) / 2.0;
        worstExact = std::max(worstExact, std::abs(shIrradiance(sh, normal).x - exact) / exact);
        worstEqual = std::max(worstEqual, std::abs(shIrradiance(equal, normal).x - exact) / exact);
    }
    EXPECT_LT(worstExact, 7e-3);
    EXPECT_GT(worstEqual, 0.10);
}

// A map bright only on one face: the band-1 coefficient of that face's axis has the face's sign
// and dominates the other two (which vanish by symmetry, 1e-6); a map bright only in texel
// (0, 0) of a face gives the signs of the table in docs/ARCHITECTURE.md ("Cube maps") at u, v < 0,
// which catches a flipped or transposed face.
TEST(CubeMapProjector, FaceOrientation) {
    const int n = 8;
    // Band-1 indices: k = 3 (x), 1 (y), 2 (z); expected sign per face of the face's axis.
    const int axisK[6] = {3, 3, 1, 1, 2, 2};
    const double axisSign[6] = {1, -1, 1, -1, 1, -1};
    // Texel (0, 0): u = v = -1 + 1/n < 0. Direction signs from the table:
    // +X (1,-v,-u) = (+,+,+)  -X (-1,-v,u) = (-,+,-)  +Y (u,1,v) = (-,+,-)
    // -Y (u,-1,-v) = (-,-,+)  +Z (u,-v,1) = (-,+,+)   -Z (-u,-v,-1) = (+,+,-)
    const double cornerSigns[6][3] = {{1, 1, 1},   {-1, 1, -1}, {-1, 1, -1},
                                      {-1, -1, 1}, {-1, 1, 1},  {1, 1, -1}};
    for (int face = 0; face < 6; ++face) {
        std::vector<float> rgb(std::size_t(6) * n * n * 3, 0.0f);
        for (int t = 0; t < n * n; ++t)
            for (int c = 0; c < 3; ++c) rgb[3 * (std::size_t(face) * n * n + t) + c] = 1.0f;
        const ShRgbD sh = project(n, rgb);
        for (int k = 1; k <= 3; ++k) {
            if (k == axisK[face]) {
                EXPECT_GT(axisSign[face] * sh.c[k].x, 0.1) << face;
            } else {
                EXPECT_NEAR(sh.c[k].x, 0.0, 1e-6) << face << k;
            }
        }

        std::fill(rgb.begin(), rgb.end(), 0.0f);
        rgb[3 * std::size_t(face) * n * n] = 1.0f;
        const ShRgbD corner = project(n, rgb);
        EXPECT_GT(cornerSigns[face][0] * corner.c[3].x, 0.0) << face;  // x
        EXPECT_GT(cornerSigns[face][1] * corner.c[1].x, 0.0) << face;  // y
        EXPECT_GT(cornerSigns[face][2] * corner.c[2].x, 0.0) << face;  // z
    }
}

// Funk-Hecke coefficients of a disc of radiance 1 and angular radius alpha around unit d.
ShRgbD discSh(const glm::dvec3& d, double alpha) {
    const double c = std::cos(alpha);
    const double band[3] = {1.0 - c, (1.0 - c * c) / 2.0, c * (1.0 - c * c) / 2.0};
    const auto y = shBasis(d);
    ShRgbD sh;
    for (int k = 0; k < 9; ++k) sh.c[k] = glm::dvec3(2.0 * kPi * band[shBand(k)] * y[k]);
    return sh;
}

// A bright disc (radius 20 degrees, radiance 100, off-axis) against its analytic SH, the map
// rendered with 16 x 16 (N = 16) or 2 x 2 (N = 256) samples per texel. What remains is the
// variation of the basis across a texel and the sub-sampling of the edge. Tolerance on every
// coefficient: 1 % of L00 at N = 16 (texel 5.6 degrees), 0.1 % at N = 256.
TEST(CubeMapProjector, BrightDiscAgainstFunkHecke) {
    const glm::dvec3 d = glm::normalize(glm::dvec3(0.3, 0.8, -0.5));
    const double alpha = 20.0 * kPi / 180.0;
    const ShRgbD exact = discSh(d, alpha) * 100.0;
    for (auto [n, tol] : {std::pair{16, 0.01}, std::pair{256, 0.001}}) {
        const ShRgbD sh =
            project(n, makeMapSupersampled(n, n == 16 ? 16 : 2, [&](const glm::dvec3& w) {
                        return glm::dvec3(glm::dot(w, d) > std::cos(alpha) ? 100.0 : 0.0);
                    }));
        for (int k = 0; k < 9; ++k) {
            EXPECT_NEAR(sh.c[k].y, exact.c[k].y, tol * exact.c[0].y) << "N=" << n << " k=" << k;
        }
    }
}

// Values spanning 1e-6 .. 1e6 (log-uniform per texel and channel) against a long double reference
// computed here from the same solid-angle formula and basis.
// - N = 1024 (streaming path, double products and sums): every coefficient to 1e-6 relative.
// - N = 64 (the largest table path: float basis textures and products, float partial sums of at
//   most 32 products flushed into double): every coefficient within 1e-6 of its condition scale
//   sum_t |omega_t Y_k(t) L_t| (float rounding of a product is 6e-8 of that product, and random
//   data makes band-1 and band-2 sums cancel far below that scale).
TEST(CubeMapProjector, AccumulationOverWideRange) {
    static_assert(CubeMapProjector::kTableMaxFaceSize == 64);
    for (int n : {64, 1024}) {
        std::mt19937 rng(11);
        std::uniform_real_distribution<double> e(-6.0, 6.0);
        std::vector<float> rgb(std::size_t(6) * n * n * 3);
        for (auto& v : rgb) v = float(std::pow(10.0, e(rng)));
        long double ref[9][3] = {}, scale[9][3] = {};
        for (int f = 0; f < 6; ++f)
            for (int j = 0; j < n; ++j)
                for (int i = 0; i < n; ++i) {
                    const double omega = cubeTexelSolidAngle(i, j, n);
                    const auto y = shBasis(glm::normalize(cubeTexelDirection(f, i, j, n)));
                    const float* p = &rgb[3 * ((std::size_t(f) * n + j) * n + i)];
                    for (int k = 0; k < 9; ++k)
                        for (int c = 0; c < 3; ++c) {
                            const long double term = (long double)omega * y[k] * (long double)p[c];
                            ref[k][c] += term;
                            scale[k][c] += std::fabs(term);
                        }
                }
        const ShRgbD sh = project(n, rgb);
        for (int k = 0; k < 9; ++k)
            for (int c = 0; c < 3; ++c) {
                const double r = double(ref[k][c]);
                const double tol = n > CubeMapProjector::kTableMaxFaceSize
                                       ? 1e-6 * std::abs(r)
                                       : 1e-6 * double(scale[k][c]);
                EXPECT_NEAR(sh.c[k][c], r, tol) << "N=" << n << " k=" << k;
            }
    }
}

// The AVX2 and portable table kernels agree (1e-6 of the condition scale, see above) for sizes
// with and without a partial block, with clean data and with bad and sun texels.
TEST(CubeMapProjector, VectorAndPortableKernelsAgree) {
    for (int n : {1, 3, 16, 17, 32, 64}) {
        std::mt19937 rng(n);
        std::uniform_real_distribution<float> u(0.0f, 4.0f);
        std::vector<float> rgb(std::size_t(6) * n * n * 3);
        for (auto& v : rgb) v = u(rng);
        for (bool dirty : {false, true}) {
            if (dirty) {
                rgb[1] = -1.0f;
                rgb[rgb.size() - 1] = 1e6f;
            }
            CubeMapProjector::Options fast, portable;
            fast.sunThreshold = portable.sunThreshold = 1e3;
            portable.allowAvx2 = false;
            const CubeMapProjection a = projectCubeMap(n, rgb, fast);
            const CubeMapProjection b = projectCubeMap(n, rgb, portable);
            EXPECT_EQ(a.badTexels, b.badTexels);
            EXPECT_EQ(a.badTexels, dirty ? 1 : 0);
            EXPECT_EQ(a.sun.irradiance.x, b.sun.irradiance.x);
            for (int k = 0; k < 9; ++k)
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(a.sh.c[k][c], b.sh.c[k][c], 1e-6 * 4.0 * 4.0 * kPi) << n << k;
        }
    }
}

// Faces added one per "frame", in any order, give the whole-map result (1e-12 relative);
// re-adding a face replaces it; complete() only after six distinct faces.
TEST(CubeMapProjector, IncrementalFaces) {
    const int n = 16;
    const auto rgb = makeMap(n, [](const glm::dvec3& d) {
        return glm::dvec3(1.0 + d.x, 2.0 + d.y * d.z, 0.5 + d.z * d.z);
    });
    const ShRgbD whole = project(n, rgb);
    CubeMapProjector p(n);
    const int order[6] = {4, 1, 5, 0, 3, 2};
    const std::vector<float> zeros(std::size_t(n) * n * 3, 0.0f);
    p.addFace(2, zeros.data());  // stale content, replaced by the last addFace below
    for (int i = 0; i < 6; ++i) {
        p.addFace(order[i], rgb.data() + std::size_t(order[i]) * n * n * 3);
        EXPECT_EQ(p.facesAdded(), std::min(i + 2, 6));
        EXPECT_EQ(p.complete(), i >= 4);
    }
    EXPECT_TRUE(p.complete());
    const ShRgbD sh = p.coefficients();
    for (int k = 0; k < 9; ++k)
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(sh.c[k][c], whole.c[k][c], 1e-12 * std::abs(whole.c[0][c]));
    p.reset();
    EXPECT_EQ(p.facesAdded(), 0);
}

// Bad-texel policy: NaN, +-Inf and negative texels contribute nothing and are counted; the
// result equals the map with those texels black (1e-12 relative) and stays finite. Both paths.
TEST(CubeMapProjector, BadTexelsAreZeroedAndCounted) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    for (int n : {15, 16, 200}) {
        auto rgb = makeMap(n, [](const glm::dvec3& d) { return glm::dvec3(2.0 + d.x, 1.0, 3.0); });
        auto clean = rgb;
        const std::size_t bad[4] = {5, std::size_t(n) * n + 7, 3 * std::size_t(n) * n + 1,
                                    6 * std::size_t(n) * n - 1};
        const float values[4] = {nan, inf, -inf, -0.5f};
        for (int i = 0; i < 4; ++i) {
            rgb[3 * bad[i] + (i % 3)] = values[i];
            for (int c = 0; c < 3; ++c) clean[3 * bad[i] + c] = 0.0f;
        }
        rgb[3 * 9] = clean[3 * 9] = -0.0f;  // negative zero is a usable zero, not a bad texel
        const CubeMapProjection result = projectCubeMap(n, rgb);
        const ShRgbD expected = project(n, clean);
        EXPECT_EQ(result.badTexels, 4);
        for (int k = 0; k < 9; ++k)
            for (int c = 0; c < 3; ++c) {
                EXPECT_TRUE(std::isfinite(result.sh.c[k][c]));
                EXPECT_NEAR(result.sh.c[k][c], expected.c[k][c], 1e-12 * expected.c[0][c]);
            }
    }
}

// Sun extraction: a sky of 1 plus one texel of 1e5. With a threshold of 100 the texel becomes a
// directional light (irradiance 1e5 omega, direction the texel's, 1e-12 relative) and the SH is
// the sky without that texel; without a threshold it stays in the SH.
TEST(CubeMapProjector, SunExtraction) {
    for (int n : {13, 16, 160}) {
        const int face = 2, i = n / 3, j = n / 4;
        auto rgb = makeMap(n, [](const glm::dvec3&) { return glm::dvec3(1.0); });
        auto skyOnly = rgb;
        const std::size_t t = (std::size_t(face) * n + j) * n + i;
        for (int c = 0; c < 3; ++c) {
            rgb[3 * t + c] = 1e5f;
            skyOnly[3 * t + c] = 0.0f;
        }
        CubeMapProjector::Options options;
        options.sunThreshold = 100.0;
        const CubeMapProjection result = projectCubeMap(n, rgb, options);
        const double omega = cubeTexelSolidAngle(i, j, n);
        const glm::dvec3 dir = glm::normalize(cubeTexelDirection(face, i, j, n));
        EXPECT_NEAR(result.sun.irradiance.x, 1e5 * omega, 1e-12 * 1e5 * omega);
        EXPECT_NEAR(glm::length(result.sun.direction - dir), 0.0, 1e-12);
        const ShRgbD sky = project(n, skyOnly);
        for (int k = 0; k < 9; ++k) EXPECT_NEAR(result.sh.c[k].y, sky.c[k].y, 1e-9);

        const CubeMapProjection kept = projectCubeMap(n, rgb);
        EXPECT_EQ(kept.sun.irradiance.x, 0.0);
        EXPECT_NEAR(kept.sh.c[0].x, sky.c[0].x + 1e5 * omega * kShY00, 1e-6 * kept.sh.c[0].x);
    }
}

}  // namespace
}  // namespace amb
