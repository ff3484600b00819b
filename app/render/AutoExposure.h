// AutoExposure.h — eye adaptation for the tone mapping (docs/ARCHITECTURE.md "Terrain and
// objects"): the frame's mean log luminance (the HDR target shrunk on the GPU to a few thousand
// pixels, read back), an adapted luminance that follows it exponentially with a time constant in
// simulation time (so a replay is exposed the same on every run), and the exposure for it.
//
// Exposure for an adapted luminance L (clamped to [minRelative, maxRelative] x L_ref):
//     E(L) = key / L * (L / L_ref)^darkening,   L_ref = key / E_noon,
// where E_noon is the fixed exposure of a noon sky (exposureFor(noon, noon)): a scene as bright
// as noon gets the fixed exposure, a darker one is brightened, but its mean before the tone curve
// (key (L / L_ref)^darkening) drops with it, so a night stays a night, only readable. With
// darkening 0 every scene's mean becomes `key`.
//
// [SECTION] AutoExposure     the adaptation (no GL; tested on its own)
// [SECTION] LuminanceMeter   the frame's mean log luminance (GL)
#pragma once

#include <functional>
#include <string>

#include "app/render/Gl.h"

namespace amb {

struct AutoExposureSettings {
    bool enabled = true;      // false: the fixed exposure of the sky (exposureFor)
    double tau_s = 1.0;       // time constant of the adaptation [s of simulation time]
    double key = 0.10;        // the mean before the tone curve of a scene as bright as noon
    double darkening = 0.08;  // how much of a darker scene's darkness stays, in [0, 1)
    double minRelative = 1e-7, maxRelative = 100.0;  // range of L / L_ref
};

// "auto" (true) or "fixed" (false), the --exposure option; anything else is an InputError.
bool parseExposure(const std::string& name, const std::string& option);

// ---- [SECTION] AutoExposure ------------------------------------------------------------------
class AutoExposure {
  public:
    // `noonExposure`: the fixed exposure of the noon sky, which sets L_ref.
    AutoExposure(const AutoExposureSettings& settings, float noonExposure);

    // The exposure for this frame. A frame is one (clock, time of day) pair: the first call for
    // it asks `meter` for the mean log luminance (natural log) and adapts towards it over the
    // clock's step since the last frame; later calls for the same frame return the same
    // exposure. The first frame, a cut, a clock that went back or a time of day that changed
    // while the clock stood still start the adaptation afresh at the metered luminance.
    float update(double time_s, double timeOfDay_h, bool cut, const std::function<double()>& meter);
    // The fixed exposure, held as this frame's (auto exposure off).
    float hold(float exposure) { return exposure_ = exposure; }
    // The exposure of the last frame (the fixed noon exposure before any).
    float exposure() const { return exposure_; }
    double adaptedLuminance() const { return adapted_; }
    double referenceLuminance() const { return reference_; }

    // E(L) above, L clamped.
    float exposureFor(double luminance) const;
    // One step of the adaptation in log luminance: exact exponential approach with time
    // constant tau_s over dt_s.
    static double adaptLog(double adaptedLog, double targetLog, double dt_s, double tau_s);

  private:
    AutoExposureSettings settings_;
    double reference_;  // L_ref
    bool started_ = false;
    double time_s_ = 0.0, timeOfDay_h_ = 0.0;
    double adapted_ = 0.0;  // L
    float exposure_;
};

// ---- [SECTION] LuminanceMeter ----------------------------------------------------------------
class LuminanceMeter {
  public:
    // Frames of width x height are shrunk to about 1/8 of that on each side.
    LuminanceMeter(int width, int height);
    // Mean of ln(max(luminance, floor_)) over the colour attachment 0 of `framebuffer`.
    double logMeanLuminance(GLuint framebuffer);
    static constexpr double kFloor = 1e-12;  // luminance of a black pixel, for the log

  private:
    int width_, height_, midWidth_, midHeight_, smallWidth_, smallHeight_;
    GlTexture mid_, small_;
    GlFramebuffer midFbo_, smallFbo_;
};

}  // namespace amb
