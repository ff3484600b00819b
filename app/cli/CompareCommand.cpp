// CompareCommand.cpp — `ambience compare`: one frame of a replay as the method draws it, the same
// frame with the reference's ambient, and a per-pixel heat map of the ambient error, side by side
// (docs/ARCHITECTURE.md "Measuring speed against error": a picture users can read).
//
// Steps: (1) play the replay with the method up to --frame, without the main view (the draw's
// lookups stood in, as `ambience run --no-frames` does); (2) render that frame shaded, and as the
// ambient irradiance the draw applies, the world normal and the albedo (app/render/Renderer.h,
// RenderOutput); (3) on a grid of pixels every --grid pixels, a reference capture of the full
// scene (lighting/ReferenceOracle.h) 0.25 m along the surface normal gives E_ref(n) there, and
// the relative error of the applied irradiance against it; (4) between grid pixels the ratio
// E_ref / E_applied and the error are interpolated bilinearly from the surface samples around;
// (5) the reference frame is the shaded frame with its ambient term replaced, per pixel:
// L + albedo / pi x (E_ref - E_applied) (fog left out: it only fades the far field), tone mapped
// as the frame is. Outputs in --out: method.png, reference.png, error.png (0 black .. 0.5 and
// above white-yellow, sky grey), compare.png (the three side by side), ambient.png and
// ambient-reference.png (the ambient term alone, albedo / pi x irradiance, the method's and the
// reference's on one scale) and compare.json (the mean error over the samples: screen-weighted,
// and by surface).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "app/cli/CliChecks.h"
#include "app/cli/Commands.h"
#include "app/render/CubeCaptureGl.h"
#include "app/frame/FrameLoop.h"
#include "app/cli/OutputPaths.h"
#include "app/cli/ReferenceLightFlags.h"
#include "app/platform/Platform.h"
#include "app/render/Renderer.h"
#include "app/cli/RunReport.h"
#include "app/cli/SettingsFlags.h"
#include "app/frame/MethodStages.h"
#include "lighting/Baselines.h"
#include "lighting/Metrics.h"
#include "lighting/BounceField.h"
#include "lighting/Metrics.h"
#include "lighting/ReferenceOracle.h"
#include "world/Error.h"
#include "world/TextFile.h"
#include "world/World.h"

