// TerrainPatch.cpp — patch sampling, quadtree LOD selection, crack-free stitching, packing, and
// the coarse terrain proxy for probe capture.
//
// [SECTION] Lattice helpers
// [SECTION] Albedo: the material blend with noise
// [SECTION] Patch sampling (cached per key)
// [SECTION] LOD selection
// [SECTION] Stitching: a vertex's rendered value comes from the coarsest patch containing it;
//           so does a corner's value (corner stitching)
// [SECTION] Packing into plain arrays
// [SECTION] Drawn surface: heights of the packed triangles at any point
// [SECTION] Terrain proxy for probe capture
#include "world/TerrainPatch.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <tbb/parallel_for.h>
#include <glm/common.hpp>
#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "world/Conventions.h"
#include "world/Error.h"
#include "world/World.h"

namespace amb {

// ---- [SECTION] Lattice helpers ---------------------------------------------------------------

namespace {

constexpr int kQ = TerrainPatch::kPatchQuads;
constexpr int kV = TerrainPatch::kVerticesPerSide;

inline std::int64_t floorDiv(std::int64_t a, std::int64_t b) {
    std::int64_t q = a / b;
    if ((a % b != 0) && ((a < 0) != (b < 0))) --q;
    return q;
}

inline double latticeToWorld(std::int64_t v) {
    return static_cast<double>(v) * TerrainPatch::kFinestSpacing_m;
}

// Lattice coordinate of a patch's vertex column a (or row).
inline std::int64_t vertexLattice(std::int64_t patchIndex, int level, int a) {
    return (patchIndex * kQ + a) * TerrainPatch::latticeStep(level);
}

}  // namespace

std::size_t PatchKeyHash::operator()(const PatchKey& key) const {
    std::uint64_t h = static_cast<std::uint64_t>(key.i) * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<std::uint64_t>(key.k) + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2);
    h ^= static_cast<std::uint64_t>(key.level) * 0xD1B54A32D192ED03ull;
    return static_cast<std::size_t>(h ^ (h >> 29));
}

double TerrainPatch::spacing_m(int level) {
    return kFinestSpacing_m * double(latticeStep(level));
}
double TerrainPatch::size_m(int level) {
    return spacing_m(level) * kPatchQuads;
}

// ---- [SECTION] Albedo ------------------------------------------------------------------------

