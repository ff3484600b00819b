// ViewCommand.cpp — `ambience view`: the world in a window (GLFW), with the tuning panel
// (app/cli/TuningPanel.h) unless --no-panel.
//
// Keys: F toggles follow-replay / free-fly; free-fly: W A S D move, Q E down / up, Shift faster,
// right mouse button + drag looks around; follow: Space pauses, Left / Right scrub 5 s;
// [ and ] change the time of day by half an hour; R starts / stops recording the camera to a new
// replay file; P saves a screenshot; Tab hides / shows the panel; Esc quits. While the panel
// takes the keyboard (a text field) or the mouse (over it), the view leaves them alone.
// `--frames N --screenshot FILE` renders N frames, saves the last and exits (used by the tests
// under Xvfb); `--window-shot FILE` saves the window as shown, the panel included.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>
#include <glm/geometric.hpp>

#include "app/cli/CliChecks.h"
#include "app/cli/Commands.h"
#include "app/cli/OutputPaths.h"
#include "app/render/DebugOverlay.h"
#include "app/frame/FrameLoop.h"
#include "app/render/CubeCaptureGl.h"
#include "app/render/ShaderDirectory.h"
#include "app/render/Renderer.h"
#include "app/platform/Platform.h"
#include "app/cli/RunReport.h"
#include "app/cli/SettingsFlags.h"
#include "app/cli/TuningPanel.h"
#include "app/render/PanelRenderer.h"
#include "app/frame/MethodStages.h"
#include "lighting/Baselines.h"
#include "world/Error.h"
#include "world/TextFile.h"
#include "world/World.h"

namespace amb {

namespace {

struct ViewOptions {
    std::string replay;
    std::string size = "960x540";
    int frames = 0;
    std::string screenshot;
    std::string record = "recorded.json";
    std::string ambient = "volume";
    bool debugOverlay = false;
    std::string view = "shaded";
    std::string camera = "chase";  // following a drive replay: chase or hood
    std::string shadows = "on";
    std::string shaders;
    double time_h = -1.0;
    std::string config;      // the volume's settings (as `run --config`)
    std::vector<std::string> settingAssignments;  // --set KEY=VALUE, after --config
    bool noPanel = false;
    std::string windowShot;  // with --frames: the window as shown, the panel included
};

constexpr double kStep_s = 1.0 / 30.0;  // the viewer's fixed simulation step

struct FreeCamera {
    glm::dvec3 position{0.0};
    double yaw_rad = 0.0, pitch_rad = 0.0;  // yaw 0 looks north (-Z)

