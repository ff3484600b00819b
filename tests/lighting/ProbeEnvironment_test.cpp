// ProbeEnvironment_test.cpp — probe placement in the generated world (never inside terrain or a
// plant: moved aside, else lifted) and the fallback cube map (finite, day brighter than night).
#include "lighting/ProbeEnvironment.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "world/Conventions.h"
#include "world/Vegetation.h"
#include "world/World.h"

namespace amb {
namespace {

const World& defaultWorld() {
    static const World world(WorldSettings{});
    return world;
}

// Top of a plant's proxy mesh [m above its base].
double plantTop(const Plant& p) {
    const WorldMesh& mesh = Vegetation::proxyMesh(p.kind);
    double top = 0.0;
    for (std::size_t v = 1; v < mesh.positions.size(); v += 3)
        top = std::max(top, double(mesh.positions[v]));
    return top * p.scale;
}

// The placement invariant: at least probeHeight above terrain and water, and for every plant
// either outside its footprint (+ clearance) or above its top (+ clearance).
void expectClear(const World& world, const glm::dvec3& p, const WorldProbeEnvironmentSettings& s) {
    const double ground = std::max(world.height(p.x, p.z), world.settings().waterLevel_m);
    EXPECT_GE(p.y, ground + s.probeHeight_m - 1e-9);
    for (const Plant& plant : world.vegetation().inDisc(p.x, p.z, 12.0)) {
        const double r = Vegetation::footprintRadius_m(plant.kind) * plant.scale + s.clearance_m;
        const double d = std::hypot(plant.position_m.x - p.x, plant.position_m.z - p.z);
        if (d < r) {
            EXPECT_GE(p.y, plant.position_m.y + plantTop(plant) + s.clearance_m - 1e-9);
        }
    }
}

TEST(WorldProbeEnvironment, ProbesNeverSitInsideTerrainOrPlants) {
    const World& world = defaultWorld();
    const WorldProbeEnvironmentSettings settings;
    const WorldProbeEnvironment env(world, settings);
    // Probes aimed at tree trunks: moved aside (or up), never left inside.
    int trees = 0, moved = 0;
    for (std::int64_t ti = -3; ti <= 3 && trees < 40; ++ti) {
        for (const Plant& p : *world.vegetation().tile(ti, 1)) {
            if (p.kind != PlantKind::Conifer && p.kind != PlantKind::Broadleaf) continue;
            const glm::dvec3 q = env.placeProbe(p.position_m.x, p.position_m.z, 4.0);
            expectClear(world, q, settings);
            EXPECT_LE(std::hypot(q.x - p.position_m.x, q.z - p.position_m.z), 4.0 + 1e-9);
            moved += q.x != p.position_m.x || q.z != p.position_m.z ||
                     q.y > world.height(q.x, q.z) + settings.probeHeight_m + 1e-9;
            ++trees;
        }
    }
    ASSERT_GT(trees, 5) << "the default world should have trees near the origin";
    EXPECT_EQ(moved, trees);
    // Anywhere: the invariant holds; without plants nearby the probe stays on its point.
    int free = 0;
    for (int n = 0; n < 300; ++n) {
        const double x = -400.0 + 2.7 * n, z = 150.0 - 1.3 * n;
        const glm::dvec3 q = env.placeProbe(x, z, 1.5);
        expectClear(world, q, settings);
        if (world.vegetation().inDisc(x, z, 8.0).empty()) {
            ++free;
            EXPECT_EQ(q.x, x);
            EXPECT_EQ(q.z, z);
            EXPECT_DOUBLE_EQ(q.y, std::max(world.height(x, z), world.settings().waterLevel_m) +
                                      settings.probeHeight_m);
        }
    }
    EXPECT_GT(free, 0);
}

TEST(WorldProbeEnvironment, FallbackCubeMapFiniteAndFollowsTheDay) {
    const WorldProbeEnvironment env(defaultWorld());
    auto mean = [](const std::vector<float>& rgb) {
        double s = 0.0;
        for (float v : rgb) s += v;
        return s / double(rgb.size());
    };
    std::vector<float> noon, night;
    env.fallbackCubeMap(12.0, 16, noon);
    env.fallbackCubeMap(0.0, 16, night);
    ASSERT_EQ(noon.size(), 6u * 16 * 16 * 3);
    for (float v : noon) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
    for (float v : night) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
    EXPECT_GT(mean(noon), 100.0 * mean(night));
    EXPECT_GT(mean(night), 0.0);  // never black (moon, airglow)
    // The zenith (+Y face centre) is blue by day.
    const std::size_t zenith = (2 * 16 * 16 + 8 * 16 + 8) * 3;
    EXPECT_GT(noon[zenith + 2], noon[zenith + 0]);
    EXPECT_GT(env.sunAngularSpeed_radPerHour(), 0.0);
    EXPECT_LE(env.sunAngularSpeed_radPerHour(), kPi / 12.0 + 1e-12);
}

}  // namespace
}  // namespace amb
