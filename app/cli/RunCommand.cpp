// RunCommand.cpp — `ambience run`: render a replay headless to frames, a video and a report.
//
// Steps: (1) read the replay, check the options; (2) an offscreen platform (auto: EGL, then
// OSMesa) and the renderer; (3) the frame loop, writing every K-th frame as PNG and every frame
// to ffmpeg through a pipe; (4) the report: JSON with per-stage timing statistics and per-frame
// rows, and a CSV of the rows beside it.
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "SourceHash.h"  // generated: AMBIENCE_SOURCE_HASH
#include "app/cli/Commands.h"
#include "app/cli/ContactSheet.h"
#include "app/render/CubeCaptureGl.h"
#include "app/render/DebugOverlay.h"
#include "app/frame/FrameLoop.h"
#include "app/render/ShaderDirectory.h"
#include "app/platform/Platform.h"
#include "app/cli/OutputPaths.h"
#include "app/cli/ReferenceLightFlags.h"
#include "app/render/Renderer.h"
#include "app/cli/RunReport.h"
#include "app/cli/SettingsFlags.h"
#include "app/frame/MethodStages.h"
#include "lighting/Baselines.h"
#include "lighting/BounceField.h"
#include "lighting/Metrics.h"
#include "world/DataPaths.h"
#include "world/Error.h"
#include "world/JsonText.h"
#include "world/TextFile.h"
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
    double share = 1.0;  // play the first share of the frames (not part of the oracle's signature)
    int stride = 2;
    std::string ambient = "volume";
    std::string ambienceConfig, saveAnchors, loadAnchors;
    int facesPerFrame = 1;
    bool facesPerFrameGiven = false;  // --faces-per-frame was on the command line
    std::vector<std::string> settingAssignments;  // --set KEY=VALUE
    bool debugOverlay = false;
    bool noVehicle = false;
    std::string camera = "chase";     // drive replays: chase or hood (--camera)
    std::string exposure = "auto";    // auto (eye adaptation) or fixed (--exposure)
    std::string view = "shaded";
    std::string shadows = "on";
    int shadowCascades = ShadowSettings{}.cascades, shadowSize = ShadowSettings{}.mapSize,
        shadowPcf = ShadowSettings{}.pcf;
    double shadowFar_m = ShadowSettings{}.farDistance_m;
    bool passTiming = false;  // --pass-timing
    std::string contactSheet;  // empty: <out>/contact-sheet.png; "none": none
    int sheetCells = 12;
    int faceSize = 16;
    std::string out;
    bool noVideo = false;
    std::string baselineConfig;
    bool noFrames = false;
    int measureEvery = 0;
    std::string oracle;
    std::string oracleKind = "self";
    std::string reference;
    bool replaceStale = false;  // --replace-stale-caches
    ReferenceSettings referenceSettings;
    bool referenceOn = false;
    bool noIdealVolume = false;
    int screenWitnesses = 0;
    int loops = 1;
    // What lights the reference's surfaces (lighting/BounceField.h): its own bounce field over
    // a lattice of spacing_m within reach_m of the path (run's default: 128 m within 600 m).
    std::string referenceLight = "bounce";
    BounceSettings bounce = runBounceSettings();
    // What lights the surfaces of the method's captures: own (its settings: the hemisphere, or
    // its field with ownLight) or reference (the reference's bounce field: a diagnostic).
    std::string captureLight = "own";
};

// Passes over the replay for --loop, and a bound on the run's length: the report keeps a row
// per frame (a few hundred bytes), so 10^7 frames (92 h at 30 frames/s) is as far as it goes.
constexpr int kMaxLoops = 10000;
constexpr long kMaxRunFrames = 10'000'000;

std::string readSettingsFile(const std::string& path, const char* what) {
    return readTextFile(path, what, kMaxSettingsFileBytes);
}

// Screen witnesses (lighting/Metrics.h): the main view rendered twice more, as the ambient
// irradiance the draw applies and as the world normal, and `count` random surface pixels of it
// (the same pixels for every method: the generator is seeded by the frame) handed to the meter.
void takeScreenWitnesses(Renderer& renderer, const CameraSample& camera,
                         const AmbientSource& ambient, int count, int frameIndex,
                         double timeOfDay_h, ErrorMeter& meter) {
    renderer.render(camera, ambient, RenderOutput::AmbientIrradiance);
    const SurfaceImage applied = renderer.readSurface(camera);
    renderer.render(camera, ambient, RenderOutput::Normal);
    const SurfaceImage normals = renderer.readSurface(camera);
    std::mt19937_64 rng(0x5C4EE7ull ^ std::uint64_t(frameIndex));
    std::uniform_int_distribution<std::size_t> pick(0, applied.position.size() - 1);
    std::vector<ScreenWitness> pixels;
    for (int tries = 0; tries < 100 * count && int(pixels.size()) < count; ++tries) {
        const std::size_t p = pick(rng);
        const int kind = int(std::lround(applied.rgba[4 * p + 3]));
        // Sky, and plants drawn with a proxy or far mesh (the reference sees the real plant,
        // somewhere inside that stand-in) are no witnesses.
        if (kind < 1 || kind > kSurfaceKinds || !(normals.rgba[4 * p + 3] > 0.5f)) continue;
        ScreenWitness w;
        w.kind = SurfaceKind(kind);
        w.position_m = camera.position_m + glm::dvec3(applied.position[p]);
        // Terrain far away is drawn with coarse patches; the reference stands on the terrain
        // itself (its own mesh is finest at the probe).
        if (w.kind == SurfaceKind::Terrain)
            w.position_m.y = renderer.world().height(w.position_m.x, w.position_m.z);
        w.normal = glm::dvec3(normals.rgba[4 * p], normals.rgba[4 * p + 1], normals.rgba[4 * p + 2]);
        if (!(glm::length(w.normal) > 0.5)) continue;
        w.applied = glm::dvec3(applied.rgba[4 * p], applied.rgba[4 * p + 1], applied.rgba[4 * p + 2]);
        pixels.push_back(w);
    }
    meter.screenFrame(frameIndex, timeOfDay_h, pixels);
}

