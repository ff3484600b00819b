// Baselines.h — the ways of giving ambience that the dynamic ambience volume is measured against
// (docs/ARCHITECTURE.md "Measuring speed against error": same capture budget, same replays, same shAt
// read by the draw and the measurement).
//
// [SECTION] Settings           BaselineSettings, baselineSettingsFromJson
// [SECTION] Shared machinery   CapturingBaseline: the stages over a CaptureCore (the clock,
//                              teleports, the fallback, the face budget, rejection), statistics
// [SECTION] The baselines      ScrollingGridMethod  "grid"      (the DDGI / RTXGI way)
//                              ReactiveCacheMethod  "reactive"  (the Lumen / kajiya way)
//                              PerObjectMethod      "object"    (one capture per object)
//                              NearestAnchorMethod  "nearest"   (ours without blending)
// [SECTION] Factory            makeCapturingMethod (--ambient volume|nearest|grid|reactive|object)
//
// Shared rules: those of lighting/CaptureCore.h (the budget, the clock and jumps, teleports,
// rejection of bad probes, the fallback), the same core the volume uses, so that only the
// placement and use of probes differ. Besides:
//   - probes are placed with ProbeEnvironment::placeProbe(x, z, maxAside_m) at their lattice
//     point (or object centre).
//   - where a method has nothing, shAt returns the fallback.
//   - a probe's lifetime is anchorLifetime_s(AnchorStoreSettings{}, sun speed, time rate). A
//     probe is stale when its age (from its first face) exceeds the lifetime at the current
//     rate, or when it was started before a jump of the time of day. What a method does with
//     stale probes is its own rule.
//   - deterministic: every choice is ordered by distance and then by integer cell; only the
//     stage timings read the clock.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "lighting/AmbienceMethod.h"
#include "lighting/AmbienceVolume.h"
#include "lighting/CaptureCore.h"

namespace amb {

class CubeCapture;
class NearFieldScene;
class ProbeEnvironment;
class RoadNetwork;

// ---- Settings -------------------------------------------------------------------------------

struct BaselineSettings {
    // Shared with the volume (lighting/CaptureCore.h; the JSON keys at the top level).
    CaptureSettings capture;
    // The probe spacing or object size of each baseline below is in metres.
    // (why these values: docs/TUNING.md "Baselines")
    // ScrollingGridMethod.
    int gridSize = 16;             // G: the grid holds G x G probes
    double gridSpacing_m = 256.0;  // s: probe spacing, also the lattice the grid snaps to [m]
    double hysteresis = 0.97;      // h: an update keeps h of the old value
    // ReactiveCacheMethod.
    double cacheSpacing_m = 192.0;  // lattice of the cached probes [m]
    double unusedTimeout_s = 4.0;  // a probe not looked up for this long is dropped [s]
    // PerObjectMethod.
    double objectSize_m = 256.0;   // objects are terrain squares of this size [m]
    double objectRange_m = 400.0;  // objects whose centre lies this close to the camera [m]
                                   // (at most 64 x objectSize_m)
};

// Parses settings from JSON text: an object whose keys are the field names above; missing keys
// keep their defaults. Unknown keys, wrong types or out-of-range values throw
// InputError(where, ...) naming the key.
BaselineSettings baselineSettingsFromJson(const std::string& jsonText, const std::string& where);

// ---- Shared machinery -----------------------------------------------------------------------

// An integer cell of a lattice (grid, cache) or an object key: exact however far from the
// origin.
struct CellKey {
    std::int64_t i = 0;
    std::int64_t k = 0;
    bool operator==(const CellKey& o) const { return i == o.i && k == o.k; }
    bool operator!=(const CellKey& o) const { return !(*this == o); }
    bool operator<(const CellKey& o) const { return i != o.i ? i < o.i : k < o.k; }
};
struct CellKeyHash {
    std::size_t operator()(const CellKey& key) const noexcept;
};

// Estimated heap bytes of an unordered_map: the bucket array plus one allocation per element
// (next pointer, cached hash and the element, rounded up as glibc's malloc does).
std::size_t hashMapBytes(std::size_t buckets, std::size_t elements, std::size_t elementBytes);

// The frame loop of every capturing baseline: predictStage measures time and motion and lets the
// method update its structure; captureStage spends the face budget on the probe in progress and,
// when it completes, asks the method for the next; storeStage hands accepted probes to the
// method. Subclasses only say which probe comes next, where it lives and how shAt reads them.
class CapturingBaseline : public AmbienceMethod {
  public:
    ~CapturingBaseline() override;
    CapturingBaseline(const CapturingBaseline&) = delete;
    CapturingBaseline& operator=(const CapturingBaseline&) = delete;

