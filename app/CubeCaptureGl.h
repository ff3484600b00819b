// CubeCaptureGl.h — the GL implementation of lighting/CubeCapture.h.
//
// Faces are rendered into one N x 6N float target (face f in rows [fN, (f+1)N)) with a 90 degree
// camera whose view rows are (U, V, -F) for the face's forward F and texel axes U, V taken from
// world/Conventions.h, so clip-space (x, y) is exactly the face's (u, v) and GL row j is the
// convention's row j. One read-back per call.
#pragma once

#include <memory>
#include <vector>

#include "app/RendererCore.h"
#include "app/RendererScene.h"
#include "lighting/CubeCapture.h"

namespace amb {

class World;

class CubeCaptureGl final : public CubeCapture {
  public:
    static constexpr int kDefaultFaceSize = 16;

    // Shares the scene (meshes, terrain cache) of a renderer; needs a current GL context.
    CubeCaptureGl(RendererScene& scene, int faceSize = kDefaultFaceSize);
    // Standalone: builds its own scene of `world`.
    CubeCaptureGl(const World& world, int faceSize = kDefaultFaceSize);
    ~CubeCaptureGl() override;

    int faceSize() const override { return n_; }
    CubeCaptureStats capture(const glm::dvec3& position_m, double timeOfDay_h, CubeFaceMask faces,
                             std::vector<float>& cube) override;

    // Statistics of the last capture() call that rendered faces (triangles per face, time).
    const CubeCaptureStats& lastStats() const { return lastStats_; }

    // The camera-relative view-projection of face f (exposed for tests).
    static glm::mat4 faceViewProj(int face, float near_m);

  private:
    void init();

    std::unique_ptr<RendererScene> ownedScene_;
    RendererScene* scene_;
    int n_;
    std::unique_ptr<SceneDrawer> drawer_;
    SkyLighting sky_;
    GlTexture colour_, depth_;
    GlFramebuffer fbo_;
    DrawList list_;
    std::vector<float> rgba_;
    CubeCaptureStats lastStats_;
};

}  // namespace amb