// Anchors holding a NaN or an infinity anywhere in what interpolation and blending read. The
// store refuses such captures on insert; this checks that none got in another way.
std::size_t nonFiniteAnchors(const AnchorStore& store) {
    std::size_t bad = 0;
    auto finite = [](const glm::dvec3& v) {
        return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
    };
    store.forEach([&](const Anchor& a) {
        bool ok = std::isfinite(a.presence) && std::isfinite(a.relight) &&
                  std::isfinite(a.blendProgress) && finite(a.capturedPosition_m);
        for (const ShRgb* sh : {&a.current, &a.target, &a.blendFrom})
            for (const glm::vec3& c : sh->c) ok = ok && finite(glm::dvec3(c));
        bad += ok ? 0 : 1;
    });
    return bad;
}

void checkLoops(const Replay& replay, const RunOptions& o) {
    if (o.loops < 1 || o.loops > kMaxLoops)
        throw InputError("--loop", "expected 1 to " + std::to_string(kMaxLoops) + " passes");
    long runFrames = long(FrameLoop::framesPerPass(replay, o.stride)) * o.loops;
    if (o.maxFrames > 0) runFrames = std::min(runFrames, long(o.maxFrames));
    if (runFrames > kMaxRunFrames) {
        throw InputError("--loop", std::to_string(o.loops) + " passes would be " +
                                       std::to_string(runFrames) + " frames (at most " +
                                       std::to_string(kMaxRunFrames) +
                                       "): fewer passes, a larger --stride or --max-frames");
    }
}

// The store's finiteness and the process's resident memory over the run.
void printSoakSummary(const RunReport& report, bool scanned) {
    if (scanned) {
        const auto& t = report.ambienceTotals;
        std::printf("  store finite: %s (%lld scans, at most %zu non-finite anchors)\n",
                    t.nonFiniteAnchorsMax == 0 ? "yes" : "NO", (long long)t.storeScans,
                    t.nonFiniteAnchorsMax);
    }
    if (report.frames.empty()) return;
    std::size_t rssMax = 0;
    for (const FrameRecord& f : report.frames) rssMax = std::max(rssMax, f.rss_kB);
    std::printf("memory: resident %.1f MB at the first frame, %.1f MB at the last, %.1f MB max "
                "(peak %.1f MB); %d pass(es) over the replay\n",
                report.frames.front().rss_kB / 1024.0, report.frames.back().rss_kB / 1024.0,
                rssMax / 1024.0, report.rssPeak_kB / 1024.0, report.loops);
}

std::string defaultReplayPath() {
    const std::string dir = shippedReplayDir();
    return (dir.empty() ? std::string("replays") : dir) + "/highway-drive.json";
}

void ensureDirectory(const std::string& dir, const std::string& option) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec || !fs::is_directory(dir) || access(dir.c_str(), W_OK) != 0) {
        throw InputError(option, "cannot create or write the folder '" + dir + "'");
    }
}

// What the checks of a run's options settle before any work.
struct RunPlan {
    Replay replay;
    Backend backend = Backend::Auto;
    AmbienceVolumeSettings volumeSettings;
    BaselineSettings baselines;
    OracleKind oracleKind = OracleKind::Self;
    Size size;
    std::string name;  // the replay's label
    RenderOutput view = RenderOutput::Shaded;
    CarView carView = CarView::None;  // the car on drive replays (--camera, --no-vehicle)
    bool autoExposure = true;
    ShadowSettings shadows;  // --shadows: the main view's, the captures' and the reference's
    ReferenceLight referenceLight = ReferenceLight::Bounce;  // --reference-light
};

