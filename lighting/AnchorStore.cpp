// AnchorStore.cpp — sparse anchor store on OpenVDB, blending, four-quadrant interpolation, .vdb
// files (see AnchorStore.h).
//
// [SECTION] Lifetime
// [SECTION] Storage       Impl: one int32 grid per level, anchor pool with a free list
// [SECTION] Lattice
// [SECTION] Insert, remove, advance (blending, presence, expiry, pruning)
// [SECTION] Interpolation (hierarchical bicubic Hermite, AnchorField.h; cache rebuilt on change)
// [SECTION] Statistics
// [SECTION] Files (.vdb)
#include "lighting/AnchorStore.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <mutex>
#include <optional>
#include <sstream>
#include <tuple>

#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/Prune.h>
#include <openvdb/tree/ValueAccessor.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lighting/AnchorField.h"
#include "lighting/AnchorStoreFile.h"
#include "world/Error.h"
#include "world/TextFile.h"

namespace amb {

namespace {

constexpr std::int32_t kNoAnchor = -1;
constexpr std::int64_t kCoordLimit = 2147483647LL;
constexpr const char* kFormat = "ambience-anchor-store-v2";

// In memory, the per-level index grids use smaller nodes than the standard Int32Grid
// (internal nodes 16^3 and 8^3 instead of 32^3 and 16^3, leaves 4^3 instead of 8^3): the
// standard tree's first internal node alone holds a 32^3 child table (~260 kB), which would
// dominate the memory of a store of a few thousand anchors on a plane. Files hold standard
// Int32Grids (save/load convert), so standard OpenVDB tools read them.
using IndexTree = openvdb::tree::Tree4<std::int32_t, 4, 3, 2>::Type;
using IndexGrid = openvdb::Grid<IndexTree>;

bool finiteSh(const ShRgb& sh, float limit) {
    for (const glm::vec3& c : sh.c) {
        for (int ch = 0; ch < 3; ++ch) {
            if (!std::isfinite(c[ch]) || std::fabs(c[ch]) > limit) return false;
        }
    }
    return true;
}

double clamp01(double v) {
    return v < 0.0 ? 0.0 : (v > 1.0 ? 1.0 : v);
}

}  // namespace

// ---- Lifetime -----------------------------------------------------------------------------------

double anchorLifetime_s(const AnchorStoreSettings& settings, double sunSpeed_radPerHour,
                        double timeRate_hPerS) {
    // Angular speed of the sun in radians per simulated second.
    const double speed = std::fabs(sunSpeed_radPerHour * timeRate_hPerS);
    double lifetime = settings.maxLifetime_s;
    if (std::isfinite(speed) && speed > 0.0) lifetime = settings.allowedSunAngle_rad / speed;
    return std::clamp(lifetime, settings.minLifetime_s, settings.maxLifetime_s);
}

// ---- Storage ------------------------------------------------------------------------------------

struct AnchorStore::Impl {
    AnchorStoreSettings settings;
    int levels = 1;
    std::array<double, kMaxAnchorLevels> spacing{};      // s_L
    std::array<std::int64_t, kMaxAnchorLevels> scale{};  // fine units per level-L unit: 3^(F-L)
    double fineSpacing = 1.0;
    std::vector<IndexGrid::Ptr> grids;  // per level: (i, 0, k) -> pool index
    std::vector<Anchor> pool;
    std::vector<std::uint8_t> alive;
    std::vector<std::int32_t> freeList;
    std::size_t count = 0;
    double now = 0.0;
    ShRgb fallback;
    AnchorStoreStatistics counters;
    // The interpolated field (AnchorField.h), rebuilt by the first lookup after a change that
    // moves it (values, presences, relight factors, removals, the fallback). A new anchor enters
    // at presence 0 and a refresh starts from the value shown, so neither moves it.
    mutable AnchorField field;
    // Its bilinear twin for points that do not move (settings.bilinearFixedPoints with smooth
    // cells; otherwise `field` serves them).
    mutable AnchorField fixedField;
    bool separateFixedField() const {
        return settings.smoothInterpolation && settings.bilinearFixedPoints;
    }
    // Coarsest level whose cells must be rebuilt (levels() or more: none). Stores happen while
    // no lookup runs, so a plain read-modify-write is enough.
    mutable std::atomic<int> fieldStaleFrom{0};
    mutable std::mutex fieldMutex;

    explicit Impl(const AnchorStoreSettings& s) : settings(s) {
        openvdb::initialize();
        AMB_CHECK(s.levels >= 1 && s.levels <= kMaxAnchorLevels);
        AMB_CHECK(std::isfinite(s.coarsestSpacing_m) && s.coarsestSpacing_m > 0.0);
        AMB_CHECK(s.searchCells >= 1 && s.reachCells >= 1 && s.coarseReachCells >= 1);
        AMB_CHECK(s.finerWeight >= 0.0 && s.finerWeight <= 1.0);
        levels = s.levels;
        std::int64_t sc = 1;
        for (int L = levels - 1; L >= 0; --L) {
            scale[L] = sc;
            sc *= 3;
        }
        for (int L = 0; L < levels; ++L)
            spacing[L] = s.coarsestSpacing_m / double(scale[0] / scale[L]);
        fineSpacing = spacing[levels - 1];
        for (int L = 0; L < levels; ++L) {
            auto grid = IndexGrid::create(kNoAnchor);
            grid->setName("anchor_index_L" + std::to_string(L));
            grid->setTransform(openvdb::math::Transform::createLinearTransform(spacing[L]));
            grid->setGridClass(openvdb::GRID_UNKNOWN);
            grids.push_back(grid);
        }
    }

    LatticeKey canonical(LatticeKey key) const {
        while (key.level > 0 && key.i % 3 == 0 && key.k % 3 == 0) {
            key.i /= 3;
            key.k /= 3;
            --key.level;
        }
        return key;
    }
    bool validKey(const LatticeKey& key) const {
        if (key.level < 0 || key.level >= levels) return false;
        const std::int64_t fi = std::int64_t(key.i) * scale[key.level];
        const std::int64_t fk = std::int64_t(key.k) * scale[key.level];
        return fi >= -kCoordLimit && fi <= kCoordLimit && fk >= -kCoordLimit && fk <= kCoordLimit;
    }
    std::int32_t indexOf(const LatticeKey& canonicalKey) const {
        return grids[canonicalKey.level]->tree().getValue(
            openvdb::Coord(canonicalKey.i, 0, canonicalKey.k));
    }
    double x(const LatticeKey& key) const {
        return double(std::int64_t(key.i) * scale[key.level]) * fineSpacing;
    }
    double z(const LatticeKey& key) const {
        return double(std::int64_t(key.k) * scale[key.level]) * fineSpacing;
    }

