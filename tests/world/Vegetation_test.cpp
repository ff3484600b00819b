// Vegetation_test.cpp — deterministic placement, minimum spacing across tile borders, nothing on
// roads, water or steep rock, near and 10^6 m from the origin; mesh budgets and orientation;
// the proxies and the near field's spheres cover what the full meshes cover.
#include "world/Vegetation.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "world/World.h"

namespace amb {
namespace {

const World& defaultWorld() {
    static const World world(WorldSettings{});
    return world;
}

std::vector<Plant> block(const Vegetation& v, std::int64_t i0, std::int64_t k0, int n) {
    std::vector<Plant> out;
    for (std::int64_t k = k0; k < k0 + n; ++k) {
        for (std::int64_t i = i0; i < i0 + n; ++i) {
            const auto t = v.tile(i, k);
            out.insert(out.end(), t->begin(), t->end());
        }
    }
    return out;
}

bool isTree(PlantKind k) {
    return k == PlantKind::Conifer || k == PlantKind::Broadleaf;
}

void expectSpacing(const std::vector<Plant>& plants) {
    for (std::size_t a = 0; a < plants.size(); ++a) {
        for (std::size_t b = a + 1; b < plants.size(); ++b) {
            const glm::dvec3 d = plants[a].position_m - plants[b].position_m;
            const double dist = std::hypot(d.x, d.z);
            const bool ta = isTree(plants[a].kind), tb = isTree(plants[b].kind);
            if (ta && tb) {
                ASSERT_GE(dist, Vegetation::kTreeSpacing_m);
            } else if (!ta && !tb) {
                ASSERT_GE(dist, Vegetation::kSmallSpacing_m);
            } else {
                ASSERT_GE(dist, Vegetation::kSmallTreeClearance_m);
            }
        }
    }
}

// Placement rules for each plant: inside its tile, on the ground, off roads, water and rock.
void expectHabitat(const World& w, const std::vector<Plant>& plants) {
    for (const Plant& p : plants) {
        const double x = p.position_m.x, z = p.position_m.z;
        ASSERT_EQ(p.position_m.y, w.height(x, z));
        ASSERT_GT(w.heightfield().height(x, z), w.settings().waterLevel_m);
        if (auto q = w.roads().nearest(x, z, 30.0)) {
            ASSERT_GE(q->distance_m, q->halfWidth_m + Vegetation::kRoadClearance_m);
        }
        const double slope = 1.0 - w.heightfield().normal(x, z).y;
        // The habitat uses a 1 m forward difference; allow for the difference in estimates.
        if (isTree(p.kind)) {
            ASSERT_LT(slope, Vegetation::kTreeMaxSlope + 0.03);
        }
        ASSERT_LT(slope, Vegetation::kRockMaxSlope + 0.05);
        ASSERT_NE(w.material(x, z), Material::Water);
        ASSERT_NE(w.material(x, z), Material::Road);
        if (isTree(p.kind)) {
            ASSERT_NE(w.material(x, z), Material::Snow);
        }
    }
}

TEST(Vegetation, SameSeedSamePlantsDifferentSeedDifferent) {
    const World& a = defaultWorld();
    const World b(WorldSettings{});
    WorldSettings s3;
    s3.seed = 5;
    const World c(s3);
    int plants = 0, same = 0;
    for (std::int64_t i = -3; i < 3; ++i) {
        const auto ta = a.vegetation().tile(i, 2), tb = b.vegetation().tile(i, 2),
                   tc = c.vegetation().tile(i, 2);
        ASSERT_EQ(ta->size(), tb->size());
        for (std::size_t n = 0; n < ta->size(); ++n) {
            ASSERT_EQ(std::memcmp(&(*ta)[n].position_m, &(*tb)[n].position_m, sizeof(glm::dvec3)),
                      0);
            ASSERT_EQ((*ta)[n].kind, (*tb)[n].kind);
            ASSERT_EQ((*ta)[n].scale, (*tb)[n].scale);
        }
        plants += static_cast<int>(ta->size());
        for (const Plant& p : *ta) {
            for (const Plant& q : *tc) same += p.position_m == q.position_m;
        }
    }
    EXPECT_GT(plants, 50);
    EXPECT_EQ(same, 0);
}

TEST(Vegetation, MinimumSpacingHoldsAcrossTileBorders) {
    const auto plants = block(defaultWorld().vegetation(), -2, -14, 3);
    ASSERT_GT(plants.size(), 100u);
    expectSpacing(plants);
}

TEST(Vegetation, NothingOnRoadsWaterOrSteepRock) {
    const World& w = defaultWorld();
    int checked = 0;
    for (const Road& road : w.roads().roads()) {
        for (double s = 0.0; s < road.length_m; s += 600.0) {
            const glm::dvec3 p = road.pointAt(s);
            const auto plants = w.vegetation().inDisc(p.x, p.z, 60.0);
            expectHabitat(w, plants);
            checked += static_cast<int>(plants.size());
        }
    }
    EXPECT_GT(checked, 100);  // roads do run through vegetated land
    // A mixed area with mountains and lakes.
    const auto plants = block(w.vegetation(), -30, 10, 4);
    expectHabitat(w, plants);
}

TEST(Vegetation, TenToTheSixMetresFromOriginFollowsTheSameRules) {
    const World& w = defaultWorld();
    const std::int64_t t = Vegetation::tileIndex(1e6);
    std::size_t total = 0;
    for (int n = 0; n < 4; ++n) {
        const auto plants = block(w.vegetation(), t + 37 * n, t - 11 * n, 2);
        expectSpacing(plants);
        expectHabitat(w, plants);
        total += plants.size();
    }
    EXPECT_GT(total, 0u);
}

TEST(Vegetation, DensityFollowsTheHabitat) {
    const World& w = defaultWorld();
    const Vegetation& v = w.vegetation();
    const Road& road = w.roads().roads().front();
    const glm::dvec3 p = road.pointAt(0.5 * road.length_m);
    EXPECT_EQ(v.treeDensity(p.x, p.z), 0.0);  // on the road
    int water = 0, dense = 0;
    for (int n = 0; n < 3000; ++n) {
        const double x = -6000.0 + 4.1 * n, z = 5000.0 - 3.3 * n;
        const double d = v.treeDensity(x, z);
        ASSERT_GE(d, 0.0);
        ASSERT_LE(d, 1.0);
        if (w.heightfield().height(x, z) < w.settings().waterLevel_m) {
            EXPECT_EQ(d, 0.0);
            ++water;
        }
        dense += d > 0.3;
    }
    EXPECT_GT(dense, 0);
}

TEST(Vegetation, MeshBudgetsAndOutwardFaces) {
    for (int k = 0; k < kPlantKinds; ++k) {
        const PlantKind kind = static_cast<PlantKind>(k);
        const WorldMesh& full = Vegetation::mesh(kind);
        const WorldMesh& proxy = Vegetation::proxyMesh(kind);
        EXPECT_GE(full.triangleCount(), 80u) << toString(kind);
        EXPECT_LE(full.triangleCount(), 500u) << toString(kind);
        EXPECT_GE(proxy.triangleCount(), 8u) << toString(kind);
        EXPECT_LE(proxy.triangleCount(), 60u) << toString(kind);
        for (const WorldMesh* m : {&full, &proxy}) {
            ASSERT_EQ(m->normals.size(), m->positions.size());
            ASSERT_EQ(m->albedo.size(), m->positions.size());
            // Counter-clockwise from outside: the face normal agrees with the vertex normals.
            int agree = 0;
            for (std::size_t t = 0; t < m->indices.size(); t += 3) {
                glm::dvec3 v[3], n(0.0);
                for (int c = 0; c < 3; ++c) {
                    const std::uint32_t i = m->indices[t + c];
                    ASSERT_LT(i, m->vertexCount());
                    v[c] = glm::dvec3(m->positions[3 * i], m->positions[3 * i + 1],
                                      m->positions[3 * i + 2]);
                    n +=
                        glm::dvec3(m->normals[3 * i], m->normals[3 * i + 1], m->normals[3 * i + 2]);
                }
                agree += glm::dot(glm::cross(v[1] - v[0], v[2] - v[0]), n) > 0.0;
            }
            EXPECT_GE(agree, static_cast<int>(m->triangleCount() * 95 / 100)) << toString(kind);
        }
    }
}

// A trunk stands under its crown, which the tree's one ambient leaves out: crownSkyShare is the
// cosine-weighted share of the sky the crown leaves a surface. Looking straight up from the
// trunk's foot at the broadleaf's ellipsoid (radii a across, b up, centre D above) it hides
// sin^2 of the tangent cone's half-angle, tan^2 = a^2 / (D^2 - b^2); the crown's bumps (within
// +-12.5 %) and facets bound it between the ellipsoid shrunk and grown by 12.5 %.
TEST(Vegetation, TrunksTakeWhatTheirCrownLeavesOfTheAmbient) {  // and what lies among the leaves
    const auto hidden = [](double a, double b, double d) {
        const double t2 = a * a / (d * d - b * b);
        return t2 / (1.0 + t2);
    };
    const double up = Vegetation::crownSkyShare(PlantKind::Broadleaf, {0.0, 0.01, 0.0}, {0, 1, 0});
    EXPECT_GE(up, 1.0 - hidden(3.2 * 1.125, 2.8 * 1.125, 6.0) - 0.03);
    EXPECT_LE(up, 1.0 - hidden(3.2 * 0.875, 2.8 * 0.875, 6.0) + 0.03);
    // Far out, facing away: nothing; inside the crown: everything; no crown: nothing.
    EXPECT_EQ(Vegetation::crownSkyShare(PlantKind::Conifer, {20.0, 1.0, 0.0}, {1, 0, 0}), 1.0);
    EXPECT_EQ(Vegetation::crownSkyShare(PlantKind::Broadleaf, {0.0, 6.0, 0.5}, {0, 0, 1}), 0.0);
    EXPECT_EQ(Vegetation::crownSkyShare(PlantKind::Rock, {0.0, 0.1, 0.0}, {0, 1, 0}), 1.0);
    // The meshes carry it on their trunks: darker up the trunk, black inside the crown, the
    // leaves untouched; bushes and rocks carry none.
    for (PlantKind kind : {PlantKind::Conifer, PlantKind::Broadleaf}) {
        for (const WorldMesh* m : {&Vegetation::mesh(kind), &Vegetation::proxyMesh(kind)}) {
            ASSERT_EQ(m->occlusion.size(), m->vertexCount()) << toString(kind);
            double yTop = 0.0;
            for (std::size_t v = 0; v < m->vertexCount(); ++v) {
                const float o = m->occlusion[v];
                ASSERT_GE(o, 0.0f);
                ASSERT_LE(o, 1.0f);
                const bool bark = m->albedo[3 * v + 1] < 0.14f && m->albedo[3 * v] > 0.19f;
                if (bark) yTop = std::max(yTop, double(m->positions[3 * v + 1]));
                if (!bark) EXPECT_EQ(o, 0.0f) << toString(kind) << " leaf vertex " << v;
            }
            double baseMax = 0.0, topMin = 1.0;
            for (std::size_t v = 0; v < m->vertexCount(); ++v) {
                const bool bark = m->albedo[3 * v + 1] < 0.14f && m->albedo[3 * v] > 0.19f;
                const double y = m->positions[3 * v + 1];
                if (bark && y < 0.01) baseMax = std::max(baseMax, double(m->occlusion[v]));
                if (bark && y > yTop - 0.01) topMin = std::min(topMin, double(m->occlusion[v]));
            }
            EXPECT_LT(baseMax, 0.3) << toString(kind);
            EXPECT_GT(topMin, baseMax + 0.2) << toString(kind);
        }
        // The full trunk's top stands inside its crown.
        const WorldMesh& full = Vegetation::mesh(kind);
        float top = 1.0f;
        for (std::size_t v = 0; v < full.vertexCount(); ++v)
            if (full.positions[3 * v + 1] > 2.4f && full.albedo[3 * v] > 0.19f)
                top = std::min(top, full.occlusion[v]);
        EXPECT_GT(top, 0.9f) << toString(kind);
    }
    EXPECT_TRUE(Vegetation::mesh(PlantKind::Bush).occlusion.empty());
    // Among the leaves: inside a crown, not under it, beside it or in a rock.
    EXPECT_TRUE(Vegetation::amongLeaves(PlantKind::Broadleaf, {0.0, 6.0, 0.0}));
    EXPECT_TRUE(Vegetation::amongLeaves(PlantKind::Conifer, {0.5, 3.0, 0.0}));
    EXPECT_FALSE(Vegetation::amongLeaves(PlantKind::Conifer, {0.5, 1.0, 0.0}));
    EXPECT_FALSE(Vegetation::amongLeaves(PlantKind::Broadleaf, {5.0, 6.0, 0.0}));
    EXPECT_FALSE(Vegetation::amongLeaves(PlantKind::Rock, {0.0, 0.2, 0.0}));
    EXPECT_TRUE(Vegetation::mesh(PlantKind::Rock).occlusion.empty());
}

// The area a shape covers seen along `d` (orthographic), by parallel rays on a grid of g x g over
// its bounds: the mesh's triangles (either side) or, with `spheres`, those spheres instead.
double coveredArea(const WorldMesh& mesh, const std::vector<PlantSphere>* spheres,
                   const glm::dvec3& d, int g) {
    const glm::dvec3 a = std::abs(d.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
    const glm::dvec3 u = glm::normalize(glm::cross(a, d)), v = glm::cross(d, u);
    const auto point = [&](std::uint32_t i) {
        return glm::dvec3(mesh.positions[3 * i], mesh.positions[3 * i + 1],
                          mesh.positions[3 * i + 2]);
    };
    double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9;
    for (std::uint32_t i = 0; i < mesh.vertexCount(); ++i) {
        u0 = std::min(u0, glm::dot(point(i), u)), u1 = std::max(u1, glm::dot(point(i), u));
        v0 = std::min(v0, glm::dot(point(i), v)), v1 = std::max(v1, glm::dot(point(i), v));
    }
    u0 -= 1.0, u1 += 1.0, v0 -= 1.0, v1 += 1.0;  // the spheres may reach past the mesh
    const auto hits = [&](const glm::dvec3& o) {
        if (spheres) {
            for (const PlantSphere& s : *spheres) {
                const glm::dvec3 c = s.centre_m - o;
                const double t = glm::dot(c, d);
                if (glm::dot(c, c) - t * t < s.radius_m * s.radius_m) return true;
            }
            return false;
        }
        for (std::size_t t = 0; t < mesh.indices.size(); t += 3) {  // Moller-Trumbore
            const glm::dvec3 p0 = point(mesh.indices[t]);
            const glm::dvec3 e1 = point(mesh.indices[t + 1]) - p0;
            const glm::dvec3 e2 = point(mesh.indices[t + 2]) - p0;
            const glm::dvec3 h = glm::cross(d, e2);
            const double det = glm::dot(e1, h);
            if (std::abs(det) < 1e-12) continue;
            const glm::dvec3 s = o - p0;
            const double b1 = glm::dot(s, h) / det;
            if (b1 < 0.0 || b1 > 1.0) continue;
            const glm::dvec3 q = glm::cross(s, e1);
            const double b2 = glm::dot(d, q) / det;
            if (b2 >= 0.0 && b1 + b2 <= 1.0) return true;
        }
        return false;
    };
    int count = 0;
    for (int j = 0; j < g; ++j)
        for (int i = 0; i < g; ++i)
            count += hits((u0 + (u1 - u0) * (i + 0.5) / g) * u +
                          (v0 + (v1 - v0) * (j + 0.5) / g) * v - 50.0 * d);
    return count * (u1 - u0) * (v1 - v0) / (double(g) * g);
}

}  // namespace

// What a probe sees of a plant is the solid angle it covers: the capture's coarse proxy and the
// near field's spheres must cover what the drawn mesh covers, on average over the directions
// and over those looking up from below (the ground's view of a crown). A proxy whose polygon is
// inscribed in the mesh's shape covers less (a 6 x 4 ellipsoid about 80 % of the bumpy crown),
// and the whole capture scene was then 12 % too bright at the ground. Rays 64 x 64 a view.
TEST(Vegetation, ProxiesAndSpheresCoverWhatTheMeshCovers) {
    constexpr int kDirections = 48;
    for (const PlantKind kind :
         {PlantKind::Conifer, PlantKind::Broadleaf, PlantKind::Bush, PlantKind::Rock}) {
        SCOPED_TRACE(int(kind));
        double full = 0.0, proxy = 0.0, spheres = 0.0, fullUp = 0.0, proxyUp = 0.0, spheresUp = 0.0;
        for (int n = 0; n < kDirections; ++n) {  // a Fibonacci sphere of directions
            const double y = 1.0 - 2.0 * (n + 0.5) / kDirections, r = std::sqrt(1.0 - y * y);
            const glm::dvec3 d(r * std::cos(2.39996323 * n), y, r * std::sin(2.39996323 * n));
            const double f = coveredArea(Vegetation::mesh(kind), nullptr, d, 64);
            const double p = coveredArea(Vegetation::proxyMesh(kind), nullptr, d, 64);
            const double s = coveredArea(Vegetation::mesh(kind), &Vegetation::spheres(kind), d, 64);
            full += f, proxy += p, spheres += s;
            if (y > 0.5) fullUp += f, proxyUp += p, spheresUp += s;
        }
        EXPECT_NEAR(proxy / full, 1.0, 0.04);
        EXPECT_NEAR(proxyUp / fullUp, 1.0, 0.06);
        EXPECT_NEAR(spheres / full, 1.0, 0.04);
        EXPECT_NEAR(spheresUp / fullUp, 1.0, 0.10);  // spheres round off the conifers' tiers
    }
}

}  // namespace amb
