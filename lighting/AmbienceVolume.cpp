// AmbienceVolume.cpp — the per-frame ambience pipeline (see AmbienceVolume.h).
//
// [SECTION] Settings from JSON
// [SECTION] Construction, sky level
// [SECTION] update(): time, predict, capture + project, store
#include "lighting/AmbienceVolume.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "lighting/ProbeEnvironment.h"
#include "lighting/SettingsSchema.h"
#include "world/Conventions.h"
#include "world/Error.h"

namespace amb {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

LatticeKey latticeKey(const ProbeKey& key) {
    return {key.level, std::int32_t(key.i), std::int32_t(key.k)};
}
ProbeKey probeKey(const LatticeKey& key) {
    return {key.level, key.i, key.k};
}

}  // namespace

// ---- Settings from JSON -------------------------------------------------------------------------

AmbienceVolumeSettings ambienceSettingsFromJson(const std::string& jsonText,
                                                const std::string& where) {
    return volumeSettingsSchema().read(jsonText, where);
}

// ---- Construction, sky level ---------------------------------------------------------------------

AmbienceVolume::AmbienceVolume(CubeCapture& capture, const ProbeEnvironment& environment,
                               const AmbienceVolumeSettings& settings, const RoadNetwork* roads)
    : environment_(environment),
      settings_(settings),
      store_(settings.store),
      scheduler_(settings.scheduler),
      core_(capture, environment, settings.capture) {
    scheduler_.setRoads(roads);
    core_.setGradients(settings.store.gradients);
    frameTime_s_ = settings.nominalFrameTime_s;
    core_.setOwnField([this](double x_m, double z_m) { return store_.interpolate(x_m, z_m); });
}

AmbienceVolume::~AmbienceVolume() = default;

bool AmbienceVolume::retunable(const AmbienceVolumeSettings& from,
                               const AmbienceVolumeSettings& to) {
    return volumeSettingsSchema().sameWhereRebuilding(from, to);
}

void AmbienceVolume::retune(const AmbienceVolumeSettings& settings) {
    AMB_CHECK(retunable(settings_, settings));
    settings_ = settings;
    store_.retune(settings.store);
    scheduler_.setSettings(settings.scheduler);
    core_.retune(settings.capture);
    core_.setGradients(settings.store.gradients);
}

std::optional<ProbeInProgress> AmbienceVolume::probeInProgress() const {
    const std::optional<ProbeJob>& job = core_.job();
    if (!job) return std::nullopt;
    return ProbeInProgress{latticeKey(job->key), job->position_m, job->facesDone};
}

double AmbienceVolume::currentLifetime_s() const {
    return anchorLifetime_s(settings_.store, environment_.sunAngularSpeed_radPerHour(),
                            core_.timeRate_hPerS());
}

double AmbienceVolume::skyLevel(double timeOfDay_h) const {
    // Cached per minute of the day: the level changes slowly and anchors share capture minutes.
    const int minute =
        int(std::floor(std::fmod(std::fmod(timeOfDay_h, 24.0) + 24.0, 24.0) * 60.0)) % 1440;
    if (auto it = skyLevels_.find(minute); it != skyLevels_.end()) return it->second;
    // Mean luminance of the fallback scene (sky over lit flat ground) on a small cube, texels
    // clamped at the sun threshold so the disc (lit separately by the renderer) does not count.
    constexpr int kN = 8;
    std::vector<float> cube;
    environment_.fallbackCubeMap((minute + 0.5) / 60.0, kN, cube);
    double sum = 0.0;
    for (std::size_t t = 0; t + 2 < cube.size(); t += 3) {
        const double lum = luminance(glm::dvec3(cube[t], cube[t + 1], cube[t + 2]));
        sum += std::min(std::isfinite(lum) ? std::max(lum, 0.0) : 0.0,
                        settings_.capture.sunThreshold);
    }
    const double level = std::max(sum / double(cube.size() / 3), 1e-12);
    skyLevels_.emplace(minute, level);
    return level;
}

// ---- update() -----------------------------------------------------------------------------------

void AmbienceVolume::update(const glm::dvec3& cameraPosition_m,
                            const glm::dvec3& cameraVelocity_mps, double timeOfDay_h, double dt_s) {
    predictStage(cameraPosition_m, cameraVelocity_mps, timeOfDay_h, dt_s);
    captureStage();
    storeStage();
}

