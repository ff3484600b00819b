// VolumeAmbience.h — the dynamic ambience volume in the frame (DESIGN.md "The frame", 2-5):
// stages 2-4 drive lighting/AmbienceVolume with captures rendered by CubeCaptureGl from the
// renderer's own scene; stage 5 answers the draw's questions from the interpolated SH:
// terrain corners get E(n) at the corner normal, objects a set of R&H matrices.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "app/FrameLoop.h"
#include "lighting/AmbienceVolume.h"

namespace amb {

class CubeCaptureGl;
class Renderer;
class WorldProbeEnvironment;

// AmbientSource over the volume's interpolation (thesis 9.3, 8.6).
class VolumeAmbient final : public AmbientSource {
  public:
    explicit VolumeAmbient(const AmbienceVolume& volume) : volume_(volume) {}
    glm::vec3 cornerIrradiance(const glm::dvec3& position_m,
                               const glm::dvec3& normal) const override;
    std::uint32_t objectSet(const glm::dvec3& position_m,
                            std::vector<AmbientSet>& sets) const override;
    // Lookups and CPU time spent answering them since the last reset (they run inside the draw
    // stage, where the scene asks for them).
    std::size_t lookups() const { return lookups_; }
    double lookupMs() const { return lookupMs_; }
    void resetCounters() { lookups_ = 0, lookupMs_ = 0.0; }

  private:
    const AmbienceVolume& volume_;
    mutable std::size_t lookups_ = 0;
    mutable double lookupMs_ = 0.0;
};

class VolumeAmbienceStages final : public AmbienceStages {
  public:
    // Needs a current GL context; the capture shares `renderer`'s scene (coarse proxies).
    VolumeAmbienceStages(Renderer& renderer, const AmbienceVolumeSettings& settings,
                         int faceSize = 16);
    ~VolumeAmbienceStages() override;

    void predict(const FrameState& frame) override;
    void capture(const FrameState& frame) override;
    void store(const FrameState& frame) override;
    const AmbientSource& interpolate(const FrameState& frame) override;

    AmbienceVolume& volume() { return *volume_; }
    const VolumeAmbient& ambient() const { return *ambient_; }
    CubeCaptureGl& cubeCapture() { return *capture_; }

  private:
    std::unique_ptr<CubeCaptureGl> capture_;
    std::unique_ptr<WorldProbeEnvironment> environment_;
    std::unique_ptr<AmbienceVolume> volume_;
    std::unique_ptr<VolumeAmbient> ambient_;
    bool havePrevious_ = false;
    glm::dvec3 previous_m_{0.0};
    double previousTime_s_ = 0.0;
};

}  // namespace amb
