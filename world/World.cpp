// World.cpp — the world façade: natural terrain with roads flattened in, normals, materials and
// albedo; owns the heightfield, the road network, the sky and the vegetation.
//
// [SECTION] Construction
// [SECTION] Height with roads: blend to the road surface within half width + shoulder
// [SECTION] Materials and albedo by height, slope and moisture
#include "world/World.h"

#include <algorithm>
#include <cmath>

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "world/Vegetation.h"

namespace amb {

namespace {

inline double smoothstep(double e0, double e1, double x) {
    const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// Roads are never wider than this; bounds the nearest-road query [m].
constexpr double kMaxRoadHalfWidth_m = 12.0;
// Snow line: permanent snow above this height on gentle slopes [m].
constexpr double kSnowLine_m = 620.0;
// Sand: a beach this high above the water level [m].
constexpr double kBeach_m = 2.5;

}  // namespace

// ---- [SECTION] Construction ------------------------------------------------------------------

World::World(const WorldSettings& settings)
    : settings_(settings),
      heightfield_(std::make_unique<Heightfield>(settings)),
      roads_(std::make_unique<RoadNetwork>(settings, *heightfield_)),
      sky_(std::make_unique<Sky>(settings)) {
    vegetation_ = std::make_unique<Vegetation>(*this);
}

World::~World() = default;

const WorldSettings& World::settings() const {
    return settings_;
}
const Heightfield& World::heightfield() const {
    return *heightfield_;
}
const RoadNetwork& World::roads() const {
    return *roads_;
}
const Sky& World::sky() const {
    return *sky_;
}
const Vegetation& World::vegetation() const {
    return *vegetation_;
}

// ---- [SECTION] Height with roads -------------------------------------------------------------

namespace {
// Flat on the carriageway, then a smooth (C1) blend back to the natural terrain across the
// shoulder: cut and fill as a road builder would.
double roadBlend(const RoadQuery& q) {
    if (q.distance_m > q.halfWidth_m + World::kShoulder_m) return 0.0;
    return 1.0 - smoothstep(q.halfWidth_m, q.halfWidth_m + World::kShoulder_m, q.distance_m);
}
}  // namespace

double World::heightAndRoad(double x_m, double z_m, double* roadWeight) const {
    const double natural = heightfield_->height(x_m, z_m);
    double w = 0.0;
    double h = natural;
    if (auto q = roads_->nearest(x_m, z_m, kMaxRoadHalfWidth_m + kShoulder_m)) {
        w = roadBlend(*q);
        h = natural + w * (q->surfaceHeight_m - natural);
    }
    if (roadWeight) *roadWeight = w;
    return h;
}

double World::roadWeight(double x_m, double z_m) const {
    const auto q = roads_->nearest(x_m, z_m, kMaxRoadHalfWidth_m + kShoulder_m);
    return q ? roadBlend(*q) : 0.0;
}

bool World::roadWithin(double x_m, double z_m, double radius_m) const {
    return roads_->nearest(x_m, z_m, radius_m + kMaxRoadHalfWidth_m + kShoulder_m).has_value();
}

double World::height(double x_m, double z_m) const {
    return heightAndRoad(x_m, z_m, nullptr);
}

glm::dvec3 World::normal(double x_m, double z_m) const {
    const double e = Heightfield::kNormalStep_m;
    const double dhdx = (height(x_m + e, z_m) - height(x_m - e, z_m)) / (2.0 * e);
    const double dhdz = (height(x_m, z_m + e) - height(x_m, z_m - e)) / (2.0 * e);
    return glm::normalize(glm::dvec3(-dhdx, 1.0, -dhdz));
}

// ---- [SECTION] Materials and albedo ----------------------------------------------------------

glm::vec3 World::materialAlbedo(Material material) {
    switch (material) {
        case Material::Grass:
            return {0.16f, 0.26f, 0.07f};
        case Material::Rock:
            return {0.30f, 0.28f, 0.26f};
        case Material::Sand:
            return {0.55f, 0.50f, 0.38f};
        case Material::Snow:
            return {0.85f, 0.87f, 0.90f};
        case Material::Water:
            return {0.03f, 0.07f, 0.10f};
        case Material::Road:
            return {0.09f, 0.09f, 0.09f};
    }
    return {0.5f, 0.5f, 0.5f};
}

GroundSample World::sample(double x_m, double z_m) const {
    double roadWeight = 0.0;
    const double h = heightAndRoad(x_m, z_m, &roadWeight);
    return classify(x_m, z_m, h, roadWeight, normal(x_m, z_m));
}

GroundSample World::classify(double x_m, double z_m, double height_m, double roadWeight,
                             const glm::dvec3& normal) const {
    GroundSample s;
    s.height_m = height_m;
    s.roadWeight = roadWeight;
    s.normal = normal;
    s.moisture = heightfield_->moistureAt(x_m, z_m, s.height_m);
    const double slope = 1.0 - s.normal.y;
    const double above_m = s.height_m - settings_.waterLevel_m;

    // Dominant material: road, water, beach, steep rock, snow, grass, in that order.
    if (s.roadWeight > 0.5) {
        s.material = Material::Road;
    } else if (above_m < 0.0) {
        s.material = Material::Water;
    } else if (above_m < kBeach_m && slope < kRockSlope) {
        s.material = Material::Sand;
    } else if (slope > kRockSlope) {
        s.material = Material::Rock;
    } else if (s.height_m > kSnowLine_m - 60.0 * s.moisture) {
        s.material = Material::Snow;
    } else {
        s.material = Material::Grass;
    }

    // Albedo blends smoothly between the materials so patches do not show hard edges.
    const glm::dvec3 dryGrass(0.30, 0.29, 0.12);
    const glm::dvec3 wetGrass(0.09, 0.20, 0.05);
    glm::dvec3 a = glm::mix(dryGrass, wetGrass, smoothstep(0.2, 0.8, s.moisture));
    a = glm::mix(a, glm::dvec3(materialAlbedo(Material::Rock)),
                 smoothstep(kRockSlope - 0.06, kRockSlope + 0.02, slope));
    const double snowLine = kSnowLine_m - 60.0 * s.moisture;
    const double snow = smoothstep(snowLine - 25.0, snowLine + 5.0, s.height_m) *
                        (1.0 - smoothstep(0.3, 0.45, slope));
    a = glm::mix(a, glm::dvec3(materialAlbedo(Material::Snow)), snow);
    a = glm::mix(
        a, glm::dvec3(materialAlbedo(Material::Sand)),
        smoothstep(kBeach_m + 1.0, kBeach_m - 0.5, above_m) * (1.0 - smoothstep(0.15, 0.3, slope)));
    if (above_m < 0.0) a = glm::dvec3(materialAlbedo(Material::Water));
    a = glm::mix(a, glm::dvec3(materialAlbedo(Material::Road)),
                 smoothstep(0.35, 0.65, s.roadWeight));
    s.albedo = glm::vec3(glm::clamp(a, 0.0, 1.0));
    return s;
}

Material World::material(double x_m, double z_m) const {
    return sample(x_m, z_m).material;
}

glm::vec3 World::albedo(double x_m, double z_m) const {
    return sample(x_m, z_m).albedo;
}

}  // namespace amb
