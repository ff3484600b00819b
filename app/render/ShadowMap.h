// ShadowMap.h — shadows of the main light (sun by day, moon by night) as depth maps seen from the
// light: cascaded shadow maps for the main view, one map over the capture region for the coarse
// captures, and probe-centred cascades for the reference oracle's full scene
// (docs/ARCHITECTURE.md "Shadows").
//
// [SECTION] ShadowSettings   on/off, cascades, map size, PCF, biases, the capture region
// [SECTION] ShadowMap        a depth texture array, one layer per cascade, fitted to spheres
#pragma once

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "app/render/RendererCore.h"

namespace amb {

class RendererScene;

// ---- [SECTION] ShadowSettings ----------------------------------------------------------------
struct ShadowSettings {
    // Main view and reference oracle: cascaded shadow maps.
    bool enabled = true;
    int cascades = 3;       // 1 to kMaxShadowCascades
    // Texels per side of each cascade and PCF taps per side (1, 2 or 3, each a bilinear 2 x 2
    // comparison): on a software rasteriser the lookups cost the most (highway, 640 x 360:
    // 512 and 1 tap add 6 % to the frame, 1024 and 2 x 2 taps 19 %).
    int mapSize = 512;
    int pcf = 1;
    double distance_m = 200.0;  // far end of the last cascade; cascade k ends at distance / 4^(N-1-k)
    double normalOffset_texels = 1.5;  // receivers look up this far along their normal
    double depthBias_texels = 1.0;     // and this much nearer the light
    // The cascades hold only static casters, so each is re-rendered only when its slice of the
    // view leaves it: fitted to the slice's sphere grown by these fractions, at most one cascade
    // a frame. The car has its own small map over carShadowRadius_m, rendered every frame.
    double nearMargin = 1.0;    // the first cascade
    double staticMargin = 0.2;  // the others
    int carMapSize = 256;
    double carShadowRadius_m = 8.0;
    // The far terrain cascade: the terrain's (and roads') shadows from the last cascade's end
    // out to farDistance_m around the camera (0: none), fitted to that sphere grown by
    // staticMargin and re-rendered only when the camera leaves it or the light turns by 1
    // degree: the terrain does not move.
    double farDistance_m = 800.0;
    // Coarse captures: maps over regions of the capture scene, reused across captures. A probe
    // uses the map of the square cell (of side sqrt 2 (region - captureTreeRange_m)) it lies in,
    // centred on the cell, so every tree of its capture is on the map; captureMaps cells are
    // kept, the least recently used replaced.
    bool captures = true;
    int captureMapSize = 512;
    int captureMaps = 12;  // 1 to kMaxShadowLayers
    double captureRegion_m = 240.0;      // radius of the region a map covers
    double captureRefresh_deg = 2.0;     // light epochs: the sun turns by at most this in one
    double captureBias_m = 1.0;          // depth bias (the caster and receiver proxies differ)
};

// Checks ranges; throws InputError naming `where` and the field.
void checkShadowSettings(const ShadowSettings& s, const std::string& where);
// "on" or "off" for --shadows; anything else is an InputError naming `option`.
bool parseShadowSwitch(const std::string& text, const std::string& option);
// What the run report says under "shadows": the technique and its settings, or "none".
std::string describeShadows(const ShadowSettings& s);

// Far end of cascade k of n [m].
double cascadeFar_m(const ShadowSettings& s, int k, int n);

// ---- [SECTION] ShadowMap ---------------------------------------------------------------------
// Each cascade is an orthographic view along the light fitted to a sphere (world centre,
// radius): texels of 2 r / N, the centre snapped to whole texels in the light's frame so that
// shadows stay put as the camera moves. Depth runs from the sphere's light side (0) to its far
// side (1); casters between the sphere and the light are clamped onto depth 0 (GL depth clamp),
// so everything towards the light casts.
constexpr int kMaxShadowLayers = 16;

class ShadowMap {
  public:
    ShadowMap(int layers, int mapSize);  // 1 to kMaxShadowLayers layers

    int layers() const { return layers_; }
    int mapSize() const { return size_; }
    GLuint texture() const { return depth_.id(); }

    // Fits layer k to the sphere and keeps it there until the next fit, over `texels` per side
    // of the layer (0: all of it; fewer render and clear only that corner).
    void fit(int k, const glm::dvec3& centre_m, double radius_m, const glm::vec3& towardLight,
             int texels = 0);
    bool fitted(int k) const { return cascades_[k].radius_m > 0.0; }
    const glm::dvec3& centre(int k) const { return cascades_[k].centre_m; }
    double radius(int k) const { return cascades_[k].radius_m; }
    double texel_m(int k) const { return 2.0 * cascades_[k].radius_m / cascades_[k].texels; }
    const glm::vec3& towardLight(int k) const { return cascades_[k].light; }
    // Layer k's camera-relative (world - eye_m) -> light clip matrix (x, y in [-1, 1], depth in
    // [0, 1]), for drawing casters.
    glm::mat4 casterViewProj(int k, const glm::dvec3& eye_m) const;
    // Renders `casters` (positions relative to eye_m) into layer k: depth only, both faces.
    // Returns the triangles drawn.
    std::size_t render(int k, SceneDrawer& drawer, const DrawList& casters,
                       const glm::dvec3& eye_m);
    // What the receivers' shaders read (shaders/shadow.glsl) for a view from eye_m, layers
    // [0, count): normal offset and depth bias in texels of each layer plus `extraBias_m`.
    // Layers [first, first + count) go to the shader's cascades [0, count).
    ShadowConstants constants(const glm::dvec3& eye_m, int count, int pcf,
                              double normalOffset_texels, double depthBias_texels,
                              double extraBias_m = 0.0, int first = 0) const;
    // Puts layer k into slot `slot` of `sc` (biases in texels of that layer).
    void setSlot(ShadowConstants& sc, int slot, int k, const glm::dvec3& eye_m,
                 double normalOffset_texels, double depthBias_texels, double extraBias_m) const;

  private:
    struct Cascade {
        glm::dvec3 centre_m{0.0};
        double radius_m = 0.0;
        int texels = 1;
        glm::vec3 light{0, 1, 0};
        glm::dvec3 ex{1, 0, 0}, ey{0, 0, 1}, ez{0, 1, 0};  // light frame; ez towards the light
    };
    int layers_, size_;
    GlTexture depth_;
    std::vector<GlFramebuffer> fbos_;
    std::vector<Cascade> cascades_;
};

// The bounding sphere of the view frustum between distances near_m and far_m along the view
// direction (tanX, tanY: tangents of the half angles): (distance of its centre along the view
// direction, radius). Its radius does not depend on the view's orientation.
std::pair<double, double> frustumSliceSphere(double near_m, double far_m, double tanX, double tanY);

}  // namespace amb
