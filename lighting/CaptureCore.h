// CaptureCore.h — what every capturing method shares, so that only where a method places its
// probes and how it reads them differ (docs/ARCHITECTURE.md "Methods"). The volume
// (AmbienceVolume.h) and every capturing baseline (Baselines.h) own one CaptureCore; a rule fixed
// here is fixed for all of them.
//
// [SECTION] Settings   CaptureSettings: the capture budget, the sun threshold, how far a probe
//                      may move aside, the clock's defaults, the teleport distance, the fallback
// [SECTION] Clock      beginFrame(): the simulation clock, the rate of the time of day (the wrap
//                      at 24 h handled), jumps of the time of day, teleports, the fallback
// [SECTION] Jobs       captureFaces(): the face budget spent on the probe in progress, a probe
//                      captured face by face over consecutive frames and projected as each face
//                      arrives; takeCompleted(): finished probes, checked
//
// The rules:
//   - time: dt_s <= 0 or not finite counts as 0; a time of day that is not finite keeps the last
//     one. The rate of the time of day [h/s] is measured between frames; a change of more than
//     timeJump_h in one frame is a jump (the rate keeps its last value; the method decides what
//     a jump does to what it holds).
//   - teleport: a camera step longer than teleportDistance_m + 3 x max(reported speed, previous
//     reported speed) x dt is a teleport (counted); the probe in progress is dropped (counted as
//     aborted). A reported speed counts up to kMaxCameraSpeed_mps only: a caller that measures
//     the velocity from the step itself (the frame loop does) reports any jump as a speed that
//     would explain it.
//   - budget: facesPerFrame faces of CubeCapture::faceSize() per frame; a probe is the six faces
//     of one position (one probe per 6 frames at one face per frame), each projected as it
//     arrives (CubeMapProjector), the sun's texel left out by the direction the capture put
//     the disc at (CubeCapture::sunDirection, lighting/SunTexel.h) at every face size.
//   - rejection: a probe with any texel that is NaN, infinite or negative, or with a coefficient
//     that is not finite or above AnchorStore::kMaxCoefficient in float, is counted in
//     rejectedProbes and never handed to the method.
//   - prime: in the first frame in which the camera is seen, and in the frame of a teleport, the
//     core first captures up to primeProbes whole probes (six faces each, outside the budget;
//     counted in primeFaces) before the budget is spent, and hands them over marked `primed`:
//     the method shows them at once instead of blending them in from the fallback, so the first
//     frame drawn at a new place shows that place's light, not the sky over flat ground. A
//     method that names no probe in that frame is primed in the first frame it names one (the
//     reactive cache names the corners of the camera's cell while a prime is due).
//   - fallback: the SH of ProbeEnvironment::fallbackCubeMap (sky model over flat ground) at
//     fallbackFaceSize, recomputed when the time of day has moved by more than fallbackRefresh_h;
//     a fallback that is not finite keeps the previous value (zero at first).
//   - determinism: only the stage timings read the clock.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "lighting/AmbienceMethod.h"
#include "lighting/CubeCapture.h"
#include "lighting/NearField.h"
#include "lighting/SH.h"
#include "lighting/ShGradient.h"
#include "world/Conventions.h"

