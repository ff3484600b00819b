// CubeCaptureGl.h — the GL implementation of lighting/CubeCapture.h.
//
// Faces are rendered into one N x 6N float target (face f in rows [fN, (f+1)N)) with a 90 degree
// camera whose view rows are (U, V, -F) for the face's forward F and texel axes U, V taken from
// world/Conventions.h, so clip-space (x, y) is exactly the face's (u, v) and GL row j is the
// convention's row j. One read-back per call.
//
// Two scenes (CaptureScene):
//   coarse — what the methods capture: the terrain proxy, tree proxies within
//            captureTreeRange_m, the road (RendererScene::buildCapture); thousands of triangles.
//   full   — what the main view draws, for the reference oracle (lighting/ReferenceOracle.h):
//            the terrain LOD mesh finest at the probe, every plant kind (bushes and rocks too)
//            with its full mesh wherever it covers at least fullMinTexels of the face, the road;
//            built per face with the face's frustum (RendererScene::buildView), lit by the same
//            shaders as the main view. Far more triangles, so it is for measuring, not for frames.
//
// Shadows of the main light (ShadowSettings::captures; app/render/ShadowMap.h):
//   coarse — maps over regions of captureRegion_m, of the capture scene's casters (terrain
//            proxy, every tree at the LOD of its height in the map's texels, as the main view's
//            cascades pick it: on these maps of about a metre a texel broadleaves and the smaller
//            conifers are the 8-triangle hull), one per square cell of the ground, centred on it, so that
//            every tree a probe in the cell captures is on it; the last captureMaps cells kept,
//            each rendered for a light epoch (the time of day in steps in which the sun turns
//            by at most captureRefresh_deg) and re-rendered when the epoch changes, so a map
//            depends on its cell and epoch alone, never on what was captured before;
//   full   — the main view's cascades (same count, size, PCF, biases and casters), fitted to
//            spheres around the probe whose radii are the cascades' far ends, so the reference
//            is shadowed as the main view is.
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "app/render/RendererCore.h"
#include "app/render/RendererScene.h"
#include "app/render/ShadowMap.h"
#include "lighting/CubeCapture.h"

namespace amb {

class World;
class MethodAmbienceStages;
class Renderer;
struct AmbienceVolumeSettings;
struct BaselineSettings;

enum class CaptureScene { Coarse, Full };
CaptureScene parseCaptureScene(const std::string& text, const std::string& where);
const char* toString(CaptureScene scene);

// The renderer scene settings of a full-scene capture of N x N faces: the main view's settings
// with its pixel density (N / (pi / 2) per radian) and every drawn plant at its full mesh.
RendererSceneSettings fullCaptureSceneSettings(int faceSize);

class CubeCaptureGl final : public CubeCapture {
  public:
    static constexpr int kDefaultFaceSize = 16;
    static constexpr int kReferenceFaceSize = 64;

    // Shares the scene (meshes, terrain cache) of a renderer; needs a current GL context.
    CubeCaptureGl(RendererScene& scene, int faceSize = kDefaultFaceSize,
                  const ShadowSettings& shadows = {});
    // Standalone: builds its own scene of `world` (for CaptureScene::Full, with
    // fullCaptureSceneSettings).
    CubeCaptureGl(const World& world, int faceSize = kDefaultFaceSize,
                  CaptureScene scene = CaptureScene::Coarse, const ShadowSettings& shadows = {});
    ~CubeCaptureGl() override;

    int faceSize() const override { return n_; }
    CaptureScene scene() const { return kind_; }
    CubeCaptureStats capture(const glm::dvec3& position_m, double timeOfDay_h, CubeFaceMask faces,
                             std::vector<float>& cube) override;
    // The coarse scene without the plants within nearRadius_m (the full scene ignores it: the
    // reference always sees everything).
    CubeCaptureStats captureFar(const glm::dvec3& position_m, double timeOfDay_h,
                                CubeFaceMask faces, std::vector<float>& cube,
                                double nearRadius_m) override;
    // The same with each texel's distance, from the depth buffer (reversed infinite depth:
    // near / depth along the face's axis).
    CubeCaptureStats captureFarWithDistance(const glm::dvec3& position_m, double timeOfDay_h,
                                            CubeFaceMask faces, std::vector<float>& cube,
                                            std::vector<float>& distance_m,
                                            double nearRadius_m) override;