// Stage (1) of a run: reads the replay and the settings files, checks every option, completes
// the output paths in `o` and checks them (no output may overwrite an input or another output).
// Throws InputError.
RunPlan planRun(RunOptions& o) {
    if (o.replay.empty()) o.replay = defaultReplayPath();
    RunPlan plan;
    plan.replay = readReplay(o.replay);
    const Replay& replay = plan.replay;
    plan.backend = parseBackend(o.backend, "--backend");
    if (plan.backend == Backend::Glfw)
        throw InputError("--backend", "run is headless: auto, egl or osmesa");
    // "volume" is the dynamic ambience volume; the others are the baselines (app/frame/MethodStages.h).
    checkAmbienceMethod(o.ambient, "--ambient");
    plan.view = parseViewOutput(o.view, "--view");
    plan.carView = parseCarView(o.camera, "--camera");
    if (replay.mode != ReplayMode::Drive || o.noVehicle) plan.carView = CarView::None;
    plan.autoExposure = parseExposure(o.exposure, "--exposure");
    plan.shadows.enabled = plan.shadows.captures = parseShadowSwitch(o.shadows, "--shadows");
    plan.shadows.cascades = o.shadowCascades;
    plan.shadows.mapSize = o.shadowSize;
    plan.shadows.pcf = o.shadowPcf;
    plan.shadows.farDistance_m = o.shadowFar_m;
    checkShadowSettings(plan.shadows,
                        "--shadow-cascades/--shadow-size/--shadow-pcf/--shadow-far");
    const bool useVolume = o.ambient == "volume";
    AmbienceVolumeSettings& volumeSettings = plan.volumeSettings;
    if (!o.ambienceConfig.empty()) {
        volumeSettings = ambienceSettingsFromJson(
            readSettingsFile(o.ambienceConfig, "ambience settings file"), o.ambienceConfig);
    }
    BaselineSettings& baselines = plan.baselines;
    if (!o.baselineConfig.empty()) {
        baselines = baselineSettingsFromJson(
            readSettingsFile(o.baselineConfig, "baseline settings file"), o.baselineConfig);
    }
    // The command line over the files, and only what it names: a budget given sets every
    // method's; none given leaves each file's.
    if (o.facesPerFrameGiven) {
        if (o.facesPerFrame < 1 || o.facesPerFrame > kMaxFacesPerFrame)
            throw InputError("--faces-per-frame",
                             "expected 1 to " + std::to_string(kMaxFacesPerFrame));
        volumeSettings.capture.facesPerFrame = baselines.capture.facesPerFrame = o.facesPerFrame;
    }
    applySettingAssignments(o.settingAssignments, volumeSettings, &baselines);
    checkLoops(replay, o);
    if (o.measureEvery < 0) throw InputError("--measure-every", "must be >= 0");
    if (!o.oracle.empty() && o.measureEvery == 0)
        throw InputError("--oracle", "needs --measure-every K");
    plan.oracleKind = parseOracleKind(o.oracleKind, "--oracle-kind");
    o.referenceOn = plan.oracleKind == OracleKind::Reference || !o.reference.empty();
    if (o.referenceOn && o.measureEvery == 0)
        throw InputError(o.reference.empty() ? "--oracle-kind" : "--reference",
                         "needs --measure-every K");
    o.referenceSettings.idealVolume = !o.noIdealVolume;
    plan.referenceLight = parseReferenceLight(o.referenceLight, "--reference-light");
    checkBounceSettings(o.bounce);
    if (!isCaptureLight(o.captureLight))
        throw InputError("--capture-light", "expected own or reference");
    if (o.captureLight == "reference" &&
        (!o.referenceOn || plan.referenceLight != ReferenceLight::Bounce))
        throw InputError("--capture-light",
                         "reference needs the reference lit by its bounce field (--oracle-kind "
                         "reference or --reference, with --reference-light bounce)");
    if (o.referenceSettings.every < 1 || o.referenceSettings.every > 1000000)
        throw InputError("--reference-every", "expected 1 to 1000000");
    if (o.referenceSettings.faceSize < 1 || o.referenceSettings.faceSize > 256)
        throw InputError("--reference-size", "expected 1 to 256");
    if (o.screenWitnesses < 0 || o.screenWitnesses > 4096)
        throw InputError("--screen-witnesses", "expected 0 to 4096");
    if (o.screenWitnesses > 0 && !o.referenceOn)
        throw InputError("--screen-witnesses", "needs the reference (--oracle-kind reference)");
    if (o.referenceSettings.objectTrees < 0 || o.referenceSettings.objectTrees > 64)
        throw InputError("--reference-trees", "expected 0 to 64");
    if (o.noFrames) {
        if (!o.video.empty()) throw InputError("--video", "--no-frames draws no main view");
        o.frames = "none";
        o.noVideo = true;
        o.contactSheet = "none";
    }
    if (o.sheetCells < 1 || o.sheetCells > 400) throw InputError("--sheet-cells", "expected 1 to 400");
    if (o.faceSize < 1 || o.faceSize > 256) throw InputError("--face-size", "expected 1 to 256");
    if (!useVolume && o.debugOverlay) throw InputError("--debug-overlay", "needs --ambient volume");
    if (!useVolume && (!o.saveAnchors.empty() || !o.loadAnchors.empty()))
        throw InputError("--save-anchors/--load-anchors", "need --ambient volume");
    plan.size = parseSize(o.size, "--size");
    if (o.every < 1) throw InputError("--every", "must be at least 1");
    if (o.stride < 1) throw InputError("--stride", "must be at least 1");
    if (o.maxFrames < 0) throw InputError("--max-frames", "must be >= 0");
    if (!(o.share > 0.0 && o.share <= 1.0)) throw InputError("--share", "expected (0, 1]");
    // The replay's name is only a label: as a file name it is reduced to a safe stem, so a
    // replay cannot make a run write outside its output folder.
    plan.name = replay.name.empty() ? fs::path(o.replay).stem().string() : replay.name;
    const std::string stem = safeFileStem(plan.name);
    if (o.out.empty()) o.out = "out/run-" + stem;
    ensureDirectory(o.out, "--out");
    if (o.frames.empty()) o.frames = o.out + "/frames";
    if (o.frames != "none") ensureDirectory(o.frames, "--frames");
    if (o.video.empty() && !o.noVideo) o.video = o.out + "/" + stem + ".mp4";
    if (o.report.empty()) o.report = o.out + "/report.json";
    if (o.contactSheet.empty()) o.contactSheet = o.out + "/contact-sheet.png";
    {
        // Before any work: no output may overwrite an input or another output, and every
        // output must be writable.
        FilePlan files;
        files.input("--replay", o.replay);
        files.input("--config", o.ambienceConfig);
        files.input("--baseline-config", o.baselineConfig);
        files.input("--load-anchors", o.loadAnchors);
        files.output("--report", o.report);
        files.output("--report (CSV)", fs::path(o.report).replace_extension(".csv").string());
        if (o.measureEvery > 0)
            files.output("--report (measure.csv)",
                         (fs::path(o.report).parent_path() / "measure.csv").string());
        files.output("--video", o.video);
        if (o.contactSheet != "none") files.output("--contact-sheet", o.contactSheet);
        files.output("--save-anchors", o.saveAnchors);
        files.output("--oracle", o.oracle);
        files.output("--reference", o.reference);
        if (o.referenceOn)
            files.output("--report (reference.csv)",
                         (fs::path(o.report).parent_path() / "reference.csv").string());
        if (o.referenceOn && o.screenWitnesses > 0)
            files.output("--report (screen.csv)",
                         (fs::path(o.report).parent_path() / "screen.csv").string());
        files.check();
    }

    return plan;
}

