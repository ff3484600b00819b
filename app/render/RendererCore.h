// RendererCore.h — what the main view and the cube capture share: the GL programs, the sky
// texture, meshes on the GPU, and drawing one DrawList (plain data) into the bound framebuffer.
//
// [SECTION] FrameConstants   the std140 block of shaders/common.glsl
// [SECTION] ShadowConstants  the std140 block of shaders/shadow.glsl
// [SECTION] GlMesh           a WorldMesh on the GPU (positions, normals, albedo, indices)
// [SECTION] DrawList         terrain patches with corner irradiance, road pieces with irradiance
//                            per vertex, instanced objects with ambient sets (three R&H 4x4
//                            matrices each): the ambient slot
// [SECTION] SceneDrawer      draws a DrawList: opaque terrain and objects, then the sky behind
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "app/frame/Draw.h"
#include "app/frame/SkyLighting.h"
#include "app/render/Gl.h"
#include "app/render/PassTimer.h"
#include "world/WorldMesh.h"

namespace amb {

// ---- FrameConstants --------------------------------------------------------------------------
struct FrameConstants {
    glm::mat4 viewProj{1.0f};  // camera-relative world -> clip
    glm::mat4 invViewProj{1.0f};
    glm::vec4 lightDir{0, 1, 0, 0};
    glm::vec4 lightIrradiance{0.0f};
    glm::vec4 sunDisc{0, 0, 0, 2};     // rgb radiance; w = cos(angular radius), 2 = no disc
    glm::vec4 fog{0.0f};               // x: extinction [1/m]; y: 1 in a capture (alpha marks sky)
    glm::vec4 sunAzimuth{0, 0, 1, 0};  // xz: unit horizontal direction of the sun's azimuth
    glm::vec4 fogToward{0.0f};         // horizon sky radiance towards the sun's azimuth
    glm::vec4 fogAway{0.0f};           // and away from it
};
static_assert(sizeof(FrameConstants) == 2 * 64 + 7 * 16, "std140 layout of FrameConstants");

// ---- ShadowConstants -------------------------------------------------------------------------
constexpr int kMaxShadowCascades = 4;
constexpr int kCarShadowSlot = kMaxShadowCascades;      // the car's own map
constexpr int kFarShadowSlot = kMaxShadowCascades + 1;  // the far terrain cascade
struct ShadowConstants {
    // Camera-relative world -> (u, v, depth, 1) of each cascade, u, v, depth in [0, 1] over the
    // part of the layer the cascade uses; then the car's map and the far cascade.
    glm::mat4 matrix[kMaxShadowCascades + 2]{};
    // x: normal offset [m]; y: depth bias [depth units]; z: layer of the texture array;
    // w: the share of the layer's side the cascade uses (its texels / the layer's)
    glm::vec4 offset[kMaxShadowCascades + 2]{};
    // x: cascades (0: no shadows); y: 1 / layer size; z: PCF taps per side; w: 1 with the car's map
    glm::vec4 params{0.0f};
    glm::vec4 far{0.0f};  // x: 1 with the far terrain cascade
};
static_assert(sizeof(ShadowConstants) == (kMaxShadowCascades + 2) * 80 + 32, "std140 layout");

// The shadows a draw reads: a depth texture array (GL_TEXTURE_2D_ARRAY, comparison on) and its
// constants. texture 0 or params.x 0: no shadows.
struct ShadowBinding {
    GLuint texture = 0;
    ShadowConstants constants{};
};

// Reversed-Z perspective with an infinite far plane (depth 1 at `near_m`, 0 at infinity), for
// glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE).
glm::mat4 reversedInfinitePerspective(float fovY_rad, float aspect, float near_m);

// ---- GlMesh ----------------------------------------------------------------------------------
struct GlMesh {
    GlVertexArray vao;
    GlBuffer positions, normals, albedo, indices;
    GlBuffer skyDetail;  // terrain only: two floats a vertex (attribute 6), else none
    GlBuffer occlusion;  // plants only: one float a vertex (attribute 7), else none
    GLsizei indexCount = 0;
    float boundRadius_m = 0.0f;  // farthest vertex from the mesh origin (culling)
    std::size_t triangles() const { return std::size_t(indexCount) / 3; }
};
// Attributes 0..2 per vertex; attributes 3 and 4 read ObjectInstance from binding 1 (instanced);
// attribute 5 (irradiance per vertex, binding 5) is enabled by the draws that use it.
GlMesh uploadMesh(const WorldMesh& mesh);

// ---- DrawList --------------------------------------------------------------------------------
struct TerrainDraw {
    const GlMesh* mesh = nullptr;
    std::uint32_t firstIndex = 0, indexCount = 0;  // range in mesh; count 0 = the whole mesh
    glm::vec3 origin{0.0f};                        // patch origin, camera-relative [m]
    glm::vec4 rect{0, 0, 1, 1};  // (x0, z0) relative to the origin [m], 1/size [1/m]
    std::array<glm::vec3, 4> cornerIrradiance{};  // (x0,z0), (x1,z0), (x0,z1), (x1,z1)
    // Road pieces, and terrain patches lit per vertex (RendererScene::buildView, the ambient's
    // terrainVertexRange_m): the irradiance of mesh vertex v is
    // DrawList::vertexIrradiance[this + v] (the corners and rect are then unused); -1: the
    // corners, bilinear across the rect.
    std::int64_t firstVertexIrradiance = -1;
    // A road piece: drawn in the roads' pass, before the terrain, and marked as surface kind 2
    // (road) in the screen witnesses' outputs; else terrain (kind 1), lit per vertex or not.
    bool road = false;
    // Terrain patches: scale the ambient by the mesh's per-vertex sky detail (attribute 6).
    bool skyDetail = false;
};

struct ObjectInstance {
    glm::vec4 positionScale{0.0f};  // camera-relative base [m], scale
    glm::vec2 rotationSet{0.0f};    // rotation about +Y [rad], ambient set index
};
static_assert(sizeof(ObjectInstance) == 24, "ObjectInstance is read as two attributes");

struct ObjectBatch {
    const GlMesh* mesh = nullptr;
    std::vector<ObjectInstance> instances;
    // A proxy or far mesh standing in for the full one: the screen witnesses' outputs mark its
    // pixels as surface kind 4 (not a witness: the reference sees the real plant).
    bool simplified = false;
    bool vehicle = false;  // the car (its own pass in the pass timing)
};

struct DrawList {
    std::vector<TerrainDraw> terrain;
    std::vector<ObjectBatch> objects;
    std::vector<AmbientSet> ambientSets;      // indexed by ObjectInstance::rotationSet.y
    std::vector<glm::vec3> vertexIrradiance;  // see TerrainDraw::firstVertexIrradiance
    void clear() {
        terrain.clear();
        objects.clear();
        ambientSets.clear();
        vertexIrradiance.clear();
    }
};

// Copies the light, sun disc and fog parts of `sky` into `fc`.
void fillSkyConstants(const SkyLighting& sky, FrameConstants& fc);

// ---- SceneDrawer -----------------------------------------------------------------------------
class SceneDrawer {
  public:
    SceneDrawer();  // compiles the programs (shaderDirectory()), creates buffers and textures

