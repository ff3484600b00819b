// ProbeCommand.cpp — `ambience probe`: capture one cube map at a point, of the static coarse
// scene the methods capture or of the full scene the reference oracle captures (--scene), and
// write it as the vertical-strip EXR of docs/ARCHITECTURE.md ("Cube maps").
#include <cmath>
#include <cstdio>
#include <sstream>

#include <CLI/CLI.hpp>

#include "app/cli/CliChecks.h"
#include "app/cli/Commands.h"
#include "app/render/CubeCaptureGl.h"
#include "app/render/ShaderDirectory.h"
#include "app/cli/OutputPaths.h"
#include "app/platform/Platform.h"
#include "lighting/CubeMapFile.h"
#include "world/Error.h"
#include "world/Replay.h"
#include "world/World.h"

namespace amb {

namespace {

struct ProbeOptions {
    std::string at;
    double height_m = 2.0;
    double time_h = 12.0;
    std::uint64_t seed = 1;
    std::string replay;
    int size = CubeCaptureGl::kDefaultFaceSize;
    std::string out;
    std::string backend = "auto";
    std::string shaders;
    std::string scene = "coarse";
};

void runProbe(const ProbeOptions& o) {
    double x = 0.0, z = 0.0;
    {
        char comma = 0;
        std::istringstream in(o.at);
        if (!(in >> x >> comma >> z) || comma != ',' || !(in >> std::ws).eof() ||
            !std::isfinite(x) || !std::isfinite(z) || std::abs(x) > 1e8 || std::abs(z) > 1e8) {
            throw InputError("--at",
                             "expected X,Z in metres (e.g. --at 120,-40), got '" + o.at + "'");
        }
    }
    if (!std::isfinite(o.time_h) || o.time_h < 0.0 || o.time_h > 24.0) {
        throw InputError("--time", "time of day must be in [0, 24] hours");
    }
    if (!std::isfinite(o.height_m) || o.height_m < 0.0 || o.height_m > 1e5) {
        throw InputError("--height", "height above the ground must be in [0, 1e5] m");
    }
    if (o.size < 1 || o.size > 2048) throw InputError("--size", "face size must be in [1, 2048]");
    const CaptureScene scene = parseCaptureScene(o.scene, "--scene");
    const Backend backend = parseBackend(o.backend, "--backend");
    // The output before any work (the replay read, the world built, the capture): a format
    // OpenImageIO writes, in a writable folder, not the replay.
    checkCubeMapOutput(o.out, "--out");
    {
        FilePlan files;
        files.input("--replay", o.replay);
        files.output("--out", o.out);
        files.check();
    }
    WorldSettings ws;
    ws.seed = o.seed;
    if (!o.replay.empty()) ws = readReplay(o.replay).world;

    const World world(ws);
    auto platform = createOffscreenPlatform(backend, 16, 16);
    CubeCaptureGl capture(world, o.size, scene);
    const glm::dvec3 probe(x, world.height(x, z) + o.height_m, z);
    CubeCaptureStats stats;
    const std::vector<float> cube = capture.captureAll(probe, o.time_h, &stats);
    writeCubeMap(o.out, o.size, cube);
    // A second capture at the same point: the cost per face once the scene is built.
    std::vector<float> again;
    const CubeCaptureStats warm = capture.capture(probe, o.time_h, kAllCubeFaces, again);
    std::printf("probe at (%.2f, %.2f, %.2f) m, %.2f h: %d x %d x 6 -> %s\n", probe.x, probe.y,
                probe.z, o.time_h, o.size, o.size, o.out.c_str());
    std::printf(
        "backend %s (%s); %s capture scene, %zu triangles per face (most); %.2f ms per face "
        "(%.2f ms in the first call, which builds the scene)\n",
        toString(platform->backend()), platform->glRenderer().c_str(), toString(scene),
        stats.triangles,
        warm.perFace_ms(), stats.perFace_ms());
}

}  // namespace

void addProbeCommand(CLI::App& app) {
    auto* cmd = app.add_subcommand("probe", "capture one cube map of the static scene to an EXR");
    auto o = std::make_shared<ProbeOptions>();
    cmd->add_option("--at", o->at, "probe position X,Z [m]")->required();
    cmd->add_option("--height", o->height_m, "height above the ground [m] (default 2)");
    cmd->add_option("--time", o->time_h, "time of day [hours] (default 12)");
    auto* seed =
        cmd->add_option("--seed", o->seed, "world seed (default 1)")->check(SeedValidator());
    cmd->add_option("--replay", o->replay, "take the world settings from this replay")
        ->excludes(seed);
    cmd->add_option("--size", o->size, "face size N in texels (default 16)");
    cmd->add_option("--scene", o->scene,
                    "coarse (what the methods capture) or full (what the main view draws: the "
                    "reference oracle's scene) (default coarse)");
    cmd->add_option("--out", o->out, "output image (vertical strip, N x 6N; any format OpenImageIO writes: .exr for HDR)")
        ->required();
    cmd->add_option("--backend", o->backend, "auto, egl or osmesa (default auto)");
    cmd->add_option("--shaders", o->shaders,
                    "GLSL folder (default <exe>/../shaders or $AMBIENCE_SHADER_DIR)");
    cmd->callback([o] {
        if (!o->shaders.empty()) setShaderDirectory(o->shaders);
        runProbe(*o);
    });
}

}  // namespace amb
