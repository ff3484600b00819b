// Heightfield_bench.cpp — cost of the world's noise, which most of the near field's builds
// spend their time in: GLM's classic Perlin noise against the table-driven one that equals it
// bit for bit (Heightfield::classicNoise), and one terrain height (8 to 14 octaves); one
// terrain patch at each level, with and without the per-vertex sky detail (which the two
// finest levels carry in ravine country, from a height grid with a 16 m border: 33 x 33 and
// 25 x 25 heights, against 19 x 19 without it).
//   build/bin/ambience_bench --benchmark_filter='Noise|Height|Patch'
#include <cmath>
#include <cstdint>
#include <vector>

#include <benchmark/benchmark.h>
#include <glm/gtc/noise.hpp>

#include "world/Heightfield.h"
#include "world/TerrainPatch.h"
#include "world/World.h"
#include "world/WorldSettings.h"

namespace amb {
namespace {

// 4096 points spread over the noise's period, reused so the loop measures the noise alone.
const std::vector<glm::dvec2>& periodPoints() {
    static const std::vector<glm::dvec2> points = [] {
        std::vector<glm::dvec2> p;
        for (int i = 0; i < 4096; ++i) p.emplace_back(std::fmod(i * 0.7548776662, 1.0) * 289.0,
                                                      std::fmod(i * 0.5698402910, 1.0) * 289.0);
        return p;
    }();
    return points;
}

void BM_NoiseGlm(benchmark::State& state) {
    const auto& points = periodPoints();
    for (auto _ : state)
        for (const glm::dvec2& p : points) benchmark::DoNotOptimize(glm::perlin(p));
    state.SetItemsProcessed(state.iterations() * std::int64_t(points.size()));
}
BENCHMARK(BM_NoiseGlm)->Unit(benchmark::kMicrosecond);

void BM_NoiseTables(benchmark::State& state) {
    const auto& points = periodPoints();
    for (auto _ : state)
        for (const glm::dvec2& p : points) benchmark::DoNotOptimize(Heightfield::classicNoise(p.x, p.y));
    state.SetItemsProcessed(state.iterations() * std::int64_t(points.size()));
}
BENCHMARK(BM_NoiseTables)->Unit(benchmark::kMicrosecond);

void BM_HeightfieldHeight(benchmark::State& state) {
    const Heightfield field{WorldSettings{}};
    const auto& points = periodPoints();
    for (auto _ : state)
        for (const glm::dvec2& p : points) benchmark::DoNotOptimize(field.height(p.x * 40.0, p.y * 40.0));
    state.SetItemsProcessed(state.iterations() * std::int64_t(points.size()));
}
BENCHMARK(BM_HeightfieldHeight)->Unit(benchmark::kMicrosecond);

// One patch of level state.range(0) beside the highway's start (no ravine country there), by
// default (no sky detail there) or with the sky detail made to cover it (state.range(1) = 1):
// what the detail costs where it is computed.
void BM_TerrainPatchGenerate(benchmark::State& state) {
    static const World world{WorldSettings{}};
    const int level = int(state.range(0));
    const auto mode = state.range(1) ? TerrainPatch::SkyDetail::Everywhere : TerrainPatch::SkyDetail::WhereGullies;
    const double size = TerrainPatch::size_m(level);
    std::int64_t n = 0;
    for (auto _ : state) {
        const PatchKey key{level, std::int64_t(std::floor(-5664.0 / size)) + n % 4,
                           std::int64_t(std::floor(-4661.0 / size)) + n / 4 % 4};
        benchmark::DoNotOptimize(TerrainPatch::generate(world, key, mode));
        ++n;
    }
}
BENCHMARK(BM_TerrainPatchGenerate)
    ->ArgNames({"level", "detail"})
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace amb
