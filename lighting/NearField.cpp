// NearField.cpp — the near field's core and its cache (NearField.h).
#include "lighting/NearField.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <glm/geometric.hpp>

#include "world/Conventions.h"
#include "world/Error.h"
#include "world/Sky.h"

namespace amb {

// ---- [SECTION] Cache ---------------------------------------------------------------------------

namespace {
// A cached light term is remade when the light has moved more than 0.5 degrees.
const double kLightMoved = std::cos(0.5 * kPi / 180.0);

// The memory of one entry of each cache, the map's slot included.
constexpr std::size_t kMapSlot = 2 * sizeof(void*);
constexpr std::size_t kGroundEntryBytes = sizeof(std::array<float, 4>) + sizeof(GroundTerm) +
                                          sizeof(std::uint64_t) + kMapSlot;
constexpr std::size_t kNormalEntryBytes = sizeof(std::array<float, 4>) + sizeof(std::uint32_t) +
                                          kMapSlot + sizeof(NormalTransfer) +
                                          sizeof(NormalApply) + sizeof(std::uint64_t);
// A patch mean's entry holds its samples' ground light terms too.
std::size_t normalEntryBytes(const NormalTransfer& t) {
    return kNormalEntryBytes +
           (t.groundParts ? sizeof(std::vector<GroundLightPart>) + 2 * sizeof(void*) +
                                t.groundParts->size() * sizeof(GroundLightPart)
                          : 0);
}
constexpr std::size_t kSampleEntryBytes =
    sizeof(std::array<float, 4>) + sizeof(NormalTransfer) + kMapSlot;
std::size_t objectEntryBytes(const NearFieldTransfer* t) {
    return sizeof(std::array<float, 4>) + sizeof(void*) + sizeof(std::uint64_t) + kMapSlot +
           (t ? sizeof(NearFieldTransfer) : 0);
}

// The use below which the older half of `stamps` lies: entries used before it are dropped. If
// no use is older than the median (one batch asked them all), all of them.
std::uint64_t olderHalf(std::vector<std::uint64_t> stamps) {
    if (stamps.empty()) return 0;
    const auto mid = stamps.begin() + std::ptrdiff_t(stamps.size() / 2);
    std::nth_element(stamps.begin(), mid, stamps.end());
    const std::uint64_t cut = *mid;
    const bool older = std::any_of(stamps.begin(), stamps.end(),
                                   [cut](std::uint64_t u) { return u < cut; });
    return older ? cut : std::numeric_limits<std::uint64_t>::max();
}

// Erases the entries of `map` last used before olderHalf of their uses.
template <class Map, class Used>
void dropOlderHalf(Map& map, Used used) {
    std::vector<std::uint64_t> stamps;
    stamps.reserve(map.size());
    for (auto it = map.begin(); it != map.end(); ++it) stamps.push_back(used(it->second));
    const std::uint64_t cut = olderHalf(std::move(stamps));
    for (auto it = map.begin(); it != map.end();) it = used(it->second) < cut ? map.erase(it) : std::next(it);
}

}  // namespace

std::size_t NearField::KeyHash::operator()(const Key& k) const {
    std::uint32_t b[4];
    std::memcpy(b, k.data(), sizeof b);
    std::uint64_t h = 1469598103934665603ull;
    for (std::uint32_t v : b) h = (h ^ v) * 1099511628211ull;
    // Mix the high bits down: lattice coordinates share their low mantissa bits, and the map
    // takes the low bits of the hash.
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdull;
    h ^= h >> 33;
    return std::size_t(h);
}

NearField::NearField(const NearFieldScene& scene, const NearFieldSettings& settings)
    : scene_(scene), settings_(settings) {}

void NearField::setTimeOfDay(double timeOfDay_h) {
    const DirectionalLight l = scene_.mainLight(timeOfDay_h);
    std::lock_guard<std::mutex> lock(mutex_);
    if (std::isfinite(l.direction.x + l.direction.y + l.direction.z) &&
        std::isfinite(l.irradiance.x + l.irradiance.y + l.irradiance.z)) {
        light_ = l;
        if (glm::dot(epochLight_, l.direction) < kLightMoved) {
            // The ambient follows the light's epochs: cached terms are remade with both.
            const HemisphereAmbient a = scene_.ambient(timeOfDay_h);
            const glm::dvec3 sum = a.sky + a.ground;
            if (std::isfinite(sum.x + sum.y + sum.z)) ambient_ = a;
            ++lightEpoch_, epochLight_ = l.direction;
        }
    }
}

void NearField::setViewer(const glm::dvec3& camera_m) {
    if (!std::isfinite(camera_m.x + camera_m.y + camera_m.z)) return;
    std::lock_guard<std::mutex> lock(mutex_);
    viewer_ = camera_m, viewerKnown_ = true;
}

bool NearField::blendsLattice(const glm::dvec3& p) const {
    // In three dimensions: a flight's ground point, 60 m below the camera, is not the car.
    return !viewerKnown_ || glm::length(p - viewer_) < settings_.latticeRange_m;
}

std::vector<SphereOccluder> NearField::occluders(const glm::dvec3& p) const {
    std::vector<SphereOccluder> out;
    if (!settings_.plants) return out;
    scene_.occludersNear(p, settings_.radius_m, settings_.smallRadius_m, out);
    sunVisibilities(out);
    skyVisibilities(out);
    return out;
}

void NearField::fillShares(ShareCache& cache, std::uint32_t epoch,
                           std::vector<SphereOccluder>& spheres, double SphereOccluder::*share,
                           const std::function<double(const glm::dvec3&, double)>& compute) const {
    if (spheres.empty()) return;
    const auto keyOf = [](const SphereOccluder& o) {
        return Key{float(o.centre_m.x), float(o.centre_m.y), float(o.centre_m.z), float(o.radius_m)};
    };
    std::vector<std::size_t> missing;
    {
        std::lock_guard<std::mutex> lock(cache.mutex);
        if (cache.epoch != epoch || cache.shares.size() >= kShareEntries)
            cache.shares.clear(), cache.epoch = epoch;
        for (std::size_t i = 0; i < spheres.size(); ++i) {
            const auto it = cache.shares.find(keyOf(spheres[i]));
            if (it != cache.shares.end())
                spheres[i].*share = double(it->second);
            else
                missing.push_back(i);
        }
    }
    if (missing.empty()) return;
    // Rounded as the cache keeps it: a sphere's share is then the same whether this point took
    // it or found it taken by another (points are built on several threads, and which comes
    // first must not show in the result).
    for (std::size_t i : missing) {
        const double v = compute(spheres[i].centre_m, spheres[i].radius_m);
        spheres[i].*share = double(float(std::isfinite(v) ? std::clamp(v, 0.0, 1.0) : 1.0));
    }
    std::lock_guard<std::mutex> lock(cache.mutex);
    if (cache.epoch != epoch) return;  // the light moved on while these were taken
    for (std::size_t i : missing) cache.shares.emplace(keyOf(spheres[i]), float(spheres[i].*share));
}

void NearField::skyVisibilities(std::vector<SphereOccluder>& spheres) const {
    if (!settings_.plantSky) return;
    fillShares(skyShares_, 0, spheres, &SphereOccluder::skyVisibility,
               [this](const glm::dvec3& c, double r) { return scene_.sphereSkyVisibility(c, r); });
}

void NearField::sunVisibilities(std::vector<SphereOccluder>& spheres) const {
    if (!settings_.plantShadows) return;
    const glm::dvec3 l = light_.direction;
    fillShares(sunShares_, lightEpoch_, spheres, &SphereOccluder::sunVisibility,
               [this, l](const glm::dvec3& c, double r) { return scene_.sphereLightVisibility(c, r, l); });
}

std::unique_ptr<NearFieldTransfer> NearField::build(const glm::dvec3& point_m, double selfRadius_m,
                                                    const GroundTerm* objectGroundTerm,
                                                    const glm::dvec3* drawnNormal) const {
    // A surface point (asked with its normal) sees its near field from surfaceHeight_m.
    const glm::dvec3 p =
        drawnNormal && selfRadius_m <= 0.0
            ? point_m - glm::dvec3(0.0, kShadingHeight_m - settings_.surfaceHeight_m, 0.0)
            : point_m;
    std::vector<HorizonWedge> horizon;
    if (settings_.terrain && selfRadius_m <= 0.0)
        scene_.terrainNear(p, settings_.terrainRadius_m, horizon);
    if (drawnNormal && drawnNormal->y > 0.0) belowTangentPlaneOut(*drawnNormal, horizon);
    // The ground is shaded by every plant near it, the object's own included.
    std::vector<SphereOccluder> all = occluders(p);
    std::vector<SphereOccluder> others;
    if (selfRadius_m > 0.0) {
        // An object's own spheres sit on its axis, above its base.
        for (const SphereOccluder& o : all)
            if (std::hypot(o.centre_m.x - p.x, o.centre_m.z - p.z) >= selfRadius_m) others.push_back(o);
    }
    const std::vector<SphereOccluder>& caps0 = selfRadius_m > 0.0 ? others : all;
    GroundTerm ground;
    if (settings_.ground)
        ground = objectGroundTerm ? *objectGroundTerm
                 : selfRadius_m > 0.0 && blendsLattice(p)
                     ? objectGround(p)
                     : groundTerm(p, scene_, caps0, all, settings_.groundRadius_m, light_.direction,
                                  drawnNormal);
    std::vector<OccluderCap> caps = nearOccluders(p, caps0, horizon);
    if (caps.empty() && !ground.any) return nullptr;
    auto t = std::make_unique<NearFieldTransfer>(nearFieldTransfer(caps, &ground));
    t->capSun = float(capSunVisibility(caps, light_.direction));
    updateLightTerm(*t, light_.direction, ambient_);
    return t;
}

void NearField::latticeOf(const glm::dvec3& p, Key keys[9], double weights[9],
                          glm::dvec3 points[9]) const {
    const double lift = p.y - scene_.groundHeight(p.x, p.z);
    // Quadratic B-spline weights of the three nearest lattice lines on each axis.
    const auto spline = [](double u, double w[3]) {
        const double f = u - std::round(u);
        w[0] = 0.5 * (0.5 - f) * (0.5 - f), w[1] = 0.75 - f * f, w[2] = 0.5 * (0.5 + f) * (0.5 + f);
        return std::round(u) - 1.0;
    };
    double wx[3], wz[3];
    const double cell = settings_.groundCell_m;
    const double i0 = spline(p.x / cell, wx), k0 = spline(p.z / cell, wz);
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            const double x = (i0 + a) * cell, z = (k0 + b) * cell;
            keys[a * 3 + b] = Key{float(x), -2e30f, float(z), float(lift)};
            weights[a * 3 + b] = wx[a] * wz[b];
            points[a * 3 + b] = glm::dvec3(x, lift, z);  // the lift for now (see latticeTerm)
        }
}

