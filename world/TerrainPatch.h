// TerrainPatch.h — the terrain as square patches on a quadtree with level of detail by distance,
// crack-free between levels, handed to the renderer as plain arrays; and the coarse terrain proxy
// mesh for probe capture.
//
// Lattice. Every vertex sits on an integer lattice of spacing kFinestSpacing_m (a power of two, so
// x = integer * spacing is exact in double and every patch computes a shared vertex at the same
// bit-identical position). A patch of level L has kPatchQuads x kPatchQuads quads of spacing
// kFinestSpacing_m * 2^L; its key (L, i, k) covers [i, i + 1) x [k, k + 1) times its size.
//
// Cracks. Where a patch borders a coarser one, its edge vertices between two coarse vertices are
// moved onto the coarse edge (linear interpolation of the coarse edge's own rendered vertices):
// a vertex's rendered height is defined once, from the coarsest patch that contains it, so every
// patch sharing an edge renders it identically (TerrainPatchCache::build, "stitching").
//
// Corner values. A value given at the patch corners and blended bilinearly across each patch (the
// ambient irradiance) is stitched the same way: a corner inside a coarser leaf's edge takes the
// linear interpolation of that edge's two end values, so a finer patch's edge blends exactly as
// the coarser edge beside it (TerrainMesh::corners, stitchCornerValues).
//
// Caching. A TerrainPatch holds the native (unstitched) samples of one key and depends on nothing
// else; stitching runs on the edges only, each frame.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <memory>
#include <unordered_map>
#include <vector>

#include <glm/vec3.hpp>

#include "world/Heightfield.h"
#include "world/WorldMesh.h"

namespace amb {

class World;

// Ground albedo as the terrain draws it, in the patches and in the capture's proxy alike
// (docs/ARCHITECTURE.md "Terrain and objects"): World::classify's blend of grass, rock, sand,
// snow, water and road, with its edges made ragged by noise (the slope where rock shows, the snow
// line, the beach), stone that varies in strata and tint, scree on high ground, and a brightness
// that varies on three scales, so that no slope is one flat colour. Noise finer than two vertex
// spacings fades out, so coarse patches do not alias it. Thread-safe.
class TerrainAlbedo {
  public:
    explicit TerrainAlbedo(const World& world);
    // At (x, z) of height h, road weight `road` and unit normal n, drawn `spacing_m` apart.
    glm::vec3 at(double x_m, double z_m, double height_m, double road, const glm::dvec3& normal,
                 double spacing_m) const;

  private:
    const World& world_;
    Heightfield::Octave vast_, broad_, mid_, fine_;  // 400 m, 90 m, 23 m, 7 m
};

struct PatchKey {
    int level = 0;       // 0 = finest
    std::int64_t i = 0;  // patch index along x at this level
    std::int64_t k = 0;  // patch index along z at this level
    bool operator==(const PatchKey& o) const { return level == o.level && i == o.i && k == o.k; }
    bool operator!=(const PatchKey& o) const { return !(*this == o); }
};

struct PatchKeyHash {
    std::size_t operator()(const PatchKey& key) const;
};

// Native samples of one patch: (kPatchQuads + 1)^2 vertices, row-major in z then x.
struct TerrainPatch {
    static constexpr int kPatchQuads = 16;
    static constexpr int kVerticesPerSide = kPatchQuads + 1;
    static constexpr double kFinestSpacing_m = 2.0;

    PatchKey key;
    std::vector<double> heights_m;            // world heights (roads flattened in)
    std::vector<float> normals;               // xyz per vertex, from the height grid at this level
    std::vector<float> albedo;                // rgb per vertex
    std::array<glm::dvec3, 4> cornerNormals;  // World::normal at the corners (exact, shared)
    // Per vertex, two floats: the terrain's own sky visibility V there and Vc, the bilinear
    // blend of V at the patch's corners. The draw blends the ambient from the patch's corners,
    // 32 m apart beside the camera, so a gully 15 m wide falls between them. Each vertex of a
    // patch whose vertices lie at most kSkyDetailMaxSpacing_m apart takes V = 1 - mean over 8
    // directions of sin^2(horizon above its tangent plane), the horizon searched in the patch's
    // own height grid out to kSkyDetailRadius_m. The draw (shaders/terrain.frag) scales the
    // corners' ambient A by (V + (1 - V) b) / (Vc + (1 - Vc) b): what the walls hide comes back
    // as their light, b = rho (A + D) / A, the vertex's albedo rho and the main light's D on
    // open ground. V = Vc at the corners (whose value the near field gives) and where the
    // terrain is smooth; V < Vc on a gully's floor. Empty for coarser patches, and by default
    // where no gully cuts within the reach (SkyDetail::WhereGullies): the rest of the world's
    // relief is tens of metres across, which the corners resolve (on the shipped drives the
    // detail there moves V from Vc by under 0.02 at the 99th percentile; tested).
    std::vector<float> skyDetail;
    static constexpr double kSkyDetailRadius_m = 16.0;
    static constexpr double kSkyDetailMaxSpacing_m = 4.0;

