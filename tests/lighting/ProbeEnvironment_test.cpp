// ProbeEnvironment_test.cpp — probe placement in the generated world (never inside terrain or a
// plant: moved aside, else lifted), the fallback cube map (finite, day brighter than night), and
// the grid cell of the drawn terrain around a point (the mesh the main view builds).
#include "lighting/ProbeEnvironment.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "world/Conventions.h"
#include "world/Road.h"
#include "world/TerrainPatch.h"
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

// Object witnesses carry the normal of the surface they stand for, at which the error at the
// drawn normal is taken: the car's roof faces up; a tree's base and crown witnesses face the
// camera horizontally (the way from the trunk to the camera) and stand on that side of it.
TEST(WorldProbeEnvironment, ObjectWitnessesFaceTheCamera) {
    const WorldProbeEnvironment env(defaultWorld());
    int trees = 0, shaded = 0;
    for (int i = 0; i < 6; ++i) {
        const double cx = 300.0 * i - 700.0, cz = 220.0 * i - 500.0;
        const auto witnesses = env.objectWitnesses(cx, cz, 3, 6.0, 48.0, 1.0, i);
        ASSERT_FALSE(witnesses.empty());
        EXPECT_EQ(witnesses[0].kind, ObjectKind::Car);
        EXPECT_NEAR(glm::length(witnesses[0].normal - glm::dvec3(0.0, 1.0, 0.0)), 0.0, 1e-12);
        EXPECT_EQ(witnesses[0].ambientShare, 1.0);
        for (std::size_t w = 1; w < witnesses.size(); ++w) {
            const ObjectWitness& o = witnesses[w];
            ASSERT_TRUE(o.kind == ObjectKind::TreeBase || o.kind == ObjectKind::TreeCrown);
            EXPECT_NEAR(glm::length(o.normal), 1.0, 1e-9);
            EXPECT_NEAR(o.normal.y, 0.0, 1e-12);
            const glm::dvec2 toCamera =
                glm::normalize(glm::dvec2(cx - o.groundX_m, cz - o.groundZ_m));
            EXPECT_NEAR(o.normal.x * toCamera.x + o.normal.z * toCamera.y, 1.0, 1e-9);
            // The witness stands out from the trunk along its normal, in the open: above the
            // terrain and outside every other plant's spheres.
            const glm::dvec2 out(o.position_m.x - o.groundX_m, o.position_m.z - o.groundZ_m);
            EXPECT_GT(out.x * o.normal.x + out.y * o.normal.z, 0.0);
            EXPECT_GE(o.position_m.y, defaultWorld().height(o.position_m.x, o.position_m.z) + 0.25);
            for (const Plant& q :
                 defaultWorld().vegetation().inDisc(o.position_m.x, o.position_m.z, 8.0)) {
                if (q.position_m.x == o.groundX_m && q.position_m.z == o.groundZ_m) continue;
                for (const PlantSphere& sphere : Vegetation::spheres(q.kind)) {
                    const glm::dvec3 c = q.position_m + double(q.scale) * sphere.centre_m;
                    EXPECT_GE(glm::length(o.position_m - c), double(q.scale) * sphere.radius_m);
                }
            }
            // The trunk is drawn with what its crown leaves of the tree's ambient (some sky is
            // always open in front of it); the crown's leaves with all of it.
            if (o.kind == ObjectKind::TreeBase) {
                EXPECT_GT(o.ambientShare, 0.5);
                EXPECT_LE(o.ambientShare, 1.0);
                shaded += o.ambientShare < 1.0;
            } else {
                EXPECT_EQ(o.ambientShare, 1.0);
            }
            ++trees;
        }
    }
    EXPECT_GT(trees, 6);  // the default world's woods give most cameras trees in range
    EXPECT_GT(shaded, trees / 4);  // half the witnesses are trunks: most stand under a crown
    EXPECT_LE(trees, 6 * 3 * 2);
}

