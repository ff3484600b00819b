// AnchorStore.cpp — the sparse anchor store: lattice, blending, four-quadrant interpolation,
// statistics (see AnchorStore.h). Its level grids and its .vdb files are OpenVDB's, in
// AnchorStoreVdb.cpp; the store's inside is AnchorStoreImpl.h.
//
// [SECTION] Lifetime
// [SECTION] Lattice
// [SECTION] Insert, remove, advance (blending, presence, expiry, pruning)
// [SECTION] Interpolation (hierarchical bicubic Hermite, AnchorField.h; cache rebuilt on change)
// [SECTION] Statistics
#include "lighting/AnchorStore.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "lighting/AnchorStoreImpl.h"
#include "world/Error.h"

namespace amb {

bool finiteSh(const ShRgb& sh, float limit) {
    for (const glm::vec3& c : sh.c) {
        for (int ch = 0; ch < 3; ++ch) {
            if (!std::isfinite(c[ch]) || std::fabs(c[ch]) > limit) return false;
        }
    }
    return true;
}

// ---- Lifetime -----------------------------------------------------------------------------------

double anchorLifetime_s(const AnchorStoreSettings& settings, double sunSpeed_radPerHour,
                        double timeRate_hPerS) {
    // Angular speed of the sun in radians per simulated second.
    const double speed = std::fabs(sunSpeed_radPerHour * timeRate_hPerS);
    double lifetime = settings.maxLifetime_s;
    if (std::isfinite(speed) && speed > 0.0) lifetime = settings.allowedSunAngle_rad / speed;
    return std::clamp(lifetime, settings.minLifetime_s, settings.maxLifetime_s);
}

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

ShSlope AnchorStore::Impl::currentSlope(const Anchor& a, const SlopeState& state) {
    ShSlope s = state.slope;
    if (a.blendProgress < 1.0f) {
        const float t = easeInOut(a.blendProgress);
        s = {lerp(state.from.dx, state.slope.dx, t), lerp(state.from.dz, state.slope.dz, t),
             state.from.validity_m + t * (state.slope.validity_m - state.from.validity_m)};
    }
    if (a.relight != 1.0f) s.dx *= a.relight, s.dz *= a.relight;
    return s;
}

std::optional<ShSlope> AnchorStore::slope(const LatticeKey& key) const {
    const Impl& m = *impl_;
    if (!m.validKey(key)) return std::nullopt;
    const std::int32_t index = m.indexOf(m.canonical(key));
    if (index == kNoAnchor) return std::nullopt;
    const Impl::SlopeState* state = m.slopeOf(std::size_t(index));
    if (!state) return std::nullopt;
    return Impl::currentSlope(m.pool[std::size_t(index)], *state);
}

AnchorStore::InsertResult AnchorStore::insert(const LatticeKey& key, const ShRgb& sh,
                                              const glm::dvec3& capturedPosition_m,
                                              double lifetime_s, double timeOfDay_h,
                                              const ShSlope* slope, bool settled) {
    if (slope && (!finiteSh(slope->dx, kMaxCoefficient) || !finiteSh(slope->dz, kMaxCoefficient) ||
                  !(slope->validity_m >= 0.0f) || !std::isfinite(slope->validity_m)))
        slope = nullptr;
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
    const bool instant = settled || m.settings.blendTime_s <= 0.0;
    const std::int32_t index = m.indexOf(c);
    if (index != kNoAnchor) {
        // Refresh (thesis appendix B: the anchor interpolates slowly to the new coefficients).
        Anchor& a = m.pool[index];
        const float presenceBefore = a.presence;
        a.presence = settled ? 1.0f : Impl::presenceAt(a, m.now, m.settings.blendTime_s);
        if (instant || a.presence != presenceBefore) m.touchField(c.level);
        m.setFadeDirection(a, false);
        // Blend from what interpolation showed (relight included), so a refresh is no pop.
        if (slope) {
            Impl::SlopeState& state = *m.slopeAt(index);
            state.from = state.has ? Impl::currentSlope(a, state) : *slope;
            state.slope = *slope;
            state.has = true;
        } else if (std::size_t(index) < m.slopes.size()) {
            m.slopes[std::size_t(index)].has = false;
        }
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
    m.setIndex(c, slot);
    if (slope) *m.slopeAt(slot) = {*slope, *slope, true};
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
    m.pruneIndex(c.level);
    ++m.counters.prunes;
    return true;
}

void AnchorStore::clear() {
    Impl& m = *impl_;
    m.clearIndex();
    m.pool.clear();
    m.alive.clear();
    m.freeList.clear();
    m.slopes.clear();
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
        m.pruneIndex(L);
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
        FieldAnchor f;
        f.level = a.key.level, f.i = a.key.i, f.k = a.key.k, f.presence = weight;
        f.value = a.relight == 1.0f ? a.current : a.current * a.relight;
        if (settings.gradients)
            if (const SlopeState* state = slopeOf(n)) {
                f.hasSlope = true;
                f.slope = currentSlope(a, *state);
            }
        anchors.push_back(f);
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
                  m.freeList.capacity() * sizeof(std::int32_t) +
                  m.slopes.capacity() * sizeof(Impl::SlopeState);
    s.gridBytes = m.indexBytes();
    return s;
}

}  // namespace amb
