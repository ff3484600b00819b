// Draw.h — what the frame hands its draw stage and what it gets back (docs/ARCHITECTURE.md
// "The frame", stages 5-6), free of GL so that the frame loop and the method adapters stay
// below the renderer: the ambient the draw applies (AmbientSource), the view that draws
// (MainView, implemented by app/render/Renderer.h) and what a draw reports (RenderStats).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "world/Replay.h"
#include "world/Vehicle.h"

namespace amb {

// R&H irradiance matrices of the red, green and blue channels (shaders/sh_irradiance.glsl).
struct AmbientSet {
    glm::mat4 r{0.0f}, g{0.0f}, b{0.0f};
};

// ---- AmbientSource ---------------------------------------------------------------------------
// What the draw needs from the ambient term (docs/ARCHITECTURE.md "The frame", stage 5): the
// irradiance at each terrain-patch corner and road vertex for its normal, and one set of R&H
// matrices per object. MethodAmbient (app/frame/MethodStages.h) answers it from any method's
// SH; FixedAmbient (app/frame/SkyLighting.h) is the constant and hemisphere ambient.
class AmbientSource {
  public:
    virtual ~AmbientSource() = default;
    virtual glm::vec3 cornerIrradiance(const glm::dvec3& position_m,
                                       const glm::dvec3& normal) const = 0;
    // The same at `count` points at once (a frame's terrain corners, its road vertices): out[i]
    // for position i and normal i. One by one by default; a source over an interpolated volume
    // answers the batch with one cache check and no per-call overhead.
    // With `patch_m`, point i is a terrain corner blended across patches patch_m[i] across
    // (world/TerrainPatch.h; the near field's patch mean), else a point (a road vertex).
    virtual void cornerIrradianceBatch(std::size_t count, const glm::dvec3* positions_m,
                                       const glm::dvec3* normals, glm::vec3* out,
                                       const double* patch_m = nullptr) const {
        (void)patch_m;
        for (std::size_t i = 0; i < count; ++i)
            out[i] = cornerIrradiance(positions_m[i], normals[i]);
    }
    // Appends the set for an object at `position_m` to `sets` if needed; returns its index.
    virtual std::uint32_t objectSet(const glm::dvec3& position_m,
                                    std::vector<AmbientSet>& sets) const = 0;
    // Whether the terrain's fine patches scale this ambient by their per-vertex sky detail
    // (world/TerrainPatch.h): a method with the near field's terrain; never a capture's.
    virtual bool terrainSkyDetail() const { return false; }
    // Terrain patches nearer the eye than this [m] take the ambient at every mesh vertex,
    // asked through cornerIrradianceBatch with the vertex spacing as patch_m, instead of their
    // corners blended (AmbienceMethod::terrainVertexRange_m); 0: none, never a capture's.
    virtual double terrainVertexRange_m() const { return 0.0; }
    // Of those, at most this many new vertices a frame (AmbienceMethod::
    // terrainVertexPointsPerFrame); 0: no bound.
    virtual int terrainVertexPointsPerFrame() const { return 0; }
    // The same for `count` objects at once (a frame's plants): index[i] for position i. One by
    // one by default.
    virtual void objectSets(std::size_t count, const glm::dvec3* positions_m,
                            std::vector<AmbientSet>& sets, std::uint32_t* index) const {
        for (std::size_t i = 0; i < count; ++i) index[i] = objectSet(positions_m[i], sets);
    }
};

// The passes of one main-view frame, as `ambience run --pass-timing` times them (each between
// two glFinish calls, with a GL_SAMPLES_PASSED query): the static shadow cascades re-rendered
// that frame, the far terrain cascade, the car's own map, then the HDR draw's plants, car,
// roads, terrain and sky, the exposure meter's read-back and the tone mapping.
enum class RenderPass : int {
    ShadowCascades,
    ShadowFar,
    ShadowCar,
    Plants,
    Car,
    Roads,
    Terrain,
    Sky,
    Exposure,
    Tonemap
};
constexpr int kRenderPasses = 10;
inline const char* toString(RenderPass p) {
    static const char* const names[kRenderPasses] = {
        "shadowCascades", "shadowFar", "shadowCar", "plants", "car",
        "roads", "terrain", "sky", "exposure", "tonemap"};
    return names[int(p)];
}
struct PassStats {
    bool ran = false;           // the pass ran this frame
    double ms = 0.0;            // wall time between the glFinish calls around it
    std::size_t triangles = 0;  // submitted
    std::uint64_t samples = 0;  // that passed the depth test (GL_SAMPLES_PASSED)
};

struct RenderStats {
    std::size_t triangles = 0;
    std::size_t terrainPatches = 0, terrainPatchesDrawn = 0, objectsDrawn = 0;
    bool terrainRebuilt = false;
    // Drawn patches in the vertex range lit per vertex, and those still blending their corners
    // (AmbientSource::terrainVertexPointsPerFrame).
    std::size_t terrainPatchesVertex = 0, terrainPatchesWaiting = 0;
    double scene_ms = 0.0;  // building the draw list (CPU)
    double draw_ms = 0.0;   // submitting GL commands (CPU), the shadow pass included
    std::size_t shadowTriangles = 0;  // drawn into the shadow maps
    double shadow_ms = 0.0;           // building and submitting the shadow pass (CPU)
    bool passesTimed = false;         // --pass-timing: `passes` holds this frame's
    std::array<PassStats, kRenderPasses> passes{};
};

// What the main view needs to know about the frame besides its eye: the run's clock (the eye
// adaptation of the tone mapping runs in simulation time) and the camera's own car, if drawn.
struct ViewState {
    double time_s = 0.0;  // the run's clock
    bool cut = false;     // the camera was cut before this frame (adaptation starts afresh)
    std::optional<VehiclePose> vehicle;
};

// The main view as the frame loop sees it.
class MainView {
  public:
    virtual ~MainView() = default;
    // Stage 1: the sky for the frame's time of day.
    virtual void setViewTimeOfDay(double timeOfDay_h) = 0;
    // Stage 6, before drawView (also on frames that draw nothing, so that a later render of the
    // frame sees the same car and clock).
    virtual void setViewState(const ViewState& state) { (void)state; }
    // Stage 6: draws the view from `camera` (the eye the main view renders from: the replay's
    // camera, or the chase camera's eye) with `ambient` and waits until it is drawn.
    virtual RenderStats drawView(const CameraSample& camera, const AmbientSource& ambient) = 0;
};

}  // namespace amb