    CameraSample sample() const {
        CameraSample s;
        s.position_m = position;
        s.forward = glm::dvec3(std::sin(yaw_rad) * std::cos(pitch_rad), std::sin(pitch_rad),
                               -std::cos(yaw_rad) * std::cos(pitch_rad));
        const glm::dvec3 right = glm::normalize(glm::cross(s.forward, glm::dvec3(0, 1, 0)));
        s.up = glm::normalize(glm::cross(right, s.forward));
        return s;
    }
    void lookAlong(const CameraSample& s) {
        position = s.position_m;
        yaw_rad = std::atan2(s.forward.x, -s.forward.z);
        pitch_rad = std::asin(std::clamp(s.forward.y, -1.0, 1.0));
    }
};

// Key presses (down now, up at the last look), while `enabled` (not while the panel types).
struct KeyEdges {
    const Platform& window;
    bool enabled = true;
    bool prev[kKeyCount] = {};
    bool pressed(Key key) {
        const bool now = window.keyDown(key);
        const bool edge = now && !prev[int(key)];
        prev[int(key)] = now;
        return edge && enabled;
    }
};

// The camera on the replay, which advances by `step_s` unless paused (and starts over at its
// end); the time of day follows it when `followDay` (no --time).
CameraSample followReplay(const Replay& replay, ViewControls& controls, double step_s,
                          bool followDay, double& timeOfDay_h) {
    if (!controls.paused) controls.replayTime_s += step_s;
    if (controls.replayTime_s > replay.duration_s()) controls.replayTime_s = 0.0;
    if (followDay && !controls.paused) timeOfDay_h = replay.timeOfDayAt_h(controls.replayTime_s);
    return replay.sampleAt(controls.replayTime_s);
}

// Checks every option and the files before any work; returns the window size.
Size checkViewOptions(const ViewOptions& o) {
    const Size size = parseSize(o.size, "--size");
    checkAmbienceMethod(o.ambient, "--ambient");
    parseViewOutput(o.view, "--view");
    parseCarView(o.camera, "--camera");
    parseShadowSwitch(o.shadows, "--shadows");
    if (o.debugOverlay && o.ambient != "volume")
        throw InputError("--debug-overlay", "needs --ambient volume");
    if (o.frames < 0) throw InputError("--frames", "must be >= 0");
    if (!o.screenshot.empty() && o.frames == 0) {
        throw InputError("--screenshot", "needs --frames N (the frame to save)");
    }
    if (!o.windowShot.empty() && o.frames == 0) {
        throw InputError("--window-shot", "needs --frames N (the frame to save)");
    }
    FilePlan files;
    files.input("--replay", o.replay);
    files.input("--config", o.config);
    files.output("--screenshot", o.screenshot);
    files.output("--window-shot", o.windowShot);
    files.check();
    if (!o.replay.empty() && resolvedPath(o.record) == resolvedPath(o.replay))
        throw InputError("--record", "'" + o.record + "' is also the input --replay");
    return size;
}

std::unique_ptr<Platform> openWindow(const Size& size) {
    try {
        return createGlfwPlatform(size.width, size.height, "ambience", true);
    } catch (const PlatformUnavailable& e) {
        // Almost always a machine without a display: say what to do instead.
        throw InputError("view", std::string(e.what()) +
                                     "; 'view' opens a window: run it on a display, under "
                                     "'xvfb-run', or use 'ambience run' to render headless");
    }
}

// Free flight: W A S D move, Q E down / up, Shift faster, right mouse button + drag looks
// around (the keys and the mouse only when the panel does not take them); never below 1 m
// above the ground.
CameraSample flyFree(const Platform& window, const World& world, FreeCamera& free, double& lastX,
                     double& lastY, bool keys, bool mouse) {
    const auto [x, y] = window.cursorPosition();
    if (mouse && window.mouseButtonDown(MouseButton::Right)) {
        free.yaw_rad += (x - lastX) * 0.004;
        free.pitch_rad = std::clamp(free.pitch_rad - (y - lastY) * 0.004, -1.5, 1.5);
    }
    lastX = x;
    lastY = y;
    const CameraSample s = free.sample();
    const glm::dvec3 right = glm::normalize(glm::cross(s.forward, glm::dvec3(0, 1, 0)));
    const double speed = (window.keyDown(Key::LeftShift) ? 120.0 : 20.0) * kStep_s;
    glm::dvec3 move(0.0);
    if (!keys) return s;
    if (window.keyDown(Key::W)) move += s.forward;
    if (window.keyDown(Key::S)) move -= s.forward;
    if (window.keyDown(Key::D)) move += right;
    if (window.keyDown(Key::A)) move -= right;
    if (window.keyDown(Key::E)) move.y += 1.0;
    if (window.keyDown(Key::Q)) move.y -= 1.0;
    free.position += move * speed;
    const double ground = world.height(free.position.x, free.position.z) + 1.0;
    free.position.y = std::max(free.position.y, ground);
    return free.sample();
}

// The R key: the camera at the viewer's fixed step, written as a fly replay of `world`.
class CameraRecorder {
  public:
    CameraRecorder(const WorldSettings& world, std::string path)
        : world_(world), path_(std::move(path)) {}
    void toggle(double timeOfDay_h) {
        on_ = !on_;
        if (on_) {
            recording_ = Replay();
            recording_.name = "recorded";
            recording_.description = "recorded in the viewer";
            recording_.world = world_;
            recording_.mode = ReplayMode::Fly;
            recording_.timeOfDayStart_h = timeOfDay_h;
            recording_.timeRate = 0.0;
            recording_.step_s = kStep_s;
            std::fprintf(stderr, "view: recording\n");
        } else if (!recording_.samples.empty()) {
            writeReplay(recording_, path_);
            std::fprintf(stderr, "view: recorded %zu samples to %s\n", recording_.samples.size(),
                         path_.c_str());
        }
    }
    void add(const CameraSample& camera) {
        if (!on_) return;
        CameraSample s = camera;
        s.time_s = double(recording_.samples.size()) * kStep_s;
        s.cut = false;
        recording_.samples.push_back(s);
    }
    // At exit: what is still being recorded is written.
    void finish() {
        if (on_ && !recording_.samples.empty()) writeReplay(recording_, path_);
    }