void AmbienceVolume::predictStage(const glm::dvec3& cameraPosition_m,
                                  const glm::dvec3& cameraVelocity_mps, double timeOfDay_h,
                                  double dt_s) {
    // 1. Time (clock, rate of the time of day, jumps), teleports and the fallback: the rules
    // every capturing method shares (CaptureCore.h). A jump shortens every anchor's life.
    const FrameEvents events = core_.beginFrame(cameraPosition_m, cameraVelocity_mps, timeOfDay_h, dt_s);
    if (events.timeJump) store_.expireAllWithin(settings_.store.blendTime_s);
    // Before this frame's inserts: a new anchor starts from what the store shows at its point,
    // and in the first frame that must already be the sky, not zero.
    if (core_.fallbackChanged()) store_.setFallback(core_.fallback());
    if (std::isfinite(dt_s) && dt_s > 0.0) frameTime_s_ = std::clamp(dt_s, 1.0 / 240.0, 0.25);
    probesPerSecond_ = double(settings_.capture.facesPerFrame) / double(kCubeFaces) / frameTime_s_;

    // 2. Predict: the motion model starts over at a teleport's new place.
    const Clock::time_point t0 = Clock::now();
    if (events.teleport) scheduler_.reset();
    scheduler_.observe(cameraPosition_m, cameraVelocity_mps, core_.time_s());
    stats_.finestLevel = scheduler_.finestLevel(store_, probesPerSecond_);
    core_.addPredictTime(secondsSince(t0));
    syncStatistics();
}

void AmbienceVolume::captureStage() {
    // 3. Capture this frame's faces (CaptureCore), the scheduler naming each next probe.
    core_.captureFaces([&](const std::vector<ProbeKey>& busyKeys) -> std::optional<ProbeRequest> {
        std::vector<LatticeKey> busy;
        for (const ProbeKey& k : busyKeys) busy.push_back(latticeKey(k));
        const auto choice = scheduler_.choose(store_, probesPerSecond_, busy);
        if (!choice) return std::nullopt;
        const double aside = std::min(settings_.asideFraction * store_.spacing_m(choice->key.level),
                                      settings_.capture.maxAside_m);
        return ProbeRequest{probeKey(choice->key), store_.keyX_m(choice->key),
                            store_.keyZ_m(choice->key), aside};
    });
    syncStatistics();
}

void AmbienceVolume::storeStage() {
    // 4. Store: advance the clock (blend, fade, expire, prune), then insert completed probes.
    const double timeOfDay_h = core_.timeOfDay_h();
    const Clock::time_point t0 = Clock::now();
    store_.advance(core_.time_s());
    const double lifetime = currentLifetime_s();
    for (const CompletedProbe& c : core_.takeCompleted()) {
        const auto result =
            store_.insert(latticeKey(c.job.key), c.sh, c.job.position_m, lifetime, timeOfDay_h,
                          c.slope ? &*c.slope : nullptr, c.job.primed);
        if (result == AnchorStore::InsertResult::Rejected) core_.countRejected();
    }
    if (settings_.relightBySkyLevel) {
        // Stale anchors follow the sky's overall level since their capture (see the header).
        const double now = skyLevel(timeOfDay_h);
        store_.relight([&](const Anchor& a) {
            return float(std::clamp(now / skyLevel(a.captureTimeOfDay_h), 1e-3, 1e3));
        });
    }
    core_.addStoreTime(secondsSince(t0));
    stats_.store = store_.statistics();
    syncStatistics();
}

void AmbienceVolume::syncStatistics() {
    const MethodStatistics& m = core_.statistics();
    stats_.facesThisFrame = m.facesThisFrame;
    stats_.facesCaptured = m.facesCaptured;
    stats_.primeFaces = m.primeFaces;
    stats_.probesCompleted = core_.probesCompleted();
    stats_.rejectedProbes = m.rejectedProbes;
    stats_.abortedProbes = core_.abortedProbes();
    stats_.teleports = m.teleports;
    stats_.predict_s = m.predict_s;
    stats_.capture_s = m.capture_s;
    stats_.project_s = m.project_s;
    stats_.store_s = m.store_s;
}

MethodStatistics AmbienceVolume::methodStatistics() const {
    MethodStatistics m = core_.statistics();
    m.probes = stats_.store.anchors;
    m.bytes = stats_.store.bytes();
    return m;
}

IdealSupport AmbienceVolume::idealSupport(double x_m, double z_m) const {
    InterpolationDetail detail;
    store_.interpolate(x_m, z_m, &detail);
    return bilinearSupport(x_m, z_m, store_.spacing_m(std::max(0, detail.level)));
}

}  // namespace amb
