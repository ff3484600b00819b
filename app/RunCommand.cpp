// RunCommand.cpp — `ambience run`: render a replay headless to frames, a video and a report.
//
// Steps: (1) read the replay, check the options; (2) an offscreen platform (auto: EGL, then
// OSMesa) and the renderer; (3) the frame loop, writing every K-th frame as PNG and every frame
// to ffmpeg through a pipe; (4) the report: JSON with per-stage timing statistics and per-frame
// rows, and a CSV of the rows beside it.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "app/Commands.h"
#include "app/FrameLoop.h"
#include "app/Gl.h"
#include "app/Platform.h"
#include "app/RunReport.h"
#include "app/VolumeAmbience.h"
#include "app/CubeCaptureGl.h"
#include "app/DebugOverlay.h"
#include "world/Error.h"
#include "world/World.h"

namespace amb {

namespace {

namespace fs = std::filesystem;

struct RunOptions {
    std::string replay;
    std::string backend = "auto";
    std::string shaders;
    std::string size = "640x360";
    std::string frames;
    int every = 10;
    std::string video;
    std::string report;
    int maxFrames = 0;
    int stride = 2;
    std::string ambient = "volume";
    std::string ambienceConfig, saveAnchors, loadAnchors;
    int facesPerFrame = 1;
    bool debugOverlay = false;
    bool noVehicle = false;
    int faceSize = 16;
    std::string out;
    bool noVideo = false;
};

std::string defaultReplayPath() {
    // Beside the executable's tree (<exe>/../../replays) or the current directory.
    char exe[4096] = {};
    const ssize_t n = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
    if (n > 0) {
        const fs::path p = fs::path(std::string(exe, size_t(n))).parent_path();
        for (const fs::path& c :
             {p / "../../replays/highway-drive.json", p / "../replays/highway-drive.json"}) {
            if (fs::exists(c)) return fs::weakly_canonical(c).string();
        }
    }
    return "replays/highway-drive.json";
}

void ensureDirectory(const std::string& dir, const std::string& option) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir) || access(dir.c_str(), W_OK) != 0) {
        throw InputError(option, "cannot create or write the folder '" + dir + "'");
    }
}

