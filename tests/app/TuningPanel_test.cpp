// TuningPanel_test.cpp — the viewer's tuning panel (app/cli/TuningPanel.h).
//
// TuningPanel.*: the settings table against the settings reader (no display). TuningPanelWindow.*
// need a window: without a display they skip, and ctest runs them under Xvfb as
// `tuning_panel_xvfb` (tests/CMakeLists.txt). There the panel draws over the scene (ImGui's draw
// data has vertices, and the window's pixels under the panel differ from the scene's while the
// rest is the scene's copy), a setting set through the panel's own setter (the one its widget
// calls, and a click through ImGui's input on one of its switches) changes the running method,
// in place or by a rebuild, and what Save writes Load reads back equal and `ambience run
// --config` accepts.
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <memory>
#include <string>

#include <gtest/gtest.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_internal.h>
#include <nlohmann/json.hpp>

#include "RunAmbience.h"
#include "app/cli/TuningPanel.h"
#include "app/frame/MethodStages.h"
#include "app/platform/Platform.h"
#include "app/render/PanelRenderer.h"
#include "app/render/Renderer.h"
#include "lighting/AmbienceVolume.h"
#include "lighting/JsonFields.h"
#include "lighting/SettingsSchema.h"
#include "world/Error.h"
#include "world/World.h"
// GLFW after glad (app/render/Renderer.h), with no GL header of its own.
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

