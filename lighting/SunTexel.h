// SunTexel.h — the sun disc in a cube map, as a known direction: the texel a capture puts it in,
// and that texel given back its sky, the same way at every face size.
//
// [SECTION] Where the disc goes
//   The disc (angular radius 0.27 degrees, Sky::sunAngularRadius_rad) is far smaller than a
//   texel at the face sizes used (16 to 64: 5.6 to 1.4 degrees at a face's centre), so a
//   capture (CubeCapture.h) does not draw it: it adds its whole energy to the one texel that
//   holds the sun direction (sunTexel), when that texel sees sky. The texel gains
//       disc radiance x disc solid angle / texel solid angle      (sunTexelRadiance),
//   so the projection keeps the sun's irradiance exactly. No other texel gets any of it.
// [SECTION] Why not a luminance threshold
//   That gain grows with 1 / texel solid angle, 16 x from 16^2 to 64^2. The sun 3.7 degrees up
//   (the ravine-dusk replay: the disc reddened and dimmed by the air mass) gives a 16^2 texel of
//   luminance ~4600 and a 64^2 texel of ~7e4, so a threshold of 5000 left the sun in the
//   methods' SH and out of the reference's. Nothing else in a capture comes near it (the
//   brightest sky at any latitude and hour is ~300 W sr^-1 m^-2; sunlit ground less), so no
//   luminance guard is kept (CubeMapProjector::Options::sunThreshold stays, off, for cube maps of
//   unknown origin and the ringing study).
// [SECTION] Leaving it out
//   Whoever leaves the sun out of the SH (the projector, the reference oracle) is told the sun
//   direction of the capture (CubeCapture::sunDirection) and replaces that texel, whether the
//   disc was added or hidden, with its neighbours' sky on the same face (a face may arrive alone,
//   one per frame): of the opposite pairs across it (its row, its column, the two diagonals)
//   whose texels are both usable, the mean of the pair that differs least in luminance, so that
//   along an edge (the horizon is a row boundary of the side faces) the fill takes the side the
//   texel is on; without a whole pair (a face's corner) the mean of its usable neighbours. What
//   remains is the sky without the sun at every face size, but for that one texel's estimate
//   (measured on the sky model, tests/lighting/SunTexel_test.cpp: at most 0.16 % of the
//   irradiance at 16^2, 6e-5 at 64^2; growing with the texel below 16, 7 % at 4^2). A texel that
//   is itself NaN, infinite or negative is left for the bad-texel policy; a 1 x 1 face (no
//   neighbours) is zeroed.
#pragma once

#include <glm/vec3.hpp>

namespace amb {

struct CubeTexel {
    int face = 0;      // 0..5: +X, -X, +Y, -Y, +Z, -Z (world/Conventions.h)
    int i = 0, j = 0;  // column, row
    bool operator==(const CubeTexel& o) const { return face == o.face && i == o.i && j == o.j; }
};

// The texel of an N x N cube map that holds direction `dir` (any length > 0): the face whose
// axis it is most along (the largest |component| and its sign; ties to the lower face index), then
// the column and row whose square holds (u, v) (clamped to the face). The one rule the capture and
// every consumer use.
CubeTexel sunTexel(const glm::dvec3& dir, int n);

// What a capture adds to the texel holding the sun: the disc's radiance spread over the texel,
// radiance x discSolidAngle_sr / (the texel's solid angle).
glm::vec3 sunTexelRadiance(const glm::vec3& discRadiance, double discSolidAngle_sr,
                           const CubeTexel& texel, int n);

// Face `face` of an N x N map (3 floats a texel, row-major): when the sun's texel lies on it,
// replaces that texel with its neighbours' sky (see above) and returns true, the
// value it had in `removed` (if given) and the value put in its place in `filled` (if given).
// False (nothing changed) when the texel is on another face or is itself not usable.
bool fillSunTexel(float* faceRgb, int face, int n, const glm::dvec3& sunDirection,
                  glm::vec3* removed = nullptr, glm::vec3* filled = nullptr);
// The same on a whole map (6 N^2 texels, face-major).
bool fillSunTexel(float* cubeRgb, int n, const glm::dvec3& sunDirection);

}  // namespace amb
