// VolumeAmbience.cpp — the ambience volume as the frame's stages 2-5.
#include "app/VolumeAmbience.h"

#include "app/CubeCaptureGl.h"
#include "app/Renderer.h"
#include "lighting/ProbeEnvironment.h"
#include "lighting/SH.h"
#include "world/World.h"

namespace amb {

namespace {
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
}  // namespace

// ---- VolumeAmbient ---------------------------------------------------------------------------

glm::vec3 VolumeAmbient::cornerIrradiance(const glm::dvec3& position_m,
                                          const glm::dvec3& normal) const {
    const auto t0 = Clock::now();
    // Terrain (thesis 8.6): the colour at a patch corner from the SH interpolated there, with
    // the corner's normal; the renderer interpolates it across the patch.
    const ShRgb sh = volume_.shAt(position_m.x, position_m.z);
    const glm::vec3 e = glm::max(shIrradiance(sh, glm::vec3(normal)), glm::vec3(0.0f));
    ++lookups_;
    lookupMs_ += msSince(t0);
    return e;
}

std::uint32_t VolumeAmbient::objectSet(const glm::dvec3& position_m,
                                       std::vector<AmbientSet>& sets) const {
    const auto t0 = Clock::now();
    // Objects (thesis 8.6, 9.4): one SH set at the object's ground point, evaluated per pixel
    // with the normal through R&H's matrices.
    const ShIrradianceMatrices m = shIrradianceMatrices(volume_.shAt(position_m.x, position_m.z));
    sets.push_back(AmbientSet{m.r, m.g, m.b});
    ++lookups_;
    lookupMs_ += msSince(t0);
    return std::uint32_t(sets.size() - 1);
}

// ---- VolumeAmbienceStages --------------------------------------------------------------------

VolumeAmbienceStages::VolumeAmbienceStages(Renderer& renderer,
                                           const AmbienceVolumeSettings& settings, int faceSize)
    : capture_(std::make_unique<CubeCaptureGl>(renderer.scene(), faceSize)),
      environment_(std::make_unique<WorldProbeEnvironment>(renderer.world())),
      volume_(std::make_unique<AmbienceVolume>(*capture_, *environment_, settings,
                                               &renderer.world().roads())),
      ambient_(std::make_unique<VolumeAmbient>(*volume_)) {}

VolumeAmbienceStages::~VolumeAmbienceStages() = default;

void VolumeAmbienceStages::predict(const FrameState& frame) {
    // Velocity from the camera's own history (the scheduler's inertia model); none across a cut.
    const glm::dvec3 p = frame.camera.position_m;
    const double dt = havePrevious_ ? frame.time_s - previousTime_s_ : 0.0;
    glm::dvec3 velocity(0.0);
    if (havePrevious_ && dt > 0.0 && !frame.camera.cut) velocity = (p - previous_m_) / dt;
    volume_->predictStage(p, velocity, frame.timeOfDay_h, dt);
    havePrevious_ = true;
    previous_m_ = p;
    previousTime_s_ = frame.time_s;
}

void VolumeAmbienceStages::capture(const FrameState&) { volume_->captureStage(); }

void VolumeAmbienceStages::store(const FrameState&) { volume_->storeStage(); }

const AmbientSource& VolumeAmbienceStages::interpolate(const FrameState&) {
    ambient_->resetCounters();
    return *ambient_;
}

}  // namespace amb
