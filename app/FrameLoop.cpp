// FrameLoop.cpp — one frame: the seven stages of DESIGN.md in order, each timed.
#include "app/FrameLoop.h"

#include <chrono>
#include <cmath>

#include "app/Gl.h"

namespace amb {

const char* toString(FrameStage stage) {
    static const char* names[kFrameStages] = {"advance",     "predict", "capture", "store",
                                              "interpolate", "draw",    "measure"};
    return names[int(stage)];
}

FrameLoop::FrameLoop(const Replay& replay, Renderer& renderer, AmbienceStages& ambience, int stride)
    : replay_(replay), renderer_(renderer), ambience_(ambience) {
    step_s_ = replay.step_s * std::max(1, stride);
    frameCount_ = int(std::floor(replay.duration_s() / step_s_ + 1e-9)) + 1;
}

FrameRecord FrameLoop::step() {
    using Clock = std::chrono::steady_clock;
    FrameRecord rec;
    FrameState frame;
    auto mark = Clock::now();
    const auto start = mark;
    auto lap = [&](FrameStage stage) {
        const auto now = Clock::now();
        rec.stageMs[int(stage)] = std::chrono::duration<double, std::milli>(now - mark).count();
        mark = now;
    };

    // 1. advance
    frame.index = next_++;
    frame.time_s = frame.index * step_s_;
    frame.timeOfDay_h = replay_.timeOfDayAt_h(frame.time_s);
    frame.camera = replay_.sampleAt(frame.time_s);
    {
        // A cut anywhere since the previous frame is this frame's cut (frames may be several
        // replay steps apart, and interpolation never lands on the cut sample itself).
        const auto& samples = replay_.samples;
        const double t0 = samples.front().time_s;
        const long last = long(std::floor((frame.time_s - t0) / replay_.step_s + 1e-6));
        for (long j = std::max(lastSample_ + 1, 1L); j <= last && j < long(samples.size()); ++j)
            if (samples[std::size_t(j)].cut) frame.camera.cut = true;
        lastSample_ = last;
    }
    frame.sky = &renderer_.setTimeOfDay(frame.timeOfDay_h);
    lap(FrameStage::Advance);
    // 2. predict
    ambience_.predict(frame);
    lap(FrameStage::Predict);
    // 3. capture
    ambience_.capture(frame);
    lap(FrameStage::Capture);
    // 4. store
    ambience_.store(frame);
    lap(FrameStage::Store);
    // 5. interpolate
    const AmbientSource& ambient = ambience_.interpolate(frame);
    lap(FrameStage::Interpolate);
    // 6. draw
    if (drawMainView_) {
        rec.render = renderer_.render(frame.camera, ambient);
        glFinish();
    }
    lap(FrameStage::Draw);
    // 7. measure
    rec.index = frame.index;
    rec.time_s = frame.time_s;
    rec.timeOfDay_h = frame.timeOfDay_h;
    lap(FrameStage::Measure);
    rec.frameMs = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    return rec;
}

}  // namespace amb