    std::int32_t allocate(const Anchor& anchor) {
        std::int32_t index;
        if (!freeList.empty()) {
            index = freeList.back();
            freeList.pop_back();
            pool[index] = anchor;
            alive[index] = 1;
        } else {
            index = std::int32_t(pool.size());
            pool.push_back(anchor);
            alive.push_back(1);
        }
        ++count;
        return index;
    }
    void release(std::int32_t index) {
        const LatticeKey key = pool[index].key;
        grids[key.level]->tree().setValueOff(openvdb::Coord(key.i, 0, key.k), kNoAnchor);
        alive[index] = 0;
        freeList.push_back(index);
        --count;
    }

    // Presence from the fade state: rising towards 1 unless expired, then falling towards 0.
    static float presenceAt(const Anchor& a, double now, double blend) {
        if (blend <= 0.0) return a.expired ? 0.0f : 1.0f;
        const double change = (now - a.presenceChange_s) / blend;
        return float(clamp01(a.expired ? a.presenceFrom - change : a.presenceFrom + change));
    }
    void setFadeDirection(Anchor& a, bool expired) {
        a.presenceFrom = a.presence;
        a.presenceChange_s = now;
        a.expired = expired;
    }

    // The field moves from `level` on (an anchor of that level, or everything for level 0).
    void touchField(int level = 0) {
        if (level < fieldStaleFrom.load(std::memory_order_relaxed))
            fieldStaleFrom.store(level, std::memory_order_release);
    }
    void ensureField() const;
    void describe(double x, double z, const AnchorField::Hit& hit,
                  InterpolationDetail& detail) const;
    ShRgb interpolate(double x, double z, InterpolationDetail* detail) const;
};

AnchorStore::AnchorStore(const AnchorStoreSettings& settings)
    : impl_(std::make_unique<Impl>(settings)) {}
AnchorStore::~AnchorStore() = default;
AnchorStore::AnchorStore(AnchorStore&&) noexcept = default;
AnchorStore& AnchorStore::operator=(AnchorStore&&) noexcept = default;

const AnchorStoreSettings& AnchorStore::settings() const {
    return impl_->settings;
}

void AnchorStore::retune(const AnchorStoreSettings& settings) {
    AMB_CHECK(settings.searchCells >= 1 && settings.reachCells >= 1 &&
              settings.coarseReachCells >= 1);
    AMB_CHECK(settings.finerWeight >= 0.0 && settings.finerWeight <= 1.0);
    AnchorStoreSettings& s = impl_->settings;
    const double coarsest_m = s.coarsestSpacing_m;
    const int levels = s.levels;
    s = settings;
    s.coarsestSpacing_m = coarsest_m;
    s.levels = levels;
    impl_->touchField();
}
int AnchorStore::levels() const {
    return impl_->levels;
}
double AnchorStore::spacing_m(int level) const {
    AMB_CHECK(level >= 0 && level < impl_->levels);
    return impl_->spacing[level];
}

// ---- Lattice ------------------------------------------------------------------------------------

LatticeKey AnchorStore::keyNear(double x_m, double z_m, int level) const {
    AMB_CHECK(level >= 0 && level < impl_->levels);
    AMB_CHECK(std::isfinite(x_m) && std::isfinite(z_m));
    const double s = impl_->spacing[level];
    const double i = std::floor(x_m / s + 0.5), k = std::floor(z_m / s + 0.5);
    const double limit = double(kCoordLimit / impl_->scale[level]);
    AMB_CHECK(std::fabs(i) <= limit && std::fabs(k) <= limit);
    return impl_->canonical({level, std::int32_t(i), std::int32_t(k)});
}

LatticeKey AnchorStore::canonical(const LatticeKey& key) const {
    return impl_->canonical(key);
}
double AnchorStore::keyX_m(const LatticeKey& key) const {
    return impl_->x(key);
}
double AnchorStore::keyZ_m(const LatticeKey& key) const {
    return impl_->z(key);
}
std::int64_t AnchorStore::fineI(const LatticeKey& key) const {
    return std::int64_t(key.i) * impl_->scale[key.level];
}
std::int64_t AnchorStore::fineK(const LatticeKey& key) const {
    return std::int64_t(key.k) * impl_->scale[key.level];
}

const Anchor* AnchorStore::find(const LatticeKey& key) const {
    if (!impl_->validKey(key)) return nullptr;
    const std::int32_t index = impl_->indexOf(impl_->canonical(key));
    return index == kNoAnchor ? nullptr : &impl_->pool[index];
}

std::size_t AnchorStore::size() const {
    return impl_->count;
}

void AnchorStore::forEach(const std::function<void(const Anchor&)>& f) const {
    for (std::size_t n = 0; n < impl_->pool.size(); ++n) {
        if (impl_->alive[n]) f(impl_->pool[n]);
    }
}

// ---- Insert, remove, advance --------------------------------------------------------------------

AnchorStore::InsertResult AnchorStore::insert(const LatticeKey& key, const ShRgb& sh,
                                              const glm::dvec3& capturedPosition_m,
                                              double lifetime_s, double timeOfDay_h) {
    Impl& m = *impl_;
    AMB_CHECK(key.level >= 0 && key.level < m.levels);
    const bool positionOk = std::isfinite(capturedPosition_m.x) &&
                            std::isfinite(capturedPosition_m.y) &&
                            std::isfinite(capturedPosition_m.z);
    // A point beyond the integer range of the finest lattice (a camera further out than the
    // settings can number) is refused like a bad capture: the store keeps its fallback there.
    if (!m.validKey(key) || !finiteSh(sh, kMaxCoefficient) || !positionOk ||
        !std::isfinite(lifetime_s) || lifetime_s <= 0.0) {
        ++m.counters.rejected;
        return InsertResult::Rejected;
    }
    const LatticeKey c = m.canonical(key);
    const bool instant = m.settings.blendTime_s <= 0.0;
    const std::int32_t index = m.indexOf(c);
    if (index != kNoAnchor) {
        // Refresh (thesis appendix B: the anchor interpolates slowly to the new coefficients).
        Anchor& a = m.pool[index];
        const float presenceBefore = a.presence;
        a.presence = Impl::presenceAt(a, m.now, m.settings.blendTime_s);
        if (instant || a.presence != presenceBefore) m.touchField(c.level);
        m.setFadeDirection(a, false);
        // Blend from what interpolation showed (relight included), so a refresh is no pop.
        a.blendFrom = a.relight == 1.0f ? a.current : a.current * a.relight;
        a.current = a.blendFrom;
        a.relight = 1.0f;
        a.target = sh;
        a.blendStart_s = m.now;
        a.blendProgress = instant ? 1.0f : 0.0f;
        if (instant) a.current = sh;
        a.captureTime_s = m.now;
        a.captureTimeOfDay_h = timeOfDay_h;
        a.lifetime_s = lifetime_s;
        a.capturedPosition_m = capturedPosition_m;
        a.regenerationRequested = false;
        ++m.counters.refreshed;
        return InsertResult::Refreshed;
    }
    // New anchor: start from what the store shows here now (thesis 7.6), fade in.
    Anchor a;
    a.current = instant ? sh : m.interpolate(m.x(c), m.z(c), nullptr);
    a.blendFrom = a.current;
    a.target = sh;
    a.blendStart_s = m.now;
    a.blendProgress = instant ? 1.0f : 0.0f;
    a.presence = instant ? 1.0f : 0.0f;
    a.presenceFrom = a.presence;
    a.presenceChange_s = m.now;
    a.birth_s = m.now;
    a.captureTime_s = m.now;
    a.captureTimeOfDay_h = timeOfDay_h;
    a.lifetime_s = lifetime_s;
    a.capturedPosition_m = capturedPosition_m;
    a.key = c;
    const std::int32_t slot = m.allocate(a);
    m.grids[c.level]->tree().setValueOn(openvdb::Coord(c.i, 0, c.k), slot);
    if (instant) m.touchField(c.level);  // present at once; otherwise presence 0 moves nothing
    ++m.counters.inserted;
    return InsertResult::Inserted;
}

bool AnchorStore::remove(const LatticeKey& key) {
    Impl& m = *impl_;
    if (!m.validKey(key)) return false;
    const LatticeKey c = m.canonical(key);
    const std::int32_t index = m.indexOf(c);
    if (index == kNoAnchor) return false;
    m.release(index);
    m.touchField(c.level);
    openvdb::tools::pruneInactive(m.grids[c.level]->tree());
    ++m.counters.prunes;
    return true;
}

void AnchorStore::clear() {
    Impl& m = *impl_;
    for (auto& grid : m.grids) grid->clear();
    m.pool.clear();
    m.alive.clear();
    m.freeList.clear();
    m.count = 0;
    m.touchField();
}

void AnchorStore::advance(double now_s) {
    Impl& m = *impl_;
    if (!std::isfinite(now_s) || now_s <= m.now) return;  // dt = 0 (or backwards): no change
    m.now = now_s;
    const double blend = m.settings.blendTime_s;
    std::array<bool, kMaxAnchorLevels> removedAt{};
    int fieldMovesFrom = kMaxAnchorLevels;
    for (std::size_t n = 0; n < m.pool.size(); ++n) {
        if (!m.alive[n]) continue;
        Anchor& a = m.pool[n];
        const float presenceBefore = a.presence;
        const bool blending = a.blendProgress < 1.0f;
        // Blending current -> target; exact at the end of the blend time.
        if (a.blendProgress < 1.0f) {
            const double t = blend > 0.0 ? (now_s - a.blendStart_s) / blend : 1.0;
            if (t >= 1.0) {
                a.blendProgress = 1.0f;
                a.current = a.target;
            } else {
                a.blendProgress = float(t);
                a.current = lerp(a.blendFrom, a.target, easeInOut(float(t)));
            }
        }
        // Regeneration request before expiry, expiry at the end of the lifetime.
        const double age = a.age_s(now_s);
        if (age >= m.settings.regenerateFraction * a.lifetime_s) a.regenerationRequested = true;
        if (!a.expired && age >= a.lifetime_s) {
            a.presence = Impl::presenceAt(a, now_s, blend);
            m.setFadeDirection(a, true);
            // The fade-out started when the lifetime ended, not at this (possibly late) step.
            a.presenceChange_s = std::min(now_s, a.captureTime_s + a.lifetime_s);
        }
        a.presence = Impl::presenceAt(a, now_s, blend);
        if (blending || a.presence != presenceBefore)
            fieldMovesFrom = std::min(fieldMovesFrom, a.key.level);
        if (a.expired && a.presence <= 0.0f) {
            removedAt[a.key.level] = true;
            m.release(std::int32_t(n));
            ++m.counters.expired;
        }
    }
    m.touchField(fieldMovesFrom);
    // Prune the branches emptied by removals.
    for (int L = 0; L < m.levels; ++L) {
        if (!removedAt[L]) continue;
        openvdb::tools::pruneInactive(m.grids[L]->tree());
        ++m.counters.prunes;
    }
}

double AnchorStore::now_s() const {
    return impl_->now;
}

void AnchorStore::expireAllWithin(double remaining_s) {
    Impl& m = *impl_;
    for (std::size_t n = 0; n < m.pool.size(); ++n) {
        if (!m.alive[n]) continue;
        Anchor& a = m.pool[n];
        const double end = m.now + std::max(0.0, remaining_s);
        if (a.captureTime_s + a.lifetime_s > end) a.lifetime_s = end - a.captureTime_s;
        a.regenerationRequested = true;
    }
}

std::vector<LatticeKey> AnchorStore::regenerationRequests() const {
    const Impl& m = *impl_;
    std::vector<std::pair<double, LatticeKey>> list;
    for (std::size_t n = 0; n < m.pool.size(); ++n) {
        if (!m.alive[n] || !m.pool[n].regenerationRequested) continue;
        const Anchor& a = m.pool[n];
        list.push_back({a.age_s(m.now) / a.lifetime_s, a.key});
    }
    std::stable_sort(list.begin(), list.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    std::vector<LatticeKey> keys;
    keys.reserve(list.size());
    for (const auto& e : list) keys.push_back(e.second);
    return keys;
}

// ---- Interpolation ------------------------------------------------------------------------------

void AnchorStore::setFallback(const ShRgb& sh) {
    // The fallback must never carry NaN into the frame: non-finite values are ignored.
    if (!finiteSh(sh, kMaxCoefficient)) return;
    impl_->fallback = sh;
    impl_->touchField();
}
const ShRgb& AnchorStore::fallback() const {
    return impl_->fallback;
}

void AnchorStore::Impl::ensureField() const {
    if (fieldStaleFrom.load(std::memory_order_acquire) >= levels) return;
    std::lock_guard<std::mutex> lock(fieldMutex);
    const int from = fieldStaleFrom.load(std::memory_order_relaxed);
    if (from >= levels) return;
    FieldLattice lattice;
    lattice.levels = levels;
    for (int L = 0; L < levels; ++L) {
        lattice.spacing[L] = spacing[L];
        lattice.scale[L] = scale[L];
    }
    lattice.fineSpacing_m = fineSpacing;
    lattice.reachCells = settings.reachCells;
    lattice.coarseReachCells = settings.coarseReachCells;
    lattice.finerWeight = settings.finerWeight;
    lattice.smooth = settings.smoothInterpolation;
    thread_local std::vector<FieldAnchor> anchors;
    anchors.clear();
    for (std::size_t n = 0; n < pool.size(); ++n) {
        const Anchor& a = pool[n];
        const float weight = easeInOut(a.presence);
        if (!alive[n] || !(weight > 0.0f)) continue;
        anchors.push_back({a.key.level, a.key.i, a.key.k, weight,
                           a.relight == 1.0f ? a.current : a.current * a.relight});
    }
    field.rebuild(lattice, anchors, fallback, from);
    if (separateFixedField()) {
        lattice.smooth = false;
        fixedField.rebuild(lattice, anchors, fallback, from);
    }
    fieldStaleFrom.store(kMaxAnchorLevels, std::memory_order_release);
}

// The anchors at the corners of the cell that answered (debugging, tests).
void AnchorStore::Impl::describe(double qx, double qz, const AnchorField::Hit& hit,
                                 InterpolationDetail& detail) const {
    detail = InterpolationDetail{};
    detail.level = hit.level;
    if (hit.level < 0) {
        detail.fallback = true;
        return;
    }
    // A corner's value carries the bilinear weights, or the Hermite value weights (smooth).
    const std::array<double, 4> hu = AnchorField::hermite(hit.u), hw = AnchorField::hermite(hit.w);
    const bool smooth = settings.smoothInterpolation;
    const double wx[2] = {smooth ? hu[0] : 1.0 - hit.u, smooth ? hu[2] : hit.u};
    const double wz[2] = {smooth ? hw[0] : 1.0 - hit.w, smooth ? hw[2] : hit.w};
    for (int q = 0; q < 4; ++q) {
        const LatticeKey point{hit.level, std::int32_t(hit.i + (q & 1)),
                               std::int32_t(hit.k + (q >> 1))};
        if (!validKey(point)) continue;
        const std::int32_t index = indexOf(canonical(point));
        if (index == kNoAnchor || !(pool[index].presence > 0.0f)) continue;
        const Anchor& a = pool[index];
        const double dx = x(a.key) - qx, dz = z(a.key) - qz;
        const int quadrant = dx >= 0.0 ? (dz >= 0.0 ? 0 : 3) : (dz >= 0.0 ? 1 : 2);
        const double d = std::sqrt(dx * dx + dz * dz);
        if (q == hit.corner) {
            detail.used = {{a.key, quadrant, d, 1.0}};
            detail.exact = true;
            return;
        }
        const double w = wx[q & 1] * wz[q >> 1];
        if (w > 0.0) detail.used.push_back({a.key, quadrant, d, w * double(easeInOut(a.presence))});
    }
}

ShRgb AnchorStore::Impl::interpolate(double qx, double qz, InterpolationDetail* detail) const {
    ensureField();
    if (!detail) return field.at(qx, qz);
    AnchorField::Hit hit;
    const ShRgb value = field.at(qx, qz, &hit);
    describe(qx, qz, hit, *detail);
    return value;
}

const Anchor* AnchorStore::nearestAnchor(double x_m, double z_m) const {
    const Impl& m = *impl_;
    const double reach = double(kCoordLimit) * m.fineSpacing;
    if (!std::isfinite(x_m) || !std::isfinite(z_m) || std::fabs(x_m) > reach ||
        std::fabs(z_m) > reach || m.count == 0)
        return nullptr;
    for (int L = m.levels - 1; L >= 0; --L) {
        const double s = m.spacing[L];
        const double radius = m.settings.searchCells * s;
        const double i0 = std::ceil((x_m - radius) / s), i1 = std::floor((x_m + radius) / s);
        const double k0 = std::ceil((z_m - radius) / s), k1 = std::floor((z_m + radius) / s);
        const double limit = double(kCoordLimit / m.scale[L]);
        const Anchor* best = nullptr;
        double bestD = radius;
        for (double di = i0; di <= i1; di += 1.0) {
            for (double dk = k0; dk <= k1; dk += 1.0) {
                if (std::fabs(di) > limit || std::fabs(dk) > limit) continue;
                const LatticeKey c = m.canonical({L, std::int32_t(di), std::int32_t(dk)});
                const std::int32_t index = m.indexOf(c);
                if (index == kNoAnchor || !(m.pool[index].presence > 0.0f)) continue;
                const double d = std::hypot(m.x(c) - x_m, m.z(c) - z_m);
                // Nearest first; ties to the smaller key, so pool slots do not matter.
                if (d < bestD || (d == bestD && best &&
                                  std::tie(c.level, c.i, c.k) <
                                      std::tie(best->key.level, best->key.i, best->key.k))) {
                    best = &m.pool[index];
                    bestD = d;
                }
            }
        }
        if (best) return best;
    }
    return nullptr;
}

void AnchorStore::relight(const std::function<float(const Anchor&)>& factor) {
    Impl& m = *impl_;
    int changedFrom = kMaxAnchorLevels;
    for (std::size_t n = 0; n < m.pool.size(); ++n) {
        if (!m.alive[n]) continue;
        const float f = factor(m.pool[n]);
        const float r = std::isfinite(f) && f > 0.0f ? f : 1.0f;
        if (r != m.pool[n].relight) changedFrom = std::min(changedFrom, m.pool[n].key.level);
        m.pool[n].relight = r;
    }
    m.touchField(changedFrom);
}

ShRgb AnchorStore::interpolate(double x_m, double z_m, InterpolationDetail* detail) const {
    return impl_->interpolate(x_m, z_m, detail);
}

namespace {
// field.at at many points; a lookup is ~0.1 us: threads pay off only for large batches.
void lookUpMany(const AnchorField& field, std::size_t count, const double* x_m,
                const double* z_m, ShRgb* out) {
    constexpr std::size_t kGrain = 4096;
    if (count <= kGrain) {
        for (std::size_t i = 0; i < count; ++i) out[i] = field.at(x_m[i], z_m[i]);
        return;
    }
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, kGrain),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i)
                              out[i] = field.at(x_m[i], z_m[i]);
                      });
}
}  // namespace

