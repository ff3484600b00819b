// TuningPanel.h — the live tuning panel of `ambience view` (Dear ImGui, Debian's libimgui-dev with
// its GLFW and OpenGL 3 backends; README "The viewer's tuning panel").
//
// [SECTION] LiveMethod     the view's running method and its frame loop. New settings apply in
//                          place where the volume allows it (AmbienceVolume::retunable: all but
//                          the lattice, the sun threshold and the near field); otherwise the
//                          method is rebuilt with them, its anchors starting over.
// [SECTION] Settings       every key of the volume's settings file as a row: the settings
//                          schema's keys (lighting/SettingsSchema.h), each with its widget over
//                          the key's range; settingsToJson writes the file `--config` reads.
// [SECTION] TuningPanel    the window: the replay (pause, scrub, speed), the view (debug
//                          overlay, ambient alone), the frame's stage times as scrolling plots,
//                          anchors per level and bytes held, the error at the camera's ground
//                          point against a fresh oracle capture (on demand or every N frames),
//                          and the settings with Save and Load. Every change goes through the
//                          settings reader first: what it refuses is shown and nothing changes.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "app/frame/FrameLoop.h"
#include "lighting/AmbienceVolume.h"
#include "lighting/SettingsSchema.h"

namespace amb {

class MethodAmbienceStages;
class PanelRenderer;
class Renderer;

// ---- LiveMethod ------------------------------------------------------------------------------

class LiveMethod {
  public:
    // `renderer` must outlive it; `method` is one of ambienceMethodNames().
    LiveMethod(Renderer& renderer, std::string method, const AmbienceVolumeSettings& settings);
    ~LiveMethod();

    MethodAmbienceStages& stages() { return *stages_; }
    FrameLoop& loop() { return *loop_; }
    const std::string& name() const { return method_; }
    const AmbienceVolumeSettings& settings() const { return settings_; }
    // True for the methods the volume's settings drive (volume, nearest).
    bool tunable() const { return method_ == "volume" || method_ == "nearest"; }
    // Applies `settings` (already checked): in place on a running volume when
    // AmbienceVolume::retunable allows, otherwise by rebuilding the method. True when rebuilt.
    bool apply(const AmbienceVolumeSettings& settings);
    int rebuilds() const { return rebuilds_; }

  private:
    void build();
    Renderer& renderer_;
    std::string method_;
    AmbienceVolumeSettings settings_;
    std::unique_ptr<MethodAmbienceStages> stages_;
    std::unique_ptr<FrameLoop> loop_;
    int rebuilds_ = 0;
};

// ---- Settings --------------------------------------------------------------------------------

// A row: a key of the volume's settings file as the settings schema describes it
// (lighting/SettingsSchema.h): its kind, its range (the widget's), whether its slider moves in
// ratios, its help, whether a change rebuilds the method, and the field it sets.
using SettingInfo = SettingField<AmbienceVolumeSettings>;
// Every key ambienceSettingsFromJson reads, in the file's order.
const std::vector<SettingInfo>& tunableSettings();
const SettingInfo* findSetting(const std::string& key);
double settingValue(const AmbienceVolumeSettings& settings, const SettingInfo& info);
void setSettingValue(AmbienceVolumeSettings& settings, const SettingInfo& info, double value);
// The settings as the file `--config` reads (every key of the table, nested as the reader
// expects), so that ambienceSettingsFromJson(settingsToJson(s)) == s.
std::string settingsToJson(const AmbienceVolumeSettings& settings);

// ---- TuningPanel -----------------------------------------------------------------------------

// What the panel changes in the view besides the method; the view reads it every frame.
struct ViewControls {
    bool paused = false;
    double replayTime_s = 0.0;  // position in the followed replay
    double speed = 1.0;         // replay and clocks run this much faster
    bool debugOverlay = false;
    bool ambientView = false;  // the ambient term alone (RenderOutput::Ambient)
};

class TuningPanel {
  public:
    // Needs the window's GL context current; `window` is Platform::nativeWindow (the backends
    // are app/render/PanelRenderer.h's). `configPath`: the file Save writes and Load reads;
    // `replayDuration_s` bounds the scrub slider (0: no replay).
    TuningPanel(void* window, LiveMethod& method, std::string configPath, double replayDuration_s);
    ~TuningPanel();
    TuningPanel(const TuningPanel&) = delete;
    TuningPanel& operator=(const TuningPanel&) = delete;

    // True when the panel takes the keyboard or the mouse (the view then leaves them alone).
    bool wantsKeyboard() const;
    bool wantsMouse() const;
    // Builds this frame's widgets, before the frame runs: what they change applies to it.
    void build(ViewControls& controls);
    // After the frame's stages: its record (times, anchors), and the camera and the time of day
    // for the error measurement (taken now when asked for or due).
    void frameDone(const FrameRecord& record, const CameraSample& camera, double timeOfDay_h);
    // Draws what build() made into the window (after the scene's blit, before the swap).
    // Returns the number of vertices drawn.
    int render(int windowWidth, int windowHeight);

    // What the widgets call (and tests). A change the settings reader refuses, or a file that
    // cannot be read or written, returns false and sets error(); nothing else changes.
    bool set(const std::string& key, double value);
    double get(const std::string& key) const;
    bool save();
    bool load();
    void setConfigPath(const std::string& path) { configPath_ = path; }
    const std::string& configPath() const { return configPath_; }
    const std::string& error() const { return error_; }
    const std::string& notice() const { return notice_; }
    // The error measurement: the next frameDone measures; every N frames (0: off).
    void measureNextFrame() { measureNext_ = true; }
    void setMeasureEvery(int frames) { measureEvery_ = frames; }
    struct Measurement {
        int frame = -1;            // -1: none yet
        double groundError = 0.0;  // at the camera's ground point
        double ringsError = -1.0;  // mean over the ring witnesses as well (-1: not taken)
        double seconds = 0.0;      // wall time of the oracle captures
    };
    const Measurement& lastMeasurement() const { return measurement_; }
    // The panel's own CPU time in the latest frame (widgets and draw) [ms]; not a stage's.
    double panel_ms() const { return panel_ms_; }

  private:
    bool applyCandidate(const AmbienceVolumeSettings& candidate, const std::string& what);
    void measure(const CameraSample& camera, double timeOfDay_h, int frame);
    void drawReplay(ViewControls& controls);
    void drawView(ViewControls& controls);
    void drawTimings();
    void drawAnchors();
    void drawError();
    void drawSettings();
    bool settingWidget(const SettingInfo& info);

    void* window_;
    LiveMethod& method_;
    std::string configPath_;
    double replayDuration_s_;
    std::unique_ptr<PanelRenderer> renderer_;
    bool built_ = false;                      // build() ran since the last render()
    double build_ms_ = 0.0, panel_ms_ = 0.0;  // its own CPU time: widgets, and widgets + draw
    std::string error_, notice_;
    // The draft of a setting that rebuilds the method while its slider is held (set() when let go).
    AmbienceVolumeSettings draft_;
    const SettingInfo* drafting_ = nullptr;
    // History for the plots.
    static constexpr int kHistory = 240;
    std::array<std::array<float, kHistory>, kFrameStages + 1> stageHistory_{};  // + frame
    std::array<float, kHistory> errorHistory_{};
    int historyNext_ = 0, historyCount_ = 0, errorNext_ = 0, errorCount_ = 0;
    FrameRecord last_;
    // The error measurement.
    bool measureNext_ = false, measureRings_ = false;
    int measureEvery_ = 0;
    Measurement measurement_;
};

}  // namespace amb
