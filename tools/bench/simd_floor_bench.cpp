// The host's FMA floor per SIMD target (runtime/simd/fma_peak.h), side by side in one run: the number
// compute-bound kernels state their speed against. Counters: gfma_s (10^9 multiply-adds a second, all
// threads), lanes, threads.
//   build/release/tools/bench/bench_simd_floor
#include <string>

#include <benchmark/benchmark.h>

#include "runtime/simd/fma_peak.h"

namespace {

void floor_of(benchmark::State& state, sffd::simd::Target target) {
    // The best run: a busy thread of the machine lowers a measurement, never raises it (as bench_util.h's
    // fma_floor, which the kernels' fractions use).
    sffd::simd::FmaPeak p;
    for (auto _ : state)
        if (const auto m = sffd::simd::measure_fma_peak(target); m.per_second > p.per_second) p = m;
    state.counters["gfma_s"] = p.per_second * 1e-9;
    state.counters["lanes"] = p.lanes;
    state.counters["threads"] = p.threads;
}

const int registered = [] {
    for (const sffd::simd::Target& t : sffd::simd::runnable())
        benchmark::RegisterBenchmark(("BM_FmaFloor/simd:" + t.name).c_str(), floor_of, t)
            ->Iterations(3)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
    return 0;
}();

}  // namespace