void runReplay(RunOptions o) {
    // (1) inputs
    if (o.replay.empty()) o.replay = defaultReplayPath();
    const Replay replay = readReplay(o.replay);
    const Backend backend = parseBackend(o.backend, "--backend");
    if (backend == Backend::Glfw)
        throw InputError("--backend", "run is headless: auto, egl or osmesa");
    // "volume" is the dynamic ambience volume; the fixed modes are the baselines.
    const bool useVolume = o.ambient == "volume";
    const AmbientMode ambientMode =
        useVolume ? AmbientMode::Hemisphere : parseAmbientMode(o.ambient, "--ambient");
    AmbienceVolumeSettings volumeSettings;
    if (!o.ambienceConfig.empty()) {
        std::ifstream in(o.ambienceConfig);
        if (!in) throw InputError(o.ambienceConfig, "cannot open the ambience settings file");
        std::ostringstream text;
        text << in.rdbuf();
        volumeSettings = ambienceSettingsFromJson(text.str(), o.ambienceConfig);
    }
    if (o.facesPerFrame < 1 || o.facesPerFrame > 6)
        throw InputError("--faces-per-frame", "expected 1 to 6");
    volumeSettings.facesPerFrame = o.facesPerFrame;
    if (o.faceSize < 1 || o.faceSize > 256) throw InputError("--face-size", "expected 1 to 256");
    if (!useVolume && o.debugOverlay) throw InputError("--debug-overlay", "needs --ambient volume");
    if (!useVolume && (!o.saveAnchors.empty() || !o.loadAnchors.empty()))
        throw InputError("--save-anchors/--load-anchors", "need --ambient volume");
    const Size size = parseSize(o.size, "--size");
    if (o.every < 1) throw InputError("--every", "must be at least 1");
    if (o.stride < 1) throw InputError("--stride", "must be at least 1");
    if (o.maxFrames < 0) throw InputError("--max-frames", "must be >= 0");
    const std::string name = replay.name.empty() ? fs::path(o.replay).stem().string() : replay.name;
    if (o.out.empty()) o.out = "out/run-" + name;
    ensureDirectory(o.out, "--out");
    if (o.frames.empty()) o.frames = o.out + "/frames";
    if (o.frames != "none") ensureDirectory(o.frames, "--frames");
    if (o.video.empty() && !o.noVideo) o.video = o.out + "/" + name + ".mp4";
    if (o.report.empty()) o.report = o.out + "/report.json";

    // (2) platform and renderer
    auto platform = createOffscreenPlatform(backend, size.width, size.height);
    const World world(replay.world);
    RenderSettings rs;
    rs.width = size.width;
    rs.height = size.height;
    rs.drawVehicle = replay.mode == ReplayMode::Drive && !o.noVehicle;
    Renderer renderer(world, rs);
    std::unique_ptr<AmbienceStages> ambience;
    VolumeAmbienceStages* volume = nullptr;
    if (useVolume) {
        auto v = std::make_unique<VolumeAmbienceStages>(renderer, volumeSettings, o.faceSize);
        volume = v.get();
        if (!o.loadAnchors.empty()) volume->volume().loadAnchors(o.loadAnchors);
        ambience = std::move(v);
    } else {
        ambience = std::make_unique<FixedAmbienceStages>(ambientMode);
    }
    FrameLoop loop(replay, renderer, *ambience, o.stride);
    const int frames =
        o.maxFrames > 0 ? std::min(o.maxFrames, loop.frameCount()) : loop.frameCount();

    RunReport report;
    report.replay = o.replay;
    report.backend = toString(platform->backend());
    report.glVersion = platform->glVersion();
    report.glRenderer = platform->glRenderer();
    report.width = size.width;
    report.height = size.height;
    report.ambient = useVolume ? "volume" : toString(ambientMode);
    report.frameStep_s = loop.frameStep_s();

    std::unique_ptr<VideoPipe> video;
    if (!o.video.empty()) {
        video =
            std::make_unique<VideoPipe>(o.video, size.width, size.height, 1.0 / loop.frameStep_s());
    }
    std::fprintf(stderr, "run: %s, %d frames at %dx%d on %s (%s)\n", name.c_str(), frames,
                 size.width, size.height, report.backend.c_str(), report.glRenderer.c_str());

    // (3) frames
    ProgressBar progress(frames);
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < frames; ++i) {
        FrameRecord rec = loop.step();
        if (volume) {
            const AmbienceStatistics& st = volume->volume().statistics();
            rec.ambience.active = true;
            rec.ambience.anchors = st.store.anchors;
            rec.ambience.bytes = st.store.bytes();
            rec.ambience.faces = st.facesThisFrame;
            rec.ambience.finestLevel = st.finestLevel;
            rec.ambience.lookups = volume->ambient().lookups();
            rec.ambience.lookupMs = volume->ambient().lookupMs();
            rec.ambience.captureMs = st.capture_s * 1e3;
            rec.ambience.predictMs = st.predict_s * 1e3;
            rec.ambience.projectMs = st.project_s * 1e3;
            rec.ambience.storeMs = st.store_s * 1e3;
            const int levels = volume->volume().store().levels();
            rec.ambience.anchorsPerLevel.assign(st.store.anchorsPerLevel.begin(),
                                                st.store.anchorsPerLevel.begin() + levels);
        }
        const bool writeFrame = o.frames != "none" && rec.index % o.every == 0;
        if (writeFrame || video) {
            auto pixels = renderer.readRgb8();
            if (o.debugOverlay && volume) {
                const CameraSample camera = replay.sampleAt(rec.time_s);
                drawAnchorOverlay(pixels, size.width, size.height,
                                  renderer.viewProjection(camera), camera.position_m,
                                  volume->volume());
            }
            if (writeFrame) {
                char file[64];
                std::snprintf(file, sizeof(file), "/frame-%05d.png", rec.index);
                writeImageRgb8(o.frames + file, size.width, size.height, pixels);
            }
            if (video) video->write(pixels);
        }
        report.frames.push_back(rec);
        progress.update(i + 1, rec.frameMs);
    }
    progress.finish();
    report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (video) video->close();
    if (volume) {
        const AmbienceStatistics& st = volume->volume().statistics();
        auto& t = report.ambienceTotals;
        t.facesCaptured = st.facesCaptured;
        t.probesCompleted = st.probesCompleted;
        t.rejectedProbes = st.rejectedProbes;
        t.teleports = st.teleports;
        t.inserted = st.store.inserted;
        t.refreshed = st.store.refreshed;
        t.expired = st.store.expired;
        t.captureTriangles = volume->cubeCapture().lastStats().triangles;
        if (!o.saveAnchors.empty()) volume->volume().saveAnchors(o.saveAnchors);
    }

    // (4) report
    report.write(o.report);
    const auto summary = report.summary();
    std::printf("rendered %d frames of %s at %dx%d on %s (%s)\n", frames, name.c_str(), size.width,
                size.height, report.backend.c_str(), report.glRenderer.c_str());
    std::printf("frame time median %.1f ms (%.1f fps), p95 %.1f ms; triangles median %.0f\n",
                summary.frameMedianMs, 1000.0 / summary.frameMedianMs, summary.frameP95Ms,
                summary.trianglesMedian);
    if (volume) {
        const AmbienceStatistics& st = volume->volume().statistics();
        std::printf("ambience: %zu anchors, %.1f kB (%.0f B/anchor), %lld faces captured, "
                    "%lld probes (%lld rejected)\n",
                    st.store.anchors, st.store.bytes() / 1024.0,
                    st.store.anchors ? double(st.store.bytes()) / double(st.store.anchors) : 0.0,
                    (long long)st.facesCaptured, (long long)st.probesCompleted,
                    (long long)st.rejectedProbes);
        if (!o.saveAnchors.empty()) std::printf("  anchors saved: %s\n", o.saveAnchors.c_str());
    }
    std::printf("output: %s\n", fs::weakly_canonical(o.out).string().c_str());
    if (o.frames != "none") std::printf("  frames: %s (every %d)\n", o.frames.c_str(), o.every);
    if (video) std::printf("  video:  %s\n", o.video.c_str());
    std::printf("  report: %s (+ .csv)\n", o.report.c_str());
}

}  // namespace

