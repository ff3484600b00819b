// TuningPanel.cpp — the live tuning panel of `ambience view` (see TuningPanel.h).
//
// [SECTION] LiveMethod
// [SECTION] Settings      the table, reading and writing one setting, the settings file
// [SECTION] TuningPanel   construction and the frame; the setters; the error measurement;
//                         the widgets, one function per part of the window
#include "app/cli/TuningPanel.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <utility>

#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_stdlib.h>
#include <nlohmann/json.hpp>

#include "app/frame/MethodStages.h"
#include "app/render/CubeCaptureGl.h"
#include "app/render/PanelRenderer.h"
#include "app/render/Renderer.h"
#include "lighting/Baselines.h"
#include "lighting/Metrics.h"
#include "world/Error.h"
#include "world/TextFile.h"

namespace amb {

// ---- [SECTION] LiveMethod ----------------------------------------------------------------------

LiveMethod::LiveMethod(Renderer& renderer, std::string method,
                       const AmbienceVolumeSettings& settings)
    : renderer_(renderer), method_(std::move(method)), settings_(settings) {
    build();
}

LiveMethod::~LiveMethod() = default;

void LiveMethod::build() {
    loop_.reset();
    stages_.reset();
    stages_ = makeMethodStages(renderer_, method_, settings_, BaselineSettings{});
    loop_ = std::make_unique<FrameLoop>(renderer_, *stages_);
}

bool LiveMethod::apply(const AmbienceVolumeSettings& settings) {
    AmbienceVolume* volume = stages_->volume();
    if (volume && AmbienceVolume::retunable(settings_, settings)) {
        volume->retune(settings);
        settings_ = settings;
        return false;
    }
    settings_ = settings;
    build();
    ++rebuilds_;
    return true;
}

// ---- [SECTION] Settings ------------------------------------------------------------------------

namespace {

using Kind = SettingInfo::Kind;
using S = AmbienceVolumeSettings;

// One row: key, kind, widget range, logarithmic, help, the field (rebuilds: see makeTable).
const SettingInfo kRows[] = {
    // store (lighting/AnchorStore.h)
    {"store.coarsestSpacing_m", Kind::Number, 27.0, 2187.0, true,
     "spacing of the coarsest lattice level [m]; level L has s_0 / 3^L",
     [](S& s) -> void* { return &s.store.coarsestSpacing_m; }, false},
    {"store.levels", Kind::Integer, 1, 8, false,
     "lattice levels (the finest is s_0 / 3^(levels - 1))",
     [](S& s) -> void* { return &s.store.levels; }, false},
    {"store.blendTime_s", Kind::Number, 0.0, 10.0, false,
     "a refreshed anchor blends, a new one fades in, over this time [s]",
     [](S& s) -> void* { return &s.store.blendTime_s; }, false},
    {"store.allowedSunAngle_rad", Kind::Number, 0.001, 0.5, true,
     "a capture is out of date once the sun has moved this far [rad]",
     [](S& s) -> void* { return &s.store.allowedSunAngle_rad; }, false},
    {"store.minLifetime_s", Kind::Number, 0.1, 600.0, true, "shortest anchor lifetime [s]",
     [](S& s) -> void* { return &s.store.minLifetime_s; }, false},
    {"store.maxLifetime_s", Kind::Number, 1.0, 3600.0, true,
     "longest anchor lifetime (also while time stands still) [s]",
     [](S& s) -> void* { return &s.store.maxLifetime_s; }, false},
    {"store.regenerateFraction", Kind::Number, 0.0, 1.0, false,
     "an anchor asks for a new capture after this fraction of its lifetime",
     [](S& s) -> void* { return &s.store.regenerateFraction; }, false},
    {"store.searchCells", Kind::Integer, 1, 16, false, "nearest-anchor search, in cells",
     [](S& s) -> void* { return &s.store.searchCells; }, false},
    {"store.reachCells", Kind::Integer, 1, 16, false,
     "a hole takes the residuals of the anchors within this many cells",
     [](S& s) -> void* { return &s.store.reachCells; }, false},
    {"store.coarseReachCells", Kind::Integer, 1, 16, false, "the same at the coarsest level",
     [](S& s) -> void* { return &s.store.coarseReachCells; }, false},
    {"store.finerWeight", Kind::Number, 0.0, 1.0, false,
     "weight of the finer levels' anchors in a hole's fill",
     [](S& s) -> void* { return &s.store.finerWeight; }, false},
    {"store.smoothInterpolation", Kind::Boolean, 0, 1, false,
     "bicubic Hermite cells (C1); off: bilinear",
     [](S& s) -> void* { return &s.store.smoothInterpolation; }, false},
    {"store.bilinearFixedPoints", Kind::Boolean, 0, 1, false,
     "terrain corners and road vertices read bilinear cells",
     [](S& s) -> void* { return &s.store.bilinearFixedPoints; }, false},
    // scheduler (lighting/ProbeScheduler.h)
    {"scheduler.velocityTimeConstant_s", Kind::Number, 0.0, 5.0, false,
     "inertia of the velocity filter [s]",
     [](S& s) -> void* { return &s.scheduler.velocityTimeConstant_s; }, false},
    {"scheduler.horizon_s", Kind::Number, 0.0, 10.0, false,
     "how far ahead the path is predicted [s]",
     [](S& s) -> void* { return &s.scheduler.horizon_s; }, false},
    {"scheduler.pathStep_s", Kind::Number, 0.01, 2.0, true, "spacing of the path samples [s]",
     [](S& s) -> void* { return &s.scheduler.pathStep_s; }, false},
    {"scheduler.historyLength_s", Kind::Number, 0.0, 10.0, false, "position history kept [s]",
     [](S& s) -> void* { return &s.scheduler.historyLength_s; }, false},
    {"scheduler.roadSnap_m", Kind::Number, 0.0, 50.0, false,
     "within the road's half width + this the camera is on it [m]",
     [](S& s) -> void* { return &s.scheduler.roadSnap_m; }, false},
    {"scheduler.roadAlignment", Kind::Number, 0.0, 1.0, false,
     "|cos| between motion and road needed to follow the road",
     [](S& s) -> void* { return &s.scheduler.roadAlignment; }, false},
    {"scheduler.corridorCells", Kind::Number, 0.1, 16.0, true,
     "width of the finest-level corridor along the path [cells]",
     [](S& s) -> void* { return &s.scheduler.corridorCells; }, false},
    {"scheduler.maxLevel", Kind::Integer, 0, 7, false, "never capture finer than this level",
     [](S& s) -> void* { return &s.scheduler.maxLevel; }, false},
    {"scheduler.finestRingCells", Kind::Number, 0.0, 8.0, false,
     "finest-level candidates within this many cells of the path",
     [](S& s) -> void* { return &s.scheduler.finestRingCells; }, false},
    {"scheduler.coarseRingCells", Kind::Number, 0.0, 8.0, false,
     "coarser-level candidates within this many cells of the path",
     [](S& s) -> void* { return &s.scheduler.coarseRingCells; }, false},
    {"scheduler.maxWiden", Kind::Integer, 0, 8, false,
     "doublings of the rings when everything near is fresh",
     [](S& s) -> void* { return &s.scheduler.maxWiden; }, false},
    {"scheduler.minReachSpeed_mps", Kind::Number, 0.1, 100.0, true,
     "speed assumed for the time to reach a point when slower [m/s]",
     [](S& s) -> void* { return &s.scheduler.minReachSpeed_mps; }, false},
    {"scheduler.gapBonus_s", Kind::Number, -5.0, 5.0, false,
     "priority of a point with no anchor of its level near it [s]",
     [](S& s) -> void* { return &s.scheduler.gapBonus_s; }, false},
    {"scheduler.staleBias_s", Kind::Number, -5.0, 5.0, false,
     "cost of refreshing an anchor that asks for it, at urgency 0 [s]",
     [](S& s) -> void* { return &s.scheduler.staleBias_s; }, false},
    {"scheduler.adaptiveThreshold", Kind::Number, 0.0, 1.0, false,
     "adaptive density: skip a finer point where the coarser anchors agree within this (0: off)",
     [](S& s) -> void* { return &s.scheduler.adaptiveThreshold; }, false},
    // capture, shared by every capturing method (lighting/CaptureCore.h)
    {"facesPerFrame", Kind::Integer, 1, kMaxFacesPerFrame, false,
     "capture budget: cube faces per frame (a probe is 6)",
     [](S& s) -> void* { return &s.capture.facesPerFrame; }, false},
    {"sunThreshold", Kind::Number, 100.0, 1e7, true,
     "texels brighter than this are the sun disc, left out of the SH [W sr^-1 m^-2]",
     [](S& s) -> void* { return &s.capture.sunThreshold; }, false},
    {"maxAside_m", Kind::Number, 0.0, 20.0, false, "how far a probe may move out of solids [m]",
     [](S& s) -> void* { return &s.capture.maxAside_m; }, false},
    {"defaultTimeRate_hPerS", Kind::Number, -0.01, 0.01, false,
     "rate of the time of day before it is measured [h/s] (at the start only)",
     [](S& s) -> void* { return &s.capture.defaultTimeRate_hPerS; }, false},
    {"timeJump_h", Kind::Number, 0.0, 12.0, false,
     "a larger change of the time of day in one frame is a jump [h]",
     [](S& s) -> void* { return &s.capture.timeJump_h; }, false},
    {"teleportDistance_m", Kind::Number, 0.0, 1000.0, false,
     "a camera step longer than this + 3 x speed x dt is a teleport [m]",
     [](S& s) -> void* { return &s.capture.teleportDistance_m; }, false},
    {"fallbackFaceSize", Kind::Integer, 1, 64, false, "cube map size of the sky fallback",
     [](S& s) -> void* { return &s.capture.fallbackFaceSize; }, false},
    {"fallbackRefresh_h", Kind::Number, 0.0, 1.0, false,
     "recompute the fallback after this much day time [h]",
     [](S& s) -> void* { return &s.capture.fallbackRefresh_h; }, false},
    // the volume's own (lighting/AmbienceVolume.h)
    {"nominalFrameTime_s", Kind::Number, 0.001, 0.1, true,
     "frame time assumed before one is seen [s] (at the start only)",
     [](S& s) -> void* { return &s.nominalFrameTime_s; }, false},
    {"asideFraction", Kind::Number, 0.0, 2.0, false,
     "a probe may move aside this x its level's spacing (and at most maxAside_m)",
     [](S& s) -> void* { return &s.asideFraction; }, false},
    {"relightBySkyLevel", Kind::Boolean, 0, 1, false,
     "read stale anchors scaled by the sky level now over the sky level at their capture",
     [](S& s) -> void* { return &s.relightBySkyLevel; }, false},
    // the near field (lighting/NearField.h)
    {"nearField.enabled", Kind::Boolean, 0, 1, false, "the two-scale ambience",
     [](S& s) -> void* { return &s.capture.nearField.enabled; }, false},
    {"nearField.radius_m", Kind::Number, 0.0, 60.0, false,
     "occluders this close to a shading point are put back there [m]",
     [](S& s) -> void* { return &s.capture.nearField.radius_m; }, false},
    {"nearField.captureRadius_m", Kind::Number, 0.0, 60.0, false,
     "probes leave out the plants this close to them [m]",
     [](S& s) -> void* { return &s.capture.nearField.captureRadius_m; }, false},
    {"nearField.plants", Kind::Boolean, 0, 1, false, "trees, bushes and rocks as spheres",
     [](S& s) -> void* { return &s.capture.nearField.plants; }, false},
    {"nearField.smallRadius_m", Kind::Number, 0.0, 200.0, false,
     "bushes and rocks (never captured) are near out to this [m]",
     [](S& s) -> void* { return &s.capture.nearField.smallRadius_m; }, false},
    {"nearField.terrain", Kind::Boolean, 0, 1, false, "the terrain's near horizon",
     [](S& s) -> void* { return &s.capture.nearField.terrain; }, false},
    {"nearField.terrainRadius_m", Kind::Number, 1.0, 200.0, false,
     "how far the near horizon is searched [m]",
     [](S& s) -> void* { return &s.capture.nearField.terrainRadius_m; }, false},
    {"nearField.ground", Kind::Boolean, 0, 1, false, "the ground below the point",
     [](S& s) -> void* { return &s.capture.nearField.ground; }, false},
    {"nearField.groundRadius_m", Kind::Number, 0.5, 100.0, false,
     "how far from the point's foot the ground is its own [m]",
     [](S& s) -> void* { return &s.capture.nearField.groundRadius_m; }, false},
    {"nearField.groundCell_m", Kind::Number, 0.25, 32.0, false,
     "the lattice whose ground terms objects blend [m]",
     [](S& s) -> void* { return &s.capture.nearField.groundCell_m; }, false},
    {"nearField.latticeRange_m", Kind::Number, 0.0, 1000.0, false,
     "objects first built this close to the camera blend the lattice's ground terms [m]",
     [](S& s) -> void* { return &s.capture.nearField.latticeRange_m; }, false},
    {"nearField.cacheEntries", Kind::Integer, 1, 1 << 20, true,
     "points cached with their transfer before the cache is emptied",
     [](S& s) -> void* { return &s.capture.nearField.cacheEntries; }, false},
    {"nearField.objectRange_m", Kind::Number, 0.0, 1000.0, false,
     "objects farther than this from the camera take the far field alone [m]",
     [](S& s) -> void* { return &s.capture.nearField.objectRange_m; }, false},
    {"nearField.cornerRange_m", Kind::Number, 0.0, 100000.0, false,
     "terrain corners and road vertices farther than this take the far field alone [m]",
     [](S& s) -> void* { return &s.capture.nearField.cornerRange_m; }, false},
    {"nearField.patchMean", Kind::Boolean, 0, 1, false,
     "a terrain corner takes the near field's mean over the patches it colours",
     [](S& s) -> void* { return &s.capture.nearField.patchMean; }, false},
    {"nearField.patchSamples", Kind::Integer, 1, 9, false,
     "points a side of a corner's patch mean",
     [](S& s) -> void* { return &s.capture.nearField.patchSamples; }, false},
    {"nearField.vertexDetail", Kind::Boolean, 0, 1, false,
     "the terrain's ambient scaled by its own sky visibility at each vertex of fine patches",
     [](S& s) -> void* { return &s.capture.nearField.vertexDetail; }, false},
};

std::vector<SettingInfo> makeTable() {
    std::vector<SettingInfo> t(std::begin(kRows), std::end(kRows));
    // Whether a change rebuilds: ask the volume (one truth), with each field moved alone.
    const AmbienceVolumeSettings defaults;
    for (SettingInfo& info : t) {
        AmbienceVolumeSettings moved = defaults;
        setSettingValue(moved, info,
                        info.kind == Kind::Boolean ? 1.0 - settingValue(defaults, info)
                                                   : settingValue(defaults, info) + 1.0);
        info.rebuilds = !AmbienceVolume::retunable(defaults, moved);
    }
    return t;
}

std::vector<std::string> splitKey(const std::string& key) {
    std::vector<std::string> parts;
    std::size_t start = 0;
    for (std::size_t dot; (dot = key.find('.', start)) != std::string::npos; start = dot + 1)
        parts.push_back(key.substr(start, dot - start));
    parts.push_back(key.substr(start));
    return parts;
}

}  // namespace

const std::vector<SettingInfo>& tunableSettings() {
    static const std::vector<SettingInfo> table = makeTable();
    return table;
}

const SettingInfo* findSetting(const std::string& key) {
    for (const SettingInfo& info : tunableSettings())
        if (key == info.key) return &info;
    return nullptr;
}

double settingValue(const AmbienceVolumeSettings& settings, const SettingInfo& info) {
    void* p = info.field(const_cast<AmbienceVolumeSettings&>(settings));
    switch (info.kind) {
        case Kind::Number:
            return *static_cast<double*>(p);
        case Kind::Integer:
            return double(*static_cast<int*>(p));
        case Kind::Boolean:
            return *static_cast<bool*>(p) ? 1.0 : 0.0;
    }
    return 0.0;
}

void setSettingValue(AmbienceVolumeSettings& settings, const SettingInfo& info, double value) {
    void* p = info.field(settings);
    switch (info.kind) {
        case Kind::Number:
            *static_cast<double*>(p) = value;
            break;
        case Kind::Integer:
            *static_cast<int*>(p) = int(std::lround(value));
            break;
        case Kind::Boolean:
            *static_cast<bool*>(p) = value != 0.0;
            break;
    }
}

std::string settingsToJson(const AmbienceVolumeSettings& settings) {
    nlohmann::ordered_json root = nlohmann::ordered_json::object();
    for (const SettingInfo& info : tunableSettings()) {
        nlohmann::ordered_json* at = &root;
        const std::vector<std::string> parts = splitKey(info.key);
        for (std::size_t i = 0; i + 1 < parts.size(); ++i) at = &(*at)[parts[i]];
        const double v = settingValue(settings, info);
        nlohmann::ordered_json& slot = (*at)[parts.back()];
        switch (info.kind) {
            case Kind::Number:
                slot = v;
                break;
            case Kind::Integer:
                slot = int(v);
                break;
            case Kind::Boolean:
                slot = v != 0.0;
                break;
        }
    }
    return root.dump(2) + "\n";
}

// ---- [SECTION] TuningPanel: construction and the frame
// -------------------------------------------

TuningPanel::TuningPanel(void* window, LiveMethod& method, std::string configPath,
                         double replayDuration_s)
    : window_(window),
      method_(method),
      configPath_(std::move(configPath)),
      replayDuration_s_(replayDuration_s) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;  // no imgui.ini in the working folder
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(static_cast<GLFWwindow*>(window_), true);
    renderer_ = std::make_unique<PanelRenderer>();
}