namespace amb {
namespace {

namespace fs = std::filesystem;

// A value of `info` away from the default, inside its widget range (the schema's): switches
// flipped, numbers and integers at 37 % of the slider (of the ratio hi / lo where the slider is
// logarithmic), so that set one at a time or all at once the values pass the reader's checks
// that bind keys together: the lifetimes 27.5 s both, the lattice 25 m over 4 levels.
double movedValue(const SettingInfo& info, double current) {
    if (info.kind == SettingInfo::Kind::Boolean) return 1.0 - current;
    double v = info.logarithmic && info.lo > 0.0 ? info.lo * std::pow(info.hi / info.lo, 0.37)
                                                 : info.lo + 0.37 * (info.hi - info.lo);
    if (info.kind == SettingInfo::Kind::Integer) v = std::round(v);
    if (v == current) v = info.kind == SettingInfo::Kind::Integer ? v + 1.0 : v * 1.25 + 0.5;
    return v;
}

AmbienceVolumeSettings movedSettings() {
    AmbienceVolumeSettings s;
    for (const SettingInfo& info : tunableSettings())
        setSettingValue(s, info, movedValue(info, settingValue(s, info)));
    return s;
}

void expectSameSettings(const AmbienceVolumeSettings& a, const AmbienceVolumeSettings& b) {
    for (const SettingInfo& info : tunableSettings())
        EXPECT_EQ(settingValue(a, info), settingValue(b, info)) << info.key;
}

TEST(TuningPanel, EverySettingRoundTripsThroughTheSettingsReader) {
    // The defaults, and every key moved at once: the reader rejects unknown keys, so a key the
    // table misspells fails here, and a field the writer drops comes back at its default.
    const AmbienceVolumeSettings defaults;
    expectSameSettings(ambienceSettingsFromJson(settingsToJson(defaults), "defaults"), defaults);
    const AmbienceVolumeSettings moved = movedSettings();
    for (const SettingInfo& info : tunableSettings())
        EXPECT_NE(settingValue(moved, info), settingValue(defaults, info)) << info.key;
    expectSameSettings(ambienceSettingsFromJson(settingsToJson(moved), "moved"), moved);
}

TEST(TuningPanel, EveryKeyOfTheSettingsFileIsInTheTable) {
    // The settings file's keys as the reader's documentation lists them (AmbienceVolume.h,
    // AnchorStore.h, ProbeScheduler.h, CaptureCore.h, NearField.h): each is a row, once.
    const char* keys[] = {"store.coarsestSpacing_m",
                          "store.levels",
                          "store.blendTime_s",
                          "store.allowedSunAngle_rad",
                          "store.minLifetime_s",
                          "store.maxLifetime_s",
                          "store.regenerateFraction",
                          "store.searchCells",
                          "store.reachCells",
                          "store.coarseReachCells",
                          "store.finerWeight",
                          "store.smoothInterpolation",
                          "store.bilinearFixedPoints",
                          "store.gradients",
                          "scheduler.velocityTimeConstant_s",
                          "scheduler.horizon_s",
                          "scheduler.pathStep_s",
                          "scheduler.historyLength_s",
                          "scheduler.roadSnap_m",
                          "scheduler.roadAlignment",
                          "scheduler.corridorCells",
                          "scheduler.maxLevel",
                          "scheduler.finestRingCells",
                          "scheduler.coarseRingCells",
                          "scheduler.maxWiden",
                          "scheduler.minReachSpeed_mps",
                          "scheduler.gapBonus_s",
                          "scheduler.coarseFirst_s",
                          "scheduler.staleBias_s",
                          "scheduler.adaptiveThreshold",
                          "facesPerFrame",
                          "sunThreshold",
                          "maxAside_m",
                          "defaultTimeRate_hPerS",
                          "timeJump_h",
                          "teleportDistance_m",
                          "fallbackFaceSize",
                          "primeProbes",
                          "fallbackRefresh_h",
                          "ownLight",
                          "nominalFrameTime_s",
                          "asideFraction",
                          "relightBySkyLevel",
                          "nearField.enabled",
                          "nearField.radius_m",
                          "nearField.captureRadius_m",
                          "nearField.plants",
                          "nearField.plantShadows",
                          "nearField.plantSky",
                          "nearField.smallRadius_m",
                          "nearField.terrain",
                          "nearField.terrainRadius_m",
                          "nearField.ground",
                          "nearField.groundRadius_m",
                          "nearField.groundCell_m",
                          "nearField.latticeRange_m",
                          "nearField.surfaceHeight_m",
                          "nearField.cacheEntries",
                          "nearField.objectRange_m",
                          "nearField.cornerRange_m",
                          "nearField.patchMean",
                          "nearField.patchSamples",
                          "nearField.vertexDetail",
                          "nearField.vertexAmbient_m",
                          "nearField.vertexPointsPerFrame",
                          "nearField.captureLightRange_m",
                          "nearField.captureLightCell_m",
                          "nearField.captureLightPointsPerFrame"};
    EXPECT_EQ(tunableSettings().size(), std::size(keys));
    for (const char* key : keys) EXPECT_NE(findSetting(key), nullptr) << key;
    // The saved file nests them as the reader expects.
    const nlohmann::json j = nlohmann::json::parse(settingsToJson(AmbienceVolumeSettings{}));
    EXPECT_EQ(j.at("store").at("blendTime_s").get<double>(), 1.0);
    EXPECT_EQ(j.at("nearField").at("radius_m").get<double>(), NearFieldSettings{}.radius_m);
    EXPECT_EQ(j.at("facesPerFrame").get<int>(), 1);
}

// The panel, the reader and the schema agree: the rows are the schema's keys in its order, each
// widget's range is the key's, and what the panel would write at either end of a range the
// reader takes, while the next value beyond it is refused naming the key and the range.
TEST(TuningPanel, TheRowsAreTheSchemasKeysWithTheReadersRanges) {
    const auto& keys = volumeSettingsSchema().fields();
    ASSERT_EQ(tunableSettings().size(), keys.size());
    for (std::size_t i = 0; i < keys.size(); ++i) {
        const SettingInfo& row = tunableSettings()[i];
        SCOPED_TRACE(row.key);
        EXPECT_EQ(row.key, keys[i].key);
        EXPECT_EQ(row.lo, keys[i].lo);
        EXPECT_EQ(row.hi, keys[i].hi);
        EXPECT_EQ(findSetting(row.key), &row);
        if (row.kind == SettingInfo::Kind::Boolean) continue;
        const std::string leaf = row.key.substr(row.key.rfind('.') + 1);
        const std::string range =
            "'" + leaf + "' must be in [" + jsonNumber(row.lo) + ", " + jsonNumber(row.hi) + "]";
        const double step = row.kind == SettingInfo::Kind::Integer ? 1.0 : 0.0;
        const double inf = std::numeric_limits<double>::infinity();
        const double outside[2] = {step > 0 ? row.lo - step : std::nextafter(row.lo, -inf),
                                   step > 0 ? row.hi + step : std::nextafter(row.hi, inf)};
        for (int end = 0; end < 2; ++end) {
            AmbienceVolumeSettings s;
            setSettingValue(s, row, end == 0 ? row.lo : row.hi);
            try {
                ambienceSettingsFromJson(settingsToJson(s), "panel");
            } catch (const InputError& e) {
                // Only a check that binds keys together may refuse an end (the finest spacing).
                EXPECT_EQ(std::string(e.what()).find("must be"), std::string::npos) << e.what();
            }
            setSettingValue(s, row, outside[end]);
            try {
                ambienceSettingsFromJson(settingsToJson(s), "panel");
                ADD_FAILURE() << outside[end] << " taken";
            } catch (const InputError& e) {
                EXPECT_NE(std::string(e.what()).find(range), std::string::npos) << e.what();
            }
        }
    }
}

TEST(TuningPanel, OnlyTheLatticeTheSunThresholdAndTheNearFieldRebuild) {
    // AmbienceVolume::retunable: a volume is built with these; everything else applies in place.
    for (const SettingInfo& info : tunableSettings()) {
        const std::string key = info.key;
        const bool expected = key == "store.coarsestSpacing_m" || key == "store.levels" ||
                              key == "sunThreshold" || key.rfind("nearField.", 0) == 0;
        EXPECT_EQ(info.rebuilds, expected) << key;
    }
}

// ---- In a window (Xvfb) ------------------------------------------------------------------------

class TuningPanelWindow : public ::testing::Test {
  protected:
    static constexpr int kW = 640, kH = 420;
    void SetUp() override {
        if (!std::getenv("DISPLAY"))
            GTEST_SKIP() << "needs a display; ctest runs these as tuning_panel_xvfb (xvfb-run)";
        platform_ = createGlfwPlatform(kW, kH, "tuning panel test", true);
        world_ = std::make_unique<World>(WorldSettings{});
        RenderSettings rs;
        rs.width = kW, rs.height = kH;
        renderer_ = std::make_unique<Renderer>(*world_, rs);
        live_ = std::make_unique<LiveMethod>(*renderer_, "volume", AmbienceVolumeSettings{});
        panel_ = std::make_unique<TuningPanel>(platform_->nativeWindow(), *live_,
                                               (dir_ / "settings.json").string(), 90.0);
    }
    void TearDown() override {
        panel_.reset();
        live_.reset();
        renderer_.reset();
        platform_.reset();
    }
    // One frame of the view at a fixed camera: the panel's widgets, the stages, the blit and
    // (with `showPanel`) the panel. Returns the panel's vertex count.
    int frame(bool showPanel = true) {
        platform_->pollEvents();
        if (showPanel) panel_->build(controls_);
        FrameInput input;
        time_s_ += 1.0 / 30.0;
        input.time_s = time_s_;
        input.timeOfDay_h = 12.0;
        input.camera.position_m = glm::dvec3(0.0, world_->height(0.0, 0.0) + 2.0, 0.0);
        input.camera.forward = glm::dvec3(0.0, 0.0, -1.0);
        input.camera.up = glm::dvec3(0.0, 1.0, 0.0);
        last_ = live_->loop().step(input);
        panel_->frameDone(last_, input.camera, input.timeOfDay_h);
        renderer_->blitToWindow(kW, kH);
        const int vertices = showPanel ? panel_->render(kW, kH) : 0;
        window_ = readWindowRgb8(kW, kH);
        platform_->swapBuffers();
        return vertices;
    }