namespace amb {

class CubeCapture;
class CubeMapProjector;
class ProbeEnvironment;

// ---- Settings -------------------------------------------------------------------------------

// The fastest the teleport rule believes a camera moves [m/s]: the fastest camera path `ambience
// replay make` makes (its --speed bound). A step at this speed is motion, not a teleport.
inline constexpr double kMaxCameraSpeed_mps = 1.0e4;

// Shared by every capturing method (the JSON keys of both settings files, at the top level).
struct CaptureSettings {
    int facesPerFrame = 1;  // capture budget (the thesis' one face per frame, 9.1)
    // No projection uses it: the sun is left out of the SH by its direction (lighting/SunTexel.h),
    // not by a luminance threshold. Only AmbienceVolume::skyLevel clamps texels at it (the disc
    // must not count in the level of the sky).
    double sunThreshold = kSunThreshold_Wpsrm2;
    double maxAside_m = 4.0;  // how far ProbeEnvironment::placeProbe may move a probe [m]
    double defaultTimeRate_hPerS = 1.0 / 3600.0;  // before the rate is measured (real time)
    double timeJump_h = 0.25;           // a larger change of the time of day in a frame is a jump
    double teleportDistance_m = 100.0;  // a camera step longer than this + 3 x speed x dt [m]
    int fallbackFaceSize = 16;          // cube map size of the fallback SH
    // Whole probes captured at once where the method has nothing yet (the first frame, a
    // teleport), before that frame is drawn: a loading step, outside the budget (the rule
    // "prime" above). 0: none, the first probes blend in from the fallback.
    int primeProbes = 4;
    double fallbackRefresh_h = 1.0 / 60.0;  // recompute the fallback after this much day time
    // What lights the surfaces the method's captures draw, besides the sun: false, the fixed
    // sky/ground hemisphere (world/SkyGround.h); true, the method's own field (its shAt at the
    // surface's ground point, the fallback where it holds nothing), so that each probe sees the
    // bounces its predecessors measured and the store converges towards the scene's own
    // multi-bounce light over probe generations (docs/METHOD.md "What the captures light their
    // surfaces with").
    bool ownLight = false;
    // The two-scale ambience (lighting/NearField.h; JSON key "nearField"): when enabled, probes
    // leave the plants within nearField.captureRadius_m out and the method's decorator puts those
    // within nearField.radius_m of each shading point back there.
    NearFieldSettings nearField;
    double nearRadius_m() const {
        return nearField.enabled && nearField.plants ? nearField.captureRadius_m : 0.0;
    }
};

// The JSON keys and their ranges: lighting/SettingsSchema.h.

// ---- Probes ---------------------------------------------------------------------------------

// A probe's key in its method's structure: a lattice point (level, i, k) of the volume, a cell
// of a grid or cache, an object. Exact however far from the origin.
struct ProbeKey {
    int level = 0;
    std::int64_t i = 0, k = 0;
    bool operator==(const ProbeKey& o) const { return level == o.level && i == o.i && k == o.k; }
    bool operator!=(const ProbeKey& o) const { return !(*this == o); }
};

// A probe a method wants captured: its key, its ground point before placement and how far
// placement may move it aside [m].
struct ProbeRequest {
    ProbeKey key;
    double x_m = 0.0, z_m = 0.0;
    double aside_m = 0.0;
};

// A probe being captured.
struct ProbeJob {
    ProbeKey key;
    glm::dvec3 position_m{0.0};  // where it is captured (after placement)
    double startTime_s = 0.0;    // simulation time of its first face
    int facesDone = 0;           // 0..6
    bool bad = false;            // a texel was NaN, infinite or negative
    bool primed = false;         // captured whole as a prime (the rule above): shown at once
};

// A probe whose six faces are in, checked: what the method may store.
struct CompletedProbe {
    ProbeJob job;
    ShRgb sh;  // the coefficients in float
    // Their translational gradient along the ground (lighting/ShGradient.h), when the method
    // asked for it (CaptureCore::setGradients); the anchor store drops one that is not finite.
    std::optional<ShSlope> slope;
};

// What beginFrame() saw.
struct FrameEvents {
    bool timeJump = false;  // the time of day jumped
    bool teleport = false;  // the camera teleported (the probe in progress was dropped)
};

// ---- The core -------------------------------------------------------------------------------

class CaptureCore {
  public:
    // `capture` and `environment` must outlive the core.
    CaptureCore(CubeCapture& capture, const ProbeEnvironment& environment,
                const CaptureSettings& settings);
    ~CaptureCore();
    CaptureCore(const CaptureCore&) = delete;
    CaptureCore& operator=(const CaptureCore&) = delete;

    // Stage 2's shared part (see the rules above): clears this frame's statistics and the
    // probes completed last frame, advances the clock, detects a jump of the time of day and a
    // teleport, refreshes the fallback.
    FrameEvents beginFrame(const glm::dvec3& cameraPosition_m, const glm::dvec3& cameraVelocity_mps,
                           double timeOfDay_h, double dt_s);

    // The method's own field, read by its captures' surfaces when settings().ownLight is on
    // (the method sets it once, at construction; until then captures use the hemisphere).
    using OwnField = std::function<ShRgb(double x_m, double z_m)>;
    void setOwnField(OwnField field) { ownLight_.field = std::move(field); }
    // A surface light in place of the method's own (AmbienceMethod::overrideCaptureLight),
    // asked with the clock's time of day; from the next capture on.
    void overrideSurfaceLight(AmbienceMethod::CaptureLightOverride light) {
        lightOverride_ = std::move(light);
    }
    // The surface light the method's captures use now: the override's answer when it gives one,
    // else the own field, or null (the hemisphere).
    const SurfaceLight* surfaceLight() const {
        if (lightOverride_)
            if (const SurfaceLight* light = lightOverride_(timeOfDay_h_)) return light;
        return settings_.ownLight && ownLight_.field ? &ownLight_ : nullptr;
    }

