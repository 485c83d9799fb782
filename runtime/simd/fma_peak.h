// The host's floor for compute-bound kernels: how many fused multiply-adds per second one SIMD target
// sustains on every core, measured by running independent MulAdd chains (no loads) on all threads. Kernel
// benchmarks state their speed as a fraction of it, which stays comparable across machines and targets
// where absolute times do not. On targets without an FMA instruction (sse4, scalar) a "fused" multiply-add
// is Highway's MulAdd there: a multiply and an add, counted as one.
#pragma once

#include "runtime/simd/simd.h"

namespace sffd::simd {

// Independent multiply-add chains the measurement keeps in flight (fma_peak.cpp).
inline constexpr int kFmaPeakChains = 12;

struct FmaPeak {
    std::string target;
    int threads = 0;
    double per_second = 0;  // multiply-adds (one per lane) per second, all threads together
    int lanes = 0;          // float lanes of the target
};

// Runs for about `seconds` on `threads` threads (0: every hardware thread) with `target` pinned.
FmaPeak measure_fma_peak(const Target& target, int threads = 0, double seconds = 0.25);

}  // namespace sffd::simd
