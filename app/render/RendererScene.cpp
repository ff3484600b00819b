// RendererScene.cpp — world -> draw lists for the main view and for the capture.
//
// [SECTION] Culling      frustum planes from the camera-relative view-projection (reversed Z)
// [SECTION] Terrain      TerrainPatchCache leaves, rebuilt and re-uploaded only when they change
// [SECTION] Roads        ribbons along the centrelines, in chunks for culling, lit per vertex
// [SECTION] Plants       per-tile culling, per-plant distance LOD (full mesh, proxy, none)
// [SECTION] Capture      terrain proxy + tree proxies + roads around the probe
// [SECTION] Casters      what casts into a shadow map, culled to it (app/render/ShadowMap.h)
#include "app/render/RendererScene.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/matrix.hpp>

#include "world/Road.h"
#include "world/Vegetation.h"
#include "world/Vehicle.h"
#include "world/World.h"

namespace amb {

// ---- [SECTION] Culling -----------------------------------------------------------------------

namespace {

struct Frustum {
    std::array<glm::vec4, 5> planes;  // left, right, bottom, top, near; inside: dot >= 0
};

Frustum frustumOf(const glm::mat4& m) {
    const glm::vec4 r0(m[0][0], m[1][0], m[2][0], m[3][0]);
    const glm::vec4 r1(m[0][1], m[1][1], m[2][1], m[3][1]);
    const glm::vec4 r2(m[0][2], m[1][2], m[2][2], m[3][2]);
    const glm::vec4 r3(m[0][3], m[1][3], m[2][3], m[3][3]);
    // Reversed Z: depth = z / w in [0, 1]; depth <= 1 is the near plane (z <= w).
    return {{r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 - r2}};
}

// Camera-relative box against the frustum (positive-vertex test).
bool boxVisible(const Frustum& f, const glm::vec3& lo, const glm::vec3& hi) {
    for (const glm::vec4& p : f.planes) {
        const glm::vec3 v(p.x >= 0 ? hi.x : lo.x, p.y >= 0 ? hi.y : lo.y, p.z >= 0 ? hi.z : lo.z);
        if (p.x * v.x + p.y * v.y + p.z * v.z + p.w < 0.0f) return false;
    }
    return true;
}

// Camera-relative sphere against the frustum (planes not normalised).
bool sphereVisible(const Frustum& f, const glm::vec3& c, float r) {
    for (const glm::vec4& p : f.planes) {
        if (glm::dot(glm::vec3(p), c) + p.w < -r * glm::length(glm::vec3(p))) return false;
    }
    return true;
}

double horizontalDistance(const glm::dvec3& a, const glm::dvec3& b) {
    return std::hypot(a.x - b.x, a.z - b.z);
}

}  // namespace

// ---- [SECTION] Roads -------------------------------------------------------------------------

struct RendererScene::RoadChunk {
    glm::dvec3 origin_m;
    glm::dvec3 min_m, max_m;
    std::vector<glm::dvec3> vertices_m, normals;  // per mesh vertex, world position and normal
    GlMesh mesh;
};

static constexpr int kRoadChunkSegments = 48;

// The far LOD of a plant: an octahedron (6 vertices, 8 triangles) spanning the bounding box of
// the upper part of the mesh (the crown, or the whole of a bush or rock), with its mean albedo
// and ellipsoid normals, so it shades like a rounded crown at a few pixels' size. A bush or a
// rock (`mound`) is the whole mesh's box with its widest ring low, at a fifth of its height, and
// its lowest point below the ground: a mound sitting on the ground, not a diamond on its tip.
static WorldMesh farPlantMesh(const WorldMesh& full, bool mound) {
    float top = 0.0f;
    for (size_t i = 1; i < full.positions.size(); i += 3) top = std::max(top, full.positions[i]);
    glm::vec3 lo(1e30f), hi(-1e30f), albedo(0.0f);
    int n = 0;
    for (size_t v = 0; v < full.vertexCount(); ++v) {
        const glm::vec3 p(full.positions[3 * v], full.positions[3 * v + 1],
                          full.positions[3 * v + 2]);
        if (!mound && p.y < 0.35f * top) continue;
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
        albedo += glm::vec3(full.albedo[3 * v], full.albedo[3 * v + 1], full.albedo[3 * v + 2]);
        ++n;
    }
    albedo /= float(std::max(n, 1));
    glm::vec3 c = 0.5f * (lo + hi), r = glm::max(0.5f * (hi - lo), glm::vec3(0.05f));
    if (mound) c.y = std::max(0.0f, lo.y) + 0.2f * (hi.y - std::max(0.0f, lo.y));
    // Reach down to the ground so the far tree stands on it.
    const glm::vec3 dirs[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    WorldMesh m;
    for (const glm::vec3& d : dirs) {
        glm::vec3 p = c + d * r;
        if (d.y < 0.0f) p.y = mound ? std::min(lo.y, 0.0f) : 0.0f;
        if (d.y > 0.0f) p.y = hi.y;
        m.positions.insert(m.positions.end(), {p.x, p.y, p.z});
        m.normals.insert(m.normals.end(), {d.x, d.y, d.z});
        m.albedo.insert(m.albedo.end(), {albedo.r, albedo.g, albedo.b});
    }
    // Counter-clockwise from outside: (+x, +y, +z) is CCW seen from (1, 1, 1).
    const std::uint32_t tris[8][3] = {{0, 2, 4}, {4, 2, 1}, {1, 2, 5}, {5, 2, 0},
                                      {4, 3, 0}, {1, 3, 4}, {5, 3, 1}, {0, 3, 5}};
    for (const auto& t : tris) m.indices.insert(m.indices.end(), {t[0], t[1], t[2]});
    return m;
}

RendererScene::RendererScene(const World& world, const RendererSceneSettings& settings)
    : world_(world), settings_(settings), terrainCache_(world, settings.terrain) {
    const glm::vec3 roadAlbedo = World::materialAlbedo(Material::Road);
    for (const Road& road : world.roads().roads()) {
        const auto& c = road.centreline;
        for (size_t start = 0; start + 1 < c.size(); start += kRoadChunkSegments) {
            const size_t end = std::min(c.size() - 1, start + kRoadChunkSegments);
            const WorldMesh m = roadRibbon(road, start, end, settings.roadLift_m, roadAlbedo);
            RoadChunk chunk;
            chunk.origin_m = c[start];
            chunk.min_m = glm::dvec3(1e300);
            chunk.max_m = glm::dvec3(-1e300);
            // World positions and normals of the vertices: where the draw looks up the ambient.
            for (size_t v = 0; v < m.vertexCount(); ++v) {
                const glm::dvec3 p =
                    chunk.origin_m +
                    glm::dvec3(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
                chunk.min_m = glm::min(chunk.min_m, p);
                chunk.max_m = glm::max(chunk.max_m, p);
                chunk.vertices_m.push_back(p);
                chunk.normals.emplace_back(m.normals[3 * v], m.normals[3 * v + 1],
                                           m.normals[3 * v + 2]);
            }
            chunk.mesh = uploadMesh(m);
            roads_.push_back(std::move(chunk));
        }
    }
    for (int k = 0; k < kPlantKinds; ++k) {
        const WorldMesh& full = Vegetation::mesh(PlantKind(k));
        plantMeshes_[k] = uploadMesh(full);
        plantProxies_[k] = uploadMesh(Vegetation::proxyMesh(PlantKind(k)));
        plantFar_[k] = uploadMesh(
            farPlantMesh(full, PlantKind(k) == PlantKind::Bush || PlantKind(k) == PlantKind::Rock));
        float top = 0.0f;
        for (size_t i = 1; i < full.positions.size(); i += 3)
            top = std::max(top, full.positions[i]);
        plantHeight_m_[k] = top;
        // objectsAtCrown: the spheres' centre weighted by their area (conifer 4.7 m, broadleaf
        // 5.8 m).
        double sum = 0.0, weight = 0.0;
        for (const PlantSphere& s : Vegetation::spheres(PlantKind(k))) {
            sum += s.centre_m.y * s.radius_m * s.radius_m;
            weight += s.radius_m * s.radius_m;
        }
        plantAmbientHeight_m_[k] = settings_.objectsAtCrown && weight > 0.0 ? sum / weight : 0.0;
    }
    vehicleLevel_ = makeVehicleMesh();
    vehicleMesh_ = uploadMesh(vehicleLevel_);
}

RendererScene::~RendererScene() = default;

// ---- [SECTION] Terrain -----------------------------------------------------------------------

void RendererScene::updateTerrain(const glm::dvec3& eye_m) {
    std::vector<PatchKey> leaves = terrainCache_.selectPatches(eye_m);
    if (leaves == terrainLeaves_ && terrainGl_.indexCount > 0) return;
    terrainLeaves_ = std::move(leaves);
    terrainMesh_ = terrainCache_.build(terrainLeaves_, terrainMeshOrigin(eye_m));
    terrainGl_ = uploadMesh(terrainMesh_.mesh);
    terrainSurface_ = TerrainSurface(terrainMesh_);
    terrainBounds_.clear();
    const auto& pos = terrainMesh_.mesh.positions;
    for (const TerrainPatchDraw& p : terrainMesh_.patches) {
        PatchBounds b{glm::dvec3(1e300), glm::dvec3(-1e300)};
        for (std::uint32_t v = p.firstVertex; v < p.firstVertex + p.vertexCount; ++v) {
            const glm::dvec3 q(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]);
            b.min = glm::min(b.min, q);
            b.max = glm::max(b.max, q);
        }
        terrainBounds_.push_back({b.min + terrainMesh_.origin_m, b.max + terrainMesh_.origin_m});
    }
}

static TerrainDraw patchDraw(const GlMesh& mesh, const TerrainPatchDraw& p,
                             const glm::dvec3& meshOrigin_m, const glm::dvec3& eye_m,
                             const glm::vec3* cornerIrradiance) {
    TerrainDraw d;
    d.mesh = &mesh;
    d.firstIndex = p.firstIndex;
    d.indexCount = p.indexCount;
    d.origin = glm::vec3(meshOrigin_m - eye_m);
    const glm::dvec3 c0 = p.corners_m[0] - meshOrigin_m;
    const double size = p.corners_m[1].x - p.corners_m[0].x;
    d.rect = glm::vec4(float(c0.x), float(c0.z), float(1.0 / size), float(1.0 / size));
    for (int k = 0; k < 4; ++k) d.cornerIrradiance[k] = cornerIrradiance[k];
    return d;
}

void RendererScene::buildView(const glm::dvec3& eye_m, const glm::mat4& viewProj,
                              const AmbientSource& ambient, DrawList& out, SceneStats* stats) {
    out.clear();
    const auto before = terrainLeaves_;
    updateTerrain(eye_m);
    const Frustum frustum = frustumOf(viewProj);
    // Visible patches, nearest first: the software rasteriser's early depth test then skips
    // shading most hidden fragments.
    std::vector<std::pair<double, size_t>> visible;
    for (size_t i = 0; i < terrainMesh_.patches.size(); ++i) {
        const PatchBounds& b = terrainBounds_[i];
        if (!boxVisible(frustum, glm::vec3(b.min - eye_m), glm::vec3(b.max - eye_m))) continue;
        const glm::dvec3 nearest = glm::clamp(eye_m, b.min, b.max);
        visible.emplace_back(glm::length(nearest - eye_m), i);
    }
    std::sort(visible.begin(), visible.end());
    // Patches nearer the eye (horizontally, to their bounds) than the ambient's vertex range are
    // lit per mesh vertex (nearField.vertexAmbient_m; docs/ARCHITECTURE.md "Terrain and
    // objects"); the others blend their corners.
    // With a bound on the new vertices a frame (terrainVertexPointsPerFrame), a patch entering
    // the range takes its turn nearest first and blends its corners until then; a patch once
    // lit per vertex stays so while it is in range, seen or not (its values stay cached).
    const double vertexRange = ambient.terrainVertexRange_m();
    const int vertexBudget = ambient.terrainVertexPointsPerFrame();
    std::vector<char> inVertexRange(terrainMesh_.patches.size(), 0);
    std::unordered_set<PatchKey, PatchKeyHash> kept;
    for (std::size_t i = 0; i < terrainMesh_.patches.size(); ++i) {
        const PatchBounds& b = terrainBounds_[i];
        const double dx = std::max({b.min.x - eye_m.x, 0.0, eye_m.x - b.max.x});
        const double dz = std::max({b.min.z - eye_m.z, 0.0, eye_m.z - b.max.z});
        inVertexRange[i] = vertexRange > 0.0 && std::hypot(dx, dz) < vertexRange;
        if (inVertexRange[i] && vertexLit_.count(terrainMesh_.patches[i].key))
            kept.insert(terrainMesh_.patches[i].key);
    }
    vertexLit_.swap(kept);
    std::vector<std::size_t> visiblePatches, vertexPatches;
    std::size_t newVertices = 0;
    vertexWaiting_ = 0;
    for (const auto& [distance, i] : visible) {
        const TerrainPatchDraw& p = terrainMesh_.patches[i];
        bool lit = false;
        if (inVertexRange[i]) {
            lit = vertexLit_.count(p.key) > 0;
            if (!lit && (vertexBudget <= 0 || newVertices == 0 ||
                         newVertices + p.vertexCount <= std::size_t(vertexBudget))) {
                newVertices += p.vertexCount;
                vertexLit_.insert(p.key);
                lit = true;
            }
            if (!lit) ++vertexWaiting_;
        }
        (lit ? vertexPatches : visiblePatches).push_back(i);
    }
    // The corner-blended patches' corners in one batch (the frame's largest set of lookups),
    // each shared corner once; a corner inside a coarser neighbour's edge is not looked up but
    // takes that edge's interpolation, so colours meet across LOD boundaries
    // (world/TerrainPatch.h).
    const std::vector<std::uint32_t> evaluate = cornersToEvaluate(terrainMesh_, visiblePatches);
    std::vector<glm::dvec3> cornerAt, cornerNormal;
    std::vector<double> cornerPatch;
    for (std::uint32_t c : evaluate) {
        cornerAt.push_back(terrainMesh_.corners[c].position_m);
        cornerNormal.push_back(terrainMesh_.corners[c].normal);
        cornerPatch.push_back(terrainMesh_.corners[c].patch_m);
    }
    std::vector<glm::vec3> irradiance(cornerAt.size());
    ambient.cornerIrradianceBatch(cornerAt.size(), cornerAt.data(), cornerNormal.data(),
                                  irradiance.data(), cornerPatch.data());
    std::vector<glm::vec3> cornerValue(terrainMesh_.corners.size(), glm::vec3(0.0f));
    for (std::size_t j = 0; j < evaluate.size(); ++j) cornerValue[evaluate[j]] = irradiance[j];
    stitchCornerValues(terrainMesh_.corners, cornerValue.data());
    const bool skyDetail = ambient.terrainSkyDetail();
    // In the draw order (nearest first), each patch lit per vertex or by its corners.
    std::vector<char> perVertex(terrainMesh_.patches.size(), 0);
    for (std::size_t i : vertexPatches) perVertex[i] = 1;
    for (const auto& [distance, i] : visible) {
        const TerrainPatchDraw& p = terrainMesh_.patches[i];
        glm::vec3 corners[4];
        for (int k = 0; k < 4; ++k) corners[k] = cornerValue[p.cornerIndex[k]];
        out.terrain.push_back(patchDraw(terrainGl_, p, terrainMesh_.origin_m, eye_m, corners));
        if (perVertex[i]) {
            // Mesh vertex v reads vertexIrradiance[v] (the layout: addRoads). The sky detail
            // scales a blend of corners; a vertex's own value needs none.
            out.terrain.back().firstVertexIrradiance = 0;
        } else {
            out.terrain.back().skyDetail = skyDetail;
        }
    }
    // The per-vertex patches' vertices: world position and the mesh's (stitched) normal, each
    // asked as a point (no patch mean: the vertex spacing is a few metres, and a mean over the
    // cell cost four times the near-field builds for 0.01 of error; docs/TUNING.md).
    VertexPoints terrainVertices;
    const auto& pos = terrainMesh_.mesh.positions;
    const auto& nrm = terrainMesh_.mesh.normals;
    for (std::size_t i : vertexPatches) {
        const TerrainPatchDraw& p = terrainMesh_.patches[i];
        for (std::uint32_t v = p.firstVertex; v < p.firstVertex + p.vertexCount; ++v) {
            terrainVertices.index.push_back(v);
            terrainVertices.at.push_back(terrainMesh_.origin_m +
                                         glm::dvec3(pos[3 * v], pos[3 * v + 1], pos[3 * v + 2]));
            terrainVertices.normal.emplace_back(nrm[3 * v], nrm[3 * v + 1], nrm[3 * v + 2]);
        }
    }
    const std::size_t drawnPatches = visible.size();
    addRoads(eye_m, &viewProj, settings_.terrain.viewRadius_m, ambient, out,
             vertexPatches.empty() ? nullptr : &terrainVertices);
    std::size_t objects = 0;
    // The car's set is asked with the plants': new points in one batch are built together.
    std::uint32_t vehicleSet = 0;
    addPlants(eye_m, &viewProj, false, ambient, out, &objects, 0.0,
              vehicle_ ? &vehicle_->position_m : nullptr, &vehicleSet);
    if (vehicle_) {
        // The camera's own car (docs/ARCHITECTURE.md "Terrain and objects": vegetation and vehicle
        // get per-pixel SH).
        // Pitched on the CPU (the object shader turns about +Y only); on the road ribbon, which
        // floats roadLift_m above the terrain the replay's eye height counts from.
        if (std::abs(vehicle_->pitch_rad - vehicleMeshPitch_rad_) > 1e-4) {
            vehicleMesh_ = uploadMesh(pitchedMesh(vehicleLevel_, vehicle_->pitch_rad));
            vehicleMeshPitch_rad_ = vehicle_->pitch_rad;
        }
        ObjectInstance inst;
        const glm::dvec3 rel =
            vehicle_->position_m + glm::dvec3(0.0, settings_.roadLift_m, 0.0) - eye_m;
        inst.positionScale = glm::vec4(float(rel.x), float(rel.y), float(rel.z), 1.0f);
        inst.rotationSet = glm::vec2(float(vehicle_->heading_rad), float(vehicleSet));
        out.objects.push_back({&vehicleMesh_, {inst}, false, true});
        ++objects;
    }
    if (stats) {
        stats->terrainPatches = terrainMesh_.patches.size();
        stats->terrainPatchesDrawn = drawnPatches;
        stats->objectsDrawn = objects;
        stats->terrainRebuilt = before != terrainLeaves_;
        stats->terrainPatchesVertex = vertexPatches.size();
        stats->terrainPatchesWaiting = vertexWaiting_;
    }
}

void RendererScene::addRoads(const glm::dvec3& eye_m, const glm::mat4* viewProj, double range_m,
                             const AmbientSource& ambient, DrawList& out,
                             const VertexPoints* terrain) {
    Frustum frustum{};
    if (viewProj) frustum = frustumOf(*viewProj);
    // The ambient at every vertex of the visible pieces, with the vertex's own normal, in one
    // batch (docs/ARCHITECTURE.md "Terrain and objects").
    std::vector<const RoadChunk*> drawn;
    std::vector<glm::dvec3> at, normal;
    for (const RoadChunk& c : roads_) {
        const glm::dvec3 centre = 0.5 * (c.min_m + c.max_m);
        const double radius = 0.5 * glm::length(c.max_m - c.min_m);
        if (horizontalDistance(centre, eye_m) - radius > range_m) continue;
        if (viewProj &&
            !boxVisible(frustum, glm::vec3(c.min_m - eye_m), glm::vec3(c.max_m - eye_m)))
            continue;
        drawn.push_back(&c);
        at.insert(at.end(), c.vertices_m.begin(), c.vertices_m.end());
        normal.insert(normal.end(), c.normals.begin(), c.normals.end());
    }
    std::size_t first = out.vertexIrradiance.size();
    if (!terrain) {
        out.vertexIrradiance.resize(first + at.size());
        ambient.cornerIrradianceBatch(at.size(), at.data(), normal.data(),
                                      out.vertexIrradiance.data() + first);
    } else {
        // Terrain vertices lit per vertex, and the road vertices after them, in one batch, all
        // as points (no patch_m). The buffer is bound at a byte offset, which cannot be
        // negative, and a patch's indices are absolute into the shared terrain mesh: so the
        // terrain's part is laid out by mesh vertex, vertexIrradiance[first + v] for mesh vertex
        // v (firstVertexIrradiance = first for every such patch), up to the last one used; the
        // vertices of patches blending their corners stay zero there, unread. The roads' part
        // follows.
        const std::size_t terrainCount = terrain->at.size();
        std::uint32_t end = 0;
        for (std::uint32_t v : terrain->index) end = std::max(end, v + 1);
        std::vector<glm::dvec3> allAt(terrain->at), allNormal(terrain->normal);
        allAt.insert(allAt.end(), at.begin(), at.end());
        allNormal.insert(allNormal.end(), normal.begin(), normal.end());
        std::vector<glm::vec3> values(allAt.size());
        ambient.cornerIrradianceBatch(allAt.size(), allAt.data(), allNormal.data(),
                                      values.data());
        out.vertexIrradiance.resize(first + end + at.size(), glm::vec3(0.0f));
        for (std::size_t j = 0; j < terrainCount; ++j)
            out.vertexIrradiance[first + terrain->index[j]] = values[j];
        for (TerrainDraw& d : out.terrain)
            if (!d.road && d.firstVertexIrradiance >= 0)
                d.firstVertexIrradiance = std::int64_t(first);
        std::copy(values.begin() + std::ptrdiff_t(terrainCount), values.end(),
                  out.vertexIrradiance.begin() + std::ptrdiff_t(first + end));
        first += end;
    }
    std::size_t offset = first;
    for (const RoadChunk* c : drawn) {
        TerrainDraw d;
        d.mesh = &c->mesh;
        d.origin = glm::vec3(c->origin_m - eye_m);
        d.firstVertexIrradiance = std::int64_t(offset);
        d.road = true;
        offset += c->vertices_m.size();
        out.terrain.push_back(d);
    }
}

// ---- [SECTION] Plants ------------------------------------------------------------------------

// Far patches are coarse: their surface lies up to metres above or below a plant's true base
// (World::height), and a plant placed there floats or sinks. The main view stands each plant on
// the drawn surface instead (TerrainSurface::baseUnder: the lowest of it under a trunk's width
// for trees, under half the footprint for bushes and rocks). Where no leaf is drawn, the true
// base; never more than kPlantSinkMargin_m from it (which the culling boxes allow for).
static constexpr double kPlantSinkMargin_m = 12.0;

static double drawnBase_m(const TerrainSurface& surface, const Plant& p) {
    const bool small = p.kind == PlantKind::Bush || p.kind == PlantKind::Rock;
    const double r = p.scale * (small ? 0.5 * Vegetation::footprintRadius_m(p.kind) : 0.3);
    const double base = surface.baseUnder(p.position_m.x, p.position_m.z, r);
    if (!std::isfinite(base)) return p.position_m.y;
    return std::clamp(base, p.position_m.y - kPlantSinkMargin_m,
                      p.position_m.y + kPlantSinkMargin_m);
}

void RendererScene::addPlants(const glm::dvec3& centre_m, const glm::mat4* viewProj, bool capture,
                              const AmbientSource& ambient, DrawList& out, std::size_t* drawn,
                              double nearRadius_m, const glm::dvec3* alsoAt,
                              std::uint32_t* alsoSet) {
    const Vegetation& veg = world_.vegetation();
    const double range = capture ? settings_.captureTreeRange_m : settings_.plantRange_m;
    Frustum frustum{};
    if (viewProj) frustum = frustumOf(*viewProj);
    // Batches: full meshes per kind, then proxies per kind.
    const size_t base = out.objects.size();
    for (int k = 0; k < kPlantKinds; ++k) out.objects.push_back({&plantMeshes_[k], {}});
    for (int k = 0; k < kPlantKinds; ++k) out.objects.push_back({&plantProxies_[k], {}, true});
    for (int k = 0; k < kPlantKinds; ++k) out.objects.push_back({&plantFar_[k], {}, true});
    const std::int64_t i0 = Vegetation::tileIndex(centre_m.x - range);
    const std::int64_t i1 = Vegetation::tileIndex(centre_m.x + range);
    const std::int64_t k0 = Vegetation::tileIndex(centre_m.z - range);
    const std::int64_t k1 = Vegetation::tileIndex(centre_m.z + range);
    const float maxHeight = *std::max_element(plantHeight_m_.begin(), plantHeight_m_.end());
    std::size_t count = 0;
    for (std::int64_t k = k0; k <= k1; ++k) {
        for (std::int64_t i = i0; i <= i1; ++i) {
            const double x0 = double(i) * Vegetation::kTile_m, z0 = double(k) * Vegetation::kTile_m;
            const double dx =
                std::max({x0 - centre_m.x, 0.0, centre_m.x - x0 - Vegetation::kTile_m});
            const double dz =
                std::max({z0 - centre_m.z, 0.0, centre_m.z - z0 - Vegetation::kTile_m});
            if (std::hypot(dx, dz) > range) continue;
            const auto plants = veg.tile(i, k);
            if (plants->empty()) continue;
            if (viewProj) {
                double ylo = 1e300, yhi = -1e300;
                for (const Plant& p : *plants) {
                    ylo = std::min(ylo, p.position_m.y);
                    yhi = std::max(yhi, p.position_m.y + p.scale * maxHeight);
                }
                // Plants stand on the drawn terrain, up to a few metres below their true base.
                ylo -= kPlantSinkMargin_m;
                yhi += kPlantSinkMargin_m;
                const glm::vec3 lo(float(x0 - 4 - centre_m.x), float(ylo - centre_m.y),
                                   float(z0 - 4 - centre_m.z));
                const glm::vec3 hi(float(x0 + Vegetation::kTile_m + 4 - centre_m.x),
                                   float(yhi - centre_m.y),
                                   float(z0 + Vegetation::kTile_m + 4 - centre_m.z));
                if (!boxVisible(frustum, lo, hi)) continue;
            }
            // Far plants (a few pixels tall) share one ambient set per tile, asked for at the
            // tile's centre: ambience LOD, so distant forests cost one lookup per tile.
            std::int64_t tileSet = -1;
            for (const Plant& p : *plants) {
                const int kind = int(p.kind);
                // Where the plant's ambient is asked (objectsAtCrown: above its base).
                const glm::dvec3 askAt =
                    p.position_m + glm::dvec3(0.0, p.scale * plantAmbientHeight_m_[kind], 0.0);
                const bool small = p.kind == PlantKind::Bush || p.kind == PlantKind::Rock;
                if (capture && small) continue;  // the capture scene keeps only trees
                const double d = glm::length(p.position_m - centre_m);
                if (d > range) continue;
                if (nearRadius_m > 0.0 && horizontalDistance(p.position_m, centre_m) < nearRadius_m)
                    continue;  // the near field's (lighting/NearField.h)
                int lod = 1;  // 0 full, 1 proxy, 2 far; a capture uses proxies
                if (!capture) {
                    // Projected height in pixels (small-angle: size / distance radians).
                    const double pixels = settings_.pixelsPerRadian * p.scale *
                                          plantHeight_m_[kind] / std::max(d, 1.0);
                    if (pixels < settings_.farMinPixels) continue;
                    lod = pixels >= settings_.fullMeshMinPixels ? 0
                          : pixels >= settings_.proxyMinPixels  ? 1
                                                                : 2;
                }
                ObjectInstance inst;
                glm::dvec3 rel = p.position_m - centre_m;
                if (!capture) rel.y = drawnBase_m(terrainSurface_, p) - centre_m.y;
                inst.positionScale = glm::vec4(float(rel.x), float(rel.y), float(rel.z), p.scale);
                const std::size_t batch = base + std::size_t(lod * kPlantKinds + kind);
                std::uint32_t set = 0;
                if (lod == 2) {
                    if (tileSet < 0) {
                        const double h = 0.5 * Vegetation::kTile_m;
                        tileSet = ambient.objectSet({x0 + h, askAt.y, z0 + h}, out.ambientSets);
                    }
                    set = std::uint32_t(tileSet);
                } else {
                    // Asked for below, all at once.
                    pendingSlot_.push_back({batch, out.objects[batch].instances.size()});
                    pendingAt_.push_back(askAt);
                }
                inst.rotationSet = glm::vec2(p.rotation_rad, float(set));
                out.objects[batch].instances.push_back(inst);
                ++count;
            }
        }
    }
    // The plants' own sets in one batch (lighting's batch lookups: one lock, one timing).
    if (alsoAt) pendingAt_.push_back(*alsoAt);
    pendingIndex_.resize(pendingAt_.size());
    ambient.objectSets(pendingAt_.size(), pendingAt_.data(), out.ambientSets, pendingIndex_.data());
    if (alsoAt) *alsoSet = pendingIndex_.back();
    for (std::size_t i = 0; i < pendingSlot_.size(); ++i) {
        const auto [batch, instance] = pendingSlot_[i];
        out.objects[batch].instances[instance].rotationSet.y = float(pendingIndex_[i]);
    }
    pendingSlot_.clear(), pendingAt_.clear();
    // Nearest first within each batch, so the early depth test rejects hidden fragments.
    if (!capture) {
        for (size_t b = base; b < out.objects.size(); ++b) {
            auto& v = out.objects[b].instances;
            std::sort(v.begin(), v.end(), [](const ObjectInstance& a, const ObjectInstance& c) {
                return glm::dot(glm::vec3(a.positionScale), glm::vec3(a.positionScale)) <
                       glm::dot(glm::vec3(c.positionScale), glm::vec3(c.positionScale));
            });
        }
    }
    if (drawn) *drawn = count;
}

// ---- [SECTION] Capture -----------------------------------------------------------------------

void RendererScene::buildCapture(const glm::dvec3& probe_m, const AmbientSource& ambient,
                                 DrawList& out, double nearRadius_m) {
    out.clear();
    // The proxy grid is finest at its centre, so it is rebuilt when the probe moves off it.
    if (horizontalDistance(probe_m, captureCentre_) > 1e-3 || captureTerrain_.indexCount == 0) {
        captureCentre_ = glm::dvec3(probe_m.x, 0.0, probe_m.z);
        captureProxy_ = makeTerrainProxy(world_, captureCentre_, settings_.captureTerrainRadius_m);
        captureTerrain_ = uploadMesh(captureProxy_);
    }
    TerrainDraw d;
    d.mesh = &captureTerrain_;
    d.origin = glm::vec3(captureCentre_ - probe_m);
    // The proxy lit at every vertex, with the vertex's own point and normal (1089 of them by
    // default): the ambient where a surface light varies over the ground, and the hemisphere's
    // own dependence on the normal, at the ground the probe sees.
    const std::size_t vertices = captureProxy_.vertexCount();
    captureAt_.resize(vertices);
    captureNormal_.resize(vertices);
    for (std::size_t v = 0; v < vertices; ++v) {
        const float* p = &captureProxy_.positions[3 * v];
        const float* n = &captureProxy_.normals[3 * v];
        captureAt_[v] = captureCentre_ + glm::dvec3(p[0], p[1], p[2]);
        captureNormal_[v] = glm::dvec3(n[0], n[1], n[2]);
    }
    d.firstVertexIrradiance = std::int64_t(out.vertexIrradiance.size());
    out.vertexIrradiance.resize(out.vertexIrradiance.size() + vertices);
    ambient.cornerIrradianceBatch(vertices, captureAt_.data(), captureNormal_.data(),
                                  out.vertexIrradiance.data() + d.firstVertexIrradiance);
    out.terrain.push_back(d);
    addRoads(probe_m, nullptr, settings_.captureTerrainRadius_m, ambient, out);
    addPlants(probe_m, nullptr, true, ambient, out, nullptr, nearRadius_m);
}

}  // namespace amb

namespace amb {

// ---- [SECTION] Casters -----------------------------------------------------------------------

void RendererScene::buildCasters(const glm::dvec3& eye_m, const glm::mat4& lightViewProj,
                                 double texel_m, DrawList& out, bool withVehicle,
                                 bool withPlants) {
    out.clear();
    updateTerrain(eye_m);
    // frustumOf's fifth plane is depth <= 1: for the light's box, its far side. The light side
    // stays open: everything towards the light casts.
    const Frustum frustum = frustumOf(lightViewProj);
    for (size_t i = 0; i < terrainMesh_.patches.size(); ++i) {
        const PatchBounds& b = terrainBounds_[i];
        if (!boxVisible(frustum, glm::vec3(b.min - eye_m), glm::vec3(b.max - eye_m))) continue;
        const glm::vec3 none[4] = {};
        out.terrain.push_back(
            patchDraw(terrainGl_, terrainMesh_.patches[i], terrainMesh_.origin_m, eye_m, none));
    }
    for (const RoadChunk& c : roads_) {
        if (!boxVisible(frustum, glm::vec3(c.min_m - eye_m), glm::vec3(c.max_m - eye_m)))
            continue;
        TerrainDraw d;
        d.mesh = &c.mesh;
        d.origin = glm::vec3(c.origin_m - eye_m);
        d.road = true;
        out.terrain.push_back(d);
    }
    if (withPlants) addPlantCasters(eye_m, lightViewProj, texel_m, false, out);
    if (vehicle_ && withVehicle) {
        ObjectInstance inst;
        const glm::dvec3 rel = vehicle_->position_m - eye_m;
        inst.positionScale = glm::vec4(float(rel.x), float(rel.y), float(rel.z), 1.0f);
        inst.rotationSet = glm::vec2(float(vehicle_->heading_rad), 0.0f);
        out.objects.push_back({&vehicleMesh_, {inst}});
    }
}

void RendererScene::buildCaptureCasters(const glm::dvec3& centre_m,
                                        const glm::mat4& lightViewProj, double texel_m,
                                        DrawList& out) {
    out.clear();
    if (horizontalDistance(centre_m, shadowTerrainCentre_) > 1e-3 ||
        shadowTerrain_.indexCount == 0) {
        shadowTerrainCentre_ = glm::dvec3(centre_m.x, 0.0, centre_m.z);
        shadowTerrain_ = uploadMesh(
            makeTerrainProxy(world_, shadowTerrainCentre_, settings_.captureTerrainRadius_m));
    }
    TerrainDraw d;
    d.mesh = &shadowTerrain_;
    d.origin = glm::vec3(shadowTerrainCentre_ - centre_m);
    out.terrain.push_back(d);
    addPlantCasters(centre_m, lightViewProj, texel_m, true, out);
}

void RendererScene::addPlantCasters(const glm::dvec3& eye_m, const glm::mat4& lightViewProj,
                                    double texel_m, bool treesOnly, DrawList& out) {
    const Vegetation& veg = world_.vegetation();
    const Frustum frustum = frustumOf(lightViewProj);
    const size_t base = out.objects.size();
    for (int k = 0; k < kPlantKinds; ++k) out.objects.push_back({&plantMeshes_[k], {}});
    for (int k = 0; k < kPlantKinds; ++k) out.objects.push_back({&plantProxies_[k], {}, true});
    for (int k = 0; k < kPlantKinds; ++k) out.objects.push_back({&plantFar_[k], {}, true});
    // The tiles under the light's box: its eight corners seen from above, widened by the
    // shadow of the tallest plant (a plant outside the box may reach into it towards the light).
    const glm::mat4 inv = glm::inverse(lightViewProj);
    glm::dvec2 lo(1e300), hi(-1e300);
    for (int c = 0; c < 8; ++c) {
        const glm::vec4 p = inv * glm::vec4(c & 1 ? 1 : -1, c & 2 ? 1 : -1, c & 4 ? 1 : 0, 1);
        const glm::dvec2 q(eye_m.x + p.x / p.w, eye_m.z + p.z / p.w);
        lo = glm::min(lo, q), hi = glm::max(hi, q);
    }
    const glm::vec3 toLight = -glm::normalize(glm::vec3(lightViewProj[0][2], lightViewProj[1][2],
                                                        lightViewProj[2][2]));
    const float maxHeight = *std::max_element(plantHeight_m_.begin(), plantHeight_m_.end());
    const double reach = std::min(
        600.0, double(maxHeight) * std::hypot(toLight.x, toLight.z) / std::max(toLight.y, 0.05f));
    const std::int64_t i0 = Vegetation::tileIndex(lo.x - reach), i1 = Vegetation::tileIndex(hi.x + reach);
    const std::int64_t k0 = Vegetation::tileIndex(lo.y - reach), k1 = Vegetation::tileIndex(hi.y + reach);
    for (std::int64_t k = k0; k <= k1; ++k) {
        for (std::int64_t i = i0; i <= i1; ++i) {
            const auto plants = veg.tile(i, k);
            if (plants->empty()) continue;
            const double x0 = double(i) * Vegetation::kTile_m, z0 = double(k) * Vegetation::kTile_m;
            double ylo = 1e300, yhi = -1e300;
            for (const Plant& p : *plants) {
                ylo = std::min(ylo, p.position_m.y);
                yhi = std::max(yhi, p.position_m.y + p.scale * maxHeight);
            }
            const glm::vec3 tlo(float(x0 - 4 - eye_m.x), float(ylo - eye_m.y), float(z0 - 4 - eye_m.z));
            const glm::vec3 thi(float(x0 + Vegetation::kTile_m + 4 - eye_m.x), float(yhi - eye_m.y),
                                float(z0 + Vegetation::kTile_m + 4 - eye_m.z));
            if (!boxVisible(frustum, tlo, thi)) continue;
            for (const Plant& p : *plants) {
                const int kind = int(p.kind);
                const bool small = p.kind == PlantKind::Bush || p.kind == PlantKind::Rock;
                if (treesOnly && small) continue;
                const float h = float(p.scale) * plantHeight_m_[kind];
                const glm::vec3 rel(p.position_m - eye_m);
                if (!sphereVisible(frustum, rel + glm::vec3(0.0f, 0.5f * h, 0.0f), 0.6f * h + 0.5f))
                    continue;
                // LOD by the plant's height in texels: the full mesh where its shape shows, the
                // proxy, the 8-triangle hull, nothing below a texel.
                int lod = 1;
                if (texel_m > 0.0) {
                    const double texels = h / texel_m;
                    if (texels < 1.0) continue;
                    lod = texels >= 64.0 ? 0 : texels >= 12.0 ? 1 : 2;
                }
                ObjectInstance inst;
                inst.positionScale = glm::vec4(rel, float(p.scale));
                inst.rotationSet = glm::vec2(p.rotation_rad, 0.0f);
                out.objects[base + lod * kPlantKinds + kind].instances.push_back(inst);
            }
        }
    }
}

}  // namespace amb