    // Stage 3: the prime when one is due (the rule above), then the face budget. When no probe
    // is in progress, `next(busy)` names the next one (or nothing: the rest of the budget stays
    // unused); `busy` lists the keys completed this frame and not yet taken. The time `next`
    // takes counts as predict time.
    using NextProbe = std::function<std::optional<ProbeRequest>(const std::vector<ProbeKey>& busy)>;
    void captureFaces(const NextProbe& next);
    // True while a prime is due (from the first frame or a teleport until a probe is named;
    // never with primeProbes 0).
    bool primeDue() const { return primeDue_ && settings_.primeProbes > 0; }

    // Stage 4's shared part: the probes completed this frame, bad ones counted in
    // rejectedProbes and left out. Empties the list.
    std::vector<CompletedProbe> takeCompleted();

    // Whether probes are captured with their distances and completed with their SH's
    // translational gradient (CompletedProbe::slope); off by default. From the next probe on.
    void setGradients(bool on) { gradients_ = on; }

    // Drops the probe in progress (its point left the method's structure).
    void abortJob() { job_.reset(); }
    const std::optional<ProbeJob>& job() const { return job_; }

    // The clock.
    double time_s() const { return time_s_; }
    double timeOfDay_h() const { return timeOfDay_h_; }
    double timeRate_hPerS() const { return timeRate_hPerS_; }
    // Simulation time of the latest jump of the time of day (-1: none yet).
    double lastJump_s() const { return lastJump_s_; }
    const glm::dvec3& camera_m() const { return camera_m_; }
    // The SH where a method has nothing (always finite).
    const ShRgb& fallback() const { return fallback_; }
    // True in the frame the fallback was recomputed.
    bool fallbackChanged() const { return fallbackChanged_; }

    const CaptureSettings& settings() const { return settings_; }
    // New settings from the next frame on, but for the two the core was built with: the sun
    // threshold (its projector) and the near field (what its probes leave out) keep theirs.
    void retune(CaptureSettings settings) {
        settings.sunThreshold = settings_.sunThreshold;
        settings.nearField = settings_.nearField;
        settings_ = settings;
    }
    // Counters since construction and this frame's stage times; methods add their own work to
    // the times (addPredictTime, addStoreTime) and fill probes and bytes.
    const MethodStatistics& statistics() const { return stats_; }
    std::int64_t probesCompleted() const { return probesCompleted_; }
    std::int64_t abortedProbes() const { return abortedProbes_; }
    void addPredictTime(double seconds) { stats_.predict_s += seconds; }
    void addStoreTime(double seconds) { stats_.store_s += seconds; }
    // A probe the method itself refused (e.g. its store rejected it).
    void countRejected() { ++stats_.rejectedProbes; }

  private:
    void updateFallback(double timeOfDay_h);
    // Spends `budget` faces (primed: the probes it completes are primes); returns the faces.
    int spendFaces(const NextProbe& next, int budget, bool primed);

    struct OwnLight final : SurfaceLight {
        OwnField field;
        ShRgb shAt(const glm::dvec3& position_m) const override {
            return field(position_m.x, position_m.z);
        }
    };

    CubeCapture& capture_;
    const ProbeEnvironment& environment_;
    CaptureSettings settings_;
    std::unique_ptr<CubeMapProjector> projector_;
    std::vector<float> cube_;
    std::optional<ProbeJob> job_;
    struct Done {
        ProbeJob job;
        ShRgbD sh;
        std::optional<ShGroundGradient> gradient;
    };
    bool gradients_ = false;
    bool jobGradients_ = false;    // the probe in progress is captured with distances
    std::vector<float> distance_;  // its texels' distances (gradients_)
    std::vector<Done> completed_;

    double time_s_ = 0.0;
    bool haveTime_ = false;
    double timeOfDay_h_ = 12.0;
    double timeRate_hPerS_ = 0.0;
    double lastJump_s_ = -1.0;
    glm::dvec3 camera_m_{0.0};
    double cameraSpeed_mps_ = 0.0;
    bool haveCamera_ = false;
    bool primeDue_ = false;
    ShRgb fallback_;
    bool haveFallback_ = false, fallbackChanged_ = false;
    double fallbackTimeOfDay_h_ = 0.0;
    MethodStatistics stats_;
    std::int64_t probesCompleted_ = 0, abortedProbes_ = 0;
    OwnLight ownLight_;
    AmbienceMethod::CaptureLightOverride lightOverride_;
};

// Signed difference b - a of two times of day, in (-12, 12] hours (the wrap at 24 h).
double dayDifference_h(double a, double b);

}  // namespace amb
