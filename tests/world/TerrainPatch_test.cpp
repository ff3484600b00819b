// TerrainPatch_test.cpp — patches are deterministic and cached by key, LOD selection refines
// towards the camera, edges coincide across patch borders and LOD transitions (no cracks), near
// and 10^6 m from the origin; corner colours meet across LOD transitions and a linear field is
// left as it is; the terrain proxy stays small; the drawn surface matches the packed triangles
// and plants stand on it; the albedo shows rock on steep slopes and is nowhere one flat colour.
#include "world/TerrainPatch.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "world/Conventions.h"
#include "world/Heightfield.h"
#include "world/Replay.h"
#include "world/Vegetation.h"
#include "world/World.h"

namespace amb {
namespace {

const World& defaultWorld() {
    static const World world(WorldSettings{});
    return world;
}

TerrainLodSettings smallLod() {
    TerrainLodSettings s;
    s.coarsestLevel = 6;  // 2048 m roots
    s.viewRadius_m = 2500.0;
    return s;
}

constexpr int kQ = TerrainPatch::kPatchQuads;
constexpr int kV = TerrainPatch::kVerticesPerSide;

// World XZ of vertex (a, b) of a patch, exact.
double vertexX(const PatchKey& k, int a) {
    return TerrainPatch::originX_m(k) + a * TerrainPatch::spacing_m(k.level);
}
double vertexZ(const PatchKey& k, int b) {
    return TerrainPatch::originZ_m(k) + b * TerrainPatch::spacing_m(k.level);
}

// Rendered height (relative to the mesh origin, float) of vertex (a, b) of a drawn patch.
float vertexY(const TerrainMesh& m, const TerrainPatchDraw& d, int a, int b) {
    return m.mesh.positions[3 * (d.firstVertex + b * kV + a) + 1];
}

struct CrackReport {
    int sharedVertices = 0;        // vertices at the same lattice point in two patches
    int interpolatedVertices = 0;  // finer vertices checked against a coarser edge
    int levelTransitions = 0;      // neighbouring pairs with different levels
    double worstGap_m = 0.0;
};

// A stretch of edge shared by leaves p and q (an ordered pair: each pair appears twice): along
// z (the line x = const) or along x, from lo to hi; pa and qa are p's and q's fixed vertex
// index across the line.
struct SharedStretch {
    std::size_t p, q;
    bool alongZ;
    double lo, hi;
    int pa, qa;
};

std::vector<SharedStretch> sharedStretches(const TerrainMesh& m) {
    std::vector<SharedStretch> out;
    const auto& P = m.patches;
    for (std::size_t p = 0; p < P.size(); ++p) {
        for (std::size_t q = 0; q < P.size(); ++q) {
            if (p == q) continue;
            const PatchKey& kp = P[p].key;
            const PatchKey& kq = P[q].key;
            const double sp = TerrainPatch::size_m(kp.level), sq = TerrainPatch::size_m(kq.level);
            const double px0 = TerrainPatch::originX_m(kp), pz0 = TerrainPatch::originZ_m(kp);
            const double qx0 = TerrainPatch::originX_m(kq), qz0 = TerrainPatch::originZ_m(kq);
            for (int side = 0; side < 4; ++side) {
                const bool alongZ = side < 2;  // the shared line is x = const
                int pa, qa;                    // p's and q's fixed vertex index across the line
                if ((side == 0 && px0 + sp == qx0) || (side == 2 && pz0 + sp == qz0)) {
                    pa = kQ;
                    qa = 0;
                } else if ((side == 1 && qx0 + sq == px0) || (side == 3 && qz0 + sq == pz0)) {
                    pa = 0;
                    qa = kQ;
                } else
                    continue;
                // Overlap of the two edges along the line.
                const double p0 = alongZ ? pz0 : px0, q0 = alongZ ? qz0 : qx0;
                const double lo = std::max(p0, q0), hi = std::min(p0 + sp, q0 + sq);
                if (hi <= lo) continue;
                out.push_back({p, q, alongZ, lo, hi, pa, qa});
            }
        }
    }
    return out;
}

// For every pair of leaves sharing a stretch of edge, every vertex of either one on the shared
// stretch must lie on the other one's edge polyline: exactly where both have a vertex, within
// float rounding where the coarser edge interpolates.
CrackReport checkCracks(const TerrainMesh& m) {
    CrackReport r;
    const auto& P = m.patches;
    for (const SharedStretch& e : sharedStretches(m)) {
        const PatchKey& kp = P[e.p].key;
        const PatchKey& kq = P[e.q].key;
        if (kp.level != kq.level) ++r.levelTransitions;
        const double p0 = e.alongZ ? TerrainPatch::originZ_m(kp) : TerrainPatch::originX_m(kp);
        const double q0 = e.alongZ ? TerrainPatch::originZ_m(kq) : TerrainPatch::originX_m(kq);
        const double stepP = TerrainPatch::spacing_m(kp.level);
        const double stepQ = TerrainPatch::spacing_m(kq.level);
        for (int t = 0; t <= kQ; ++t) {
            const double s = p0 + t * stepP;  // coordinate along the line
            if (s < e.lo || s > e.hi) continue;
            const float yp = e.alongZ ? vertexY(m, P[e.p], e.pa, t) : vertexY(m, P[e.p], t, e.pa);
            // q's polyline at s.
            const double u = (s - q0) / stepQ;
            const int j = std::min(static_cast<int>(std::floor(u)), kQ - 1);
            const double f = u - j;
            const float y0 = e.alongZ ? vertexY(m, P[e.q], e.qa, j) : vertexY(m, P[e.q], j, e.qa);
            const float y1 =
                e.alongZ ? vertexY(m, P[e.q], e.qa, j + 1) : vertexY(m, P[e.q], j + 1, e.qa);
            if (f == 0.0) {
                if (yp != y0)
                    r.worstGap_m = std::max(r.worstGap_m, std::abs(double(yp) - y0) + 1.0);
                ++r.sharedVertices;
            } else {
                const double yq = y0 + f * (double(y1) - y0);
                r.worstGap_m = std::max(r.worstGap_m, std::abs(yp - yq));
                ++r.interpolatedVertices;
            }
        }
    }
    return r;
}

TEST(TerrainPatch, GenerationIsDeterministicAndKeyed) {
    const PatchKey key{2, 3, -5};
    const TerrainPatch a = TerrainPatch::generate(defaultWorld(), key);
    const World other(WorldSettings{});
    const TerrainPatch b = TerrainPatch::generate(other, key);
    ASSERT_EQ(a.heights_m.size(), std::size_t(kV * kV));
    EXPECT_EQ(
        std::memcmp(a.heights_m.data(), b.heights_m.data(), a.heights_m.size() * sizeof(double)),
        0);
    EXPECT_EQ(a.normals, b.normals);
    EXPECT_EQ(a.albedo, b.albedo);
    // Heights are World::height at the lattice points, exactly.
    for (int v = 0; v < kV * kV; v += 7) {
        EXPECT_EQ(a.heights_m[v],
                  defaultWorld().height(vertexX(key, v % kV), vertexZ(key, v / kV)));
    }
    WorldSettings s2;
    s2.seed = 99;
    const World w2(s2);
    const TerrainPatch c = TerrainPatch::generate(w2, key);
    EXPECT_NE(a.heights_m, c.heights_m);
}

TEST(TerrainPatch, LodRefinesTowardsTheCamera) {
    TerrainPatchCache cache(defaultWorld(), smallLod());
    const double h = defaultWorld().height(300.0, -200.0);
    const auto leaves = cache.selectPatches(glm::dvec3(300.0, h + 2.0, -200.0));
    ASSERT_FALSE(leaves.empty());
    // The patch under the camera is the finest; far patches are coarse.
    int under = -1, maxLevel = 0;
    double area = 0.0;
    for (const PatchKey& k : leaves) {
        const double s = TerrainPatch::size_m(k.level);
        const double x0 = TerrainPatch::originX_m(k), z0 = TerrainPatch::originZ_m(k);
        if (300.0 >= x0 && 300.0 < x0 + s && -200.0 >= z0 && -200.0 < z0 + s) under = k.level;
        maxLevel = std::max(maxLevel, k.level);
        area += s * s;
    }
    EXPECT_EQ(under, 0);
    EXPECT_GE(maxLevel, 4);
    // Leaves tile the selected roots without overlap: their area is a whole number of roots.
    const double root = TerrainPatch::size_m(6);
    EXPECT_NEAR(std::fmod(area, root * root), 0.0, 1e-6);
    // Deterministic.
    EXPECT_EQ(leaves.size(), cache.selectPatches(glm::dvec3(300.0, h + 2.0, -200.0)).size());
}

void expectCrackFree(const glm::dvec3& cameraXZ) {
    TerrainPatchCache cache(defaultWorld(), smallLod());
    const glm::dvec3 camera(cameraXZ.x, defaultWorld().height(cameraXZ.x, cameraXZ.z) + 3.0,
                            cameraXZ.z);
    const TerrainMesh mesh = cache.build(camera, camera);
    ASSERT_FALSE(mesh.patches.empty());
    const CrackReport r = checkCracks(mesh);
    EXPECT_GT(r.levelTransitions, 10);
    EXPECT_GT(r.sharedVertices, 1000);
    EXPECT_GT(r.interpolatedVertices, 100);
    // Float positions relative to the camera: interpolation agrees to a few millimetres.
    EXPECT_LT(r.worstGap_m, 5e-3);

    // Corners: patches sharing a corner agree on its position and normal; normals are unit.
    std::map<std::pair<double, double>, std::pair<glm::dvec3, glm::dvec3>> corners;
    for (const TerrainPatchDraw& d : mesh.patches) {
        for (int c = 0; c < 4; ++c) {
            EXPECT_NEAR(glm::length(d.cornerNormals[c]), 1.0, 1e-9);
            const auto key = std::make_pair(d.corners_m[c].x, d.corners_m[c].z);
            auto [it, fresh] =
                corners.emplace(key, std::make_pair(d.corners_m[c], d.cornerNormals[c]));
            if (!fresh) {
                EXPECT_EQ(it->second.first.y, d.corners_m[c].y);
                EXPECT_EQ(it->second.second, d.cornerNormals[c]);
            }
        }
    }
    // Every triangle faces up (counter-clockwise seen from +Y) and positions stay small.
    const auto& pos = mesh.mesh.positions;
    for (std::size_t t = 0; t < mesh.mesh.indices.size(); t += 3) {
        const auto v = [&](int k) {
            const std::uint32_t i = mesh.mesh.indices[t + k];
            return glm::dvec3(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]);
        };
        ASSERT_GT(glm::cross(v(1) - v(0), v(2) - v(0)).y, 0.0);
    }
    for (float p : pos) ASSERT_LT(std::abs(p), 2.0f * 2500.0f + 2048.0f);
}

TEST(TerrainPatch, NoCracksAcrossBordersAndLodTransitions) {
    expectCrackFree({250.0, 0.0, -730.0});
}

TEST(TerrainPatch, NoCracksTenToTheSixMetresFromOrigin) {
    expectCrackFree({1e6 + 250.0, 0.0, 1e6 - 730.0});
}

TEST(TerrainPatch, CacheReusesPatchesAndRebuildsIdentically) {
    TerrainPatchCache cache(defaultWorld(), smallLod());
    const glm::dvec3 cam(120.0, defaultWorld().height(120.0, 80.0) + 2.0, 80.0);
    const TerrainMesh a = cache.build(cam, cam);
    const std::size_t generated = cache.generatedPatches();
    EXPECT_EQ(generated, a.patches.size());
    const TerrainMesh b = cache.build(cam, cam);
    EXPECT_EQ(cache.generatedPatches(), generated);  // nothing regenerated
    EXPECT_EQ(a.mesh.positions, b.mesh.positions);
    EXPECT_EQ(a.mesh.indices, b.mesh.indices);
    // A fresh cache over an equal world gives the same arrays, bit for bit.
    const World other(WorldSettings{});
    TerrainPatchCache cache2(other, smallLod());
    const TerrainMesh c = cache2.build(cam, cam);
    EXPECT_EQ(a.mesh.positions, c.mesh.positions);
    EXPECT_EQ(a.mesh.normals, c.mesh.normals);
    EXPECT_EQ(a.mesh.albedo, c.mesh.albedo);
}

TEST(TerrainPatch, ProxyIsSmallAndFollowsTheTerrain) {
    const World& w = defaultWorld();
    const glm::dvec3 centre(400.0, w.height(400.0, 900.0) + 5.0, 900.0);
    const WorldMesh proxy = makeTerrainProxy(w, centre, 2000.0);
    EXPECT_LE(proxy.triangleCount(), 4000u);
    EXPECT_GE(proxy.triangleCount(), 500u);
    float maxX = 0.0f;
    for (std::size_t v = 0; v < proxy.vertexCount(); ++v) {
        const double x = centre.x + proxy.positions[3 * v],
                     z = centre.z + proxy.positions[3 * v + 2];
        EXPECT_NEAR(centre.y + proxy.positions[3 * v + 1], w.height(x, z), 1e-3);
        maxX = std::max(maxX, std::abs(proxy.positions[3 * v]));
    }
    EXPECT_FLOAT_EQ(maxX, 2000.0f);
    for (std::size_t t = 0; t < proxy.indices.size(); t += 3) {
        const auto v = [&](int k) {
            const std::uint32_t i = proxy.indices[t + k];
            return glm::dvec3(proxy.positions[3 * i], proxy.positions[3 * i + 1],
                              proxy.positions[3 * i + 2]);
        };
        ASSERT_GT(glm::cross(v(1) - v(0), v(2) - v(0)).y, 0.0);
    }
}

// ---- Corner values stitched across LOD boundaries ------------------------------------------

// A colour field that is not linear in x and z: a coarse edge's interpolation differs from it at
// the finer corners along the edge.
glm::vec3 curvedField(const glm::dvec3& p) {
    return glm::vec3(float(1.0 + 0.5 * std::sin(p.x / 37.0)),
                     float(1.0 + 0.5 * std::cos(p.z / 23.0)),
                     float(1.0 + 0.3 * std::sin((p.x + p.z) / 51.0)));
}

glm::vec3 linearField(const glm::dvec3& p) {
    return glm::vec3(float(0.8 + 1e-3 * p.x - 2e-4 * p.z), float(0.5 - 5e-4 * p.x + 1e-3 * p.z),
                     float(0.3 + 2e-4 * (p.x + p.z)));
}

std::vector<std::size_t> allPatches(const TerrainMesh& mesh) {
    std::vector<std::size_t> all(mesh.patches.size());
    std::iota(all.begin(), all.end(), std::size_t(0));
    return all;
}

// Stitched values at every corner of `mesh`: the field where cornersToEvaluate(patches) asks
// (NaN elsewhere, so a value read but never evaluated shows), then stitchCornerValues.
std::vector<glm::vec3> stitchedCorners(const TerrainMesh& mesh,
                                       glm::vec3 (*field)(const glm::dvec3&),
                                       const std::vector<std::size_t>& patches) {
    std::vector<glm::vec3> v(mesh.corners.size(),
                             glm::vec3(std::numeric_limits<float>::quiet_NaN()));
    for (std::uint32_t c : cornersToEvaluate(mesh, patches))
        v[c] = field(mesh.corners[c].position_m);
    stitchCornerValues(mesh.corners, v.data());
    return v;
}

using PatchCorners = std::function<std::array<glm::vec3, 4>(std::size_t patch)>;

// The colour patch p shows at world (x, z) on its square: its corner values, bilinear.
glm::vec3 shownColour(const TerrainMesh& m, std::size_t p, const PatchCorners& corners, double x,
                      double z) {
    const PatchKey& k = m.patches[p].key;
    const double size = TerrainPatch::size_m(k.level);
    const float u = float((x - TerrainPatch::originX_m(k)) / size);
    const float v = float((z - TerrainPatch::originZ_m(k)) / size);
    const std::array<glm::vec3, 4> c = corners(p);
    return glm::mix(glm::mix(c[0], c[1], u), glm::mix(c[2], c[3], u), v);
}

struct SeamReport {
    int lodStretches = 0;  // shared stretches between leaves of different levels
    int samples = 0;
    double worst = 0.0;  // largest difference of a channel between the two sides
};

// Along every stretch shared by leaves of different levels, the colour each side shows at the
// finer leaf's two corners on it and at three points between them.
SeamReport checkSeams(const TerrainMesh& m, const PatchCorners& corners) {
    SeamReport r;
    for (const SharedStretch& e : sharedStretches(m)) {
        const PatchKey& kp = m.patches[e.p].key;
        if (kp.level >= m.patches[e.q].key.level) continue;  // p is the finer side
        ++r.lodStretches;
        const double size = TerrainPatch::size_m(kp.level);
        const double across =
            (e.alongZ ? TerrainPatch::originX_m(kp) : TerrainPatch::originZ_m(kp)) +
            (e.pa == kQ ? size : 0.0);
        for (int j = 0; j <= 4; ++j) {
            const double along = e.lo + (e.hi - e.lo) * j / 4.0;
            const double x = e.alongZ ? across : along, z = e.alongZ ? along : across;
            const glm::vec3 d =
                shownColour(m, e.p, corners, x, z) - shownColour(m, e.q, corners, x, z);
            r.worst = std::max(
                {r.worst, double(std::abs(d.x)), double(std::abs(d.y)), double(std::abs(d.z))});
            if (std::isnan(d.x + d.y + d.z)) r.worst = 1e30;
            ++r.samples;
        }
    }
    return r;
}

PatchCorners stitchedOf(const TerrainMesh& m, const std::vector<glm::vec3>& values) {
    return [&m, &values](std::size_t p) {
        std::array<glm::vec3, 4> c;
        for (int k = 0; k < 4; ++k) c[k] = values[m.patches[p].cornerIndex[k]];
        return c;
    };
}

PatchCorners unstitchedOf(const TerrainMesh& m, glm::vec3 (*field)(const glm::dvec3&)) {
    return [&m, field](std::size_t p) {
        std::array<glm::vec3, 4> c;
        for (int k = 0; k < 4; ++k) c[k] = field(m.patches[p].corners_m[k]);
        return c;
    };
}

glm::dvec3 cameraAbove(double x, double z) {
    return {x, defaultWorld().height(x, z) + 3.0, z};
}

// Two levels side by side (a 64 m leaf west of the four 32 m leaves of its east neighbour), then
// a camera's selection with levels 0 to 6: along every edge between leaves of different levels
// the fine side shows what the coarse side interpolates, at its corners and between them.
TEST(TerrainPatch, CornerColoursMeetAcrossLodBoundaries) {
    TerrainPatchCache cache(defaultWorld(), smallLod());
    const std::vector<PatchKey> twoLevels = {{1, 0, 0}, {0, 2, 0}, {0, 3, 0}, {0, 2, 1}, {0, 3, 1}};
    const glm::dvec3 camera = cameraAbove(250.0, -730.0);
    const TerrainMesh meshes[2] = {cache.build(twoLevels, glm::dvec3(0.0)),
                                   cache.build(camera, camera)};
    for (const TerrainMesh& mesh : meshes) {
        const std::vector<glm::vec3> stitched =
            stitchedCorners(mesh, curvedField, allPatches(mesh));
        const SeamReport after = checkSeams(mesh, stitchedOf(mesh, stitched));
        const SeamReport before = checkSeams(mesh, unstitchedOf(mesh, curvedField));
        EXPECT_GE(after.lodStretches, mesh.patches.size() == 5 ? 2 : 40);
        // Values near 1 in float: agreement to rounding.
        EXPECT_LT(after.worst, 1e-5) << "over " << after.samples << " points";
        // Without stitching the seams are there (the field bends between the fine corners).
        EXPECT_GT(before.worst, 1e-2);
    }
}

// Where the field is linear in x and z a coarse edge's interpolation is the field itself:
// stitching changes nothing.
TEST(TerrainPatch, StitchingKeepsALinearField) {
    TerrainPatchCache cache(defaultWorld(), smallLod());
    const glm::dvec3 camera = cameraAbove(250.0, -730.0);
    const TerrainMesh mesh = cache.build(camera, camera);
    const std::vector<glm::vec3> stitched = stitchedCorners(mesh, linearField, allPatches(mesh));
    int interpolated = 0;
    for (const TerrainCorner& c : mesh.corners) interpolated += c.evaluated() ? 0 : 1;
    EXPECT_GT(interpolated, 20);
    double worst = 0.0;
    for (const TerrainPatchDraw& d : mesh.patches) {
        for (int k = 0; k < 4; ++k) {
            const glm::vec3 diff = stitched[d.cornerIndex[k]] - linearField(d.corners_m[k]);
            worst = std::max({worst, double(std::abs(diff.x)), double(std::abs(diff.y)),
                              double(std::abs(diff.z))});
        }
    }
    // Values up to about 4 in float.
    EXPECT_LT(worst, 1e-5);
}

// An evaluated corner knows the size of the largest patch it is a corner of (what its value is
// blended across: the near field's patch mean); a corner inside a coarser edge has none.
TEST(TerrainPatch, AnEvaluatedCornerKnowsItsLargestPatch) {
    TerrainPatchCache cache(defaultWorld(), smallLod());
    const glm::dvec3 camera = cameraAbove(250.0, -730.0);
    const TerrainMesh mesh = cache.build(camera, camera);
    std::vector<double> largest(mesh.corners.size(), 0.0);
    std::set<double> sizes;
    for (const TerrainPatchDraw& d : mesh.patches) {
        const double size = d.corners_m[1].x - d.corners_m[0].x;
        sizes.insert(size);
        for (int k = 0; k < 4; ++k)
            if (mesh.corners[d.cornerIndex[k]].evaluated())
                largest[d.cornerIndex[k]] = std::max(largest[d.cornerIndex[k]], size);
    }
    EXPECT_GE(sizes.size(), 3u);  // several levels of detail in view
    for (std::size_t c = 0; c < mesh.corners.size(); ++c) {
        if (mesh.corners[c].evaluated())
            EXPECT_EQ(mesh.corners[c].patch_m, largest[c]) << c;
        else
            EXPECT_EQ(mesh.corners[c].patch_m, 0.0) << c;
    }
}

// Drawing only some patches (the visible ones) evaluates their corners and the coarser edge ends
// they read, each once, and gives them the same values as stitching everything.
TEST(TerrainPatch, CornersToEvaluateReachTheCoarserEdges) {
    TerrainPatchCache cache(defaultWorld(), smallLod());
    const glm::dvec3 camera = cameraAbove(250.0, -730.0);
    const TerrainMesh mesh = cache.build(camera, camera);
    const std::vector<glm::vec3> all = stitchedCorners(mesh, curvedField, allPatches(mesh));
    std::vector<std::size_t> fine;
    for (std::size_t p = 0; p < mesh.patches.size(); ++p) {
        if (mesh.patches[p].key.level <= 1) fine.push_back(p);
    }
    ASSERT_FALSE(fine.empty());
    const std::vector<glm::vec3> some = stitchedCorners(mesh, curvedField, fine);
    for (std::size_t p : fine) {
        for (int k = 0; k < 4; ++k) {
            const std::uint32_t c = mesh.patches[p].cornerIndex[k];
            EXPECT_EQ(some[c], all[c]) << "patch " << p << " corner " << k;
        }
    }
    // Each lattice point once: no two corners at the same place; at most four per patch.
    const std::vector<std::uint32_t> everything = cornersToEvaluate(mesh, allPatches(mesh));
    std::set<std::pair<double, double>> places;
    for (const TerrainCorner& c : mesh.corners) places.emplace(c.position_m.x, c.position_m.z);
    EXPECT_EQ(places.size(), mesh.corners.size());
    EXPECT_LT(everything.size(), 4 * mesh.patches.size());
    EXPECT_LT(cornersToEvaluate(mesh, fine).size(), everything.size());
}

// The sky detail (TerrainPatch::skyDetail): on a gully's floor the terrain's own visibility V
// falls well below the corners' blend Vc; at the corners V = Vc exactly (their value is the
// near field's); on a plane (a road's flat carriageway is not needed: a patch far from any
// relief within 16 m) V = 1; coarser patches carry none.
TEST(TerrainPatch, SkyDetailDarkensAGullysFloorOnly) {
    const World& world = defaultWorld();
    const Heightfield& hf = world.heightfield();
    // The deepest point of a ravine-country square (world seed 1).
    double best = 0.0, gx = 0.0, gz = 0.0;
    for (double x = -4900.0; x <= -4820.0; x += 1.0)
        for (double z = 4520.0; z <= 4600.0; z += 1.0)
            if (const double d = hf.gullyDepth(x, z); d > best) best = d, gx = x, gz = z;
    ASSERT_GT(best, 5.0);
    const double size = TerrainPatch::size_m(0);
    const PatchKey key{0, std::int64_t(std::floor(gx / size)), std::int64_t(std::floor(gz / size))};
    const TerrainPatch p = TerrainPatch::generate(world, key);
    ASSERT_EQ(p.skyDetail.size(), std::size_t(2 * kV * kV));
    double floorV = 1.0, floorVc = 1.0, nearest = 1e9;
    for (int v = 0; v < kV * kV; ++v) {
        const double V = p.skyDetail[2 * v], Vc = p.skyDetail[2 * v + 1];
        ASSERT_GE(V, 0.0);
        ASSERT_LE(V, 1.0);
        const double d = std::hypot(vertexX(key, v % kV) - gx, vertexZ(key, v / kV) - gz);
        if (d < nearest) nearest = d, floorV = V, floorVc = Vc;
    }
    for (int a : {0, kQ})
        for (int b : {0, kQ})
            EXPECT_EQ(p.skyDetail[2 * (b * kV + a)], p.skyDetail[2 * (b * kV + a) + 1]);
    // Walls of 5 m or more about 5 m away on two sides hide over a tenth of the sky.
    EXPECT_LT(floorV, 0.9) << "at " << gx << ", " << gz;
    EXPECT_LT(floorV, floorVc - 0.05);
    // A lowland patch far from ravine country and roads carries no detail by default; made to,
    // it finds gentle hills, nearly all sky, and the detail changes nothing else in the patch.
    const PatchKey plain{0, 40, 40};
    ASSERT_EQ(hf.ravineMask(TerrainPatch::originX_m(plain), TerrainPatch::originZ_m(plain)), 0.0);
    const TerrainPatch bare = TerrainPatch::generate(world, plain);
    EXPECT_TRUE(bare.skyDetail.empty());
    const TerrainPatch q = TerrainPatch::generate(world, plain, TerrainPatch::SkyDetail::Everywhere);
    ASSERT_EQ(q.skyDetail.size(), std::size_t(2 * kV * kV));
    for (std::size_t i = 0; i < q.skyDetail.size(); ++i) EXPECT_GT(q.skyDetail[i], 0.97) << i;
    EXPECT_EQ(bare.heights_m, q.heights_m);
    EXPECT_EQ(bare.normals, q.normals);
    EXPECT_EQ(bare.albedo, q.albedo);
    // A patch too coarse: none, even when asked for everywhere.
    EXPECT_TRUE(TerrainPatch::generate(world, PatchKey{2, 3, -5}, TerrainPatch::SkyDetail::Everywhere)
                    .skyDetail.empty());
}

// Why the detail is left to ravine country: beside the shipped drives (cuts, embankments,
// hills) it moves V from the corners' blend Vc by under 0.02 at the 99th percentile and 0.08
// at most, when b = 0.3 (a lit wall's light, relative) changes the ambient by 1.4 % and 6 %.
// The patches within 64 m of every 60th sample, at the two levels that could carry it.
TEST(TerrainPatch, SkyDetailBesideTheShippedDrivesIsSmall) {
    for (const char* name : {"highway-drive", "mountain-drive"}) {
        const Replay rp = readReplay(std::string(AMBIENCE_SOURCE_DIR) + "/replays/" + name + ".json");
        const World world(rp.world);
        std::vector<double> moved;
        for (int level = 0; level <= 1; ++level) {
            ASSERT_LE(TerrainPatch::spacing_m(level), TerrainPatch::kSkyDetailMaxSpacing_m);
            std::set<std::pair<std::int64_t, std::int64_t>> seen;
            const double size = TerrainPatch::size_m(level);
            for (std::size_t i = 0; i < rp.samples.size(); i += 60) {
                const glm::dvec3 c = rp.samples[i].position_m;
                for (double dx = -64.0; dx <= 64.0; dx += size)
                    for (double dz = -64.0; dz <= 64.0; dz += size) {
                        const PatchKey key{level, std::int64_t(std::floor((c.x + dx) / size)),
                                           std::int64_t(std::floor((c.z + dz) / size))};
                        if (!seen.insert({key.i, key.k}).second) continue;
                        EXPECT_TRUE(TerrainPatch::generate(world, key).skyDetail.empty()) << name;
                        const TerrainPatch p =
                            TerrainPatch::generate(world, key, TerrainPatch::SkyDetail::Everywhere);
                        for (std::size_t j = 0; j < p.skyDetail.size(); j += 2)
                            moved.push_back(std::abs(double(p.skyDetail[j]) - p.skyDetail[j + 1]));
                    }
            }
        }
        ASSERT_GT(moved.size(), 100000u) << name;
        std::sort(moved.begin(), moved.end());
        EXPECT_LT(moved[moved.size() * 99 / 100], 0.02) << name;
        EXPECT_LT(moved.back(), 0.08) << name;
    }
}

}  // namespace
}  // namespace amb

