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
#include <utility>

#include <imgui.h>
#include <imgui_stdlib.h>

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

// The rows are the volume's keys as the settings schema has them (lighting/SettingsSchema.h).

namespace {

using Kind = SettingInfo::Kind;

}  // namespace

const std::vector<SettingInfo>& tunableSettings() {
    return volumeSettingsSchema().fields();
}

const SettingInfo* findSetting(const std::string& key) {
    return volumeSettingsSchema().find(key);
}

double settingValue(const AmbienceVolumeSettings& settings, const SettingInfo& info) {
    return SettingsSchema<AmbienceVolumeSettings>::value(settings, info);
}

void setSettingValue(AmbienceVolumeSettings& settings, const SettingInfo& info, double value) {
    SettingsSchema<AmbienceVolumeSettings>::setValue(settings, info, value);
}

std::string settingsToJson(const AmbienceVolumeSettings& settings) {
    return volumeSettingsSchema().write(settings);
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
    renderer_ = std::make_unique<PanelRenderer>(window_);
}

TuningPanel::~TuningPanel() {
    renderer_.reset();
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
            changed = ImGui::Checkbox(info.key.c_str(), &b);
            v = b ? 1.0 : 0.0;
            break;
        }
        case Kind::Integer: {
            int i = int(v), lo = int(info.lo), hi = int(info.hi);
            changed = ImGui::SliderInt(info.key.c_str(), &i, lo, hi, "%d",
                                       info.logarithmic ? ImGuiSliderFlags_Logarithmic : 0);
            v = i;
            break;
        }
        case Kind::Number:
            changed =
                ImGui::SliderScalar(info.key.c_str(), ImGuiDataType_Double, &v, &info.lo, &info.hi, "%.4g",
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
    std::string group;
    bool open = false;
    for (const SettingInfo& info : tunableSettings()) {
        // The groups of the file: the objects ("store", "scheduler", "nearField"), and the
        // keys at its top level.
        const std::size_t dot = info.key.find('.');
        const std::string g =
            dot == std::string::npos ? "capture and volume" : info.key.substr(0, dot);
        if (g != group) {
            if (open) ImGui::TreePop();
            group = g;
            open = ImGui::TreeNode(g.c_str());
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
