// MethodStages.cpp — an ambience method as the frame's stages 2-5 and 7.
#include "app/frame/MethodStages.h"

#include <glm/geometric.hpp>

#include "lighting/Baselines.h"
#include "lighting/CubeCapture.h"
#include "lighting/Metrics.h"
#include "lighting/NearField.h"
#include "lighting/ProbeEnvironment.h"
#include "lighting/SH.h"
#include "world/Error.h"
#include "world/World.h"

namespace amb {

namespace {
using Clock = std::chrono::steady_clock;
double elapsed_ms(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
}  // namespace

const std::vector<std::string>& ambienceMethodNames() {
    static const std::vector<std::string> names = {"volume", "nearest",  "grid",      "reactive",
                                                   "object", "constant", "hemisphere"};
    return names;
}

void checkAmbienceMethod(const std::string& name, const std::string& option) {
    for (const auto& n : ambienceMethodNames())
        if (n == name) return;
    std::string list;
    for (const auto& n : ambienceMethodNames()) list += (list.empty() ? "" : ", ") + n;
    throw InputError(option,
                     "unknown ambience method '" + name + "' (expected one of " + list + ")");
}

std::string ambienceMethodHelp() {
    return "volume (ours: the dynamic ambience volume, default), nearest (ours without "
           "blending: the nearest anchor), grid (camera-centred scrolling grid, round-robin "
           "with hysteresis), reactive (probes only where lookups happen), object (one capture "
           "per object), constant, hemisphere";
}

// ---- MethodAmbient ---------------------------------------------------------------------------

void MethodAmbient::note(const glm::dvec3& p) const {
    if (!method_.wantsLookups()) return;
    x_.push_back(p.x);
    z_.push_back(p.z);
}

glm::vec3 MethodAmbient::cornerIrradiance(const glm::dvec3& position_m,
                                          const glm::dvec3& normal) const {
    const auto t0 = Clock::now();
    // Terrain (thesis 8.6): the colour at a patch corner from the SH interpolated there, with
    // the corner's normal; the renderer interpolates it across the patch.
    const ShRgb sh = method_.cornerShAtPoint(position_m + glm::dvec3(0.0, kShadingHeight_m, 0.0));
    const glm::vec3 e = glm::max(shIrradiance(sh, glm::vec3(normal)), glm::vec3(0.0f));
    ++lookups_;
    note(position_m);
    lookup_ms_ += elapsed_ms(t0);
    return e;
}

void MethodAmbient::cornerIrradianceBatch(std::size_t count, const glm::dvec3* positions_m,
                                          const glm::dvec3* normals, glm::vec3* out,
                                          const double* patch_m) const {
    const auto t0 = Clock::now();
    batchAt_.resize(count);
    for (std::size_t i = 0; i < count; ++i)
        batchAt_[i] = positions_m[i] + glm::dvec3(0.0, kShadingHeight_m, 0.0);
    method_.cornerIrradianceAtPoints(count, batchAt_.data(), normals, out, patch_m);
    for (std::size_t i = 0; i < count; ++i) note(positions_m[i]);
    lookups_ += count;
    lookup_ms_ += elapsed_ms(t0);
}

std::uint32_t MethodAmbient::objectSet(const glm::dvec3& position_m,
                                       std::vector<AmbientSet>& sets) const {
    std::uint32_t index = 0;
    objectSets(1, &position_m, sets, &index);
    return index;
}

void MethodAmbient::objectSets(std::size_t count, const glm::dvec3* positions_m,
                               std::vector<AmbientSet>& sets, std::uint32_t* index) const {
    const auto t0 = Clock::now();
    // Objects (thesis 8.6, 9.4): one SH set at the object's ground point, evaluated per pixel
    // with the normal through R&H's matrices.
    batchX_.resize(count), batchZ_.resize(count), batchSh_.resize(count);
    for (std::size_t i = 0; i < count; ++i) batchX_[i] = positions_m[i].x, batchZ_[i] = positions_m[i].z;
    method_.shAt(count, batchX_.data(), batchZ_.data(), batchSh_.data());
    for (std::size_t i = 0; i < count; ++i) {
        const ShIrradianceMatrices m = shIrradianceMatrices(batchSh_[i]);
        sets.push_back(AmbientSet{m.r, m.g, m.b});
        index[i] = std::uint32_t(sets.size() - 1);
        note(positions_m[i]);
    }
    lookups_ += count;
    lookup_ms_ += elapsed_ms(t0);
}

// ---- FixedMethod -----------------------------------------------------------------------------

void FixedMethod::predictStage(const glm::dvec3&, const glm::dvec3&, double timeOfDay_h, double) {
    if (timeOfDay_h == timeOfDay_h_) return;
    timeOfDay_h_ = timeOfDay_h;
    // The same SH FixedAmbient draws with (Renderer.h): the sky and ground means.
    sh_ = FixedAmbient(mode_, evaluateSky(sky_, timeOfDay_h)).sh();
}

// ---- MethodAmbienceStages --------------------------------------------------------------------

MethodAmbienceStages::MethodAmbienceStages(std::unique_ptr<CubeCapture> capture, const World& world,
                                           const std::string& method,
                                           const AmbienceVolumeSettings& settings,
                                           const BaselineSettings& baselines)
    : capture_(std::move(capture)), environment_(std::make_unique<WorldProbeEnvironment>(world)) {
    if (method == "constant" || method == "hemisphere") {
        method_ = std::make_unique<FixedMethod>(parseAmbientMode(method, "--ambient"), world.sky());
    } else {
        // The two-scale ambience: the method's own settings say whether its captures leave the
        // near plants out; then the factory wraps it so that every shading point gets them
        // back, from the world drawn (lighting/NearField.h).
        method_ = makeCapturingMethod(method, *capture_, *environment_, settings, baselines,
                                      &world.roads(), [&world] {
                                          return std::make_unique<WorldNearFieldScene>(world);
                                      });
        auto* near = dynamic_cast<NearFieldMethod*>(method_.get());
        volume_ = dynamic_cast<AmbienceVolume*>(near ? &near->far() : method_.get());
    }
    ambient_ = std::make_unique<MethodAmbient>(*method_);
}

MethodAmbienceStages::~MethodAmbienceStages() = default;

const ProbeEnvironment& MethodAmbienceStages::environment() const {
    return *environment_;
}

void MethodAmbienceStages::addLookups(const std::vector<double>& x_m,
                                      const std::vector<double>& z_m) {
    extraX_.insert(extraX_.end(), x_m.begin(), x_m.end());
    extraZ_.insert(extraZ_.end(), z_m.begin(), z_m.end());
}

void MethodAmbienceStages::predict(const FrameState& frame) {
    // Where the last frame's draw (and the measurement's stand-in for it) looked.
    std::vector<double> x = ambient_->lookupX(), z = ambient_->lookupZ();
    x.insert(x.end(), extraX_.begin(), extraX_.end());
    z.insert(z.end(), extraZ_.begin(), extraZ_.end());
    extraX_.clear(), extraZ_.clear();
    if (!x.empty() && method_->wantsLookups()) method_->noteLookups(x.size(), x.data(), z.data());
    // Velocity from the camera's own history (the scheduler's inertia model); none across a cut.
    const glm::dvec3 p = frame.camera.position_m;
    const double dt = havePrevious_ ? frame.time_s - previousTime_s_ : 0.0;
    velocity_ = glm::dvec3(0.0);
    if (havePrevious_ && dt > 0.0 && !frame.camera.cut) velocity_ = (p - previous_m_) / dt;
    method_->predictStage(p, velocity_, frame.timeOfDay_h, dt);
    havePrevious_ = true;
    previous_m_ = p;
    previousTime_s_ = frame.time_s;
}

void MethodAmbienceStages::capture(const FrameState&) {
    method_->captureStage();
}

void MethodAmbienceStages::store(const FrameState&) {
    method_->storeStage();
}

const AmbientSource& MethodAmbienceStages::interpolate(const FrameState&) {
    ambient_->resetCounters();
    return *ambient_;
}

void MethodAmbienceStages::measure(const FrameState& frame, FrameRecord& rec) {
    const MethodStatistics st = method_->methodStatistics();
    FrameRecord::Ambience& a = rec.ambience;
    a.active = true;
    a.anchors = st.probes;
    a.bytes = st.bytes;
    a.faces = st.facesThisFrame;
    a.lookups = ambient_->lookups();
    a.lookup_ms = ambient_->lookup_ms();
    a.capture_ms = st.capture_s * 1e3;
    a.predict_ms = st.predict_s * 1e3;
    a.project_ms = st.project_s * 1e3;
    a.store_ms = st.store_s * 1e3;
    a.nearField_ms = st.nearField_s * 1e3;
    a.nearFieldPoints = st.nearFieldPoints;
    a.nearFieldBuild_ms = st.nearFieldBuild_s * 1e3;
    a.nearFieldBuilds = st.nearFieldBuilds;
    a.nearFieldBytes = st.nearFieldBytes;
    if (const AmbienceVolume* v = volume()) {
        const AmbienceStatistics& vs = v->statistics();
        a.finestLevel = vs.finestLevel;
        a.levels = v->store().levels();
        a.anchorsPerLevel = vs.store.anchorsPerLevel;
    }
    if (meter_) {
        meter_->frame(rec.index, rec.time_s, rec.timeOfDay_h, frame.camera.position_m,
                      glm::length(velocity_), *method_);
        rec.popMove = meter_->lastMovingPop();
    }
    if (standIn_) {
        drawLookupStandIn(frame.camera, standInX_, standInZ_);
        standInSh_.resize(standInX_.size());
        const auto t0 = Clock::now();
        method_->shAt(standInX_.size(), standInX_.data(), standInZ_.data(), standInSh_.data());
        a.lookups = standInX_.size();
        a.lookup_ms = elapsed_ms(t0);
        addLookups(standInX_, standInZ_);
    }
}

}  // namespace amb
