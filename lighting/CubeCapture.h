// CubeCapture.h — the capture interface: a cube map of the static, coarse scene at a point.
//
// Declared here, without GL, so the lighting code (scheduler, anchor store, oracle) can ask for
// captures; the GL implementation lives in app/ (CubeCaptureGl.cpp). What is drawn
// (docs/ARCHITECTURE.md, "Capture"): the terrain proxy mesh, tree proxies, the road, the sky and the
// sun — nothing dynamic (thesis 8.2). Face order and texel orientation are those of
// world/Conventions.h (cubeTexelDirection): face f, texel (column i, row j) looks along
// cubeTexelDirection(f, i, j, N).
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <limits>
#include <optional>
#include <vector>

#include <glm/vec3.hpp>

#include "lighting/SH.h"

namespace amb {

// What lights the surfaces a capture draws besides the main light: an irradiance field, read as
// order-2 SH at a surface's position (lighting/BounceField.h). A capture without one uses its
// own fixed ambient (the GL capture: the sky/ground hemisphere, app/frame/SkyLighting.h).
class SurfaceLight {
  public:
    virtual ~SurfaceLight() = default;
    virtual ShRgb shAt(const glm::dvec3& position_m) const = 0;
};

// Which faces a call renders: bit f is face f (0 = +X ... 5 = -Z).
using CubeFaceMask = unsigned;
inline constexpr CubeFaceMask kAllCubeFaces = 0x3fu;
inline constexpr CubeFaceMask cubeFaceBit(int face) {
    return 1u << face;
}

struct CubeCaptureStats {
    int faces = 0;              // faces rendered by the call
    std::size_t triangles = 0;  // triangles submitted per face (capture scene size)
    double wall_ms = 0.0;  // wall time of the call, read-back included
    double perFace_ms() const { return faces > 0 ? wall_ms / faces : 0.0; }
};

class CubeCapture {
  public:
    virtual ~CubeCapture() = default;

    // Face size N in texels (default 16, as the thesis chose, 9.1).
    virtual int faceSize() const = 0;

    // Renders the faces in `faces` as seen from `position_m` (world, metres) at `timeOfDay_h`
    // (hours) into `cube`: linear HDR RGB, 6 N^2 texels, face-major, row-major, 3 floats per
    // texel. `cube` is resized to 6 N^2 x 3 if it has another size; faces outside the mask are
    // left as they are, so a cube can be filled over several calls (one face per frame).
    // The sun disc is added to the texel that holds the sun direction with its whole energy
    // (radiance x disc solid angle / texel solid angle), unless terrain or trees hide it
    // (lighting/SunTexel.h: sunTexel, sunTexelRadiance).
    virtual CubeCaptureStats capture(const glm::dvec3& position_m, double timeOfDay_h,
                                     CubeFaceMask faces, std::vector<float>& cube) = 0;

    // The same with the plants whose base lies within nearRadius_m (horizontally) of
    // `position_m` left out: the far field of the two-scale ambience (lighting/NearField.h).
    // A capture that has no plants to leave out (a test's analytic scene) renders as capture().
    virtual CubeCaptureStats captureFar(const glm::dvec3& position_m, double timeOfDay_h,
                                        CubeFaceMask faces, std::vector<float>& cube,
                                        double nearRadius_m) {
        (void)nearRadius_m;
        return capture(position_m, timeOfDay_h, faces, cube);
    }

    // captureFar, and the distance [m] from `position_m` to what each texel of the rendered
    // faces shows, along its direction, into `distance_m` (6 N^2 floats, face-major, resized
    // as `cube` is; infinite where a texel shows sky, the sun's included): what the
    // translational gradient of the probe's SH is estimated from (lighting/ShGradient.h). A
    // capture that knows no distances (this default) gives every texel as sky.
    virtual CubeCaptureStats captureFarWithDistance(const glm::dvec3& position_m,
                                                    double timeOfDay_h, CubeFaceMask faces,
                                                    std::vector<float>& cube,
                                                    std::vector<float>& distance_m,
                                                    double nearRadius_m) {
        const CubeCaptureStats stats = captureFar(position_m, timeOfDay_h, faces, cube, nearRadius_m);
        const std::size_t face = std::size_t(faceSize()) * std::size_t(faceSize());
        if (distance_m.size() != 6 * face) distance_m.assign(6 * face, kFar);
        for (int f = 0; f < 6; ++f)
            if (faces & cubeFaceBit(f))
                std::fill_n(distance_m.begin() + std::ptrdiff_t(f * face), face, kFar);
        return stats;
    }
    static constexpr float kFar = std::numeric_limits<float>::infinity();

    // The direction whose texel gets the sun disc in a capture at `timeOfDay_h`: what whoever
    // leaves the sun out of the SH is told (CubeMapProjector::addFace, the reference oracle).
    // None when the capture adds no disc then (the sun below the horizon, or a capture that
    // draws no sun, as this default says).
    virtual std::optional<glm::dvec3> sunDirection(double timeOfDay_h) const {
        (void)timeOfDay_h;
        return std::nullopt;
    }

    // Lights the surfaces of later captures with `light` (null: the capture's own fixed
    // ambient); it must outlive its use. A capture that draws no lit surfaces ignores it.
    virtual void setSurfaceLight(const SurfaceLight* light) { (void)light; }

    // Triangles per face of the latest capture (the capture scene's size; 0 if not known).
    virtual std::size_t lastTriangles() const { return 0; }

    // All six faces, returned.
    std::vector<float> captureAll(const glm::dvec3& position_m, double timeOfDay_h,
                                  CubeCaptureStats* stats = nullptr) {
        std::vector<float> cube;
        const CubeCaptureStats s = capture(position_m, timeOfDay_h, kAllCubeFaces, cube);
        if (stats) *stats = s;
        return cube;
    }
};

}  // namespace amb