GroundTerm NearField::latticeTerm(const glm::dvec3& at) const {
    const glm::dvec3 q(at.x, scene_.groundHeight(at.x, at.z) + at.y, at.z);
    // No plant stops the rays from a lattice point: one standing at it would take its ground out
    // of the blend for an object that does not see that plant.
    return groundTerm(q, scene_, {}, occluders(q), settings_.groundRadius_m, light_.direction);
}

NormalTransfer NearField::groundSample(double x_m, double z_m) const {
    GroundPoint g;
    if (!scene_.groundAt(x_m, z_m, g)) {
        g.height_m = scene_.groundHeight(x_m, z_m);
        g.normal = glm::dvec3(0.0, 1.0, 0.0);
    }
    if (!std::isfinite(g.height_m) || !std::isfinite(g.normal.x + g.normal.y + g.normal.z)) return {};
    const std::unique_ptr<NearFieldTransfer> full =
        build(glm::dvec3(x_m, g.height_m + kShadingHeight_m, z_m), 0.0, nullptr, &g.normal);
    NormalTransfer nt = normalTransfer(full.get(), g.normal);
    if (full) updateLightTerm(nt, light_.direction, ambient_, lightEpoch_);
    return nt;
}

GroundTerm NearField::objectGround(const glm::dvec3& p) const {
    Key keys[9];
    double weights[9];
    glm::dvec3 points[9];
    latticeOf(p, keys, weights, points);
    if (groundCache_.size() + 9 > std::size_t(settings_.cacheEntries)) evictGround();
    const std::uint64_t now = ++uses_;
    for (int i = 0; i < 9; ++i) {
        if (auto it = groundCache_.find(keys[i]); it != groundCache_.end()) {
            it.value().used = now;
            continue;
        }
        groundCache_.emplace(keys[i], CachedGround{latticeTerm(points[i]), now});
        groundBytes_ += kGroundEntryBytes;
    }
    // Looked up only once all nine are in: an insertion may move the map's entries.
    const GroundTerm* terms[9];
    for (int i = 0; i < 9; ++i) terms[i] = &groundCache_.find(keys[i])->second.term;
    return blendGroundTerms(terms, weights, 9);
}

