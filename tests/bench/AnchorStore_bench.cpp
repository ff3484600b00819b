// AnchorStore_bench.cpp — cost of the anchor store: insert (new and refresh), find, advance, and
// four-quadrant interpolation per query in a populated store (the per-corner cost of terrain
// colouring and the per-instance cost of vegetation).
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "lighting/AnchorStore.h"

namespace amb {
namespace {

ShRgb makeSh(float v) {
    ShRgb sh;
    for (int k = 0; k < kShCoefficients; ++k) sh.c[k] = glm::vec3(v, 0.5f * v, 2.0f * v);
    return sh;
}

// A store like the scheduler builds around a 1 km drive: every level's points within 3 cells of
// the track (about 3300 anchors).
void populate(AnchorStore& store) {
    for (int L = 0; L < store.levels(); ++L) {
        const double s = store.spacing_m(L);
        for (double x = 0.0; x <= 1000.0; x += s) {
            for (int dk = -3; dk <= 3; ++dk) {
                const LatticeKey key = store.keyNear(x, dk * s, L);
                if (!store.find(key))
                    store.insert(key, makeSh(float(x * 1e-3)), {x, 2.0, dk * s}, 1e6);
            }
        }
    }
    store.advance(10.0);
}

void BM_AnchorStoreInsertNew(benchmark::State& state) {
    std::int64_t n = 0;
    for (auto _ : state) {
        state.PauseTiming();
        AnchorStore store;
        state.ResumeTiming();
        for (int i = 0; i < 1000; ++i) {
            benchmark::DoNotOptimize(store.insert({4, i % 40, i / 40}, makeSh(1.0f),
                                                  {3.0 * (i % 40), 2.0, 3.0 * (i / 40)}, 100.0));
        }
        n += 1000;
    }
    state.SetItemsProcessed(n);
}
BENCHMARK(BM_AnchorStoreInsertNew)->Unit(benchmark::kMicrosecond);

void BM_AnchorStoreRefresh(benchmark::State& state) {
    AnchorStore store;
    populate(store);
    std::vector<LatticeKey> keys;
    store.forEach([&](const Anchor& a) { keys.push_back(a.key); });
    std::size_t i = 0;
    for (auto _ : state) {
        const LatticeKey& k = keys[i++ % keys.size()];
        benchmark::DoNotOptimize(store.insert(k, makeSh(2.0f), {0.0, 2.0, 0.0}, 100.0));
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_AnchorStoreRefresh);

void BM_AnchorStoreFind(benchmark::State& state) {
    AnchorStore store;
    populate(store);
    std::mt19937 rng(1);
    std::uniform_int_distribution<int> i(-10, 340), k(-10, 10);
    for (auto _ : state) benchmark::DoNotOptimize(store.find({4, i(rng), k(rng)}));
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_AnchorStoreFind);

void BM_AnchorStoreAdvance(benchmark::State& state) {
    AnchorStore store;
    populate(store);
    double t = 10.0;
    for (auto _ : state) store.advance(t += 1.0 / 60.0);
    state.counters["anchors"] = double(store.size());
}
BENCHMARK(BM_AnchorStoreAdvance)->Unit(benchmark::kMicrosecond);

void BM_AnchorStoreInterpolate(benchmark::State& state) {
    AnchorStore store;
    populate(store);
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> x(0.0, 1000.0), z(-40.0, 40.0);
    std::vector<std::pair<double, double>> queries(4096);
    for (auto& q : queries) q = {x(rng), z(rng)};
    std::size_t i = 0;
    for (auto _ : state) {
        const auto& q = queries[i++ & 4095];
        benchmark::DoNotOptimize(store.interpolate(q.first, q.second));
    }
    state.SetItemsProcessed(state.iterations());
    state.counters["anchors"] = double(store.size());
}
BENCHMARK(BM_AnchorStoreInterpolate);

// Far from the track: coarse levels only, the longest searches.
void BM_AnchorStoreInterpolateSparse(benchmark::State& state) {
    AnchorStore store;
    populate(store);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> x(0.0, 1000.0), z(200.0, 600.0);
    std::vector<std::pair<double, double>> queries(4096);
    for (auto& q : queries) q = {x(rng), z(rng)};
    std::size_t i = 0;
    for (auto _ : state) {
        const auto& q = queries[i++ & 4095];
        benchmark::DoNotOptimize(store.interpolate(q.first, q.second));
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_AnchorStoreInterpolateSparse);

}  // namespace
}  // namespace amb
