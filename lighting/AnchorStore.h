// AnchorStore.h — the sparse, hierarchical store of ambience anchors along the ground plane
// (thesis 7.5, 7.6, 8.4, 9.3; docs/ARCHITECTURE.md "Anchor store"), with blending and smooth
// (hierarchical bicubic Hermite) interpolation.
//
// [SECTION] Lattice        Level L has spacing s_L = s_0 / 3^L (3 x 3 subdivision, the thesis'
//                          SHGraph restricted to the ground). A level-L point (i, k) lies at
//                          (i s_L, k s_L) on the XZ plane; it is also level-(L+1) point (3i, 3k)
//                          (the centre child shares its parent's position and anchor). Every point
//                          is stored once, under its *canonical* key: the coarsest level holding
//                          it. All positions are integer multiples of the finest spacing, so keys
//                          are exact integers however far from the origin (|x|, |z| < 2^31 s_fine).
// [SECTION] Anchors        One coefficient set per lattice point: current value, target value,
//                          blend state, presence, capture time, lifetime, captured position.
// [SECTION] Time           advance(now_s) runs blending, presence fades, regeneration requests
//                          and expiry on the store's simulation clock (seconds, monotonic; the
//                          time of day is only recorded, so its wrap at 24 h does not matter).
// [SECTION] Lifetime       anchorLifetime_s(): how long a capture stays valid while the sun moves.
// [SECTION] Interpolation  interpolate(x, z): level by level, what each level adds to the
//                          coarser ones, bicubic Hermite between values and gradients (C1),
//                          missing points from the coarser levels (thesis 7.6's example made
//                          hierarchical and smooth; see AnchorStore::interpolate).
// [SECTION] Files          save()/load() as .vdb (OpenVDB grids, inspectable with vdb_print).
//
// OpenVDB is used only inside AnchorStoreVdb.cpp (one int32 grid per level mapping (i, 0, k) to
// an index into a contiguous anchor pool with a free list; in memory with smaller tree nodes than
// the standard Int32Grid, in files as standard Int32Grids); this header and AnchorStore.cpp (the
// rest of the store, its inside in AnchorStoreImpl.h) do not include it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "lighting/SH.h"
#include "lighting/ShGradient.h"

