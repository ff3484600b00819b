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

}  // namespace

WorldProbeEnvironment::WorldProbeEnvironment(const World& world,
                                             const WorldProbeEnvironmentSettings& s)
    : world_(world), settings_(s) {}

glm::dvec3 WorldProbeEnvironment::placeProbe(double x_m, double z_m, double maxAside_m) const {
    const double kLargestFootprint_m = 3.2 * 2.0;  // largest crown x a generous scale
    const double clearance = settings_.clearance_m;
    const double water = world_.settings().waterLevel_m;
    const std::vector<Plant> plants =
        world_.vegetation().inDisc(x_m, z_m, kLargestFootprint_m + maxAside_m + clearance);
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

}  // namespace amb