void AnchorStore::interpolateMany(std::size_t count, const double* x_m, const double* z_m,
                                  ShRgb* out) const {
    impl_->ensureField();
    lookUpMany(impl_->field, count, x_m, z_m, out);
}

ShRgb AnchorStore::interpolateFixed(double x_m, double z_m) const {
    impl_->ensureField();
    return (impl_->separateFixedField() ? impl_->fixedField : impl_->field).at(x_m, z_m);
}

void AnchorStore::interpolateFixedMany(std::size_t count, const double* x_m, const double* z_m,
                                       ShRgb* out) const {
    impl_->ensureField();
    lookUpMany(impl_->separateFixedField() ? impl_->fixedField : impl_->field, count, x_m, z_m,
               out);
}

std::array<double, 27> AnchorStore::interpolationSlopeBound() const {
    impl_->ensureField();
    return impl_->field.slopeBound();
}

std::size_t AnchorStore::interpolationCacheBytes() const {
    impl_->ensureField();
    return impl_->field.bytes() + (impl_->separateFixedField() ? impl_->fixedField.bytes() : 0);
}

// ---- Statistics ---------------------------------------------------------------------------------

AnchorStoreStatistics AnchorStore::statistics() const {
    const Impl& m = *impl_;
    AnchorStoreStatistics s = m.counters;
    s.anchors = m.count;
    for (std::size_t n = 0; n < m.pool.size(); ++n) {
        if (m.alive[n]) ++s.anchorsPerLevel[m.pool[n].key.level];
    }
    s.poolBytes = sizeof(Impl) + m.pool.capacity() * sizeof(Anchor) +
                  m.alive.capacity() * sizeof(std::uint8_t) +
                  m.freeList.capacity() * sizeof(std::int32_t);
    s.gridBytes = 0;
    for (const auto& grid : m.grids) s.gridBytes += std::size_t(grid->memUsage());
    return s;
}

