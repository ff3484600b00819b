// ReferenceIrradiance.h — irradiance taken straight from a cube map, and the error over the
// sphere of normals by quadrature: the measuring stick that does not go through SH.
//
// [SECTION] Irradiance from a cube map
//   A cube map is radiance that is constant over each texel. The irradiance at normal n is
//       E(n) = sum_t L_t * integral over texel t of max(0, n . w) dw,
//   and each texel's integral is taken exactly: a texel is a planar quad on its cube face, whose
//   edges are great-circle arcs seen from the centre; the part above the horizon of n is that
//   quad clipped by the plane n . x = 0 (still a planar polygon), and for a spherical polygon
//   with vertices v_i (Lambert's formula for a polygonal luminaire)
//       integral of (n . w) dw = 1/2 sum_i theta_i n . (v_i x v_{i+1}) / |v_i x v_{i+1}|,
//   theta_i the angle between v_i and v_{i+1}. So a constant environment L gives pi L exactly,
//   at every n and face size; texels wholly above the horizon use a precomputed vector
//   V_t = integral of w dw (E gets n . V_t), and only texels that the horizon cuts are clipped.
// [SECTION] Quadrature over the sphere of normals
//   A product rule: Gauss-Legendre in cos(theta) (Boost.Math) times equally spaced azimuths.
//   With m Legendre nodes and 2m azimuths it integrates every polynomial in (x, y, z) of degree
//   <= 2m - 1 exactly; the weights add up to 4 pi. The squared irradiance difference of two
//   order-2 SH sets is a polynomial of degree 4, so the rule of degree 5 (m = 3, 18 normals)
//   already reproduces the closed form of Metrics.h; the default (m = 5, degree 9, 50 normals)
//   also resolves the smooth higher bands of a reference taken from a cube map.
#pragma once

#include <functional>
#include <vector>

#include <glm/vec3.hpp>

#include "lighting/SH.h"

namespace amb {

// Directions and weights of a rule over the unit sphere (weights sum to 4 pi).
struct SphereRule {
    std::vector<glm::dvec3> directions;
    std::vector<double> weights;
    int degree = 0;  // exact for polynomials up to this degree
};
// legendreNodes in 1..8: degree 2 * legendreNodes - 1.
SphereRule sphereProductRule(int legendreNodes = 5);

// Irradiance of a cube map (RGB, face-major, row-major; the layout of CubeMapImage and of the
// capture) at any normal, exact for texel-constant radiance.
class CubeIrradiance {
  public:
    CubeIrradiance(int faceSize, const std::vector<float>& rgb);
    glm::dvec3 at(const glm::dvec3& normal) const;
    int faceSize() const { return n_; }

  private:
    int n_;
    std::vector<glm::dvec3> radiance_;  // per texel
    std::vector<glm::dvec3> vector_;    // per texel: integral of w dw over the texel
};

// Integral of max(0, n . w) dw over the texel (face, column i, row j) of an N x N face.
double texelCosineIntegral(int face, int i, int j, int n, const glm::dvec3& normal);

using IrradianceField = std::function<glm::dvec3(const glm::dvec3& normal)>;

// sqrt(sum_i W_i sum_c w_c (a_c(n_i) - b_c(n_i))^2), with the luminance weights w_c of
// Metrics.h: the quadrature twin of irradianceDistance().
double irradianceDistance(const IrradianceField& a, const IrradianceField& b,
                          const SphereRule& rule);
// The same with b = 0.
double irradianceNorm(const IrradianceField& a, const SphereRule& rule);

// E(n) of an SH set as a field (Ahat-convolved, as shIrradiance).
IrradianceField shField(const ShRgb& sh);

}  // namespace amb