    static double spacing_m(int level);  // vertex spacing
    static double size_m(int level);     // edge length
    static std::int64_t latticeStep(int level) { return std::int64_t(1) << level; }
    // World XZ of the patch's minimum corner.
    static double originX_m(const PatchKey& key) { return double(key.i) * size_m(key.level); }
    static double originZ_m(const PatchKey& key) { return double(key.k) * size_m(key.level); }

    // Where a fine enough patch carries skyDetail: where gullies may cut within its reach
    // (Heightfield::mayHaveGullies), or on every such patch (to measure what it would do).
    enum class SkyDetail { WhereGullies, Everywhere };

    // Samples a patch (pure function of the key and mode; thread-safe).
    static TerrainPatch generate(const World& world, const PatchKey& key,
                                 SkyDetail mode = SkyDetail::WhereGullies);
};

// Per-patch draw information in a TerrainMesh. Corners are ordered (x0, z0), (x1, z0), (x0, z1),
// (x1, z1): the minimum corner first, x varying fastest.
struct TerrainPatchDraw {
    PatchKey key;
    std::uint32_t firstIndex = 0, indexCount = 0;
    std::uint32_t firstVertex = 0, vertexCount = 0;
    std::array<glm::dvec3, 4> corners_m;         // world positions as rendered (stitched)
    std::array<glm::dvec3, 4> cornerNormals;     // unit, World::normal at the corner
    std::array<std::uint32_t, 4> cornerIndex{};  // into TerrainMesh::corners
};

// A corner of the leaves, held once however many patches share it. Evaluated, or, inside a
// coarser leaf's edge, the linear interpolation of that edge's end corners:
// value = (1 - t) value[from[0]] + t value[from[1]].
struct TerrainCorner {
    glm::dvec3 position_m{0.0};           // as rendered (stitched)
    glm::dvec3 normal{0.0};               // unit, World::normal at the corner
    std::array<std::uint32_t, 2> from{};  // both its own index when evaluated
    float t = 0.0f;
    // Evaluated: the size of the coarsest leaf it is a corner of, the patches its value is
    // blended across [m] (the near field's patch mean, lighting/NearField.h).
    double patch_m = 0.0;
    bool evaluated() const { return from[0] == from[1]; }
};

struct TerrainMesh {
    glm::dvec3 origin_m{0.0};  // positions in `mesh` are relative to this
    WorldMesh mesh;            // all patches; indices are absolute into the mesh
    std::vector<TerrainPatchDraw> patches;
    // Every leaf corner once; an interpolated corner comes after the corners it reads.
    std::vector<TerrainCorner> corners;
};

// Corner values stitched across LOD boundaries (docs/ARCHITECTURE.md "Terrain and objects").
// The corners whose values must be evaluated to draw the patches `patches` (indices into
// mesh.patches) stitched: their evaluated corners and the ends of the coarser edges their other
// corners read, each once, ascending. O(patches).
std::vector<std::uint32_t> cornersToEvaluate(const TerrainMesh& mesh,
                                             const std::vector<std::size_t>& patches);
// values[c] for every corner of `corners`, the evaluated ones set: fills in the interpolated
// ones (in list order, so chains along ever coarser edges resolve). O(corners).
void stitchCornerValues(const std::vector<TerrainCorner>& corners, glm::vec3* values);

// The weights with which a quad's two triangles, as TerrainPatchCache::build packs them,
// interpolate values given at its vertices (v00, v10, v01, v11) at (fu, fw) in [0, 1]^2 of the
// quad: (v00, v01, v10) where fu + fw <= 1, (v10, v01, v11) beyond; one weight is 0. What the
// rasteriser does to a value per vertex across the drawn surface (the heights, and the ambient
// of a patch lit per vertex).
std::array<double, 4> quadTriangleWeights(double fu, double fw);

// The origin the main view's terrain mesh is built about for an eye at `eye_m`: the eye snapped
// to a 256 m lattice, y 0, so float positions stay small and exact enough (the meter builds the
// same mesh about the same origin: its heights round as the draw's do).
inline glm::dvec3 terrainMeshOrigin(const glm::dvec3& eye_m) {
    constexpr double kSnap_m = 256.0;
    return {std::floor(eye_m.x / kSnap_m) * kSnap_m, 0.0, std::floor(eye_m.z / kSnap_m) * kSnap_m};
}

// The drawn terrain surface of a TerrainMesh (stitched heights, two triangles per quad as packed)
// at any (x, z) inside its leaves: where objects placed on the terrain must stand, since far
// patches are coarse and their surface lies up to metres off the true height.
class TerrainSurface {
  public:
    TerrainSurface() = default;
    explicit TerrainSurface(const TerrainMesh& mesh);
    // Height of the drawn surface [m]; NaN outside every leaf. Remembers the last leaf it used
    // (not thread-safe), so nearby queries in a row are cheap.
    double heightAt(double x_m, double z_m) const;
    // Where an object of footprint radius_m centred at (x, z) stands on the drawn surface: the
    // lowest of it at the centre and at four points radius_m away along x and z, so that no side
    // of its base hangs above a slope. NaN where the centre is outside every leaf.
    double baseUnder(double x_m, double z_m, double radius_m) const;