// A run's error measurement: the meter, the reference oracle's capture and the signatures its
// caches are kept under.
struct RunMeasurement {
    std::unique_ptr<ErrorMeter> meter;
    std::unique_ptr<CubeCaptureGl> referenceCapture;
    // With --reference-light bounce: the lattice's captures and the reference lit by its field.
    std::unique_ptr<CubeCaptureGl> latticeCapture;
    std::unique_ptr<BounceLitCapture> bounceLit;
    std::string oracleSignature, referenceSignature;
};

// FNV-1a over the replay file's bytes, as 16 hex digits.
std::string replayHash(const std::string& path) {
    std::uint64_t h = 1469598103934665603ull;
    for (const char c : readTextFile(path, "replay file", kMaxReplayFileBytes)) {
        h ^= std::uint64_t(static_cast<unsigned char>(c));
        h *= 1099511628211ull;
    }
    char text[24];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
    return text;
}

// True when the cache at `path` is a well-formed cache of another signature (another replay,
// code or settings): with --replace-stale-caches it is captured anew and replaced, not read.
// Anything else (not JSON, no signature) is left to the loader, which names what is wrong.
bool staleCache(const std::string& path, const std::string& signature) {
    try {
        const nlohmann::json j =
            parseJsonText(readTextFile(path, "cache file", kMaxOracleFileBytes), path);
        return j.is_object() && j.contains("signature") && j["signature"].is_string() &&
               j["signature"].get<std::string>() != signature;
    } catch (const std::exception&) {
        return false;
    }
}

// The ground points (x, z) of the frames a run plays: where the reference's bounce lattice is
// laid (lighting/BounceField.h). Every stride-th sample up to the run's last frame.
std::vector<glm::dvec2> runPath(const Replay& replay, const RunOptions& o) {
    std::vector<glm::dvec2> path;
    const std::size_t n = replay.samples.size();
    std::size_t last = n;
    if (o.maxFrames > 0) last = std::min(n, std::size_t(o.maxFrames) * std::size_t(o.stride));
    for (std::size_t i = 0; i < last; i += std::size_t(o.stride))
        path.emplace_back(replay.samples[i].position_m.x, replay.samples[i].position_m.z);
    return path;
}

