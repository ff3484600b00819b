// AmbienceMethod.h — one way of giving ambience to ground points, run frame by frame: ours (the
// dynamic ambience volume, AmbienceVolume.h) and the baselines it is measured against
// (Baselines.h; docs/ARCHITECTURE.md "Measuring speed against error"). The frame loop drives every
// method through the same three stages with the same capture budget, and the draw and the
// measurement read the same shAt (objects) and cornerShAt (terrain corners), so what is
// measured is what is drawn.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <glm/vec3.hpp>

#include "lighting/SH.h"

namespace amb {

class SurfaceLight;

// The height above the ground at which terrain corners and objects take their ambience: the
// height of the probes and of the witnesses that measure them (ProbeEnvironment.h).
inline constexpr double kShadingHeight_m = 2.0;

// The capture budget's upper end, cube faces per frame (the settings readers and the command
// line): four probes a frame, the largest budget measured (README "Budget beyond one probe a
// frame"; beyond 6 faces more captures of the same lattice bought almost nothing). Every probe
// becomes an anchor, and the store rebuilds its field over all of them while any blends: the
// budget bounds what a frame of the store costs (docs/TUNING.md "Settings keys").
inline constexpr int kMaxFacesPerFrame = 24;

struct MethodStatistics {
    std::size_t probes = 0;  // coefficient sets held (anchors, grid probes, cache entries)
    std::size_t bytes = 0;   // memory those take, structure included
    int facesThisFrame = 0;  // cube faces captured this frame
    std::int64_t facesCaptured = 0;   // the primes' included
    std::int64_t primeFaces = 0;      // of facesCaptured, those of primes (CaptureCore.h)
    std::int64_t rejectedProbes = 0;  // captures refused (NaN, Inf, negative)
    std::int64_t teleports = 0;
    // The near field (lighting/NearField.h): wall time since the last predictStage, points it
    // answered, points it holds and the memory they take (0 without one).
    double nearField_s = 0.0;
    std::size_t nearFieldPoints = 0, nearFieldCached = 0, nearFieldBytes = 0;
    std::size_t nearFieldBuilds = 0;  // of nearFieldPoints, those built (not cached)
    double nearFieldBuild_s = 0.0;    // of nearField_s, the builds'
    // Wall time of this frame's stages [s] (project = SH projection of captured faces).
    double predict_s = 0.0, capture_s = 0.0, project_s = 0.0, store_s = 0.0;
};

// The lattice points a method's interpolation reads at a ground point, with their weights: the
// "ideal volume" of the error budget (lighting/ReferenceOracle.h, term c) puts a fresh capture
// at each and interpolates those. count 0: the method has no lattice there (a constant, a probe
// per object, a nearest-anchor lookup).
struct IdealSupport {
    int count = 0;
    std::array<double, 4> x_m{}, z_m{}, weight{};
};
// The four corners of the cell of the lattice {(i s, k s)} that holds (x, z), bilinear weights.
IdealSupport bilinearSupport(double x_m, double z_m, double spacing_m);

class AmbienceMethod {
  public:
    virtual ~AmbienceMethod() = default;

    // Short name, as given to --ambient.
    virtual std::string methodName() const = 0;

    // The frame's stages 2-4 (docs/ARCHITECTURE.md "The frame"). dt_s <= 0 or non-finite: no time passes.
    virtual void predictStage(const glm::dvec3& cameraPosition_m,
                              const glm::dvec3& cameraVelocity_mps, double timeOfDay_h,
                              double dt_s) = 0;
    virtual void captureStage() = 0;
    virtual void storeStage() = 0;

    // The SH applied at ground point (x, z); always finite.
    virtual ShRgb shAt(double x_m, double z_m) const = 0;
    // The same at many points.
    virtual void shAt(std::size_t count, const double* x_m, const double* z_m, ShRgb* out) const {
        for (std::size_t i = 0; i < count; ++i) out[i] = shAt(x_m[i], z_m[i]);
    }
    // The SH applied at a terrain patch corner: a point that does not move, whose colour the
    // draw interpolates linearly across the patch, so it needs no smoothness across cells. By
    // default shAt; the volume answers it from its bilinear cells (AnchorStore.h).
    virtual ShRgb cornerShAt(double x_m, double z_m) const { return shAt(x_m, z_m); }
    virtual void cornerShAt(std::size_t count, const double* x_m, const double* z_m,
                            ShRgb* out) const {
        shAt(count, x_m, z_m, out);
    }

    // cornerShAt at shading points in space: a terrain corner's point kShadingHeight_m above
    // the ground, a witness' probe position. The near field (lighting/NearField.h) needs the
    // point; a method without one reads its ground point.
    virtual ShRgb cornerShAtPoint(const glm::dvec3& point_m) const {
        return cornerShAt(point_m.x, point_m.z);
    }
    virtual void cornerShAtPoints(std::size_t count, const glm::dvec3* points_m, ShRgb* out) const {
        std::vector<double> x(count), z(count);
        for (std::size_t i = 0; i < count; ++i) x[i] = points_m[i].x, z[i] = points_m[i].z;
        cornerShAt(count, x.data(), z.data(), out);
    }

