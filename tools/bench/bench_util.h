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