    void predictStage(const glm::dvec3& cameraPosition_m, const glm::dvec3& cameraVelocity_mps,
                      double timeOfDay_h, double dt_s) final;
    void captureStage() final;
    void storeStage() final;
    MethodStatistics methodStatistics() const final;
    const SurfaceLight* captureSurfaceLight() const final { return core_.surfaceLight(); }
    void overrideCaptureLight(CaptureLightOverride light) final {
        core_.overrideSurfaceLight(std::move(light));
    }

    const BaselineSettings& settings() const { return settings_; }
    double simulationTime_s() const { return core_.time_s(); }
    double timeRate_hPerS() const { return core_.timeRate_hPerS(); }
    // Lifetime of a probe at the current time rate [s].
    double currentLifetime_s() const;
    const ShRgb& fallback() const { return core_.fallback(); }

  protected:
    CapturingBaseline(CubeCapture& capture, const ProbeEnvironment& environment,
                      const BaselineSettings& settings);

    // A probe the method wants captured: its key and its ground point before placement.
    struct ProbeRequest {
        CellKey key;
        double x_m = 0.0, z_m = 0.0;
    };

    // After time and motion are updated, every frame: scroll, drop, forget.
    virtual void updateStructure() = 0;
    // The next probe to capture, or nothing (the budget stays unused). `busy` lists probes
    // completed this frame and not yet stored.
    virtual std::optional<ProbeRequest> nextProbe(const std::vector<CellKey>& busy) = 0;
    // Whether a probe of `key` is still wanted (a probe no longer wanted is dropped when it
    // completes, or aborted in progress).
    virtual bool wantsProbe(const CellKey& key) const = 0;
    // An accepted capture (finite coefficients) of `key`, begun at captureTime_s.
    virtual void storeProbe(const CellKey& key, const ShRgb& sh, double captureTime_s) = 0;
    virtual std::size_t probesHeld() const = 0;
    virtual std::size_t bytesHeld() const = 0;

    // For subclasses.
    bool isStale(double captureTime_s) const;
    // Work done for the method between frames (e.g. recording lookups) [s]: counted in the next
    // frame's predict time.
    void addPendingPredictTime(double seconds) { pendingPredict_s_ += seconds; }
    const glm::dvec3& camera_m() const { return core_.camera_m(); }
    // A prime is due this frame (lighting/CaptureCore.h).
    bool primeDue() const { return core_.primeDue(); }
    // Squared horizontal distance from the camera [m^2].
    double cameraDistance2(double x_m, double z_m) const;
    const ProbeEnvironment& environment() const { return environment_; }

  private:
    const ProbeEnvironment& environment_;
    BaselineSettings settings_;
    CaptureCore core_;
    double lifetime_s_ = 0.0;  // currentLifetime_s() as of this frame's predictStage
    double pendingPredict_s_ = 0.0;
};

// ---- The baselines --------------------------------------------------------------------------

// The DDGI / RTXGI way: a camera-centred G x G grid of probes on the ground plane at spacing s,
// snapped to the world lattice of spacing s (probe (i, k) at (i s, k s), i and k integers). The
// grid's lowest cell is round(camera / s - (G - 1) / 2) on each axis; when the camera moves the
// grid scrolls: slots are addressed toroidally (slot (i mod G, k mod G)), so a slot whose cell
// leaves the grid takes the entering cell and becomes invalid, the others keep their values.
// Capture order: invalid probes first (nearest the camera first, ties by cell), else the next
// slot of a fixed round-robin over the G x G slots. A completed capture sets an invalid probe
// and updates a valid one with hysteresis: value = h old + (1 - h) new. No lifetime: the
// hysteresis is the only update rule. shAt: bilinear over the four probes at the corners of the
// cell holding (x, z), weights renormalised over the valid ones; outside the grid or no valid
// weight -> fallback.
class ScrollingGridMethod final : public CapturingBaseline {
  public:
    ScrollingGridMethod(CubeCapture& capture, const ProbeEnvironment& environment,
                        const BaselineSettings& settings = {});
    std::string methodName() const override { return "grid"; }
    ShRgb shAt(double x_m, double z_m) const override;
    using AmbienceMethod::shAt;
    IdealSupport idealSupport(double x_m, double z_m) const override;

