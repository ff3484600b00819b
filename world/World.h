// World.h — the generated world: terrain with roads flattened in, materials, vegetation, sky.
// The one object the renderer, the capture scene and the camera paths ask about the world.
#pragma once

#include <memory>

#include <glm/vec3.hpp>

#include "world/Heightfield.h"
#include "world/Road.h"
#include "world/Sky.h"
#include "world/WorldSettings.h"

namespace amb {

enum class Material : int { Grass = 0, Rock = 1, Sand = 2, Snow = 3, Water = 4, Road = 5 };

class Vegetation;

// Everything known about one ground point, computed together (cheaper than separate queries).
struct GroundSample {
    double height_m = 0.0;  // terrain with roads flattened in
    glm::dvec3 normal{0, 1, 0};
    double moisture = 0.0;    // [0, 1]
    double roadWeight = 0.0;  // 1 on the road surface, 0 beyond the shoulder
    Material material = Material::Grass;
    glm::vec3 albedo{0.0f};  // linear RGB in [0, 1]
};

class World {
  public:
    explicit World(const WorldSettings& settings);
    ~World();

    const WorldSettings& settings() const;
    const Heightfield& heightfield() const;
    const RoadNetwork& roads() const;
    const Sky& sky() const;
    const Vegetation& vegetation() const;

    double height(double x_m, double z_m) const;      // terrain with roads flattened in
    glm::dvec3 normal(double x_m, double z_m) const;  // unit, of height()
    Material material(double x_m, double z_m) const;
    glm::vec3 albedo(double x_m, double z_m) const;  // linear RGB in [0, 1]
    // Height, normal, moisture, road weight, material and albedo in one call.
    GroundSample sample(double x_m, double z_m) const;

    // Height with roads plus the road weight (1 on the road surface, 0 beyond the shoulder).
    double heightAndRoad(double x_m, double z_m, double* roadWeight) const;
    // The road weight alone (no terrain height: cheap).
    double roadWeight(double x_m, double z_m) const;
    // Whether a road's surface or shoulder reaches within radius_m of (x, z). Where none does,
    // every point of that disc has the heightfield's height and road weight 0, so a caller
    // sampling the disc may ask the heightfield alone (one road query, not one a sample).
    bool roadWithin(double x_m, double z_m, double radius_m) const;
    // Material, moisture and albedo of a point whose height, road weight and normal are known
    // (lets grid samplers derive normals from their own height grid).
    GroundSample classify(double x_m, double z_m, double height_m, double roadWeight,
                          const glm::dvec3& normal) const;

    // Width of the shoulder beyond a road's half width over which the natural terrain blends
    // into the road surface [m].
    static constexpr double kShoulder_m = 6.0;
    // Slope (1 - normal.y) above which bare rock shows.
    static constexpr double kRockSlope = 0.22;
    static glm::vec3 materialAlbedo(Material material);

  private:
    WorldSettings settings_;
    std::unique_ptr<Heightfield> heightfield_;
    std::unique_ptr<RoadNetwork> roads_;
    std::unique_ptr<Sky> sky_;
    std::unique_ptr<Vegetation> vegetation_;
};

}  // namespace amb