// ---- Files --------------------------------------------------------------------------------------

namespace {

enum AnchorFlags : int { kFlagRegenerate = 1, kFlagExpired = 2 };

std::string shGridName(const char* what, int k) {
    return std::string(what) + "_" + std::to_string(k);
}

// The grids as OpenVDB's stream writer lays them out, with mask compression only (no Blosc or
// zlib blocks, whose declared sizes the loader would have to trust), sealed with the checksum
// (AnchorStoreFile.h) and written next to `path` first, so a failed save leaves the old file.
void writeStoreFile(const std::string& path, const openvdb::GridPtrVec& grids,
                    const openvdb::MetaMap& meta) {
    std::string bytes;
    try {
        std::ostringstream os(std::ios::binary);
        openvdb::io::Stream stream(os);
        stream.setCompression(openvdb::io::COMPRESS_ACTIVE_MASK);
        stream.write(grids, meta);
        bytes = sealAnchorStoreFile(os.str(), "anchor store");
    } catch (const std::exception& e) {
        throw InputError(path, std::string("cannot write anchor store: ") + e.what());
    }
    if (bytes.size() > kMaxAnchorStoreFileBytes) {
        throw InputError(path, "cannot write anchor store: " + std::to_string(bytes.size()) +
                                   " bytes, more than a store file may hold");
    }
    const std::string part = path + ".part";
    {
        std::ofstream out(part, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), std::streamsize(bytes.size()));
        out.close();
        if (!out) {
            std::remove(part.c_str());
            throw InputError(path, "cannot write anchor store");
        }
    }
    if (std::rename(part.c_str(), path.c_str()) != 0) {
        std::remove(part.c_str());
        throw InputError(path, "cannot write anchor store");
    }
}