    void setSky(const SkyLighting& sky);  // uploads the sky texture
    // Draws `list` into the bound framebuffer (depth cleared to 0 by the caller): terrain and
    // objects, then the sky where nothing was drawn; the main light's direct term shadowed by
    // `shadows` (none: unshadowed). Returns the triangles submitted.
    std::size_t draw(const DrawList& list, const FrameConstants& constants, bool cullBackFaces,
                     bool frontFaceClockwise, const ShadowBinding* shadows = nullptr);
    // Shadow casters: the depth of `list`'s terrain and objects only, both faces, with
    // `viewProj` (camera-relative -> light clip) into the bound framebuffer. Returns triangles.
    std::size_t drawDepth(const DrawList& list, const glm::mat4& viewProj);
    // Tone maps `hdrTexture` into the bound framebuffer (full-screen pass, no depth).
    void drawTonemap(GLuint hdrTexture, float exposure);
    // Times draw()'s passes (plants, car, roads, terrain, sky) into `timer` (null: none).
    void setPassTimer(PassTimer* timer) { timer_ = timer; }

  private:
    PassTimer* timer_ = nullptr;
    // Uploads every batch's instances into one buffer (grown as needed); returns their count.
    std::size_t uploadInstances(const DrawList& list);
    std::size_t drawObjectBatches(const DrawList& list, GLint simplifiedLocation,
                                  PassTimer* timer = nullptr);
    GlProgram terrain_, object_, sky_, tonemap_, caster_;
    GlBuffer constants_, shadowConstants_;
    GlTexture noShadow_;  // 1 x 1 x 1 depth array bound when a draw has no shadows
    GlBuffer instances_;
    std::size_t instanceCapacity_ = 0;
    GlBuffer ambientSets_;
    std::size_t ambientCapacity_ = 0;
    GlBuffer vertexIrradiance_;
    std::size_t vertexIrradianceCapacity_ = 0;
    GlTexture skyTexture_;
    GlVertexArray emptyVao_;
    GLint terrainOrigin_ = -1, terrainRect_ = -1, terrainCorners_ = -1, terrainPerVertex_ = -1;
    GLint terrainSkyDetail_ = -1, terrainRoad_ = -1;
    GLint objectSimplified_ = -1;
    GLint casterOrigin_ = -1, casterInstanced_ = -1;
};

}  // namespace amb
