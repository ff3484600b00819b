// PassTimer.h — times the passes of one main-view frame (`ambience run --pass-timing`): each
// pass between two glFinish calls, so the time is the pass's own rasterisation and shading
// (a software rasteriser works on its own threads until the finish), with a GL_SAMPLES_PASSED
// query counting the samples that passed the depth test. Timing adds waits between the passes
// but changes no pixel (tests/app/Renderer_test.cpp). Off, begin and end do nothing.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>

#include "app/frame/Draw.h"
#include "app/render/Gl.h"

namespace amb {

class PassTimer {
  public:
    PassTimer() = default;
    ~PassTimer();
    PassTimer(const PassTimer&) = delete;
    PassTimer& operator=(const PassTimer&) = delete;

    void setEnabled(bool on) { enabled_ = on; }
    bool enabled() const { return enabled_; }
    // Clears the frame's passes.
    void startFrame() { passes_ = {}; }
    // Opens pass `p` (waits for the GL work before it); passes do not nest.
    void begin(RenderPass p);
    // Closes the open pass (waits for it) and adds its time, `triangles` and samples.
    void end(std::size_t triangles);
    const std::array<PassStats, kRenderPasses>& passes() const { return passes_; }

  private:
    bool enabled_ = false;
    int open_ = -1;
    GLuint query_ = 0;
    std::chrono::steady_clock::time_point start_{};
    std::array<PassStats, kRenderPasses> passes_{};
};

}  // namespace amb