void NearField::buildObjects(std::size_t count, const Key* keys, const glm::dvec3* points_m,
                             double selfRadius_m) const {
    // The points not in the cache, each once.
    std::vector<std::size_t> missing;
    {
        tsl::hopscotch_map<Key, char, KeyHash> seen;
        for (std::size_t i = 0; i < count; ++i) {
            const glm::dvec3& p = points_m[i];
            if (!std::isfinite(p.x + p.y + p.z) || !std::isfinite(double(keys[i][0]) + keys[i][2]))
                continue;
            if (cache_.count(keys[i]) || !seen.emplace(keys[i], 0).second) continue;
            missing.push_back(i);
        }
    }
    if (missing.size() < 2) return;  // applyLocked builds a lone point itself
    const auto b0 = std::chrono::steady_clock::now();
    // An object's ground blends lattice terms: the missing ones first, on every thread.
    std::vector<GroundTerm> grounds(missing.size());
    std::vector<char> lattice(missing.size(), 0);
    for (std::size_t m = 0; m < missing.size(); ++m)
        lattice[m] = settings_.ground && selfRadius_m > 0.0 && blendsLattice(points_m[missing[m]]);
    if (std::find(lattice.begin(), lattice.end(), 1) != lattice.end()) {
        std::vector<Key> latticeKeys;
        std::vector<glm::dvec3> latticeAt;
        tsl::hopscotch_map<Key, char, KeyHash> seen;
        for (std::size_t m = 0; m < missing.size(); ++m) {
            if (!lattice[m]) continue;
            const std::size_t i = missing[m];
            Key k[9];
            double w[9];
            glm::dvec3 at[9];
            latticeOf(points_m[i], k, w, at);
            for (int j = 0; j < 9; ++j)
                if (!groundCache_.count(k[j]) && seen.emplace(k[j], 0).second)
                    latticeKeys.push_back(k[j]), latticeAt.push_back(at[j]);
        }
        if (groundCache_.size() + latticeKeys.size() + 9 > std::size_t(settings_.cacheEntries))
            evictGround();
        std::vector<GroundTerm> terms(latticeKeys.size());
        tbb::this_task_arena::isolate([&] {
            tbb::parallel_for(std::size_t(0), terms.size(),
                              [&](std::size_t j) { terms[j] = latticeTerm(latticeAt[j]); });
        });
        const std::uint64_t now = ++uses_;
        for (std::size_t j = 0; j < terms.size(); ++j) {
            groundCache_.emplace(latticeKeys[j], CachedGround{terms[j], now});
            groundBytes_ += kGroundEntryBytes;
        }
        for (std::size_t m = 0; m < missing.size(); ++m)
            if (lattice[m]) grounds[m] = objectGround(points_m[missing[m]]);
    }
    // Then the transfers, which read only the scene, the light and those terms.
    std::vector<std::unique_ptr<NearFieldTransfer>> built(missing.size());
    tbb::this_task_arena::isolate([&] {
        tbb::parallel_for(std::size_t(0), missing.size(), [&](std::size_t m) {
            built[m] = build(points_m[missing[m]], selfRadius_m,
                             lattice[m] ? &grounds[m] : nullptr);
        });
    });
    if (cache_.size() + missing.size() > std::size_t(settings_.cacheEntries)) evictObjects();
    const std::uint64_t now = ++uses_;
    for (std::size_t m = 0; m < missing.size(); ++m) {
        bytes_ += objectEntryBytes(built[m].get());
        cache_.emplace(keys[missing[m]], Cached{std::move(built[m]), now});
    }
    builds_ += missing.size();
    buildSeconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - b0).count();
}

