// SH.h — order-2 real spherical harmonics: basis, coefficient sets, irradiance, deringing.
//
// Conventions (basis, index order k = l(l+1)+m, normalisation, Ahat) are those of
// world/Conventions.h: Ramamoorthi-Hanrahan basis without Condon-Shortley phase, coefficients
// L_k = integral of L(w) Y_k(w) dw, irradiance E(n) = sum_k Ahat_l L_k Y_k(n) = n^T M n.
//
// [SECTION] Coefficient sets      ShRgb (float, stored and blended), ShRgbD (double, analysis)
// [SECTION] Basis                 shBasis
// [SECTION] Irradiance            shIrradiance (direct), shIrradianceMatrices (R&H 4x4, for
//                                 shaders/sh_irradiance.glsl), shIrradianceBatch (SoA, float)
// [SECTION] Ringing               ShWindow (Hanning, Lanczos), shApplyWindow, shAutoWindow,
//                                 shMinIrradiance / shMaxIrradiance over the sphere of normals
// [SECTION] Directional lights    DirectionalLight, shAddDirectional (the sun taken out of the SH
//                                 and lit exactly, thesis 10.2: the sun is ~10^5 x the sky)
#pragma once

#include <array>
#include <cstddef>
#include <string>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "world/Conventions.h"
#include "world/DirectionalLight.h"

namespace amb {

// ---- Coefficient sets ------------------------------------------------------------------------

// Nine RGB coefficients (radiance x steradian) in float: what anchors store, blend and upload.
struct ShRgb {
    std::array<glm::vec3, kShCoefficients> c{};

    ShRgb& operator+=(const ShRgb& o);
    ShRgb& operator*=(float s);
};
ShRgb operator+(ShRgb a, const ShRgb& b);
ShRgb operator-(const ShRgb& a, const ShRgb& b);
ShRgb operator*(ShRgb a, float s);
// (1 - t) a + t b, per coefficient (the thesis' per-coefficient linear interpolation, 9.3).
ShRgb lerp(const ShRgb& a, const ShRgb& b, float t);

struct HemisphereAmbient;
// The SH of a hemisphere ambient (world/SkyGround.h): its sky over y > 0, its ground below.
ShRgb hemisphereSh(const HemisphereAmbient& ambient);

// The same in double: what projection produces and what analysis (windows, minima) works on.
struct ShRgbD {
    std::array<glm::dvec3, kShCoefficients> c{};

    ShRgbD& operator+=(const ShRgbD& o);
    ShRgbD& operator*=(double s);
};
ShRgbD operator+(ShRgbD a, const ShRgbD& b);
ShRgbD operator*(ShRgbD a, double s);

ShRgb toFloat(const ShRgbD& sh);
ShRgbD toDouble(const ShRgb& sh);

// ---- Basis -----------------------------------------------------------------------------------

// Y_k(dir) for k = 0..8; `dir` must be a unit vector.
std::array<double, kShCoefficients> shBasis(const glm::dvec3& dir);
std::array<float, kShCoefficients> shBasis(const glm::vec3& dir);

// Band l of coefficient index k (0 for k = 0, 1 for k = 1..3, 2 for k = 4..8).
inline int shBand(int k) {
    return k == 0 ? 0 : (k < 4 ? 1 : 2);
}

// ---- Irradiance ------------------------------------------------------------------------------

// E(n) = sum_k Ahat_l L_k Y_k(n) for a unit normal n (radiance units x steradian, e.g. W/m^2
// when L is in W/(m^2 sr)). Not clamped: ringing may make it negative.
glm::dvec3 shIrradiance(const ShRgbD& sh, const glm::dvec3& normal);
glm::vec3 shIrradiance(const ShRgb& sh, const glm::vec3& normal);

// Ramamoorthi & Hanrahan's symmetric 4x4 matrices, one per channel: E(n) = (n,1)^T M (n,1).
// glm stores them column-major, as GLSL does; they are symmetric so the order does not matter.
struct ShIrradianceMatrices {
    glm::mat4 r{0.0f}, g{0.0f}, b{0.0f};
};
ShIrradianceMatrices shIrradianceMatrices(const ShRgb& sh);
glm::vec3 shIrradiance(const ShIrradianceMatrices& m, const glm::vec3& normal);

// Batch evaluation for many unit normals, structure of arrays: normal i is (nx[i], ny[i], nz[i]),
// its irradiance goes to (er[i], eg[i], eb[i]). Float throughout; the loop vectorises.
void shIrradianceBatch(const ShRgb& sh, std::size_t count, const float* nx, const float* ny,
                       const float* nz, float* er, float* eg, float* eb);

// ---- Ringing: windows and extrema ------------------------------------------------------------

// A per-band window h_l multiplied into the coefficients before evaluation (Sloan, "Stupid
// spherical harmonics tricks", 2008). With width W > 0, for l < W (else 0):
//   Hanning:  h_l = (1 + cos(pi l / W)) / 2
//   Lanczos:  h_l = sin(pi l / W) / (pi l / W)         (h_0 = 1)
// A larger W is a weaker window (W -> infinity is no window).
struct ShWindow {
    enum class Kind { None, Hanning, Lanczos };
    Kind kind = Kind::None;
    double width = 0.0;  // W, in bands; ignored for None

    static ShWindow none() { return {}; }
    static ShWindow hanning(double width) { return {Kind::Hanning, width}; }
    static ShWindow lanczos(double width) { return {Kind::Lanczos, width}; }

    // h_0, h_1, h_2. AMB_CHECKs width > 0 for Hanning and Lanczos.
    std::array<double, 3> bandFactors() const;
    // "none", "hanning:W", "lanczos:W" — the syntax of `ambience sh project --window`.
    std::string name() const;
};

ShRgbD shApplyWindow(const ShRgbD& sh, const ShWindow& window);

// The i-th of n directions of a Fibonacci (golden-angle) lattice on the sphere, about +Z: nearly
// uniform, for sampling functions over the sphere of normals.
glm::dvec3 fibonacciDirection(int i, int n);

// Minimum / maximum of E(n) over all unit normals, per channel, found by a dense Fibonacci
// sampling refined by projected Newton steps on the sphere (the quadratic form is smooth, so the
// refined value is accurate to ~1e-12 relative of the form's scale).
glm::dvec3 shMinIrradiance(const ShRgbD& sh);
glm::dvec3 shMaxIrradiance(const ShRgbD& sh);

// The weakest window under which the irradiance of every channel is >= 0 for every normal, or
// ShWindow::none() when no window is needed. For each family (Hanning, Lanczos) the largest W
// that keeps E >= 0 is found by a scan from weak to strong refined by bisection (E_min is not
// monotone in W); of the two, the one that changes the irradiance least (L2 over the sphere) is
// returned. Hanning W = 2 (h_1 = 1/2, h_2 = 0) keeps E >= 0 for any non-negative radiance; for
// other coefficient sets (L00 < 0) the strongest window of the scan is returned.
ShWindow shAutoWindow(const ShRgbD& sh);

// ---- Directional lights ----------------------------------------------------------------------

// A distant light (world/DirectionalLight.h) kept out of the SH and lit exactly:
// E(n) = irradiance max(0, n.dir).
glm::dvec3 directionalIrradiance(const DirectionalLight& light, const glm::dvec3& normal);

// Adds (scale = +1) or removes (scale = -1) the SH projection of a directional light (a delta of
// the given irradiance): L_k += scale irradiance Y_k(direction).
void shAddDirectional(ShRgbD& sh, const DirectionalLight& light, double scale = 1.0);

}  // namespace amb