namespace amb {

inline constexpr int kMaxAnchorLevels = 8;

struct AnchorStoreSettings {
    // Spacing of the coarsest level, s_0 [m]. Level L has s_L = s_0 / 3^L.
    double coarsestSpacing_m = 243.0;
    // Number of levels (1..kMaxAnchorLevels); the finest spacing is s_0 / 3^(levels - 1)
    // (3 m by default: 243, 81, 27, 9, 3).
    int levels = 5;
    // Time over which a refreshed anchor moves from its old to its new coefficients, and over
    // which a new anchor fades in (or an expired one fades out) of the interpolation [s].
    // (why this value: docs/TUNING.md "Anchor store")
    double blendTime_s = 1.0;
    // Lifetime (see anchorLifetime_s): the sun may move this far across the sky before a capture
    // is considered out of date [rad] (2 degrees).
    double allowedSunAngle_rad = 0.0349;
    double minLifetime_s = 5.0;    // lower clamp of the lifetime [s]
    double maxLifetime_s = 600.0;  // upper clamp (also the lifetime when time stands still) [s]
    // An anchor asks for regeneration once this fraction of its lifetime has passed.
    double regenerateFraction = 0.75;
    // nearestAnchor() searches searchCells x s_L on the level-L lattice.
    int searchCells = 2;
    // Reach into holes (AnchorField.h, G_L): a missing lattice point of level L takes the coarser
    // levels' value corrected by the residuals of the anchors within reachCells x s_L (kernel
    // (1 - (d / R)^2)^2): the level's own and, with weight finerWeight each, the finer levels'.
    // At level 0 (the coarsest; its coarser value is the fallback, the sky over flat ground) the
    // reach is coarseReachCells (both in cells of that level's spacing; finerWeight in [0, 1]).
    // See docs/ARCHITECTURE.md, "Interpolation". (why these values: docs/TUNING.md "Anchor store")
    int reachCells = 1;
    int coarseReachCells = 2;
    double finerWeight = 1.0;
    // Interpolation between lattice points (AnchorField.h): bicubic Hermite, smooth (C1: no
    // kink where a moving object crosses a lattice line), or bilinear (C0: cheaper lookups).
    bool smoothInterpolation = true;
    // Points that do not move (terrain patch corners, road vertices: interpolateFixed) read the
    // bilinear cells of the same anchors, kept beside the smooth ones. The draw interpolates
    // their colours linearly across each patch, so a kink at a lattice line cannot show there.
    // false: fixed points read interpolate() too. (why this value: docs/TUNING.md "Anchor store")
    bool bilinearFixedPoints = true;
    // Each probe also measures how its SH change as it moves along the ground (its
    // translational gradient, from the capture's distances: lighting/ShGradient.h), and the
    // smooth cells take that as the slope at the anchor's point, weighted by its presence,
    // instead of the central differences of its neighbours (AnchorField.h, H_L): interpolation
    // extrapolates first order from each anchor. It acts through the smooth cells only, so
    // fixed points feel it when bilinearFixedPoints is off. (why this value: docs/TUNING.md
    // "Anchor store")
    bool gradients = false;
};

// Spacing of the finest level, s_0 / 3^(levels - 1) [m].
inline double finestSpacing_m(const AnchorStoreSettings& settings) {
    double cells = 1.0;
    for (int L = 1; L < settings.levels; ++L) cells *= 3.0;
    return settings.coarsestSpacing_m / cells;
}
// The smallest finest spacing the settings readers accept [m]. Keys are int32 on the finest
// lattice, and every point up to 1e8 m from the origin (the largest coordinate a replay may
// hold) must have one: 1e8 m / (2^31 - 1) = 0.047 m. (OpenVDB transforms also need spacings
// above ~1.4e-5 m.)
inline constexpr double kMinFinestSpacing_m = 0.05;

// A lattice point: level and integer coordinates on that level's lattice.
struct LatticeKey {
    int level = 0;
    std::int32_t i = 0;
    std::int32_t k = 0;
    bool operator==(const LatticeKey& o) const { return level == o.level && i == o.i && k == o.k; }
    bool operator!=(const LatticeKey& o) const { return !(*this == o); }
};

// Blends and fades run linearly in time and are read through smoothstep, 3t^2 - 2t^3: the value
// and its rate are continuous when a blend starts and ends, so a point moving through the store
// sees no kink there (a linear blend of a step J over N frames gives a second difference of J / N
// at each end; smoothstep gives at most 6 J / N^2). Halfway is still halfway.
inline float easeInOut(float t) {
    t = t < 0.0f ? 0.0f : (t > 1.0f ? 1.0f : t);
    return t * t * (3.0f - 2.0f * t);
}

// One anchor (the thesis' CoefficientAnchor, appendix B). Plain data.
struct Anchor {
    ShRgb current;    // what interpolation uses now
    ShRgb target;     // the latest capture
    ShRgb blendFrom;  // value of `current` when the blend towards `target` began
    double blendStart_s = 0.0;
    float blendProgress = 1.0f;     // [0, 1], linear in time; current = lerp(blendFrom, target,
                                    // easeInOut(blendProgress))
    float presence = 1.0f;          // [0, 1], linear in time (fade in / fade out); its weight in
                                    // interpolation is easeInOut(presence)
    float presenceFrom = 1.0f;      // fade state: presence at presenceChange_s, from which it
    double presenceChange_s = 0.0;  // rises (or falls, once expired) by dt / blendTime
    double birth_s = 0.0;           // store clock at first insertion
    double captureTime_s = 0.0;     // store clock at the latest capture
    double captureTimeOfDay_h = 0.0;
    double lifetime_s = 0.0;             // validity of the latest capture
    glm::dvec3 capturedPosition_m{0.0};  // where the probe actually was (moved out of solids)
    LatticeKey key;                      // canonical key
    bool regenerationRequested = false;  // age >= regenerateFraction x lifetime
    bool expired = false;                // age >= lifetime: fading out, then removed
    float relight = 1.0f;                // read as current x relight (AnchorStore::relight)

