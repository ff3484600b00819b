// Vegetation.cpp — deterministic plant placement per tile and the plant meshes.
//
// [SECTION] Per-cell random numbers: a hash of (seed, layer, cell key), never a running RNG
// [SECTION] Habitat: density from slope, height, moisture; zero on roads, water, rock, snow
// [SECTION] Matérn type-II thinning over the 3x3 cell neighbourhood
// [SECTION] Meshes: full (trunk + crown) and coarse proxies
#include "world/Vegetation.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <glm/vec2.hpp>
#include <glm/geometric.hpp>
#define GLM_ENABLE_EXPERIMENTAL
#include <glm/gtx/intersect.hpp>

#include "world/Conventions.h"
#include "world/World.h"

namespace amb {

namespace {

// ---- [SECTION] Per-cell random numbers -----------------------------------------------------

inline std::uint64_t mix64(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

// A small counter-based stream for one cell: the same cell gives the same numbers in every tile
// that looks at it.
struct CellRandom {
    std::uint64_t state;
    CellRandom(std::uint64_t seed, int layer, std::int64_t cx, std::int64_t cz)
        : state(mix64(seed ^ mix64(static_cast<std::uint64_t>(cx) * 0x9E3779B97F4A7C15ull ^
                                   mix64(static_cast<std::uint64_t>(cz) + 0x632BE59BD9B4E019ull +
                                         static_cast<std::uint64_t>(layer))))) {}
    std::uint64_t next() { return mix64(state += 0x9E3779B97F4A7C15ull); }
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }  // [0, 1)
};

inline double smoothstep(double e0, double e1, double x) {
    const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

constexpr int kTreeLayer = 0;
constexpr int kSmallLayer = 1;
constexpr double kTreeLine_m = 540.0;     // no trees above
constexpr double kMaxTreeDensity = 0.85;  // upper bound of treeDensity()
constexpr double kMaxSmallDensity = 0.5;  // upper bound of the bush + rock density
constexpr double kSlopeStep_m = 1.0;      // forward-difference step for the habitat slope

// Tiles are whole numbers of cells of either layer.
constexpr int kTreeCellsPerTile = 16;
constexpr int kSmallCellsPerTile = 20;
static_assert(Vegetation::kTile_m == kTreeCellsPerTile * Vegetation::kTreeSpacing_m);
static_assert(Vegetation::kTile_m == kSmallCellsPerTile * Vegetation::kSmallSpacing_m);

}  // namespace

const char* toString(PlantKind kind) {
    switch (kind) {
        case PlantKind::Conifer:
            return "conifer";
        case PlantKind::Broadleaf:
            return "broadleaf";
        case PlantKind::Bush:
            return "bush";
        case PlantKind::Rock:
            return "rock";
    }
    return "?";
}

// ---- [SECTION] Habitat -----------------------------------------------------------------------

// The local conditions a candidate is tested against.
struct Vegetation::Habitat {
    double height_m, slope, moisture, clump;
    bool onRoad, inWater;
};

namespace {

// Local conditions at (x, z): natural height, slope (1 - n.y from forward differences), moisture,
// a forest-clump noise, and the road and water masks.
struct HabitatProbe {
    const World& world;
    Heightfield::Octave clumps;