// The meter for --measure-every (none without it), its caches loaded, attached to `stages`.
RunMeasurement startMeasurement(const RunOptions& o, const RunPlan& plan, const World& world,
                                MethodAmbienceStages& stages) {
    RunMeasurement m;
    // The error measurement: the oracle's captures use the same capture as the method.
    MeasureSettings measureSettings;
    measureSettings.every = o.measureEvery;
    // The oracle depends on the replay (its world and path: the file's bytes), the frames
    // measured, the capture settings and the code that captures and projects (the sources'
    // hash, cmake/SourceHash.cmake): a cache made by other code or of another world is stale.
    // The sun's texel is left out by its direction ("sun=texel").
    m.oracleSignature =
        fs::path(o.replay).filename().string() + " replay=" + replayHash(o.replay) +
        " code=" + AMBIENCE_SOURCE_HASH + " stride=" + std::to_string(o.stride) +
        " every=" + std::to_string(o.measureEvery) + " face=" + std::to_string(o.faceSize) +
        " sun=texel frames=" + std::to_string(o.maxFrames) +
        " shadows=" + describeShadows(plan.shadows) +
        (o.loops > 1 ? " loops=" + std::to_string(o.loops) : std::string());
    if (o.measureEvery > 0) {
        m.meter = std::make_unique<ErrorMeter>(stages.cubeCapture(), stages.environment(),
                                               measureSettings);
        if (!o.oracle.empty() && fs::exists(o.oracle) &&
            !(o.replaceStale && staleCache(o.oracle, m.oracleSignature)))
            m.meter->loadOracle(o.oracle, m.oracleSignature);
    }
    // The reference oracle: the full scene at 64 x 64 (lighting/ReferenceOracle.h).
    const ReferenceSettings& ref = o.referenceSettings;
    m.referenceSignature =
        m.oracleSignature + " reference: face=" + std::to_string(ref.faceSize) +
        " scene=full rule=" + std::to_string(ref.legendreNodes) +
        " every=" + std::to_string(ref.every) + " trees=" + std::to_string(ref.objectTrees) +
        " light=" + toString(plan.referenceLight) +
        (plan.referenceLight == ReferenceLight::Bounce ? " " + describeBounceSettings(o.bounce)
                                                       : std::string());
    if (m.meter && o.referenceOn) {
        m.referenceCapture =
            std::make_unique<CubeCaptureGl>(world, ref.faceSize, CaptureScene::Full, plan.shadows);
        CubeCapture* referenceCapture = m.referenceCapture.get();
        if (plan.referenceLight == ReferenceLight::Bounce) {
            // The lattice around the frames this run plays; solved on the first reference
            // capture (none when the cache holds every reference).
            m.latticeCapture = std::make_unique<CubeCaptureGl>(world, o.bounce.faceSize,
                                                               CaptureScene::Full, plan.shadows);
            m.bounceLit = std::make_unique<BounceLitCapture>(
                *m.referenceCapture, *m.latticeCapture, o.bounce, runPath(plan.replay, o),
                bounceLatticePlacement(world), plan.replay.timeOfDayStart_h);
            referenceCapture = m.bounceLit.get();
            // --capture-light reference: the method's captures lit by the same field, of the
            // epoch holding each capture's time of day (solved when first asked).
            if (o.captureLight == "reference")
                stages.method().overrideCaptureLight(
                    [field = m.bounceLit.get()](double timeOfDay_h) -> const SurfaceLight* {
                        return &field->field(timeOfDay_h);
                    });
        }
        m.meter->attachReference(*referenceCapture, ref,
                                 plan.oracleKind == OracleKind::Reference);
        if (!o.reference.empty() && fs::exists(o.reference) &&
            !(o.replaceStale && staleCache(o.reference, m.referenceSignature)))
            m.meter->loadReference(o.reference, m.referenceSignature);
    }
    if (m.meter) stages.attachMeter(m.meter.get());
    return m;
}

// The run's totals from the method (and the volume's store), after the last frame; the
// anchors saved with --save-anchors.
void addAmbienceTotals(const RunOptions& o, MethodAmbienceStages& stages, RunReport& report) {
    AmbienceVolume* volume = stages.volume();
    {
        const MethodStatistics st = stages.method().methodStatistics();
        auto& t = report.ambienceTotals;
        t.facesCaptured = st.facesCaptured;
        t.primeFaces = st.primeFaces;
        t.rejectedProbes = st.rejectedProbes;
        t.teleports = st.teleports;
        t.captureTriangles = stages.cubeCapture().lastTriangles();
        if (const auto* gl = dynamic_cast<const CubeCaptureGl*>(&stages.cubeCapture())) {
            t.captureShadowRenders = gl->shadowStats().renders;
            t.captureShadowRender_ms = gl->shadowStats().render_ms;
            t.captureShadowTriangles = gl->shadowStats().triangles;
        }
    }
    if (volume) {
        const AmbienceStatistics& st = volume->statistics();
        auto& t = report.ambienceTotals;
        t.facesCaptured = st.facesCaptured;
        t.primeFaces = st.primeFaces;
        t.probesCompleted = st.probesCompleted;
        t.rejectedProbes = st.rejectedProbes;
        t.teleports = st.teleports;
        t.inserted = st.store.inserted;
        t.refreshed = st.store.refreshed;
        t.expired = st.store.expired;
        if (!o.saveAnchors.empty()) volume->saveAnchors(o.saveAnchors);
    }
}

// The measurement's part of the report and its files: measure.csv, reference.csv, the caches.
void finishMeasurement(const RunOptions& o, RunMeasurement& m, RunReport& report) {
    ErrorMeter* meter = m.meter.get();
    if (!meter) return;
    {
        report.measurementJson = measurementJson(*meter);
        if (meter->hasReference()) {
            // What lit the reference's surfaces, and how its bounce field converged.
            nlohmann::json j = nlohmann::json::parse(report.measurementJson);
            j["reference"]["light"] = m.bounceLit ? "bounce" : "hemisphere";
            j["reference"]["captureLight"] = o.captureLight;
            if (m.bounceLit) j["reference"]["bounce"] = bounceJson(o.bounce, m.bounceLit->solves());
            report.measurementJson = j.dump();
            if (m.bounceLit)
                for (const BounceSolve& b : m.bounceLit->solves()) {
                    std::printf("reference light: bounce field at %.3f h, %zu points, %d bounces "
                                "(%s; last change %.4f), %.1f s\n",
                                b.timeOfDay_h, b.points, b.bounces,
                                b.converged ? "converged" : "NOT converged",
                                b.changes.empty() ? 0.0 : b.changes.back(), b.seconds);
                }
        }
        writeMeasureCsv(*meter, (fs::path(o.report).parent_path() / "measure.csv").string());
        if (!o.oracle.empty() && meter->oracleCaptures() > 0)
            meter->saveOracle(o.oracle, m.oracleSignature);
        if (meter->hasReference()) {
            writeReferenceCsv(*meter, (fs::path(o.report).parent_path() / "reference.csv").string());
            if (o.screenWitnesses > 0)
                writeScreenCsv(*meter, (fs::path(o.report).parent_path() / "screen.csv").string());
            if (!o.reference.empty() && meter->referenceCaptures() > 0)
                meter->saveReference(o.reference, m.referenceSignature);
        }
    }

}