    // Lights the surfaces with `light` (lighting/BounceField.h) instead of the sky/ground
    // hemisphere ambient; null: the hemisphere again.
    void setSurfaceLight(const SurfaceLight* light) override { surfaceLight_ = light; }
    const SurfaceLight* surfaceLight() const { return surfaceLight_; }

    // The sun's direction while it is above the horizon (its disc has radiance then).
    std::optional<glm::dvec3> sunDirection(double timeOfDay_h) const override;

    // Statistics of the last capture() call that rendered faces (triangles per face, time).
    const CubeCaptureStats& lastStats() const { return lastStats_; }
    std::size_t lastTriangles() const override { return lastStats_.triangles; }

    // The camera-relative view-projection of face f (exposed for tests).
    static glm::mat4 faceViewProj(int face, float near_m);

    // The shadow maps' cost so far: renders of the coarse scene's region map (or of the full
    // scene's cascades, one per capture) and their wall time [ms].
    struct ShadowStats {
        std::int64_t renders = 0;
        double render_ms = 0.0;
        std::size_t triangles = 0;  // of the last render
    };
    const ShadowStats& shadowStats() const { return shadowStats_; }
    const ShadowSettings& shadowSettings() const { return shadows_; }
    // The region map (coarse scene), for tests: null until the first shadowed capture.
    const ShadowMap* regionShadowMap() const { return shadowMap_.get(); }

  private:
    void init();
    CubeCaptureStats render(const glm::dvec3& position_m, double timeOfDay_h, CubeFaceMask faces,
                            std::vector<float>& cube, std::vector<float>* distance_m,
                            double nearRadius_m);
    // The shadows of a capture at `probe_m` (rendering the maps when due).
    ShadowBinding prepareShadows(const glm::dvec3& probe_m);

    std::unique_ptr<RendererScene> ownedScene_;
    RendererScene* scene_;
    int n_;
    CaptureScene kind_ = CaptureScene::Coarse;
    const SurfaceLight* surfaceLight_ = nullptr;
    std::unique_ptr<SceneDrawer> drawer_;
    SkyLighting sky_;
    GlTexture colour_, depth_;
    GlFramebuffer fbo_;
    DrawList list_, faceList_;  // the capture's scene, and its objects culled to one face
    std::vector<float> rgba_;
    std::vector<float> depthRows_;  // depth read-back (captureFarWithDistance)
    CubeCaptureStats lastStats_;
    ShadowSettings shadows_;
    std::unique_ptr<ShadowMap> shadowMap_;
    DrawList casters_;
    ShadowStats shadowStats_;
    struct RegionCell {
        std::int64_t i = 0, k = 0;  // the cell's integer key (x, z over the cell size)
        std::int64_t lastUse = -1;  // -1: the layer holds no map
        std::int64_t epoch = 0;     // the light epoch it was rendered for
    };
    std::vector<RegionCell> cells_;  // per layer of the coarse scene's region maps
    std::int64_t useClock_ = 0;
    std::int64_t lightEpoch_ = std::numeric_limits<std::int64_t>::min();  // none yet
    glm::vec3 epochLight_{0, 1, 0};  // towards the main light of lightEpoch_
};

// An ambience method's frame stages (app/frame/MethodStages.h) capturing from `renderer`'s own
// scene (coarse proxies) with faces of `faceSize`, shadowed as the renderer's settings say
// (ShadowSettings::captures). Needs a current GL context.
std::unique_ptr<MethodAmbienceStages> makeMethodStages(Renderer& renderer,
                                                       const std::string& method,
                                                       const AmbienceVolumeSettings& settings,
                                                       const BaselineSettings& baselines,
                                                       int faceSize = 16);

}  // namespace amb
