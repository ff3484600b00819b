// CaptureCore.cpp — the clock, the jobs and the fallback every capturing method shares (see
// CaptureCore.h).
#include "lighting/CaptureCore.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <glm/geometric.hpp>

#include "lighting/AnchorStore.h"
#include "lighting/CubeCapture.h"
#include "lighting/CubeMapProjector.h"
#include "lighting/ProbeEnvironment.h"
#include "lighting/ShGradient.h"
#include "world/Error.h"

namespace amb {

namespace {

using Clock = std::chrono::steady_clock;
double secondsSince(Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
}

bool finite(const glm::dvec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

// Every coefficient finite and within the range the anchor store accepts.
bool acceptable(const ShRgb& sh) {
    for (const glm::vec3& c : sh.c) {
        for (int ch = 0; ch < 3; ++ch) {
            if (!std::isfinite(c[ch]) || std::fabs(c[ch]) > AnchorStore::kMaxCoefficient) {
                return false;
            }
        }
    }
    return true;
}

// Faces facesDone .. min(5, facesDone + budget - 1) of the probe at `position_m`, captured into
// `cube` and added to `projector`. A texel that is NaN, infinite or negative sets `bad` (the
// projector zeroes and counts such texels, so its sums stay finite).
struct FacesResult {
    int faces = 0;
    double capture_s = 0.0, project_s = 0.0;
};
FacesResult captureProbeFaces(CubeCapture& capture, CubeMapProjector& projector,
                              std::vector<float>& cube, const glm::dvec3& position_m,
                              double timeOfDay_h, int facesDone, int budget, double nearRadius_m,
                              const SurfaceLight* light, std::vector<float>* distance, bool& bad) {
    FacesResult result;
    const int count = std::min(budget, kCubeFaces - facesDone);
    if (count <= 0) return result;
    CubeFaceMask mask = 0;
    for (int f = facesDone; f < facesDone + count; ++f) mask |= cubeFaceBit(f);

    auto t0 = Clock::now();
    // The method's own light for its own captures only: a capture may serve others.
    capture.setSurfaceLight(light);
    if (distance)
        capture.captureFarWithDistance(position_m, timeOfDay_h, mask, cube, *distance, nearRadius_m);
    else
        capture.captureFar(position_m, timeOfDay_h, mask, cube, nearRadius_m);
    capture.setSurfaceLight(nullptr);
    result.capture_s = secondsSince(t0);
    const std::size_t faceFloats = 3 * std::size_t(capture.faceSize()) * capture.faceSize();
    AMB_CHECK(cube.size() == faceFloats * kCubeFaces);

    t0 = Clock::now();
    // The sun's texel is left out by the direction the capture put the disc at (SunTexel.h).
    const std::optional<glm::dvec3> sun = capture.sunDirection(timeOfDay_h);
    for (int f = facesDone; f < facesDone + count; ++f) {
        const float* face = cube.data() + faceFloats * std::size_t(f);
        for (std::size_t t = 0; t < faceFloats && !bad; ++t) {
            if (!(face[t] >= 0.0f) || !std::isfinite(face[t])) bad = true;
        }
        projector.addFace(f, face, sun);
    }
    result.project_s = secondsSince(t0);
    result.faces = count;
    return result;
}

}  // namespace

double dayDifference_h(double a, double b) {
    double d = std::fmod(b - a, 24.0);
    if (d > 12.0) d -= 24.0;
    if (d <= -12.0) d += 24.0;
    return d;
}

// ---- Clock --------------------------------------------------------------------------------------

CaptureCore::CaptureCore(CubeCapture& capture, const ProbeEnvironment& environment,
                         const CaptureSettings& settings)
    : capture_(capture), environment_(environment), settings_(settings) {
    AMB_CHECK(settings.facesPerFrame >= 1 && settings.fallbackFaceSize >= 1);
    projector_ = std::make_unique<CubeMapProjector>(capture_.faceSize());
    timeRate_hPerS_ = settings.defaultTimeRate_hPerS;
}

CaptureCore::~CaptureCore() = default;

void CaptureCore::updateFallback(double timeOfDay_h) {
    fallbackChanged_ = false;
    if (haveFallback_ && !(std::fabs(dayDifference_h(fallbackTimeOfDay_h_, timeOfDay_h)) >=
                           settings_.fallbackRefresh_h)) {
        return;
    }
    std::vector<float> cube;
    const int n = settings_.fallbackFaceSize;
    environment_.fallbackCubeMap(timeOfDay_h, n, cube);
    const ShRgb sh = toFloat(projectCubeMap(n, cube).sh);
    // A broken fallback scene must not put NaN into shAt: keep the previous value (or zero).
    if (acceptable(sh)) {
        fallback_ = sh;
        fallbackChanged_ = true;
    }
    haveFallback_ = true;
    fallbackTimeOfDay_h_ = timeOfDay_h;
}

FrameEvents CaptureCore::beginFrame(const glm::dvec3& cameraPosition_m,
                                    const glm::dvec3& cameraVelocity_mps, double timeOfDay_h,
                                    double dt_s) {
    stats_.facesThisFrame = 0;
    stats_.predict_s = stats_.capture_s = stats_.project_s = stats_.store_s = 0.0;
    completed_.clear();
    const Clock::time_point t0 = Clock::now();
    FrameEvents events;
    if (!std::isfinite(dt_s) || dt_s < 0.0) dt_s = 0.0;
    if (!std::isfinite(timeOfDay_h)) timeOfDay_h = timeOfDay_h_;
    timeOfDay_h = std::fmod(timeOfDay_h, 24.0);
    if (timeOfDay_h < 0.0) timeOfDay_h += 24.0;

    // Time: clock, rate of the time of day (wrap-safe), jumps.
    time_s_ += dt_s;
    if (haveTime_) {
        const double d = dayDifference_h(timeOfDay_h_, timeOfDay_h);
        if (std::fabs(d) > settings_.timeJump_h) {
            lastJump_s_ = time_s_;
            events.timeJump = true;
        } else if (dt_s > 0.0) {
            timeRate_hPerS_ = d / dt_s;
        }
    }
    haveTime_ = true;
    timeOfDay_h_ = timeOfDay_h;

    // Motion: a step the reported speed or the speed before it cannot explain is a teleport;
    // the probe in progress belongs to the old place. A reported speed above any camera's is
    // the step itself reported as a speed, not a measurement: it explains nothing.
    if (finite(cameraPosition_m)) {
        const double reported =
            finite(cameraVelocity_mps)
                ? std::min(glm::length(cameraVelocity_mps), kMaxCameraSpeed_mps)
                : 0.0;
        if (haveCamera_) {
            const double speed = std::max(reported, cameraSpeed_mps_);
            const double allowed = settings_.teleportDistance_m + 3.0 * speed * dt_s;
            if (glm::length(cameraPosition_m - camera_m_) > allowed) {
                ++stats_.teleports;
                events.teleport = true;
                primeDue_ = settings_.primeProbes > 0;
                if (job_) {
                    ++abortedProbes_;
                    job_.reset();
                }
            }
        }
        // The first frame: the method holds nothing yet.
        if (!haveCamera_) primeDue_ = settings_.primeProbes > 0;
        camera_m_ = cameraPosition_m;
        cameraSpeed_mps_ = reported;
        haveCamera_ = true;
    }

    updateFallback(timeOfDay_h);
    stats_.predict_s += secondsSince(t0);
    return events;
}

// ---- Jobs ---------------------------------------------------------------------------------------

void CaptureCore::captureFaces(const NextProbe& next) {
    // The prime first (the rule in the header): whole probes, each named by the method as the
    // budget's are, so it picks what it would have captured first anyway.
    if (primeDue()) {
        for (int p = 0; p < settings_.primeProbes; ++p) {
            const int faces = spendFaces(next, kCubeFaces, true);
            if (faces > 0) primeDue_ = false;  // begun: it ends with this frame
            if (faces < kCubeFaces) break;     // the method names nothing more
        }
    }
    spendFaces(next, settings_.facesPerFrame, false);
}

int CaptureCore::spendFaces(const NextProbe& next, int budget, bool primed) {
    const int total = budget;
    while (budget > 0) {
        if (!job_) {
            const Clock::time_point t0 = Clock::now();
            std::vector<ProbeKey> busy;
            for (const Done& c : completed_) busy.push_back(c.job.key);
            const std::optional<ProbeRequest> request = next(busy);
            if (request) {
                ProbeJob job;
                job.key = request->key;
                job.position_m = environment_.placeProbe(request->x_m, request->z_m, request->aside_m);
                job.startTime_s = time_s_;
                job_ = job;
                jobGradients_ = gradients_;
                projector_->reset();
            }
            stats_.predict_s += secondsSince(t0);
            if (!job_) break;  // nothing worth capturing: the budget stays unused
        }
        const FacesResult r = captureProbeFaces(capture_, *projector_, cube_, job_->position_m,
                                                timeOfDay_h_, job_->facesDone, budget,
                                                settings_.nearRadius_m(), surfaceLight(),
                                                jobGradients_ ? &distance_ : nullptr, job_->bad);
        stats_.capture_s += r.capture_s;
        stats_.project_s += r.project_s;
        job_->facesDone += r.faces;
        budget -= r.faces;
        stats_.facesThisFrame += r.faces;
        stats_.facesCaptured += r.faces;
        if (primed) stats_.primeFaces += r.faces;
        if (job_->facesDone == kCubeFaces) {
            job_->primed = primed;
            std::optional<ShGroundGradient> gradient;
            if (jobGradients_ && !job_->bad) {
                const Clock::time_point t0 = Clock::now();
                gradient = shGroundGradient(capture_.faceSize(), cube_, distance_);
                stats_.project_s += secondsSince(t0);
            }
            completed_.push_back({*job_, projector_->coefficients(), gradient});
            job_.reset();
        }
    }
    return total - budget;
}

std::vector<CompletedProbe> CaptureCore::takeCompleted() {
    std::vector<CompletedProbe> out;
    for (const Done& c : completed_) {
        ++probesCompleted_;
        const ShRgb sh = toFloat(c.sh);
        if (c.job.bad || !acceptable(sh)) {
            ++stats_.rejectedProbes;
            continue;
        }
        std::optional<ShSlope> slope;
        if (c.gradient) slope = toFloat(*c.gradient);
        out.push_back({c.job, sh, slope});
    }
    completed_.clear();
    return out;
}

}  // namespace amb