namespace amb {

namespace {

namespace fs = std::filesystem;

struct CompareOptions {
    std::string replay, ambient = "volume", config, out, size = "640x360", backend = "auto";
    std::string shaders;
    std::string camera = "chase", exposure = "auto";  // --camera, --exposure (as in run)
    std::string shadows = "on";
    int frame = 0;            // --frame, read only when given
    bool frameGiven = false;  // --frame not given: the middle of the replay
    int grid = 16;
    int referenceSize = CubeCaptureGl::kReferenceFaceSize;
    int facesPerFrame = 1;
    bool facesPerFrameGiven = false;              // --faces-per-frame was on the command line
    std::vector<std::string> settingAssignments;  // --set KEY=VALUE
    int stride = 2;
    // What lights the reference's surfaces (as in run: lighting/BounceField.h).
    std::string referenceLight = "bounce";
    BounceSettings bounce = runBounceSettings();
};

// A heat colour for an error in [0, 0.5]: black, red, orange, yellow, white.
glm::vec3 heat(double error) {
    static const glm::vec3 stops[] = {
        {0.0f, 0.0f, 0.0f}, {0.6f, 0.0f, 0.0f}, {1.0f, 0.45f, 0.0f}, {1.0f, 0.9f, 0.2f},
        {1.0f, 1.0f, 1.0f}};
    const double t = std::clamp(error / 0.5, 0.0, 1.0) * 4.0;
    const int i = std::min(3, int(t));
    return glm::mix(stops[i], stops[i + 1], float(t - i));
}

unsigned char byte(float v) {
    return (unsigned char)std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f);
}

// The options checked and resolved: the replay, the methods' settings, the frame to compare and
// the output folder.
struct CompareInputs {
    std::string replayPath;
    Replay replay;
    AmbienceVolumeSettings volumeSettings;
    BaselineSettings baselines;
    Size size;
    int target = 0;    // the frame to compare
    std::string stem;  // the replay's name as a file name
    std::string out;   // output folder, created
};

// (1) inputs: reads the replay and the settings, checks every option, creates the output folder
// and checks that the inputs can be read and the outputs written before anything is played.
CompareInputs checkInputs(const CompareOptions& o) {
    parseShadowSwitch(o.shadows, "--shadows");
    const std::string replayPath =
        o.replay.empty() ? (shippedReplayDir().empty() ? std::string("replays")
                                                       : shippedReplayDir()) +
                               "/highway-drive.json"
                         : o.replay;
    Replay replay = readReplay(replayPath);
    checkAmbienceMethod(o.ambient, "--ambient");
    parseCarView(o.camera, "--camera");
    parseExposure(o.exposure, "--exposure");
    AmbienceVolumeSettings volumeSettings;
    if (!o.config.empty())
        volumeSettings = ambienceSettingsFromJson(
            readTextFile(o.config, "ambience settings file", kMaxSettingsFileBytes), o.config);
    BaselineSettings baselines;
    // The command line over the file, and only what it names (as `run`).
    if (o.facesPerFrameGiven) {
        if (o.facesPerFrame < 1 || o.facesPerFrame > kMaxFacesPerFrame)
            throw InputError("--faces-per-frame",
                             "expected 1 to " + std::to_string(kMaxFacesPerFrame));
        volumeSettings.capture.facesPerFrame = baselines.capture.facesPerFrame = o.facesPerFrame;
    }
    applySettingAssignments(o.settingAssignments, volumeSettings, &baselines);
    if (o.grid < 2 || o.grid > 256) throw InputError("--grid", "expected 2 to 256 pixels");
    if (o.referenceSize < 4 || o.referenceSize > 256)
        throw InputError("--reference-size", "expected 4 to 256");
    if (o.stride < 1) throw InputError("--stride", "must be at least 1");
    parseReferenceLight(o.referenceLight, "--reference-light");
    checkBounceSettings(o.bounce);
    const Size size = parseSize(o.size, "--size");
    const int passFrames = FrameLoop::framesPerPass(replay, o.stride);
    if (o.frameGiven && (o.frame < 0 || o.frame >= passFrames))
        throw InputError("--frame", "expected 0 to " + std::to_string(passFrames - 1) +
                                        " (the replay has " + std::to_string(passFrames) +
                                        " frames at stride " + std::to_string(o.stride) +
                                        "), got " + std::to_string(o.frame));
    const int target = o.frameGiven ? o.frame : passFrames / 2;
    const std::string stem =
        safeFileStem(replay.name.empty() ? fs::path(replayPath).stem().string() : replay.name);
    const std::string out = o.out.empty() ? "out/compare-" + stem : o.out;
    std::error_code ec;
    fs::create_directories(out, ec);
    if (ec || !fs::is_directory(out)) throw InputError("--out", "cannot create '" + out + "'");
    {
        FilePlan files;
        files.input("--replay", replayPath);
        files.input("--config", o.config);
        for (const char* name : {"method.png", "reference.png", "error.png", "ambient.png",
                                 "ambient-reference.png", "compare.png", "compare.json"})
            files.output("--out", (fs::path(out) / name).string());
        files.check();
    }
    return {replayPath, std::move(replay), std::move(volumeSettings), baselines, size, target,
            stem, out};
}

// The target frame as the loop played it: its record (clock, time of day) and its camera.
struct TargetFrame {
    FrameRecord rec;
    CameraSample camera;
};

// (1) the frames up to and including the target, as a run without the main view plays them; the
// target's own stand-in lookups only feed a next frame that never comes.
TargetFrame playToTarget(FrameLoop& loop, int target) {
    TargetFrame frame;
    for (int i = 0; i <= target; ++i) {
        frame.rec = loop.step();
        frame.camera = frame.rec.view;  // the eye the main view draws from (the chase eye)
    }
    return frame;
}

// What the renderer gives of the target frame: shaded (linear and tone mapped), and the ambient
// irradiance the draw applies, the world normal and the albedo per pixel.
struct FrameImages {
    std::vector<float> hdr;
    std::vector<unsigned char> methodLdr;
    SurfaceImage applied, normals, albedo;
};

// (2) the frame and its outputs.
FrameImages renderFrame(Renderer& renderer, const CameraSample& camera,
                        const AmbientSource& ambient) {
    FrameImages images;
    renderer.render(camera, ambient);
    images.hdr = renderer.readHdr();
    images.methodLdr = renderer.readRgb8();
    renderer.render(camera, ambient, RenderOutput::AmbientIrradiance);
    images.applied = renderer.readSurface(camera);
    renderer.render(camera, ambient, RenderOutput::Normal);
    images.normals = renderer.readSurface(camera);
    renderer.render(camera, ambient, RenderOutput::Albedo);
    images.albedo = renderer.readSurface(camera);
    return images;
}

// A grid pixel: whether it shows a surface, and there E_ref / E_applied per channel and the
// relative error.
struct GridSample {
    bool surface = false;
    glm::dvec3 ratio{1.0};
    double error = 0.0;
};

// The reference samples on the grid (gw x gh, by rows) and their errors summed, over all of
// them and by surface kind.
struct ReferenceGrid {
    int gw = 0, gh = 0;
    std::vector<GridSample> samples;
    double sum = 0.0;
    std::array<double, kSurfaceKinds + 1> kindSum{}, kindCount{};
    int count = 0;
};

// (3) a reference capture of the full scene above the surface at the centre of every grid cell.
ReferenceGrid sampleReference(const CompareOptions& o, const Size& size, const World& world,
                              CubeCapture& reference, const TargetFrame& frame,
                              const FrameImages& images) {
    const CameraSample& camera = frame.camera;
    const SurfaceImage& applied = images.applied;
    const SurfaceImage& normals = images.normals;
    const int w = size.width, h = size.height, g = o.grid;
    ReferenceGrid grid;
    grid.gw = (w + g - 1) / g;
    grid.gh = (h + g - 1) / g;
    const int gw = grid.gw, gh = grid.gh;
    std::vector<GridSample>& samples = grid.samples;
    samples.resize(std::size_t(gw) * gh);
    for (int gy = 0; gy < gh; ++gy)
        for (int gx = 0; gx < gw; ++gx) {
            const int x = std::min(w - 1, gx * g + g / 2), y = std::min(h - 1, gy * g + g / 2);
            const std::size_t p = std::size_t(y) * w + x;
            const int kind = int(std::lround(applied.rgba[4 * p + 3]));
            if (kind < 1 || kind > kSurfaceKinds) continue;  // sky, or a simplified plant mesh
            glm::dvec3 n(normals.rgba[4 * p], normals.rgba[4 * p + 1], normals.rgba[4 * p + 2]);
            if (!(glm::length(n) > 0.5)) continue;
            n = glm::normalize(n);
            glm::dvec3 at = camera.position_m + glm::dvec3(applied.position[p]);
            if (kind == int(SurfaceKind::Terrain)) at.y = world.height(at.x, at.z);
            const glm::dvec3 probe = at + ErrorMeter::kScreenProbeOffset_m * n;
            const glm::dvec3 ref = referenceIrradianceAt(
                o.referenceSize, reference.captureAll(probe, frame.rec.timeOfDay_h),
                reference.sunDirection(frame.rec.timeOfDay_h), n);
            const glm::dvec3 a(applied.rgba[4 * p], applied.rgba[4 * p + 1],
                               applied.rgba[4 * p + 2]);
            GridSample& s = samples[std::size_t(gy) * gw + gx];
            s.surface = true;
            s.error = irradianceRelativeError(a, ref);
            for (int c = 0; c < 3; ++c) s.ratio[c] = ref[c] / std::max(a[c], 1e-6);
            grid.sum += s.error;
            ++grid.count;
            grid.kindSum[std::size_t(kind)] += s.error;
            grid.kindCount[std::size_t(kind)] += 1.0;
        }
    return grid;
}

// The reference frame (tone mapped) and the error map, both of the view's size.
struct ComposedImages {
    std::vector<unsigned char> refLdr;
    std::vector<unsigned char> errorRgb;
    // The ambient term alone (albedo / pi x irradiance), the method's and the reference's, on
    // one scale: white at the method's 99th percentile, gamma 2.2, sky grey.
    std::vector<unsigned char> ambientLdr, ambientRefLdr;
};

// Ambient-only images of `method` and `reference` (linear RGB, < 0 for sky) on a shared scale.
void ambientImages(const std::vector<float>& method, const std::vector<float>& reference,
                   ComposedImages& out) {
    std::vector<float> lum;
    for (std::size_t p = 0; 3 * p < method.size(); ++p)
        if (method[3 * p] >= 0.0f)
            lum.push_back(std::max({method[3 * p], method[3 * p + 1], method[3 * p + 2]}));
    float white = 1.0f;
    if (!lum.empty()) {
        std::nth_element(lum.begin(), lum.begin() + std::ptrdiff_t(lum.size() * 99 / 100), lum.end());
        white = std::max(lum[lum.size() * 99 / 100], 1e-6f);
    }
    const auto toLdr = [&](const std::vector<float>& img) {
        std::vector<unsigned char> ldr(img.size());
        for (std::size_t i = 0; i < img.size(); ++i)
            ldr[i] = img[i] < 0.0f ? 60
                                   : (unsigned char)std::lround(
                                         255.0 * std::pow(std::clamp(img[i] / white, 0.0f, 1.0f),
                                                          1.0 / 2.2));
        return ldr;
    };
    out.ambientLdr = toLdr(method);
    out.ambientRefLdr = toLdr(reference);
}

// (4) + (5) per pixel: the ratio and the error interpolated from the grid samples around, the
// error as a heat colour and the shaded frame's ambient term scaled by the ratio.
ComposedImages composeImages(const CompareOptions& o, const Size& size, Renderer& renderer,
                             const FrameImages& images, const ReferenceGrid& grid) {
    const SurfaceImage& applied = images.applied;
    const SurfaceImage& albedo = images.albedo;
    const int w = size.width, h = size.height, g = o.grid;
    const int gw = grid.gw, gh = grid.gh;
    const std::vector<GridSample>& samples = grid.samples;
    std::vector<float> refHdr = images.hdr;
    std::vector<unsigned char> errorRgb(std::size_t(w) * h * 3);
    std::vector<float> ambient(std::size_t(w) * h * 3, -1.0f), ambientRef = ambient;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y) * w + x;
            if (!(applied.rgba[4 * p + 3] > 0.5f)) {
                for (int c = 0; c < 3; ++c) errorRgb[3 * p + c] = 60;  // sky
                continue;
            }
            const double u = std::clamp((x - g / 2 + 0.5) / g, 0.0, gw - 1.0);
            const double v = std::clamp((y - g / 2 + 0.5) / g, 0.0, gh - 1.0);
            const int x0 = int(u), y0 = int(v);
            glm::dvec3 ratio(0.0);
            double error = 0.0, weight = 0.0;
            for (int dy = 0; dy < 2; ++dy)
                for (int dx = 0; dx < 2; ++dx) {
                    const int sx = std::min(gw - 1, x0 + dx), sy = std::min(gh - 1, y0 + dy);
                    const GridSample& s = samples[std::size_t(sy) * gw + sx];
                    if (!s.surface) continue;
                    const double wgt =
                        (dx ? u - x0 : 1.0 - (u - x0)) * (dy ? v - y0 : 1.0 - (v - y0)) + 1e-6;
                    ratio += wgt * s.ratio;
                    error += wgt * s.error;
                    weight += wgt;
                }
            if (weight <= 0.0) {
                for (int c = 0; c < 3; ++c) errorRgb[3 * p + c] = 30;  // no sample near
                continue;
            }
            ratio /= weight;
            error /= weight;
            const glm::vec3 colour = heat(error);
            for (int c = 0; c < 3; ++c) {
                errorRgb[3 * p + c] = byte(colour[c]);
                const double a = applied.rgba[4 * p + c];
                refHdr[3 * p + c] += float(albedo.rgba[4 * p + c] / kPi * (ratio[c] - 1.0) * a);
                refHdr[3 * p + c] = std::max(refHdr[3 * p + c], 0.0f);
                ambient[3 * p + c] = float(albedo.rgba[4 * p + c] / kPi * a);
                ambientRef[3 * p + c] = float(albedo.rgba[4 * p + c] / kPi * ratio[c] * a);
            }
        }
    ComposedImages out{renderer.tonemap(refHdr), std::move(errorRgb), {}, {}};
    ambientImages(ambient, ambientRef, out);
    return out;
}

