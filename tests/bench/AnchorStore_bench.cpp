// AnchorStore_bench.cpp — cost of the anchor store: insert (new and refresh), find, advance, and
// interpolation per query in a populated store (the per-instance cost of vegetation and the car;
// the per-corner cost of terrain colouring, at fixed points), one by one and in batches as a
// frame asks, and the rebuild of the interpolation cache after the anchors change (once a frame
// while probes arrive).
//   build/bin/ambience_bench --benchmark_filter=Interpolat --benchmark_repetitions=9
//       --benchmark_report_aggregates_only=true   (one command line; target <= 100 ns a lookup)
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

// One lookup at a time, at 4096 random points near the track: `lookUp(store, x, z)`.
template <class LookUp>
void lookUpOneByOne(benchmark::State& state, LookUp lookUp) {
    AnchorStore store;
    populate(store);
    std::mt19937 rng(2);
    std::uniform_real_distribution<double> x(0.0, 1000.0), z(-40.0, 40.0);
    std::vector<std::pair<double, double>> queries(4096);
    for (auto& q : queries) q = {x(rng), z(rng)};
    std::size_t i = 0;
    for (auto _ : state) {
        const auto& q = queries[i++ & 4095];
        benchmark::DoNotOptimize(lookUp(store, q.first, q.second));
    }
    state.SetItemsProcessed(state.iterations());
    state.counters["anchors"] = double(store.size());
}

// A frame's batch, 1024 random points near the track: `lookUpMany(store, n, x, z, out)`; the
// time per lookup is the counter s_per_lookup (wall time).
template <class LookUpMany>
void lookUpInBatches(benchmark::State& state, LookUpMany lookUpMany) {
    AnchorStore store;
    populate(store);
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> x(0.0, 1000.0), z(-40.0, 40.0);
    constexpr std::size_t kBatch = 1024;
    std::vector<double> qx(kBatch), qz(kBatch);
    for (std::size_t i = 0; i < kBatch; ++i) qx[i] = x(rng), qz[i] = z(rng);
    std::vector<ShRgb> out(kBatch);
    for (auto _ : state) {
        lookUpMany(store, kBatch, qx.data(), qz.data(), out.data());
        benchmark::DoNotOptimize(out.data());
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(state.iterations() * std::int64_t(kBatch));
    state.counters["s_per_lookup"] = benchmark::Counter(
        double(kBatch) * double(state.iterations()),
        benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// A moving point (plants, the car): the smooth cells.
void BM_AnchorStoreInterpolate(benchmark::State& state) {
    lookUpOneByOne(state, [](const AnchorStore& s, double x, double z) {
        return s.interpolate(x, z);
    });
}
BENCHMARK(BM_AnchorStoreInterpolate);

// A fixed point (terrain corners, road vertices): the bilinear cells.
void BM_AnchorStoreInterpolateFixed(benchmark::State& state) {
    lookUpOneByOne(state, [](const AnchorStore& s, double x, double z) {
        return s.interpolateFixed(x, z);
    });
}
BENCHMARK(BM_AnchorStoreInterpolateFixed);

// A frame's objects through interpolateMany.
void BM_AnchorStoreInterpolateBatch(benchmark::State& state) {
    lookUpInBatches(state, [](const AnchorStore& s, std::size_t n, const double* x,
                              const double* z, ShRgb* out) { s.interpolateMany(n, x, z, out); });
}
BENCHMARK(BM_AnchorStoreInterpolateBatch)->Unit(benchmark::kMicrosecond);

// A frame's terrain corners through interpolateFixedMany.
void BM_AnchorStoreInterpolateFixedBatch(benchmark::State& state) {
    lookUpInBatches(state, [](const AnchorStore& s, std::size_t n, const double* x,
                              const double* z,
                              ShRgb* out) { s.interpolateFixedMany(n, x, z, out); });
}
BENCHMARK(BM_AnchorStoreInterpolateFixedBatch)->Unit(benchmark::kMicrosecond);

// A moving object's lookups: one a frame along the track at 30 m/s and 60 frames a second
// (0.5 m apart), so consecutive lookups share cells as a car's or a plant's do.
void BM_AnchorStoreInterpolateWalk(benchmark::State& state) {
    AnchorStore store;
    populate(store);
    double x = 0.0;
    for (auto _ : state) {
        x = x < 1000.0 ? x + 0.5 : 0.0;
        benchmark::DoNotOptimize(store.interpolate(x, 1.0 + 0.01 * x));
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_AnchorStoreInterpolateWalk);

// The interpolation cache rebuilt from ~3000 anchors (a relight that moves every anchor, then
// one lookup).
void BM_AnchorStoreInterpolationRebuild(benchmark::State& state) {
    AnchorStore store;
    populate(store);
    float f = 1.0f;
    for (auto _ : state) {
        f = f == 1.0f ? 1.01f : 1.0f;
        store.relight([f](const Anchor&) { return f; });
        benchmark::DoNotOptimize(store.interpolate(500.0, 0.0));
    }
    state.counters["anchors"] = double(store.size());
    state.counters["cache_kB"] = double(store.interpolationCacheBytes()) / 1024.0;
}
BENCHMARK(BM_AnchorStoreInterpolationRebuild)->Unit(benchmark::kMicrosecond);

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
