// BounceField.h — the reference's own indirect light: a sparse lattice of full-scene captures
// around the camera path, iterated bounce after bounce until it stops changing
// (docs/ARCHITECTURE.md "Measuring speed against error", docs/METHOD.md "How the reference is lit").
//
// [SECTION] Why
//   A capture shades the surfaces it draws with the main light and an ambient term. With the
//   fixed sky/ground hemisphere ambient (app/frame/SkyLighting.h FixedAmbient) the reference
//   lights its surfaces with the very model the near field copies (world/SkyGround.h
//   hemisphereAmbient), so it leans towards the near field. The bounce field lights them with
//   the scene's own irradiance instead: what the sky, the sun and the surfaces themselves send.
// [SECTION] The lattice
//   Points on the square lattice (i spacing_m, k spacing_m) of the XZ plane whose distance to
//   some point of the camera path is at most reach_m, each placed by the caller (the probes'
//   rule at kBounceHeight_m: 2 m above the ground, out of plant footprints, whatever height
//   the methods' probes stand at, so the reference does not move with them), and with two
//   layers a second point canopy_m above each. The lattice is global, so two runs of one
//   replay lay the same points.
// [SECTION] The iteration (Jacobi)
//   Pass 1 lights the surfaces with no ambient at all: its captures hold the sky and the
//   surfaces lit by the main light (one bounce). Pass k lights them with pass k-1's field
//   (interpolated SH irradiance x the surface's albedo, as the draw applies any ambient) and so
//   holds k bounces. The sun's texel is left out of every point's SH, as the methods leave it out
//   (the renderer lights the sun apart). The change of a pass is
//       sqrt(sum_i ||E_k,i - E_k-1,i||^2) / sqrt(sum_i ||E_k,i||^2)
//   over the points (irradiance over the sphere of normals, luminance-weighted: Metrics.h); the
//   iteration stops at the first pass whose change is below `tolerance` (that pass's count is
//   the number of bounces), or after maxBounces. For a closed scene of uniform albedo rho lit by
//   E_d the passes are the partial sums of the geometric series rho E_d (1 + rho + ... ), whose
//   change at pass k is rho^(k-1) (1 - rho) / (1 - rho^k) (tested).
// [SECTION] Reading the field (shAt)
//   Bilinear over the lattice in x and z, layer by layer (with one layer height is not a
//   coordinate: a point reads the field of the ground below it; with two, see Two layers).
//   Lattice points with no capture (outside the reach) take the value of the nearest captured
//   point (chessboard distance on the lattice, first found on ties), so the field is defined
//   and continuous everywhere; beyond the lattice's bounding box the box's edge value holds.
//   Before the first pass the field is zero everywhere.
// [SECTION] Two layers (canopy_m > 0)
//   One layer reads, for every surface, the field where a probe stands 2 m above the ground,
//   out of plant footprints: in a wood, under its neighbours' crowns. A crown's top is lit by
//   far more sky than that. With canopy_m > 0 each lattice node holds a second point canopy_m
//   above its first, solved with it (both layers in every pass), and a surface at height y
//   reads the two layers' bilinear values blended linearly by
//       t = clamp((y - y_low) / (y_high - y_low), 0, 1)
//   y_low and y_high the layers' bilinear heights at its x, z: the ground reads the lower layer,
//   a surface canopy_m above it the upper one. Objects (plants) are read at their spheres'
//   area-weighted centre (app/render RendererSceneSettings::objectsAtCrown), not at their base.
// [SECTION] BounceLitCapture
//   A CubeCapture that lights the surfaces of another (the reference's full-scene capture) with
//   bounce fields: solved on the first capture that needs one (a reference read from a cache
//   never solves), one per light epoch of epoch_h hours counted from timeOrigin_h, solved at the
//   epoch's start (a replay at a steady time of day solves once).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "lighting/CubeCapture.h"
#include "lighting/SH.h"

