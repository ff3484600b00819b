// SettingsSchema.cpp — the keys of the two settings files and what is built on them (see
// SettingsSchema.h).
//
// [SECTION] The keys           one function per part of a file: the store, the scheduler, the
//                              capture keys every capturing method shares, the near field, the
//                              volume's own keys, the baselines' own keys
// [SECTION] The checks         what binds keys together
// [SECTION] The schema         reading, writing, comparing, assigning
// [SECTION] Generated text
#include "lighting/SettingsSchema.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <type_traits>
#include <utility>

#include <nlohmann/json.hpp>

#include "lighting/JsonFields.h"
#include "world/Conventions.h"
#include "world/Error.h"

namespace amb {

namespace {

using Kind = SettingSpec::Kind;
using Cost = SettingSpec::Cost;

// How a key behaves: a slider in ratios, the costly end of its range, whether a change rebuilds
// the method.
struct KeyOptions {
    bool logarithmic = false;
    Cost cost = Cost::None;
    bool rebuilds = false;
};
constexpr KeyOptions kPlain{};
constexpr KeyOptions kLog{true, Cost::None};
constexpr KeyOptions kCostHigh{false, Cost::AtHigh};
constexpr KeyOptions kCostHighLog{true, Cost::AtHigh};
constexpr KeyOptions kCostLowLog{true, Cost::AtLow};
constexpr KeyOptions rebuilding(KeyOptions o) {
    o.rebuilds = true;
    return o;
}

// Collects the keys of a settings struct S. Each call names a key once: its path, unit, range,
// help, and the field, as a function of S returning a reference to it (its type must match the
// kind).
template <typename S>
class Keys {
  public:
    explicit Keys(std::string prefix = "") : prefix_(std::move(prefix)) {}

    template <typename F>
    void number(const char* key, const char* unit, double lo, double hi, const char* help, F field,
                KeyOptions options = kPlain) {
        add<double>(key, Kind::Number, unit, lo, hi, help, field, options);
    }
    template <typename F>
    void integer(const char* key, const char* unit, int lo, int hi, const char* help, F field,
                 KeyOptions options = kPlain) {
        add<int>(key, Kind::Integer, unit, lo, hi, help, field, options);
    }
    template <typename F>
    void boolean(const char* key, const char* help, F field, KeyOptions options = kPlain) {
        add<bool>(key, Kind::Boolean, "", 0.0, 1.0, help, field, options);
    }
    // Every key of `part` (keys of a struct P inside S), at `part`'s place in S.
    template <typename P, typename F>
    void nest(const Keys<P>& part, F place) {
        for (const SettingField<P>& f : part.fields()) {
            SettingField<S> g;
            static_cast<SettingSpec&>(g) = f;
            g.key = prefix_ + f.key;
            g.field = [inner = f.field, place](S& s) -> void* { return inner(place(s)); };
            fields_.push_back(std::move(g));
        }
    }
    const std::vector<SettingField<S>>& fields() const { return fields_; }

