// RendererScene.h — turns the world into draw lists: the terrain LOD mesh (world/TerrainPatch.h),
// vegetation instanced by kind with distance LOD, road ribbons, each frustum-culled; and the
// capture scene (terrain proxy, tree proxies, road) around a probe.
//
// [SECTION] RendererScene   main-view and capture draw lists
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <optional>
#include <unordered_set>
#include <utility>
#include <vector>

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include "app/render/RendererCore.h"
#include "world/TerrainPatch.h"
#include "world/Vehicle.h"  // VehiclePose

namespace amb {

class World;

struct RendererSceneSettings {
    TerrainLodSettings terrain{};
    // Plant LOD by projected height on screen: the full mesh while a plant is at least
    // fullMeshMinPixels tall, the world's proxy mesh while at least proxyMinPixels, a far mesh
    // (an 8-triangle ellipsoid hull of the crown, 6 vertices) while at least farMinPixels, none
    // below; and nothing beyond plantRange_m. The view sets pixelsPerRadian (image height /
    // vertical fov).
    double fullMeshMinPixels = 90.0;
    double proxyMinPixels = 30.0;
    double farMinPixels = 5.0;
    double plantRange_m = 600.0;
    double pixelsPerRadian = 360.0 / 1.0471976;
    double captureTerrainRadius_m = 2000.0;
    double captureTreeRange_m = 150.0;  // tree proxies in a capture nearer than this
    double roadLift_m = 0.12;           // road ribbons float this far above the terrain
    // Ask a plant's ambient at the height of its spheres' area-weighted centre (world/
    // Vegetation.h spheres) instead of at its base: the full captures, whose surface light may
    // vary with height (lighting/BounceField.h "Two layers"). The methods' fields do not.
    bool objectsAtCrown = false;
};

struct SceneStats {
    std::size_t terrainPatches = 0, terrainPatchesDrawn = 0;
    std::size_t objectsDrawn = 0;
    bool terrainRebuilt = false;
    // Visible patches in the ambient's vertex range: lit per vertex, and waiting their turn
    // (blending their corners; terrainVertexPointsPerFrame).
    std::size_t terrainPatchesVertex = 0, terrainPatchesWaiting = 0;
};

class RendererScene {
  public:
    RendererScene(const World& world, const RendererSceneSettings& settings = {});
    ~RendererScene();

    // Main view: `viewProj` maps camera-relative positions (world - eye) to clip space. Terrain
    // patches blend the ambient of their corners, or, nearer the eye than the ambient's
    // terrainVertexRange_m, take it at every mesh vertex.
    void buildView(const glm::dvec3& eye_m, const glm::mat4& viewProj, const AmbientSource& ambient,
                   DrawList& out, SceneStats* stats = nullptr);
    // The car drawn by the next buildView calls (lit like any object: its own SH set), or none.
    void setVehicle(const std::optional<VehiclePose>& pose) { vehicle_ = pose; }
    const std::optional<VehiclePose>& vehicle() const { return vehicle_; }
    // Capture scene around a probe (no culling: all six faces share it). Positions relative to
    // `probe_m`. Plants whose base lies within nearRadius_m (horizontally) are left out.
    void buildCapture(const glm::dvec3& probe_m, const AmbientSource& ambient, DrawList& out,
                      double nearRadius_m = 0.0);
    // Shadow casters of the main view's scene for one cascade (app/render/ShadowMap.h):
    // `lightViewProj` maps positions relative to `eye_m` to the cascade's light clip space;
    // terrain patches of the LOD mesh around `eye_m` (buildView's), road pieces, every plant
    // kind and (withVehicle) the car, each culled to the cascade and plants at a LOD by their
    // size in texels of `texel_m` (full mesh, proxy, far mesh). No ambient is looked up.
    void buildCasters(const glm::dvec3& eye_m, const glm::mat4& lightViewProj, double texel_m,
                      DrawList& out, bool withVehicle = true, bool withPlants = true);
    // Shadow casters of the capture scene over a region: a terrain proxy centred on `centre_m`
    // and the trees (all of them: a tree in the near field still shades the ground the probe
    // sees), culled to the map, at the LOD of their height in texels of `texel_m` as the main
    // view's cascades choose it (on a map of about a metre a texel, broadleaves and the smaller
    // conifers take the 8-triangle hull); positions relative to `centre_m`.
    void buildCaptureCasters(const glm::dvec3& centre_m, const glm::mat4& lightViewProj,
                             double texel_m, DrawList& out);

