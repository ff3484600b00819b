// FrameLoop_test.cpp — the camera handoff of stages 1 and 6: the ambience sees the replay's
// camera (the car's eye) while the main view renders from the chase eye, which the frame's record
// names; the car stands under the replay's eye; the chase eye is the same whether frames are drawn
// or not (compare plays without drawing); --camera hood renders from the replay's eye.
#include "app/frame/FrameLoop.h"

#include <vector>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "world/Error.h"

namespace amb {
namespace {

class ZeroAmbient final : public AmbientSource {
  public:
    glm::vec3 cornerIrradiance(const glm::dvec3&, const glm::dvec3&) const override {
        return glm::vec3(0.0f);
    }
    std::uint32_t objectSet(const glm::dvec3&, std::vector<AmbientSet>& sets) const override {
        if (sets.empty()) sets.emplace_back();
        return 0;
    }
};

class RecordingStages final : public AmbienceStages {
  public:
    void predict(const FrameState& frame) override { cameras.push_back(frame.camera); }
    void capture(const FrameState&) override {}
    void store(const FrameState&) override {}
    const AmbientSource& interpolate(const FrameState&) override { return ambient; }
    std::vector<CameraSample> cameras;
    ZeroAmbient ambient;
};

class RecordingView final : public MainView {
  public:
    void setViewTimeOfDay(double) override {}
    void setViewState(const ViewState& state) override { states.push_back(state); }
    RenderStats drawView(const CameraSample& camera, const AmbientSource&) override {
        drawn.push_back(camera);
        return {};
    }
    std::vector<ViewState> states;
    std::vector<CameraSample> drawn;
};

// A straight drive east on flat ground at 20 m/s, eye 1.5 m up, with a cut halfway.
Replay straightDrive() {
    Replay r;
    r.mode = ReplayMode::Drive;
    r.step_s = 0.1;
    for (int i = 0; i <= 40; ++i) {
        CameraSample s;
        s.time_s = i * r.step_s;
        s.position_m = {2.0 * i + (i >= 20 ? 1000.0 : 0.0), 1.5, 0.0};
        s.forward = {1.0, 0.0, 0.0};
        s.cut = i == 20;
        r.samples.push_back(s);
    }
    return r;
}

TEST(FrameLoop, AmbienceSeesTheReplayEyeAndTheViewTheChaseEye) {
    const Replay replay = straightDrive();
    const auto flat = [](double, double) { return 0.0; };
    RecordingView view, quiet;
    RecordingStages stages, quietStages;
    FrameLoop loop(replay, view, stages), undrawn(replay, quiet, quietStages);
    loop.setCarView(CarView::Chase, flat);
    undrawn.setCarView(CarView::Chase, flat);
    undrawn.setDrawMainView(false);
    const ChaseSettings chase;
    while (!loop.done()) {
        const FrameRecord rec = loop.step();
        const FrameRecord other = undrawn.step();
        const std::size_t i = std::size_t(rec.index);
        const CameraSample& eye = replay.samples[i];
        EXPECT_EQ(stages.cameras[i].position_m, eye.position_m);  // the ambience: the car's eye
        EXPECT_EQ(view.drawn[i].position_m, rec.view.position_m);  // drawn from the record's eye
        EXPECT_EQ(other.view.position_m, rec.view.position_m);     // drawn or not, the same eye
        ASSERT_TRUE(view.states[i].vehicle.has_value());
        EXPECT_NEAR(glm::length(view.states[i].vehicle->position_m -
                                (eye.position_m - glm::dvec3(0.0, 1.5, 0.0))), 0.0, 1e-12);
        EXPECT_EQ(view.states[i].cut, i == 0 || i == 20);
        // Driving straight at constant speed the spring rests at its target: behind and above.
        const glm::dvec3 rest = view.states[i].vehicle->position_m +
                                ChaseCamera::targetOffset(*view.states[i].vehicle, chase);
        EXPECT_NEAR(glm::length(rec.view.position_m - rest), 0.0, 1e-9) << "frame " << i;
        EXPECT_LT(rec.view.position_m.x, eye.position_m.x - 5.0);
        EXPECT_GT(rec.view.position_m.y, eye.position_m.y);
    }
    EXPECT_TRUE(quiet.drawn.empty());
    EXPECT_EQ(quiet.states.size(), view.states.size());
}

TEST(FrameLoop, HoodAndNoCarRenderFromTheReplayEye) {
    const Replay replay = straightDrive();
    for (CarView carView : {CarView::Hood, CarView::None}) {
        RecordingView view;
        RecordingStages stages;
        FrameLoop loop(replay, view, stages);
        loop.setCarView(carView, {});
        while (!loop.done()) {
            const FrameRecord rec = loop.step();
            EXPECT_EQ(rec.view.position_m, replay.samples[std::size_t(rec.index)].position_m);
            EXPECT_EQ(view.states.back().vehicle.has_value(), carView == CarView::Hood);
        }
    }
    EXPECT_EQ(parseCarView("hood", "--camera"), CarView::Hood);
    EXPECT_EQ(parseCarView("chase", "--camera"), CarView::Chase);
    EXPECT_THROW(parseCarView("drone", "--camera"), InputError);
}

}  // namespace
}  // namespace amb
