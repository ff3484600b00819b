// Vegetation.h — trees, bushes and rocks placed deterministically per tile.
//
// Placement is a Matérn type-II hard-core process on an integer cell lattice (a Poisson-disc-like
// pattern built locally): every cell holds one candidate with a random position and priority
// derived from (seed, cell key); a candidate survives its habitat test with a probability equal
// to the local density (slope, height, moisture; zero on roads, water, steep rock and snow) and is
// kept only if no surviving candidate within the minimum spacing has a higher priority. A cell is
// at least the spacing wide, so the test needs only the 3x3 neighbouring cells: results do not
// depend on which tile asks, and any two kept plants of a layer are at least the spacing apart.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include <glm/vec3.hpp>

#include "world/WorldMesh.h"

namespace amb {

class World;

enum class PlantKind : int { Conifer = 0, Broadleaf = 1, Bush = 2, Rock = 3 };
inline constexpr int kPlantKinds = 4;
const char* toString(PlantKind kind);

// A sphere standing in for part of a plant (crown, trunk, rock) at scale 1, origin at the base of
// the trunk, +Y up [m], with the albedo of what it stands for: the near field's occluders
// (lighting/NearField.h).
struct PlantSphere {
    glm::dvec3 centre_m{0.0};
    double radius_m = 0.0;
    glm::dvec3 albedo{0.0};
};

struct Plant {
    glm::dvec3 position_m{0.0};  // base of the trunk on the ground (world, y = World::height)
    PlantKind kind = PlantKind::Conifer;
    float scale = 1.0f;         // multiplies the kind's mesh (unit mesh sizes in metres)
    float rotation_rad = 0.0f;  // about +Y
};

class Vegetation {
  public:
    explicit Vegetation(const World& world);
    ~Vegetation();

    // Tiles are kTile_m squares with integer keys: tile (i, k) covers
    // [i * kTile_m, (i + 1) * kTile_m) x [k * kTile_m, (k + 1) * kTile_m).
    static constexpr double kTile_m = 80.0;
    static constexpr double kTreeSpacing_m = 5.0;         // minimum distance between trees
    static constexpr double kSmallSpacing_m = 4.0;        // minimum distance between bushes/rocks
    static constexpr double kSmallTreeClearance_m = 1.5;  // bushes/rocks keep off trunks
    // Plants keep this far beyond a road's half width [m].
    static constexpr double kRoadClearance_m = 3.0;
    // Slope (1 - normal.y) above which nothing but rocks grows, and above which nothing at all.
    static constexpr double kTreeMaxSlope = 0.16;
    static constexpr double kRockMaxSlope = 0.35;

    // Plants of one tile, sorted by position (cached; thread-safe).
    std::shared_ptr<const std::vector<Plant>> tile(std::int64_t i, std::int64_t k) const;
    // Plants whose base lies within radius_m (XZ) of (x, z).
    std::vector<Plant> inDisc(double x_m, double z_m, double radius_m) const;
    static std::int64_t tileIndex(double coordinate_m);

    // Probability in [0, 1] that a tree candidate survives its habitat test at (x, z);
    // 0 on roads, water, steep rock and snow.
    double treeDensity(double x_m, double z_m) const;

    // Unit meshes: the full mesh (trunk + crown, a few hundred triangles) and the coarse proxy for
    // probe capture (a few dozen). Origin at the base of the trunk, +Y up, metres.
    static const WorldMesh& mesh(PlantKind kind);
    static const WorldMesh& proxyMesh(PlantKind kind);
    // The kind's shape as a few spheres (crown, trunk, rock) of about the full mesh's extent: a
    // crown of one or three spheres, a trunk of thin spheres stacked up to the crown.
    static const std::vector<PlantSphere>& spheres(PlantKind kind);
    // The share of a surface's ambient the kind's crown leaves it, at `point_m` (scale 1, the
    // kind's frame) with unit `normal`: the cosine-weighted fraction of 72 directions about
    // the normal along which a ray from the point meets none of the full mesh's crown
    // triangles (those without bark). 1 for a kind without a crown (bushes, rocks). The
    // meshes' trunks carry 1 - this a vertex (WorldMesh::occlusion): a tree's one ambient
    // leaves the tree's own crown out (lighting/NearField.h), yet a trunk stands under it.
    static double crownSkyShare(PlantKind kind, const glm::dvec3& point_m,
                                const glm::dvec3& normal);
    // Whether `point_m` (scale 1, the kind's frame) lies among the full mesh's leaves: each of
    // six rays from it, along the axes (tilted a little), meets a crown triangle. A point there sees leaves all
    // round, which no drawn surface does (the object witnesses keep out of them). False for a
    // kind without a crown.
    static bool amongLeaves(PlantKind kind, const glm::dvec3& point_m);
    // Radius of the kind's footprint at scale 1 (crown or rock) [m].
    static double footprintRadius_m(PlantKind kind);

  private:
    struct Habitat;
    std::vector<Plant> generateTile(std::int64_t i, std::int64_t k) const;

    const World& world_;
    std::uint64_t seed_;
    mutable std::mutex cacheMutex_;
    mutable std::unordered_map<std::uint64_t, std::shared_ptr<const std::vector<Plant>>> cache_;
};

}  // namespace amb