  private:
    const TerrainMesh* mesh_ = nullptr;
    std::unordered_map<PatchKey, std::size_t, PatchKeyHash> index_;
    int minLevel_ = 0, maxLevel_ = -1;
    mutable std::size_t last_ = 0;
    double heightIn(std::size_t patch, double x_m, double z_m) const;
};

struct TerrainLodSettings {
    int coarsestLevel = 8;             // patch size 32 m * 2^8 = 8192 m
    double splitFactor = 1.5;          // split a patch while its distance < splitFactor * size
    double viewRadius_m = 8000.0;      // patches beyond this horizontal distance are left out
    std::size_t cacheCapacity = 4096;  // patches kept when unused
};

class TerrainPatchCache {
  public:
    explicit TerrainPatchCache(const World& world, TerrainLodSettings settings = {});

    // Quadtree leaves for a camera: a patch splits while the camera (its height above the
    // ground counted) is closer than splitFactor * its size. Deterministic.
    std::vector<PatchKey> selectPatches(const glm::dvec3& camera_m) const;
    // Generates missing patches (in parallel), stitches edges to coarser neighbours and packs
    // everything relative to origin_m.
    TerrainMesh build(const std::vector<PatchKey>& leaves, const glm::dvec3& origin_m);
    TerrainMesh build(const glm::dvec3& camera_m, const glm::dvec3& origin_m) {
        return build(selectPatches(camera_m), origin_m);
    }
    // The cached native samples of a key (generated on demand).
    std::shared_ptr<const TerrainPatch> patch(const PatchKey& key);
    std::size_t cachedPatches() const { return cache_.size(); }
    std::size_t generatedPatches() const { return generated_; }

  private:
    const World& world_;
    TerrainLodSettings settings_;
    struct Entry {
        std::shared_ptr<const TerrainPatch> patch;
        std::uint64_t lastUse = 0;
    };
    std::unordered_map<PatchKey, Entry, PatchKeyHash> cache_;
    std::uint64_t frame_ = 0;
    std::size_t generated_ = 0;
};

// Coarse terrain proxy for probe capture: a grid centred on (centre.x, centre.z) whose spacing
// grows geometrically from `innerSpacing_m` to reach radius_m in `stepsPerSide` steps, so the
// ground near the probe is detailed and the horizon is cheap. (2 stepsPerSide)^2 * 2 triangles
// (2048 for the default). Positions relative to centre_m; roads flattened in; albedo per vertex.
WorldMesh makeTerrainProxy(const World& world, const glm::dvec3& centre_m, double radius_m = 2000.0,
                           int stepsPerSide = 16, double innerSpacing_m = 6.0);

}  // namespace amb
