// Deformation of 3D Gaussians at 1M and 6M: the CPU path (gaussian::deform, TBB) in both SH
// modes and the GPU compute pass (gaussian::GpuGaussianDeformer, shaders/gaussian/deform.comp) in both SH
// modes and at SH degree 0 (nothing to rotate: no frames, no coefficients, a program of its own), on N
// flat degree-3 Gaussians tangent to a unit Fibonacci sphere through the twisted 11³ Bernstein
// lattice of gaussian_bench. GPU: the cloud is uploaded once (GpuGaussianStore entry), a run is the
// dispatch plus glFinish (no read-back: the frame path), control points uploaded on the first run only
// (stamp fixed). On a software rasterizer (llvmpipe) the "GPU" is these CPU cores; the label says which.
// The 1M case of the README's CPU claim (SH 3, coefficients rotated, vectorised kernel) also runs once per
// SIMD target this CPU runs, pinned (BM_GaussianDeformCpu/1000000/0/0/simd:avx2, ...; runtime/simd/simd.h).
//   build/release/tools/bench/bench_gaussian_deform --benchmark_min_time=0.01
#include <benchmark/benchmark.h>

#include <chrono>
#include <optional>
#include <string>
#include <vector>

#include "runtime/gfx/context.h"
#include "runtime/gfx/gl.h"
#include "runtime/simd/simd.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gpu_deform.h"
#include "tools/bench/bench_util.h"
#include "tools/bench/fma_model.h"
#include "tools/bench/gaussian_case.h"

namespace {

using namespace sffd;

using bench::process_cpu_s;
using bench::sphere_gaussians;

// One cloud per size and SH degree for the whole run (6M degree-3 Gaussians take 1.4 GB and seconds to
// make).
const GaussianCloud& cloud(std::size_t n, int degree = 3) {
    static std::size_t made_n = 0;
    static int made_degree = -1;
    static GaussianCloud g;
    if (made_n != n || made_degree != degree)
        g = GaussianCloud{}, g = sphere_gaussians(n, degree), made_n = n, made_degree = degree;
    return g;
}

gaussian::ShMode mode(std::int64_t m) {
    return m ? gaussian::ShMode::rotate_view : gaussian::ShMode::rotate_coefficients;
}

// Args: Gaussians, SH mode (0 rotate the coefficients, 1 store the view rotation), shape kernel (0 the
// vectorised float kernel, 1 the double-precision per-Gaussian reference: the A/B of the two).
void BM_GaussianDeformCpu(benchmark::State& state) {
    bench::run_cpu_deform(state, cloud(std::size_t(state.range(0))), mode(state.range(1)),
                          state.range(2) != 0);
}
BENCHMARK(BM_GaussianDeformCpu)
    ->Args({1000000, 0, 0})
    ->Args({1000000, 1, 0})
    ->Args({1000000, 0, 1})
    ->Args({1000000, 1, 1})
    ->Args({6000000, 0, 0})
    ->Args({6000000, 1, 0})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The same run as BM_GaussianDeformCpu/1000000/0/0 with the kernels pinned to one SIMD target, and its
// counted work as a fraction of that target's FMA floor (tools/bench/fma_model.h: a lower bound).
void BM_GaussianDeformCpuSimd(benchmark::State& state, const simd::Target& target) {
    const simd::ScopedTarget pin(target);
    const GaussianCloud& g = cloud(1000000);
    const Lattice l = bench::twisted_gaussian_lattice();
    GaussianCloud out;
    gaussian::DeformOptions options;
    options.sh = mode(0);
    // Untimed: sizes `out` (as run_cpu_deform does) and measures the floor before the timed runs.
    if (auto s = gaussian::deform(l, g, out, options); !s) return state.SkipWithError(s.message().c_str());
    (void)bench::fma_floor(target);
    const double cpu0 = process_cpu_s();
    const auto t0 = std::chrono::steady_clock::now();
    for (auto _ : state) {
        auto s = gaussian::deform(l, g, out, options);
        if (!s) state.SkipWithError(s.message().c_str());
        benchmark::DoNotOptimize(out.positions.data());
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double cpu = process_cpu_s() - cpu0, runs = double(state.iterations());
    state.SetItemsProcessed(int64_t(state.iterations()) * int64_t(g.size()));
    state.counters["process_cpu_ms_per_run"] = 1e3 * cpu / runs;
    state.SetLabel(simd::chosen());
    const double per = bench::bernstein_multiply_adds(l, false) + bench::gaussian_extra_multiply_adds(3);
    bench::report_floor_fraction(state, target, per * double(g.size()) * runs, wall, cpu);
    state.counters["madds_per_gaussian"] = per;
}
const bool kSimdRegistered = [] {
    for (const simd::Target& t : simd::runnable())
        benchmark::RegisterBenchmark(("BM_GaussianDeformCpu/1000000/0/0/simd:" + t.name).c_str(),
                                     BM_GaussianDeformCpuSimd, t)
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
    return true;
}();

// Args: Gaussians, SH mode (as above), SH degree (0: no view-dependent colour, nothing to rotate, the
// profile's synthetic-gaussians scenes).
void BM_GaussianDeformGpu(benchmark::State& state) {
    auto ctx = bench::made_or_skip(
        state, gfx::create_context({.headless = true, .width = 16, .height = 16, .debug = false}));
    if (!ctx) return;
    std::optional<gaussian::GpuGaussianDeformer> deformer =
        bench::made_or_skip(state, gaussian::GpuGaussianDeformer::create());
    if (!deformer) return;
    std::optional<gaussian::GpuGaussians> store;
    const GaussianCloud& g = cloud(std::size_t(state.range(0)), int(state.range(2)));
    const Lattice l = bench::twisted_gaussian_lattice();
    store.emplace();
    if (auto s = gaussian::upload_rest(*store, g, 1); !s) state.SkipWithError(s.message().c_str());
    const std::vector<const Lattice*> ls = {&l};
    const std::vector<std::uint64_t> keys = {1}, stamps = {1};
    // Warm-up: compiles the specialised program, uploads the control points once.
    if (auto s = deformer->deform(*store, g.origin, ls, keys, stamps, mode(state.range(1))); !s)
        state.SkipWithError(s.message().c_str());
    glFinish();
    const double cpu0 = process_cpu_s();
    for (auto _ : state) {
        if (auto s = deformer->deform(*store, g.origin, ls, keys, stamps, mode(state.range(1))); !s)
            state.SkipWithError(s.message().c_str());
        glFinish();
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * state.range(0));
    state.counters["process_cpu_ms_per_run"] = 1e3 * (process_cpu_s() - cpu0) / double(state.iterations());
    state.SetLabel(ctx->renderer());
    store.reset();
    deformer.reset();
}
BENCHMARK(BM_GaussianDeformGpu)
    ->Args({1000000, 0, 3})
    ->Args({1000000, 1, 3})
    ->Args({1000000, 1, 0})
    ->Args({6000000, 0, 3})
    ->Args({6000000, 1, 3})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