  private:
    template <typename T, typename F>
    void add(const char* key, Kind kind, const char* unit, double lo, double hi, const char* help,
             F field, const KeyOptions& options) {
        static_assert(std::is_same_v<decltype(field(std::declval<S&>())), T&>,
                      "the field's type does not match the key's kind");
        SettingField<S> f;
        f.key = prefix_ + key;
        f.kind = kind;
        f.unit = unit;
        f.lo = lo;
        f.hi = hi;
        f.logarithmic = options.logarithmic;
        f.help = help;
        f.rebuilds = options.rebuilds;
        f.cost = options.cost;
        f.field = [field](S& s) -> void* { return &field(s); };
        fields_.push_back(std::move(f));
    }
    std::string prefix_;
    std::vector<SettingField<S>> fields_;
};

// ---- [SECTION] The keys ------------------------------------------------------------------------

// Seconds, metres, ... long enough to mean "never" or "everywhere" [the key's unit].
constexpr double kBig = 1e9;

// lighting/AnchorStore.h.
Keys<AnchorStoreSettings> storeKeys() {
    using T = AnchorStoreSettings;
    Keys<T> k("store.");
    k.number(
        "coarsestSpacing_m", "m", kMinFinestSpacing_m, 1e6,
        "spacing of the coarsest lattice level, s_0; level L has s_0 / 3^L",
        [](T& t) -> double& { return t.coarsestSpacing_m; }, rebuilding(kLog));
    k.integer(
        "levels", "", 1, kMaxAnchorLevels, "lattice levels (the finest is s_0 / 3^(levels - 1))",
        [](T& t) -> int& { return t.levels; }, rebuilding(kCostHigh));
    k.number(
        "blendTime_s", "s", 0.0, 3600.0,
        "a refreshed anchor blends, a new one fades in, over this time",
        [](T& t) -> double& { return t.blendTime_s; }, kLog);
    k.number(
        "allowedSunAngle_rad", "rad", 1e-6, kPi,
        "a capture is out of date once the sun has moved this far",
        [](T& t) -> double& { return t.allowedSunAngle_rad; }, kLog);
    k.number(
        "minLifetime_s", "s", 1e-3, kBig, "shortest anchor lifetime (at most maxLifetime_s)",
        [](T& t) -> double& { return t.minLifetime_s; }, kLog);
    k.number(
        "maxLifetime_s", "s", 1e-3, kBig, "longest anchor lifetime (also while time stands still)",
        [](T& t) -> double& { return t.maxLifetime_s; }, kLog);
    k.number("regenerateFraction", "", 0.0, 1.0,
             "an anchor asks for a new capture after this fraction of its lifetime",
             [](T& t) -> double& { return t.regenerateFraction; });
    k.integer(
        "searchCells", "cells", 1, 4, "nearest-anchor search, in cells of the level",
        [](T& t) -> int& { return t.searchCells; }, kCostHigh);
    k.integer(
        "reachCells", "cells", 1, 4,
        "a hole takes the residuals of the anchors within this many cells",
        [](T& t) -> int& { return t.reachCells; }, kCostHigh);
    k.integer(
        "coarseReachCells", "cells", 1, 4, "the same at the coarsest level",
        [](T& t) -> int& { return t.coarseReachCells; }, kCostHigh);
    k.number("finerWeight", "", 0.0, 1.0, "weight of the finer levels' anchors in a hole's fill",
             [](T& t) -> double& { return t.finerWeight; });
    k.boolean(
        "smoothInterpolation", "bicubic Hermite cells (C1); off: bilinear",
        [](T& t) -> bool& { return t.smoothInterpolation; }, kCostHigh);
    k.boolean("bilinearFixedPoints", "terrain corners and road vertices read bilinear cells",
              [](T& t) -> bool& { return t.bilinearFixedPoints; });
    k.boolean("gradients", "anchors carry their measured translational gradient as slope",
              [](T& t) -> bool& { return t.gradients; });
    return k;
}

// lighting/ProbeScheduler.h.
Keys<ProbeSchedulerSettings> schedulerKeys() {
    using T = ProbeSchedulerSettings;
    Keys<T> k("scheduler.");
    k.number("velocityTimeConstant_s", "s", 0.0, 60.0, "inertia of the velocity filter",
             [](T& t) -> double& { return t.velocityTimeConstant_s; });
    k.number(
        "horizon_s", "s", 0.0, 10.0, "how far ahead the path is predicted",
        [](T& t) -> double& { return t.horizon_s; }, kCostHigh);
    k.number(
        "pathStep_s", "s", 0.1, 60.0, "spacing of the path samples",
        [](T& t) -> double& { return t.pathStep_s; }, kCostLowLog);
    k.number(
        "historyLength_s", "s", 0.0, 600.0, "position history kept",
        [](T& t) -> double& { return t.historyLength_s; }, kCostHigh);
    k.number(
        "roadSnap_m", "m", 0.0, 1000.0, "within the road's half width + this the camera is on it",
        [](T& t) -> double& { return t.roadSnap_m; }, kCostHighLog);
    k.number("roadAlignment", "", 0.0, 1.0,
             "the cosine between motion and road (either way) needed to follow the road",
             [](T& t) -> double& { return t.roadAlignment; });
    k.number(
        "corridorCells", "cells", 0.01, 100.0, "width of the finest-level corridor along the path",
        [](T& t) -> double& { return t.corridorCells; }, kLog);
    k.integer(
        "maxLevel", "", 0, kMaxAnchorLevels - 1, "never capture finer than this level",
        [](T& t) -> int& { return t.maxLevel; }, kCostHigh);
    k.number(
        "finestRingCells", "cells", 0.0, 8.0,
        "finest-level candidates within this many cells of the path",
        [](T& t) -> double& { return t.finestRingCells; }, kCostHigh);
    k.number(
        "coarseRingCells", "cells", 0.0, 8.0,
        "coarser-level candidates within this many cells of the path",
        [](T& t) -> double& { return t.coarseRingCells; }, kCostHigh);
    k.integer(
        "maxWiden", "", 0, 3, "doublings of the rings when everything near is fresh",
        [](T& t) -> int& { return t.maxWiden; }, kCostHigh);
    k.number(
        "minReachSpeed_mps", "m/s", 1e-3, 1e6,
        "speed assumed for the time to reach a point when slower",
        [](T& t) -> double& { return t.minReachSpeed_mps; }, kLog);
    k.number("gapBonus_s", "s", -1e3, 1e3,
             "priority of a point with no anchor of its level near it",
             [](T& t) -> double& { return t.gapBonus_s; });
    k.number("coarseFirst_s", "s", 0.0, 1e3,
             "a new point is ranked this x its spacing over the coarsest spacing earlier",
             [](T& t) -> double& { return t.coarseFirst_s; });
    k.number("staleBias_s", "s", -1e3, 1e3,
             "cost of refreshing an anchor that asks for it, at urgency 0",
             [](T& t) -> double& { return t.staleBias_s; });
    k.number(
        "adaptiveThreshold", "", 0.0, 10.0,
        "adaptive density: skip a finer point where the coarser anchors agree within this "
        "(0: off)",
        [](T& t) -> double& { return t.adaptiveThreshold; }, kCostHigh);
    return k;
}

// lighting/CaptureCore.h: the keys at the top level of both files (the near field apart).
Keys<CaptureSettings> captureKeys() {
    using T = CaptureSettings;
    Keys<T> k;
    k.integer(
        "facesPerFrame", "faces", 1, kMaxFacesPerFrame,
        "capture budget: cube faces per frame (a probe is 6)",
        [](T& t) -> int& { return t.facesPerFrame; }, kCostHigh);
    k.number(
        "sunThreshold", "W sr^-1 m^-2", 0.0, 1e12,
        "the sky level that rescales an anchor captured at another time clamps texels at this "
        "luminance (the disc); the SH leave the sun out by its direction, not by this",
        [](T& t) -> double& { return t.sunThreshold; }, rebuilding(kLog));
    k.number(
        "maxAside_m", "m", 0.0, 100.0, "how far a probe may move out of solids",
        [](T& t) -> double& { return t.maxAside_m; }, kCostHigh);
    k.number("defaultTimeRate_hPerS", "h/s", -10.0, 10.0,
             "rate of the time of day before it is measured (at the start only)",
             [](T& t) -> double& { return t.defaultTimeRate_hPerS; });
    k.number("timeJump_h", "h", 0.0, 12.0,
             "a larger change of the time of day in one frame is a jump",
             [](T& t) -> double& { return t.timeJump_h; });
    k.number(
        "teleportDistance_m", "m", 0.0, kBig,
        "a camera step longer than this + 3 x speed x dt is a teleport",
        [](T& t) -> double& { return t.teleportDistance_m; }, kLog);
    k.integer(
        "fallbackFaceSize", "texels", 1, 64, "cube map size of the sky fallback",
        [](T& t) -> int& { return t.fallbackFaceSize; }, kCostHigh);
    k.integer(
        "primeProbes", "probes", 0, 16,
        "whole probes captured at once in the first frame and after a teleport, outside the "
        "budget (0: none, the first probes blend in from the sky fallback)",
        [](T& t) -> int& { return t.primeProbes; }, kCostHigh);
    k.number(
        "fallbackRefresh_h", "h", 0.0, 24.0, "recompute the fallback after this much day time",
        [](T& t) -> double& { return t.fallbackRefresh_h; }, kCostLowLog);
    k.boolean(
        "ownLight", "captures light their surfaces with the method's own field, not the hemisphere",
        [](T& t) -> bool& { return t.ownLight; }, kCostHigh);
    return k;
}

// lighting/NearField.h ("nearField" in both files). A volume is built with its near field:
// every key rebuilds.
Keys<NearFieldSettings> nearFieldKeys() {
    using T = NearFieldSettings;
    const auto costHigh = rebuilding(kCostHigh);
    const auto costHighLog = rebuilding(kCostHighLog);
    Keys<T> k("nearField.");
    k.boolean(
        "enabled", "the two-scale ambience", [](T& t) -> bool& { return t.enabled; }, costHigh);
    k.number(
        "radius_m", "m", 0.0, 150.0, "occluders this close to a shading point are put back there",
        [](T& t) -> double& { return t.radius_m; }, costHigh);
    k.number(
        "captureRadius_m", "m", 0.0, 200.0, "probes leave out the plants this close to them",
        [](T& t) -> double& { return t.captureRadius_m; }, rebuilding(kLog));
    k.boolean(
        "plants", "trees, bushes and rocks as spheres", [](T& t) -> bool& { return t.plants; },
        costHigh);
    k.boolean(
        "plantShadows", "the plants' spheres lit by the sun only where other plants and the terrain leave it",
        [](T& t) -> bool& { return t.plantShadows; }, costHigh);
    k.boolean(
        "plantSky", "the plants' spheres lit by the share of the sky the other plants leave them",
        [](T& t) -> bool& { return t.plantSky; }, costHigh);
    k.number(
        "smallRadius_m", "m", 0.0, 100.0, "bushes and rocks (never captured) are near out to this",
        [](T& t) -> double& { return t.smallRadius_m; }, costHigh);
    k.boolean(
        "terrain", "the terrain's near horizon", [](T& t) -> bool& { return t.terrain; }, costHigh);
    k.number(
        "terrainRadius_m", "m", 1.0, 200.0, "how far the near horizon is searched",
        [](T& t) -> double& { return t.terrainRadius_m; }, costHigh);
    k.boolean(
        "ground", "the ground below the point", [](T& t) -> bool& { return t.ground; }, costHigh);
    k.number(
        "groundRadius_m", "m", 0.5, 100.0, "how far from the point's foot the ground is its own",
        [](T& t) -> double& { return t.groundRadius_m; }, costHigh);
    k.number(
        "groundCell_m", "m", 1.0, 64.0, "the lattice whose ground terms objects blend",
        [](T& t) -> double& { return t.groundCell_m; }, rebuilding(kCostLowLog));
    k.number(
        "latticeRange_m", "m", 0.0, 1000.0,
        "objects first built this close to the camera blend the lattice's ground terms",
        [](T& t) -> double& { return t.latticeRange_m; }, costHighLog);
    k.number(
        "surfaceHeight_m", "m", 0.05, kShadingHeight_m,
        "terrain corners and road vertices see the near field from this height above the ground",
        [](T& t) -> double& { return t.surfaceHeight_m; }, rebuilding(kPlain));
    k.integer(
        "cacheEntries", "", 4096, 1 << 18,
        "points cached with their transfer before the cache is emptied (about 2.5 kB each)",
        [](T& t) -> int& { return t.cacheEntries; }, rebuilding(kCostLowLog));
    k.number(
        "objectRange_m", "m", 0.0, 250.0,
        "objects farther than this from the camera take the far field alone",
        [](T& t) -> double& { return t.objectRange_m; }, costHighLog);
    k.number(
        "cornerRange_m", "m", 0.0, 2000.0,
        "terrain corners and road vertices farther than this take the far field alone",
        [](T& t) -> double& { return t.cornerRange_m; }, costHighLog);
    k.boolean(
        "patchMean", "a terrain corner takes the near field's mean over the patches it colours",
        [](T& t) -> bool& { return t.patchMean; }, costHigh);
    k.integer(
        "patchSamples", "", 1, 5, "points a side of a corner's patch mean",
        [](T& t) -> int& { return t.patchSamples; }, costHigh);
    k.boolean(
        "vertexDetail",
        "the terrain's ambient scaled by its own sky visibility at each vertex of fine "
        "patches",
        [](T& t) -> bool& { return t.vertexDetail; }, costHigh);
    k.number(
        "vertexAmbient_m", "m", 0.0, 2000.0,
        "terrain patches nearer the eye than this take the ambient at every vertex, not their "
        "corners blended (0: off)",
        [](T& t) -> double& { return t.vertexAmbient_m; }, costHighLog);
    k.integer(
        "vertexPointsPerFrame", "points", 0, 1 << 20,
        "new terrain vertices lit per vertex a frame, nearest patches first; the others blend "
        "their corners until their turn (0: no bound)",
        [](T& t) -> int& { return t.vertexPointsPerFrame; }, costHigh);
    k.number(
        "captureLightRange_m", "m", 0.0, 2000.0,
        "the captures' surfaces this close to the camera take the near field too (0: off)",
        [](T& t) -> double& { return t.captureLightRange_m; }, costHigh);
    k.number(
        "captureLightCell_m", "m", 2.0, 256.0, "the lattice of the captures' near field",
        [](T& t) -> double& { return t.captureLightCell_m; }, costHigh);
    k.integer(
        "captureLightPointsPerFrame", "points", 0, 1 << 20,
        "new lattice points of the captures' near field a frame, nearest first (0: no bound)",
        [](T& t) -> int& { return t.captureLightPointsPerFrame; }, costHigh);
    return k;
}

// lighting/AmbienceVolume.h: the volume's file.
Keys<AmbienceVolumeSettings> volumeKeys() {
    using T = AmbienceVolumeSettings;
    Keys<T> k;
    k.nest(storeKeys(), [](T& t) -> AnchorStoreSettings& { return t.store; });
    k.nest(schedulerKeys(), [](T& t) -> ProbeSchedulerSettings& { return t.scheduler; });
    k.nest(captureKeys(), [](T& t) -> CaptureSettings& { return t.capture; });
    k.number(
        "nominalFrameTime_s", "s", 1e-4, 10.0,
        "frame time assumed before one is seen (at the start only)",
        [](T& t) -> double& { return t.nominalFrameTime_s; }, kLog);
    k.number(
        "asideFraction", "", 0.0, 10.0,
        "a probe may move aside this x its level's spacing (and at most maxAside_m)",
        [](T& t) -> double& { return t.asideFraction; }, kCostHigh);
    k.boolean(
        "relightBySkyLevel",
        "read stale anchors scaled by the sky level now over the sky level at their capture",
        [](T& t) -> bool& { return t.relightBySkyLevel; }, kCostHigh);
    k.nest(nearFieldKeys(), [](T& t) -> NearFieldSettings& { return t.capture.nearField; });
    return k;
}

// lighting/Baselines.h: the baselines' file.
Keys<BaselineSettings> baselineKeys() {
    using T = BaselineSettings;
    Keys<T> k;
    k.nest(captureKeys(), [](T& t) -> CaptureSettings& { return t.capture; });
    k.nest(nearFieldKeys(), [](T& t) -> NearFieldSettings& { return t.capture.nearField; });
    k.integer(
        "gridSize", "probes", 2, 256, "grid: the grid holds gridSize x gridSize probes",
        [](T& t) -> int& { return t.gridSize; }, kCostHigh);
    k.number(
        "gridSpacing_m", "m", 1e-3, 1e6, "grid: probe spacing, also the lattice the grid snaps to",
        [](T& t) -> double& { return t.gridSpacing_m; }, kLog);
    k.number("hysteresis", "", 0.0, 1.0, "grid: an update keeps this much of the old value",
             [](T& t) -> double& { return t.hysteresis; });
    k.number(
        "cacheSpacing_m", "m", 1.0, 1e6, "reactive: lattice of the cached probes",
        [](T& t) -> double& { return t.cacheSpacing_m; }, kCostLowLog);
    k.number(
        "unusedTimeout_s", "s", 1e-3, 600.0,
        "reactive: a probe not looked up for this long is dropped",
        [](T& t) -> double& { return t.unusedTimeout_s; }, kCostHighLog);
    k.number(
        "objectSize_m", "m", 1e-3, 1e6, "object: objects are terrain squares of this size",
        [](T& t) -> double& { return t.objectSize_m; }, kLog);
    k.number(
        "objectRange_m", "m", 0.0, 16384.0,
        "object: objects whose centre lies this close to the camera (at most 64 x "
        "objectSize_m)",
        [](T& t) -> double& { return t.objectRange_m; }, kCostHighLog);
    return k;
}

// ---- [SECTION] The checks ----------------------------------------------------------------------

void checkVolume(const AmbienceVolumeSettings& s, const std::string& where) {
    if (s.store.minLifetime_s > s.store.maxLifetime_s) {
        throw InputError(where, "'store': minLifetime_s exceeds maxLifetime_s");
    }
    // Every point a replay may hold (|x|, |z| up to 1e8 m) must have an integer key on the
    // finest lattice (AnchorStore.h "Lattice").
    // (With a relative margin, so that 4.05 m over 5 levels, 0.05 m up to rounding, passes.)
    const double finest_m = finestSpacing_m(s.store);
    if (!(finest_m >= kMinFinestSpacing_m * (1.0 - 1e-9))) {
        throw InputError(where,
                         "'store': the finest spacing coarsestSpacing_m / 3^(levels - 1) is " +
                             jsonNumber(finest_m) + " m, below " + jsonNumber(kMinFinestSpacing_m) +
                             " m (raise coarsestSpacing_m or lower levels)");
    }
}

// objectRange_m / objectSize_m at most: 64 scans 129^2 objects per probe choice.
constexpr double kMaxObjectRangeCells = 64.0;

void checkBaseline(const BaselineSettings& s, const std::string& where) {
    // Each choice of the next object scans the (2 range / size + 1)^2 objects around the camera.
    if (s.objectRange_m > kMaxObjectRangeCells * s.objectSize_m) {
        throw InputError(
            where, "'objectRange_m' may be at most " + std::to_string(int(kMaxObjectRangeCells)) +
                       " x objectSize_m (each probe choice scans the objects in range)");
    }
}

// ---- [SECTION] The schema ----------------------------------------------------------------------

// The keys of `fields` under `prefix` ("" or "store.") into the object `f` reads: a key with no
// further dot is a value, the others the objects they sit in, each read once where its first
// key is.
template <typename S>
void readObject(JsonFields& f, const std::vector<SettingField<S>>& fields,
                const std::string& prefix, S& s) {
    std::vector<std::string> objects;
    for (const SettingField<S>& field : fields) {
        if (field.key.compare(0, prefix.size(), prefix) != 0) continue;
        const std::string rest = field.key.substr(prefix.size());
        const std::size_t dot = rest.find('.');
        if (dot != std::string::npos) {
            const std::string name = rest.substr(0, dot);
            if (std::find(objects.begin(), objects.end(), name) != objects.end()) continue;
            objects.push_back(name);
            f.object(name.c_str(),
                     [&](JsonFields& inner) { readObject(inner, fields, prefix + name + ".", s); });
            continue;
        }
        void* p = field.field(s);
        switch (field.kind) {
            case Kind::Number:
                f.number(rest.c_str(), *static_cast<double*>(p), field.lo, field.hi);
                break;
            case Kind::Integer:
                f.integer(rest.c_str(), *static_cast<int*>(p), int(field.lo), int(field.hi));
                break;
            case Kind::Boolean:
                f.boolean(rest.c_str(), *static_cast<bool*>(p));
                break;
        }
    }
}

std::vector<std::string> splitKey(const std::string& key) {
    std::vector<std::string> parts;
    std::size_t start = 0;
    for (std::size_t dot; (dot = key.find('.', start)) != std::string::npos; start = dot + 1)
        parts.push_back(key.substr(start, dot - start));
    parts.push_back(key.substr(start));
    return parts;
}

}  // namespace

template <typename S>
SettingsSchema<S>::SettingsSchema(std::vector<Field> fields, Check check)
    : fields_(std::move(fields)), check_(std::move(check)) {}

template <typename S>
const SettingField<S>* SettingsSchema<S>::find(const std::string& key) const {
    for (const Field& f : fields_)
        if (f.key == key) return &f;
    return nullptr;
}

template <typename S>
double SettingsSchema<S>::value(const S& settings, const Field& field) {
    const void* p = field.field(const_cast<S&>(settings));
    switch (field.kind) {
        case Kind::Number:
            return *static_cast<const double*>(p);
        case Kind::Integer:
            return double(*static_cast<const int*>(p));
        case Kind::Boolean:
            return *static_cast<const bool*>(p) ? 1.0 : 0.0;
    }
    return 0.0;
}

template <typename S>
void SettingsSchema<S>::setValue(S& settings, const Field& field, double value) {
    void* p = field.field(settings);
    switch (field.kind) {
        case Kind::Number:
            *static_cast<double*>(p) = value;
            break;
        case Kind::Integer:
            *static_cast<int*>(p) = int(std::lround(value));
            break;
        case Kind::Boolean:
            *static_cast<bool*>(p) = value != 0.0;
            break;
    }
}

template <typename S>
S SettingsSchema<S>::read(const std::string& jsonText, const std::string& where) const {
    S s;
    readJsonSettings(jsonText, where, [&](JsonFields& f) { readObject(f, fields_, "", s); });
    check_(s, where);
    return s;
}

template <typename S>
std::string SettingsSchema<S>::write(const S& settings) const {
    nlohmann::ordered_json root = nlohmann::ordered_json::object();
    for (const Field& f : fields_) {
        nlohmann::ordered_json* at = &root;
        const std::vector<std::string> parts = splitKey(f.key);
        for (std::size_t i = 0; i + 1 < parts.size(); ++i) at = &(*at)[parts[i]];
        nlohmann::ordered_json& slot = (*at)[parts.back()];
        const double v = value(settings, f);
        switch (f.kind) {
            case Kind::Number:
                slot = v;
                break;
            case Kind::Integer:
                slot = int(v);
                break;
            case Kind::Boolean:
                slot = v != 0.0;
                break;
        }
    }
    return root.dump(2) + "\n";
}

template <typename S>
bool SettingsSchema<S>::equal(const S& a, const S& b) const {
    for (const Field& f : fields_)
        if (value(a, f) != value(b, f)) return false;
    return true;
}

template <typename S>
bool SettingsSchema<S>::sameWhereRebuilding(const S& a, const S& b) const {
    for (const Field& f : fields_)
        if (f.rebuilds && value(a, f) != value(b, f)) return false;
    return true;
}

template <typename S>
bool SettingsSchema<S>::assignIfKnown(S& settings, const std::string& assignment,
                                      const std::string& where) const {
    const std::size_t eq = assignment.find('=');
    if (eq == std::string::npos)
        throw InputError(where, "expected KEY=VALUE, got '" + assignment + "'");
    const std::string key = assignment.substr(0, eq), text = assignment.substr(eq + 1);
    const Field* field = find(key);
    if (!field) return false;
    // The value as the file would hold it; text that is no JSON value at all is a string, which
    // the check below refuses as such ("must be a number").
    nlohmann::json object = nlohmann::json::object();
    try {
        object[key] = nlohmann::json::parse(text);
    } catch (const nlohmann::json::exception&) {
        object[key] = text;
    }
    // JsonFields names the key as given: its whole path.
    JsonFields f(object, where);
    void* p = field->field(settings);
    switch (field->kind) {
        case Kind::Number:
            f.number(key.c_str(), *static_cast<double*>(p), field->lo, field->hi);
            break;
        case Kind::Integer:
            f.integer(key.c_str(), *static_cast<int*>(p), int(field->lo), int(field->hi));
            break;
        case Kind::Boolean:
            f.boolean(key.c_str(), *static_cast<bool*>(p));
            break;
    }
    return true;
}

template <typename S>
void SettingsSchema<S>::assign(S& settings, const std::string& assignment,
                               const std::string& where) const {
    if (!assignIfKnown(settings, assignment, where))
        throw InputError(where, "unknown setting '" + assignmentKey(assignment) +
                                    "' (`ambience settings` lists them)");
}

template <typename S>
S SettingsSchema<S>::worstCase() const {
    S s;
    for (const Field& f : fields_)
        if (f.cost != Cost::None) setValue(s, f, f.worstValue());
    return s;
}

template class SettingsSchema<AmbienceVolumeSettings>;
template class SettingsSchema<BaselineSettings>;

const SettingsSchema<AmbienceVolumeSettings>& volumeSettingsSchema() {
    static const SettingsSchema<AmbienceVolumeSettings> schema(volumeKeys().fields(), checkVolume);
    return schema;
}

const SettingsSchema<BaselineSettings>& baselineSettingsSchema() {
    static const SettingsSchema<BaselineSettings> schema(baselineKeys().fields(), checkBaseline);
    return schema;
}

std::string assignmentKey(const std::string& assignment) {
    return assignment.substr(0, assignment.find('='));
}

// ---- [SECTION] Generated text ------------------------------------------------------------------

namespace {

const char* kindName(Kind kind) {
    switch (kind) {
        case Kind::Number:
            return "number";
        case Kind::Integer:
            return "integer";
        case Kind::Boolean:
            return "switch";
    }
    return "";
}

// A value as the file holds it.
std::string valueText(Kind kind, double v) {
    if (kind == Kind::Boolean) return v != 0.0 ? "true" : "false";
    if (kind == Kind::Integer) return std::to_string((long long)v);
    return jsonNumber(v);
}

// Markdown table cells may not hold '|'.
std::string cell(const std::string& text) {
    std::string out;
    for (char c : text) {
        if (c == '|') out += '\\';
        out += c;
    }
    return out;
}

template <typename S>
void markdownTable(std::ostringstream& out, const SettingsSchema<S>& schema, bool rebuilds) {
    out << "| key | kind | default | range | unit | costly end |" << (rebuilds ? " rebuilds |" : "")
        << " what it does |\n";
    out << "|---|---|---|---|---|---|" << (rebuilds ? "---|" : "") << "---|\n";
    const S defaults{};
    for (const SettingField<S>& f : schema.fields()) {
        const std::string range = f.kind == Kind::Boolean
                                      ? ""
                                      : valueText(f.kind, f.lo) + " to " + valueText(f.kind, f.hi);
        const char* cost = f.cost == Cost::None      ? ""
                           : f.kind == Kind::Boolean ? "on"
                           : f.cost == Cost::AtHigh  ? "high"
                                                     : "low";
        out << "| `" << f.key << "` | " << kindName(f.kind) << " | "
            << valueText(f.kind, SettingsSchema<S>::value(defaults, f)) << " | " << range << " | "
            << cell(f.unit) << " | " << cost << " |";
        if (rebuilds) out << (f.rebuilds ? " yes |" : " |");
        out << " " << cell(f.help) << " |\n";
    }
}

}  // namespace

std::string settingsMarkdown() {
    std::ostringstream out;
    out << "#### The volume's settings file\n\n"
           "`AmbienceVolumeSettings` (`lighting/AmbienceVolume.h`): `ambience run --config`,\n"
           "`view --config`, `compare --config`, `\"volume\"` in a sweep point. \"rebuilds\": a "
           "change cannot\napply to a running volume (the tuning panel rebuilds it).\n\n";
    markdownTable(out, volumeSettingsSchema(), true);
    out << "\n#### The baselines' settings file\n\n"
           "`BaselineSettings` (`lighting/Baselines.h`): `ambience run --baseline-config`,\n"
           "`\"baseline\"` in a sweep point. The capture and near-field keys are the volume's.\n\n";
    markdownTable(out, baselineSettingsSchema(), false);
    return out.str();
}

std::string settingsFuzzDictionary() {
    std::set<std::string> names;
    auto add = [&](const std::string& key) {
        for (const std::string& part : splitKey(key)) names.insert(part);
    };
    for (const auto& f : volumeSettingsSchema().fields()) add(f.key);
    for (const auto& f : baselineSettingsSchema().fields()) add(f.key);
    std::string out;
    for (const std::string& name : names) out += "settings_" + name + "=\"\\\"" + name + "\\\"\"\n";
    return out;
}

}  // namespace amb
