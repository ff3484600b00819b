// AmbienceVolume.h — the dynamic ambience volume: predict, capture, project, store, blend, and
// answer "what ambience at this ground point" (thesis 5, 7-9; docs/ARCHITECTURE.md "The frame", 2-4).
//
// Per frame the frame loop calls the three stages (or update(), which runs them in order). The
// clock, teleports, the face budget, rejection and the fallback are the rules every capturing
// method shares (lighting/CaptureCore.h); what is the volume's own:
//   1. time     a jump of the time of day shortens every anchor's life to blendTime_s; the
//               fallback, when it changed, goes to the store before this frame's inserts (a new
//               anchor starts from what the store shows at its point);
//   2. predict  the scheduler observes the camera (after a teleport it starts over) and, when no
//               probe is in progress, picks the next lattice point; the environment places the
//               probe (out of terrain and trees), at most asideFraction x the level's spacing
//               aside;
//   3. capture  capture.facesPerFrame faces of the probe's cube map (a probe spans several
//               frames: 6 at the default one face per frame), each projected to SH as it
//               arrives (sun disc extracted, not kept);
//   4. store    the clock advances (blending, fades, regeneration requests, expiry, pruning),
//               then a completed probe is inserted or refreshes its anchor — after the advance,
//               so it starts at presence 0 and changes nothing this frame; then stale anchors
//               are relit by the sky level.
// shAt(x, z) then gives the interpolated SH at any ground point (AnchorStore::interpolate).
// Where no anchor is in reach it is the fallback (sky model over a flat ground).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "lighting/AmbienceMethod.h"
#include "lighting/AnchorStore.h"
#include "lighting/CaptureCore.h"
#include "lighting/ProbeScheduler.h"
#include "world/Conventions.h"

namespace amb {

class CubeCapture;
class ProbeEnvironment;
class RoadNetwork;

// Every parameter of the volume, in one place (settable from JSON, see ambienceSettingsFromJson).
struct AmbienceVolumeSettings {
    AnchorStoreSettings store;
    ProbeSchedulerSettings scheduler;
    // What every capturing method shares (lighting/CaptureCore.h): the face budget, the sun
    // threshold, maxAside_m, the clock's defaults, the teleport distance, the fallback.
    CaptureSettings capture;
    double nominalFrameTime_s = 1.0 / 60.0;  // frame time assumed before any dt > 0 is seen
    double asideFraction = 0.5;  // a probe may move aside up to this x its level's spacing,
                                 // and at most capture.maxAside_m
    // Relighting of stale anchors (an extension of the thesis' expiry, 7.5.3): every anchor is
    // read scaled by skyLevel(now) / skyLevel(its capture's time of day), skyLevel being the
    // mean luminance of the sky-model fallback scene. While the day changes slowly the factor
    // is ~1; through a fast sunset or a time-lapse, anchors older than the capture budget can
    // refresh no longer carry daylight into the dusk.
    bool relightBySkyLevel = true;
};

// Parses settings from JSON text: an object whose keys are the field names above (nested
// objects "store" and "scheduler"; the keys of CaptureSettings at the top level); missing keys
// keep their defaults. Unknown keys, wrong types
// or out-of-range values throw InputError(where, ...).
AmbienceVolumeSettings ambienceSettingsFromJson(const std::string& jsonText,
                                                const std::string& where);

struct AmbienceStatistics {
    AnchorStoreStatistics store;  // anchors held (per level), bytes, inserts, expiries
    int facesThisFrame = 0;
    std::int64_t facesCaptured = 0;    // since construction
    std::int64_t primeFaces = 0;       // of those, the primes' (CaptureCore.h)
    std::int64_t probesCompleted = 0;  // probes projected (accepted or rejected)
    std::int64_t rejectedProbes = 0;   // probes with NaN/Inf/negative texels or coefficients
    std::int64_t abortedProbes = 0;    // probes dropped on a teleport
    std::int64_t teleports = 0;
    int finestLevel = 0;  // scheduler's finest level this frame
    // Wall time of this frame's stages [s].
    double predict_s = 0.0, capture_s = 0.0, project_s = 0.0, store_s = 0.0;
};

// The probe being captured (for debug overlays).
struct ProbeInProgress {
    LatticeKey key;
    glm::dvec3 position_m{0.0};  // where it is captured
    int facesDone = 0;           // 0..6
};

class AmbienceVolume final : public AmbienceMethod {
  public:
    // `capture`, `environment` (and `roads`, may be null) must outlive the volume.
    AmbienceVolume(CubeCapture& capture, const ProbeEnvironment& environment,
                   const AmbienceVolumeSettings& settings = {}, const RoadNetwork* roads = nullptr);
    ~AmbienceVolume();
    AmbienceVolume(const AmbienceVolume&) = delete;
    AmbienceVolume& operator=(const AmbienceVolume&) = delete;

