// ProbeEnvironment.cpp — probe placement and fallback radiance from the World (see
// ProbeEnvironment.h).
#include "lighting/ProbeEnvironment.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <mutex>

#include <glm/geometric.hpp>

#include "world/Conventions.h"
#include "world/SkyGround.h"
#include "world/TerrainPatch.h"
#include "world/Vegetation.h"
#include "world/World.h"

namespace amb {

namespace {

// Height of a plant kind's proxy mesh at scale 1 [m] (top of the crown or rock).
double plantTop_m(PlantKind kind) {
    static std::once_flag once;
    static std::array<double, kPlantKinds> tops{};
    std::call_once(once, [] {
        for (int k = 0; k < kPlantKinds; ++k) {
            const WorldMesh& mesh = Vegetation::proxyMesh(static_cast<PlantKind>(k));
            double top = 0.0;
            for (std::size_t v = 1; v < mesh.positions.size(); v += 3) {
                top = std::max(top, double(mesh.positions[v]));
            }
            tops[k] = top;
        }
    });
    return tops[static_cast<int>(kind)];
}

// `world_m` in a plant's mesh frame at scale 1 (the inverse of shaders/object.vert's placing:
// scaled, turned by its rotation about +Y, moved to its base).
glm::dvec3 plantFrame(const Plant& plant, const glm::dvec3& world_m) {
    const glm::dvec3 d = (world_m - plant.position_m) / double(plant.scale);
    const double c = std::cos(double(plant.rotation_rad)), s = std::sin(double(plant.rotation_rad));
    return {c * d.x - s * d.z, d.y, s * d.x + c * d.z};
}

// Object witnesses (see Object witnesses): how far above the terrain a witness must stand (the
// reference's offset from a surface), and a plant's reach, crown or rock, at the largest scale.
constexpr double kWitnessClearance_m = 0.25;
constexpr double kLargestPlant_m = 3.2 * 2.0;

}  // namespace

bool WorldProbeEnvironment::inTheOpen(const glm::dvec3& point_m, double clearance_m,
                                      const glm::dvec3* ownBase_m) const {
    if (!(point_m.y >= world_.height(point_m.x, point_m.z) + clearance_m)) return false;
    for (const Plant& q : world_.vegetation().inDisc(point_m.x, point_m.z, kLargestPlant_m)) {
        // Among a tree's leaves (its own too): the full crown's bumps reach past its spheres.
        if (Vegetation::amongLeaves(q.kind, plantFrame(q, point_m))) return false;
        if (ownBase_m && q.position_m == *ownBase_m) continue;
        // Bushes and rocks spread wider near the ground than their spheres: their footprint,
        // up to their top (the rule that hides a terrain witness's ground, DrawnPatch::cover).
        if (q.kind == PlantKind::Bush || q.kind == PlantKind::Rock) {
            if (std::hypot(q.position_m.x - point_m.x, q.position_m.z - point_m.z) <
                    Vegetation::footprintRadius_m(q.kind) * q.scale &&
                point_m.y < q.position_m.y + plantTop_m(q.kind) * q.scale)
                return false;
            continue;
        }
        for (const PlantSphere& sphere : Vegetation::spheres(q.kind)) {
            const glm::dvec3 c = q.position_m + double(q.scale) * sphere.centre_m;
            const double r = double(q.scale) * sphere.radius_m;
            if (glm::dot(point_m - c, point_m - c) < r * r) return false;
        }
    }
    return true;
}

WorldProbeEnvironment::WorldProbeEnvironment(const World& world,
                                             const WorldProbeEnvironmentSettings& s)
    : world_(world), settings_(s) {}

glm::dvec3 WorldProbeEnvironment::placeProbe(double x_m, double z_m, double maxAside_m) const {
    const double clearance = settings_.clearance_m;
    const double water = world_.settings().waterLevel_m;
    const std::vector<Plant> plants =
        world_.vegetation().inDisc(x_m, z_m, kLargestPlant_m + maxAside_m + clearance);
    auto blocking = [&](double x, double z) -> const Plant* {
        for (const Plant& p : plants) {
            const double r = Vegetation::footprintRadius_m(p.kind) * p.scale + clearance;
            if (std::hypot(p.position_m.x - x, p.position_m.z - z) < r) return &p;
        }
        return nullptr;
    };
    auto onGround = [&](double x, double z) {
        return glm::dvec3(x, std::max(world_.height(x, z), water) + settings_.probeHeight_m, z);
    };
    const Plant* hit = blocking(x_m, z_m);
    if (!hit) return onGround(x_m, z_m);
    // Aside: rings of 8 directions at growing radii, nearest free spot first.
    const int kRings = 4, kDirections = 8;
    for (int r = 1; r <= kRings; ++r) {
        const double radius = maxAside_m * r / kRings;
        for (int d = 0; d < kDirections; ++d) {
            const double a = 2.0 * kPi * d / kDirections;
            const double x = x_m + radius * std::cos(a), z = z_m + radius * std::sin(a);
            if (!blocking(x, z)) return onGround(x, z);
        }
    }
    // Up: above the tallest plant overlapping the point.
    glm::dvec3 p = onGround(x_m, z_m);
    for (const Plant& plant : plants) {
        const double r = Vegetation::footprintRadius_m(plant.kind) * plant.scale + clearance;
        if (std::hypot(plant.position_m.x - x_m, plant.position_m.z - z_m) >= r) continue;
        p.y = std::max(p.y, plant.position_m.y + plantTop_m(plant.kind) * plant.scale + clearance);
    }
    return p;
}

const char* toString(ProbePlacement placement) {
    switch (placement) {
        case ProbePlacement::AtPoint:
            return "point";
        case ProbePlacement::MovedAside:
            return "aside";
        case ProbePlacement::Lifted:
            return "lifted";
    }
    return "?";
}

ProbePlacement ProbeEnvironment::placement(double x_m, double z_m, double maxAside_m) const {
    const glm::dvec3 p = placeProbe(x_m, z_m, maxAside_m);
    return std::hypot(p.x - x_m, p.z - z_m) > 1e-9 ? ProbePlacement::MovedAside
                                                   : ProbePlacement::AtPoint;
}

ProbePlacement WorldProbeEnvironment::placement(double x_m, double z_m, double maxAside_m) const {
    const glm::dvec3 p = placeProbe(x_m, z_m, maxAside_m);
    if (std::hypot(p.x - x_m, p.z - z_m) > 1e-9) return ProbePlacement::MovedAside;
    const double ground =
        std::max(world_.height(x_m, z_m), world_.settings().waterLevel_m) + settings_.probeHeight_m;
    return p.y > ground + 1e-9 ? ProbePlacement::Lifted : ProbePlacement::AtPoint;
}

double WorldProbeEnvironment::sunAngularSpeed_radPerHour() const {
    return world_.sky().sunAngularSpeed_radPerHour();
}

void WorldProbeEnvironment::fallbackCubeMap(double timeOfDay_h, int n,
                                            std::vector<float>& rgb) const {
    // Texel directions and solid angles (2/n)^2 / |d|^3 (d has unit major axis), then the sky
    // over flat ground there (world/SkyGround.h).
    std::vector<glm::dvec3> dirs(std::size_t(6) * n * n);
    std::vector<double> omegas(dirs.size());
    for (int f = 0; f < kCubeFaces; ++f) {
        for (int j = 0; j < n; ++j) {
            for (int i = 0; i < n; ++i) {
                const glm::dvec3 d = cubeTexelDirection(f, i, j, n);
                const double len2 = glm::dot(d, d);
                const std::size_t t = (std::size_t(f) * n + j) * n + i;
                dirs[t] = d / std::sqrt(len2);
                omegas[t] = (4.0 / (double(n) * n)) / (len2 * std::sqrt(len2));
            }
        }
    }
    evaluateSkyGround(world_.sky(), timeOfDay_h, dirs, omegas, rgb);
}

const char* toString(ObjectKind kind) {
    switch (kind) {
        case ObjectKind::Car:
            return "car";
        case ObjectKind::TreeBase:
            return "tree_base";
        case ObjectKind::TreeCrown:
            return "tree_crown";
    }
    return "?";
}

std::vector<ObjectWitness> WorldProbeEnvironment::objectWitnesses(double cameraX_m,
                                                                  double cameraZ_m, int trees,
                                                                  double near_m, double far_m,
                                                                  double carHeight_m,
                                                                  int measuredIndex) const {
    std::vector<ObjectWitness> out;
    ObjectWitness car;
    car.kind = ObjectKind::Car;
    car.groundX_m = cameraX_m, car.groundZ_m = cameraZ_m;
    car.position_m = glm::dvec3(
        cameraX_m,
        std::max(world_.height(cameraX_m, cameraZ_m), world_.settings().waterLevel_m) + carHeight_m,
        cameraZ_m);
    out.push_back(car);
    if (trees <= 0) return out;
    // Trees in the ring, ordered by a hash of their position and the measured frame.
    std::vector<std::pair<std::uint64_t, Plant>> candidates;
    for (const Plant& p : world_.vegetation().inDisc(cameraX_m, cameraZ_m, far_m)) {
        if (p.kind != PlantKind::Conifer && p.kind != PlantKind::Broadleaf) continue;
        const double d = std::hypot(p.position_m.x - cameraX_m, p.position_m.z - cameraZ_m);
        if (d < near_m || d > far_m) continue;
        std::uint64_t h = std::uint64_t(std::int64_t(std::llround(p.position_m.x * 16.0))) *
                              0x9E3779B97F4A7C15ull ^
                          std::uint64_t(std::int64_t(std::llround(p.position_m.z * 16.0))) *
                              0xC2B2AE3D27D4EB4Full ^
                          std::uint64_t(measuredIndex) * 0x165667B19E3779F9ull;
        h ^= h >> 29;
        h *= 0xBF58476D1CE4E5B9ull;
        h ^= h >> 32;
        candidates.emplace_back(h, p);
    }
    std::sort(candidates.begin(), candidates.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    // A witness stands in the open: kWitnessClearance_m above the terrain (its reference is
    // captured there) and outside every other plant's spheres (a crown's, a trunk's, a rock's).
    // A point inside another plant shows nothing the camera sees; that tree is passed over.
    const auto clear = [&](const glm::dvec3& at, const Plant& own) {
        return inTheOpen(at, kWitnessClearance_m, &own.position_m);
    };
    int taken = 0;
    for (std::size_t t = 0; taken < trees && t < candidates.size(); ++t) {
        const Plant& p = candidates[t].second;
        glm::dvec3 toward(cameraX_m - p.position_m.x, 0.0, cameraZ_m - p.position_m.z);
        toward /= std::max(glm::length(toward), 1e-9);
        const double crown = Vegetation::footprintRadius_m(p.kind) * p.scale;
        ObjectWitness base;
        base.kind = ObjectKind::TreeBase;
        base.groundX_m = p.position_m.x, base.groundZ_m = p.position_m.z;
        base.position_m = p.position_m + 0.5 * crown * toward + glm::dvec3(0.0, 1.0, 0.0);
        base.normal = toward;
        // The trunk's mesh is drawn with what its crown leaves of the tree's ambient.
        const glm::dvec3 n = plantFrame(p, p.position_m + base.normal) - plantFrame(p, p.position_m);
        base.ambientShare =
            Vegetation::crownSkyShare(p.kind, plantFrame(p, base.position_m), glm::normalize(n));
        ObjectWitness top = base;
        top.kind = ObjectKind::TreeCrown;
        top.ambientShare = 1.0;
        top.position_m = p.position_m + (crown + settings_.clearance_m) * toward +
                         glm::dvec3(0.0, 0.6 * plantTop_m(p.kind) * p.scale, 0.0);
        if (!clear(base.position_m, p) || !clear(top.position_m, p)) continue;
        out.push_back(base);
        out.push_back(top);
        ++taken;
    }
    return out;
}

DrawnPatch WorldProbeEnvironment::drawnPatch(double x_m, double z_m,
                                             const glm::dvec3& camera_m) const {
    if (!(camera_m == leavesCamera_)) {
        leaves_.clear();
        for (const PatchKey& key : TerrainPatchCache(world_).selectPatches(camera_m)) {
            const double size = TerrainPatch::size_m(key.level);
            leaves_.push_back({double(key.i) * size, double(key.k) * size, size});
        }
        leavesCamera_ = camera_m;
    }
    DrawnPatch p;
    p.surface_m = glm::dvec3(x_m, world_.height(x_m, z_m), z_m);
    p.surfaceNormal = world_.normal(x_m, z_m);
    // A tree's footprint is its crown's; its trunk, about kTrunkRadius_m x its scale, hides the
    // ground as bushes and rocks do within theirs.
    constexpr double kTrunkRadius_m = 0.4;
    for (const Plant& plant : world_.vegetation().inDisc(x_m, z_m, 3.2 * 2.0)) {
        const double d = std::hypot(plant.position_m.x - x_m, plant.position_m.z - z_m);
        const bool tree = plant.kind == PlantKind::Conifer || plant.kind == PlantKind::Broadleaf;
        if (d >= Vegetation::footprintRadius_m(plant.kind) * plant.scale) continue;
        if (!tree || d < kTrunkRadius_m * plant.scale) {
            p.cover = GroundCover::Hidden;
            break;
        }
        p.cover = GroundCover::UnderCrown;
    }
    for (const auto& [x0, z0, size] : leaves_) {
        if (!(x_m >= x0 && x_m < x0 + size && z_m >= z0 && z_m < z0 + size)) continue;
        p.x0_m = x0, p.z0_m = z0, p.size_m = size;
        p.quads = TerrainPatch::kPatchQuads;
        for (int c = 0; c < 4; ++c) {
            const double x = x0 + ((c & 1) ? size : 0.0), z = z0 + ((c & 2) ? size : 0.0);
            p.corner_m[std::size_t(c)] = glm::dvec3(x, world_.height(x, z), z);
            p.cornerNormal[std::size_t(c)] = world_.normal(x, z);
        }
        break;
    }
    return p;
}

struct WorldProbeEnvironment::Mesh {
    explicit Mesh(const World& world) : patches(world) {}
    TerrainPatchCache patches;
    glm::dvec3 camera{std::nan("")};
    TerrainMesh mesh;
};

WorldProbeEnvironment::~WorldProbeEnvironment() = default;

DrawnCell WorldProbeEnvironment::drawnCell(double x_m, double z_m,
                                           const glm::dvec3& camera_m) const {
    if (!mesh_) mesh_ = std::make_unique<Mesh>(world_);
    Mesh& m = *mesh_;
    if (!(camera_m == m.camera)) {
        m.mesh = m.patches.build(m.patches.selectPatches(camera_m), terrainMeshOrigin(camera_m));
        m.camera = camera_m;
    }
    DrawnCell cell;
    for (const TerrainPatchDraw& p : m.mesh.patches) {
        const PatchKey& key = p.key;
        const double size = TerrainPatch::size_m(key.level);
        const double x0 = TerrainPatch::originX_m(key), z0 = TerrainPatch::originZ_m(key);
        if (!(x_m >= x0 && x_m < x0 + size && z_m >= z0 && z_m < z0 + size)) continue;
        constexpr int kQ = TerrainPatch::kPatchQuads, kV = TerrainPatch::kVerticesPerSide;
        const double s = TerrainPatch::spacing_m(key.level);
        const double u = (x_m - x0) / s, w = (z_m - z0) / s;
        const int a = std::clamp(int(std::floor(u)), 0, kQ - 1);
        const int b = std::clamp(int(std::floor(w)), 0, kQ - 1);
        const auto& pos = m.mesh.mesh.positions;
        const auto& nrm = m.mesh.mesh.normals;
        for (int c = 0; c < 4; ++c) {
            const std::size_t v = p.firstVertex + std::size_t((b + (c >> 1)) * kV + a + (c & 1));
            cell.vertex_m[std::size_t(c)] =
                m.mesh.origin_m + glm::dvec3(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]);
            cell.normal[std::size_t(c)] = glm::dvec3(nrm[3 * v], nrm[3 * v + 1], nrm[3 * v + 2]);
        }
        cell.weight = quadTriangleWeights(u - a, w - b);
        cell.spacing_m = s;
        cell.known = true;
        break;
    }
    return cell;
}

}  // namespace amb