    fs::path dir_ = test::scratchDir("tuning-panel");
    std::unique_ptr<Platform> platform_;
    std::unique_ptr<World> world_;
    std::unique_ptr<Renderer> renderer_;
    std::unique_ptr<LiveMethod> live_;
    std::unique_ptr<TuningPanel> panel_;
    ViewControls controls_;
    double time_s_ = 0.0;
    FrameRecord last_;
    std::vector<unsigned char> window_;
};

// Mean absolute difference of two RGB images over the rectangle [x0, x1) x [y0, y1).
double meanDifference(const std::vector<unsigned char>& a, const std::vector<unsigned char>& b,
                      int width, int x0, int y0, int x1, int y1) {
    double sum = 0.0;
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
            for (int c = 0; c < 3; ++c) {
                const std::size_t i = (std::size_t(y) * width + x) * 3 + c;
                sum += std::abs(int(a[i]) - int(b[i]));
            }
    return sum / (double(x1 - x0) * (y1 - y0) * 3.0);
}

TEST_F(TuningPanelWindow, DrawsOverTheSceneAndOnlyThere) {
    frame();  // ImGui lays the window out on its first frame
    const int vertices = frame();
    // A glyph is 4 vertices: the panel's lines of text alone make hundreds.
    EXPECT_GT(vertices, 200);
    const std::vector<unsigned char> scene = renderer_->readRgb8();
    ASSERT_EQ(window_.size(), scene.size());
    // The panel sits at the top left, 400 px wide (the window's own default): beneath it the
    // window differs from the scene; right of it the window is the scene's 1:1 blit.
    EXPECT_GT(meanDifference(window_, scene, kW, 16, 16, 380, kH - 16), 15.0);
    EXPECT_LT(meanDifference(window_, scene, kW, 430, 0, kW, kH), 0.5);
    // Without the panel the whole window is the scene.
    frame(false);
    EXPECT_LT(meanDifference(window_, renderer_->readRgb8(), kW, 0, 0, kW, kH), 0.5);
}

TEST_F(TuningPanelWindow, ASettingChangesTheRunningMethod) {
    frame();
    AmbienceVolume* volume = live_->stages().volume();
    ASSERT_NE(volume, nullptr);
    EXPECT_EQ(last_.ambience.faces, 1 + 4 * 6);  // the budget's, and the first frame's prime
    // In place: the same volume captures six faces in the next frame, reads the new scheduler
    // and blend settings, and keeps its anchors.
    ASSERT_TRUE(panel_->set("facesPerFrame", 6)) << panel_->error();
    ASSERT_TRUE(panel_->set("scheduler.corridorCells", 7.5)) << panel_->error();
    ASSERT_TRUE(panel_->set("store.blendTime_s", 2.5)) << panel_->error();
    EXPECT_EQ(live_->stages().volume(), volume);
    EXPECT_EQ(live_->rebuilds(), 0);
    frame();
    EXPECT_EQ(last_.ambience.faces, 6);
    EXPECT_EQ(volume->scheduler().settings().corridorCells, 7.5);
    EXPECT_EQ(volume->store().settings().blendTime_s, 2.5);
    EXPECT_EQ(panel_->get("facesPerFrame"), 6.0);
    // The lattice cannot change in place: a new volume with four levels, the rest kept.
    ASSERT_TRUE(panel_->set("store.levels", 4)) << panel_->error();
    EXPECT_EQ(live_->rebuilds(), 1);
    frame();
    volume = live_->stages().volume();
    ASSERT_NE(volume, nullptr);
    EXPECT_EQ(volume->store().levels(), 4);
    EXPECT_EQ(volume->scheduler().settings().corridorCells, 7.5);
    EXPECT_EQ(last_.ambience.levels, 4);
    // What the reader refuses changes nothing and says what, on one line.
    EXPECT_FALSE(panel_->set("store.minLifetime_s", 700.0));
    EXPECT_NE(panel_->error().find("minLifetime_s"), std::string::npos) << panel_->error();
    EXPECT_EQ(panel_->error().find('\n'), std::string::npos);
    EXPECT_EQ(volume->store().settings().minLifetime_s, AnchorStoreSettings{}.minLifetime_s);
    EXPECT_FALSE(panel_->set("store.noSuchKey", 1.0));
    EXPECT_FALSE(panel_->set("store.blendTime_s", std::nan("")));
    EXPECT_EQ(volume->store().settings().blendTime_s, 2.5);
}

TEST_F(TuningPanelWindow, AClickOnASettingsSwitchChangesTheRunningMethod) {
    // Through Dear ImGui's own input: the pointer moved onto the panel's "nearField.enabled"
    // switch and its left button pressed and let go, as the GLFW backend hears them.
    frame();
    EXPECT_GT(last_.ambience.nearFieldPoints, 0u) << "the near field is on by default";
    GLFWwindow* window = static_cast<GLFWwindow*>(platform_->nativeWindow());
    ImGuiWindow* tuning = ImGui::FindWindowByName("Tuning (Tab hides)");
    ASSERT_NE(tuning, nullptr);
    // The other parts folded and the near field's group open, so that the switch is in view.
    for (const char* header : {"Replay", "View", "Stage times", "Anchors and memory", "Error"})
        tuning->StateStorage.SetInt(tuning->GetIDNoKeepAlive(header), 0);
    const ImGuiID group = tuning->GetIDNoKeepAlive("nearField");
    tuning->StateStorage.SetInt(group, 1);
    const ImGuiID target = ImHashStr("nearField.enabled", 0, group);
    ImGui_ImplGlfw_CursorEnterCallback(window, GLFW_TRUE);
    // Find the switch: the pointer down the panel, over the switches' labels, until ImGui says
    // it hovers this one.
    bool found = false;
    for (int y = 20; y < kH && !found; y += 3) {
        glfwSetCursorPos(window, 120.0, double(y));
        panel_->build(controls_);
        found = GImGui->HoveredId == target;
    }
    ASSERT_TRUE(found) << "the switch is not under the pointer anywhere in the panel";
    EXPECT_TRUE(live_->settings().capture.nearField.enabled);
    ImGui_ImplGlfw_MouseButtonCallback(window, GLFW_MOUSE_BUTTON_LEFT, GLFW_PRESS, 0);
    panel_->build(controls_);  // pressed
    panel_->build(controls_);  // let go over it: a click
    EXPECT_FALSE(live_->settings().capture.nearField.enabled);
    EXPECT_EQ(live_->rebuilds(), 1) << "the near field cannot change in place";
    frame();
    EXPECT_EQ(last_.ambience.nearFieldPoints, 0u);
}

TEST_F(TuningPanelWindow, TheErrorIsMeasuredOnDemandAndEveryNFrames) {
    frame();
    EXPECT_EQ(panel_->lastMeasurement().frame, -1);
    panel_->measureNextFrame();
    frame();
    const TuningPanel::Measurement first = panel_->lastMeasurement();
    EXPECT_EQ(first.frame, last_.index);
    EXPECT_TRUE(std::isfinite(first.groundError));
    EXPECT_GE(first.groundError, 0.0);
    // Before any anchor the volume answers with its fallback, the sky over flat ground: not
    // what a capture among the trees sees, so the error is well above zero.
    EXPECT_GT(first.groundError, 0.01);
    panel_->setMeasureEvery(2);
    for (int i = 0; i < 4; ++i) frame();
    EXPECT_EQ(panel_->lastMeasurement().frame % 2, 0);
    EXPECT_GT(panel_->lastMeasurement().frame, first.frame);
}

TEST_F(TuningPanelWindow, SaveAndLoadRoundTripAndRunReadsTheFile) {
    const AmbienceVolumeSettings moved = movedSettings();
    frame();
    for (const SettingInfo& info : tunableSettings())
        ASSERT_TRUE(panel_->set(info.key, settingValue(moved, info))) << panel_->error();
    ASSERT_TRUE(panel_->save()) << panel_->error();
    expectSameSettings(live_->settings(), moved);
    // A fresh method at the defaults loads them back.
    panel_.reset();
    live_ = std::make_unique<LiveMethod>(*renderer_, "volume", AmbienceVolumeSettings{});
    panel_ = std::make_unique<TuningPanel>(platform_->nativeWindow(), *live_,
                                           (dir_ / "settings.json").string(), 90.0);
    ASSERT_TRUE(panel_->load()) << panel_->error();
    expectSameSettings(live_->settings(), moved);
    frame();
    EXPECT_EQ(live_->stages().volume()->store().settings().blendTime_s, moved.store.blendTime_s);

    // A bad file: one line naming it, and nothing lost.
    const fs::path bad = dir_ / "bad.json";
    std::ofstream(bad) << "{\"store\": {\"blendTime_s\": \"slow\"}}";
    panel_->setConfigPath(bad.string());
    EXPECT_FALSE(panel_->load());
    EXPECT_NE(panel_->error().find("bad.json"), std::string::npos) << panel_->error();
    EXPECT_NE(panel_->error().find("blendTime_s"), std::string::npos) << panel_->error();
    EXPECT_EQ(panel_->error().find('\n'), std::string::npos);
    expectSameSettings(live_->settings(), moved);
    panel_->setConfigPath((dir_ / "missing.json").string());
    EXPECT_FALSE(panel_->load());
    EXPECT_FALSE(panel_->error().empty());
    expectSameSettings(live_->settings(), moved);

    // `ambience run --config` takes the saved file as it is.
    const auto r = test::runAmbience("run --config " + (dir_ / "settings.json").string() +
                                     " --max-frames 2 --no-frames --out " +
                                     (dir_ / "run").string());
    EXPECT_EQ(r.exitCode, 0) << r.err;
}

}  // namespace
}  // namespace amb
