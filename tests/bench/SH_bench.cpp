// SH_bench.cpp — speed of the SH core (issue targets on one core: <= 2 us per 16 x 16 cube-map
// projection, >= 100 M irradiance evaluations per second in batch).
//   build/bin/ambience_bench --benchmark_filter='Sh|CubeMap' --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true   (one command line)
#include <cmath>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "lighting/CubeMapProjector.h"
#include "lighting/SH.h"
#include "lighting/ShGradient.h"

namespace {

std::vector<float> randomMap(int n) {
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0.0f, 2.0f);
    std::vector<float> rgb(std::size_t(6) * n * n * 3);
    for (auto& v : rgb) v = u(rng);
    return rgb;
}

// One whole N x N x 6 projection with a warm projector (tables built once per N).
void BM_CubeMapProjection(benchmark::State& state) {
    const int n = int(state.range(0));
    const auto rgb = randomMap(n);
    amb::CubeMapProjector projector(n);
    for (auto _ : state) {
        projector.addCubeMap(rgb.data());
        benchmark::DoNotOptimize(projector.coefficients());
    }
    state.SetItemsProcessed(state.iterations() * 6 * n * n);  // texels
}
BENCHMARK(BM_CubeMapProjection)->Arg(16)->Arg(32)->Arg(64);

// The translational gradient of one probe (lighting/ShGradient.h): every texel a surface at
// 2 to 50 m (none sky, the worst case), once per completed probe.
void BM_ShGroundGradient(benchmark::State& state) {
    const int n = int(state.range(0));
    const auto rgb = randomMap(n);
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> d(2.0f, 50.0f);
    std::vector<float> distance(std::size_t(6) * n * n);
    for (auto& v : distance) v = d(rng);
    for (auto _ : state) benchmark::DoNotOptimize(amb::shGroundGradient(n, rgb, distance));
    state.SetItemsProcessed(state.iterations() * 6 * n * n);  // texels
}
BENCHMARK(BM_ShGroundGradient)->Arg(16)->Arg(32)->Unit(benchmark::kMicrosecond);

// One face (the per-frame cost when one face is captured per frame).
void BM_CubeMapProjectionOneFace(benchmark::State& state) {
    const int n = int(state.range(0));
    const auto rgb = randomMap(n);
    amb::CubeMapProjector projector(n);
    int face = 0;
    for (auto _ : state) {
        projector.addFace(face, rgb.data() + std::size_t(face) * n * n * 3);
        face = (face + 1) % 6;
        benchmark::ClobberMemory();
    }
}
BENCHMARK(BM_CubeMapProjectionOneFace)->Arg(16);

// One face holding the sun's texel, left out by its direction (a copy of the face, its texel
// filled from its neighbours): what the face with the sun costs over the others.
void BM_CubeMapProjectionSunFace(benchmark::State& state) {
    const int n = int(state.range(0));
    const auto rgb = randomMap(n);
    amb::CubeMapProjector projector(n);
    const glm::dvec3 sun = amb::cubeTexelDirection(0, n / 3, n / 2, n);
    for (auto _ : state) {
        projector.addFace(0, rgb.data(), sun);
        benchmark::ClobberMemory();
    }
}
BENCHMARK(BM_CubeMapProjectionSunFace)->Arg(16)->Arg(64);
BENCHMARK(BM_CubeMapProjectionOneFace)->Arg(64);

// Batch irradiance for many unit normals (structure of arrays, float).
void BM_ShIrradianceBatch(benchmark::State& state) {
    const std::size_t count = std::size_t(state.range(0));
    std::mt19937 rng(2);
    std::normal_distribution<float> g;
    std::vector<float> nx(count), ny(count), nz(count), er(count), eg(count), eb(count);
    for (std::size_t i = 0; i < count; ++i) {
        float x = g(rng), y = g(rng), z = g(rng);
        const float l = std::sqrt(x * x + y * y + z * z);
        nx[i] = x / l;
        ny[i] = y / l;
        nz[i] = z / l;
    }
    amb::ShRgb sh;
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (auto& c : sh.c) c = {u(rng), u(rng), u(rng)};
    for (auto _ : state) {
        amb::shIrradianceBatch(sh, count, nx.data(), ny.data(), nz.data(), er.data(), eg.data(),
                               eb.data());
        benchmark::DoNotOptimize(er.data());
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(state.iterations() * std::int64_t(count));  // normals
}
BENCHMARK(BM_ShIrradianceBatch)->Arg(1024)->Arg(16384);

// Building the R&H matrices (once per object per frame).
void BM_ShIrradianceMatrices(benchmark::State& state) {
    amb::ShRgb sh;
    for (int k = 0; k < 9; ++k) sh.c[k] = glm::vec3(0.1f * k, 0.2f, -0.1f * k);
    for (auto _ : state) benchmark::DoNotOptimize(amb::shIrradianceMatrices(sh));
}
BENCHMARK(BM_ShIrradianceMatrices);

// The automatic window on a ringing set (a directional light over a dim sky).
void BM_ShAutoWindow(benchmark::State& state) {
    amb::ShRgbD sh;
    amb::shAddDirectional(sh, {glm::normalize(glm::dvec3(0.3, 0.8, 0.5)), glm::dvec3(1.0)});
    sh.c[0] += glm::dvec3(0.02);
    for (auto _ : state) benchmark::DoNotOptimize(amb::shAutoWindow(sh));
}
BENCHMARK(BM_ShAutoWindow)->Unit(benchmark::kMillisecond);

}  // namespace
