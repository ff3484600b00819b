// FrameLoop.cpp — one frame: the seven stages of docs/ARCHITECTURE.md "The frame" in order, each timed.
#include "app/frame/FrameLoop.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include "world/Error.h"


namespace amb {

const char* toString(FrameStage stage) {
    static const char* names[kFrameStages] = {"advance",     "predict", "capture", "store",
                                              "interpolate", "draw",    "measure"};
    return names[int(stage)];
}

int FrameLoop::framesPerPass(const Replay& replay, int stride) {
    const double step_s = replay.step_s * std::max(1, stride);
    return int(std::floor(replay.duration_s() / step_s + 1e-9)) + 1;
}

FrameLoop::FrameLoop(const Replay& replay, MainView& view, AmbienceStages& ambience, int stride,
                     int loops)
    : replay_(&replay), view_(view), ambience_(ambience) {
    step_s_ = replay.step_s * std::max(1, stride);
    framesPerLoop_ = framesPerPass(replay, stride);
    // The run length is checked by the caller (run --loop); saturate rather than overflow.
    const long total = long(framesPerLoop_) * std::max(1, loops);
    frameCount_ = int(std::min<long>(total, std::numeric_limits<int>::max()));
}

FrameLoop::FrameLoop(MainView& view, AmbienceStages& ambience)
    : view_(view), ambience_(ambience), step_s_(0.0), framesPerLoop_(1), frameCount_(0) {}

FrameRecord FrameLoop::step() {
    AMB_CHECK(replay_ && !done());
    const Replay& replay = *replay_;
    const Clock::time_point start = Clock::now();
    FrameState frame;
    // 1. advance (the rest of it, the sky, in run())
    frame.index = next_++;
    frame.loop = frame.index / framesPerLoop_;
    const int inLoop = frame.index % framesPerLoop_;
    // One clock for the whole run, so dt stays one frame step across a loop's end and the time
    // of day keeps moving at the replay's rate; the camera follows the replay's own time.
    frame.time_s = frame.index * step_s_;
    frame.replayTime_s = inLoop * step_s_;
    frame.timeOfDay_h = replay.timeOfDayAt_h(frame.time_s);
    frame.camera = replay.sampleAt(frame.replayTime_s);
    if (inLoop == 0) {
        // Back at the replay's start: the jump from its end is a camera cut.
        frame.camera.cut = frame.loop > 0;
        lastSample_ = 0;
    } else {
        // A cut anywhere since the previous frame is this frame's cut (frames may be several
        // replay steps apart, and interpolation never lands on the cut sample itself).
        const auto& samples = replay.samples;
        const double t0 = samples.front().time_s;
        const long last = long(std::floor((frame.replayTime_s - t0) / replay.step_s + 1e-6));
        for (long j = std::max(lastSample_ + 1, 1L); j <= last && j < long(samples.size()); ++j)
            if (samples[std::size_t(j)].cut) frame.camera.cut = true;
        lastSample_ = last;
    }
    return run(frame, start);
}

FrameRecord FrameLoop::step(const FrameInput& input) {
    const Clock::time_point start = Clock::now();
    FrameState frame;
    frame.index = next_++;
    frame.loop = input.loop;
    frame.time_s = input.time_s;
    frame.replayTime_s = input.replayTime_s;
    frame.timeOfDay_h = input.timeOfDay_h;
    frame.camera = input.camera;
    return run(frame, start);
}

CarView parseCarView(const std::string& name, const std::string& option) {
    if (name == "hood") return CarView::Hood;
    if (name == "chase") return CarView::Chase;
    throw InputError(option, "unknown camera '" + name + "' (expected hood or chase)");
}

void FrameLoop::setCarView(CarView view, ChaseCamera::GroundHeight groundHeight,
                           double eyeHeight_m, const ChaseSettings& chase) {
    carView_ = view;
    groundHeight_ = std::move(groundHeight);
    eyeHeight_m_ = eyeHeight_m;
    chase_.reset();
    if (view == CarView::Chase) chase_.emplace(chase, groundHeight_);
}

// Stage 1's last part: the car under the replay's eye and the eye the main view renders from.
// The chase eye moves on the run's clock, so it is placed on every frame, drawn or not.
void FrameLoop::placeView(FrameState& frame) {
    frame.view = frame.camera;
    const bool first = frame.index == 0;
    const double dt_s = first ? 0.0 : std::max(0.0, frame.time_s - lastTime_s_);
    lastTime_s_ = frame.time_s;
    if (carView_ == CarView::None) return;
    frame.vehicle = vehiclePoseFromEye(frame.camera, eyeHeight_m_, groundHeight_);
    if (chase_) frame.view = chase_->update(*frame.vehicle, dt_s, frame.camera.cut || first,
                                            frame.camera);
}

FrameRecord FrameLoop::run(FrameState& frame, Clock::time_point start) {
    FrameRecord rec;
    Clock::time_point mark = start;
    auto lap = [&](FrameStage stage) {
        const auto now = Clock::now();
        rec.stage_ms[int(stage)] = std::chrono::duration<double, std::milli>(now - mark).count();
        mark = now;
    };
    view_.setViewTimeOfDay(frame.timeOfDay_h);
    placeView(frame);
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
    view_.setViewState({frame.time_s, frame.camera.cut || frame.index == 0, frame.vehicle});
    if (drawMainView_) rec.render = view_.drawView(frame.view, ambient);
    lap(FrameStage::Draw);
    // 7. measure
    rec.index = frame.index;
    rec.loop = frame.loop;
    rec.time_s = frame.time_s;
    rec.replayTime_s = frame.replayTime_s;
    rec.timeOfDay_h = frame.timeOfDay_h;
    rec.cut = frame.camera.cut;
    rec.view = frame.view;
    lap(FrameStage::Measure);
    rec.frame_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    // The method's state and its error, outside the frame's time.
    ambience_.measure(frame, rec);
    return rec;
}

void drawLookupStandIn(const CameraSample& camera, std::vector<double>& x, std::vector<double>& z) {
    x.clear(), z.clear();
    constexpr double kSpacing = 8.0, kNear = 48.0, kFar = 240.0, kCosCone = 0.5;
    glm::dvec2 ahead(camera.forward.x, camera.forward.z);
    const double len = glm::length(ahead);
    ahead = len > 1e-6 ? ahead / len : glm::dvec2(0.0);
    const double i0 = std::floor(camera.position_m.x / kSpacing);
    const double k0 = std::floor(camera.position_m.z / kSpacing);
    const int reach = int(kFar / kSpacing) + 1;
    for (int di = -reach; di <= reach; ++di)
        for (int dk = -reach; dk <= reach; ++dk) {
            const double px = (i0 + di) * kSpacing, pz = (k0 + dk) * kSpacing;
            const glm::dvec2 d(px - camera.position_m.x, pz - camera.position_m.z);
            const double r = glm::length(d);
            const bool near = r <= kNear;
            const bool inCone = r <= kFar && len > 1e-6 && glm::dot(d, ahead) >= kCosCone * r;
            if (near || inCone) x.push_back(px), z.push_back(pz);
        }
}


}  // namespace amb