template <typename GridT>
typename GridT::Ptr makePayloadGrid(const std::string& name, double fineSpacing,
                                    const typename GridT::ValueType& background) {
    auto grid = GridT::create(background);
    grid->setName(name);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(fineSpacing));
    return grid;
}

}  // namespace

void AnchorStore::save(const std::string& path) const {
    const Impl& m = *impl_;
    openvdb::GridPtrVec grids;
    for (const auto& g : m.grids) {
        // Anchor numbers in the file are 0..n-1 in pool order (pool slots are not kept).
        auto copy = openvdb::Int32Grid::create(kNoAnchor);
        copy->setName(g->getName());
        copy->setTransform(g->transform().copy());
        grids.push_back(copy);
    }
    std::array<openvdb::Vec3SGrid::Ptr, kShCoefficients> current, target, from;
    for (int k = 0; k < kShCoefficients; ++k) {
        current[k] = makePayloadGrid<openvdb::Vec3SGrid>(shGridName("sh_current", k), m.fineSpacing,
                                                         openvdb::Vec3s(0.0f));
        target[k] = makePayloadGrid<openvdb::Vec3SGrid>(shGridName("sh_target", k), m.fineSpacing,
                                                        openvdb::Vec3s(0.0f));
        from[k] = makePayloadGrid<openvdb::Vec3SGrid>(shGridName("sh_blend_from", k), m.fineSpacing,
                                                      openvdb::Vec3s(0.0f));
        grids.push_back(current[k]);
        grids.push_back(target[k]);
        grids.push_back(from[k]);
    }
    auto position = makePayloadGrid<openvdb::Vec3DGrid>("captured_position", m.fineSpacing,
                                                        openvdb::Vec3d(0.0));
    auto age = makePayloadGrid<openvdb::FloatGrid>("age_s", m.fineSpacing, 0.0f);
    auto lifetime = makePayloadGrid<openvdb::FloatGrid>("lifetime_s", m.fineSpacing, 0.0f);
    auto blendElapsed = makePayloadGrid<openvdb::FloatGrid>("blend_elapsed_s", m.fineSpacing, 0.0f);
    auto presence = makePayloadGrid<openvdb::FloatGrid>("presence", m.fineSpacing, 0.0f);
    auto sinceBirth = makePayloadGrid<openvdb::FloatGrid>("since_birth_s", m.fineSpacing, 0.0f);
    auto tod = makePayloadGrid<openvdb::FloatGrid>("capture_time_of_day_h", m.fineSpacing, 0.0f);
    auto flags = makePayloadGrid<openvdb::Int32Grid>("flags", m.fineSpacing, 0);
    grids.push_back(position);
    for (auto& g : {age, lifetime, blendElapsed, presence, sinceBirth, tod}) grids.push_back(g);
    grids.push_back(flags);

    std::int32_t number = 0;
    for (std::size_t n = 0; n < m.pool.size(); ++n) {
        if (!m.alive[n]) continue;
        const Anchor& a = m.pool[n];
        const auto levelGrid = openvdb::GridBase::grid<openvdb::Int32Grid>(grids[a.key.level]);
        levelGrid->tree().setValueOn(openvdb::Coord(a.key.i, 0, a.key.k), number++);
        const openvdb::Coord fine(std::int32_t(fineI(a.key)), 0, std::int32_t(fineK(a.key)));
        for (int k = 0; k < kShCoefficients; ++k) {
            current[k]->tree().setValueOn(
                fine, openvdb::Vec3s(a.current.c[k].x, a.current.c[k].y, a.current.c[k].z));
            target[k]->tree().setValueOn(
                fine, openvdb::Vec3s(a.target.c[k].x, a.target.c[k].y, a.target.c[k].z));
            from[k]->tree().setValueOn(
                fine, openvdb::Vec3s(a.blendFrom.c[k].x, a.blendFrom.c[k].y, a.blendFrom.c[k].z));
        }
        position->tree().setValueOn(
            fine,
            openvdb::Vec3d(a.capturedPosition_m.x, a.capturedPosition_m.y, a.capturedPosition_m.z));
        age->tree().setValueOn(fine, float(a.age_s(m.now)));
        lifetime->tree().setValueOn(fine, float(a.lifetime_s));
        blendElapsed->tree().setValueOn(
            fine, float(a.blendProgress >= 1.0f ? m.settings.blendTime_s : m.now - a.blendStart_s));
        presence->tree().setValueOn(fine, a.presence);
        sinceBirth->tree().setValueOn(fine, float(m.now - a.birth_s));
        tod->tree().setValueOn(fine, float(a.captureTimeOfDay_h));
        flags->tree().setValueOn(
            fine, (a.regenerationRequested ? kFlagRegenerate : 0) | (a.expired ? kFlagExpired : 0));
    }

    openvdb::MetaMap meta;
    meta.insertMeta("format", openvdb::StringMetadata(kFormat));
    meta.insertMeta("coarsest_spacing_m", openvdb::DoubleMetadata(m.settings.coarsestSpacing_m));
    meta.insertMeta("levels", openvdb::Int32Metadata(m.levels));
    meta.insertMeta("anchors", openvdb::Int32Metadata(number));
    meta.insertMeta("clock_s", openvdb::DoubleMetadata(m.now));
    meta.insertMeta(kAnchorStoreChecksumKey, openvdb::StringMetadata("00000000"));
    writeStoreFile(path, grids, meta);
}