    // The ambient irradiance (clamped at 0) at such points for their normals: what the draw
    // asks at terrain corners and road vertices. By default cornerShAtPoints evaluated there;
    // the near field answers it with its transfer seen through the normal (lighting/NearField.h).
    // With `patch_m`, point i is a terrain corner whose value the draw blends across patches
    // patch_m[i] across (0: a point, a road vertex); only the near field reads it.
    virtual void cornerIrradianceAtPoints(std::size_t count, const glm::dvec3* points_m,
                                          const glm::dvec3* normals, glm::vec3* out,
                                          const double* patch_m = nullptr) const {
        (void)patch_m;
        std::vector<ShRgb> sh(count);
        cornerShAtPoints(count, points_m, sh.data());
        for (std::size_t i = 0; i < count; ++i)
            out[i] = glm::max(shIrradiance(sh[i], glm::vec3(normals[i])), glm::vec3(0.0f));
    }

    // What cornerIrradianceAtPoints gives at these points if the method's far field (its
    // interpolated probes: cornerShAt at the points' ground points) were `far` instead: the error
    // budget at the drawn normal (lighting/Metrics.h, DrawnBudget) puts fresh captures there to
    // make the far field ideal and keep the rest of the draw's path. By default the far field is
    // all there is.
    virtual void irradianceFromFar(std::size_t count, const glm::dvec3* points_m,
                                   const glm::dvec3* normals, const ShRgb* far, glm::vec3* out,
                                   const double* patch_m = nullptr) const {
        (void)points_m, (void)patch_m;
        for (std::size_t i = 0; i < count; ++i)
            out[i] = glm::max(shIrradiance(far[i], glm::vec3(normals[i])), glm::vec3(0.0f));
    }
    // The radius (horizontal, metres) of the plants the method's captures leave out around a
    // probe (the near field puts them back); 0: its captures see the whole coarse scene.
    virtual double farCaptureRadius_m() const { return 0.0; }
    // What the method's captures light their surfaces with now besides the sun (CaptureSettings
    // ownLight: its own field); null: the capture's fixed hemisphere. The error budget's fresh
    // captures (lighting/Metrics.h, DrawnBudget) use the same, so its far-field term compares
    // like with like.
    virtual const SurfaceLight* captureSurfaceLight() const { return nullptr; }
    // A surface light that replaces the method's own in its captures (and so in the budget's
    // fresh ones), asked at the time of day of each capture; a null function or a null answer
    // leaves the method's own. A diagnostic: `run --capture-light reference` passes the
    // reference's bounce field (docs/USAGE.md), which no method has, to measure how much of the
    // model term is the captures' surface light. Methods that capture nothing ignore it.
    using CaptureLightOverride = std::function<const SurfaceLight*(double timeOfDay_h)>;
    virtual void overrideCaptureLight(CaptureLightOverride light) { (void)light; }

    // Where the draw looked up ambience this frame (terrain corners, objects). Only methods that
    // place probes by demand use it; called once per frame before the next predictStage.
    virtual void noteLookups(std::size_t count, const double* x_m, const double* z_m) {
        (void)count, (void)x_m, (void)z_m;
    }
    // True when noteLookups is used (the draw then records where it looks; otherwise it need not).
    virtual bool wantsLookups() const { return false; }
    // True when the draw should scale the terrain's ambient by the per-vertex sky detail of its
    // finest patches (world/TerrainPatch.h; the near field's vertexDetail).
    virtual bool terrainSkyDetail() const { return false; }
    // Terrain patches nearer the eye than this (horizontal distance to the patch's bounds, m)
    // are drawn with the ambient evaluated at every mesh vertex (cornerIrradianceAtPoints at
    // the vertex's point and normal, patch_m the vertex spacing) instead of their corners
    // blended across the patch; 0: none (the near field's vertexAmbient_m).
    virtual double terrainVertexRange_m() const { return 0.0; }
    // At most this many new mesh vertices a frame become lit per vertex (nearest patches first,
    // the others blend their corners until their turn); 0: no bound (the near field's
    // vertexPointsPerFrame).
    virtual int terrainVertexPointsPerFrame() const { return 0; }

    virtual MethodStatistics methodStatistics() const = 0;
    // Where the interpolation at (x, z) reads its probes now (see IdealSupport); none by default.
    virtual IdealSupport idealSupport(double x_m, double z_m) const {
        (void)x_m, (void)z_m;
        return {};
    }
};

inline IdealSupport bilinearSupport(double x_m, double z_m, double spacing_m) {
    IdealSupport s;
    const double i0 = std::floor(x_m / spacing_m), k0 = std::floor(z_m / spacing_m);
    const double fx = x_m / spacing_m - i0, fz = z_m / spacing_m - k0;
    s.count = 4;
    for (int c = 0; c < 4; ++c) {
        const int di = c & 1, dk = c >> 1;
        s.x_m[c] = (i0 + di) * spacing_m;
        s.z_m[c] = (k0 + dk) * spacing_m;
        s.weight[c] = (di ? fx : 1.0 - fx) * (dk ? fz : 1.0 - fz);
    }
    return s;
}

}  // namespace amb
