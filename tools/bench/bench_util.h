// Small pieces the GL and Gaussian benches share: process CPU time next to wall time, and the
// "create it or skip the benchmark with its message" step for contexts, renderers and deformers.
#pragma once

#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <optional>
#include <utility>

#include "runtime/core/result.h"

namespace sffd::bench {

// CPU time of the whole process (all TBB threads, llvmpipe's workers): the work done, meaningful on a
// loaded machine where wall time mostly measures the other processes.
inline double process_cpu_s() {
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    return double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
           1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

// The made object, or nullopt after state.SkipWithError(its message): `auto r = made_or_skip(state, f());
// if (!r) return;`. Declare a context before what it owns: locals are destroyed in reverse order.
template <class T>
std::optional<T> made_or_skip(benchmark::State& state, Result<T> made) {
    if (!made) {
        state.SkipWithError(made.message().c_str());
        return std::nullopt;
    }
    return std::optional<T>(std::move(*made));
}

}  // namespace sffd::bench

#include <algorithm>
#include <map>
#include <mutex>
#include <string>
#include <thread>

#include "runtime/simd/fma_peak.h"

namespace sffd::bench {

// The host's FMA floor for one SIMD target (multiply-adds a second on every core), measured once per
// process and target, the best of three (runtime/simd/fma_peak.h; bench_simd_floor prints it alone).
inline double fma_floor(const simd::Target& target) {
    static std::mutex m;
    static std::map<std::string, double> floors;
    const std::lock_guard<std::mutex> lock(m);
    auto it = floors.find(target.name);
    if (it == floors.end()) {
        // The best of three: a thread of the machine still busy (a TBB worker spinning after the last
        // parallel loop, another process) lowers one measurement, never raises it.
        double best = 0;
        for (int i = 0; i < 3; ++i) best = std::max(best, simd::measure_fma_peak(target, 0, 0.1).per_second);
        it = floors.emplace(target.name, best).first;
    }
    return it->second;
}

// Sets the counters of a compute-bound kernel's per-target benchmark, for `fmas` multiply-adds done in
// `wall` seconds and `cpu` seconds of process CPU time: gfma_s; floor_frac, the rate by wall time against
// every core's floor; floor_frac_cpu, the rate per CPU second against one core's floor (the same on a quiet
// machine, and the steadier of the two on a loaded one).
inline void report_floor_fraction(benchmark::State& state, const simd::Target& target, double fmas,
                                  double wall, double cpu) {
    const double floor = fma_floor(target);
    const double cores = double(std::max(1u, std::thread::hardware_concurrency()));
    state.counters["gfma_s"] = fmas / wall * 1e-9;
    state.counters["floor_frac"] = fmas / wall / floor;
    state.counters["floor_frac_cpu"] = fmas / cpu / (floor / cores);
}

}  // namespace sffd::bench