namespace {

double smoothstep(double e0, double e1, double x) {
    const double t = std::clamp((x - e0) / (e1 - e0), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

}  // namespace

TerrainAlbedo::TerrainAlbedo(const World& world)
    : world_(world),
      vast_(Heightfield::makeOctave(world.settings().seed, 0xA1BDu, 400.0)),
      broad_(Heightfield::makeOctave(world.settings().seed, 0xA1BEu, 90.0)),
      mid_(Heightfield::makeOctave(world.settings().seed, 0xA1BFu, 23.0)),
      fine_(Heightfield::makeOctave(world.settings().seed, 0xA1C0u, 7.0)) {}

glm::vec3 TerrainAlbedo::at(double x_m, double z_m, double height_m, double road,
                            const glm::dvec3& normal, double spacing_m) const {
    const auto fade = [&](double wavelength_m) {
        return smoothstep(2.0 * spacing_m, 4.0 * spacing_m, wavelength_m);
    };
    const double n0 = Heightfield::octaveNoise(vast_, x_m, z_m) * fade(400.0);
    const double n1 = Heightfield::octaveNoise(broad_, x_m, z_m) * fade(90.0);
    const double n2 = Heightfield::octaveNoise(mid_, x_m, z_m) * fade(23.0);
    const double n3 = Heightfield::octaveNoise(fine_, x_m, z_m) * fade(7.0);
    const double water_m = world_.settings().waterLevel_m;
    // (1) The material blend with ragged edges: the slope where rock shows moves by +-0.06, the
    // snow line by +-30 m on high ground, the beach by +-0.8 m; land stays land.
    const double slope = std::clamp(1.0 - normal.y + 0.06 * n2, 0.0, 1.0);
    const double horizontal = std::sqrt(std::max(0.0, 1.0 - normal.y * normal.y));
    const double ny = 1.0 - slope, nh = std::sqrt(std::max(0.0, 1.0 - ny * ny));
    const glm::dvec3 tilted = horizontal > 1e-9
                                  ? glm::dvec3(normal.x * nh / horizontal, ny, normal.z * nh / horizontal)
                                  : glm::dvec3(0.0, 1.0, 0.0);
    double h = height_m + 30.0 * n1 * smoothstep(300.0, 500.0, height_m) +
               0.8 * n2 * (1.0 - smoothstep(3.0, 8.0, height_m - water_m));
    if (height_m >= water_m) h = std::max(h, water_m + 0.01);
    glm::dvec3 a(world_.classify(x_m, z_m, h, road, tilted).albedo);
    if (height_m < water_m) return glm::vec3(a);
    // (2) Stone: light and dark strata across the height, a warm tint in places, grain.
    const double strata = 0.5 + 0.5 * std::sin(height_m / 7.0 + 2.5 * n1 + 1.5 * n2);
    glm::dvec3 rock = glm::mix(glm::dvec3(0.34, 0.32, 0.29), glm::dvec3(0.17, 0.16, 0.155), strata);
    rock = glm::mix(rock, glm::dvec3(0.36, 0.27, 0.19), 0.5 * smoothstep(0.0, 0.8, n1));
    rock *= 1.0 + 0.15 * n3;
    const double paved = smoothstep(0.35, 0.65, road);
    const double snowy = smoothstep(0.45, 0.75, luminance(a));
    const double rocky = smoothstep(World::kRockSlope - 0.06, World::kRockSlope + 0.02, slope) *
                         (1.0 - snowy) * (1.0 - paved);
    a += rocky * (rock - glm::dvec3(World::materialAlbedo(Material::Rock)));
    // (3) Scree on gentle high ground, in patches.
    const double scree = 0.6 * smoothstep(0.1, 0.6, n2) * smoothstep(380.0, 520.0, height_m) *
                         (1.0 - snowy) * (1.0 - paved) * (1.0 - rocky);
    a = glm::mix(a, rock, scree);
    // (4) Meadows turn lusher or drier in broad patches (not on rock, snow, sand or road), and
    // everything but the road varies in brightness.
    const double meadow = (1.0 - rocky) * (1.0 - snowy) * (1.0 - paved) * (1.0 - scree / 0.6) *
                          smoothstep(3.0, 6.0, height_m - water_m);
    const double lush = std::clamp(0.9 * n0 + 0.5 * n1, -1.0, 1.0) * meadow;
    a *= lush > 0.0 ? glm::mix(glm::dvec3(1.0), glm::dvec3(0.62, 1.0, 0.7), lush)
                    : glm::mix(glm::dvec3(1.0), glm::dvec3(1.2, 1.02, 0.75), -lush);
    a *= 1.0 + (0.16 * n2 + 0.08 * n3 + 0.08 * n1 + 0.1 * n0) * (1.0 - 0.8 * paved);
    return glm::vec3(glm::clamp(a, 0.0, 1.0));
}

// ---- [SECTION] Patch sampling ----------------------------------------------------------------

namespace {

// TerrainPatch::skyDetail's V at grid point c of a height grid `h` (kB a row, spacing s) with
// normal n: the 8 directions along the grid's axes and diagonals, `reach` steps each.
double skyVisibility(const std::vector<double>& h, int kB, int c, int reach, double s,
                     const glm::dvec3& n) {
    static constexpr int kDx[8] = {1, 1, 0, -1, -1, -1, 0, 1};
    static constexpr int kDz[8] = {0, 1, 1, 1, 0, -1, -1, -1};
    double hidden = 0.0;
    for (int d = 0; d < 8; ++d) {
        const double step = (kDx[d] != 0 && kDz[d] != 0) ? s * std::sqrt(2.0) : s;
        const glm::dvec2 dir = glm::normalize(glm::dvec2(kDx[d], kDz[d]));
        // The tangent plane's rise along the direction; the horizon above it.
        const double plane = -(n.x * dir.x + n.z * dir.y) / n.y;
        double best = 0.0;  // tan of the elevation above the plane's
        for (int k = 1; k <= reach; ++k) {
            const double dist = k * step;
            if (dist > TerrainPatch::kSkyDetailRadius_m + 1e-9) break;
            const double rise = (h[std::size_t(c + k * (kDz[d] * kB + kDx[d]))] - h[std::size_t(c)]) / dist;
            best = std::max(best, rise - plane);
        }
        // sin^2 of the elevation above the plane: the share of a cosine-weighted wedge below it
        // (the plane's tilt is small next to the walls a gully shows).
        hidden += best * best / (1.0 + best * best);
    }
    return 1.0 - hidden / 8.0;
}

// Whether a patch carries the sky detail: fine enough, and by default only where a gully may
// cut within its reach (its border's half-diagonal from its centre).
bool carriesSkyDetail(const World& world, const PatchKey& key, TerrainPatch::SkyDetail mode) {
    if (TerrainPatch::spacing_m(key.level) > TerrainPatch::kSkyDetailMaxSpacing_m) return false;
    if (mode == TerrainPatch::SkyDetail::Everywhere) return true;
    const double half = 0.5 * TerrainPatch::size_m(key.level);
    const double reach = std::sqrt(2.0) * (half + TerrainPatch::kSkyDetailRadius_m);
    return world.heightfield().mayHaveGullies(TerrainPatch::originX_m(key) + half,
                                              TerrainPatch::originZ_m(key) + half, reach);
}

}  // namespace

TerrainPatch TerrainPatch::generate(const World& world, const PatchKey& key, SkyDetail mode) {
    TerrainPatch p;
    p.key = key;
    const double s = spacing_m(key.level);
    // Heights on the patch grid plus a border: one vertex for the normals, or the sky detail's
    // reach where the patch carries it.
    const bool detail = carriesSkyDetail(world, key, mode);
    const int border = detail ? int(std::ceil(kSkyDetailRadius_m / s - 1e-9)) : 1;
    const int kB = kV + 2 * border;
    std::vector<double> h(std::size_t(kB * kB)), road(std::size_t(kB * kB));
    for (int b = -border; b <= kQ + border; ++b) {
        for (int a = -border; a <= kQ + border; ++a) {
            const double x = latticeToWorld(vertexLattice(key.i, key.level, a));
            const double z = latticeToWorld(vertexLattice(key.k, key.level, b));
            const int idx = (b + border) * kB + (a + border);
            h[std::size_t(idx)] = world.heightAndRoad(x, z, &road[std::size_t(idx)]);
        }
    }
    p.heights_m.resize(kV * kV);
    p.normals.resize(3 * kV * kV);
    p.albedo.resize(3 * kV * kV);
    std::vector<double> visibility(detail ? kV * kV : 0);
    const TerrainAlbedo material(world);
    for (int b = 0; b <= kQ; ++b) {
        for (int a = 0; a <= kQ; ++a) {
            const int c = (b + border) * kB + (a + border);
            const double dhdx = (h[c + 1] - h[c - 1]) / (2.0 * s);
            const double dhdz = (h[c + kB] - h[c - kB]) / (2.0 * s);
            const glm::dvec3 n = glm::normalize(glm::dvec3(-dhdx, 1.0, -dhdz));
            const double x = latticeToWorld(vertexLattice(key.i, key.level, a));
            const double z = latticeToWorld(vertexLattice(key.k, key.level, b));
            const glm::vec3 albedo = material.at(x, z, h[c], road[c], n, s);
            const int v = b * kV + a;
            p.heights_m[v] = h[c];
            for (int j = 0; j < 3; ++j) {
                p.normals[3 * v + j] = static_cast<float>(n[j]);
                p.albedo[3 * v + j] = albedo[j];
            }
            if (detail) visibility[std::size_t(v)] = skyVisibility(h, kB, c, border, s, n);
        }
    }
    if (detail) {
        const double c00 = visibility[0], c10 = visibility[kQ];
        const double c01 = visibility[std::size_t(kQ * kV)], c11 = visibility[std::size_t(kQ * kV + kQ)];
        p.skyDetail.resize(2 * kV * kV);
        for (int b = 0; b <= kQ; ++b) {
            const double v = double(b) / kQ;
            for (int a = 0; a <= kQ; ++a) {
                const double u = double(a) / kQ;
                const double corners = (1 - v) * ((1 - u) * c00 + u * c10) + v * ((1 - u) * c01 + u * c11);
                const std::size_t i = std::size_t(b * kV + a);
                p.skyDetail[2 * i] = float(visibility[i]);
                p.skyDetail[2 * i + 1] = float(corners);
            }
        }
    }
    for (int c = 0; c < 4; ++c) {
        const double x = latticeToWorld(vertexLattice(key.i, key.level, (c & 1) ? kQ : 0));
        const double z = latticeToWorld(vertexLattice(key.k, key.level, (c & 2) ? kQ : 0));
        p.cornerNormals[c] = world.normal(x, z);
    }
    return p;
}

// ---- [SECTION] LOD selection -----------------------------------------------------------------

TerrainPatchCache::TerrainPatchCache(const World& world, TerrainLodSettings settings)
    : world_(world), settings_(settings) {
    AMB_CHECK(settings_.coarsestLevel >= 0 && settings_.coarsestLevel < 24);
}

std::vector<PatchKey> TerrainPatchCache::selectPatches(const glm::dvec3& camera_m) const {
    const double altitude_m = std::max(0.0, camera_m.y - world_.height(camera_m.x, camera_m.z));
    const int top = settings_.coarsestLevel;
    const double rootSize = TerrainPatch::size_m(top);
    const double r = settings_.viewRadius_m;
    const auto i0 = static_cast<std::int64_t>(std::floor((camera_m.x - r) / rootSize));
    const auto i1 = static_cast<std::int64_t>(std::floor((camera_m.x + r) / rootSize));
    const auto k0 = static_cast<std::int64_t>(std::floor((camera_m.z - r) / rootSize));
    const auto k1 = static_cast<std::int64_t>(std::floor((camera_m.z + r) / rootSize));

    std::vector<PatchKey> leaves;
    std::vector<PatchKey> stack;
    for (std::int64_t k = k1; k >= k0; --k) {
        for (std::int64_t i = i1; i >= i0; --i) stack.push_back({top, i, k});
    }
    while (!stack.empty()) {
        const PatchKey key = stack.back();
        stack.pop_back();
        const double size = TerrainPatch::size_m(key.level);
        const double x0 = TerrainPatch::originX_m(key), z0 = TerrainPatch::originZ_m(key);
        // Horizontal distance from the camera to the patch square (0 inside it).
        const double dx = std::max({x0 - camera_m.x, 0.0, camera_m.x - (x0 + size)});
        const double dz = std::max({z0 - camera_m.z, 0.0, camera_m.z - (z0 + size)});
        if (key.level == top && std::sqrt(dx * dx + dz * dz) > r) continue;
        const double distance = std::sqrt(dx * dx + dz * dz + altitude_m * altitude_m);
        if (key.level > 0 && distance < settings_.splitFactor * size) {
            // Children pushed in reverse so they pop in (x0 z0), (x1 z0), (x0 z1), (x1 z1) order.
            for (int c = 3; c >= 0; --c) {
                stack.push_back({key.level - 1, 2 * key.i + (c & 1), 2 * key.k + (c >> 1)});
            }
        } else {
            leaves.push_back(key);
        }
    }
    return leaves;
}

std::shared_ptr<const TerrainPatch> TerrainPatchCache::patch(const PatchKey& key) {
    auto it = cache_.find(key);
    if (it == cache_.end()) {
        auto p = std::make_shared<const TerrainPatch>(TerrainPatch::generate(world_, key));
        ++generated_;
        it = cache_.emplace(key, Entry{std::move(p), frame_}).first;
    }
    it->second.lastUse = frame_;
    return it->second.patch;
}

// ---- [SECTION] Stitching ---------------------------------------------------------------------

namespace {

struct VertexValue {
    double height_m;
    glm::vec3 normal;
    glm::vec3 albedo;
    glm::vec2 skyDetail{1.0f};  // (V, Vc): TerrainPatch::skyDetail; (1, 1) where it has none
};

glm::vec2 skyDetailOf(const TerrainPatch& p, int idx) {
    return p.skyDetail.empty() ? glm::vec2(1.0f)
                               : glm::vec2(p.skyDetail[2 * std::size_t(idx)], p.skyDetail[2 * std::size_t(idx) + 1]);
}

struct LatticeHash {
    std::size_t operator()(const std::pair<std::int64_t, std::int64_t>& v) const {
        return PatchKeyHash()(PatchKey{0, v.first, v.second});
    }
};

// Rendered values of lattice points for one set of leaves. The coarsest leaf D containing a point
// P decides: on D's vertex lattice, P takes its native sample; otherwise P lies inside one of D's
// edges and takes the linear interpolation of the rendered values of the two D vertices around it
// (those may in turn sit on an even coarser edge: the recursion ends at the coarsest level).
// Every patch that renders P asks the same question, so shared edges coincide exactly.
class Stitcher {
  public:
    Stitcher(const std::unordered_map<PatchKey, const TerrainPatch*, PatchKeyHash>& leaves,
             int topLevel)
        : leaves_(leaves), top_(topLevel) {}

    VertexValue rendered(std::int64_t vx, std::int64_t vz) {
        const auto key = std::make_pair(vx, vz);
        if (auto it = memo_.find(key); it != memo_.end()) return it->second;
        const TerrainPatch* d = coarsestContaining(vx, vz);
        AMB_CHECK(d != nullptr);
        const std::int64_t step = TerrainPatch::latticeStep(d->key.level);
        const bool onX = vx % step == 0, onZ = vz % step == 0;
        VertexValue v;
        if (onX && onZ) {
            const int a = static_cast<int>(vx / step - d->key.i * kQ);
            const int b = static_cast<int>(vz / step - d->key.k * kQ);
            const int idx = b * kV + a;
            v.height_m = d->heights_m[idx];
            v.normal =
                glm::vec3(d->normals[3 * idx], d->normals[3 * idx + 1], d->normals[3 * idx + 2]);
            v.albedo =
                glm::vec3(d->albedo[3 * idx], d->albedo[3 * idx + 1], d->albedo[3 * idx + 2]);
            v.skyDetail = skyDetailOf(*d, idx);
        } else {
            AMB_CHECK(onX || onZ);  // a vertex of a finer patch lies on D's boundary
            VertexValue a, b;
            double t;
            if (!onX) {
                const std::int64_t x0 = floorDiv(vx, step) * step;
                t = double(vx - x0) / double(step);
                a = rendered(x0, vz);
                b = rendered(x0 + step, vz);
            } else {
                const std::int64_t z0 = floorDiv(vz, step) * step;
                t = double(vz - z0) / double(step);
                a = rendered(vx, z0);
                b = rendered(vx, z0 + step);
            }
            v.height_m = a.height_m + t * (b.height_m - a.height_m);
            v.normal = glm::normalize(a.normal + float(t) * (b.normal - a.normal));
            v.albedo = a.albedo + float(t) * (b.albedo - a.albedo);
            v.skyDetail = a.skyDetail + float(t) * (b.skyDetail - a.skyDetail);
        }
        memo_.emplace(key, v);
        return v;
    }

    // Index in `corners` of the leaf corner at lattice point (vx, vz), whose normal is `normal`;
    // appended on first use, after the corners it reads. The coarsest leaf D containing it
    // decides, as for heights: a corner of D is evaluated; a point inside one of D's edges
    // reads that edge's two ends (which may in turn lie inside an even coarser edge).
    std::uint32_t corner(std::int64_t vx, std::int64_t vz, const glm::dvec3& normal,
                         std::vector<TerrainCorner>& corners) {
        const auto key = std::make_pair(vx, vz);
        if (auto it = cornerMemo_.find(key); it != cornerMemo_.end()) return it->second;
        const TerrainPatch* d = coarsestContaining(vx, vz);
        AMB_CHECK(d != nullptr);
        const std::int64_t n = std::int64_t(kQ) * TerrainPatch::latticeStep(d->key.level);
        const std::int64_t x0 = d->key.i * n, z0 = d->key.k * n;
        const bool onX = vx == x0 || vx == x0 + n, onZ = vz == z0 || vz == z0 + n;
        AMB_CHECK(onX || onZ);  // a leaf's corner lies on D's boundary
        TerrainCorner c;
        c.position_m =
            glm::dvec3(latticeToWorld(vx), rendered(vx, vz).height_m, latticeToWorld(vz));
        c.normal = normal;
        if (!(onX && onZ)) {
            // The ends of D's edge through the point, with their own normals.
            const std::int64_t ax = onX ? vx : x0, az = onX ? z0 : vz;
            const std::int64_t bx = onX ? vx : x0 + n, bz = onX ? z0 + n : vz;
            const auto endNormal = [&](std::int64_t ex, std::int64_t ez) {
                return d->cornerNormals[(ex == x0 ? 0 : 1) + (ez == z0 ? 0 : 2)];
            };
            c.from = {corner(ax, az, endNormal(ax, az), corners),
                      corner(bx, bz, endNormal(bx, bz), corners)};
            c.t = float(double(onX ? vz - z0 : vx - x0) / double(n));
        }
        const auto index = static_cast<std::uint32_t>(corners.size());
        if (onX && onZ) c.from = {index, index}, c.patch_m = latticeToWorld(n);
        corners.push_back(c);
        cornerMemo_.emplace(key, index);
        return index;
    }

  private:
    const TerrainPatch* coarsestContaining(std::int64_t vx, std::int64_t vz) const {
        for (int level = top_; level >= 0; --level) {
            const std::int64_t n = std::int64_t(kQ) * TerrainPatch::latticeStep(level);
            const std::int64_t ix = floorDiv(vx, n), iz = floorDiv(vz, n);
            // A point on a patch boundary belongs to the patches on both sides.
            const std::int64_t xs[2] = {ix, ix - 1}, zs[2] = {iz, iz - 1};
            const int nx = (vx == ix * n) ? 2 : 1, nz = (vz == iz * n) ? 2 : 1;
            for (int a = 0; a < nx; ++a) {
                for (int b = 0; b < nz; ++b) {
                    auto it = leaves_.find(PatchKey{level, xs[a], zs[b]});
                    if (it != leaves_.end()) return it->second;
                }
            }
        }
        return nullptr;
    }

    const std::unordered_map<PatchKey, const TerrainPatch*, PatchKeyHash>& leaves_;
    int top_;
    std::unordered_map<std::pair<std::int64_t, std::int64_t>, VertexValue, LatticeHash> memo_;
    std::unordered_map<std::pair<std::int64_t, std::int64_t>, std::uint32_t, LatticeHash>
        cornerMemo_;
};

}  // namespace

std::vector<std::uint32_t> cornersToEvaluate(const TerrainMesh& mesh,
                                             const std::vector<std::size_t>& patches) {
    std::vector<char> needed(mesh.corners.size(), 0);
    std::vector<std::uint32_t> stack;
    for (std::size_t p : patches) {
        const auto& index = mesh.patches[p].cornerIndex;
        stack.insert(stack.end(), index.begin(), index.end());
    }
    while (!stack.empty()) {
        const std::uint32_t c = stack.back();
        stack.pop_back();
        if (needed[c]) continue;
        needed[c] = 1;
        const TerrainCorner& corner = mesh.corners[c];
        if (!corner.evaluated()) stack.insert(stack.end(), corner.from.begin(), corner.from.end());
    }
    std::vector<std::uint32_t> out;
    for (std::size_t c = 0; c < needed.size(); ++c) {
        if (needed[c] && mesh.corners[c].evaluated()) out.push_back(static_cast<std::uint32_t>(c));
    }
    return out;
}

void stitchCornerValues(const std::vector<TerrainCorner>& corners, glm::vec3* values) {
    for (std::size_t c = 0; c < corners.size(); ++c) {
        const TerrainCorner& corner = corners[c];
        if (corner.evaluated()) continue;
        values[c] = (1.0f - corner.t) * values[corner.from[0]] + corner.t * values[corner.from[1]];
    }
}

// ---- [SECTION] Packing -----------------------------------------------------------------------

TerrainMesh TerrainPatchCache::build(const std::vector<PatchKey>& leaves,
                                     const glm::dvec3& origin_m) {
    ++frame_;
    // Generate the missing patches in parallel; they depend on their key only.
    std::vector<PatchKey> missing;
    for (const PatchKey& key : leaves) {
        if (!cache_.count(key)) missing.push_back(key);
    }
    std::vector<std::shared_ptr<const TerrainPatch>> fresh(missing.size());
    tbb::parallel_for(std::size_t(0), missing.size(), [&](std::size_t n) {
        fresh[n] = std::make_shared<const TerrainPatch>(TerrainPatch::generate(world_, missing[n]));
    });
    for (std::size_t n = 0; n < missing.size(); ++n) {
        cache_[missing[n]] = Entry{std::move(fresh[n]), frame_};
        ++generated_;
    }

    std::unordered_map<PatchKey, const TerrainPatch*, PatchKeyHash> leafMap;
    std::vector<std::shared_ptr<const TerrainPatch>> held;
    int top = 0;
    for (const PatchKey& key : leaves) {
        held.push_back(patch(key));
        leafMap[key] = held.back().get();
        top = std::max(top, key.level);
    }
    Stitcher stitcher(leafMap, top);

    TerrainMesh out;
    out.origin_m = origin_m;
    WorldMesh& m = out.mesh;
    m.positions.reserve(leaves.size() * kV * kV * 3);
    m.normals.reserve(leaves.size() * kV * kV * 3);
    m.albedo.reserve(leaves.size() * kV * kV * 3);
    m.indices.reserve(leaves.size() * kQ * kQ * 6);
    for (std::size_t n = 0; n < leaves.size(); ++n) {
        const TerrainPatch& p = *held[n];
        const PatchKey& key = p.key;
        TerrainPatchDraw draw;
        draw.key = key;
        draw.firstVertex = static_cast<std::uint32_t>(m.vertexCount());
        draw.firstIndex = static_cast<std::uint32_t>(m.indices.size());
        for (int b = 0; b <= kQ; ++b) {
            for (int a = 0; a <= kQ; ++a) {
                const std::int64_t vx = vertexLattice(key.i, key.level, a);
                const std::int64_t vz = vertexLattice(key.k, key.level, b);
                const int idx = b * kV + a;
                VertexValue v;
                if (a == 0 || b == 0 || a == kQ || b == kQ) {
                    v = stitcher.rendered(vx, vz);
                } else {
                    v.height_m = p.heights_m[idx];
                    v.normal = glm::vec3(p.normals[3 * idx], p.normals[3 * idx + 1],
                                         p.normals[3 * idx + 2]);
                    v.albedo =
                        glm::vec3(p.albedo[3 * idx], p.albedo[3 * idx + 1], p.albedo[3 * idx + 2]);
                    v.skyDetail = skyDetailOf(p, idx);
                }
                const glm::dvec3 world(latticeToWorld(vx), v.height_m, latticeToWorld(vz));
                const glm::dvec3 rel = world - origin_m;
                m.positions.insert(m.positions.end(), {float(rel.x), float(rel.y), float(rel.z)});
                m.normals.insert(m.normals.end(), {v.normal.x, v.normal.y, v.normal.z});
                m.albedo.insert(m.albedo.end(), {v.albedo.x, v.albedo.y, v.albedo.z});
                m.skyDetail.insert(m.skyDetail.end(), {v.skyDetail.x, v.skyDetail.y});
                if ((a == 0 || a == kQ) && (b == 0 || b == kQ)) {
                    const int c = (a == kQ ? 1 : 0) + (b == kQ ? 2 : 0);
                    draw.corners_m[c] = world;
                    draw.cornerNormals[c] = p.cornerNormals[c];
                }
            }
        }
        for (int c = 0; c < 4; ++c) {
            draw.cornerIndex[c] = stitcher.corner(vertexLattice(key.i, key.level, (c & 1) ? kQ : 0),
                                                  vertexLattice(key.k, key.level, (c & 2) ? kQ : 0),
                                                  p.cornerNormals[c], out.corners);
        }
        // Two triangles per quad, counter-clockwise seen from +Y.
        const std::uint32_t base = draw.firstVertex;
        for (int b = 0; b < kQ; ++b) {
            for (int a = 0; a < kQ; ++a) {
                const std::uint32_t v00 = base + b * kV + a, v10 = v00 + 1;
                const std::uint32_t v01 = v00 + kV, v11 = v01 + 1;
                m.indices.insert(m.indices.end(), {v00, v01, v10, v10, v01, v11});
            }
        }
        draw.vertexCount = static_cast<std::uint32_t>(m.vertexCount()) - draw.firstVertex;
        draw.indexCount = static_cast<std::uint32_t>(m.indices.size()) - draw.firstIndex;
        out.patches.push_back(draw);
    }

    // Forget the least recently used patches beyond the capacity (never this frame's).
    if (cache_.size() > settings_.cacheCapacity) {
        std::vector<std::pair<std::uint64_t, PatchKey>> old;
        for (const auto& [key, e] : cache_) {
            if (e.lastUse < frame_) old.emplace_back(e.lastUse, key);
        }
        std::sort(old.begin(), old.end(),
                  [](const auto& x, const auto& y) { return x.first < y.first; });
        for (std::size_t n = 0; n < old.size() && cache_.size() > settings_.cacheCapacity; ++n) {
            cache_.erase(old[n].second);
        }
    }
    return out;
}

// ---- [SECTION] Drawn surface -----------------------------------------------------------------

TerrainSurface::TerrainSurface(const TerrainMesh& mesh) : mesh_(&mesh) {
    minLevel_ = std::numeric_limits<int>::max();
    for (std::size_t p = 0; p < mesh.patches.size(); ++p) {
        index_[mesh.patches[p].key] = p;
        minLevel_ = std::min(minLevel_, mesh.patches[p].key.level);
        maxLevel_ = std::max(maxLevel_, mesh.patches[p].key.level);
    }
}

std::array<double, 4> quadTriangleWeights(double fu, double fw) {
    if (fu + fw <= 1.0) return {1.0 - fu - fw, fu, fw, 0.0};
    return {0.0, 1.0 - fw, 1.0 - fu, fu + fw - 1.0};
}

// Inside patch `patch` (no check): the quad's triangle holding (x, z), as build() packs them:
// (v00, v01, v10) below the diagonal from v10 to v01, (v10, v01, v11) above it.
double TerrainSurface::heightIn(std::size_t patch, double x_m, double z_m) const {
    const TerrainPatchDraw& p = mesh_->patches[patch];
    const double s = TerrainPatch::spacing_m(p.key.level);
    const double u = (x_m - TerrainPatch::originX_m(p.key)) / s;
    const double w = (z_m - TerrainPatch::originZ_m(p.key)) / s;
    const int a = std::clamp(int(std::floor(u)), 0, kQ - 1);
    const int b = std::clamp(int(std::floor(w)), 0, kQ - 1);
    const double fu = u - a, fw = w - b;
    const auto y = [&](int da, int db) {
        return double(mesh_->mesh.positions[3 * (p.firstVertex + (b + db) * kV + a + da) + 1]) +
               mesh_->origin_m.y;
    };
    const std::array<double, 4> k = quadTriangleWeights(fu, fw);
    return k[0] * y(0, 0) + k[1] * y(1, 0) + k[2] * y(0, 1) + k[3] * y(1, 1);
}

double TerrainSurface::heightAt(double x_m, double z_m) const {
    if (!mesh_ || index_.empty()) return std::numeric_limits<double>::quiet_NaN();
    const auto inside = [&](const PatchKey& key) {
        const double size = TerrainPatch::size_m(key.level);
        const double x0 = TerrainPatch::originX_m(key), z0 = TerrainPatch::originZ_m(key);
        return x_m >= x0 && x_m <= x0 + size && z_m >= z0 && z_m <= z0 + size;
    };
    if (last_ < mesh_->patches.size() && inside(mesh_->patches[last_].key))
        return heightIn(last_, x_m, z_m);
    for (int level = minLevel_; level <= maxLevel_; ++level) {
        const double size = TerrainPatch::size_m(level);
        const PatchKey key{level, std::int64_t(std::floor(x_m / size)),
                           std::int64_t(std::floor(z_m / size))};
        if (auto it = index_.find(key); it != index_.end()) {
            last_ = it->second;
            return heightIn(last_, x_m, z_m);
        }
    }
    return std::numeric_limits<double>::quiet_NaN();
}

double TerrainSurface::baseUnder(double x_m, double z_m, double radius_m) const {
    double base = heightAt(x_m, z_m);
    if (!std::isfinite(base)) return base;
    const double r = radius_m;
    for (const auto& [dx, dz] : {std::pair{r, 0.0}, {-r, 0.0}, {0.0, r}, {0.0, -r}}) {
        const double h = heightAt(x_m + dx, z_m + dz);
        if (std::isfinite(h)) base = std::min(base, h);
    }
    return base;
}

// ---- [SECTION] Terrain proxy -----------------------------------------------------------------

WorldMesh makeTerrainProxy(const World& world, const glm::dvec3& centre_m, double radius_m,
                           int stepsPerSide, double innerSpacing_m) {
    AMB_CHECK(stepsPerSide >= 1 && radius_m > 0.0 && innerSpacing_m > 0.0);
    const int K = stepsPerSide;
    // Offsets d_k = s (q^k - 1) / (q - 1) with d_K = radius: find the ratio q by bisection
    // (q = 1 means uniform spacing; a larger inner spacing than radius/K is clamped to uniform).
    double q = 1.0;
    if (innerSpacing_m * K < radius_m) {
        double lo = 1.0, hi = 4.0;
        for (int it = 0; it < 100; ++it) {
            const double mid = 0.5 * (lo + hi);
            const double d = innerSpacing_m * (std::pow(mid, K) - 1.0) / (mid - 1.0);
            (d < radius_m ? lo : hi) = mid;
        }
        q = 0.5 * (lo + hi);
    }
    std::vector<double> offsets(2 * K + 1);
    for (int k = 0; k <= K; ++k) {
        const double d =
            (q == 1.0) ? radius_m * k / K : innerSpacing_m * (std::pow(q, k) - 1.0) / (q - 1.0);
        offsets[K + k] = d;
        offsets[K - k] = -d;
    }
    offsets[2 * K] = radius_m;
    offsets[0] = -radius_m;

    const int n = 2 * K + 1;
    std::vector<double> h(n * n), road(n * n);
    for (int b = 0; b < n; ++b) {
        for (int a = 0; a < n; ++a) {
            h[b * n + a] = world.heightAndRoad(centre_m.x + offsets[a], centre_m.z + offsets[b],
                                               &road[b * n + a]);
        }
    }
    WorldMesh m;
    const TerrainAlbedo material(world);
    for (int b = 0; b < n; ++b) {
        for (int a = 0; a < n; ++a) {
            // Differences over the (non-uniform) neighbours; one-sided at the rim.
            const int a0 = std::max(a - 1, 0), a1 = std::min(a + 1, n - 1);
            const int b0 = std::max(b - 1, 0), b1 = std::min(b + 1, n - 1);
            const double dhdx = (h[b * n + a1] - h[b * n + a0]) / (offsets[a1] - offsets[a0]);
            const double dhdz = (h[b1 * n + a] - h[b0 * n + a]) / (offsets[b1] - offsets[b0]);
            const glm::dvec3 nn = glm::normalize(glm::dvec3(-dhdx, 1.0, -dhdz));
            const double x = centre_m.x + offsets[a], z = centre_m.z + offsets[b];
            // The proxy's spacing here: the larger of its two neighbour gaps.
            const double spacing = std::max(offsets[a1] - offsets[a0], offsets[b1] - offsets[b0]) / 2.0;
            const glm::vec3 albedo = material.at(x, z, h[b * n + a], road[b * n + a], nn, spacing);
            m.positions.insert(
                m.positions.end(),
                {float(offsets[a]), float(h[b * n + a] - centre_m.y), float(offsets[b])});
            m.normals.insert(m.normals.end(), {float(nn.x), float(nn.y), float(nn.z)});
            m.albedo.insert(m.albedo.end(), {albedo.r, albedo.g, albedo.b});
        }
    }
    for (int b = 0; b + 1 < n; ++b) {
        for (int a = 0; a + 1 < n; ++a) {
            const std::uint32_t v00 = b * n + a, v10 = v00 + 1, v01 = v00 + n, v11 = v01 + 1;
            m.indices.insert(m.indices.end(), {v00, v01, v10, v10, v01, v11});
        }
    }
    return m;
}

}  // namespace amb
