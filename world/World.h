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

class World {
public:
    explicit World(const WorldSettings& settings);
    ~World();

    const WorldSettings& settings() const;
    const Heightfield& heightfield() const;
    const RoadNetwork& roads() const;
    const Sky& sky() const;

    double height(double x_m, double z_m) const;        // terrain with roads flattened in
    glm::dvec3 normal(double x_m, double z_m) const;    // unit, of height()
    Material material(double x_m, double z_m) const;
    glm::vec3 albedo(double x_m, double z_m) const;     // linear RGB in [0, 1]
};

}  // namespace amb