// Outputs: the three images alone and side by side, compare.json with the mean errors, and a
// summary on stdout.
void writeOutputs(const CompareOptions& o, const CompareInputs& in, const TargetFrame& frame,
                  const FrameImages& images, const ReferenceGrid& grid,
                  const ComposedImages& composed, const std::vector<BounceSolve>& bounce) {
    const std::string& out = in.out;
    const std::string& stem = in.stem;
    const int target = in.target;
    const FrameRecord& rec = frame.rec;
    const std::vector<unsigned char>& methodLdr = images.methodLdr;
    const std::vector<unsigned char>& refLdr = composed.refLdr;
    const std::vector<unsigned char>& errorRgb = composed.errorRgb;
    const int w = in.size.width, h = in.size.height, g = o.grid;
    const double sum = grid.sum;
    const int count = grid.count;
    const auto& kindSum = grid.kindSum;
    const auto& kindCount = grid.kindCount;
    writeImageRgb8((fs::path(out) / "method.png").string(), w, h, methodLdr);
    writeImageRgb8((fs::path(out) / "reference.png").string(), w, h, refLdr);
    writeImageRgb8((fs::path(out) / "error.png").string(), w, h, errorRgb);
    writeImageRgb8((fs::path(out) / "ambient.png").string(), w, h, composed.ambientLdr);
    writeImageRgb8((fs::path(out) / "ambient-reference.png").string(), w, h,
                   composed.ambientRefLdr);
    std::vector<unsigned char> side(std::size_t(3) * w * h * 3);
    for (int y = 0; y < h; ++y)
        for (int i = 0; i < 3; ++i) {
            const std::vector<unsigned char>& src = i == 0 ? methodLdr : i == 1 ? refLdr : errorRgb;
            std::copy_n(&src[std::size_t(y) * w * 3], std::size_t(w) * 3,
                        &side[(std::size_t(y) * 3 * w + std::size_t(i) * w) * 3]);
        }
    writeImageRgb8((fs::path(out) / "compare.png").string(), 3 * w, h, side);
    nlohmann::json j{{"replay", stem},
                     {"method", o.ambient},
                     {"frame", target},
                     {"timeOfDay_h", rec.timeOfDay_h},
                     {"gridPixels", g},
                     {"referenceFaceSize", o.referenceSize},
                     {"referenceLight", o.referenceLight},
                     {"samples", count},
                     {"screenMeanError", count ? sum / count : 0.0}};
    for (int k = 1; k <= kSurfaceKinds; ++k)
        j[std::string(toString(SurfaceKind(k))) + "MeanError"] =
            kindCount[std::size_t(k)] > 0 ? kindSum[std::size_t(k)] / kindCount[std::size_t(k)]
                                          : 0.0;
    if (!bounce.empty()) j["bounce"] = bounceJson(o.bounce, bounce);
    std::ofstream((fs::path(out) / "compare.json").string()) << j.dump(1) << "\n";
    std::printf("compare: %s, frame %d (%.2f h), %s: screen-weighted mean ambient error %.4f over "
                "%d reference samples (terrain %.3f, road %.3f, objects %.3f)\n",
                stem.c_str(), target, rec.timeOfDay_h, o.ambient.c_str(),
                count ? sum / count : 0.0, count,
                j["terrainMeanError"].get<double>(), j["roadMeanError"].get<double>(),
                j["objectMeanError"].get<double>());
    std::printf("  %s (method | reference | error 0 to 0.5)\n",
                (fs::path(out) / "compare.png").string().c_str());
}