    void operator()(double x, double z, double* h, double* slope, double* moisture, double* clump,
                    bool* onRoad, bool* inWater) const {
        const Heightfield& hf = world.heightfield();
        *h = hf.height(x, z);
        *inWater = *h < world.settings().waterLevel_m + 0.5;
        *onRoad = false;
        if (auto q = world.roads().nearest(x, z, 12.0 + Vegetation::kRoadClearance_m)) {
            *onRoad = q->distance_m < q->halfWidth_m + Vegetation::kRoadClearance_m;
        }
        if (*inWater || *onRoad) return;
        const double hx = hf.height(x + kSlopeStep_m, z);
        const double hz = hf.height(x, z + kSlopeStep_m);
        const glm::dvec3 n =
            glm::normalize(glm::dvec3(-(hx - *h) / kSlopeStep_m, 1.0, -(hz - *h) / kSlopeStep_m));
        *slope = 1.0 - n.y;
        *moisture = hf.moistureAt(x, z, *h);
        *clump = Heightfield::octaveNoise(clumps, x, z);
    }
};

double treeDensityOf(double h, double slope, double moisture, double clump, bool onRoad,
                     bool inWater) {
    if (onRoad || inWater || slope > Vegetation::kTreeMaxSlope || h > kTreeLine_m) return 0.0;
    const double wet = smoothstep(0.3, 0.75, moisture + 0.35 * clump);
    const double altitude = 1.0 - smoothstep(kTreeLine_m - 160.0, kTreeLine_m, h);
    const double steep =
        1.0 - smoothstep(0.6 * Vegetation::kTreeMaxSlope, Vegetation::kTreeMaxSlope, slope);
    return kMaxTreeDensity * wet * altitude * steep;
}

// Bush and rock densities (their sum is at most kMaxSmallDensity).
void smallDensities(double h, double slope, double moisture, bool onRoad, bool inWater,
                    double* bush, double* rock) {
    *bush = *rock = 0.0;
    if (onRoad || inWater || slope > Vegetation::kRockMaxSlope) return;
    if (slope < Vegetation::kTreeMaxSlope && h < kTreeLine_m + 60.0) {
        *bush = 0.3 * smoothstep(0.25, 0.7, moisture);
    }
    *rock = 0.04 + 0.16 * smoothstep(0.08, 0.25, slope);
}

struct Candidate {
    double x, z;
    std::uint64_t priority;
    bool alive;
    PlantKind kind;
    float scale, rotation;
};

}  // namespace

Vegetation::Vegetation(const World& world) : world_(world), seed_(world.settings().seed) {}
Vegetation::~Vegetation() = default;

std::int64_t Vegetation::tileIndex(double coordinate_m) {
    return static_cast<std::int64_t>(std::floor(coordinate_m / kTile_m));
}

double Vegetation::treeDensity(double x_m, double z_m) const {
    HabitatProbe probe{world_, Heightfield::makeOctave(seed_, 0x7C1u, 420.0)};
    double h = 0, slope = 0, moisture = 0, clump = 0;
    bool onRoad = false, inWater = false;
    probe(x_m, z_m, &h, &slope, &moisture, &clump, &onRoad, &inWater);
    return treeDensityOf(h, slope, moisture, clump, onRoad, inWater);
}

// ---- [SECTION] Matérn type-II thinning -------------------------------------------------------

std::vector<Plant> Vegetation::generateTile(std::int64_t ti, std::int64_t tk) const {
    const HabitatProbe probe{world_, Heightfield::makeOctave(seed_, 0x7C1u, 420.0)};

    // Builds the candidates of one layer for cells [c0 - border, c0 + n + border)^2.
    auto candidates = [&](int layer, double cell_m, std::int64_t c0x, std::int64_t c0z, int n,
                          int border) {
        const int w = n + 2 * border;
        std::vector<Candidate> out(static_cast<std::size_t>(w) * w);
        for (int j = 0; j < w; ++j) {
            for (int i = 0; i < w; ++i) {
                const std::int64_t cx = c0x - border + i, cz = c0z - border + j;
                CellRandom rng(seed_, layer, cx, cz);
                Candidate& c = out[static_cast<std::size_t>(j) * w + i];
                c.x = (static_cast<double>(cx) + rng.uniform()) * cell_m;
                c.z = (static_cast<double>(cz) + rng.uniform()) * cell_m;
                c.priority = rng.next();
                const double draw = rng.uniform();
                const double kindDraw = rng.uniform();
                c.scale = static_cast<float>(0.75 + 0.5 * rng.uniform());
                c.rotation = static_cast<float>(2.0 * kPi * rng.uniform());
                c.alive = false;
                // The draw decides before any terrain is evaluated when it cannot pass anyway.
                const double maxDensity = layer == kTreeLayer ? kMaxTreeDensity : kMaxSmallDensity;
                if (draw >= maxDensity) continue;
                double h, slope = 0, moisture = 0, clump = 0;
                bool onRoad, inWater;
                probe(c.x, c.z, &h, &slope, &moisture, &clump, &onRoad, &inWater);
                if (layer == kTreeLayer) {
                    c.alive = draw < treeDensityOf(h, slope, moisture, clump, onRoad, inWater);
                    // Conifers take over with height and dryness.
                    const double conifer = std::clamp(
                        0.2 + 0.9 * smoothstep(120.0, 420.0, h) - 0.5 * (moisture - 0.5), 0.0, 1.0);
                    c.kind = kindDraw < conifer ? PlantKind::Conifer : PlantKind::Broadleaf;
                } else {
                    double bush, rock;
                    smallDensities(h, slope, moisture, onRoad, inWater, &bush, &rock);
                    c.alive = draw < bush + rock;
                    c.kind = draw < bush ? PlantKind::Bush : PlantKind::Rock;
                }
            }
        }
        return out;
    };

    // Matérn II: a live candidate is kept unless a live neighbour within `spacing` has a higher
    // priority. Evaluated for cells [border, w - border) of the candidate grid.
    auto thin = [](const std::vector<Candidate>& cand, int w, int border, double spacing_m) {
        std::vector<const Candidate*> kept;
        const double r2 = spacing_m * spacing_m;
        for (int j = border; j < w - border; ++j) {
            for (int i = border; i < w - border; ++i) {
                const Candidate& c = cand[static_cast<std::size_t>(j) * w + i];
                if (!c.alive) continue;
                bool keep = true;
                for (int dj = -1; dj <= 1 && keep; ++dj) {
                    for (int di = -1; di <= 1 && keep; ++di) {
                        if (!di && !dj) continue;
                        const Candidate& o = cand[static_cast<std::size_t>(j + dj) * w + i + di];
                        if (!o.alive) continue;
                        const double dx = o.x - c.x, dz = o.z - c.z;
                        if (dx * dx + dz * dz < r2 && o.priority > c.priority) keep = false;
                    }
                }
                if (keep) kept.push_back(&c);
            }
        }
        return kept;
    };

    // Trees for the tile plus one cell around it (bushes near the border keep off those too).
    const std::int64_t t0x = ti * kTreeCellsPerTile, t0z = tk * kTreeCellsPerTile;
    const auto trees = candidates(kTreeLayer, kTreeSpacing_m, t0x, t0z, kTreeCellsPerTile, 2);
    const auto keptTrees = thin(trees, kTreeCellsPerTile + 4, 1, kTreeSpacing_m);

    const std::int64_t s0x = ti * kSmallCellsPerTile, s0z = tk * kSmallCellsPerTile;
    const auto small = candidates(kSmallLayer, kSmallSpacing_m, s0x, s0z, kSmallCellsPerTile, 1);
    const auto keptSmall = thin(small, kSmallCellsPerTile + 2, 1, kSmallSpacing_m);

    const double x0 = static_cast<double>(ti) * kTile_m, z0 = static_cast<double>(tk) * kTile_m;
    auto inTile = [&](const Candidate& c) {
        return c.x >= x0 && c.x < x0 + kTile_m && c.z >= z0 && c.z < z0 + kTile_m;
    };
    std::vector<Plant> plants;
    auto emit = [&](const Candidate& c) {
        Plant p;
        p.position_m = glm::dvec3(c.x, world_.height(c.x, c.z), c.z);
        p.kind = c.kind;
        p.scale = c.scale;
        p.rotation_rad = c.rotation;
        plants.push_back(p);
    };
    for (const Candidate* c : keptTrees) {
        if (inTile(*c)) emit(*c);
    }
    const double clear2 = kSmallTreeClearance_m * kSmallTreeClearance_m;
    for (const Candidate* c : keptSmall) {
        if (!inTile(*c)) continue;
        bool clear = true;
        for (const Candidate* t : keptTrees) {
            const double dx = t->x - c->x, dz = t->z - c->z;
            if (dx * dx + dz * dz < clear2) {
                clear = false;
                break;
            }
        }
        if (clear) emit(*c);
    }
    return plants;
}

std::shared_ptr<const std::vector<Plant>> Vegetation::tile(std::int64_t i, std::int64_t k) const {
    const std::uint64_t key = (static_cast<std::uint64_t>(static_cast<std::uint32_t>(i)) << 32) |
                              static_cast<std::uint32_t>(k);
    {
        std::lock_guard<std::mutex> lock(cacheMutex_);
        auto it = cache_.find(key);
        if (it != cache_.end()) return it->second;
    }
    auto plants = std::make_shared<const std::vector<Plant>>(generateTile(i, k));
    std::lock_guard<std::mutex> lock(cacheMutex_);
    // A simple bound on memory: forget everything when the cache grows large (tiles regenerate
    // identically on demand).
    if (cache_.size() > 8192) cache_.clear();
    return cache_.emplace(key, std::move(plants)).first->second;
}

std::vector<Plant> Vegetation::inDisc(double x_m, double z_m, double radius_m) const {
    std::vector<Plant> out;
    const double r2 = radius_m * radius_m;
    for (std::int64_t k = tileIndex(z_m - radius_m); k <= tileIndex(z_m + radius_m); ++k) {
        for (std::int64_t i = tileIndex(x_m - radius_m); i <= tileIndex(x_m + radius_m); ++i) {
            for (const Plant& p : *tile(i, k)) {
                const double dx = p.position_m.x - x_m, dz = p.position_m.z - z_m;
                if (dx * dx + dz * dz <= r2) out.push_back(p);
            }
        }
    }
    return out;
}

// ---- [SECTION] Meshes ------------------------------------------------------------------------

namespace {

struct MeshBuilder {
    WorldMesh m;
    std::uint32_t vertex(const glm::dvec3& p, const glm::dvec3& n, const glm::vec3& c) {
        const glm::dvec3 nn = glm::normalize(n);
        m.positions.insert(m.positions.end(), {float(p.x), float(p.y), float(p.z)});
        m.normals.insert(m.normals.end(), {float(nn.x), float(nn.y), float(nn.z)});
        m.albedo.insert(m.albedo.end(), {c.r, c.g, c.b});
        return static_cast<std::uint32_t>(m.positions.size() / 3 - 1);
    }
    void tri(std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        m.indices.insert(m.indices.end(), {a, b, c});
    }
    // Open-ended frustum of a cone about +Y (a cylinder when r0 == r1; a cone when r1 == 0),
    // smooth side normals, plus a bottom cap when `cap`.
    void frustum(double y0, double y1, double r0, double r1, int segments, glm::vec3 colour,
                 bool cap) {
        const double slant = (r0 - r1) / (y1 - y0);
        std::vector<std::uint32_t> bottom, top;
        for (int s = 0; s <= segments; ++s) {
            const double a = 2.0 * kPi * s / segments;
            const glm::dvec3 d(std::cos(a), 0.0, std::sin(a));
            const glm::dvec3 n(d.x, slant, d.z);
            bottom.push_back(vertex(glm::dvec3(r0 * d.x, y0, r0 * d.z), n, colour));
            top.push_back(vertex(glm::dvec3(r1 * d.x, y1, r1 * d.z), n, colour));
        }
        // The angle grows from +X towards +Z, so (bottom s, top s, bottom s+1) is
        // counter-clockwise seen from outside.
        for (int s = 0; s < segments; ++s) {
            tri(bottom[s], top[s], bottom[s + 1]);
            if (r1 > 0.0) tri(bottom[s + 1], top[s], top[s + 1]);
        }
        if (cap) {
            const std::uint32_t centre = vertex(glm::dvec3(0, y0, 0), glm::dvec3(0, -1, 0), colour);
            std::vector<std::uint32_t> ring;
            for (int s = 0; s <= segments; ++s) {
                const double a = 2.0 * kPi * s / segments;
                ring.push_back(vertex(glm::dvec3(r0 * std::cos(a), y0, r0 * std::sin(a)),
                                      glm::dvec3(0, -1, 0), colour));
            }
            for (int s = 0; s < segments; ++s) tri(centre, ring[s], ring[s + 1]);
        }
    }
    // Ellipsoid (UV sphere) centred at c with radii r, smooth normals.
    void ellipsoid(glm::dvec3 c, glm::dvec3 r, int slices, int stacks, glm::vec3 colour,
                   double bumpiness, std::uint64_t bumpSeed) {
        std::vector<std::uint32_t> idx;
        for (int j = 0; j <= stacks; ++j) {
            const double theta = kPi * j / stacks;
            for (int i = 0; i <= slices; ++i) {
                const double phi = 2.0 * kPi * (i % slices) / slices;
                const glm::dvec3 d(std::sin(theta) * std::cos(phi), std::cos(theta),
                                   std::sin(theta) * std::sin(phi));
                double bump = 1.0;
                if (bumpiness > 0.0 && j > 0 && j < stacks) {
                    const std::uint64_t h = mix64(bumpSeed ^ (std::uint64_t(j) * 131 + i % slices));
                    bump += bumpiness * ((h >> 11) * 0x1.0p-53 - 0.5);
                }
                idx.push_back(vertex(c + d * r * bump, d / r, colour));
            }
        }
        const int w = slices + 1;
        for (int j = 0; j < stacks; ++j) {
            for (int i = 0; i < slices; ++i) {
                const std::uint32_t a = idx[j * w + i], b = idx[j * w + i + 1];
                const std::uint32_t c2 = idx[(j + 1) * w + i], d = idx[(j + 1) * w + i + 1];
                if (j > 0) tri(a, b, c2);
                if (j < stacks - 1) tri(b, d, c2);
            }
        }
    }
};

constexpr glm::vec3 kBark(0.20f, 0.13f, 0.08f);
constexpr glm::vec3 kNeedles(0.04f, 0.11f, 0.05f);
constexpr glm::vec3 kLeaves(0.10f, 0.21f, 0.05f);
constexpr glm::vec3 kBushLeaves(0.12f, 0.19f, 0.06f);
constexpr glm::vec3 kStone(0.34f, 0.32f, 0.29f);

// A proxy's few-sided ellipsoid has its vertices on the full mesh's shape, so its faces cut
// inside it: a 6 x 4 crown covers about 80 % of the solid angle the full (bumpy) crown covers,
// and a capture scene of such crowns saw 12 % too much sky from the ground. The proxies' radii
// are widened (horizontal, vertical) until the area they cover matches the full mesh's within
// 2 %, on average over the directions and looking up from below
// (Vegetation.ProxiesAndSpheresCoverWhatTheMeshCovers measures it).
constexpr glm::dvec2 kBroadleafProxyWiden(1.135, 1.09);
constexpr glm::dvec2 kBushProxyWiden(1.2, 1.1);
constexpr glm::dvec2 kRockProxyWiden(1.155, 1.13);

glm::dvec3 widened(glm::dvec3 radii, glm::dvec2 widen) {
    return {radii.x * widen.x, radii.y * widen.y, radii.z * widen.x};
}

WorldMesh buildMesh(PlantKind kind, bool proxy) {
    MeshBuilder b;
    switch (kind) {
        case PlantKind::Conifer:
            if (proxy) {
                b.frustum(0.0, 2.0, 0.3, 0.3, 3, kBark, false);
                b.frustum(1.5, 12.0, 2.6, 0.0, 8, kNeedles, true);
            } else {
                // The trunk in two bands: its vertices carry the crown's occlusion.
                b.frustum(0.0, 1.25, 0.28, 0.25, 10, kBark, false);
                b.frustum(1.25, 2.5, 0.25, 0.22, 10, kBark, false);
                // Four stacked cones, narrowing upwards.
                const double ys[4] = {1.5, 4.0, 6.3, 8.4};
                const double rs[4] = {2.6, 2.1, 1.6, 1.1};
                for (int i = 0; i < 4; ++i)
                    b.frustum(ys[i], ys[i] + 3.6, rs[i], 0.0, 14, kNeedles, true);
            }
            break;
        case PlantKind::Broadleaf:
            if (proxy) {
                b.frustum(0.0, 3.0, 0.35, 0.35, 3, kBark, false);
                b.ellipsoid({0, 6.0, 0}, widened({3.2, 2.8, 3.2}, kBroadleafProxyWiden), 6, 4,
                            kLeaves, 0.0, 0);
            } else {
                b.frustum(0.0, 1.75, 0.35, 0.3, 10, kBark, false);
                b.frustum(1.75, 3.5, 0.3, 0.25, 10, kBark, false);
                b.ellipsoid({0, 6.0, 0}, {3.2, 2.8, 3.2}, 14, 9, kLeaves, 0.25, 17);
            }
            break;
        case PlantKind::Bush:
            if (proxy) {
                b.ellipsoid({0, 0.6, 0}, widened({1.1, 0.8, 1.1}, kBushProxyWiden), 4, 3,
                            kBushLeaves, 0.0, 0);
            } else {
                b.ellipsoid({0, 0.6, 0}, {1.1, 0.8, 1.1}, 10, 6, kBushLeaves, 0.3, 29);
            }
            break;
        case PlantKind::Rock:
            if (proxy) {
                b.ellipsoid({0, 0.25, 0}, widened({0.9, 0.6, 0.7}, kRockProxyWiden), 5, 3, kStone,
                            0.0, 0);
            } else {
                b.ellipsoid({0, 0.25, 0}, {0.9, 0.6, 0.7}, 10, 6, kStone, 0.35, 43);
            }
            break;
    }
    return b.m;
}

// The full crown's triangles (those with no bark vertex), at scale 1: what a trunk sees of it.
struct CrownTriangles {
    std::vector<glm::dvec3> corners;  // three a triangle
};

const CrownTriangles& crownTriangles(PlantKind kind) {
    static const std::array<CrownTriangles, kPlantKinds> all = [] {
        std::array<CrownTriangles, kPlantKinds> out;
        for (PlantKind k : {PlantKind::Conifer, PlantKind::Broadleaf}) {
            const WorldMesh m = buildMesh(k, false);
            const auto at = [&](std::uint32_t v) {
                return glm::dvec3(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
            };
            const auto bark = [&](std::uint32_t v) {
                return glm::vec3(m.albedo[3 * v], m.albedo[3 * v + 1], m.albedo[3 * v + 2]) == kBark;
            };
            CrownTriangles& c = out[static_cast<int>(k)];
            for (std::size_t t = 0; t + 2 < m.indices.size(); t += 3) {
                const std::uint32_t a = m.indices[t], b = m.indices[t + 1], d = m.indices[t + 2];
                if (bark(a) || bark(b) || bark(d)) continue;
                for (std::uint32_t v : {a, b, d}) c.corners.push_back(at(v));
            }
        }
        return out;
    }();
    return all[static_cast<int>(kind)];
}

// The mesh with its trunk's vertices darkened by the crown (WorldMesh::occlusion; trees only).
WorldMesh withOcclusion(WorldMesh m, PlantKind kind) {
    if (kind != PlantKind::Conifer && kind != PlantKind::Broadleaf) return m;
    m.occlusion.assign(m.vertexCount(), 0.0f);
    for (std::size_t v = 0; v < m.vertexCount(); ++v) {
        if (glm::vec3(m.albedo[3 * v], m.albedo[3 * v + 1], m.albedo[3 * v + 2]) != kBark)
            continue;  // the crown's own leaves keep the ambient
        const glm::dvec3 p(m.positions[3 * v], m.positions[3 * v + 1], m.positions[3 * v + 2]);
        const glm::dvec3 n(m.normals[3 * v], m.normals[3 * v + 1], m.normals[3 * v + 2]);
        m.occlusion[v] = float(1.0 - Vegetation::crownSkyShare(kind, p, n));
    }
    return m;
}

}  // namespace

const WorldMesh& Vegetation::mesh(PlantKind kind) {
    static const std::array<WorldMesh, kPlantKinds> meshes = {
        withOcclusion(buildMesh(PlantKind::Conifer, false), PlantKind::Conifer),
        withOcclusion(buildMesh(PlantKind::Broadleaf, false), PlantKind::Broadleaf),
        buildMesh(PlantKind::Bush, false), buildMesh(PlantKind::Rock, false)};
    return meshes[static_cast<int>(kind)];
}

const WorldMesh& Vegetation::proxyMesh(PlantKind kind) {
    static const std::array<WorldMesh, kPlantKinds> meshes = {
        withOcclusion(buildMesh(PlantKind::Conifer, true), PlantKind::Conifer),
        withOcclusion(buildMesh(PlantKind::Broadleaf, true), PlantKind::Broadleaf),
        buildMesh(PlantKind::Bush, true), buildMesh(PlantKind::Rock, true)};
    return meshes[static_cast<int>(kind)];
}

const std::vector<PlantSphere>& Vegetation::spheres(PlantKind kind) {
    const auto bark = glm::dvec3(kBark), needles = glm::dvec3(kNeedles);
    const auto leaves = glm::dvec3(kLeaves);
    // The conifer's cones (1.5 to 12 m, 2.6 m at the base) as three spheres narrowing upwards;
    // the broadleaf's 3.2 x 2.8 ellipsoid as one sphere; trunks up to where the crown starts.
    // Each set covers, on average over the directions, the area its full mesh covers within 2 %
    // (the bumps widen the full crowns' outline; a conifer's wide lowest tier takes a lowest
    // sphere of 2.5 m), as the proxies do.
    static const std::array<std::vector<PlantSphere>, kPlantKinds> s = {
        std::vector<PlantSphere>{{{0, 3.4, 0}, 2.5, needles},
                                 {{0, 6.4, 0}, 1.6, needles},
                                 {{0, 9.0, 0}, 1.0, needles},
                                 {{0, 0.5, 0}, 0.3, bark},
                                 {{0, 1.2, 0}, 0.3, bark}},
        std::vector<PlantSphere>{{{0, 6.0, 0}, 3.15, leaves},
                                 {{0, 0.6, 0}, 0.35, bark},
                                 {{0, 1.6, 0}, 0.35, bark},
                                 {{0, 2.6, 0}, 0.35, bark}},
        std::vector<PlantSphere>{{{0, 0.6, 0}, 0.97, glm::dvec3(kBushLeaves)}},
        std::vector<PlantSphere>{{{0, 0.25, 0}, 0.72, glm::dvec3(kStone)}}};
    return s[static_cast<int>(kind)];
}

double Vegetation::crownSkyShare(PlantKind kind, const glm::dvec3& point_m,
                                 const glm::dvec3& normal) {
    if (kind != PlantKind::Conifer && kind != PlantKind::Broadleaf) return 1.0;
    const CrownTriangles& crown = crownTriangles(kind);
    // Cosine-weighted directions about the normal, of equal shares: kRings rings of equal
    // projected area, kAzimuths each, the rings' azimuths staggered.
    constexpr int kRings = 6, kAzimuths = 12;
    const glm::dvec3 w = glm::normalize(normal);
    const glm::dvec3 a = std::abs(w.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
    const glm::dvec3 u = glm::normalize(glm::cross(a, w)), v = glm::cross(w, u);
    int open = 0;
    for (int r = 0; r < kRings; ++r) {
        const double rho = std::sqrt((r + 0.5) / kRings), up = std::sqrt(1.0 - rho * rho);
        for (int k = 0; k < kAzimuths; ++k) {
            const double phi = 2.0 * kPi * (k + 0.5 * (r % 2)) / kAzimuths;
            const glm::dvec3 d = rho * std::cos(phi) * u + rho * std::sin(phi) * v + up * w;
            bool blocked = false;
            for (std::size_t t = 0; !blocked && t + 2 < crown.corners.size(); t += 3) {
                glm::dvec2 bary;
                double distance = 0.0;
                blocked = glm::intersectRayTriangle(point_m, d, crown.corners[t],
                                                    crown.corners[t + 1], crown.corners[t + 2],
                                                    bary, distance) &&
                          distance > 1e-6;
            }
            open += blocked ? 0 : 1;
        }
    }
    return double(open) / double(kRings * kAzimuths);
}

bool Vegetation::amongLeaves(PlantKind kind, const glm::dvec3& point_m) {
    if (kind != PlantKind::Conifer && kind != PlantKind::Broadleaf) return false;
    const CrownTriangles& crown = crownTriangles(kind);
    for (int axis = 0; axis < 6; ++axis) {
        // Along the axes, tilted a little so that no ray runs along a seam or through a pole.
        glm::dvec3 d(0.0131, 0.0077, 0.0103);
        d[axis / 2] = axis % 2 ? -1.0 : 1.0;
        d = glm::normalize(d);
        bool met = false;
        for (std::size_t t = 0; !met && t + 2 < crown.corners.size(); t += 3) {
            glm::dvec2 bary;
            double distance = 0.0;
            met = glm::intersectRayTriangle(point_m, d, crown.corners[t], crown.corners[t + 1],
                                            crown.corners[t + 2], bary, distance) &&
                  distance > 0.0;
        }
        if (!met) return false;
    }
    return true;
}

double Vegetation::footprintRadius_m(PlantKind kind) {
    switch (kind) {
        case PlantKind::Conifer:
            return 2.6;
        case PlantKind::Broadleaf:
            return 3.2;
        case PlantKind::Bush:
            return 1.1;
        case PlantKind::Rock:
            return 0.9;
    }
    return 1.0;
}

}  // namespace amb
