// AnchorStoreImpl.h — the inside of AnchorStore (AnchorStore.h), private to AnchorStore.cpp and
// AnchorStoreVdb.cpp: the anchor pool with its free list, the lattice's numbers and the
// interpolated field. The per-level index grids are OpenVDB's, and only AnchorStoreVdb.cpp
// includes OpenVDB (slow to compile): here they are the incomplete AnchorIndexLevel, reached
// through Impl's index functions.
#pragma once

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <vector>

#include "lighting/AnchorField.h"
#include "lighting/AnchorStore.h"
#include "world/Error.h"

namespace amb {

inline constexpr std::int32_t kNoAnchor = -1;
inline constexpr std::int64_t kCoordLimit = 2147483647LL;

// True when every coefficient is finite and within `limit`.
bool finiteSh(const ShRgb& sh, float limit);

inline double clamp01(double v) {
    return v < 0.0 ? 0.0 : (v > 1.0 ? 1.0 : v);
}

// One level's index grid, (i, 0, k) -> pool slot (AnchorStoreVdb.cpp).
struct AnchorIndexLevel;

struct AnchorStore::Impl {
    AnchorStoreSettings settings;
    int levels = 1;
    std::array<double, kMaxAnchorLevels> spacing{};      // s_L
    std::array<std::int64_t, kMaxAnchorLevels> scale{};  // fine units per level-L unit: 3^(F-L)
    double fineSpacing = 1.0;
    std::vector<AnchorIndexLevel> grids;  // per level: (i, 0, k) -> pool index
    std::vector<Anchor> pool;
    std::vector<std::uint8_t> alive;
    std::vector<std::int32_t> freeList;
    // Measured slopes (settings.gradients) by pool slot: the latest capture's and the one its
    // blend started from; empty until the first slope arrives.
    struct SlopeState {
        ShSlope slope, from;
        bool has = false;
    };
    std::vector<SlopeState> slopes;
    SlopeState* slopeAt(std::int32_t slot) {
        if (slopes.size() < pool.size()) slopes.resize(pool.size());
        return &slopes[std::size_t(slot)];
    }
    const SlopeState* slopeOf(std::size_t slot) const {
        return slot < slopes.size() && slopes[slot].has ? &slopes[slot] : nullptr;
    }
    // The slope interpolation reads: blended as the value, relit.
    static ShSlope currentSlope(const Anchor& a, const SlopeState& s);
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

    explicit Impl(const AnchorStoreSettings& s);  // AnchorStoreVdb.cpp: makes the level grids
    ~Impl();

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
    // The level grids (AnchorStoreVdb.cpp): the pool slot at a canonical key (kNoAnchor where
    // none), set and unset one, prune a level's emptied branches, empty all, their bytes.
    std::int32_t indexOf(const LatticeKey& canonicalKey) const;
    void setIndex(const LatticeKey& canonicalKey, std::int32_t slot);
    void unsetIndex(const LatticeKey& canonicalKey);
    void pruneIndex(int level);
    void clearIndex();
    std::size_t indexBytes() const;
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
            if (std::size_t(index) < slopes.size()) slopes[std::size_t(index)] = SlopeState{};
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
        unsetIndex(key);
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

}  // namespace amb