    double age_s(double now_s) const { return now_s - captureTime_s; }
};

// Lifetime of a capture from how fast the lighting changes (thesis 7.5.3: samples expire at a
// rate set by how fast the light changes; docs/ARCHITECTURE.md "Blending"):
//     lifetime = clamp(allowedSunAngle / (sunSpeed x |timeRate|), minLifetime, maxLifetime)
// with sunSpeed the sun's angular speed across the sky [rad per hour of day] and timeRate the
// hours of day that pass per simulated second (1/3600 in real time). Time standing still gives
// maxLifetime. Example: real time, 45 deg N at the solstice (0.24 rad/h), 2 deg -> 524 s;
// a one-hour-per-minute time-lapse -> 8.7 s.
double anchorLifetime_s(const AnchorStoreSettings& settings, double sunSpeed_radPerHour,
                        double timeRate_hPerS);

// Where interpolate() answered a point, for tests and debug overlays: the level of the cell
// used and the anchors at its corners.
struct InterpolationDetail {
    struct Used {
        LatticeKey key;
        int quadrant = 0;  // 0: dx >= 0, dz >= 0; 1: dx < 0, dz >= 0; 2: dx < 0, dz < 0;
                           // 3: dx >= 0, dz < 0 (dx, dz = anchor - query)
        double distance_m = 0.0;
        double weight = 0.0;  // its corner's Hermite value weight x easeInOut(presence): the
                              // share of its own value (the rest: neighbours, coarser levels)
    };
    std::vector<Used> used;  // present anchors at the corners of the cell used (or the one hit)
    int level = -1;          // level of the cell used; -1 with `fallback`
    bool exact = false;      // the query lies on a present anchor: `used` is that one alone
    bool fallback = false;   // no anchor in reach: the store's fallback value is returned
};

struct AnchorStoreStatistics {
    std::size_t anchors = 0;
    std::array<std::size_t, kMaxAnchorLevels> anchorsPerLevel{};
    std::size_t poolBytes = 0;  // anchor pool and free list (capacity, not size)
    std::size_t gridBytes = 0;  // OpenVDB trees (Grid::memUsage of every level grid)
    std::size_t bytes() const { return poolBytes + gridBytes; }
    std::int64_t inserted = 0;   // new anchors
    std::int64_t refreshed = 0;  // captures that replaced an anchor's target
    std::int64_t rejected = 0;   // captures refused for NaN/Inf/out-of-range values
    std::int64_t expired = 0;    // anchors removed at the end of their lifetime
    std::int64_t prunes = 0;     // tree prunes run after removals
};

class AnchorStore {
  public:
    explicit AnchorStore(const AnchorStoreSettings& settings = {});
    ~AnchorStore();
    AnchorStore(AnchorStore&&) noexcept;
    AnchorStore& operator=(AnchorStore&&) noexcept;
    AnchorStore(const AnchorStore&) = delete;
    AnchorStore& operator=(const AnchorStore&) = delete;

    const AnchorStoreSettings& settings() const;
    // New settings in place, but for the lattice (coarsestSpacing_m and levels keep theirs):
    // blends, fades and lifetimes read them from the next advance on, and the field is rebuilt
    // with the new reach and interpolation by the next lookup.
    void retune(const AnchorStoreSettings& settings);
    int levels() const;
    int finestLevel() const { return levels() - 1; }
    double spacing_m(int level) const;

    // ---- Lattice ----
    // The level-`level` lattice point nearest to (x, z) (ties round up), in canonical form.
    LatticeKey keyNear(double x_m, double z_m, int level) const;
    // The same point under its canonical (coarsest) level.
    LatticeKey canonical(const LatticeKey& key) const;
    // World XZ position of a lattice point [m] (exact multiple of the finest spacing).
    double keyX_m(const LatticeKey& key) const;
    double keyZ_m(const LatticeKey& key) const;
    // Coordinates on the finest lattice (exact integers).
    std::int64_t fineI(const LatticeKey& key) const;
    std::int64_t fineK(const LatticeKey& key) const;

    // ---- Anchors ----
    // The anchor at a lattice point (any level naming it), or nullptr. The pointer stays valid
    // until the next insert, remove, advance or load.
    const Anchor* find(const LatticeKey& key) const;
    // The measured slope of the anchor at a lattice point (AnchorStoreSettings::gradients),
    // blended as its value is (from the slope before the latest refresh, by easeInOut of the
    // blend) and relit: none without an anchor, without gradients or for an anchor read from a
    // file. (Kept beside the anchor pool, allocated by the first slope: a store without
    // gradients pays nothing for them.)
    std::optional<ShSlope> slope(const LatticeKey& key) const;
    std::size_t size() const;
    // Calls f for every anchor (unspecified order).
    void forEach(const std::function<void(const Anchor&)>& f) const;