namespace {

std::string coordString(const openvdb::Coord& c) {
    return "(" + std::to_string(c.x()) + ", " + std::to_string(c.y()) + ", " +
           std::to_string(c.z()) + ")";
}

template <typename GridT>
typename GridT::Ptr requireGrid(const openvdb::GridPtrVec& grids, const std::string& name,
                                const std::string& path) {
    for (const auto& g : grids) {
        if (g && g->getName() == name) {
            auto typed = openvdb::gridPtrCast<GridT>(g);
            if (!typed) {
                throw InputError(path, "grid '" + name + "' has type " + g->type() + ", expected " +
                                           GridT::gridType());
            }
            return typed;
        }
    }
    throw InputError(path, "grid '" + name + "' is missing");
}

template <typename GridT>
typename GridT::ValueType requireVoxel(const GridT& grid, const openvdb::Coord& c,
                                       const std::string& path) {
    typename GridT::ValueType v;
    if (!grid.tree().probeValue(c, v)) {
        throw InputError(path,
                         "grid '" + grid.getName() + "' has no value at voxel " + coordString(c));
    }
    return v;
}

// A file-level metadata value of the checked bytes (the walk checked its size).
template <typename T>
T metaValue(const VdbFileSummary& file, const char* name, const char* type,
            const std::string& path) {
    const auto it = file.metadata.find(name);
    if (it == file.metadata.end() || it->second.type != type) {
        throw InputError(path, std::string("metadata '") + name + "' is missing or not " + type);
    }
    T v;
    std::memcpy(&v, it->second.bytes.data(), sizeof(T));
    return v;
}

struct StoreFileHeader {
    std::int32_t anchors = 0;
};

// Everything that can be known before OpenVDB parses the bytes: the checksum (corruption and
// truncation stop here), the stream structure (AnchorStoreFile.h), the lattice and the anchor
// count, and the grids — each expected one present once with its type and voxel size, nothing
// else, the level grids holding `anchors` voxels together and every payload grid one per anchor.
StoreFileHeader checkStoreFile(const std::string& bytes, const std::string& path, double s0,
                               const std::vector<double>& spacing) {
    const VdbFileSummary header = readVdbHeader(bytes, path);
    const auto format = header.metadata.find("format");
    if (format == header.metadata.end() || format->second.type != "string" ||
        format->second.bytes != kFormat) {
        const std::string found =
            format == header.metadata.end() ? "missing" : "'" + format->second.bytes + "'";
        throw InputError(path, std::string("not an anchor store of format ") + kFormat +
                                   " (metadata 'format' is " + found + ")");
    }
    verifyAnchorStoreChecksum(bytes, header, path);
    const VdbFileSummary file = checkVdbFile(bytes, path);

    StoreFileHeader h;
    const double fileS0 = metaValue<double>(file, "coarsest_spacing_m", "double", path);
    const std::int32_t levels = metaValue<std::int32_t>(file, "levels", "int32", path);
    h.anchors = metaValue<std::int32_t>(file, "anchors", "int32", path);
    const double clock = metaValue<double>(file, "clock_s", "double", path);
    if (fileS0 != s0 || levels != std::int32_t(spacing.size())) {
        throw InputError(path, "lattice (s0 " + std::to_string(fileS0) + " m, " +
                                   std::to_string(levels) + " levels) differs from this store's");
    }
    if (!std::isfinite(clock)) throw InputError(path, "metadata 'clock_s' is not finite");
    if (h.anchors < 0) throw InputError(path, "metadata 'anchors' is negative");

    struct Expected {
        std::string name, type;
        double voxel_m;
    };
    std::vector<Expected> expected;
    for (std::size_t L = 0; L < spacing.size(); ++L)
        expected.push_back({"anchor_index_L" + std::to_string(L), "Tree_int32_5_4_3", spacing[L]});
    const std::size_t payloadFrom = expected.size();
    const double fine = spacing.back();
    for (const char* sh : {"sh_current", "sh_target", "sh_blend_from"}) {
        for (int k = 0; k < kShCoefficients; ++k)
            expected.push_back({shGridName(sh, k), "Tree_vec3s_5_4_3", fine});
    }
    expected.push_back({"captured_position", "Tree_vec3d_5_4_3", fine});
    for (const char* f : {"age_s", "lifetime_s", "blend_elapsed_s", "presence", "since_birth_s",
                          "capture_time_of_day_h"})
        expected.push_back({f, "Tree_float_5_4_3", fine});
    expected.push_back({"flags", "Tree_int32_5_4_3", fine});

    if (file.grids.size() != expected.size()) {
        throw InputError(path, std::to_string(file.grids.size()) + " grids, expected " +
                                   std::to_string(expected.size()));
    }
    std::uint64_t levelVoxels = 0;
    for (std::size_t e = 0; e < expected.size(); ++e) {
        const Expected& x = expected[e];
        const auto g = std::find_if(file.grids.begin(), file.grids.end(),
                                    [&](const VdbGridSummary& s) { return s.name == x.name; });
        if (g == file.grids.end()) throw InputError(path, "grid '" + x.name + "' is missing");
        if (g->type != x.type) {
            throw InputError(path,
                             "grid '" + x.name + "' has type " + g->type + ", expected " + x.type);
        }
        if (g->voxelSize_m != x.voxel_m) {
            throw InputError(path, "grid '" + x.name + "' has voxel size " +
                                       std::to_string(g->voxelSize_m) + " m, expected " +
                                       std::to_string(x.voxel_m));
        }
        if (e < payloadFrom) {
            levelVoxels += g->activeVoxels;
        } else if (g->activeVoxels != std::uint64_t(h.anchors)) {
            throw InputError(path, "grid '" + x.name + "' holds " +
                                       std::to_string(g->activeVoxels) + " values for " +
                                       std::to_string(h.anchors) + " anchors");
        }
    }
    if (levelVoxels != std::uint64_t(h.anchors)) {
        throw InputError(path, "metadata 'anchors' is " + std::to_string(h.anchors) +
                                   " but the level grids hold " + std::to_string(levelVoxels));
    }
    return h;
}

// OpenVDB parses the checked bytes from memory, all at once (no delayed loading, so nothing is
// read after load() returns); a read past the end throws instead of yielding zeros.
openvdb::GridPtrVecPtr parseStoreGrids(const std::string& bytes, const std::string& path) {
    try {
        std::istringstream is(bytes, std::ios::binary);
        is.exceptions(std::ios::failbit | std::ios::badbit | std::ios::eofbit);
        openvdb::io::Stream stream(is, /*delayLoad=*/false);
        openvdb::GridPtrVecPtr grids = stream.getGrids();
        if (!grids) throw InputError(path, "no grids");
        return grids;
    } catch (const InputError&) {
        throw;
    } catch (const std::exception& e) {
        throw InputError(path, std::string("cannot read anchor store: ") + e.what());
    }
}

// The payload grids (AnchorStore::save), found by name and type.
struct PayloadGrids {
    std::array<openvdb::Vec3SGrid::Ptr, kShCoefficients> current, target, from;
    openvdb::Vec3DGrid::Ptr position;
    openvdb::FloatGrid::Ptr age, lifetime, blendElapsed, presence, sinceBirth, tod;
    openvdb::Int32Grid::Ptr flags;