// ---- Drawn surface and albedo ----------------------------------------------------------------

namespace amb {
namespace {

// The steepest spot below the snow line on a 250 m grid around the origin (mountainsides).
glm::dvec3 steepSpot(const World& world) {
    glm::dvec3 best(0.0);
    double steepest = -1.0;
    for (int i = -20; i <= 20; ++i)
        for (int k = -20; k <= 20; ++k) {
            const double x = 250.0 * i, z = 250.0 * k;
            const GroundSample g = world.sample(x, z);
            if (g.height_m > 450.0 || g.height_m < 20.0) continue;
            if (1.0 - g.normal.y > steepest) steepest = 1.0 - g.normal.y, best = {x, g.height_m, z};
        }
    return best;
}

TEST(TerrainSurface, MatchesTheDrawnTrianglesAndPlantsStandOnThem) {
    const World& world = defaultWorld();
    TerrainPatchCache cache(world, smallLod());
    const glm::dvec3 spot = steepSpot(world);
    const glm::dvec3 eye = spot + glm::dvec3(0.0, 2.0, 0.0);
    const TerrainMesh mesh = cache.build(eye, glm::dvec3(std::floor(eye.x), 0.0, std::floor(eye.z)));
    const TerrainSurface surface(mesh);
    // At every vertex of the packed mesh the surface is the vertex's height (to float rounding).
    for (std::size_t p = 0; p < mesh.patches.size(); p += 7) {
        const TerrainPatchDraw& d = mesh.patches[p];
        for (std::uint32_t v = d.firstVertex; v < d.firstVertex + d.vertexCount; v += 5) {
            const glm::dvec3 q = glm::dvec3(mesh.mesh.positions[3 * v], mesh.mesh.positions[3 * v + 1],
                                            mesh.mesh.positions[3 * v + 2]) + mesh.origin_m;
            ASSERT_NEAR(surface.heightAt(q.x, q.z), q.y, 1e-3 + 1e-6 * std::abs(q.y));
        }
    }
    // Plants within 600 m: the base stands at or below the drawn surface at the centre and at
    // the four footprint points (tolerance 1e-9 m), at the lowest of them, and sinks below the
    // centre by less than twice the footprint radius (coarse triangles are steeper than the
    // ground plants grow on, normal.y >= 0.65: a gradient of 1.17).
    const double r = 1.1;
    double worstOff = 0.0;
    int plants = 0;
    for (const Plant& p : world.vegetation().inDisc(spot.x, spot.z, 600.0)) {
        const double centre = surface.heightAt(p.position_m.x, p.position_m.z);
        if (!std::isfinite(centre)) continue;
        const double base = surface.baseUnder(p.position_m.x, p.position_m.z, r);
        EXPECT_LE(base, centre + 1e-9);
        double lowest = centre;
        for (const auto& [dx, dz] : {std::pair{r, 0.0}, {-r, 0.0}, {0.0, r}, {0.0, -r}}) {
            const double h = surface.heightAt(p.position_m.x + dx, p.position_m.z + dz);
            EXPECT_LE(base, h + 1e-9);
            lowest = std::min(lowest, h);
        }
        EXPECT_GE(base, lowest - 1e-9);
        EXPECT_GT(base, centre - 2.0 * r);
        worstOff = std::max(worstOff, std::abs(centre - p.position_m.y));
        ++plants;
    }
    EXPECT_GT(plants, 100);
    // Why: far patches lie well off the true ground (World::height) where plants were placed.
    EXPECT_GT(worstOff, 0.3);
    EXPECT_TRUE(std::isnan(surface.heightAt(spot.x + 1e5, spot.z)));
}

// The flattest spot of lowland (20 to 300 m) on a 250 m grid around the origin.
glm::dvec3 flatSpot(const World& world) {
    glm::dvec3 best(0.0);
    double flattest = 1e9;
    for (int i = -20; i <= 20; ++i)
        for (int k = -20; k <= 20; ++k) {
            const double x = 250.0 * i, z = 250.0 * k;
            const GroundSample g = world.sample(x, z);
            if (g.height_m > 300.0 || g.height_m < 20.0 || g.roadWeight > 0.0) continue;
            if (1.0 - g.normal.y < flattest) flattest = 1.0 - g.normal.y, best = {x, g.height_m, z};
        }
    return best;
}

TEST(TerrainAlbedo, RockOnSteepSlopesAndNoFlatColour) {
    const World& world = defaultWorld();
    int steep = 0, rockLike = 0;
    // Colour statistics: sums of the albedo and of its squared length, per class.
    glm::dvec3 grassSum(0.0), rockSum(0.0);
    double grassSq = 0.0, rockSq = 0.0;
    int grass = 0;
    for (const glm::dvec3& spot : {steepSpot(world), flatSpot(world)}) {
        const std::int64_t i0 = std::int64_t(std::floor(spot.x / 32.0)),
                           k0 = std::int64_t(std::floor(spot.z / 32.0));
        for (std::int64_t i = i0 - 6; i <= i0 + 6; ++i)
            for (std::int64_t k = k0 - 6; k <= k0 + 6; ++k) {
                const PatchKey key{0, i, k};
                const TerrainPatch p = TerrainPatch::generate(world, key);
                for (int v = 0; v < kV * kV; ++v) {
                    const double ny = p.normals[3 * v + 1];
                    const double x = vertexX(key, v % kV), z = vertexZ(key, v / kV);
                    double road = 0.0;
                    world.heightAndRoad(x, z, &road);
                    if (road > 0.0 || p.heights_m[v] < 5.0 || p.heights_m[v] > 450.0) continue;
                    const glm::dvec3 a(p.albedo[3 * v], p.albedo[3 * v + 1], p.albedo[3 * v + 2]);
                        if (1.0 - ny > World::kRockSlope + 0.1) {
                        ++steep;
                        // Stone: grey to warm, never green (g <= r) nor straw (b >= 0.45 r).
                        if (a.g <= 1.0 * a.r + 1e-6 && a.b >= 0.45 * a.r) ++rockLike;
                        rockSum += a, rockSq += glm::dot(a, a);
                    } else if (1.0 - ny < 0.03) {
                        ++grass;
                        grassSum += a, grassSq += glm::dot(a, a);
                    }
                }
            }
    }
    ASSERT_GT(steep, 200);
    ASSERT_GT(grass, 200);
    EXPECT_GE(double(rockLike) / steep, 0.95);
    // Not one flat colour: the albedo's RMS distance from its mean colour is 8 % of the mean's
    // length or more, on rock and on grass alike.
    const auto relStd = [](const glm::dvec3& sum, double sq, int n) {
        const glm::dvec3 mean = sum / double(n);
        return std::sqrt(std::max(0.0, sq / n - glm::dot(mean, mean))) / glm::length(mean);
    };
    EXPECT_GT(relStd(rockSum, rockSq, steep), 0.08);
    EXPECT_GT(relStd(grassSum, grassSq, grass), 0.08);
}

}  // namespace
}  // namespace amb
