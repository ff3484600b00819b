// NearFieldMethod.cpp — the decorator that puts the near field back onto any method's far field
// (NearField.h, NearFieldMethod).
#include "lighting/NearField.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <utility>
#include <vector>

#include "lighting/CubeCapture.h"
#include "world/Error.h"

namespace amb {

// ---- [SECTION] Captures' light ---------------------------------------------------------------
//
// A capture lights its surfaces with the hemisphere ambient (or, with ownLight, its method's own
// far field): a forest floor as if it stood in the open, or as if no tree stood within
// captureRadius_m of where the field was captured. The draw puts those plants, the terrain's
// walls and the ground back at each terrain corner; this light does the same for the captures'
// surfaces, on a lattice of captureLightCell_m within captureLightRange_m of the camera: at
// each lattice point the near field's change of that light there (the corner path,
// kShadingHeight_m up, whose transfers the near field caches with the draw's corners), faded
// out over the range's last quarter and blended bilinearly, is added to the light at the
// surface. A lattice point's change is made once it is in range (at most
// captureLightPointsPerFrame new points a frame, nearest the camera first: the near field's
// build of a point costs milliseconds) and remade after kRefreshFrames to 2 kRefreshFrames
// frames (staggered by its key), so that it follows the light and the method's own field
// without remaking the whole lattice in one frame.
class NearFieldMethod::CaptureLight final : public SurfaceLight {
  public:
    // own: the far method's own field, or null for the hemisphere ambient.
    CaptureLight(const NearFieldMethod& method, const SurfaceLight* own)
        : method_(method), own_(own) {}

    ShRgb shAt(const glm::dvec3& position_m) const override {
        std::lock_guard<std::mutex> lock(mutex_);
        ShRgb out = base(position_m);
        if (change_.empty()) return out;
        const double cell = method_.near_->settings().captureLightCell_m;
        const double fx = position_m.x / cell, fz = position_m.z / cell;
        if (!std::isfinite(fx + fz) || std::fabs(fx) > 1e15 || std::fabs(fz) > 1e15) return out;
        const double i0 = std::floor(fx), k0 = std::floor(fz);
        const float tx = float(fx - i0), tz = float(fz - k0);
        for (int corner = 0; corner < 4; ++corner) {
            const Index q{std::int64_t(i0) + (corner & 1), std::int64_t(k0) + (corner >> 1)};
            const auto it = change_.find(q);
            if (it == change_.end()) continue;
            const float w = ((corner & 1) ? tx : 1.0f - tx) * ((corner >> 1) ? tz : 1.0f - tz);
            out += it->second.change * (w * it->second.fade);
        }
        return out;
    }

    using Index = std::pair<std::int64_t, std::int64_t>;
    static constexpr std::uint64_t kRefreshFrames = 30;

