// Conventions.h — the project's conventions, stated once (docs/ARCHITECTURE.md, "Conventions").
//
// [SECTION] Axes and units
//   Right-handed, +Y up, metres, seconds, radians. The ground plane is XZ; heights are h(x, z).
//   World positions are double (the world is open; replays may run 10^6 m from the origin);
//   render code uses camera-relative float. Lattice keys are integers, never floats.
//   Time of day is in hours [0, 24); simulation time advances in fixed steps (replay dt).
//   Parameters carry their unit in the name: _m (metres), _s (seconds), _h (hours),
//   _mps (metres per second), _rad (radians), _deg (degrees, only at the user interface).
//
// [SECTION] Radiance
//   Linear HDR float RGB. The sun may be ~10^5 times the sky; tone mapping happens only at display.
//   Units: the sky model's cd/m^2 over a luminous efficacy of 100 lm/W, roughly W sr^-1 m^-2
//   (world/Sky.h). Luminance = Rec. 709 weights (0.2126, 0.7152, 0.0722) . linear RGB.
//   The sun disc is in one cube-map texel, known by its direction (lighting/SunTexel.h).
//   The distant ground below the horizon is flat and Lambertian with albedo kGroundAlbedo
//   (world/SkyGround.h). shaders/conventions.glsl repeats pi, the weights and the albedo;
//   tests/world/Conventions_test.cpp checks that the two agree.
//
// [SECTION] Spherical harmonics
//   Real order-2 SH, 9 coefficients per channel, index k = l(l+1)+m, Ramamoorthi-Hanrahan basis
//   without Condon-Shortley phase, (x, y, z) the unit world direction:
//     Y00 = 0.282095; Y1-1 = 0.488603 y; Y10 = 0.488603 z; Y11 = 0.488603 x;
//     Y2-2 = 1.092548 xy; Y2-1 = 1.092548 yz; Y20 = 0.315392 (3z^2 - 1);
//     Y21 = 1.092548 xz; Y22 = 0.546274 (x^2 - y^2).
//   Coefficients L_k = integral of L(w) Y_k(w) dw over steradians (no 1/4pi): constant radiance c
//   gives L00 = 2 sqrt(pi) c. Irradiance E(n) = sum_k Ahat_l L_k Y_k(n), Ahat = (pi, 2pi/3, pi/4),
//   equal to R&H's n^T M n; constant c gives E = pi c.
//
// [SECTION] Cube maps
//   OpenGL face order +X, -X, +Y, -Y, +Z, -Z. For texel (column i, row j) of an N x N face,
//   u = 2(i + 1/2)/N - 1, v = 2(j + 1/2)/N - 1, and the (unnormalised) world direction is
//     +X: ( 1, -v, -u)   -X: (-1, -v,  u)   +Y: ( u,  1,  v)
//     -Y: ( u, -1, -v)   +Z: ( u, -v,  1)   -Z: (-u, -v, -1)
//   Row 0 is the first row given to glTexImage2D. As a file, a cube map is one image (EXR for HDR)
//   of width N and height 6N, faces stacked vertically in that order, face row 0 at the top.
#pragma once

#include <array>
#include <cstdint>

#include <glm/vec3.hpp>

namespace amb {

// ---- Pi, luminance, ground, sun --------------------------------------------------------------
inline constexpr double kPi = 3.14159265358979323846;
// Rec. 709 luminance weights of linear RGB (R, G, B).
inline constexpr double kLuminanceWeights[3] = {0.2126, 0.7152, 0.0722};
// Luminance of a linear RGB value, in the precision of its components.
template <typename T, glm::qualifier Q>
constexpr T luminance(const glm::vec<3, T, Q>& rgb) {
    return T(kLuminanceWeights[0]) * rgb.r + T(kLuminanceWeights[1]) * rgb.g +
           T(kLuminanceWeights[2]) * rgb.b;
}
// Albedo of the flat Lambertian ground below the horizon (the fallback scene, the sky texture's
// lower half, the hemisphere ambient). A float, as the fallback has always read it.
inline constexpr float kGroundAlbedo = 0.2f;
// Luminance radiance [W sr^-1 m^-2] that once told the sun's cube-map texel (a low sun's 16^2
// texel stays under it: the texel is now found by the sun's direction, docs/ARCHITECTURE.md
// "Spherical harmonics"). The default of the retired `sunThreshold` settings.
inline constexpr double kSunThreshold_Wpsrm2 = 5000.0;

// ---- SH constants (full precision) ----------------------------------------------------------
inline constexpr int kShCoefficients = 9;  // order 2: bands l = 0, 1, 2
inline constexpr double kShY00 = 0.28209479177387814347;  // 1 / (2 sqrt(pi))
inline constexpr double kShY1 = 0.48860251190291992159;   // sqrt(3 / (4 pi))
inline constexpr double kShY2a = 1.09254843059207907054;  // sqrt(15 / (4 pi))
inline constexpr double kShY20 = 0.31539156525252000603;  // sqrt(5 / (16 pi))
inline constexpr double kShY22 = 0.54627421529603953527;  // sqrt(15 / (16 pi))
// Convolution with the clamped cosine, per band: Ahat_l.
inline constexpr double kShA0 = kPi;
inline constexpr double kShA1 = 2.0 * kPi / 3.0;
inline constexpr double kShA2 = kPi / 4.0;

// ---- Cube-map faces --------------------------------------------------------------------------
enum class CubeFace : int { PosX = 0, NegX = 1, PosY = 2, NegY = 3, PosZ = 4, NegZ = 5 };
inline constexpr int kCubeFaces = 6;

// Unnormalised world direction through face coordinates (u, v) in [-1, 1], per the table above.
inline glm::dvec3 cubeFaceDirection(int face, double u, double v) {
    switch (face) {
        case 0: return {1.0, -v, -u};
        case 1: return {-1.0, -v, u};
        case 2: return {u, 1.0, v};
        case 3: return {u, -1.0, -v};
        case 4: return {u, -v, 1.0};
        default: return {-u, -v, -1.0};
    }
}

// Unnormalised world direction through the centre of texel (column i, row j) of an N x N face.
inline glm::dvec3 cubeTexelDirection(int face, int i, int j, int n) {
    const double u = 2.0 * (i + 0.5) / n - 1.0;
    const double v = 2.0 * (j + 0.5) / n - 1.0;
    return cubeFaceDirection(face, u, v);
}

}  // namespace amb
