// Renderer.h — the main view: linear HDR into a float target, then exposure and tone mapping
// (shaders/tonemap.frag: ACES filmic fit, sRGB) into an 8-bit target that is read back (offscreen)
// or blitted to the window. The main light's direct term is shadowed by cascaded shadow maps
// (app/render/ShadowMap.h; docs/ARCHITECTURE.md "Shadows").
//
// [SECTION] Renderer   one frame of the main view
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "app/render/AutoExposure.h"
#include "app/render/PassTimer.h"
#include "app/render/RendererCore.h"
#include "app/render/RendererScene.h"
#include "app/render/ShadowMap.h"
#include "lighting/SH.h"
#include "world/Replay.h"

namespace amb {

class World;

// What render() writes into the HDR target: the shaded view, or an output of the screen
// witnesses (lighting/Metrics.h): per pixel the ambient irradiance exactly as the draw applies it
// (corner colours for terrain, per-vertex for roads, per-pixel SH for objects), the world
// normal or the albedo; alpha names the surface (1 terrain, 2 road, 3 object, 4 object drawn
// with a simplified mesh; 0 sky). Ambient is the ambient view: every surface as a white
// Lambertian one lit by the ambient alone (radiance = ambient irradiance / pi, the sky as in
// Shaded). Outputs other than Shaded and Ambient skip tone mapping.
enum class RenderOutput { Shaded = 0, AmbientIrradiance = 1, Normal = 2, Albedo = 3, Ambient = 4 };
// "shaded" or "ambient" (--view); anything else is an InputError naming `option`.
RenderOutput parseViewOutput(const std::string& name, const std::string& option);

// ---- Renderer --------------------------------------------------------------------------------
struct RenderSettings {
    int width = 640, height = 360;
    float fovY_rad = 1.0471976f;  // 60 degrees
    float near_m = 0.3f;
    float fogExtinction_perM = 1.0f / 4000.0f;
    RendererSceneSettings scene{};
    // Eye adaptation of the tone mapping (app/render/AutoExposure.h); off: the sky's fixed one.
    AutoExposureSettings exposure{};
    // What the main view (drawView) shows: Shaded, or Ambient (--view ambient).
    RenderOutput viewOutput = RenderOutput::Shaded;
    // Shadows of the main light (main view; `captures` is read by the cube captures).
    ShadowSettings shadows{};
    // Time each pass of the frame (app/render/PassTimer.h; --pass-timing) into RenderStats.
    bool passTiming = false;
};

// One output read back: RGBA per pixel and the camera-relative position of its surface (from
// the depth buffer), top row first.
struct SurfaceImage {
    int width = 0, height = 0;
    std::vector<float> rgba;
    std::vector<glm::vec3> position;  // world - camera [m]; only where alpha > 0
};

class Renderer final : public MainView {
  public:
    Renderer(const World& world, const RenderSettings& settings);
    ~Renderer() override;

    // MainView (the frame loop's stages 1 and 6): setTimeOfDay, and render + glFinish.
    void setViewTimeOfDay(double timeOfDay_h) override { setTimeOfDay(timeOfDay_h); }
    // The car (drawn by the next renders) and the clock the exposure adapts on.
    void setViewState(const ViewState& state) override;
    RenderStats drawView(const CameraSample& camera, const AmbientSource& ambient) override;
    // What drawView shows from the next frame on (the viewer's panel switches it).
    void setViewOutput(RenderOutput output) { settings_.viewOutput = output; }
    RenderOutput viewOutput() const { return settings_.viewOutput; }

    // The sky for a time of day (re-evaluated only when the time changes).
    const SkyLighting& setTimeOfDay(double timeOfDay_h);
    const SkyLighting& skyLighting() const { return sky_; }

    // Maps camera-relative positions (world - camera.position_m) to clip space.
    glm::mat4 viewProjection(const CameraSample& camera) const;
    // Renders the view from `camera` with `ambient` into the HDR target and tone maps it.
    RenderStats render(const CameraSample& camera, const AmbientSource& ambient,
                       RenderOutput output = RenderOutput::Shaded);
    // The HDR target of the last render() with its surface positions (after a non-shaded output).
    SurfaceImage readSurface(const CameraSample& camera);
    // Tone maps a linear HDR image of the view's size (top row first, RGB float, e.g. readHdr()
    // changed on the CPU) with the exposure of the last shaded render and returns it as readRgb8
    // does.
    std::vector<unsigned char> tonemap(const std::vector<float>& hdrRgb);
    // The tone-mapped image, top row first, RGB 8-bit (waits for the GPU).
    std::vector<unsigned char> readRgb8();
    // The linear HDR image, top row first, RGB float.
    std::vector<float> readHdr();
    // Replaces the tone-mapped image by `rgb` (top row first, as readRgb8 gives it), e.g. with
    // a debug overlay drawn on it, before blitToWindow.
    void replaceLdr(const std::vector<unsigned char>& rgb);
    // Copies the tone-mapped image to the window's default framebuffer of the given size.
    void blitToWindow(int windowWidth, int windowHeight);

    int width() const { return settings_.width; }
    int height() const { return settings_.height; }
    SceneDrawer& drawer() { return *drawer_; }
    RendererScene& scene() { return *scene_; }
    const World& world() const { return world_; }
    const RenderSettings& settings() const { return settings_; }
    // The main view's cascades (null with shadows off), e.g. for tests.
    const ShadowMap* shadowMap() const { return shadowMap_.get(); }

  private:
    // Fits and renders the cascades due this frame; returns the shadows the draw reads.
    ShadowBinding renderShadows(const CameraSample& camera, RenderStats& stats);

    const World& world_;
    RenderSettings settings_;
    std::unique_ptr<SceneDrawer> drawer_;
    std::unique_ptr<RendererScene> scene_;
    SkyLighting sky_, noon_;
    GlTexture hdr_, depth_, ldr_;
    GlFramebuffer hdrFbo_, ldrFbo_;
    DrawList list_;
    ViewState viewState_;
    AutoExposure exposure_;
    LuminanceMeter meter_;
    float adaptExposure();  // this frame's exposure (metered once per frame)
    std::unique_ptr<ShadowMap> shadowMap_;
    DrawList casters_;
    PassTimer timer_;
};

}  // namespace amb