  private:
    WorldSettings world_;
    std::string path_;
    Replay recording_;
    bool on_ = false;
};

// The P key's screenshot (the scene), and on the last frame of --frames the --screenshot and
// the --window-shot (the window as shown, the panel included).
void saveShots(const ViewOptions& o, bool pKey, bool last, Renderer& renderer, Platform& platform,
               int& screenshots) {
    if (pKey || (last && !o.screenshot.empty())) {
        char name[64];
        std::snprintf(name, sizeof(name), "screenshot-%03d.png", screenshots++);
        const std::string path = last && !o.screenshot.empty() ? o.screenshot : name;
        writeImageRgb8(path, renderer.width(), renderer.height(), renderer.readRgb8());
        std::fprintf(stderr, "view: screenshot %s\n", path.c_str());
    }
    if (last && !o.windowShot.empty()) {
        writeImageRgb8(o.windowShot, platform.width(), platform.height(),
                       readWindowRgb8(platform.width(), platform.height()));
        std::fprintf(stderr, "view: window %s\n", o.windowShot.c_str());
    }
}

// The view's settings: --config, read as `ambience run --config` reads it, then --set.
AmbienceVolumeSettings viewSettings(const ViewOptions& o) {
    AmbienceVolumeSettings settings;
    if (!o.config.empty())
        settings = ambienceSettingsFromJson(
            readTextFile(o.config, "ambience settings file", kMaxSettingsFileBytes), o.config);
    applySettingAssignments(o.settingAssignments, settings, nullptr);
    return settings;
}

void runView(const ViewOptions& o) {
    const Size size = checkViewOptions(o);
    Replay replay;
    const bool haveReplay = !o.replay.empty();
    if (haveReplay) replay = readReplay(o.replay);
    const AmbienceVolumeSettings settings = viewSettings(o);

    std::unique_ptr<Platform> platform = openWindow(size);
    const World world(replay.world);
    RenderSettings rs;
    rs.width = size.width;
    rs.height = size.height;
    rs.viewOutput = parseViewOutput(o.view, "--view");
    rs.shadows.enabled = rs.shadows.captures = parseShadowSwitch(o.shadows, "--shadows");
    Renderer renderer(world, rs);
    // The frame of `run`, with the camera and the clocks from the keyboard, the mouse and the
    // panel; the panel may rebuild the method (LiveMethod).
    LiveMethod live(renderer, o.ambient, settings);
    std::unique_ptr<TuningPanel> panel;
    if (!o.noPanel) {
        panel = std::make_unique<TuningPanel>(
            platform->nativeWindow(), live, o.config.empty() ? "ambience-settings.json" : o.config,
            haveReplay ? replay.duration_s() : 0.0);
    }
    bool showPanel = panel != nullptr;
    ViewControls controls;
    controls.debugOverlay = o.debugOverlay;
    controls.ambientView = rs.viewOutput == RenderOutput::Ambient;
    double simulation_s = 0.0;  // the volume's clock: fixed steps, stops while paused

    double timeOfDay_h = o.time_h >= 0.0 ? o.time_h : replay.timeOfDayStart_h;
    bool follow = haveReplay;
    FreeCamera free;
    if (haveReplay) {
        free.lookAlong(replay.sampleAt(0.0));
    } else {
        free.position = glm::dvec3(0.0, world.height(0.0, 0.0) + 20.0, 0.0);
    }
    CameraRecorder recorder(replay.world, o.record);
    int screenshots = 0;
    KeyEdges keys{*platform};
    auto pressed = [&](Key key) { return keys.pressed(key); };
    const CursorPosition cursor = platform->cursorPosition();
    double lastX = cursor.x, lastY = cursor.y;
    std::fprintf(stderr,
                 "view: %s; F follow/free, WASD+QE, right mouse look, Space pause, "
                 "arrows scrub, [ ] time, R record, P screenshot, Tab panel, Esc quit\n",
                 platform->glRenderer().c_str());

    for (int frame = 0; !platform->shouldClose(); ++frame) {
        platform->pollEvents();
        // The panel's widgets first: what they change applies to this frame.
        if (panel && showPanel) panel->build(controls);
        keys.enabled = !(panel && showPanel && panel->wantsKeyboard());
        const bool mouseToView = !(panel && showPanel && panel->wantsMouse());
        if (pressed(Key::Escape)) break;
        if (pressed(Key::Tab) && panel) showPanel = !showPanel;
        if (pressed(Key::F) && haveReplay) {
            follow = !follow;
            if (!follow) free.lookAlong(replay.sampleAt(controls.replayTime_s));
        }
        double& replayTime_s = controls.replayTime_s;
        if (pressed(Key::Space)) controls.paused = !controls.paused;
        if (pressed(Key::Left)) replayTime_s = std::max(0.0, replayTime_s - 5.0);
        if (pressed(Key::Right)) replayTime_s += 5.0;
        if (pressed(Key::LeftBracket)) timeOfDay_h = std::fmod(timeOfDay_h + 23.5, 24.0);
        if (pressed(Key::RightBracket)) timeOfDay_h = std::fmod(timeOfDay_h + 0.5, 24.0);
        renderer.setViewOutput(controls.ambientView ? RenderOutput::Ambient : RenderOutput::Shaded);

        // Camera for this frame.
        const double step_s = kStep_s * controls.speed;
        CameraSample cam;
        if (follow) {
            cam = followReplay(replay, controls, step_s, o.time_h < 0.0, timeOfDay_h);
        } else {
            cam = flyFree(*platform, world, free, lastX, lastY, keys.enabled, mouseToView);
        }

        // Record the camera at the fixed step.
        if (pressed(Key::R)) recorder.toggle(timeOfDay_h);
        recorder.add(cam);

        // Every stage of the frame (FrameLoop), on the window's camera and clocks.
        FrameInput input;
        if (!controls.paused) simulation_s += step_s;
        input.time_s = simulation_s;
        input.replayTime_s = replayTime_s;
        input.timeOfDay_h = timeOfDay_h;
        input.camera = cam;
        // Following a drive: the car, seen as --camera says; flying free: no car. Set on the
        // loop each frame, since the panel may rebuild the method and its loop.
        const CarView carView = follow && replay.mode == ReplayMode::Drive
                                    ? parseCarView(o.camera, "--camera") : CarView::None;
        if (carView != live.loop().carView())
            live.loop().setCarView(carView,
                                   [&world](double x, double z) { return world.height(x, z); });
        const FrameRecord record = live.loop().step(input);
        const CameraSample eye = record.view;  // the eye the view rendered from
        if (panel) panel->frameDone(record, cam, timeOfDay_h);
        AmbienceVolume* volume = live.stages().volume();
        if (controls.debugOverlay && volume) {
            auto pixels = renderer.readRgb8();
            drawAnchorOverlay(pixels, size.width, size.height, renderer.viewProjection(eye),
                              eye.position_m, *volume);
            renderer.replaceLdr(pixels);
        }
        renderer.blitToWindow(platform->width(), platform->height());
        if (panel && showPanel) panel->render(platform->width(), platform->height());

        const bool last = o.frames > 0 && frame + 1 >= o.frames;
        saveShots(o, pressed(Key::P), last, renderer, *platform, screenshots);
        platform->swapBuffers();
        if (last) break;
    }
    recorder.finish();
}

}  // namespace

void addViewCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("view", "show the world in a window (follow a replay or fly)");
    auto o = std::make_shared<ViewOptions>();
    cmd->add_option("--replay", o->replay, "replay to follow (its world is shown)");
    cmd->add_option("--size", o->size, "window size WxH (default 960x540)");
    cmd->add_option("--time", o->time_h, "fixed time of day [hours] (default: the replay's)")
        ->check(FiniteRange(0.0, 24.0));
    cmd->add_option("--ambient", o->ambient, ambienceMethodHelp());
    cmd->add_flag("--debug-overlay", o->debugOverlay,
                  "mark anchors and the probe being captured on screen and on screenshots");
    cmd->add_option("--view", o->view,
                    "shaded (default) or ambient: the ambient term alone, every surface white");
    cmd->add_option("--camera", o->camera,
                    "following a drive replay: chase (default; behind and above the car) or hood");
    cmd->add_option("--shadows", o->shadows,
                    "on (default) or off: shadows of the sun and moon in the view and the captures");
    cmd->add_option("--record", o->record, "file the R key records to (default recorded.json)");
    cmd->add_option("--frames", o->frames, "render N frames, then exit (non-interactive)");
    cmd->add_option("--screenshot", o->screenshot, "with --frames: save the last frame here");
    cmd->add_option("--config,--ambience-config", o->config,
                    "the volume's settings (JSON, as `run --config`); the panel's Save writes "
                    "and Load reads this file (default ambience-settings.json)");
    addSetOption(*cmd, o->settingAssignments);
    cmd->add_flag("--no-panel", o->noPanel, "no tuning panel (Tab hides it while running)");
    cmd->add_option("--window-shot", o->windowShot,
                    "with --frames: save the window as shown (the panel included) here");
    cmd->add_option("--shaders", o->shaders,
                    "GLSL folder (default <exe>/../shaders or $AMBIENCE_SHADER_DIR)");
    cmd->callback([o] {
        if (!o->shaders.empty()) setShaderDirectory(o->shaders);
        runView(*o);
    });
}

}  // namespace amb