    // Lowest cell of the grid (the grid holds cells origin .. origin + G - 1 on each axis).
    CellKey gridOrigin() const { return origin_; }
    // The probe of a cell, or nothing when the cell is outside the grid or its probe invalid.
    struct GridProbe {
        ShRgb value;
        int updates = 0;  // captures applied since the probe became valid (the first counts)
    };
    std::optional<GridProbe> probe(const CellKey& cell) const;

  protected:
    void updateStructure() override;
    std::optional<ProbeRequest> nextProbe(const std::vector<CellKey>& busy) override;
    bool wantsProbe(const CellKey& key) const override;
    void storeProbe(const CellKey& key, const ShRgb& sh, double captureTime_s) override;
    std::size_t probesHeld() const override { return validCount_; }
    std::size_t bytesHeld() const override;

  private:
    struct Slot {
        ShRgb value;
        CellKey cell;
        int updates = 0;
        bool valid = false;
    };
    std::size_t slotOf(const CellKey& cell) const;
    bool inGrid(const CellKey& cell) const;

    int size_;
    double spacing_m_;
    std::vector<Slot> slots_;  // size_ x size_, slot (a, b) at a + size_ b
    CellKey origin_;
    bool haveOrigin_ = false;
    std::size_t roundRobin_ = 0;  // next slot of the round-robin
    std::size_t validCount_ = 0;
};

// The Lumen / kajiya way: probes exist only where lookups happen. noteLookups marks, for each
// point, the four corners of its cell of the lattice of spacing cacheSpacing_m (probe (i, k) at
// (i s, k s)) as wanted now; so is the camera's ground point when a prime is due (the first
// frame, a teleport: lighting/CaptureCore.h), before the draw has looked anywhere there.
// Missing wanted probes are captured nearest the camera first (ties by cell), then stale ones,
// nearest first. A probe (or wish) not looked up for unusedTimeout_s of
// simulation time is dropped. shAt: bilinear over the four corners of the cell holding (x, z),
// renormalised over the present probes; none -> fallback.
class ReactiveCacheMethod final : public CapturingBaseline {
  public:
    ReactiveCacheMethod(CubeCapture& capture, const ProbeEnvironment& environment,
                        const BaselineSettings& settings = {});
    std::string methodName() const override { return "reactive"; }
    ShRgb shAt(double x_m, double z_m) const override;
    using AmbienceMethod::shAt;
    IdealSupport idealSupport(double x_m, double z_m) const override;
    void noteLookups(std::size_t count, const double* x_m, const double* z_m) override;
    bool wantsLookups() const override { return true; }

    // Lattice points wanted (looked up within the timeout), probes present among them.
    std::size_t wantedCount() const { return entries_.size(); }
    std::size_t presentCount() const { return presentCount_; }

  protected:
    void updateStructure() override;
    std::optional<ProbeRequest> nextProbe(const std::vector<CellKey>& busy) override;
    bool wantsProbe(const CellKey& key) const override;
    void storeProbe(const CellKey& key, const ShRgb& sh, double captureTime_s) override;
    std::size_t probesHeld() const override { return presentCount_; }
    std::size_t bytesHeld() const override;

  private:
    // Marks the four corners of each point's cell as wanted now.
    void want(std::size_t count, const double* x_m, const double* z_m);

    struct Entry {
        ShRgb value;
        double lastWanted_s = 0.0;
        double captureTime_s = 0.0;
        bool present = false;
    };
    double spacing_m_;
    std::unordered_map<CellKey, Entry, CellKeyHash> entries_;
    std::size_t presentCount_ = 0;
};

// One capture per object, no structure: no sharing, blending or interpolation. Objects are the
// level-0 terrain patches, squares of objectSize_m with keys (floor(x / size), floor(z / size)).
// Wanted: the objects whose centre lies within objectRange_m of the camera; each gets one probe
// at its centre, the missing ones first, then the stale ones, each nearest the camera first
// (ties by key). Objects further than 2 x objectRange_m are forgotten. shAt(x, z): the capture of
// the object holding (x, z), else the fallback.
class PerObjectMethod final : public CapturingBaseline {
  public:
    PerObjectMethod(CubeCapture& capture, const ProbeEnvironment& environment,
                    const BaselineSettings& settings = {});
    std::string methodName() const override { return "object"; }
    ShRgb shAt(double x_m, double z_m) const override;
    using AmbienceMethod::shAt;