// What a run prints when it is done.
void printRunSummary(const RunOptions& o, const RunPlan& plan, int frames, const RunReport& report,
                     const ErrorMeter* meter, const AmbienceVolume* volume, bool video) {
    const Size& size = plan.size;
    const std::string& name = plan.name;
    const auto summary = report.summary();
    std::printf("rendered %d frames of %s at %dx%d on %s (%s)\n", frames, name.c_str(), size.width,
                size.height, report.backend.c_str(), report.glRenderer.c_str());
    std::printf("frame time median %.1f ms (%.1f fps), p95 %.1f ms; triangles median %.0f\n",
                summary.frameMedian_ms, 1000.0 / summary.frameMedian_ms, summary.frameP95_ms,
                summary.trianglesMedian);
    if (meter) {
        const Summary e = summarize(meter->errors()), p = summarize(meter->pops());
        std::printf(
            "error vs %s oracle: mean %.4f, p95 %.4f, max %.4f over %zu witnesses; "
            "pop p99 %.5f, max %.5f (oracle %.1f s, %lld captures, %lld from cache)\n",
            toString(meter->oracleKind()), e.mean, e.p95, e.max, e.count, p.p99, p.max,
            meter->oracleSeconds(), (long long)meter->oracleCaptures(),
            (long long)meter->oracleCacheHits());
        if (meter->hasReference()) {
            const BudgetSummary b = summarizeBudget(meter->terrainBudget());
            std::printf(
                "error budget (RMS over %zu terrain witnesses against the reference): total "
                "%.4f = truncation %.4f, capture %.4f, spacing %.4f, schedule %.4f (squares add "
                "to %.2f of the total's; reference %.1f s, %lld captures, %lld from cache)\n",
                b.count, b.total, b.truncation, b.capture, b.spacing, b.schedule, b.closure(),
                meter->referenceSeconds(), (long long)meter->referenceCaptures(),
                (long long)meter->referenceCacheHits());
            const DrawnBudgetSummary d = summarizeDrawnBudget(meter->drawnBudgets());
            if (d.count > 0)
                std::printf(
                    "error at the drawn normal (mean over %zu terrain witnesses): %.4f = far field "
                    "%+.4f, patch %+.4f, model %+.4f, truncation %+.4f (closure %.3f); the "
                    "method at each witness' own point: %.4f\n",
                    d.count, d.drawn, d.farField, d.patch, d.model, d.truncation, d.closure(),
                    d.perPoint);
        }
    }
    if (volume) {
        const AmbienceStatistics& st = volume->statistics();
        std::printf(
            "ambience: %zu anchors, %.1f kB (%.0f B/anchor), %lld faces captured, "
            "%lld probes (%lld rejected)\n",
            st.store.anchors, st.store.bytes() / 1024.0,
            st.store.anchors ? double(st.store.bytes()) / double(st.store.anchors) : 0.0,
            (long long)st.facesCaptured, (long long)st.probesCompleted,
            (long long)st.rejectedProbes);
        if (!o.saveAnchors.empty()) std::printf("  anchors saved: %s\n", o.saveAnchors.c_str());
    }
    printSoakSummary(report, volume != nullptr);
    std::printf("output: %s\n", fs::weakly_canonical(o.out).string().c_str());
    if (o.frames != "none") std::printf("  frames: %s (every %d)\n", o.frames.c_str(), o.every);
    if (o.contactSheet != "none") std::printf("  contact sheet: %s\n", o.contactSheet.c_str());
    if (video) std::printf("  video:  %s\n", o.video.c_str());
    std::printf("  report: %s (+ .csv)\n", o.report.c_str());
    if (meter)
        std::printf("  measurement: %s\n",
                    (fs::path(o.report).parent_path() / "measure.csv").string().c_str());
}

