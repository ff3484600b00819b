// Road.h — long roads routed along gentle slopes (least-cost path over the heightfield),
// smoothed as a spline; queries for flattening the terrain and keeping trees off.
//
// [SECTION] How a road is made (Road.cpp)
//   1. route: Dijkstra on a coarse grid (kRouteCell_m) over Heightfield::height, 16-neighbour
//      moves, edge cost = length * (1 + k * slope^2) + penalties for water and for grades above
//      the road's limit (+ a mild preference for low ground on the highway);
//   2. smooth: Laplacian relaxation of the grid path, then a uniform cubic B-spline through it;
//   3. resample every kRoadSpacing_m of arc length (XZ);
//   4. profile: the surface height is the terrain height along the line, made grade-bounded
//      (mean of the largest g-Lipschitz minorant and smallest g-Lipschitz majorant) and then
//      moving-averaged (which keeps the bound).
//   The result depends only on the settings (seed), so it is deterministic.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "world/WorldMesh.h"
#include "world/WorldSettings.h"

namespace amb {

class Heightfield;

struct Road {
    std::string name;                    // "highway", "mountain"
    std::vector<glm::dvec3> centreline;  // resampled every few metres; y = road surface height
    double halfWidth_m = 4.0;
    double length_m = 0.0;                   // horizontal (XZ) arc length of the centreline
    double maxGrade = 0.08;                  // bound on |dy| / horizontal distance along the line
    glm::dvec3 pointAt(double s_m) const;    // arc length s along the centreline, clamped
    glm::dvec3 tangentAt(double s_m) const;  // unit
    // Horizontal arc length at centreline vertex i (the vertices are evenly spaced).
    double vertexDistance_m(std::size_t i) const;
};

// The stretch of `road` from centreline vertex `first` to `last` as a ribbon to draw: a left and
// a right vertex per centreline vertex at the half width, lifted `lift_m` above the surface,
// positions relative to centreline[first], every triangle facing up. The surface is level across
// the road and follows its grade along it, so each normal is perpendicular to the horizontal
// across direction and to the centreline's (central-difference) tangent.
WorldMesh roadRibbon(const Road& road, std::size_t first, std::size_t last, double lift_m,
                     const glm::vec3& albedo);

struct RoadQuery {
    double distance_m;       // horizontal (XZ) distance to the centreline
    double surfaceHeight_m;  // road surface height at the closest centreline point
    double halfWidth_m;
    int roadIndex;
    double along_m = 0.0;  // arc length of the closest centreline point on that road
};

class RoadNetwork {
  public:
    // Grid cell of the least-cost routing and spacing of the resampled centreline.
    static constexpr double kRouteCell_m = 40.0;
    static constexpr double kRoadSpacing_m = 3.0;

    // Routes the roads (or reuses the roads of an earlier network with the same settings).
    RoadNetwork(const WorldSettings& settings, const Heightfield& heightfield);
    // The routing itself, uncached (deterministic: the same settings give the same roads).
    static std::vector<Road> route(const WorldSettings& settings, const Heightfield& heightfield);
    const std::vector<Road>& roads() const;
    // The road with this name, or nullptr.
    const Road* find(const std::string& name) const;
    // The nearest road point within maxDistance_m (XZ), if any.
    std::optional<RoadQuery> nearest(double x_m, double z_m, double maxDistance_m) const;

  private:
    struct SegmentRef {
        std::int32_t road;
        std::int32_t segment;  // from centreline[segment] to centreline[segment + 1]
    };
    void buildIndex();

    std::vector<Road> roads_;
    // Spatial hash of segments: a uniform grid of kIndexCell_m cells over the roads' bounds.
    static constexpr double kIndexCell_m = 32.0;
    double indexMinX_m_ = 0.0, indexMinZ_m_ = 0.0;
    int indexNx_ = 0, indexNz_ = 0;
    std::vector<std::uint32_t> cellStart_;  // CSR: segments of cell c are cellStart_[c]..[c+1]
    std::vector<SegmentRef> cellSegments_;
};

}  // namespace amb
