// NearField_bench.cpp — cost of the near field on the highway drive's world, as the draw asks it:
// building a terrain corner's transfer (a corner new to the cache: plants, horizon, ground) and
// an object's (its own spheres left out, the ground from the lattice), one ground term of that
// lattice, and the lookups of cached corners through their normals and of cached objects (every
// frame).
//   build/bin/ambience_bench --benchmark_filter=NearField --benchmark_repetitions=9
//       --benchmark_report_aggregates_only=true   (one command line)
// The frame's figure is ambience.nearField_ms in `ambience run`'s report; this splits it.
#include <algorithm>
#include <cmath>
#include <vector>

#include <benchmark/benchmark.h>

#include "lighting/AmbienceMethod.h"
#include "lighting/NearField.h"
#include "world/DataPaths.h"
#include "world/Replay.h"
#include "world/World.h"

namespace amb {
namespace {

struct Drive {
    Replay replay = readReplay(findDataFile("replays/highway-drive.json"));
    World world{replay.world};
    WorldNearFieldScene scene{world};
    double time_h = replay.timeOfDayAt_h(0.5 * replay.duration_s());
};

const Drive& drive() {
    static const Drive d;
    return d;
}

// Terrain corners on the finest patch lattice (2 m) in a square of side `side` corners around
// the camera at each of `stops` times along the drive, kShadingHeight_m up, with their normals.
struct Corners {
    std::vector<glm::dvec3> points, normals;
    std::vector<ShRgb> far;
};

Corners corners(int stops, int side) {
    const Drive& d = drive();
    Corners c;
    for (int s = 0; s < stops; ++s) {
        const glm::dvec3 cam = d.replay.sampleAt(d.replay.duration_s() * (s + 0.5) / stops).position_m;
        const double x0 = 2.0 * std::floor(cam.x / 2.0) - side, z0 = 2.0 * std::floor(cam.z / 2.0) - side;
        for (int i = 0; i < side; ++i)
            for (int k = 0; k < side; ++k) {
                const double x = x0 + 2.0 * i, z = z0 + 2.0 * k;
                c.points.emplace_back(x, d.world.height(x, z) + kShadingHeight_m, z);
                c.normals.push_back(d.world.normal(x, z));
            }
    }
    ShRgb sky{};
    sky.c[0] = glm::vec3(3.0f, 3.5f, 4.5f);
    sky.c[2] = glm::vec3(1.0f, 1.2f, 1.6f);
    c.far.assign(c.points.size(), sky);
    return c;
}

// A fresh cache each iteration: every corner is built.
void BM_NearFieldCornerBuild(benchmark::State& state) {
    const Corners c = corners(8, 8);
    std::vector<glm::vec3> out(c.points.size());
    for (auto _ : state) {
        state.PauseTiming();
        NearField near(drive().scene, NearFieldSettings{});
        near.setTimeOfDay(drive().time_h);
        state.ResumeTiming();
        near.irradianceMany(c.points.size(), c.far.data(), c.points.data(), c.normals.data(),
                            out.data());
        benchmark::DoNotOptimize(out.data());
    }
    state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(c.points.size()));
    // The spheres near a corner (plants within radius_m, bushes and rocks within smallRadius_m).
    std::vector<SphereOccluder> spheres;
    const NearFieldSettings settings;
    for (const glm::dvec3& p : c.points)
        drive().scene.occludersNear(p, settings.radius_m, settings.smallRadius_m, spheres);
    state.counters["spheres"] = double(spheres.size()) / double(c.points.size());
    state.counters["s_per_build"] = benchmark::Counter(
        double(c.points.size()), benchmark::Counter::kIsIterationInvariantRate |
                                     benchmark::Counter::kInvert);
}
BENCHMARK(BM_NearFieldCornerBuild)->Unit(benchmark::kMillisecond);

// Objects 1 m apart along the road, each new to the cache (the lattice's ground terms are shared
// as they are on a drive).
void BM_NearFieldObjectBuild(benchmark::State& state) {
    const Drive& d = drive();
    constexpr int kObjects = 64;
    std::vector<double> x(kObjects), z(kObjects);
    const glm::dvec3 cam = d.replay.sampleAt(0.5 * d.replay.duration_s()).position_m;
    for (int i = 0; i < kObjects; ++i) x[i] = cam.x + i, z[i] = cam.z;
    ShRgb sky{};
    sky.c[0] = glm::vec3(3.0f, 3.5f, 4.5f);
    for (auto _ : state) {
        state.PauseTiming();
        NearField near(d.scene, NearFieldSettings{});
        near.setTimeOfDay(d.time_h);
        state.ResumeTiming();
        for (int i = 0; i < kObjects; ++i)
            benchmark::DoNotOptimize(near.applyAbove(sky, x[i], z[i], kShadingHeight_m,
                                                     NearFieldMethod::kSelfRadius_m));
    }
    state.counters["s_per_build"] = benchmark::Counter(
        double(kObjects), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_NearFieldObjectBuild)->Unit(benchmark::kMillisecond);

// One ground term as the objects' lattice takes it (every plant near the lattice point shades
// its ground, none stops its rays), at corners along the drive.
void BM_NearFieldGroundTerm(benchmark::State& state) {
    const Drive& d = drive();
    const Corners c = corners(16, 2);
    const NearFieldSettings settings;
    const glm::dvec3 light = d.scene.mainLight(d.time_h).direction;
    std::vector<std::vector<SphereOccluder>> near(c.points.size());
    for (std::size_t i = 0; i < c.points.size(); ++i)
        d.scene.occludersNear(c.points[i], settings.radius_m, settings.smallRadius_m, near[i]);
    for (auto _ : state)
        for (std::size_t i = 0; i < c.points.size(); ++i)
            benchmark::DoNotOptimize(
                groundTerm(c.points[i], d.scene, {}, near[i], settings.groundRadius_m, light));
    state.counters["s_per_term"] = benchmark::Counter(
        double(c.points.size()), benchmark::Counter::kIsIterationInvariantRate |
                                     benchmark::Counter::kInvert);
}
BENCHMARK(BM_NearFieldGroundTerm)->Unit(benchmark::kMillisecond);

// A frame's corners, all cached (about as many as the highway's view asks).
void BM_NearFieldCornerLookup(benchmark::State& state) {
    const Corners c = corners(1, 84);
    NearField near(drive().scene, NearFieldSettings{});
    near.setTimeOfDay(drive().time_h);
    std::vector<glm::vec3> out(c.points.size());
    near.irradianceMany(c.points.size(), c.far.data(), c.points.data(), c.normals.data(), out.data());
    for (auto _ : state) {
        near.irradianceMany(c.points.size(), c.far.data(), c.points.data(), c.normals.data(),
                            out.data());
        benchmark::DoNotOptimize(out.data());
    }
    state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(c.points.size()));
    state.counters["corners"] = double(c.points.size());
}
BENCHMARK(BM_NearFieldCornerLookup)->Unit(benchmark::kMicrosecond);

// A frame's objects near the camera, all cached: plants and the car take the far field with the
// near field applied every frame (about 600 within objectRange_m on the highway).
void BM_NearFieldObjectLookup(benchmark::State& state) {
    const Drive& d = drive();
    const glm::dvec3 cam = d.replay.sampleAt(0.5 * d.replay.duration_s()).position_m;
    std::vector<double> x, z;
    for (int i = 0; i < 24; ++i)
        for (int k = 0; k < 25; ++k) x.push_back(cam.x - 60.0 + 5.0 * i), z.push_back(cam.z - 60.0 + 5.0 * k);
    NearField near(d.scene, NearFieldSettings{});
    near.setTimeOfDay(d.time_h);
    ShRgb sky{};
    sky.c[0] = glm::vec3(3.0f, 3.5f, 4.5f);
    sky.c[2] = glm::vec3(1.0f, 1.2f, 1.6f);
    for (std::size_t i = 0; i < x.size(); ++i)
        near.applyAbove(sky, x[i], z[i], kShadingHeight_m, NearFieldMethod::kSelfRadius_m);
    // In one batch, as the draw asks (NearFieldMethod::shAt over many).
    std::vector<ShRgb> sh(x.size());
    for (auto _ : state) {
        std::fill(sh.begin(), sh.end(), sky);
        near.applyAboveMany(sh.size(), sh.data(), x.data(), z.data(), kShadingHeight_m,
                            NearFieldMethod::kSelfRadius_m);
        benchmark::DoNotOptimize(sh.data());
    }
    state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(x.size()));
    state.counters["objects"] = double(x.size());
}
BENCHMARK(BM_NearFieldObjectLookup)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace amb
