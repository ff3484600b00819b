// Baselines.cpp — the baseline ambience methods (see Baselines.h).
//
// [SECTION] Settings from JSON
// [SECTION] Shared machinery (CapturingBaseline)
// [SECTION] ScrollingGridMethod
// [SECTION] ReactiveCacheMethod
// [SECTION] PerObjectMethod
// [SECTION] NearestAnchorMethod
// [SECTION] Factory
#include "lighting/Baselines.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <glm/geometric.hpp>

#include "lighting/AnchorField.h"
#include "lighting/AnchorStore.h"
#include "lighting/NearField.h"
#include "lighting/ProbeEnvironment.h"
#include "lighting/SettingsSchema.h"
#include "world/Error.h"

namespace amb {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Cell coordinates beyond this are not formed (x / s must convert to int64 exactly; points that
// far out get the fallback).
constexpr double kMaxCell = 1.0e15;

CellKey cellKey(const ProbeKey& key) {
    return {key.i, key.k};
}

// floor(x / s) as an integer cell, if representable.
std::optional<std::int64_t> cellOf(double x_m, double spacing_m) {
    const double u = std::floor(x_m / spacing_m);
    if (!(std::fabs(u) <= kMaxCell)) return std::nullopt;
    return std::int64_t(u);
}

// Non-negative remainder of a by m (m > 0).
std::int64_t positiveModulo(std::int64_t a, std::int64_t m) {
    const std::int64_t r = a % m;
    return r < 0 ? r + m : r;
}

// Ordering of candidate probes: nearest the camera first, ties by cell.
struct Rank {
    double distance2 = std::numeric_limits<double>::infinity();
    CellKey key;
    bool operator<(const Rank& o) const {
        return distance2 != o.distance2 ? distance2 < o.distance2 : key < o.key;
    }
};

bool contains(const std::vector<CellKey>& keys, const CellKey& key) {
    return std::find(keys.begin(), keys.end(), key) != keys.end();
}

// Bilinear interpolation over the four lattice points (i s, k s) at the corners of the cell
// holding (x, z), renormalised over the corners `lookup` returns a value for (lookup(cell) gives
// a const ShRgb* or null). Corners of weight 0 are not looked up, so a query on a lattice point
// returns that point's value exactly. Returns false when no corner with weight > 0 has a value.
template <class Lookup>
bool bilinear(double x_m, double z_m, double spacing_m, const Lookup& lookup, ShRgb& out) {
    if (!std::isfinite(x_m) || !std::isfinite(z_m)) return false;
    const double u = x_m / spacing_m, v = z_m / spacing_m;
    const double fu = std::floor(u), fv = std::floor(v);
    if (!(std::fabs(fu) <= kMaxCell && std::fabs(fv) <= kMaxCell)) return false;
    const double tx = u - fu, tz = v - fv;
    const std::int64_t i = std::int64_t(fu), k = std::int64_t(fv);
    const CellKey corners[4] = {{i, k}, {i + 1, k}, {i, k + 1}, {i + 1, k + 1}};
    const double weights[4] = {(1.0 - tx) * (1.0 - tz), tx * (1.0 - tz), (1.0 - tx) * tz, tx * tz};
    std::array<double, 3 * kShCoefficients> sum{};
    double weightSum = 0.0;
    for (int c = 0; c < 4; ++c) {
        if (!(weights[c] > 0.0)) continue;
        const ShRgb* value = lookup(corners[c]);
        if (!value) continue;
        weightSum += weights[c];
        for (int n = 0; n < kShCoefficients; ++n) {
            for (int ch = 0; ch < 3; ++ch) sum[3 * n + ch] += weights[c] * value->c[n][ch];
        }
    }
    if (!(weightSum > 0.0)) return false;
    for (int n = 0; n < kShCoefficients; ++n) {
        for (int ch = 0; ch < 3; ++ch) out.c[n][ch] = float(sum[3 * n + ch] / weightSum);
    }
    return true;
}

}  // namespace

// ---- Settings from JSON -------------------------------------------------------------------------

BaselineSettings baselineSettingsFromJson(const std::string& jsonText, const std::string& where) {
    return baselineSettingsSchema().read(jsonText, where);
}

// ---- Shared machinery ---------------------------------------------------------------------------

std::size_t CellKeyHash::operator()(const CellKey& key) const noexcept {
    return hashLatticeCell(key.i, key.k);
}

std::size_t hashMapBytes(std::size_t buckets, std::size_t elements, std::size_t elementBytes) {
    // A node holds the next pointer, the cached hash (conservatively) and the element; glibc's
    // malloc adds an 8-byte header, rounds to 16 bytes and allocates at least 32.
    const std::size_t node = sizeof(void*) + sizeof(std::size_t) + elementBytes;
    const std::size_t chunk = std::max<std::size_t>(32, (node + 8 + 15) / 16 * 16);
    return buckets * sizeof(void*) + elements * chunk;
}

CapturingBaseline::CapturingBaseline(CubeCapture& capture, const ProbeEnvironment& environment,
                                     const BaselineSettings& settings)
    : environment_(environment), settings_(settings), core_(capture, environment, settings.capture) {
    lifetime_s_ = currentLifetime_s();
    core_.setOwnField([this](double x_m, double z_m) { return shAt(x_m, z_m); });
}

CapturingBaseline::~CapturingBaseline() = default;

double CapturingBaseline::currentLifetime_s() const {
    return anchorLifetime_s(AnchorStoreSettings{}, environment_.sunAngularSpeed_radPerHour(),
                            core_.timeRate_hPerS());
}

bool CapturingBaseline::isStale(double captureTime_s) const {
    return captureTime_s < core_.lastJump_s() || core_.time_s() - captureTime_s > lifetime_s_;
}

double CapturingBaseline::cameraDistance2(double x_m, double z_m) const {
    const glm::dvec3& camera = core_.camera_m();
    const double dx = x_m - camera.x, dz = z_m - camera.z;
    return dx * dx + dz * dz;
}

void CapturingBaseline::predictStage(const glm::dvec3& cameraPosition_m,
                                     const glm::dvec3& cameraVelocity_mps, double timeOfDay_h,
                                     double dt_s) {
    core_.beginFrame(cameraPosition_m, cameraVelocity_mps, timeOfDay_h, dt_s);
    core_.addPredictTime(pendingPredict_s_);  // work recorded since the last frame (lookups)
    pendingPredict_s_ = 0.0;
    const Clock::time_point t0 = Clock::now();
    lifetime_s_ = currentLifetime_s();
    updateStructure();
    core_.addPredictTime(secondsSince(t0));
}

void CapturingBaseline::captureStage() {
    // A probe whose point left the method's structure (scrolled out, forgotten) is not finished.
    if (core_.job() && !wantsProbe(cellKey(core_.job()->key))) core_.abortJob();
    const double aside_m = settings_.capture.maxAside_m;
    core_.captureFaces([&](const std::vector<ProbeKey>& busyKeys) -> std::optional<amb::ProbeRequest> {
        std::vector<CellKey> busy;
        for (const ProbeKey& k : busyKeys) busy.push_back(cellKey(k));
        const std::optional<ProbeRequest> request = nextProbe(busy);
        if (!request) return std::nullopt;
        return amb::ProbeRequest{ProbeKey{0, request->key.i, request->key.k}, request->x_m,
                                 request->z_m, aside_m};
    });
}

void CapturingBaseline::storeStage() {
    const Clock::time_point t0 = Clock::now();
    for (const CompletedProbe& c : core_.takeCompleted()) {
        const CellKey key = cellKey(c.job.key);
        if (wantsProbe(key)) storeProbe(key, c.sh, c.job.startTime_s);
    }
    core_.addStoreTime(secondsSince(t0));
}

MethodStatistics CapturingBaseline::methodStatistics() const {
    MethodStatistics m = core_.statistics();
    m.probes = probesHeld();
    m.bytes = bytesHeld();
    return m;
}

// ---- ScrollingGridMethod ------------------------------------------------------------------------

ScrollingGridMethod::ScrollingGridMethod(CubeCapture& capture, const ProbeEnvironment& environment,
                                         const BaselineSettings& settings)
    : CapturingBaseline(capture, environment, settings),
      size_(settings.gridSize),
      spacing_m_(settings.gridSpacing_m),
      slots_(std::size_t(settings.gridSize) * std::size_t(settings.gridSize)) {
    AMB_CHECK(settings.gridSize >= 1);
    AMB_CHECK(settings.gridSpacing_m > 0.0);
    AMB_CHECK(settings.hysteresis >= 0.0 && settings.hysteresis <= 1.0);
}

std::size_t ScrollingGridMethod::slotOf(const CellKey& cell) const {
    return std::size_t(positiveModulo(cell.i, size_) + size_ * positiveModulo(cell.k, size_));
}

bool ScrollingGridMethod::inGrid(const CellKey& cell) const {
    return haveOrigin_ && cell.i >= origin_.i && cell.i < origin_.i + size_ &&
           cell.k >= origin_.k && cell.k < origin_.k + size_;
}

void ScrollingGridMethod::updateStructure() {
    // The grid's centre (origin + (G - 1) / 2) at the lattice position nearest the camera: for
    // even G the camera lies in the central cell, for odd G nearest the central probe.
    const glm::dvec3& p = camera_m();
    const auto lowest = [&](double x_m) -> std::optional<std::int64_t> {
        if (size_ % 2 == 0) {
            const auto c = cellOf(x_m, spacing_m_);
            if (!c) return std::nullopt;
            return *c - (size_ / 2 - 1);
        }
        const auto c = cellOf(x_m + 0.5 * spacing_m_, spacing_m_);
        if (!c) return std::nullopt;
        return *c - (size_ - 1) / 2;
    };
    const auto i0 = lowest(p.x), k0 = lowest(p.z);
    if (!i0 || !k0) return;  // the camera is too far out to form cells: keep the grid
    const CellKey origin{*i0, *k0};
    if (haveOrigin_ && origin == origin_) return;
    origin_ = origin;
    haveOrigin_ = true;
    // Scroll: slot (a, b) holds the one grid cell congruent to (a, b) modulo G.
    for (int b = 0; b < size_; ++b) {
        for (int a = 0; a < size_; ++a) {
            const CellKey cell{origin_.i + positiveModulo(a - origin_.i, size_),
                               origin_.k + positiveModulo(b - origin_.k, size_)};
            Slot& slot = slots_[std::size_t(a) + std::size_t(size_) * std::size_t(b)];
            if (slot.cell == cell && slot.valid) continue;
            if (slot.valid) --validCount_;
            slot.cell = cell;
            slot.valid = false;
            slot.updates = 0;
        }
    }
}

std::optional<CapturingBaseline::ProbeRequest> ScrollingGridMethod::nextProbe(
    const std::vector<CellKey>& busy) {
    if (!haveOrigin_) return std::nullopt;
    const auto request = [&](const CellKey& cell) {
        return ProbeRequest{cell, double(cell.i) * spacing_m_, double(cell.k) * spacing_m_};
    };
    // Invalid probes first, nearest the camera first.
    if (validCount_ < slots_.size()) {
        Rank best;
        bool found = false;
        for (const Slot& slot : slots_) {
            if (slot.valid || contains(busy, slot.cell)) continue;
            const Rank r{
                cameraDistance2(double(slot.cell.i) * spacing_m_, double(slot.cell.k) * spacing_m_),
                slot.cell};
            if (!found || r < best) best = r;
            found = true;
        }
        if (found) return request(best.key);
    }
    // Otherwise the round-robin over the slots.
    for (std::size_t tries = 0; tries < slots_.size(); ++tries) {
        const Slot& slot = slots_[roundRobin_];
        roundRobin_ = (roundRobin_ + 1) % slots_.size();
        if (!contains(busy, slot.cell)) return request(slot.cell);
    }
    return std::nullopt;
}

bool ScrollingGridMethod::wantsProbe(const CellKey& key) const {
    return inGrid(key);
}

void ScrollingGridMethod::storeProbe(const CellKey& key, const ShRgb& sh, double) {
    Slot& slot = slots_[slotOf(key)];
    if (slot.cell != key) return;
    if (!slot.valid) {
        slot.value = sh;
        slot.valid = true;
        slot.updates = 1;
        ++validCount_;
        return;
    }
    // Hysteresis (DDGI): h of the old value, 1 - h of the new, in double, rounded once.
    const double h = settings().hysteresis;
    for (int n = 0; n < kShCoefficients; ++n) {
        for (int ch = 0; ch < 3; ++ch) {
            slot.value.c[n][ch] =
                float(h * double(slot.value.c[n][ch]) + (1.0 - h) * double(sh.c[n][ch]));
        }
    }
    ++slot.updates;
}

std::optional<ScrollingGridMethod::GridProbe> ScrollingGridMethod::probe(
    const CellKey& cell) const {
    if (!inGrid(cell)) return std::nullopt;
    const Slot& slot = slots_[slotOf(cell)];
    if (!slot.valid || slot.cell != cell) return std::nullopt;
    return GridProbe{slot.value, slot.updates};
}

ShRgb ScrollingGridMethod::shAt(double x_m, double z_m) const {
    bool outside = false;
    const auto lookup = [&](const CellKey& cell) -> const ShRgb* {
        if (!inGrid(cell)) {
            outside = true;
            return nullptr;
        }
        const Slot& slot = slots_[slotOf(cell)];
        return slot.valid && slot.cell == cell ? &slot.value : nullptr;
    };
    ShRgb out;
    if (!bilinear(x_m, z_m, spacing_m_, lookup, out) || outside) return fallback();
    return out;
}

IdealSupport ScrollingGridMethod::idealSupport(double x_m, double z_m) const {
    return bilinearSupport(x_m, z_m, spacing_m_);
}

std::size_t ScrollingGridMethod::bytesHeld() const {
    return slots_.capacity() * sizeof(Slot);
}

// ---- ReactiveCacheMethod ------------------------------------------------------------------------

ReactiveCacheMethod::ReactiveCacheMethod(CubeCapture& capture, const ProbeEnvironment& environment,
                                         const BaselineSettings& settings)
    : CapturingBaseline(capture, environment, settings), spacing_m_(settings.cacheSpacing_m) {
    AMB_CHECK(settings.cacheSpacing_m > 0.0);
}

void ReactiveCacheMethod::noteLookups(std::size_t count, const double* x_m, const double* z_m) {
    const Clock::time_point t0 = Clock::now();
    want(count, x_m, z_m);
    addPendingPredictTime(secondsSince(t0));
}

void ReactiveCacheMethod::want(std::size_t count, const double* x_m, const double* z_m) {
    const double now = simulationTime_s();
    std::optional<CellKey> previous;
    for (std::size_t p = 0; p < count; ++p) {
        if (!std::isfinite(x_m[p]) || !std::isfinite(z_m[p])) continue;
        const auto i = cellOf(x_m[p], spacing_m_), k = cellOf(z_m[p], spacing_m_);
        if (!i || !k) continue;
        const CellKey cell{*i, *k};
        if (previous && *previous == cell) continue;  // neighbouring lookups share cells
        previous = cell;
        for (int b = 0; b <= 1; ++b) {
            for (int a = 0; a <= 1; ++a) {
                entries_[CellKey{cell.i + a, cell.k + b}].lastWanted_s = now;
            }
        }
    }
}

void ReactiveCacheMethod::updateStructure() {
    const double now = simulationTime_s();
    const double timeout = settings().unusedTimeout_s;
    for (auto it = entries_.begin(); it != entries_.end();) {
        if (now - it->second.lastWanted_s > timeout) {
            if (it->second.present) --presentCount_;
            it = entries_.erase(it);
        } else {
            ++it;
        }
    }
    // When a prime is due (the first frame, a teleport: lighting/CaptureCore.h) the camera's
    // own ground point counts as looked up: the draw is about to look there, and the cache
    // has its probes to name before the draw's first lookups at the new place.
    if (primeDue()) {
        const glm::dvec3& c = camera_m();
        want(1, &c.x, &c.z);
    }
}

std::optional<CapturingBaseline::ProbeRequest> ReactiveCacheMethod::nextProbe(
    const std::vector<CellKey>& busy) {
    // Missing probes first, then stale ones; nearest the camera first within each.
    Rank missing, stale;
    bool haveMissing = false, haveStale = false;
    for (const auto& [key, entry] : entries_) {
        if (entry.present && !isStale(entry.captureTime_s)) continue;
        if (contains(busy, key)) continue;
        const Rank r{cameraDistance2(double(key.i) * spacing_m_, double(key.k) * spacing_m_), key};
        if (!entry.present) {
            if (!haveMissing || r < missing) missing = r;
            haveMissing = true;
        } else {
            if (!haveStale || r < stale) stale = r;
            haveStale = true;
        }
    }
    if (!haveMissing && !haveStale) return std::nullopt;
    const CellKey key = haveMissing ? missing.key : stale.key;
    return ProbeRequest{key, double(key.i) * spacing_m_, double(key.k) * spacing_m_};
}

bool ReactiveCacheMethod::wantsProbe(const CellKey& key) const {
    return entries_.count(key) != 0;
}

void ReactiveCacheMethod::storeProbe(const CellKey& key, const ShRgb& sh, double captureTime_s) {
    const auto it = entries_.find(key);
    if (it == entries_.end()) return;
    if (!it->second.present) ++presentCount_;
    it->second.present = true;
    it->second.value = sh;
    it->second.captureTime_s = captureTime_s;
}

ShRgb ReactiveCacheMethod::shAt(double x_m, double z_m) const {
    const auto lookup = [&](const CellKey& cell) -> const ShRgb* {
        const auto it = entries_.find(cell);
        return it != entries_.end() && it->second.present ? &it->second.value : nullptr;
    };
    ShRgb out;
    if (!bilinear(x_m, z_m, spacing_m_, lookup, out)) return fallback();
    return out;
}

IdealSupport ReactiveCacheMethod::idealSupport(double x_m, double z_m) const {
    return bilinearSupport(x_m, z_m, spacing_m_);
}

std::size_t ReactiveCacheMethod::bytesHeld() const {
    return hashMapBytes(entries_.bucket_count(), entries_.size(),
                        sizeof(std::pair<const CellKey, Entry>));
}

// ---- PerObjectMethod ----------------------------------------------------------------------------

PerObjectMethod::PerObjectMethod(CubeCapture& capture, const ProbeEnvironment& environment,
                                 const BaselineSettings& settings)
    : CapturingBaseline(capture, environment, settings),
      size_m_(settings.objectSize_m),
      range_m_(settings.objectRange_m) {
    AMB_CHECK(settings.objectSize_m > 0.0);
    AMB_CHECK(settings.objectRange_m >= 0.0);
}

CellKey PerObjectMethod::objectAt(double x_m, double z_m) const {
    const auto i = cellOf(x_m, size_m_), k = cellOf(z_m, size_m_);
    AMB_CHECK(i && k);
    return {*i, *k};
}

double PerObjectMethod::objectCentreX_m(const CellKey& key) const {
    return (double(key.i) + 0.5) * size_m_;
}

double PerObjectMethod::objectCentreZ_m(const CellKey& key) const {
    return (double(key.k) + 0.5) * size_m_;
}

void PerObjectMethod::updateStructure() {
    const double forget2 = 4.0 * range_m_ * range_m_;
    for (auto it = objects_.begin(); it != objects_.end();) {
        if (cameraDistance2(objectCentreX_m(it->first), objectCentreZ_m(it->first)) > forget2) {
            it = objects_.erase(it);
        } else {
            ++it;
        }
    }
}

std::optional<CapturingBaseline::ProbeRequest> PerObjectMethod::nextProbe(
    const std::vector<CellKey>& busy) {
    // The objects whose centre lies within range: missing first, then stale, nearest first.
    const glm::dvec3& p = camera_m();
    const auto i0 = cellOf(p.x - range_m_, size_m_), i1 = cellOf(p.x + range_m_, size_m_);
    const auto k0 = cellOf(p.z - range_m_, size_m_), k1 = cellOf(p.z + range_m_, size_m_);
    if (!i0 || !i1 || !k0 || !k1) return std::nullopt;
    const double range2 = range_m_ * range_m_;
    Rank missing, stale;
    bool haveMissing = false, haveStale = false;
    for (std::int64_t k = *k0; k <= *k1; ++k) {
        for (std::int64_t i = *i0; i <= *i1; ++i) {
            const CellKey key{i, k};
            const double d2 = cameraDistance2(objectCentreX_m(key), objectCentreZ_m(key));
            if (d2 > range2 || contains(busy, key)) continue;
            const auto it = objects_.find(key);
            if (it == objects_.end()) {
                const Rank r{d2, key};
                if (!haveMissing || r < missing) missing = r;
                haveMissing = true;
            } else if (isStale(it->second.captureTime_s)) {
                const Rank r{d2, key};
                if (!haveStale || r < stale) stale = r;
                haveStale = true;
            }
        }
    }
    if (!haveMissing && !haveStale) return std::nullopt;
    const CellKey key = haveMissing ? missing.key : stale.key;
    return ProbeRequest{key, objectCentreX_m(key), objectCentreZ_m(key)};
}

bool PerObjectMethod::wantsProbe(const CellKey& key) const {
    return cameraDistance2(objectCentreX_m(key), objectCentreZ_m(key)) <= 4.0 * range_m_ * range_m_;
}

void PerObjectMethod::storeProbe(const CellKey& key, const ShRgb& sh, double captureTime_s) {
    objects_[key] = ObjectProbe{sh, captureTime_s};
}

ShRgb PerObjectMethod::shAt(double x_m, double z_m) const {
    if (!std::isfinite(x_m) || !std::isfinite(z_m)) return fallback();
    const auto i = cellOf(x_m, size_m_), k = cellOf(z_m, size_m_);
    if (!i || !k) return fallback();
    const auto it = objects_.find(CellKey{*i, *k});
    return it != objects_.end() ? it->second.value : fallback();
}

std::size_t PerObjectMethod::bytesHeld() const {
    return hashMapBytes(objects_.bucket_count(), objects_.size(),
                        sizeof(std::pair<const CellKey, ObjectProbe>));
}

// ---- NearestAnchorMethod ------------------------------------------------------------------------

AmbienceVolumeSettings NearestAnchorMethod::withoutBlending(AmbienceVolumeSettings settings) {
    settings.store.blendTime_s = kBlendTime_s;
    return settings;
}

NearestAnchorMethod::NearestAnchorMethod(CubeCapture& capture, const ProbeEnvironment& environment,
                                         const AmbienceVolumeSettings& settings,
                                         const RoadNetwork* roads)
    : volume_(capture, environment, withoutBlending(settings), roads) {}

ShRgb NearestAnchorMethod::shAt(double x_m, double z_m) const {
    const AnchorStore& store = volume_.store();
    const Anchor* anchor = store.nearestAnchor(x_m, z_m);
    if (!anchor) return store.interpolate(x_m, z_m);
    return anchor->relight == 1.0f ? anchor->current : anchor->current * anchor->relight;
}

void NearestAnchorMethod::shAt(std::size_t count, const double* x_m, const double* z_m,
                               ShRgb* out) const {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 256),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) {
                              out[i] = shAt(x_m[i], z_m[i]);
                          }
                      });
}