    enum class InsertResult { Inserted, Refreshed, Rejected };
    // A capture at lattice point `key` taken from `capturedPosition_m` at the current clock.
    // New point: the anchor starts from the value the store interpolates there now and blends
    // to `sh` over blendTime_s while fading into the interpolation (presence 0 -> 1), so the
    // insertion changes nothing anywhere at this instant (thesis 7.6). Existing point: its
    // current value blends to `sh` over blendTime_s and its lifetime restarts.
    // Any coefficient that is NaN, infinite or above kMaxCoefficient, a non-finite position, a
    // non-positive lifetime or a key outside the lattice's integer range (|i|, |k| x 3^(F-L)
    // above 2^31 - 1) rejects the capture (counted in statistics().rejected).
    // `slope`: the capture's translational gradient (AnchorStoreSettings::gradients), kept when
    // finite and in range; a refresh blends the anchor's slope to it as it blends the value.
    // `settled`: no blend and no fade, the capture is shown at once (a prime, CaptureCore.h:
    // where the store had nothing to show but its fallback, before the frame is drawn).
    InsertResult insert(const LatticeKey& key, const ShRgb& sh,
                        const glm::dvec3& capturedPosition_m, double lifetime_s,
                        double timeOfDay_h = 0.0, const ShSlope* slope = nullptr,
                        bool settled = false);
    static constexpr float kMaxCoefficient = 1.0e15f;
    // Sets every anchor's relight factor (finite, > 0; anything else counts as 1): interpolation
    // reads an anchor as current x relight. A refresh bakes the factor into the blend's start.
    void relight(const std::function<float(const Anchor&)>& factor);
    // Removes an anchor at once (no fade). Returns false if there was none.
    bool remove(const LatticeKey& key);
    void clear();

    // Advances the clock to now_s (>= the current clock; earlier times are ignored): blends,
    // fades presence, flags regeneration, starts fading out anchors whose lifetime is over and
    // removes those fully faded, pruning the trees after removals. dt = 0 changes nothing; a long
    // step (a hitch) completes blends and fades at once.
    void advance(double now_s);
    double now_s() const;
    // Shortens every anchor's remaining lifetime to at most `remaining_s` (e.g. after a jump in
    // the time of day) and flags them for regeneration.
    void expireAllWithin(double remaining_s);
    // Keys of anchors that asked for regeneration, most urgent (oldest relative to lifetime)
    // first.
    std::vector<LatticeKey> regenerationRequests() const;