void runReplay(RunOptions o) {
    // (1) inputs
    const RunPlan plan = planRun(o);
    // (2) platform and renderer
    const Replay& replay = plan.replay;
    const Size& size = plan.size;
    auto platform = createOffscreenPlatform(plan.backend, size.width, size.height);
    const World world(replay.world);
    RenderSettings rs;
    rs.width = size.width;
    rs.height = size.height;
    rs.viewOutput = plan.view;
    rs.exposure.enabled = plan.autoExposure;
    rs.shadows = plan.shadows;
    rs.passTiming = o.passTiming;
    Renderer renderer(world, rs);
    auto stages =
        makeMethodStages(renderer, o.ambient, plan.volumeSettings, plan.baselines, o.faceSize);
    AmbienceVolume* volume = stages->volume();
    if (volume && !o.loadAnchors.empty()) volume->loadAnchors(o.loadAnchors);
    FrameLoop loop(replay, renderer, *stages, o.stride, o.loops);
    loop.setDrawMainView(!o.noFrames);
    loop.setCarView(plan.carView, [&world](double x, double z) { return world.height(x, z); });
    stages->setLookupStandIn(o.noFrames);

    // The error measurement: the oracle's captures use the same capture as the method.
    RunMeasurement measurement = startMeasurement(o, plan, world, *stages);
    ErrorMeter* meter = measurement.meter.get();
    // A shorter run (--share) measures a prefix of the full run's witnesses: the same frames,
    // so it reads the same oracle caches.
    const int frames = std::max(
        1, int(std::ceil(o.share * double(o.maxFrames > 0 ? std::min(o.maxFrames, loop.frameCount())
                                                          : loop.frameCount()))));

    RunReport report;
    report.replay = o.replay;
    report.backend = toString(platform->backend());
    report.glVersion = platform->glVersion();
    report.glRenderer = platform->glRenderer();
    report.width = size.width;
    report.height = size.height;
    report.ambient = o.ambient;
    if (plan.autoExposure)
        report.toneMapping = "auto exposure (eye adaptation to the mean log luminance in "
                             "simulation time), ACES filmic fit (Narkowicz 2015), sRGB";
    report.shadows = describeShadows(plan.shadows);
    report.frameStep_s = loop.frameStep_s();
    report.loops = o.loops;
    // Rows in one block from the start: no copy of them all when a long run outgrows it.
    report.frames.reserve(std::size_t(frames));

    std::unique_ptr<VideoPipe> video;
    if (!o.video.empty()) {
        video =
            std::make_unique<VideoPipe>(o.video, size.width, size.height, 1.0 / loop.frameStep_s());
    }
    std::fprintf(stderr, "run: %s, %d frames at %dx%d on %s (%s)\n", plan.name.c_str(), frames,
                 size.width, size.height, report.backend.c_str(), report.glRenderer.c_str());

    // (3) frames
    std::unique_ptr<ContactSheet> sheet;
    if (o.contactSheet != "none")
        sheet = std::make_unique<ContactSheet>(frames, o.sheetCells, size.width, size.height);
    ProgressBar progress(frames);
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < frames; ++i) {
        FrameRecord rec = loop.step();
        if (volume) {
            auto& t = report.ambienceTotals;
            t.nonFiniteAnchorsMax =
                std::max(t.nonFiniteAnchorsMax, nonFiniteAnchors(volume->store()));
            ++t.storeScans;
        }
        const CameraSample& camera = rec.view;  // the eye the main view rendered from
        if (meter && o.screenWitnesses > 0 && meter->referenceFrameNow())
            takeScreenWitnesses(renderer, camera, stages->ambient(), o.screenWitnesses, rec.index,
                                rec.timeOfDay_h, *meter);
        const bool writeFrame = o.frames != "none" && rec.index % o.every == 0;
        const bool onSheet = sheet && sheet->wants(i);
        if (writeFrame || video || onSheet) {
            auto pixels = renderer.readRgb8();
            if (o.debugOverlay && volume) {
                drawAnchorOverlay(pixels, size.width, size.height, renderer.viewProjection(camera),
                                  camera.position_m, *volume);
            }
            if (writeFrame) {
                char file[64];
                std::snprintf(file, sizeof(file), "/frame-%05d.png", rec.index);
                writeImageRgb8(o.frames + file, size.width, size.height, pixels);
            }
            if (video) video->write(pixels);
            if (onSheet) {
                char label[64];
                std::snprintf(label, sizeof(label), "frame %d  %05.2f h", rec.index,
                              rec.timeOfDay_h);
                sheet->add(i, pixels, label);
            }
        }
        // After everything this frame allocated (captures, lookups, frames written).
        rec.rss_kB = residentMemory_kB();
        rec.heap_kB = heapInUse_kB();
        report.frames.push_back(rec);
        progress.update(i + 1, rec.frame_ms);
    }
    progress.finish();
    report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    report.rssPeak_kB = peakResidentMemory_kB();
    if (video) video->close();
    if (sheet) sheet->write(o.contactSheet);
    addAmbienceTotals(o, *stages, report);
    finishMeasurement(o, measurement, report);

    // (4) report
    report.write(o.report);
    printRunSummary(o, plan, frames, report, meter, volume, video != nullptr);
}

}  // namespace

