// AutoExposure.cpp — the adaptation and the luminance meter.
#include "app/render/AutoExposure.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "world/Conventions.h"
#include "world/Error.h"

namespace amb {

bool parseExposure(const std::string& name, const std::string& option) {
    if (name == "auto") return true;
    if (name == "fixed") return false;
    throw InputError(option, "unknown exposure '" + name + "' (expected auto or fixed)");
}

// ---- [SECTION] AutoExposure ------------------------------------------------------------------

AutoExposure::AutoExposure(const AutoExposureSettings& settings, float noonExposure)
    : settings_(settings),
      reference_(settings.key / std::max(double(noonExposure), 1e-30)),
      adapted_(reference_),
      exposure_(noonExposure) {}

double AutoExposure::adaptLog(double adaptedLog, double targetLog, double dt_s, double tau_s) {
    if (!(tau_s > 0.0)) return targetLog;
    return targetLog + (adaptedLog - targetLog) * std::exp(-std::max(dt_s, 0.0) / tau_s);
}

float AutoExposure::exposureFor(double luminance) const {
    const double l = std::clamp(luminance, settings_.minRelative * reference_,
                                settings_.maxRelative * reference_);
    return float(settings_.key / l * std::pow(l / reference_, settings_.darkening));
}

float AutoExposure::update(double time_s, double timeOfDay_h, bool cut,
                           const std::function<double()>& meter) {
    if (started_ && time_s == time_s_ && timeOfDay_h == timeOfDay_h_) return exposure_;
    const double target = meter();
    const bool restart = !started_ || cut || time_s < time_s_ ||
                         (time_s == time_s_ && timeOfDay_h != timeOfDay_h_) ||
                         !std::isfinite(target);
    const double floorLog = std::log(settings_.minRelative * reference_);
    const double ceilLog = std::log(settings_.maxRelative * reference_);
    const double targetLog =
        std::isfinite(target) ? std::clamp(target, floorLog, ceilLog) : std::log(reference_);
    const double adaptedLog =
        restart ? targetLog
                : adaptLog(std::log(adapted_), targetLog, time_s - time_s_, settings_.tau_s);
    adapted_ = std::exp(adaptedLog);
    started_ = true;
    time_s_ = time_s;
    timeOfDay_h_ = timeOfDay_h;
    exposure_ = exposureFor(adapted_);
    return exposure_;
}

// ---- [SECTION] LuminanceMeter ----------------------------------------------------------------

namespace {

GlFramebuffer colourFramebuffer(GLuint texture) {
    GLuint fbo = 0;
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, texture, 0);
    return GlFramebuffer(fbo);
}

}  // namespace

LuminanceMeter::LuminanceMeter(int width, int height)
    : width_(width),
      height_(height),
      midWidth_(std::max(1, (width + 3) / 4)),
      midHeight_(std::max(1, (height + 3) / 4)),
      smallWidth_(std::max(1, (width + 7) / 8)),
      smallHeight_(std::max(1, (height + 7) / 8)) {
    mid_ = makeTexture2D(GL_RGBA16F, midWidth_, midHeight_);
    midFbo_ = colourFramebuffer(mid_.id());
    small_ = makeTexture2D(GL_RGBA16F, smallWidth_, smallHeight_);
    smallFbo_ = colourFramebuffer(small_.id());
}

double LuminanceMeter::logMeanLuminance(GLuint framebuffer) {
    // Two linear blits (1/4, then 1/2 of that on each side): every pixel of the small image is a
    // bilinear blend of the frame's pixels, spread evenly over it.
    glBlitNamedFramebuffer(framebuffer, midFbo_.id(), 0, 0, width_, height_, 0, 0, midWidth_,
                           midHeight_, GL_COLOR_BUFFER_BIT, GL_LINEAR);
    glBlitNamedFramebuffer(midFbo_.id(), smallFbo_.id(), 0, 0, midWidth_, midHeight_, 0, 0,
                           smallWidth_, smallHeight_, GL_COLOR_BUFFER_BIT, GL_LINEAR);
    const std::vector<float> rgb =
        readPixelsRgb32f(smallFbo_.id(), 0, 0, smallWidth_, smallHeight_);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    double sum = 0.0;
    const std::size_t n = rgb.size() / 3;
    for (std::size_t i = 0; i < n; ++i) {
        const double l = luminance(glm::dvec3(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]));
        sum += std::log(std::max(std::isfinite(l) ? l : 0.0, kFloor));
    }
    return n ? sum / double(n) : std::log(kFloor);
}

}  // namespace amb