    // One frame (see the list at the top). dt_s <= 0 or non-finite is treated as 0: nothing
    // ages or blends, the budget is still spent. timeOfDay_h in hours, any value (wrapped).
    void update(const glm::dvec3& cameraPosition_m, const glm::dvec3& cameraVelocity_mps,
                double timeOfDay_h, double dt_s);
    // The same in the frame's three stages (docs/ARCHITECTURE.md "The frame", 2-4), for a frame loop
    // that times them separately: predict (time, motion model), capture (this frame's faces, each
    // projected as it arrives), store (advance the clock, insert completed probes).
    void predictStage(const glm::dvec3& cameraPosition_m, const glm::dvec3& cameraVelocity_mps,
                      double timeOfDay_h, double dt_s) override;
    void captureStage() override;
    void storeStage() override;

    std::string methodName() const override { return "volume"; }
    // Interpolated SH at ground point (x, z); finite everywhere.
    ShRgb shAt(double x_m, double z_m) const override { return store_.interpolate(x_m, z_m); }
    // The corners of the cell of the level the interpolation reads at (x, z) (the coarsest
    // level where it falls back to the sky).
    IdealSupport idealSupport(double x_m, double z_m) const override;
    // The same at many points (terrain-patch corners, object instances), in parallel.
    void shAt(std::size_t count, const double* x_m, const double* z_m,
              ShRgb* out) const override {
        store_.interpolateMany(count, x_m, z_m, out);
    }
    // At terrain corners and road vertices (points that do not move): AnchorStore's fixed-point
    // cells (bilinear by default).
    ShRgb cornerShAt(double x_m, double z_m) const override {
        return store_.interpolateFixed(x_m, z_m);
    }
    void cornerShAt(std::size_t count, const double* x_m, const double* z_m,
                    ShRgb* out) const override {
        store_.interpolateFixedMany(count, x_m, z_m, out);
    }
    MethodStatistics methodStatistics() const override;
    const SurfaceLight* captureSurfaceLight() const override { return core_.surfaceLight(); }
    void overrideCaptureLight(CaptureLightOverride light) override {
        core_.overrideSurfaceLight(std::move(light));
    }

    const AmbienceStatistics& statistics() const { return stats_; }
    const AnchorStore& store() const { return store_; }
    AnchorStore& store() { return store_; }
    const ProbeScheduler& scheduler() const { return scheduler_; }
    const AmbienceVolumeSettings& settings() const { return settings_; }
    // True when every change from `from` to `to` can apply to a running volume (retune): all
    // but the lattice (store.coarsestSpacing_m, store.levels), the sun threshold and the near
    // field, which a volume is built with.
    static bool retunable(const AmbienceVolumeSettings& from, const AmbienceVolumeSettings& to);
    // Applies `settings` from the next frame on; retunable(settings(), settings) must hold.
    void retune(const AmbienceVolumeSettings& settings);
    std::optional<ProbeInProgress> probeInProgress() const;
    double simulationTime_s() const { return core_.time_s(); }
    double timeRate_hPerS() const { return core_.timeRate_hPerS(); }
    // Lifetime given to a capture now (anchorLifetime_s with the measured time rate).
    double currentLifetime_s() const;

    void saveAnchors(const std::string& path) const { store_.save(path); }
    void loadAnchors(const std::string& path) { store_.load(path); }

  private:
    double skyLevel(double timeOfDay_h) const;
    void syncStatistics();

    const ProbeEnvironment& environment_;
    AmbienceVolumeSettings settings_;
    AnchorStore store_;
    ProbeScheduler scheduler_;
    CaptureCore core_;
    double probesPerSecond_ = 0.0;
    double frameTime_s_ = 0.0;
    AmbienceStatistics stats_;
    mutable std::unordered_map<int, double> skyLevels_;  // minute of the day -> sky level
};

}  // namespace amb