void addRunCommand(CLI::App& app) {
    auto* cmd =
        app.add_subcommand("run", "render a replay headless to frames, a video and a report");
    auto o = std::make_shared<RunOptions>();
    cmd->add_option("--replay", o->replay, "replay file (default replays/highway-drive.json)");
    cmd->add_option("--backend", o->backend,
                    "auto, egl or osmesa (default auto: EGL, then OSMesa)");
    cmd->add_option("--size", o->size, "image size WxH (default 640x360)");
    cmd->add_option("--out", o->out, "output folder (default out/run-<replay name>)");
    cmd->add_option("--frames", o->frames,
                    "folder for PNG frames, or 'none' (default <out>/frames)");
    cmd->add_option("--every", o->every, "write every K-th frame as PNG (default 10)");
    cmd->add_option("--video", o->video, "video file, through ffmpeg (default <out>/<name>.mp4)");
    cmd->add_flag("--no-video", o->noVideo, "do not write a video");
    cmd->add_option("--report", o->report, "report JSON (default <out>/report.json)");
    cmd->add_option("--max-frames", o->maxFrames, "stop after N frames (default: whole replay)");
    cmd->add_option("--stride", o->stride,
                    "replay steps per frame (default 2: 30 frames/s of a 60 Hz replay)");
    cmd->add_option("--ambient", o->ambient,
                    "volume (the dynamic ambience volume), constant or hemisphere (default volume)");
    cmd->add_option("--config,--ambience-config", o->ambienceConfig,
                    "JSON file of ambience volume settings (AmbienceVolumeSettings fields, "
                    "lighting/AmbienceVolume.h)");
    cmd->add_option("--faces-per-frame", o->facesPerFrame,
                    "capture budget: cube faces per frame (default 1, as in the thesis)");
    cmd->add_option("--face-size", o->faceSize, "capture face size N (default 16)");
    cmd->add_option("--save-anchors", o->saveAnchors, "write the anchor store at the end (.vdb)");
    cmd->add_option("--load-anchors", o->loadAnchors, "warm-start from an anchor store (.vdb)");
    cmd->add_flag("--no-vehicle", o->noVehicle, "do not draw the car on drive replays");
    cmd->add_flag("--debug-overlay", o->debugOverlay,
                  "draw anchors (colour = level, darker = older) and the probe being captured "
                  "over frames and video");
    cmd->add_option("--shaders", o->shaders,
                    "GLSL folder (default <exe>/../shaders or $AMBIENCE_SHADER_DIR)");
    cmd->callback([o] {
        if (!o->shaders.empty()) setShaderDirectory(o->shaders);
        runReplay(*o);
    });
}

}  // namespace amb