    PayloadGrids(const openvdb::GridPtrVec& grids, const std::string& path) {
        for (int k = 0; k < kShCoefficients; ++k) {
            current[k] = requireGrid<openvdb::Vec3SGrid>(grids, shGridName("sh_current", k), path);
            target[k] = requireGrid<openvdb::Vec3SGrid>(grids, shGridName("sh_target", k), path);
            from[k] = requireGrid<openvdb::Vec3SGrid>(grids, shGridName("sh_blend_from", k), path);
        }
        position = requireGrid<openvdb::Vec3DGrid>(grids, "captured_position", path);
        age = requireGrid<openvdb::FloatGrid>(grids, "age_s", path);
        lifetime = requireGrid<openvdb::FloatGrid>(grids, "lifetime_s", path);
        blendElapsed = requireGrid<openvdb::FloatGrid>(grids, "blend_elapsed_s", path);
        presence = requireGrid<openvdb::FloatGrid>(grids, "presence", path);
        sinceBirth = requireGrid<openvdb::FloatGrid>(grids, "since_birth_s", path);
        tod = requireGrid<openvdb::FloatGrid>(grids, "capture_time_of_day_h", path);
        flags = requireGrid<openvdb::Int32Grid>(grids, "flags", path);
    }
};

// The anchor stored at fine voxel `fine`, its times relative to the clock `now`; every value
// checked (finite coefficients within AnchorStore::kMaxCoefficient, finite position, positive
// lifetime, non-negative ages, presence in [0, 1], known flags).
Anchor readAnchor(const PayloadGrids& g, const openvdb::Coord& fine, double now, double blendTime_s,
                  const std::string& where, const std::string& path) {
    Anchor a;
    for (int k = 0; k < kShCoefficients; ++k) {
        const auto cv = requireVoxel(*g.current[k], fine, path);
        const auto tv = requireVoxel(*g.target[k], fine, path);
        const auto fv = requireVoxel(*g.from[k], fine, path);
        a.current.c[k] = {cv.x(), cv.y(), cv.z()};
        a.target.c[k] = {tv.x(), tv.y(), tv.z()};
        a.blendFrom.c[k] = {fv.x(), fv.y(), fv.z()};
    }
    if (!finiteSh(a.current, AnchorStore::kMaxCoefficient) ||
        !finiteSh(a.target, AnchorStore::kMaxCoefficient) ||
        !finiteSh(a.blendFrom, AnchorStore::kMaxCoefficient)) {
        throw InputError(path, where + ": coefficients not finite or out of range");
    }
    const auto p = requireVoxel(*g.position, fine, path);
    a.capturedPosition_m = {p.x(), p.y(), p.z()};
    const double ageV = requireVoxel(*g.age, fine, path);
    const double lifeV = requireVoxel(*g.lifetime, fine, path);
    const double blendV = requireVoxel(*g.blendElapsed, fine, path);
    const double presV = requireVoxel(*g.presence, fine, path);
    const double birthV = requireVoxel(*g.sinceBirth, fine, path);
    const double todV = requireVoxel(*g.tod, fine, path);
    const int flagV = requireVoxel(*g.flags, fine, path);
    const auto finiteNonNegative = [](double v) { return std::isfinite(v) && v >= 0.0; };
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()) ||
        !finiteNonNegative(ageV) || !std::isfinite(lifeV) || !(lifeV > 0.0) ||
        !finiteNonNegative(blendV) || !(presV >= 0.0 && presV <= 1.0) ||
        !finiteNonNegative(birthV) || !std::isfinite(todV) ||
        (flagV & ~(kFlagRegenerate | kFlagExpired)) != 0) {
        throw InputError(path, where + ": anchor state out of range");
    }
    a.captureTime_s = now - ageV;
    a.birth_s = now - birthV;
    a.lifetime_s = lifeV;
    a.captureTimeOfDay_h = todV;
    a.blendStart_s = now - blendV;
    a.blendProgress = float(blendTime_s > 0.0 ? clamp01(blendV / blendTime_s) : 1.0);
    a.presence = float(presV);
    a.presenceFrom = a.presence;
    a.presenceChange_s = now;
    a.regenerationRequested = (flagV & kFlagRegenerate) != 0;
    a.expired = (flagV & kFlagExpired) != 0;
    return a;
}

}  // namespace

