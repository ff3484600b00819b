// MethodStages.h — an ambience method in the frame (docs/ARCHITECTURE.md "The frame", 2-5 and
// 7): stages 2-4 drive an AmbienceMethod (ours, lighting/AmbienceVolume.h, or a baseline,
// lighting/Baselines.h) with the captures of a CubeCapture (the renderer's, CubeCaptureGl, in
// the app); stage 5 answers the draw's questions from the method's SH: terrain corners get E(n)
// at the corner normal, objects a set of R&H matrices. The places the draw asked about are
// handed back to the method at the next frame (noteLookups), for the methods that place probes
// by demand. Stage 7 reads the method's state into the frame's record and, with an ErrorMeter
// attached, measures its error. No GL here.
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "app/frame/FrameLoop.h"
#include "app/frame/SkyLighting.h"
#include "lighting/AmbienceVolume.h"

namespace amb {

class CubeCapture;
class ErrorMeter;
class World;
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
                               const glm::dvec3* normals, glm::vec3* out,
                               const double* patch_m = nullptr) const override;
    std::uint32_t objectSet(const glm::dvec3& position_m,
                            std::vector<AmbientSet>& sets) const override;
    bool terrainSkyDetail() const override { return method_.terrainSkyDetail(); }
    double terrainVertexRange_m() const override { return method_.terrainVertexRange_m(); }
    int terrainVertexPointsPerFrame() const override {
        return method_.terrainVertexPointsPerFrame();
    }
    // The batch through the method's batch shAt (one timing, one lock of the near field).
    void objectSets(std::size_t count, const glm::dvec3* positions_m,
                    std::vector<AmbientSet>& sets, std::uint32_t* index) const override;
    // Lookups and CPU time spent answering them since the last reset (they run inside the draw
    // stage, where the scene asks for them), and where they were.
    std::size_t lookups() const { return lookups_; }
    double lookup_ms() const { return lookup_ms_; }
    const std::vector<double>& lookupX() const { return x_; }
    const std::vector<double>& lookupZ() const { return z_; }
    void resetCounters() { lookups_ = 0, lookup_ms_ = 0.0, x_.clear(), z_.clear(); }

  private:
    void note(const glm::dvec3& p) const;
    const AmbienceMethod& method_;
    mutable std::size_t lookups_ = 0;
    mutable double lookup_ms_ = 0.0;
    mutable std::vector<double> x_, z_;
    mutable std::vector<glm::dvec3> batchAt_;  // scratch of the batch: the shading points
    mutable std::vector<double> batchX_, batchZ_;  // and the objects' ground points
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
    // `capture` renders the method's probes (and the oracle's, when one is attached); `world`
    // must outlive the stages. `method`: volume, nearest, grid, reactive, object, constant or
    // hemisphere.
    MethodAmbienceStages(std::unique_ptr<CubeCapture> capture, const World& world,
                         const std::string& method, const AmbienceVolumeSettings& settings,
                         const BaselineSettings& baselines);
    ~MethodAmbienceStages() override;

    void predict(const FrameState& frame) override;
    void capture(const FrameState& frame) override;
    void store(const FrameState& frame) override;
    const AmbientSource& interpolate(const FrameState& frame) override;
    // The method's statistics into record.ambience; with a meter attached, the frame's error
    // (ErrorMeter::frame) and the pop along the camera (record.popMove).
    void measure(const FrameState& frame, FrameRecord& record) override;
    // Measure every frame against `meter` (null: stop); it must outlive the stages.
    void attachMeter(ErrorMeter* meter) { meter_ = meter; }
    // For a loop that draws no main view: in stage 7, look the method up where the draw would
    // have (drawLookupStandIn), timed as the draw's lookups and handed to the method as such.
    void setLookupStandIn(bool on) { standIn_ = on; }

    AmbienceMethod& method() { return *method_; }
    const AmbienceMethod& method() const { return *method_; }
    // Ours, or null for a baseline.
    AmbienceVolume* volume() { return volume_; }
    const MethodAmbient& ambient() const { return *ambient_; }
    CubeCapture& cubeCapture() { return *capture_; }
    const ProbeEnvironment& environment() const;
    // Lookups to hand to the method at the next frame besides the draw's (a run without the
    // main view hands the places the draw would have looked at).
    void addLookups(const std::vector<double>& x_m, const std::vector<double>& z_m);
    // The camera's velocity this frame (from its own history; zero across a cut).
    const glm::dvec3& velocity() const { return velocity_; }

  private:
    std::unique_ptr<CubeCapture> capture_;
    std::unique_ptr<WorldProbeEnvironment> environment_;
    std::unique_ptr<AmbienceMethod> method_;  // with the near field around it when enabled
    AmbienceVolume* volume_ = nullptr;        // the method when it is ours
    std::unique_ptr<MethodAmbient> ambient_;
    std::vector<double> extraX_, extraZ_;
    bool havePrevious_ = false;
    glm::dvec3 previous_m_{0.0};
    glm::dvec3 velocity_{0.0};
    double previousTime_s_ = 0.0;
    ErrorMeter* meter_ = nullptr;
    bool standIn_ = false;
    std::vector<double> standInX_, standInZ_;
    std::vector<ShRgb> standInSh_;
};

}  // namespace amb