    // The object holding ground point (x, z), and its centre [m].
    CellKey objectAt(double x_m, double z_m) const;
    double objectCentreX_m(const CellKey& key) const;
    double objectCentreZ_m(const CellKey& key) const;

  protected:
    void updateStructure() override;
    std::optional<ProbeRequest> nextProbe(const std::vector<CellKey>& busy) override;
    bool wantsProbe(const CellKey& key) const override;
    void storeProbe(const CellKey& key, const ShRgb& sh, double captureTime_s) override;
    std::size_t probesHeld() const override { return objects_.size(); }
    std::size_t bytesHeld() const override;

  private:
    struct ObjectProbe {
        ShRgb value;
        double captureTime_s = 0.0;
    };
    double size_m_;
    double range_m_;
    std::unordered_map<CellKey, ObjectProbe, CellKeyHash> objects_;
};

// Ours without blending: an AmbienceVolume with the given settings but a blend time of 1e-6 s
// (new anchors are present from the next frame on, refreshes replace at once), read as the
// single nearest anchor (AnchorStore::nearestAnchor: within searchCells x s_L on the level-L
// lattice, finest level first), its current value times its relight factor. Where none is in
// reach, the interpolated value (the store's fallback there).
class NearestAnchorMethod final : public AmbienceMethod {
  public:
    static constexpr double kBlendTime_s = 1e-6;

    NearestAnchorMethod(CubeCapture& capture, const ProbeEnvironment& environment,
                        const AmbienceVolumeSettings& settings = {},
                        const RoadNetwork* roads = nullptr);
    std::string methodName() const override { return "nearest"; }
    void predictStage(const glm::dvec3& cameraPosition_m, const glm::dvec3& cameraVelocity_mps,
                      double timeOfDay_h, double dt_s) override {
        volume_.predictStage(cameraPosition_m, cameraVelocity_mps, timeOfDay_h, dt_s);
    }
    void captureStage() override { volume_.captureStage(); }
    void storeStage() override { volume_.storeStage(); }
    ShRgb shAt(double x_m, double z_m) const override;
    // The same at many points, in parallel.
    void shAt(std::size_t count, const double* x_m, const double* z_m, ShRgb* out) const override;
    MethodStatistics methodStatistics() const override { return volume_.methodStatistics(); }
    const SurfaceLight* captureSurfaceLight() const override {
        return volume_.captureSurfaceLight();
    }
    void overrideCaptureLight(CaptureLightOverride light) override {
        volume_.overrideCaptureLight(std::move(light));
    }

    const AmbienceVolume& volume() const { return volume_; }

  private:
    static AmbienceVolumeSettings withoutBlending(AmbienceVolumeSettings settings);
    AmbienceVolume volume_;
};

// ---- Factory --------------------------------------------------------------------------------

// Makes the scene the near field reads (NearField.h; WorldNearFieldScene for the world drawn).
using NearFieldSceneMaker = std::function<std::unique_ptr<NearFieldScene>()>;

// The method named `name` (the --ambient option): "volume" (AmbienceVolume), "nearest", "grid",
// "reactive" or "object". `capture`, `environment` and `roads` (may be null) must outlive it.
// Another name throws InputError("--ambient", ...).
// The two-scale ambience (NearField.h) is the method's own settings' to ask for: volume and
// nearest read volumeSettings.capture.nearField, the baselines baselineSettings.capture.nearField.
// Where that asks for it (enabled), the method comes wrapped in a NearFieldMethod over a scene
// from `nearScene`, with those settings; without `nearScene` (the bare methods, in tests), never.
std::unique_ptr<AmbienceMethod> makeCapturingMethod(const std::string& name, CubeCapture& capture,
                                                    const ProbeEnvironment& environment,
                                                    const AmbienceVolumeSettings& volumeSettings,
                                                    const BaselineSettings& baselineSettings,
                                                    const RoadNetwork* roads,
                                                    const NearFieldSceneMaker& nearScene = {});

}  // namespace amb