    const World& world() const { return world_; }
    const RendererSceneSettings& settings() const { return settings_; }

  private:
    struct RoadChunk;
    // Terrain mesh vertices whose ambient the draw asks for (patches lit per vertex): the mesh
    // vertex, its world position and normal (asked as points, no patch mean).
    struct VertexPoints {
        std::vector<std::uint32_t> index;
        std::vector<glm::dvec3> at, normal;
    };
    void updateTerrain(const glm::dvec3& eye_m);
    // With `terrain`, those vertices are asked in the roads' batch, and the terrain draws
    // already in `out` with firstVertexIrradiance >= 0 are pointed at their values.
    void addRoads(const glm::dvec3& eye_m, const glm::mat4* viewProj, double range_m,
                  const AmbientSource& ambient, DrawList& out,
                  const VertexPoints* terrain = nullptr);
    // With `alsoAt`, that point's set (the car's) is asked in the plants' batch, into *alsoSet.
    void addPlants(const glm::dvec3& centre_m, const glm::mat4* viewProj, bool capture,
                   const AmbientSource& ambient, DrawList& out, std::size_t* drawn,
                   double nearRadius_m = 0.0, const glm::dvec3* alsoAt = nullptr,
                   std::uint32_t* alsoSet = nullptr);
    // Plants casting into a light frustum: trees only (`treesOnly`, the capture scene) or every
    // kind, at a LOD by size in texels (texel_m 0: proxies).
    void addPlantCasters(const glm::dvec3& eye_m, const glm::mat4& lightViewProj,
                         double texel_m, bool treesOnly, DrawList& out);

    const World& world_;
    RendererSceneSettings settings_;
    TerrainPatchCache terrainCache_;
    std::vector<PatchKey> terrainLeaves_;
    TerrainMesh terrainMesh_;
    GlMesh terrainGl_;  // one mesh holding every selected patch
    struct PatchBounds {
        glm::dvec3 min, max;
    };
    std::vector<PatchBounds> terrainBounds_;
    // The patches lit per vertex (terrainVertexRange_m), kept while in range; of the visible
    // ones in range, how many blended their corners in the last buildView, waiting their turn
    // (terrainVertexPointsPerFrame).
    std::unordered_set<PatchKey, PatchKeyHash> vertexLit_;
    std::size_t vertexWaiting_ = 0;
    // Proxy terrain of the last capture and where it was centred.
    GlMesh captureTerrain_;
    WorldMesh captureProxy_;  // captureTerrain_'s vertices, lit per capture
    std::vector<glm::dvec3> captureAt_, captureNormal_;
    glm::dvec3 captureCentre_{1e300};
    // Proxy terrain of the capture shadow map's region and its centre.
    GlMesh shadowTerrain_;
    glm::dvec3 shadowTerrainCentre_{1e300};
    std::vector<RoadChunk> roads_;
    std::array<GlMesh, 4> plantMeshes_, plantProxies_, plantFar_;
    std::array<float, 4> plantHeight_m_{};
    // With objectsAtCrown: how far above its base a plant of scale 1 is asked for its ambient.
    std::array<double, 4> plantAmbientHeight_m_{};
    WorldMesh vehicleLevel_;  // the car's mesh, level; vehicleMesh_ is it pitched
    GlMesh vehicleMesh_;
    double vehicleMeshPitch_rad_ = 0.0;
    std::optional<VehiclePose> vehicle_;
    TerrainSurface terrainSurface_;  // the drawn terrain, where plants stand in the main view
    // addPlants' scratch: the instances (batch, instance) whose own ambient set is asked for in
    // one batch, where they stand, and the sets' indices.
    std::vector<std::pair<std::size_t, std::size_t>> pendingSlot_;
    std::vector<glm::dvec3> pendingAt_;
    std::vector<std::uint32_t> pendingIndex_;
};

}  // namespace amb