// ---- Factory ------------------------------------------------------------------------------------

std::unique_ptr<AmbienceMethod> makeCapturingMethod(const std::string& name, CubeCapture& capture,
                                                    const ProbeEnvironment& environment,
                                                    const AmbienceVolumeSettings& volumeSettings,
                                                    const BaselineSettings& baselineSettings,
                                                    const RoadNetwork* roads,
                                                    const NearFieldSceneMaker& nearScene) {
    std::unique_ptr<AmbienceMethod> method;
    // The near field as the method's own settings say (see NearField.h "Radii").
    const NearFieldSettings* near = &baselineSettings.capture.nearField;
    if (name == "volume") {
        method = std::make_unique<AmbienceVolume>(capture, environment, volumeSettings, roads);
        near = &volumeSettings.capture.nearField;
    } else if (name == "nearest") {
        method = std::make_unique<NearestAnchorMethod>(capture, environment, volumeSettings, roads);
        near = &volumeSettings.capture.nearField;
    } else if (name == "grid") {
        method = std::make_unique<ScrollingGridMethod>(capture, environment, baselineSettings);
    } else if (name == "reactive") {
        method = std::make_unique<ReactiveCacheMethod>(capture, environment, baselineSettings);
    } else if (name == "object") {
        method = std::make_unique<PerObjectMethod>(capture, environment, baselineSettings);
    } else {
        throw InputError("--ambient", "unknown method '" + name +
                                          "' (expected volume, nearest, grid, reactive or object)");
    }
    if (!near->enabled || !nearScene) return method;
    return std::make_unique<NearFieldMethod>(std::move(method), nearScene(), *near);
}

}  // namespace amb