void AnchorStore::load(const std::string& path) {
    // The whole file, bounded, checked byte by byte before OpenVDB sees it (AnchorStoreFile.h).
    const std::string bytes = readTextFile(path, "anchor store file", kMaxAnchorStoreFileBytes);
    const std::vector<double> spacing(impl_->spacing.begin(),
                                      impl_->spacing.begin() + impl_->levels);
    const StoreFileHeader header =
        checkStoreFile(bytes, path, impl_->settings.coarsestSpacing_m, spacing);
    const std::int32_t anchors = header.anchors;
    const openvdb::GridPtrVecPtr grids = parseStoreGrids(bytes, path);

    auto fresh = std::make_unique<Impl>(impl_->settings);
    Impl& m = *fresh;
    m.now = impl_->now;
    m.fallback = impl_->fallback;
    m.counters = impl_->counters;
    const PayloadGrids payload(*grids, path);

    std::vector<std::uint8_t> numberSeen(std::size_t(anchors), 0);
    for (int L = 0; L < m.levels; ++L) {
        const auto levelGrid =
            requireGrid<openvdb::Int32Grid>(*grids, "anchor_index_L" + std::to_string(L), path);
        for (auto it = levelGrid->cbeginValueOn(); it; ++it) {
            const openvdb::Coord c = it.getCoord();
            const std::int32_t number = *it;
            const std::string where = "grid '" + levelGrid->getName() + "' voxel " + coordString(c);
            if (c.y() != 0) throw InputError(path, where + ": y must be 0");
            const LatticeKey key{L, c.x(), c.z()};
            if (!m.validKey(key) || m.canonical(key) != key) {
                throw InputError(path, where + ": not a canonical level-" + std::to_string(L) +
                                           " lattice point");
            }
            if (number < 0 || number >= anchors || numberSeen[std::size_t(number)]) {
                throw InputError(path, where + ": anchor number out of range or repeated");
            }
            numberSeen[std::size_t(number)] = 1;
            const openvdb::Coord fine(std::int32_t(std::int64_t(key.i) * m.scale[L]), 0,
                                      std::int32_t(std::int64_t(key.k) * m.scale[L]));
            Anchor a = readAnchor(payload, fine, m.now, m.settings.blendTime_s, where, path);
            a.key = key;
            const std::int32_t slot = m.allocate(a);
            m.grids[L]->tree().setValueOn(openvdb::Coord(key.i, 0, key.k), slot);
        }
    }
    if (m.count != std::size_t(anchors)) {
        throw InputError(path, "metadata 'anchors' is " + std::to_string(anchors) +
                                   " but the level grids hold " + std::to_string(m.count));
    }
    impl_ = std::move(fresh);
}

}  // namespace amb