    // Once a frame, before the frame's captures (NearFieldMethod::captureStage), with the
    // frame's time of day and camera: the lattice points in range whose change is missing or
    // due, made at once (the near field builds the new ones on every thread); those out of
    // range dropped. Made in the method's own stage, not by whoever asks first, so that what
    // the light holds does not depend on who reads it (the error budget's fresh captures, which
    // a cached reference skips).
    void prepare(double timeOfDay_h) {
        std::lock_guard<std::mutex> lock(mutex_);
        const std::uint64_t frame = ++frame_;
        if (std::isfinite(timeOfDay_h))
            hemisphere_ = hemisphereSh(method_.scene_->ambient(timeOfDay_h));
        const NearFieldSettings& s = method_.near_->settings();
        const double range = s.captureLightRange_m, cell = s.captureLightCell_m;
        const glm::dvec3 c = method_.camera_m_;
        if (!(range > 0.0) || !(cell > 0.0) || !std::isfinite(c.x + c.z)) return;
        const auto lo = [&](double v) { return std::int64_t(std::floor((v - range) / cell)); };
        const auto hi = [&](double v) { return std::int64_t(std::ceil((v + range) / cell)); };
        for (auto it = change_.begin(); it != change_.end();) {
            const double w = rangeWeight(std::hypot(double(it->first.first) * cell - c.x,
                                                    double(it->first.second) * cell - c.z),
                                         range);
            if (!(w > 0.0)) {
                it = change_.erase(it);
            } else {
                it.value().fade = float(w);
                ++it;
            }
        }
        // Due ones (their transfers cached) all; new ones nearest first, at most
        // captureLightPointsPerFrame (0: no bound).
        std::vector<std::pair<double, Index>> fresh;
        std::vector<Index> keys;
        for (std::int64_t k = lo(c.z); k <= hi(c.z); ++k)
            for (std::int64_t i = lo(c.x); i <= hi(c.x); ++i) {
                const double d = std::hypot(double(i) * cell - c.x, double(k) * cell - c.z);
                if (!(rangeWeight(d, range) > 0.0)) continue;
                const auto it = change_.find({i, k});
                if (it == change_.end())
                    fresh.push_back({d, {i, k}});
                else if (frame >= it->second.due)
                    keys.push_back({i, k});
            }
        const std::size_t bound = s.captureLightPointsPerFrame > 0
                                      ? std::size_t(s.captureLightPointsPerFrame)
                                      : fresh.size();
        if (fresh.size() > bound) {
            std::nth_element(fresh.begin(), fresh.begin() + std::ptrdiff_t(bound), fresh.end());
            fresh.resize(bound);
        }
        for (const auto& f : fresh) keys.push_back(f.second);
        if (keys.empty()) return;
        std::vector<double> x, z;
        std::vector<ShRgb> light;
        for (const Index& q : keys) {
            x.push_back(double(q.first) * cell), z.push_back(double(q.second) * cell);
            light.push_back(base(glm::dvec3(x.back(), 0.0, z.back())));
        }
        std::vector<ShRgb> near = light;
        method_.near_->applyAboveMany(near.size(), near.data(), x.data(), z.data(),
                                      kShadingHeight_m);
        for (std::size_t j = 0; j < keys.size(); ++j) {
            const ShRgb d = near[j] - light[j];
            bool finite = true;
            for (const glm::vec3& v : d.c) finite = finite && std::isfinite(v.x + v.y + v.z);
            const std::uint64_t stagger =
                std::uint64_t(keys[j].first * 7 + keys[j].second * 13) % kRefreshFrames;
            const double w = rangeWeight(std::hypot(x[j] - c.x, z[j] - c.z), range);
            if (finite)
                change_[keys[j]] = Entry{d, frame + kRefreshFrames + stagger, float(w)};
            else
                change_.erase(keys[j]);
        }
    }

  private:
    ShRgb base(const glm::dvec3& position_m) const {
        return own_ ? own_->shAt(position_m) : hemisphere_;
    }

    struct Entry {
        ShRgb change;           // the near field's change of the light there, unfaded
        std::uint64_t due = 0;  // the frame from which it is remade
        float fade = 1.0f;      // its range weight from this frame's camera
    };
    struct IndexHash {
        std::size_t operator()(const Index& q) const {
            std::uint64_t h = std::uint64_t(q.first) * 0x9e3779b97f4a7c15ull ^
                              std::uint64_t(q.second) * 0xc2b2ae3d27d4eb4full;
            h ^= h >> 29;
            return std::size_t(h);
        }
    };
    const NearFieldMethod& method_;
    const SurfaceLight* own_;
    mutable std::mutex mutex_;
    std::uint64_t frame_ = 0;  // prepare's count
    ShRgb hemisphere_;
    tsl::hopscotch_map<Index, Entry, IndexHash> change_;
};

// ---- [SECTION] The decorator -------------------------------------------------------------------

NearFieldMethod::NearFieldMethod(std::unique_ptr<AmbienceMethod> far,
                                 std::unique_ptr<NearFieldScene> scene,
                                 const NearFieldSettings& settings)
    : far_(std::move(far)),
      scene_(std::move(scene)),
      near_(std::make_unique<NearField>(*scene_, settings)),
      skyDetail_(settings.terrain && settings.vertexDetail) {
    AMB_CHECK(far_ && scene_);
    if (settings.enabled && settings.captureLightRange_m > 0.0) {
        captureLight_ = std::make_unique<CaptureLight>(*this, far_->captureSurfaceLight());
        overrideCaptureLight({});
    }
}

NearFieldMethod::~NearFieldMethod() = default;

void NearFieldMethod::captureStage() {
    if (captureLight_) captureLight_->prepare(timeOfDay_h_);
    far_->captureStage();
}

void NearFieldMethod::overrideCaptureLight(CaptureLightOverride light) {
    if (!light && captureLight_) {
        const CaptureLight* ours = captureLight_.get();
        light = [ours](double) -> const SurfaceLight* { return ours; };
    }
    far_->overrideCaptureLight(std::move(light));
}

void NearFieldMethod::predictStage(const glm::dvec3& cameraPosition_m,
                                   const glm::dvec3& cameraVelocity_mps, double timeOfDay_h,
                                   double dt_s) {
    near_->resetCounters();
    if (std::isfinite(timeOfDay_h)) near_->setTimeOfDay(timeOfDay_h), timeOfDay_h_ = timeOfDay_h;
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