TuningPanel::~TuningPanel() {
    renderer_.reset();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
}

bool TuningPanel::wantsKeyboard() const {
    return ImGui::GetIO().WantCaptureKeyboard || ImGui::GetIO().WantTextInput;
}

bool TuningPanel::wantsMouse() const {
    return ImGui::GetIO().WantCaptureMouse;
}

void TuningPanel::build(ViewControls& controls) {
    const auto t0 = std::chrono::steady_clock::now();
    renderer_->newFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowSize(ImVec2(400, 0), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowBgAlpha(0.85f);
    if (ImGui::Begin("Tuning (Tab hides)")) {
        ImGui::Text("method %s, frame %d, %.1f ms (%.0f fps)", method_.name().c_str(), last_.index,
                    last_.frame_ms, last_.frame_ms > 0.0 ? 1000.0 / last_.frame_ms : 0.0);
        ImGui::TextDisabled("the panel: %.2f ms a frame (in no stage)", panel_ms_);
        if (!error_.empty())
            ImGui::TextColored(ImVec4(1.0f, 0.4f, 0.3f, 1.0f), "%s", error_.c_str());
        if (!notice_.empty()) ImGui::TextDisabled("%s", notice_.c_str());
        drawReplay(controls);
        drawView(controls);
        drawTimings();
        drawAnchors();
        drawError();
        drawSettings();
    }
    ImGui::End();
    ImGui::Render();
    built_ = true;
    build_ms_ =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

void TuningPanel::frameDone(const FrameRecord& record, const CameraSample& camera,
                            double timeOfDay_h) {
    last_ = record;
    for (int s = 0; s < kFrameStages; ++s)
        stageHistory_[std::size_t(s)][std::size_t(historyNext_)] =
            float(record.stage_ms[std::size_t(s)]);
    stageHistory_[kFrameStages][std::size_t(historyNext_)] = float(record.frame_ms);
    historyNext_ = (historyNext_ + 1) % kHistory;
    historyCount_ = std::min(historyCount_ + 1, kHistory);
    const bool due = measureEvery_ > 0 && record.index % measureEvery_ == 0;
    if (measureNext_ || due) {
        measureNext_ = false;
        measure(camera, timeOfDay_h, record.index);
    }
}

int TuningPanel::render(int windowWidth, int windowHeight) {
    if (!built_) return 0;
    built_ = false;
    const auto t0 = std::chrono::steady_clock::now();
    ImDrawData* data = ImGui::GetDrawData();
    renderer_->draw(data, windowWidth, windowHeight);
    // (The draw's GL work finishes with the frame's swap; this is its CPU part.)
    panel_ms_ =
        build_ms_ +
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return data ? data->TotalVtxCount : 0;
}

// ---- [SECTION] TuningPanel: the setters
// ------------------------------------------------------------

// Every candidate goes through the settings reader (ranges, lifetimes, the finest spacing) by
// way of the file it would be saved as: what it refuses is shown, and nothing changes.
bool TuningPanel::applyCandidate(const AmbienceVolumeSettings& candidate, const std::string& what) {
    AmbienceVolumeSettings checked;
    try {
        checked = ambienceSettingsFromJson(settingsToJson(candidate), what);
    } catch (const InputError& e) {
        error_ = e.what();
        return false;
    }
    error_.clear();
    if (method_.apply(checked)) {
        notice_ = what + ": method rebuilt (" + std::to_string(method_.rebuilds()) +
                  " rebuilds), anchors start over";
    } else {
        notice_ = what + ": applied in place";
    }
    return true;
}

bool TuningPanel::set(const std::string& key, double value) {
    const SettingInfo* info = findSetting(key);
    if (!info) {
        error_ = "panel: unknown setting '" + key + "'";
        return false;
    }
    if (!std::isfinite(value)) {
        error_ = "panel: '" + key + "' must be a finite number";
        return false;
    }
    AmbienceVolumeSettings candidate = method_.settings();
    setSettingValue(candidate, *info, value);
    return applyCandidate(candidate, key);
}

double TuningPanel::get(const std::string& key) const {
    const SettingInfo* info = findSetting(key);
    AMB_CHECK(info);
    return settingValue(method_.settings(), *info);
}

bool TuningPanel::save() {
    if (configPath_.empty()) {
        error_ = "save: no file named";
        return false;
    }
    std::ofstream out(configPath_, std::ios::binary | std::ios::trunc);
    out << settingsToJson(method_.settings());
    out.close();
    if (!out) {
        error_ = "save: cannot write '" + configPath_ + "'";
        return false;
    }
    error_.clear();
    notice_ = "saved " + configPath_;
    return true;
}

bool TuningPanel::load() {
    AmbienceVolumeSettings loaded;
    try {
        loaded = ambienceSettingsFromJson(
            readTextFile(configPath_, "ambience settings file", kMaxSettingsFileBytes),
            configPath_);
    } catch (const InputError& e) {
        error_ = e.what();
        return false;
    }
    if (!applyCandidate(loaded, "load " + configPath_)) return false;
    return true;
}

// ---- [SECTION] TuningPanel: the error measurement
// ------------------------------------------------

// As `ambience run --measure-every` measures (lighting/Metrics.h, ErrorMeter::frame): the
// witnesses of a measured frame, each read the way the draw reads it (appliedAt) against a fresh
// capture of the coarse scene placed as the volume's probes (oracleSh), with the run's settings.
void TuningPanel::measure(const CameraSample& camera, double timeOfDay_h, int frame) {
    const auto t0 = std::chrono::steady_clock::now();
    MethodAmbienceStages& stages = method_.stages();
    MeasureSettings settings;
    settings.sunThreshold = method_.settings().capture.sunThreshold;
    settings.maxAside_m = method_.settings().capture.maxAside_m;
    if (!measureRings_) settings.ringRadii = {settings.ringRadii.front()};  // ring 0 alone
    const std::vector<Witness> witnesses =
        witnessPoints(settings, camera.position_m.x, camera.position_m.z, frame);
    double sum = 0.0;
    for (const Witness& w : witnesses) {
        const ShRgb oracle = oracleSh(stages.cubeCapture(), stages.environment(), settings, w.x_m,
                                      w.z_m, timeOfDay_h);
        const glm::dvec3 point = stages.environment().placeProbe(w.x_m, w.z_m, settings.maxAside_m);
        const double error = relativeIrradianceError(appliedAt(stages.method(), w, point), oracle);
        if (w.ring == 0) measurement_.groundError = error;
        sum += error;
    }
    measurement_.frame = frame;
    measurement_.ringsError = measureRings_ ? sum / double(witnesses.size()) : -1.0;
    measurement_.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    errorHistory_[std::size_t(errorNext_)] = float(measurement_.groundError);
    errorNext_ = (errorNext_ + 1) % kHistory;
    errorCount_ = std::min(errorCount_ + 1, kHistory);
}

// ---- [SECTION] TuningPanel: the widgets
// ----------------------------------------------------------

namespace {

// A tooltip on the last item.
void tooltip(const std::string& text) {
    if (ImGui::IsItemHovered()) {
        ImGui::BeginTooltip();
        ImGui::PushTextWrapPos(ImGui::GetFontSize() * 30.0f);
        ImGui::TextUnformatted(text.c_str());
        ImGui::PopTextWrapPos();
        ImGui::EndTooltip();
    }
}

// A ring buffer as a plot, oldest first.
void plotRing(const char* label, const float* values, int count, int next, int capacity,
              const char* overlay, float height) {
    const int offset = count < capacity ? 0 : next;
    float hi = 0.0f;
    for (int i = 0; i < count; ++i) hi = std::max(hi, values[i]);
    // The window's width (a width of -1 collapses the plot in ImGui 1.86's auto-fit windows).
    ImGui::PlotLines(label, values, count, offset, overlay, 0.0f, std::max(hi * 1.1f, 1e-3f),
                     ImVec2(ImGui::GetContentRegionAvail().x, height));
}

}  // namespace

void TuningPanel::drawReplay(ViewControls& controls) {
    if (!ImGui::CollapsingHeader("Replay", ImGuiTreeNodeFlags_DefaultOpen)) return;
    ImGui::Checkbox("pause (Space)", &controls.paused);
    if (replayDuration_s_ > 0.0) {
        double t = controls.replayTime_s;
        const double lo = 0.0, hi = replayDuration_s_;
        if (ImGui::SliderScalar("time [s]", ImGuiDataType_Double, &t, &lo, &hi, "%.1f"))
            controls.replayTime_s = std::clamp(t, lo, hi);
        tooltip("scrub the replay (Left / Right: 5 s); a jump is a camera cut for the method");
    }
    const double slow = 0.1, fast = 8.0;
    ImGui::SliderScalar("speed", ImGuiDataType_Double, &controls.speed, &slow, &fast, "%.2fx",
                        ImGuiSliderFlags_Logarithmic);
    controls.speed = std::clamp(controls.speed, slow, fast);
    tooltip("the replay and the method's clock run this much faster per frame");
}

void TuningPanel::drawView(ViewControls& controls) {
    if (!ImGui::CollapsingHeader("View", ImGuiTreeNodeFlags_DefaultOpen)) return;
    if (method_.stages().volume()) {
        ImGui::Checkbox("debug overlay", &controls.debugOverlay);
        tooltip("anchors coloured by level and darkened with age; the probe being captured");
        ImGui::SameLine();
    }
    ImGui::Checkbox("ambient alone", &controls.ambientView);
    tooltip(
        "the ambient term alone: every surface white, lit by the ambient only (--view ambient)");
}

void TuningPanel::drawTimings() {
    if (!ImGui::CollapsingHeader("Stage times", ImGuiTreeNodeFlags_DefaultOpen)) return;
    const std::size_t now = std::size_t((historyNext_ + kHistory - 1) % kHistory);
    for (int s = 0; s <= kFrameStages; ++s) {
        const auto& h = stageHistory_[std::size_t(s)];
        const char* name = s < kFrameStages ? toString(FrameStage(s)) : "frame";
        char overlay[64];
        std::snprintf(overlay, sizeof overlay, "%s %.2f ms", name, double(h[now]));
        ImGui::PushID(s);
        plotRing("", h.data(), historyCount_, historyNext_, kHistory, overlay,
                 s < kFrameStages ? 22.0f : 36.0f);
        ImGui::PopID();
    }
}

void TuningPanel::drawAnchors() {
    if (!ImGui::CollapsingHeader("Anchors and memory", ImGuiTreeNodeFlags_DefaultOpen)) return;
    const FrameRecord::Ambience& a = last_.ambience;
    ImGui::Text("%zu held, %.1f kB; near field cache %.1f kB", a.anchors, double(a.bytes) / 1024.0,
                double(a.nearFieldBytes) / 1024.0);
    ImGui::Text("faces this frame %d, finest level %d", a.faces, a.finestLevel);
    AmbienceVolume* volume = method_.stages().volume();
    if (a.levels <= 0 || !ImGui::BeginTable("levels", 3, ImGuiTableFlags_SizingStretchSame)) return;
    ImGui::TableSetupColumn("level");
    ImGui::TableSetupColumn("spacing [m]");
    ImGui::TableSetupColumn("anchors");
    ImGui::TableHeadersRow();
    for (int L = 0; L < a.levels; ++L) {
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::Text("%d", L);
        ImGui::TableNextColumn();
        // (The record may be of the method before a rebuild, with other levels.)
        if (volume && L < volume->store().levels())
            ImGui::Text("%.3g", volume->store().spacing_m(L));
        ImGui::TableNextColumn();
        ImGui::Text("%zu", a.anchorsPerLevel[std::size_t(L)]);
    }
    ImGui::EndTable();
}

void TuningPanel::drawError() {
    if (!ImGui::CollapsingHeader("Error", ImGuiTreeNodeFlags_DefaultOpen)) return;
    if (ImGui::Button("measure now")) measureNextFrame();
    tooltip(
        "the relative irradiance error at the camera's ground point against a fresh 6-face "
        "capture there (the self-oracle of `ambience run --measure-every`)");
    ImGui::SameLine();
    ImGui::Checkbox("rings too", &measureRings_);
    tooltip("also the 12 terrain corners of the rings 16-432 m (13 captures a measurement)");
    ImGui::SetNextItemWidth(120.0f);
    ImGui::SliderInt("every N frames (0: off)", &measureEvery_, 0, 300);
    if (measurement_.frame < 0) {
        ImGui::TextDisabled("no measurement yet");
        return;
    }
    if (measurement_.ringsError >= 0.0) {
        ImGui::Text("frame %d: ground point %.4f, all witnesses %.4f (%.0f ms)", measurement_.frame,
                    measurement_.groundError, measurement_.ringsError, measurement_.seconds * 1e3);
    } else {
        ImGui::Text("frame %d: ground point %.4f (%.0f ms)", measurement_.frame,
                    measurement_.groundError, measurement_.seconds * 1e3);
    }
    plotRing("##error", errorHistory_.data(), errorCount_, errorNext_, kHistory, "error", 40.0f);
}

// One setting's widget, through set() like every other change; true when its value changed.
// Settings that apply in place (and switches) are set at once; the others, which rebuild the
// method, when the slider is let go, so that a drag rebuilds once (the slider shows the draft
// meanwhile).
bool TuningPanel::settingWidget(const SettingInfo& info) {
    const bool drafted = drafting_ == &info;
    double v = settingValue(drafted ? draft_ : method_.settings(), info);
    bool changed = false;
    switch (info.kind) {
        case Kind::Boolean: {
            bool b = v != 0.0;
            changed = ImGui::Checkbox(info.key, &b);
            v = b ? 1.0 : 0.0;
            break;
        }
        case Kind::Integer: {
            int i = int(v), lo = int(info.lo), hi = int(info.hi);
            changed = ImGui::SliderInt(info.key, &i, lo, hi, "%d",
                                       info.logarithmic ? ImGuiSliderFlags_Logarithmic : 0);
            v = i;
            break;
        }
        case Kind::Number:
            changed =
                ImGui::SliderScalar(info.key, ImGuiDataType_Double, &v, &info.lo, &info.hi, "%.4g",
                                    info.logarithmic ? ImGuiSliderFlags_Logarithmic : 0);
            break;
    }
    std::string help = info.help;
    help += info.rebuilds ? "\nChanging it rebuilds the method (when the slider is let go): its "
                            "anchors start over."
                          : "\nApplies in place, from the next frame on.";
    help += "\nCtrl+click a slider to type a value.";
    tooltip(help);
    if (changed && (!info.rebuilds || info.kind == Kind::Boolean)) {
        set(info.key, v);
    } else if (changed) {
        if (!drafted) draft_ = method_.settings();
        setSettingValue(draft_, info, v);
        drafting_ = &info;
    }
    if (drafting_ == &info && ImGui::IsItemDeactivatedAfterEdit()) {
        drafting_ = nullptr;
        set(info.key, settingValue(draft_, info));
    }
    return changed;
}

void TuningPanel::drawSettings() {
    if (!ImGui::CollapsingHeader("Settings", ImGuiTreeNodeFlags_DefaultOpen)) return;
    ImGui::SetNextItemWidth(220.0f);
    ImGui::InputText("file", &configPath_);
    tooltip("the settings file (the JSON `ambience run --config` and `view --config` read)");
    if (ImGui::Button("Save settings")) save();
    ImGui::SameLine();
    if (ImGui::Button("Load")) load();
    ImGui::SameLine();
    if (ImGui::Button("Defaults")) applyCandidate(AmbienceVolumeSettings{}, "defaults");
    if (!method_.tunable()) {
        ImGui::TextDisabled("these are the volume's settings: --ambient %s does not read them",
                            method_.name().c_str());
        return;
    }
    ImGui::TextDisabled("%d rebuilds so far; (r) rebuilds the method", method_.rebuilds());
    const char* group = "";
    bool open = false;
    for (const SettingInfo& info : tunableSettings()) {
        const std::vector<std::string> parts = splitKey(info.key);
        const char* g = parts.size() > 1 ? (parts[0] == "store"       ? "store"
                                            : parts[0] == "scheduler" ? "scheduler"
                                                                      : "nearField")
                                         : "capture and volume";
        if (std::string(g) != group) {
            if (open) ImGui::TreePop();
            group = g;
            open = ImGui::TreeNode(g);
        }
        if (!open) continue;
        if (info.rebuilds) {
            ImGui::TextDisabled("(r)");
            ImGui::SameLine();
        }
        ImGui::SetNextItemWidth(140.0f);
        settingWidget(info);
    }
    if (open) ImGui::TreePop();
}

}  // namespace amb
