// VolumeAmbience.h — an ambience method in the frame (docs/DESIGN.md "The frame", 2-5): stages
// 2-4 drive an AmbienceMethod (ours, lighting/AmbienceVolume, or a baseline, lighting/Baselines.h)
// with captures rendered by CubeCaptureGl from the renderer's own scene; stage 5 answers the
// draw's questions from the method's SH: terrain corners get E(n) at the corner normal, objects
// a set of R&H matrices. The places the draw asked about are handed back to the method at the
// next frame (noteLookups), for the methods that place probes by demand.
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "app/FrameLoop.h"
#include "lighting/AmbienceVolume.h"

namespace amb {

class CubeCaptureGl;
class Renderer;
class WorldProbeEnvironment;
struct BaselineSettings;

// The names --ambient takes, and a check that throws InputError(option, ...) for others.
const std::vector<std::string>& ambienceMethodNames();
void checkAmbienceMethod(const std::string& name, const std::string& option);
std::string ambienceMethodHelp();

// AmbientSource over a method's shAt (thesis 9.3, 8.6).
class MethodAmbient final : public AmbientSource {
  public:
    explicit MethodAmbient(const AmbienceMethod& method) : method_(method) {}
    glm::vec3 cornerIrradiance(const glm::dvec3& position_m,
                               const glm::dvec3& normal) const override;
    // The batch through the method's batch shAt (AnchorStore::interpolateMany for ours).
    void cornerIrradianceBatch(std::size_t count, const glm::dvec3* positions_m,
                               const glm::dvec3* normals, glm::vec3* out) const override;
    std::uint32_t objectSet(const glm::dvec3& position_m,
                            std::vector<AmbientSet>& sets) const override;
    // Lookups and CPU time spent answering them since the last reset (they run inside the draw
    // stage, where the scene asks for them), and where they were.
    std::size_t lookups() const { return lookups_; }
    double lookupMs() const { return lookupMs_; }
    const std::vector<double>& lookupX() const { return x_; }
    const std::vector<double>& lookupZ() const { return z_; }
    void resetCounters() { lookups_ = 0, lookupMs_ = 0.0, x_.clear(), z_.clear(); }

  private:
    void note(const glm::dvec3& p) const;
    const AmbienceMethod& method_;
    mutable std::size_t lookups_ = 0;
    mutable double lookupMs_ = 0.0;
    mutable std::vector<double> x_, z_;
    mutable std::vector<double> batchX_, batchZ_;  // scratch of the batch
    mutable std::vector<ShRgb> batchSh_;
};

// The SH of the fixed ambients (AmbientMode): the same at every point, from the sky model.
class FixedMethod final : public AmbienceMethod {
  public:
    FixedMethod(AmbientMode mode, const Sky& sky) : mode_(mode), sky_(sky) {}
    std::string methodName() const override { return toString(mode_); }
    void predictStage(const glm::dvec3&, const glm::dvec3&, double timeOfDay_h, double) override;
    void captureStage() override {}
    void storeStage() override {}
    ShRgb shAt(double, double) const override { return sh_; }
    MethodStatistics methodStatistics() const override { return stats_; }

  private:
    AmbientMode mode_;
    const Sky& sky_;
    double timeOfDay_h_ = -1.0;
    ShRgb sh_;
    MethodStatistics stats_;
};

class MethodAmbienceStages final : public AmbienceStages {
  public:
    // Needs a current GL context; the capture shares `renderer`'s scene (coarse proxies).
    // `method`: volume, nearest, grid, reactive, object, constant or hemisphere.
    MethodAmbienceStages(Renderer& renderer, const std::string& method,
                         const AmbienceVolumeSettings& settings, const BaselineSettings& baselines,
                         int faceSize = 16);
    // Ours with default baseline settings.
    MethodAmbienceStages(Renderer& renderer, const AmbienceVolumeSettings& settings,
                         int faceSize = 16);
    ~MethodAmbienceStages() override;

    void predict(const FrameState& frame) override;
    void capture(const FrameState& frame) override;
    void store(const FrameState& frame) override;
    const AmbientSource& interpolate(const FrameState& frame) override;

    AmbienceMethod& method() { return *method_; }
    const AmbienceMethod& method() const { return *method_; }
    // Ours, or null for a baseline.
    AmbienceVolume* volume() { return dynamic_cast<AmbienceVolume*>(method_.get()); }
    const MethodAmbient& ambient() const { return *ambient_; }
    CubeCaptureGl& cubeCapture() { return *capture_; }
    const ProbeEnvironment& environment() const;
    // Lookups to hand to the method at the next frame besides the draw's (a run without the
    // main view hands the places the draw would have looked at).
    void addLookups(const std::vector<double>& x_m, const std::vector<double>& z_m);
    // The camera's velocity this frame (from its own history; zero across a cut).
    const glm::dvec3& velocity() const { return velocity_; }

  private:
    std::unique_ptr<CubeCaptureGl> capture_;
    std::unique_ptr<WorldProbeEnvironment> environment_;
    std::unique_ptr<AmbienceMethod> method_;
    std::unique_ptr<MethodAmbient> ambient_;
    std::vector<double> extraX_, extraZ_;
    bool havePrevious_ = false;
    glm::dvec3 previous_m_{0.0};
    glm::dvec3 velocity_{0.0};
    double previousTime_s_ = 0.0;
};

}  // namespace amb
