// Deformation of 3D Gaussians at 1M and 6M (issue 17): the CPU path (gaussian::deform, TBB) in both SH
// modes and the GPU compute pass (gaussian::GpuGaussianDeformer, shaders/gaussian/deform.comp) in both SH
// modes, on N flat degree-3 Gaussians tangent to a unit Fibonacci sphere through the twisted 11³ Bernstein
// lattice of gaussian_bench. GPU: the cloud is uploaded once (GpuGaussianStore entry), a run is the
// dispatch plus glFinish (no read-back: the frame path), control points uploaded on the first run only
// (stamp fixed). On a software rasterizer (llvmpipe) the "GPU" is these CPU cores; the label says which.
//   build/release/tools/bench/bench_gaussian_deform --benchmark_min_time=0.01
#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <optional>
#include <random>
#include <vector>

#define GLM_ENABLE_EXPERIMENTAL
#include <glm/gtx/quaternion.hpp>

#include "runtime/gfx/context.h"
#include "runtime/gfx/gl.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gpu_deform.h"
#include "tools/bench/paper_case.h"

namespace {

using namespace sffd;

GaussianCloud sphere_gaussians(std::size_t count, int degree) {
    GaussianCloud g;
    g.sh_degree = degree;
    g.positions.reserve(count), g.scales.reserve(count), g.rotations.reserve(count), g.opacities.reserve(count);
    g.sh.reserve(count * std::size_t(sh_coeffs(degree)) * 3);
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(-0.5f, 0.5f);
    for (std::size_t i = 0; i < count; ++i) {
        const glm::dvec3 n = bench::fibonacci_sphere(i, count);
        g.positions.push_back(glm::vec3(n));
        g.scales.emplace_back(0.01f, 0.01f, 0.001f);
        g.rotations.push_back(glm::quat(glm::rotation(glm::dvec3(0, 0, 1), n)));
        g.opacities.push_back(0.8f);
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(u(rng));
    }
    return g;
}

// One cloud per size for the whole run (6M degree-3 Gaussians take 1.4 GB and seconds to make).
const GaussianCloud& cloud(std::size_t n) {
    static std::size_t made_n = 0;
    static GaussianCloud g;
    if (made_n != n) g = GaussianCloud{}, g = sphere_gaussians(n, 3), made_n = n;
    return g;
}

double process_cpu_s() {
    rusage ru{};
    getrusage(RUSAGE_SELF, &ru);
    return double(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) + 1e-6 * double(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

Lattice twisted() {
    Lattice l = ffd::make_lattice({-1.1, -1.1, -1.1}, {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)},
                                  {10, 10, 10});
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.6 / 1.1, glm::dvec3(0.0));
    return l;
}

gaussian::ShMode mode(std::int64_t m) { return m ? gaussian::ShMode::rotate_view : gaussian::ShMode::rotate_coefficients; }

// Args: Gaussians, SH mode (0 rotate the coefficients, 1 store the view rotation).
void BM_GaussianDeformCpu(benchmark::State& state) {
    const GaussianCloud& g = cloud(std::size_t(state.range(0)));
    const Lattice l = twisted();
    GaussianCloud out;
    gaussian::DeformOptions options;
    options.sh = mode(state.range(1));
    const double cpu0 = process_cpu_s();
    for (auto _ : state) {
        auto s = gaussian::deform(l, g, out, options);
        if (!s) state.SkipWithError(s.message().c_str());
        benchmark::DoNotOptimize(out.positions.data());
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * state.range(0));
    state.counters["process_cpu_ms_per_run"] = 1e3 * (process_cpu_s() - cpu0) / double(state.iterations());
}
BENCHMARK(BM_GaussianDeformCpu)->Args({1000000, 0})->Args({1000000, 1})->Args({6000000, 0})->Args({6000000, 1})
    ->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_GaussianDeformGpu(benchmark::State& state) {
    auto ctx = gfx::create_context({.headless = true, .width = 16, .height = 16, .debug = false});
    if (!ctx) {
        state.SkipWithError(ctx.message().c_str());
        return;
    }
    std::optional<gaussian::GpuGaussianDeformer> deformer;
    std::optional<gaussian::GpuGaussians> store;
    {
        auto d = gaussian::GpuGaussianDeformer::create();
        if (!d) {
            state.SkipWithError(d.message().c_str());
            return;
        }
        deformer.emplace(std::move(*d));
    }
    const GaussianCloud& g = cloud(std::size_t(state.range(0)));
    const Lattice l = twisted();
    store.emplace();
    if (auto s = gaussian::upload_rest(*store, g, 1); !s) state.SkipWithError(s.message().c_str());
    const std::vector<const Lattice*> ls = {&l};
    const std::vector<std::uint64_t> keys = {1}, stamps = {1};
    // Warm-up: compiles the specialised program, uploads the control points once.
    if (auto s = deformer->deform(*store, g.origin, ls, keys, stamps, mode(state.range(1))); !s) state.SkipWithError(s.message().c_str());
    glFinish();
    const double cpu0 = process_cpu_s();
    for (auto _ : state) {
        if (auto s = deformer->deform(*store, g.origin, ls, keys, stamps, mode(state.range(1))); !s) state.SkipWithError(s.message().c_str());
        glFinish();
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * state.range(0));
    state.counters["process_cpu_ms_per_run"] = 1e3 * (process_cpu_s() - cpu0) / double(state.iterations());
    state.SetLabel(ctx->renderer());
    store.reset();
    deformer.reset();
}
BENCHMARK(BM_GaussianDeformGpu)->Args({1000000, 0})->Args({1000000, 1})->Args({6000000, 0})->Args({6000000, 1})
    ->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
