#include "runtime/simd/fma_peak.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "runtime/simd/fma_peak.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace sffd::simd::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// kChains independent accumulators hide the FMA latency (4-5 cycles on two pipes needs 8-10 in flight);
// 12 fit in the 16 registers of sse4/avx2 with the two constants. Returns the multiply-adds of one
// iteration (chains times lanes); the sum is
// written out so the chains are not optimised away.
constexpr int kChains = kFmaPeakChains;
int FmaChains(std::uint64_t iterations, float* sink) {
    const hn::ScalableTag<float> d;
    const auto m = hn::Set(d, 0.9999999f), c = hn::Set(d, 1e-7f);
    auto a0 = hn::Set(d, 0.0f), a1 = hn::Set(d, 0.1f), a2 = hn::Set(d, 0.2f), a3 = hn::Set(d, 0.3f);
    auto a4 = hn::Set(d, 0.4f), a5 = hn::Set(d, 0.5f), a6 = hn::Set(d, 0.6f), a7 = hn::Set(d, 0.7f);
    auto a8 = hn::Set(d, 0.8f), a9 = hn::Set(d, 0.9f), a10 = hn::Set(d, 1.0f), a11 = hn::Set(d, 1.1f);
    for (std::uint64_t i = 0; i < iterations; ++i) {
        a0 = hn::MulAdd(a0, m, c), a1 = hn::MulAdd(a1, m, c), a2 = hn::MulAdd(a2, m, c);
        a3 = hn::MulAdd(a3, m, c), a4 = hn::MulAdd(a4, m, c), a5 = hn::MulAdd(a5, m, c);
        a6 = hn::MulAdd(a6, m, c), a7 = hn::MulAdd(a7, m, c), a8 = hn::MulAdd(a8, m, c);
        a9 = hn::MulAdd(a9, m, c), a10 = hn::MulAdd(a10, m, c), a11 = hn::MulAdd(a11, m, c);
#if HWY_TARGET == HWY_SCALAR
        // An empty asm with the accumulators as operands keeps the compiler from vectorising the 12
        // chains of the one-lane target into wider registers than the target has.
#if HWY_ARCH_X86
#define SFFD_KEEP(v) asm volatile("" : "+x"(v.raw))
#elif HWY_ARCH_ARM_A64
#define SFFD_KEEP(v) asm volatile("" : "+w"(v.raw))
#else
#define SFFD_KEEP(v) (void)0
#endif
        SFFD_KEEP(a0);
        SFFD_KEEP(a1);
        SFFD_KEEP(a2);
        SFFD_KEEP(a3);
        SFFD_KEEP(a4);
        SFFD_KEEP(a5);
        SFFD_KEEP(a6);
        SFFD_KEEP(a7);
        SFFD_KEEP(a8);
        SFFD_KEEP(a9);
        SFFD_KEEP(a10);
        SFFD_KEEP(a11);
#undef SFFD_KEEP
#endif
    }
    const auto s = hn::Add(
        hn::Add(hn::Add(a0, a1), hn::Add(a2, a3)),
        hn::Add(hn::Add(hn::Add(a4, a5), hn::Add(a6, a7)), hn::Add(hn::Add(a8, a9), hn::Add(a10, a11))));
    *sink = hn::GetLane(hn::SumOfLanes(d, s));
    return kChains * int(hn::Lanes(d));
}

}  // namespace sffd::simd::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

#include <algorithm>
#include <chrono>
#include <ctime>
#include <thread>
#include <vector>

namespace sffd::simd {

HWY_EXPORT(FmaChains);

namespace {

double thread_cpu_seconds() {
    timespec ts{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

}  // namespace

FmaPeak measure_fma_peak(const Target& target, int threads, double seconds) {
    const ScopedTarget pinned(target);
    const int n = threads > 0 ? threads : int(std::max(1u, std::thread::hardware_concurrency()));
    float sink = 0;
    // Calibrate one thread's iterations to a tenth of the time, then run every thread that long ten times.
    std::uint64_t iters = 1 << 16;
    int per_iteration = 1;
    for (;;) {
        const auto t0 = std::chrono::steady_clock::now();
        per_iteration = HWY_DYNAMIC_DISPATCH(FmaChains)(iters, &sink);
        const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (dt > seconds / 10 || iters > (std::uint64_t(1) << 40)) {
            iters = std::uint64_t(double(iters) * seconds / std::max(dt, 1e-9) / 2.0) + 1;
            break;
        }
        iters *= 4;
    }
    // Each thread's rate over its own CPU time, summed: what the cores sustain, not what a busy machine
    // happens to give this process (kernel benchmarks are compared with it on a quiet machine).
    std::vector<std::thread> pool;
    std::vector<float> sinks(std::size_t(n), 0.0f);
    std::vector<double> rate(std::size_t(n), 0.0);
    for (int t = 0; t < n; ++t)
        pool.emplace_back([&, t] {
            const double c0 = thread_cpu_seconds();
            HWY_DYNAMIC_DISPATCH(FmaChains)(iters, &sinks[std::size_t(t)]);
            rate[std::size_t(t)] = double(iters) * double(per_iteration) / (thread_cpu_seconds() - c0);
        });
    for (auto& th : pool) th.join();
    FmaPeak p;
    p.target = target.name;
    p.threads = n;
    p.lanes = per_iteration / kFmaPeakChains;
    for (double r : rate) p.per_second += r;
    return p;
}

}  // namespace sffd::simd

#endif  // HWY_ONCE
