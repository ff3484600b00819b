// ShGradient.h — how a probe's order-2 SH change as the probe moves along the ground: the
// translational gradient of every coefficient, estimated from the capture's own distances
// (the irradiance gradients of Ward & Heckbert 1992, carried to SH as radiance caching does,
// Krivanek et al. 2005). The anchor store uses it as each anchor's slope (AnchorStore.h,
// "gradients"), so that interpolation between anchors extrapolates first order from each.
//
// [SECTION] The estimate
//   Each texel t of the cube is a small piece of surface: direction w (unit), solid angle W,
//   radiance L, distance r (infinite: sky, which does not move). When the probe moves by d, the
//   piece is seen along w' = w - (d - (w.d) w) / r (first order), and its solid angle
//   W = A cos / r^2 (cos = -w.n, n the surface normal facing the probe) changes by
//       dW / W = (3 w.d - n.d / (w.n)) / r.
//   So, with Y_k the basis and D_d Y_k its change as w moves towards -(d - (w.d) w):
//       d c_k / d d = sum_t L W (D_d Y_k(w) + Y_k(w) (3 w.d - n.d / (w.n))) / r.
//   Every piece keeps its radiance (the scene is static, its light fixed) and nothing it hides
//   or uncovers as the probe moves is accounted (first order; Ward and Heckbert's split of the
//   hemisphere at the nearer of two neighbours is not made). A flat ground of one radiance, or
//   an infinite wall, gives no gradient along itself, as it must (tested).
//   The normal is the surface's as the distances give it: the cross product of the position
//   differences to a neighbouring texel along the row and along the column, each taken towards
//   the neighbour whose distance differs least (so an edge between near and far does not tilt
//   it); without two such neighbours on the face, the piece is taken to face the probe.
//   Guards: r at least minDistance_m (a leaf against the lens does not swing the field) and
//   |w.n| at least minCosine (grazing pieces).
// [SECTION] Cost
//   Three basis evaluations per texel that is not sky, once per probe: 0.30 ms at 16^2 and
//   1.3 ms at 32^2 with no texel of sky (median of 5, `build/bin/ambience_bench
//   --benchmark_filter=ShGroundGradient --benchmark_repetitions=5`), 0.05 ms a frame at one
//   face a frame.
#pragma once

#include <limits>
#include <vector>

#include "lighting/SH.h"

namespace amb {

struct ShGradientOptions {
    double minDistance_m = 1.0;  // distances below count as this [m]
    double minCosine = 0.2;      // |w.n| below counts as this
};

// d/dx and d/dz of each coefficient [per metre] of the SH of a cube map (6 N^2 texels,
// face-major, row-major, 3 floats each, as CubeCapture fills it) whose texels lie at
// `distance_m` (6 N^2 floats: metres from the probe along the texel's direction; infinite or not
// positive: sky). Texels that are NaN, infinite or negative, in colour or distance, count as sky.
// The sun's texel must show sky (its distance infinite), as CubeCapture's does.
// harmonicDistance_m: Ward's radius of validity, the number of texels over the sum of their
// inverse distances (sky: 0), infinite for a cube of sky alone. A first-order step further than
// this from the probe leaves what its gradient describes (the near surfaces that dominate it).
struct ShGroundGradient {
    ShRgbD dx, dz;
    double harmonicDistance_m = std::numeric_limits<double>::infinity();
};
// The same in float: what an anchor keeps (AnchorStore.h).
struct ShSlope {
    ShRgb dx, dz;
    float validity_m = 0.0f;  // harmonicDistance_m, at most kMaxCoefficient
};
ShSlope toFloat(const ShGroundGradient& g);

ShGroundGradient shGroundGradient(int n, const std::vector<float>& rgb,
                                  const std::vector<float>& distance_m,
                                  const ShGradientOptions& options = {});

}  // namespace amb
