// FrameLoop.h — the frame, its stages listed once, in order (docs/ARCHITECTURE.md, "The frame"):
//   1. advance      the replay camera (fixed dt) and the time of day; on drives the car under it
//                   and the main view's eye (the chase camera, world/ChaseCamera.h)
//   2. predict      the scheduler's motion model picks the next probe position(s)
//   3. capture      this frame's share of cube faces of the static coarse scene
//   4. store        insert / refresh anchors; expire, prune; advance blending
//   5. interpolate  ambient at every terrain-patch corner and every object
//   6. draw         terrain, vegetation, road, sky; HDR -> tone map
//   7. measure      stage timings, the method's state, and (after the frame's clock stops) its
//                   error against an oracle when one is attached
// Stages 2-5 and 7's method part belong to an AmbienceStages implementation
// (MethodAmbienceStages, app/frame/MethodStages.h: ours or a baseline); stages 1 and 6 to a
// MainView (app/render/Renderer.h). `ambience run` plays a replay through it (step()), `ambience
// view` feeds it the window's camera (step(input)): one frame, one code path.
#pragma once

#include <array>
#include <chrono>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/frame/Draw.h"
#include "lighting/AnchorStore.h"
#include "world/ChaseCamera.h"
#include "world/Replay.h"

namespace amb {

enum class FrameStage : int {
    Advance = 0,
    Predict,
    Capture,
    Store,
    Interpolate,
    Draw,
    Measure,
};
inline constexpr int kFrameStages = 7;
const char* toString(FrameStage stage);

// What every stage may read about the current frame.
struct FrameState {
    int index = 0;        // frame number from 0
    double time_s = 0.0;  // the run's clock: replay time, continuing to grow across loops
    double replayTime_s = 0.0;  // position in the replay (time_s less the loops before)
    int loop = 0;               // which pass over the replay, from 0
    double timeOfDay_h = 12.0;
    CameraSample camera;  // the replay's (or the viewer's) camera: what the ambience uses
    CameraSample view;    // the eye the main view renders from (the chase eye, or `camera`)
    std::optional<VehiclePose> vehicle;  // the camera's own car, when drawn
};

// How the main view shows the camera's own car on drives (--camera): none; from its hood (the
// replay's eye, the car under it); or from behind and above (the chase camera, world/ChaseCamera.h).
enum class CarView { None, Hood, Chase };
// "hood" or "chase"; anything else is an InputError naming `option`.
CarView parseCarView(const std::string& name, const std::string& option);

struct FrameRecord;

// Stages 2-5.
class AmbienceStages {
  public:
    virtual ~AmbienceStages() = default;
    virtual void predict(const FrameState& frame) = 0;
    virtual void capture(const FrameState& frame) = 0;
    virtual void store(const FrameState& frame) = 0;
    // The ambient the draw stage uses this frame.
    virtual const AmbientSource& interpolate(const FrameState& frame) = 0;
    // Stage 7, after the frame's clock has stopped: the method's state into `record`, and
    // whatever measuring the implementation does (the error against an oracle).
    virtual void measure(const FrameState& frame, FrameRecord& record) {
        (void)frame, (void)record;
    }
};

// A frame whose camera and clocks come from outside the loop (the viewer).
struct FrameInput {
    double time_s = 0.0;        // the run's clock (stops while the viewer is paused)
    double replayTime_s = 0.0;  // position in the replay, if one is followed
    int loop = 0;
    double timeOfDay_h = 12.0;
    CameraSample camera;
};

struct FrameRecord {
    int index = 0, loop = 0;
    double time_s = 0.0, replayTime_s = 0.0, timeOfDay_h = 0.0;
    bool cut = false;            // the camera was cut (teleported) before this frame
    CameraSample view;           // the eye the main view rendered from (or would have)
    double popMove = std::numeric_limits<double>::quiet_NaN();  // pop along the camera's ground
                                                                // point (measured runs; NaN: none)
    std::size_t rss_kB = 0;      // resident memory of the process after the frame (0: unknown)
    std::size_t heap_kB = 0;     // of which malloc has handed out and not had back (0: unknown)
    std::array<double, kFrameStages> stage_ms{};  // CPU wall time per stage
    double frame_ms = 0.0;                        // all stages
    RenderStats render;
    // The ambience method (ours or a baseline): state after the frame.
    struct Ambience {
        bool active = false;
        std::size_t anchors = 0, bytes = 0;
        int faces = 0;            // cube faces captured this frame
        int finestLevel = 0;      // the scheduler's finest lattice level this frame
        std::size_t lookups = 0;  // ambient lookups answered for the draw
        double lookup_ms = 0.0;    // CPU time of those lookups (inside the draw stage)
        double capture_ms = 0.0;   // of which GL capture (inside the capture stage)
        // The volume's own timings of its stages [ms] (project = SH projection of the faces).
        double predict_ms = 0.0, project_ms = 0.0, store_ms = 0.0;
        // The near field (lighting/NearField.h), part of the lookups: its time [ms], the points
        // it answered, the memory of its cache.
        double nearField_ms = 0.0, nearFieldBuild_ms = 0.0;  // all, and building transfers
        std::size_t nearFieldPoints = 0, nearFieldBuilds = 0, nearFieldBytes = 0;
        // Alive anchors per level, coarsest first: the first `levels` entries (0 without an
        // anchor store). Inline, so that the rows of a long run allocate nothing per frame.
        std::array<std::size_t, kMaxAnchorLevels> anchorsPerLevel{};
        int levels = 0;
    } ambience;
};

class FrameLoop {
  public:
    // Frames are `stride` replay steps apart (fixed dt = stride * replay.step_s). With `loops`
    // > 1 the replay is played that many times back to back: the clock and the time of day keep
    // advancing (at the replay's time rate) and each jump back to the start is a camera cut.
    FrameLoop(const Replay& replay, MainView& view, AmbienceStages& ambience, int stride = 1,
              int loops = 1);
    // A loop without a replay: each frame comes from step(input).
    FrameLoop(MainView& view, AmbienceStages& ambience);