ShRgb NearField::apply(const ShRgb& far, const glm::dvec3& point_m, double selfRadius_m) const {
    const Key key{float(point_m.x), float(point_m.y), float(point_m.z), float(selfRadius_m)};
    return applyKeyed(far, key, [&] { return point_m; }, selfRadius_m);
}

ShRgb NearField::applyAbove(const ShRgb& far, double x_m, double z_m, double height_m,
                            double selfRadius_m) const {
    // A key no explicit point has (a height of -1e30): one NearField uses one lift.
    const Key key{float(x_m), -1e30f, float(z_m), float(selfRadius_m)};
    return applyKeyed(
        far, key, [&] { return glm::dvec3(x_m, scene_.groundHeight(x_m, z_m) + height_m, z_m); },
        selfRadius_m);
}

ShRgb NearField::applyKeyed(const ShRgb& far, const Key& key,
                            const std::function<glm::dvec3()>& point, double selfRadius_m) const {
    if (!settings_.enabled) return far;
    const auto t0 = std::chrono::steady_clock::now();
    std::lock_guard<std::mutex> lock(mutex_);
    const ShRgb out = applyLocked(far, key, point, selfRadius_m);
    ++points_;
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return out;
}

void NearField::applyMany(std::size_t count, ShRgb* inOut, const glm::dvec3* points_m) const {
    if (!settings_.enabled || count == 0) return;
    const auto t0 = std::chrono::steady_clock::now();
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<Key> keys(count);
    for (std::size_t i = 0; i < count; ++i) {
        const glm::dvec3& p = points_m[i];
        keys[i] = Key{float(p.x), float(p.y), float(p.z), 0.0f};
    }
    buildObjects(count, keys.data(), points_m, 0.0);
    for (std::size_t i = 0; i < count; ++i)
        inOut[i] = applyLocked(inOut[i], keys[i], [&] { return points_m[i]; }, 0.0);
    points_ += count;
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void NearField::applyAboveMany(std::size_t count, ShRgb* inOut, const double* x_m,
                               const double* z_m, double height_m, double selfRadius_m) const {
    if (!settings_.enabled || count == 0) return;
    const auto t0 = std::chrono::steady_clock::now();
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<Key> keys(count);
    std::vector<glm::dvec3> points(count);
    for (std::size_t i = 0; i < count; ++i) {
        const double x = x_m[i], z = z_m[i];
        keys[i] = Key{float(x), -1e30f, float(z), float(selfRadius_m)};
        // The ground's height only for points not yet cached (as applyAbove).
        points[i] = cache_.count(keys[i])
                        ? glm::dvec3(x, 0.0, z)
                        : glm::dvec3(x, scene_.groundHeight(x, z) + height_m, z);
    }
    buildObjects(count, keys.data(), points.data(), selfRadius_m);
    for (std::size_t i = 0; i < count; ++i)
        inOut[i] = applyLocked(inOut[i], keys[i], [&] { return points[i]; }, selfRadius_m);
    points_ += count;
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::uint32_t NearField::addNormalEntry(const Key& key, const NormalTransfer& transfer,
                                       const NormalApply& apply) const {
    const std::uint32_t index = std::uint32_t(normalTransfers_.size());
    normalTransfers_.push_back(transfer);
    normalApplies_.push_back(apply);
    normalUsed_.push_back(uses_);
    normalBytes_ += normalEntryBytes(transfer);
    normalCache_.emplace(key, index);
    return index;
}

void NearField::irradianceMany(std::size_t count, const ShRgb* far, const glm::dvec3* points_m,
                               const glm::dvec3* normals, glm::vec3* out, const double* weights,
                               const double* patch_m) const {
    if (count == 0) return;
    const auto t0 = std::chrono::steady_clock::now();
    static const NormalApply none;
    std::lock_guard<std::mutex> lock(mutex_);
    ++uses_;
    // A terrain corner's patch size when it takes the patch mean, else 0 (see Patch mean).
    const auto patchOf = [&](std::size_t i) {
        return settings_.patchMean && patch_m && patch_m[i] > 0.0 && patch_m[i] < 1e6
                   ? patch_m[i]
                   : 0.0;
    };
    const auto keyOf = [&](std::size_t i) {
        const glm::dvec3& p = points_m[i];
        return Key{float(p.x), float(p.y), float(p.z), -1.0f - float(patchOf(i))};
    };
    // The sequence this batch follows: the one that began with the same point, else the least
    // recently used.
    const auto sequenceOf = [&]() {
        Sequence* seq = &sequences_[0];
        const Key first = keyOf(0);
        for (Sequence& q : sequences_) {
            if (!q.keys.empty() && q.first == first) return &q;
            if (q.used < seq->used) seq = &q;
        }
        return seq;
    };
    constexpr std::uint32_t kNone = ~0u;      // a point not asked of the cache (disabled, not finite)
    constexpr std::uint32_t kMissing = ~1u;   // a point with no entry yet
    constexpr std::size_t kLookAhead = 16;    // points dropped from the batch since last time
    // This batch's keys and indices go into buffers kept from the last batch (no allocation).
    std::vector<Key>& keys = batchKeys_;
    std::vector<std::uint32_t>& at = batchAt_;
    std::vector<std::size_t>& missing = batchMissing_;
    Sequence* seq = nullptr;
    // Every point's entry, found on its sequence or in the map, or kMissing; the points without
    // an entry in `missing` (each key once).
    const auto find = [&]() {
        seq = sequenceOf();
        keys.clear(), at.assign(count, kNone), missing.clear();
        keys.reserve(count);
        std::size_t cursor = 0;
        for (std::size_t i = 0; i < count; ++i) {
            const glm::dvec3& p = points_m[i];
            const glm::dvec3& n = normals[i];
            if (!settings_.enabled || !std::isfinite(p.x + p.y + p.z) ||
                !std::isfinite(n.x + n.y + n.z) || (weights && !(weights[i] > 0.0))) {
                keys.push_back(Key{});
                continue;
            }
            const Key key = keyOf(i);
            keys.push_back(key);
            bool found = false;
            for (std::size_t d = 0; d < kLookAhead && cursor + d < seq->keys.size(); ++d) {
                if (seq->keys[cursor + d] == key) {
                    at[i] = seq->index[cursor + d];
                    cursor += d + 1;
                    found = true;
                    break;
                }
            }
            if (found) {
                // A point on a sequence last asked under this light has its light term already
                // (its entry counts as used when the cache is full: see evictNormals).
                if (seq->lightEpoch == lightEpoch_) continue;
            } else {
                auto it = normalCache_.find(key);
                if (it == normalCache_.end()) {
                    at[i] = kMissing;
                    missing.push_back(i);
                    continue;
                }
                at[i] = it->second;
                normalUsed_[at[i]] = uses_;
            }
            NormalApply& na = normalApplies_[at[i]];
            if (na.any && na.lightEpoch != lightEpoch_) {
                NormalTransfer& nt = normalTransfers_[at[i]];
                updateLightTerm(nt, light_.direction, ambient_, lightEpoch_);
                na.light = nt.light, na.sky = nt.sky, na.lightEpoch = nt.lightEpoch;
            }
        }
    };
    find();
    if (!missing.empty()) {
        // Room first: evicting moves the kept entries (and clears the sequences), so the batch
        // is found again. A batch larger than the cache's room stays whole until the next.
        if (normalCache_.size() + missing.size() > std::size_t(settings_.cacheEntries)) {
            evictNormals();
            find();
        }
        const auto b0 = std::chrono::steady_clock::now();
        // A point asked twice in one batch is built once.
        std::vector<std::size_t>& unique = batchUnique_;
        unique.clear();
        {
            tsl::hopscotch_map<Key, std::uint32_t, KeyHash> first;
            for (std::size_t i : missing)
                if (first.emplace(keys[i], std::uint32_t(unique.size())).second) unique.push_back(i);
        }
        // A patch mean's samples (see Patch mean): its offsets a side and their tent weights.
        const int m = std::max(1, settings_.patchSamples);
        std::vector<double> offset(static_cast<std::size_t>(m)), tent(static_cast<std::size_t>(m));
        double tentSum = 0.0;
        for (int j = 0; j < m; ++j) {
            offset[std::size_t(j)] = -1.0 + 2.0 * (j + 1) / (m + 1);  // times the patch size
            tentSum += tent[std::size_t(j)] = 1.0 - std::abs(offset[std::size_t(j)]);
        }
        for (double& w : tent) w /= tentSum;
        const auto sampleAt = [&](std::size_t i, int j) {
            const double p = patchOf(i);
            return glm::dvec2(points_m[i].x + offset[std::size_t(j % m)] * p,
                              points_m[i].z + offset[std::size_t(j / m)] * p);
        };
        const auto sampleKey = [](const glm::dvec2& q) {
            return Key{float(q.x), float(q.y), 0.0f, 0.0f};
        };
        // The samples not cached yet, each once.
        std::vector<glm::dvec2> toSample;
        {
            if (sampleCache_.size() > std::size_t(settings_.cacheEntries)) sampleCache_.clear();
            tsl::hopscotch_map<Key, std::uint32_t, KeyHash> queued;
            for (std::size_t i : unique) {
                if (patchOf(i) <= 0.0) continue;
                for (int j = 0; j < m * m; ++j) {
                    const glm::dvec2 q = sampleAt(i, j);
                    const Key k = sampleKey(q);
                    if (sampleCache_.find(k) == sampleCache_.end() &&
                        queued.emplace(k, std::uint32_t(toSample.size())).second)
                        toSample.push_back(q);
                }
            }
        }
        // The builds only read the scene and the light: on every thread (a corner's is ~0.2 ms,
        // and a frame that refines patches asks hundreds). A patch mean is put together after.
        std::vector<NormalTransfer> transfers(unique.size()), samples(toSample.size());
        std::vector<NormalApply> applies(unique.size());
        std::size_t pointBuilds = 0;
        for (std::size_t i : unique) pointBuilds += patchOf(i) > 0.0 ? 0 : 1;
        const auto buildOne = [&](std::size_t u) {
            if (u >= unique.size()) {
                const glm::dvec2& q = toSample[u - unique.size()];
                samples[u - unique.size()] = groundSample(q.x, q.y);
                return;
            }
            const std::size_t i = unique[u];
            if (patchOf(i) > 0.0) return;
            // Nothing near: the entry has no transfer (any = false) and answers the far field.
            const std::unique_ptr<NearFieldTransfer> full =
                build(points_m[i], 0.0, nullptr, &normals[i]);
            NormalTransfer& nt = transfers[u];
            nt = normalTransfer(full.get(), normals[i]);
            if (full) updateLightTerm(nt, light_.direction, ambient_, lightEpoch_);
            applies[u] = normalApply(nt, normals[i]);
        };
        const std::size_t tasks = unique.size() + toSample.size();
        if (tasks == 1) {
            buildOne(0);
        } else {
            tbb::this_task_arena::isolate([&] {
                tbb::parallel_for(std::size_t(0), tasks, buildOne);
            });
        }
        for (std::size_t k = 0; k < toSample.size(); ++k)
            sampleCache_.emplace(sampleKey(toSample[k]), std::move(samples[k]));
        std::vector<const NormalTransfer*> meanOf(std::size_t(m * m));
        std::vector<double> meanWeight(std::size_t(m * m));
        for (std::size_t u = 0; u < unique.size(); ++u) {
            const std::size_t i = unique[u];
            if (patchOf(i) <= 0.0) continue;
            for (int j = 0; j < m * m; ++j) {
                auto it = sampleCache_.find(sampleKey(sampleAt(i, j)));
                NormalTransfer& sample = it.value();
                if (sample.any && sample.lightEpoch != lightEpoch_)
                    updateLightTerm(sample, light_.direction, ambient_, lightEpoch_);
                meanOf[std::size_t(j)] = &sample;
                meanWeight[std::size_t(j)] = tent[std::size_t(j % m)] * tent[std::size_t(j / m)];
            }
            transfers[u] = meanNormalTransfer(meanOf.data(), meanWeight.data(), meanOf.size());
            transfers[u].lightEpoch = lightEpoch_;
            applies[u] = normalApply(transfers[u], normals[i]);
        }
        for (std::size_t u = 0; u < unique.size(); ++u)
            addNormalEntry(keys[unique[u]], transfers[u], applies[u]);
        for (std::size_t i : missing) at[i] = normalCache_.find(keys[i])->second;
        builds_ += pointBuilds + toSample.size();
        buildSeconds_ +=
            std::chrono::duration<double>(std::chrono::steady_clock::now() - b0).count();
    }
    // The sums only read: on two threads for a frame's corners (a sum is ~30 ns).
    const auto answer = [&](std::size_t i) {
        const glm::vec3 n(normals[i]);
        if (at[i] == kNone) {
            out[i] = applyNormalTransfer(none, far[i], n, light_);
            return;
        }
        out[i] = applyNormalTransfer(normalApplies_[at[i]], far[i], n, light_);
        if (weights && weights[i] < 1.0)
            out[i] = glm::mix(applyNormalTransfer(none, far[i], n, light_), out[i],
                              float(weights[i]));
    };
    constexpr std::size_t kGrain = 2048;
    if (count <= kGrain) {
        for (std::size_t i = 0; i < count; ++i) answer(i);
    } else {
        tbb::this_task_arena::isolate([&] {
            tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kGrain),
                              [&](const tbb::blocked_range<std::size_t>& r) {
                                  for (std::size_t i = r.begin(); i != r.end(); ++i) answer(i);
                              });
        });
    }
    // The points asked of the cache become the batch's sequence.
    std::vector<std::uint32_t>& indices = batchIndex_;
    indices.clear();
    std::size_t kept = 0;
    for (std::size_t i = 0; i < count; ++i)
        if (at[i] != kNone) keys[kept++] = keys[i], indices.push_back(at[i]);
    keys.resize(kept);
    seq->keys.swap(keys), seq->index.swap(indices);
    seq->first = keyOf(0);
    seq->used = uses_;  // this batch's reading of the use clock
    seq->lightEpoch = lightEpoch_;
    points_ += count;
    seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

ShRgb NearField::applyLocked(const ShRgb& far, const Key& key,
                             const std::function<glm::dvec3()>& point, double selfRadius_m) const {
    if (!std::isfinite(double(key[0]) + double(key[2]))) return far;
    const NearFieldTransfer* t = nullptr;
    const std::uint64_t now = ++uses_;
    auto it = cache_.find(key);
    if (it == cache_.end()) {
        const glm::dvec3 p = point();
        if (!std::isfinite(p.x + p.y + p.z)) return far;
        if (cache_.size() >= std::size_t(settings_.cacheEntries)) evictObjects();
        const auto b0 = std::chrono::steady_clock::now();
        std::unique_ptr<NearFieldTransfer> built = build(p, selfRadius_m);
        bytes_ += objectEntryBytes(built.get());
        t = cache_.emplace(key, Cached{std::move(built), now}).first->second.transfer.get();
        ++builds_;
        buildSeconds_ +=
            std::chrono::duration<double>(std::chrono::steady_clock::now() - b0).count();
    } else {
        it.value().used = now;
        t = it->second.transfer.get();
        if (t && glm::dot(t->lightDirection, light_.direction) < kLightMoved)
            updateLightTerm(*it.value().transfer, light_.direction, ambient_);
    }
    if (!t) return far;
    const ShRgb near = applyTransfer(*t, far, light_);
    // Never NaN: a far field that overflows keeps its own value.
    for (const auto& c : near.c)
        if (!std::isfinite(c.x + c.y + c.z)) return far;
    return near;
}

void NearField::evictObjects() const {
    dropOlderHalf(cache_, [](const Cached& c) { return c.used; });
    bytes_ = 0;
    for (auto it = cache_.begin(); it != cache_.end(); ++it)
        bytes_ += objectEntryBytes(it->second.transfer.get());
}

void NearField::evictGround() const {
    dropOlderHalf(groundCache_, [](const CachedGround& c) { return c.used; });
    groundBytes_ = groundCache_.size() * kGroundEntryBytes;
}

void NearField::evictNormals() const {
    // The last batches' entries were used when those batches were asked (irradianceMany marks
    // only the entries it finds off its sequences).
    for (const Sequence& q : sequences_)
        for (std::uint32_t i : q.index)
            if (i < normalUsed_.size()) normalUsed_[i] = std::max(normalUsed_[i], q.used);
    // The kept entries move down in their vectors; the map follows.
    const std::uint64_t cut = olderHalf(normalUsed_);
    constexpr std::uint32_t kGone = ~0u;
    std::vector<std::uint32_t> moved(normalUsed_.size(), kGone);
    std::uint32_t kept = 0;
    for (std::size_t i = 0; i < normalUsed_.size(); ++i) {
        if (normalUsed_[i] < cut) continue;
        normalTransfers_[kept] = normalTransfers_[i];
        normalApplies_[kept] = normalApplies_[i];
        normalUsed_[kept] = normalUsed_[i];
        moved[i] = kept++;
    }
    normalTransfers_.resize(kept), normalApplies_.resize(kept), normalUsed_.resize(kept);
    for (auto it = normalCache_.begin(); it != normalCache_.end();) {
        const std::uint32_t to = moved[it->second];
        if (to == kGone) {
            it = normalCache_.erase(it);
        } else {
            it.value() = to;
            ++it;
        }
    }
    normalBytes_ = 0;
    for (const NormalTransfer& t : normalTransfers_) normalBytes_ += normalEntryBytes(t);
    // The sequences' indices are stale (see irradianceMany).
    for (Sequence& q : sequences_) q.keys.clear(), q.index.clear();
}

std::size_t NearField::cachedPoints() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return cache_.size() + normalCache_.size() + groundCache_.size() + sampleCache_.size();
}

std::size_t NearField::cacheBytes() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return bytes_ + normalBytes_ + groundBytes_ + sampleCache_.size() * kSampleEntryBytes;
}

double NearField::seconds() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return seconds_;
}

std::size_t NearField::points() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return points_;
}

std::size_t NearField::builds() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return builds_;
}

double NearField::buildSeconds() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return buildSeconds_;
}

void NearField::resetCounters() {
    std::lock_guard<std::mutex> lock(mutex_);
    seconds_ = buildSeconds_ = 0.0;
    points_ = builds_ = 0;
}

}  // namespace amb