namespace amb {

// The height above the ground of the lattice's lower layer (see The lattice).
inline constexpr double kBounceHeight_m = 2.0;

struct BounceSettings {
    double spacing_m = 256.0;  // lattice spacing (bench default; `run` uses 128)
    double reach_m = 500.0;    // lattice points within this distance of the path
    int faceSize = 32;         // face size of the lattice's captures
    double tolerance = 0.01;   // stop at the first pass changing the field by less
    int maxBounces = 12;
    double epoch_h = 0.25;     // BounceLitCapture: a field per this much time of day
    // A second layer of points this far above the first (0: one layer). See "Two layers":
    // 10 m puts it at 12 m, the top of a full-grown conifer (world/Vegetation.h).
    double canopy_m = 10.0;
};
// Throws InputError(option names) for settings out of range.
void checkBounceSettings(const BounceSettings& s);
// "spacing=256 reach=500 face=32 tolerance=0.01": what the reference cache's key names.
std::string describeBounceSettings(const BounceSettings& s);

// Which ambient lights the surfaces of the reference's captures (--reference-light).
enum class ReferenceLight { Bounce, Hemisphere };
ReferenceLight parseReferenceLight(const std::string& text, const std::string& where);
const char* toString(ReferenceLight light);

// One solve: how the iteration went.
struct BounceSolve {
    double timeOfDay_h = 0.0;
    std::size_t points = 0;
    int bounces = 0;              // passes made (the last one changed less than tolerance)
    bool converged = false;       // false: stopped at maxBounces
    std::vector<double> changes;  // per pass (pass 1's is 1: from nothing)
    std::vector<double> maxPointChanges;  // per pass, the largest change at one point
    std::int64_t captures = 0;
    double seconds = 0.0;
};

class BounceField final : public SurfaceLight {
  public:
    explicit BounceField(const BounceSettings& settings);

    // Lays the lattice points within reach of `path` (x, z points), placed by `place(x, z)`.
    void layOut(const std::vector<glm::dvec2>& path,
                const std::function<glm::dvec3(double x_m, double z_m)>& place);
    // Iterates (see above) with `capture`, which the field lights while it runs (its surface
    // light is this field during the solve and none after it).
    const BounceSolve& solve(CubeCapture& capture, double timeOfDay_h);

    ShRgb shAt(const glm::dvec3& position_m) const override;

    const BounceSettings& settings() const { return settings_; }
    std::size_t points() const { return points_.size(); }
    // Every point, the lower layer first (the upper one, when there is one, in the same order).
    const glm::dvec3& pointPosition(std::size_t i) const { return points_[i].position_m; }
    const ShRgb& pointSh(std::size_t i) const { return points_[i].sh; }
    const BounceSolve& lastSolve() const { return solve_; }

  private:
    void fillGrid();
    // The bilinear value over one layer (offset 0: the lower; layerSize_: the upper) of `get`.
    template <typename T, typename Get>
    T bilinear(const glm::dvec3& position_m, std::size_t offset, Get get) const;

    struct Point {
        std::int64_t i = 0, k = 0;
        glm::dvec3 position_m{0.0};
        ShRgb sh;
    };
    BounceSettings settings_;
    std::vector<Point> points_;  // the lower layer, then the upper one (layerSize_ each)
    std::size_t layerSize_ = 0;
    // The lattice's bounding box [i0, i0 + width) x [k0, k0 + height), every node filled.
    std::int64_t i0_ = 0, k0_ = 0;
    int width_ = 0, height_ = 0;
    std::vector<int> nearest_;  // per node: index of the point whose value it takes
    BounceSolve solve_;
};

// See above. `reference` and the lattice capture must outlive it; the lattice capture may be
// `reference` itself.
class BounceLitCapture final : public CubeCapture {
  public:
    BounceLitCapture(CubeCapture& reference, CubeCapture& lattice, const BounceSettings& settings,
                     std::vector<glm::dvec2> path,
                     std::function<glm::dvec3(double x_m, double z_m)> place, double timeOrigin_h);

    int faceSize() const override { return reference_.faceSize(); }
    CubeCaptureStats capture(const glm::dvec3& position_m, double timeOfDay_h, CubeFaceMask faces,
                             std::vector<float>& cube) override;
    std::optional<glm::dvec3> sunDirection(double timeOfDay_h) const override {
        return reference_.sunDirection(timeOfDay_h);
    }
    std::size_t lastTriangles() const override { return reference_.lastTriangles(); }

    // The field of the epoch holding `timeOfDay_h`, solved if it is not yet.
    const BounceField& field(double timeOfDay_h);
    // Every solve so far, in order.
    std::vector<BounceSolve> solves() const;

  private:
    CubeCapture& reference_;
    CubeCapture& lattice_;
    BounceSettings settings_;
    std::vector<glm::dvec2> path_;
    std::function<glm::dvec3(double, double)> place_;
    double timeOrigin_h_;
    std::map<std::int64_t, std::unique_ptr<BounceField>> fields_;
    std::vector<std::int64_t> order_;  // epochs in the order they were solved
};

}  // namespace amb
