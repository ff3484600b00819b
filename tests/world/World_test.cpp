// World_test.cpp — roads flattened into the terrain, normals of the combined height, materials
// and albedo, determinism.
#include "world/World.h"

#include <cmath>
#include <cstring>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

namespace amb {
namespace {

const World& defaultWorld() {
    static const World world(WorldSettings{});
    return world;
}

TEST(World, RoadSurfaceIsFlattenedIn) {
    const World& w = defaultWorld();
    ASSERT_FALSE(w.roads().roads().empty());
    int checked = 0;
    for (const Road& road : w.roads().roads()) {
        for (std::size_t i = 0; i < road.centreline.size(); i += 37) {
            const glm::dvec3 p = road.centreline[i];
            // On the centreline the terrain is the road surface (centimetres).
            EXPECT_NEAR(w.height(p.x, p.z), p.y, 0.05) << road.name << " vertex " << i;
            EXPECT_EQ(w.material(p.x, p.z), Material::Road);
            // Beyond the shoulder the natural terrain is back, exactly.
            const glm::dvec3 t = road.tangentAt(road.vertexDistance_m(i));
            const glm::dvec3 side = glm::normalize(glm::dvec3(-t.z, 0.0, t.x));
            const glm::dvec3 q = p + side * (road.halfWidth_m + World::kShoulder_m + 30.0);
            if (!w.roads().nearest(q.x, q.z, road.halfWidth_m + World::kShoulder_m + 1.0)) {
                EXPECT_EQ(w.height(q.x, q.z), w.heightfield().height(q.x, q.z));
            }
            ++checked;
        }
    }
    EXPECT_GT(checked, 50);
}

TEST(World, HeightIsContinuousAcrossTheShoulder) {
    const World& w = defaultWorld();
    const Road& road = w.roads().roads().front();
    const std::size_t i = road.centreline.size() / 2;
    const glm::dvec3 p = road.centreline[i];
    const glm::dvec3 t = road.tangentAt(road.vertexDistance_m(i));
    const glm::dvec3 side = glm::normalize(glm::dvec3(-t.z, 0.0, t.x));
    double prev = w.height(p.x, p.z);
    for (int s = 1; s <= 400; ++s) {
        const glm::dvec3 q = p + side * (0.05 * s);  // 5 cm steps out to 20 m
        const double h = w.height(q.x, q.z);
        // Slopes below 2 (the blend is C1 and the terrain is smooth): steps below 10 cm.
        EXPECT_LT(std::abs(h - prev), 0.1) << "at " << 0.05 * s << " m from the centreline";
        prev = h;
    }
}

TEST(World, RoadWeightAloneIsTheHeightQuerysWeight) {
    // Across a road from beyond one shoulder to beyond the other: 1 on the carriageway, 0 past
    // the shoulder, and the cheap query equal to the one that also gives the height.
    const World& w = defaultWorld();
    const Road& road = w.roads().roads().front();
    const std::size_t i = road.centreline.size() / 3;
    const glm::dvec3 p = road.centreline[i];
    const glm::dvec3 t = road.tangentAt(road.vertexDistance_m(i));
    const glm::dvec3 side = glm::normalize(glm::dvec3(-t.z, 0.0, t.x));
    const double reach = road.halfWidth_m + World::kShoulder_m + 4.0;
    for (int s = -100; s <= 100; ++s) {
        const glm::dvec3 q = p + side * (reach * s / 100.0);
        double weight = -1.0;
        w.heightAndRoad(q.x, q.z, &weight);
        EXPECT_EQ(w.roadWeight(q.x, q.z), weight) << "at " << reach * s / 100.0 << " m";
    }
    EXPECT_EQ(w.roadWeight(p.x, p.z), 1.0);
    const glm::dvec3 beyond = p + side * reach;
    if (!w.roads().nearest(beyond.x, beyond.z, road.halfWidth_m + World::kShoulder_m + 1.0)) {
        EXPECT_EQ(w.roadWeight(beyond.x, beyond.z), 0.0);
    }
}

TEST(World, NormalMatchesDifferenceQuotientOfHeight) {
    const World& w = defaultWorld();
    for (int n = 0; n < 200; ++n) {
        const double x = -5000.0 + 53.1 * n, z = 4000.0 - 41.7 * n;
        const double e = 0.02;
        const double dhdx = (w.height(x + e, z) - w.height(x - e, z)) / (2 * e);
        const double dhdz = (w.height(x, z + e) - w.height(x, z - e)) / (2 * e);
        const glm::dvec3 ref = glm::normalize(glm::dvec3(-dhdx, 1.0, -dhdz));
        EXPECT_GT(glm::dot(w.normal(x, z), ref), std::cos(0.02));
    }
}

TEST(World, MaterialsFollowHeightSlopeAndWater) {
    const World& w = defaultWorld();
    int counts[6] = {0, 0, 0, 0, 0, 0};
    for (int j = 0; j < 120; ++j) {
        for (int i = 0; i < 120; ++i) {
            const double x = -6000.0 + 100.0 * i, z = -6000.0 + 100.0 * j;
            const GroundSample g = w.sample(x, z);
            ++counts[static_cast<int>(g.material)];
            for (int c = 0; c < 3; ++c) {
                ASSERT_GE(g.albedo[c], 0.0f);
                ASSERT_LE(g.albedo[c], 1.0f);
            }
            if (g.height_m < w.settings().waterLevel_m && g.roadWeight < 0.5) {
                EXPECT_EQ(g.material, Material::Water);
            }
            if (g.material == Material::Rock) {
                EXPECT_GT(1.0 - g.normal.y, World::kRockSlope);
            }
            if (g.material == Material::Snow) {
                EXPECT_GT(g.height_m, 450.0);
            }
            if (g.material == Material::Grass) {
                EXPECT_LE(1.0 - g.normal.y, World::kRockSlope);
                EXPECT_GE(g.height_m, w.settings().waterLevel_m);
            }
        }
    }
    // The default world shows every natural material somewhere in a 12 km square.
    for (Material m : {Material::Grass, Material::Rock, Material::Snow, Material::Water}) {
        EXPECT_GT(counts[static_cast<int>(m)], 0) << "material " << static_cast<int>(m);
    }
}

TEST(World, SameSeedSameWorldBitForBit) {
    WorldSettings s;
    s.seed = 11;
    const World a(s), b(s);
    for (int n = 0; n < 300; ++n) {
        const double x = -3000.0 + 21.3 * n, z = 2000.0 - 17.9 * n;
        const double ha = a.height(x, z), hb = b.height(x, z);
        ASSERT_EQ(std::memcmp(&ha, &hb, sizeof ha), 0);
        const glm::vec3 aa = a.albedo(x, z), ab = b.albedo(x, z);
        ASSERT_EQ(std::memcmp(&aa, &ab, sizeof aa), 0);
    }
}

}  // namespace
}  // namespace amb