// A reference may stand where nothing is: not inside a tree's spheres (unless the tree is the
// one named as its own), not low within a bush's or rock's footprint, not below the terrain plus
// the clearance; high above the ground it may.
TEST(WorldProbeEnvironment, InTheOpenMeansOutsidePlantsAndAboveTheTerrain) {
    const World& world = defaultWorld();
    const WorldProbeEnvironment env(world);
    int checked = 0, small = 0, bumps = 0;
    for (const Plant& p : world.vegetation().inDisc(0.0, 0.0, 400.0)) {
        if (p.kind == PlantKind::Bush || p.kind == PlantKind::Rock) {
            // Within its footprint, low: inside; beside it or high above it: not its doing.
            const double r = Vegetation::footprintRadius_m(p.kind) * p.scale;
            const glm::dvec3 low = p.position_m + glm::dvec3(0.9 * r, 0.1, 0.0);
            if (low.y < world.height(low.x, low.z)) continue;
            EXPECT_FALSE(env.inTheOpen(low, 0.0)) << "a point low within a bush or rock";
            ++small;
            continue;
        }
        // A tree: inside its crown's first sphere, among its own leaves too.
        const PlantSphere& first = Vegetation::spheres(p.kind).front();
        const glm::dvec3 inside = p.position_m + double(p.scale) * first.centre_m;
        EXPECT_FALSE(env.inTheOpen(inside, 0.0));
        EXPECT_FALSE(env.inTheOpen(inside, 0.0, &p.position_m));
        // In its trunk's last sphere, below the leaves: its own plant's spheres do not count, but
        // a neighbour's sphere or leaves may still hold the point.
        const glm::dvec3 trunk =
            p.position_m + double(p.scale) * Vegetation::spheres(p.kind).back().centre_m;
        if (trunk.y < world.height(trunk.x, trunk.z) + 0.1) continue;
        EXPECT_FALSE(env.inTheOpen(trunk, 0.0));
        bool neighbour = false;
        for (const Plant& q : world.vegetation().inDisc(trunk.x, trunk.z, 8.0)) {
            if (q.position_m == p.position_m) continue;
            for (const PlantSphere& s : Vegetation::spheres(q.kind))
                neighbour |= glm::length(trunk - (q.position_m + double(q.scale) * s.centre_m)) <
                             double(q.scale) * s.radius_m;
            const glm::dvec3 d = (trunk - q.position_m) / double(q.scale);
            const double c = std::cos(double(q.rotation_rad)), sn = std::sin(double(q.rotation_rad));
            neighbour |= Vegetation::amongLeaves(q.kind, {c * d.x - sn * d.z, d.y, sn * d.x + c * d.z});
        }
        EXPECT_EQ(env.inTheOpen(trunk, 0.0, &p.position_m), !neighbour);
        // Between a broadleaf's sphere and the bumps of its leaves: among them, not in the open.
        if (p.kind == PlantKind::Broadleaf) {
            for (int a = 0; a < 32; ++a) {
                const double phi = 2.0 * kPi * a / 32.0;
                const glm::dvec3 at = p.position_m + double(p.scale) * glm::dvec3(3.3 * std::cos(phi), 6.0,
                                                                                  3.3 * std::sin(phi));
                const glm::dvec3 d = (at - p.position_m) / double(p.scale);
                const double c = std::cos(double(p.rotation_rad)), sn = std::sin(double(p.rotation_rad));
                if (!Vegetation::amongLeaves(p.kind, {c * d.x - sn * d.z, d.y, sn * d.x + c * d.z}))
                    continue;
                EXPECT_FALSE(env.inTheOpen(at, 0.0, &p.position_m));
                ++bumps;
            }
        }
        if (++checked == 40) break;
    }
    EXPECT_EQ(checked, 40);
    EXPECT_GT(small, 5);
    EXPECT_GT(bumps, 0);  // the bumps reach past the sphere (3.15 m) at 3.3 m somewhere
    for (double x = -300.0; x <= 300.0; x += 150.0) {
        const double ground = world.height(x, 77.0);
        EXPECT_FALSE(env.inTheOpen({x, ground + 0.2, 77.0}, 0.25));
        EXPECT_FALSE(env.inTheOpen({x, ground - 0.5, 77.0}, 0.0));
        EXPECT_TRUE(env.inTheOpen({x, ground + 80.0, 77.0}, 0.25));  // above every plant
    }
}

// The cell a patch lit per vertex interpolates at a point is the drawn mesh's: over a field of
// points around a camera on the highway (across LOD boundaries, where the edges are stitched),
// its vertices lie on the leaf's grid of size / quads, its weights are a triangle's (non-negative,
// one of them 0, summing to 1), and the vertex heights interpolated with them are the drawn
// surface's height there (TerrainSurface over the mesh TerrainPatchCache builds for the camera).
TEST(WorldProbeEnvironment, DrawnCellsAreTheDrawnMeshs) {
    const World& world = defaultWorld();
    const WorldProbeEnvironment env(world);
    const Road* road = world.roads().find("highway");
    ASSERT_NE(road, nullptr);
    const glm::dvec3 camera =
        road->centreline[road->centreline.size() / 3] + glm::dvec3(0.0, 2.0, 0.0);
    TerrainPatchCache cache(world);
    const TerrainMesh mesh = cache.build(camera, glm::dvec3(camera.x, 0.0, camera.z));
    const TerrainSurface surface(mesh);
    int checked = 0, stitched = 0;
    for (double dz = -150.0; dz <= 150.0; dz += 7.3) {
        for (double dx = -150.0; dx <= 150.0; dx += 6.1) {
            const double x = camera.x + dx, z = camera.z + dz;
            const DrawnPatch patch = env.drawnPatch(x, z, camera);
            const DrawnCell cell = env.drawnCell(x, z, camera);
            ASSERT_TRUE(patch.size_m > 0.0 && cell.known);
            ASSERT_EQ(patch.quads, TerrainPatch::kPatchQuads);
            const double spacing = patch.size_m / patch.quads;
            EXPECT_EQ(cell.spacing_m, spacing);
            double sum = 0.0, height = 0.0;
            int zeros = 0;
            for (int c = 0; c < 4; ++c) {
                const glm::dvec3& v = cell.vertex_m[c];
                const double i = (v.x - patch.x0_m) / spacing, k = (v.z - patch.z0_m) / spacing;
                EXPECT_NEAR(i, std::round(i), 1e-6);
                EXPECT_NEAR(k, std::round(k), 1e-6);
                EXPECT_TRUE(i >= -1e-6 && i <= patch.quads + 1e-6 && k >= -1e-6 &&
                            k <= patch.quads + 1e-6);
                EXPECT_NEAR(glm::length(cell.normal[c]), 1.0, 1e-5);
                EXPECT_GE(cell.weight[c], 0.0);
                zeros += cell.weight[c] == 0.0;
                sum += cell.weight[c];
                height += cell.weight[c] * v.y;
                stitched += std::fabs(v.y - world.height(v.x, v.z)) > 1e-3;
            }
            EXPECT_GE(zeros, 1);
            EXPECT_NEAR(sum, 1.0, 1e-12);
            EXPECT_NEAR(height, surface.heightAt(x, z), 1e-3) << x << ", " << z;
            ++checked;
        }
    }
    EXPECT_GT(checked, 1500);
    EXPECT_GT(stitched, 0);  // some vertices lie on a coarser neighbour's edge
}

}  // namespace
}  // namespace amb
