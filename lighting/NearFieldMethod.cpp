// NearFieldMethod.cpp — the decorator that puts the near field back onto any method's far field
// (NearField.h, NearFieldMethod).
#include "lighting/NearField.h"

#include <algorithm>
#include <cmath>

#include "world/Error.h"

namespace amb {

// ---- [SECTION] The decorator -------------------------------------------------------------------

NearFieldMethod::NearFieldMethod(std::unique_ptr<AmbienceMethod> far,
                                 std::unique_ptr<NearFieldScene> scene,
                                 const NearFieldSettings& settings)
    : far_(std::move(far)),
      scene_(std::move(scene)),
      near_(std::make_unique<NearField>(*scene_, settings)),
      skyDetail_(settings.terrain && settings.vertexDetail) {
    AMB_CHECK(far_ && scene_);
}

NearFieldMethod::~NearFieldMethod() = default;

void NearFieldMethod::predictStage(const glm::dvec3& cameraPosition_m,
                                   const glm::dvec3& cameraVelocity_mps, double timeOfDay_h,
                                   double dt_s) {
    near_->resetCounters();
    if (std::isfinite(timeOfDay_h)) near_->setTimeOfDay(timeOfDay_h);
    if (std::isfinite(cameraPosition_m.x + cameraPosition_m.z)) {
        camera_m_ = cameraPosition_m;
        near_->setViewer(cameraPosition_m);
    }
    far_->predictStage(cameraPosition_m, cameraVelocity_mps, timeOfDay_h, dt_s);
}

namespace {

// far + w (near - far): the near field faded in by w (see Range).
ShRgb fadedNear(const ShRgb& far, const ShRgb& near, double w) {
    return w >= 1.0 ? near : lerp(far, near, float(w));
}

}  // namespace

double NearFieldMethod::weight(double x_m, double z_m, double range_m) const {
    return rangeWeight(std::hypot(x_m - camera_m_.x, z_m - camera_m_.z), range_m);
}

ShRgb NearFieldMethod::shAt(double x_m, double z_m) const {
    const ShRgb far = far_->shAt(x_m, z_m);
    const double w = weight(x_m, z_m, near_->settings().objectRange_m);
    if (w <= 0.0) return far;
    return fadedNear(far, near_->applyAbove(far, x_m, z_m, kShadingHeight_m, kSelfRadius_m), w);
}

void NearFieldMethod::gather(std::size_t count, const double* x_m, const double* z_m,
                             const ShRgb* far, double range_m) const {
    nearIndex_.clear(), nearX_.clear(), nearZ_.clear(), nearSh_.clear(), nearWeight_.clear();
    for (std::size_t i = 0; i < count; ++i) {
        const double w = weight(x_m[i], z_m[i], range_m);
        if (w <= 0.0) continue;
        nearIndex_.push_back(i), nearX_.push_back(x_m[i]), nearZ_.push_back(z_m[i]);
        nearSh_.push_back(far[i]), nearWeight_.push_back(w);
    }
}

void NearFieldMethod::scatter(ShRgb* out) const {
    for (std::size_t j = 0; j < nearIndex_.size(); ++j)
        out[nearIndex_[j]] = fadedNear(out[nearIndex_[j]], nearSh_[j], nearWeight_[j]);
}

void NearFieldMethod::shAt(std::size_t count, const double* x_m, const double* z_m,
                           ShRgb* out) const {
    far_->shAt(count, x_m, z_m, out);
    gather(count, x_m, z_m, out, near_->settings().objectRange_m);
    near_->applyAboveMany(nearSh_.size(), nearSh_.data(), nearX_.data(), nearZ_.data(),
                          kShadingHeight_m, kSelfRadius_m);
    scatter(out);
}

ShRgb NearFieldMethod::cornerShAt(double x_m, double z_m) const {
    const ShRgb far = far_->cornerShAt(x_m, z_m);
    const double w = weight(x_m, z_m, near_->settings().cornerRange_m);
    if (w <= 0.0) return far;
    return fadedNear(far, near_->applyAbove(far, x_m, z_m, kShadingHeight_m), w);
}

void NearFieldMethod::cornerShAt(std::size_t count, const double* x_m, const double* z_m,
                                 ShRgb* out) const {
    far_->cornerShAt(count, x_m, z_m, out);
    gather(count, x_m, z_m, out, near_->settings().cornerRange_m);
    near_->applyAboveMany(nearSh_.size(), nearSh_.data(), nearX_.data(), nearZ_.data(),
                          kShadingHeight_m);
    scatter(out);
}

ShRgb NearFieldMethod::cornerShAtPoint(const glm::dvec3& point_m) const {
    const ShRgb far = far_->cornerShAt(point_m.x, point_m.z);
    const double w = weight(point_m.x, point_m.z, near_->settings().cornerRange_m);
    if (w <= 0.0) return far;
    return fadedNear(far, near_->apply(far, point_m), w);
}

void NearFieldMethod::cornerShAtPoints(std::size_t count, const glm::dvec3* points_m,
                                       ShRgb* out) const {
    std::vector<double> x(count), z(count);
    for (std::size_t i = 0; i < count; ++i) x[i] = points_m[i].x, z[i] = points_m[i].z;
    far_->cornerShAt(count, x.data(), z.data(), out);
    gather(count, x.data(), z.data(), out, near_->settings().cornerRange_m);
    std::vector<glm::dvec3> points;
    points.reserve(nearIndex_.size());
    for (std::size_t i : nearIndex_) points.push_back(points_m[i]);
    near_->applyMany(points.size(), nearSh_.data(), points.data());
    scatter(out);
}

void NearFieldMethod::cornerIrradianceAtPoints(std::size_t count, const glm::dvec3* points_m,
                                               const glm::dvec3* normals, glm::vec3* out,
                                               const double* patch_m) const {
    std::vector<double> x(count), z(count);
    for (std::size_t i = 0; i < count; ++i) x[i] = points_m[i].x, z[i] = points_m[i].z;
    std::vector<ShRgb> far(count);
    far_->cornerShAt(count, x.data(), z.data(), far.data());
    irradianceFromFar(count, points_m, normals, far.data(), out, patch_m);
}

double NearFieldMethod::farCaptureRadius_m() const {
    // As CaptureSettings::nearRadius_m: what the far method's probes leave out.
    const NearFieldSettings& s = near_->settings();
    return s.enabled && s.plants ? s.captureRadius_m : 0.0;
}

void NearFieldMethod::irradianceFromFar(std::size_t count, const glm::dvec3* points_m,
                                        const glm::dvec3* normals, const ShRgb* far,
                                        glm::vec3* out, const double* patch_m) const {
    std::vector<double> x(count), z(count);
    for (std::size_t i = 0; i < count; ++i) x[i] = points_m[i].x, z[i] = points_m[i].z;
    // Every point's far-field irradiance (what the far method alone gives, not the near field's
    // time); the near field's answers replace it within range.
    for (std::size_t i = 0; i < count; ++i)
        out[i] = glm::max(shIrradiance(far[i], glm::vec3(normals[i])), glm::vec3(0.0f));
    gather(count, x.data(), z.data(), far, near_->settings().cornerRange_m);
    std::vector<glm::dvec3> points, pointNormals;
    nearPatch_.clear();
    for (std::size_t i : nearIndex_) {
        points.push_back(points_m[i]), pointNormals.push_back(normals[i]);
        nearPatch_.push_back(patch_m ? patch_m[i] : 0.0);
    }
    std::vector<glm::vec3> near(points.size());
    near_->irradianceMany(points.size(), nearSh_.data(), points.data(), pointNormals.data(),
                          near.data(), nearWeight_.data(), nearPatch_.data());
    for (std::size_t j = 0; j < nearIndex_.size(); ++j) out[nearIndex_[j]] = near[j];
}

double NearFieldMethod::terrainVertexRange_m() const {
    const NearFieldSettings& s = near_->settings();
    return s.enabled && s.vertexAmbient_m > 0.0 ? s.vertexAmbient_m : 0.0;
}

int NearFieldMethod::terrainVertexPointsPerFrame() const {
    return std::max(0, near_->settings().vertexPointsPerFrame);
}

MethodStatistics NearFieldMethod::methodStatistics() const {
    MethodStatistics s = far_->methodStatistics();
    s.nearField_s = near_->seconds();
    s.nearFieldPoints = near_->points();
    s.nearFieldBuilds = near_->builds();
    s.nearFieldBuild_s = near_->buildSeconds();
    s.nearFieldCached = near_->cachedPoints();
    s.nearFieldBytes = near_->cacheBytes();
    return s;
}

}  // namespace amb