    // ---- Interpolation (thesis 7.6, 9.3) ----
    // Value used where no anchor is in reach (e.g. the sky-only SH, see AmbienceVolume.h).
    void setFallback(const ShRgb& sh);
    const ShRgb& fallback() const;
    // The interpolated SH at ground point (x, z) (AnchorField.h has the formulas):
    //  1. Level by level, coarsest first, each lattice point c of level L gets a value C_L(c).
    //     A point holding a level-L anchor of presence weight p has p x (current x relight) +
    //     (1 - p) x (the value without it); a point without one takes the coarser levels'
    //     interpolated value there (the fallback below level 0), corrected by the weighted mean
    //     of the residuals (anchor minus coarser value) of the anchors within reachCells x s_L
    //     (coarseReachCells at level 0): this level's and, with weight finerWeight, the finer
    //     levels', in part where they cover it thinly.
    //  2. Each point also gets a gradient: the coarser field's own where the level adds nothing,
    //     the central differences of its neighbours' values where the level's anchors cover it,
    //     blended by that coverage. The cells in reach of the level's anchors are bicubic
    //     Hermite between their corners' values and gradients; a lookup answers from the finest
    //     such cell (elsewhere a level equals the coarser one exactly).
    //  Properties: continuous with a continuous gradient everywhere (across lattice lines,
    //  partly present cells and levels), so a point moving at a steady speed sees no kink and
    //  no pop; Lipschitz (AnchorField::slopeBound); exact on a present anchor (within 1e-9 m:
    //  its value bit for bit); a new anchor (p = 0) changes nothing, and as its presence grows
    //  the pattern moves from the old to the new one (thesis 7.6); a field bilinear on a
    //  complete lattice is reproduced; always finite; a lookup reads one cell per level,
    //  finest first (bounded), from a cache rebuilt by the first lookup after the anchors
    //  change.
    //  Relation to the thesis: 9.3's four-quadrant rule keeps the nearest anchor per quadrant
    //  to find a neighbourhood when the lattice is incomplete, and weights it by inverse
    //  distance, which jumps whenever the chosen set changes; 7.6's worked example weights the
    //  four surrounding sets bilinearly, which is continuous but kinks at every lattice line.
    //  Here the four corners are the cell's own, a missing corner is filled from the coarser
    //  levels (the lattice's holes need no search), and the Hermite cubic removes the kinks.
    // Safe to call from several threads at once while nothing modifies the store.
    ShRgb interpolate(double x_m, double z_m, InterpolationDetail* detail = nullptr) const;
    // interpolate() at `count` points (x_m[i], z_m[i]) into out[i]: one cache check for the
    // batch, then the lookups (in parallel with TBB for large batches). The per-frame path.
    void interpolateMany(std::size_t count, const double* x_m, const double* z_m, ShRgb* out) const;
    // The value for a point that does not move (a terrain patch corner, a road vertex): the
    // same rule on bilinear cells when bilinearFixedPoints (continuous, exact on anchors, a new
    // anchor changes nothing; kinks at lattice lines), else interpolate().
    ShRgb interpolateFixed(double x_m, double z_m) const;
    void interpolateFixedMany(std::size_t count, const double* x_m, const double* z_m,
                              ShRgb* out) const;
    // Per coefficient (ShRgb order, c[k][ch] at 3k + ch), a bound on the gradient of
    // interpolate() along x and along z [per m] (AnchorField::slopeBound).
    std::array<double, 27> interpolationSlopeBound() const;
    // The nearest anchor of presence > 0 on the level-L lattice within searchCells x s_L,
    // finest level first (ties to the smaller key), or nullptr: the `nearest` baseline.
    const Anchor* nearestAnchor(double x_m, double z_m) const;
    // Memory of the interpolation cache (derived from the anchors, not counted in bytes()).
    std::size_t interpolationCacheBytes() const;

    // ---- Memory ----
    AnchorStoreStatistics statistics() const;

    // ---- Files ----
    // Writes the store as a .vdb file: per level an Int32Grid "anchor_index_L<n>" (voxel (i, 0, k)
    // -> anchor number, transform scaled by s_L), and the payload on the finest lattice
    // (voxel (I, 0, K), transform scaled by the finest spacing): Vec3SGrids "sh_current_<k>",
    // "sh_target_<k>", "sh_blend_from_<k>" (k = 0..8, RGB), a Vec3DGrid "captured_position",
    // FloatGrids "age_s", "lifetime_s", "blend_elapsed_s", "presence", "since_birth_s",
    // "capture_time_of_day_h", Int32Grid "flags". File metadata: "format"
    // ("ambience-anchor-store-v2"), "coarsest_spacing_m", "levels", "anchors" (int32), "clock_s"
    // and "checksum_crc32": 8 hex digits, the CRC-32 of the whole file with these digits as '0'
    // (AnchorStoreFile.h). Grids are compressed with OpenVDB's "active values" only (no Blosc or
    // zlib blocks) and carry no delayed-load metadata; the file is written beside `path` and
    // renamed over it. Throws InputError if the file cannot be written.
    void save(const std::string& path) const;
    // Replaces the contents by a file written by save(). The file's lattice (s_0, levels) must
    // equal this store's; ages are kept relative to the current clock. Throws InputError (and
    // leaves the store and the file unchanged) for a missing, unreadable, corrupt, truncated,
    // oversized or inconsistent file: the file is read whole (at most kMaxAnchorStoreFileBytes),
    // its checksum verified and its OpenVDB structure walked (AnchorStoreFile.h) before OpenVDB
    // parses it from memory with delayed loading off; then every grid, count and value is
    // checked (coefficients finite and within kMaxCoefficient, so no NaN enters the store).
    // Measured slopes (AnchorStoreSettings::gradients) are not in the file: a loaded anchor has
    // none until its next capture, and its cells take the lattice's slopes meanwhile.
    void load(const std::string& path);

  private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace amb