// The whole comparison. The platform (GL context), renderer, method and reference capture live
// here, in this order, until the outputs are written.
void runCompare(const CompareOptions& o) {
    const CompareInputs in = checkInputs(o);

    auto platform = createOffscreenPlatform(parseBackend(o.backend, "--backend"),
                                            in.size.width, in.size.height);
    const World world(in.replay.world);
    RenderSettings rs;
    rs.width = in.size.width;
    rs.height = in.size.height;
    rs.exposure.enabled = parseExposure(o.exposure, "--exposure");
    rs.shadows.enabled = rs.shadows.captures = parseShadowSwitch(o.shadows, "--shadows");
    Renderer renderer(world, rs);
    const auto stagesOwner =
        makeMethodStages(renderer, o.ambient, in.volumeSettings, in.baselines);
    MethodAmbienceStages& stages = *stagesOwner;
    FrameLoop loop(in.replay, renderer, stages, o.stride, 1);
    loop.setDrawMainView(false);
    loop.setCarView(in.replay.mode == ReplayMode::Drive ? parseCarView(o.camera, "--camera")
                                                        : CarView::None,
                    [&world](double x, double z) { return world.height(x, z); });
    stages.setLookupStandIn(true);
    std::fprintf(stderr, "compare: playing %d frames of %s with %s\n", in.target + 1,
                 in.stem.c_str(), o.ambient.c_str());
    const TargetFrame frame = playToTarget(loop, in.target);

    const FrameImages images = renderFrame(renderer, frame.camera, stages.ambient());
    CubeCaptureGl reference(world, o.referenceSize, CaptureScene::Full, rs.shadows);
    // The reference's surfaces lit by the bounce field of a lattice around this frame's camera
    // (or by the hemisphere ambient, --reference-light hemisphere).
    std::unique_ptr<CubeCaptureGl> lattice;
    std::unique_ptr<BounceLitCapture> bounceLit;
    CubeCapture* referenceCapture = &reference;
    if (parseReferenceLight(o.referenceLight, "--reference-light") == ReferenceLight::Bounce) {
        lattice = std::make_unique<CubeCaptureGl>(world, o.bounce.faceSize, CaptureScene::Full,
                                                  rs.shadows);
        bounceLit = std::make_unique<BounceLitCapture>(
            reference, *lattice, o.bounce,
            std::vector<glm::dvec2>{{frame.camera.position_m.x, frame.camera.position_m.z}},
            bounceLatticePlacement(world), frame.rec.timeOfDay_h);
        referenceCapture = bounceLit.get();
    }
    const ReferenceGrid grid = sampleReference(o, in.size, world, *referenceCapture, frame, images);
    const ComposedImages composed = composeImages(o, in.size, renderer, images, grid);
    writeOutputs(o, in, frame, images, grid, composed,
                 bounceLit ? bounceLit->solves() : std::vector<BounceSolve>{});
}

}  // namespace

void addCompareCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand(
        "compare",
        "one frame as the method draws it, with the reference's ambient, and the ambient error "
        "per pixel, side by side");
    auto o = std::make_shared<CompareOptions>();
    cmd->add_option("--replay", o->replay, "replay file (default replays/highway-drive.json)");
    cmd->add_option("--ambient", o->ambient, ambienceMethodHelp());
    cmd->add_option("--config", o->config, "JSON file of ambience volume settings");
    auto* frame = cmd->add_option(
        "--frame", o->frame,
        "frame to compare, from 0 to the last at --stride (default: the middle of the replay)");
    cmd->add_option("--grid", o->grid,
                    "a reference sample every N pixels (default 16; each costs a 64 x 64 capture "
                    "of the full scene)");
    cmd->add_option("--reference-size", o->referenceSize, "reference face size (default 64)");
    addReferenceLightOptions(*cmd, o->referenceLight, o->bounce);
    auto* faces = cmd->add_option("--faces-per-frame", o->facesPerFrame,
                                  "capture budget (default: the settings file's, 1)");
    addSetOption(*cmd, o->settingAssignments);
    cmd->add_option("--stride", o->stride, "replay steps per frame (default 2)");
    cmd->add_option("--size", o->size, "image size WxH (default 640x360)");
    cmd->add_option("--camera", o->camera,
                    "drive replays: chase (default; behind and above the car) or hood (first "
                    "person, the replay's eye)");
    cmd->add_option("--exposure", o->exposure, "auto (default: eye adaptation) or fixed");
    cmd->add_option("--out", o->out, "output folder (default out/compare-<replay name>)");
    cmd->add_option("--backend", o->backend, "auto, egl or osmesa (default auto)");
    cmd->add_option("--shadows", o->shadows,
                    "on (default) or off: shadows of the sun and moon in the view, the captures "
                    "and the reference");
    cmd->add_option("--shaders", o->shaders,
                    "GLSL folder (default <exe>/../shaders or $AMBIENCE_SHADER_DIR)");
    cmd->callback([o, frame, faces] {
        o->frameGiven = frame->count() > 0;
        o->facesPerFrameGiven = faces->count() > 0;
        if (!o->shaders.empty()) setShaderDirectory(o->shaders);
        runCompare(*o);
    });
}

}  // namespace amb