std::string shippedReplayDir() {
    // The data folders (world/DataPaths.h: P/share/ambience/replays installed, the source's
    // replays/ around a build tree inside it), else the current directory.
    const std::string found = findDataFile("replays/highway-drive.json");
    if (!found.empty()) return fs::weakly_canonical(fs::path(found).parent_path()).string();
    if (fs::exists("replays/highway-drive.json")) return fs::weakly_canonical("replays").string();
    return "";
}

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
    cmd->add_option("--share", o->share,
                    "play the first share (0 to 1] of those frames; oracle caches of the whole "
                    "run still match (default 1)");
    cmd->add_option("--loop", o->loops,
                    "play the replay N times back to back (1 to 10000, default 1); the clock and "
                    "the time of day keep going, each jump back to the start is a camera cut");
    cmd->add_option("--stride", o->stride,
                    "replay steps per frame (default 2: 30 frames/s of a 60 Hz replay)");
    cmd->add_option("--ambient", o->ambient, ambienceMethodHelp());
    cmd->add_option("--baseline-config", o->baselineConfig,
                    "JSON file of baseline settings (BaselineSettings fields, "
                    "lighting/Baselines.h)");
    cmd->add_flag("--no-frames", o->noFrames,
                  "do not render the main view (captures still render): no frames, no video");
    cmd->add_option("--measure-every", o->measureEvery,
                    "measure the error against the oracle every K-th frame (default 0: off)");
    cmd->add_option("--oracle", o->oracle,
                    "oracle cache (JSON): read if it exists and matches, else written");
    cmd->add_option("--oracle-kind", o->oracleKind,
                    "what the headline error is measured against: self (the methods' own 16 x 16 "
                    "coarse capture at the point, fast) or reference (the full scene at 64 x 64, "
                    "irradiance straight from the cube map; lighting/ReferenceOracle.h) "
                    "(default self)");
    cmd->add_option("--reference", o->reference,
                    "reference cache (JSON): read if it exists and matches, else written; also "
                    "turns on the reference and the error budget with --oracle-kind self");
    cmd->add_flag("--replace-stale-caches", o->replaceStale,
                  "an --oracle or --reference cache made for another replay, other code or other "
                  "capture settings is captured anew and replaced (default: refused)");
    cmd->add_option("--reference-every", o->referenceSettings.every,
                    "take the reference on every K-th measured frame (default 3)");
    cmd->add_option("--reference-size", o->referenceSettings.faceSize,
                    "reference face size N (default 64)");
    cmd->add_option("--reference-trees", o->referenceSettings.objectTrees,
                    "trees per reference frame with a base and a crown witness (default 2)");
    cmd->add_option("--screen-witnesses", o->screenWitnesses,
                    "on each reference frame, compare the ambient irradiance the draw applies at "
                    "N random pixels of the main view with the reference there (slow; default 0)");
    addReferenceLightOptions(*cmd, o->referenceLight, o->bounce);
    addCaptureLightOption(*cmd, o->captureLight);
    cmd->add_flag("--no-ideal-volume", o->noIdealVolume,
                  "error budget without the ideal volume (no extra captures; spacing and "
                  "schedule reported as one term)");
    cmd->add_option("--config,--ambience-config", o->ambienceConfig,
                    "JSON file of ambience volume settings (AmbienceVolumeSettings fields, "
                    "lighting/AmbienceVolume.h)");
    auto* faces = cmd->add_option("--faces-per-frame", o->facesPerFrame,
                                  "capture budget: cube faces per frame, 1 to " +
                                      std::to_string(kMaxFacesPerFrame) +
                                      " (default: the settings files', 1 as in the thesis)");
    addSetOption(*cmd, o->settingAssignments);
    cmd->add_option("--face-size", o->faceSize, "capture face size N (default 16)");
    cmd->add_option("--save-anchors", o->saveAnchors, "write the anchor store at the end (.vdb)");
    cmd->add_option("--load-anchors", o->loadAnchors, "warm-start from an anchor store (.vdb)");
    cmd->add_flag("--no-vehicle", o->noVehicle, "do not draw the car on drive replays");
    cmd->add_option("--camera", o->camera,
                    "drive replays: chase (default; the main view behind and above the car) or "
                    "hood (first person, the replay's eye)");
    cmd->add_option("--exposure", o->exposure,
                    "auto (default: eye adaptation in simulation time) or fixed (the sky's)");
    cmd->add_option("--view", o->view,
                    "shaded (default) or ambient: the ambient term alone, every surface white");
    cmd->add_option("--shadows", o->shadows,
                    "on (default) or off: shadows of the sun and moon in the main view, the "
                    "captures and the reference");
    cmd->add_option("--shadow-cascades", o->shadowCascades,
                    "cascades of the main view's shadow maps, 1 to 4 (default 3)");
    cmd->add_option("--shadow-size", o->shadowSize,
                    "texels per side of each cascade, 64 to 8192 (default 512)");
    cmd->add_option("--shadow-pcf", o->shadowPcf,
                    "PCF taps per side, 1 to 3, each a bilinear 2 x 2 comparison (default 1)");
    cmd->add_option("--shadow-far", o->shadowFar_m,
                    "far end of the terrain's far shadow cascade [m], beyond the cascades' 200 m "
                    "(default 800; 0: none)");
    cmd->add_flag("--pass-timing", o->passTiming,
                  "time each pass of the main view (shadow maps, plants, car, roads, terrain, "
                  "sky, exposure, tone mapping) between glFinish calls, with their triangles and "
                  "samples, into the report's \"passes\" (adds waits; changes no pixel)");
    cmd->add_option("--contact-sheet", o->contactSheet,
                    "PNG of frames across the run in a grid, or 'none' "
                    "(default <out>/contact-sheet.png)");
    cmd->add_option("--sheet-cells", o->sheetCells,
                    "frames on the contact sheet, evenly across the run (default 12)");
    cmd->add_flag("--debug-overlay", o->debugOverlay,
                  "draw anchors (colour = level, darker = older) and the probe being captured "
                  "over frames and video");
    cmd->add_option("--shaders", o->shaders,
                    "GLSL folder (default <exe>/../shaders or $AMBIENCE_SHADER_DIR)");
    cmd->callback([o, faces] {
        o->facesPerFrameGiven = faces->count() > 0;
        if (!o->shaders.empty()) setShaderDirectory(o->shaders);
        runReplay(*o);
    });
}

}  // namespace amb