    // Frames of one pass over `replay` at `stride` (its start and end included).
    static int framesPerPass(const Replay& replay, int stride);
    int frameCount() const { return frameCount_; }
    int framesPerLoop() const { return framesPerLoop_; }
    double frameStep_s() const { return step_s_; }
    bool done() const { return next_ >= frameCount_; }
    // Runs every stage of the replay's next frame, in order. The draw stage waits for the GPU,
    // so its time includes rasterisation.
    FrameRecord step();
    // The same for a frame whose stage-1 input the caller gives (its clocks and camera).
    FrameRecord step(const FrameInput& input);
    // Without the main view the draw stage renders nothing (captures still render); for runs
    // that measure the ambience alone.
    void setDrawMainView(bool draw) { drawMainView_ = draw; }
    // The camera's own car (drive replays): `view` says how the main view shows it; the car
    // stands eyeHeight_m under the replay's eye, pitched to `groundHeight` (the terrain height
    // at x, z, which also keeps the chase eye above the ground). CarView::None by default.
    void setCarView(CarView view, ChaseCamera::GroundHeight groundHeight,
                    double eyeHeight_m = 1.5, const ChaseSettings& chase = {});
    CarView carView() const { return carView_; }

  private:
    using Clock = std::chrono::steady_clock;
    FrameRecord run(FrameState& frame, Clock::time_point start);

    const Replay* replay_ = nullptr;
    MainView& view_;
    AmbienceStages& ambience_;
    double step_s_;
    int framesPerLoop_;
    int frameCount_;
    int next_ = 0;
    long lastSample_ = 0;  // replay sample index of the previous frame
    bool drawMainView_ = true;
    // The car and the chase eye (setCarView); the clock of the previous frame, for its dt.
    CarView carView_ = CarView::None;
    ChaseCamera::GroundHeight groundHeight_;
    double eyeHeight_m_ = 1.5;
    std::optional<ChaseCamera> chase_;
    double lastTime_s_ = 0.0;
    void placeView(FrameState& frame);
};

// Where the draw would look up ambience, for a run without the main view: points of an 8 m
// lattice (about the density of near terrain corners and plants) within 48 m all around the
// camera and within 240 m in a 60-degree half-angle cone ahead, on the ground plane: about a
// thousand a frame. They are looked up (and timed as the draw's lookups), and the reactive
// baseline creates its probes from them.
void drawLookupStandIn(const CameraSample& camera, std::vector<double>& x, std::vector<double>& z);

}  // namespace amb
