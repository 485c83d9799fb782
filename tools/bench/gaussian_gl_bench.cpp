// GL renderer of 3D Gaussians (systems/gaussian/gl_render.h) on a headless EGL context: one frame at
// 1200x797 (the resolution of UnityGaussianSplatting's published 6.1M figure) of N flat Gaussians on
// the unit sphere (gaussians_from_splats of the built-in sphere), camera framing it. The cloud is
// uploaded once (upload_gl); a frame (draw_gl) is the compute projection, the depth sort (CPU: key
// readback + TBB sort + order upload; GPU: radix sort, no readback), the blending (instanced quads or
// the compute tile renderer) and the image readback. Stage times come from GlRenderer::stage_timing
// (a glFinish after each stage; GL timer queries are meaningless on llvmpipe). One untimed frame first.
//   build/release/tools/bench/bench_gaussian_gl --benchmark_filter='Frame/1000000/'
// Args: Gaussians, sort (0 CPU, 1 GPU), blend (0 quads, 1 tiles).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/radix_sort.h"
#include "systems/gaussian/from_splats.h"
#include "systems/gaussian/gl_render.h"
#include "tools/bench/bench_util.h"

namespace {

using namespace sffd;

using bench::process_cpu_s;

void BM_GaussianGlFrame(benchmark::State& state) {
    auto ctx = bench::made_or_skip(
        state, gfx::create_context({.headless = true, .width = 16, .height = 16, .debug = false}));
    if (!ctx) return;
    std::optional<gaussian::GlRenderer> r = bench::made_or_skip(state, gaussian::create_gl_renderer());
    if (!r) return;
    r->sort_path = state.range(1) ? gaussian::SortPath::gpu : gaussian::SortPath::cpu;
    r->blend_path = state.range(2) ? gaussian::BlendPath::tiles : gaussian::BlendPath::quads;
    r->stage_timing = true;
    const GaussianCloud g =
        gaussian::gaussians_from_splats(assets::make_sphere_cloud(std::size_t(state.range(0))));
    Camera cam;
    cam.eye = {0.0, 0.8, 3.2};
    cam.target = {0.0, 0.0, 0.0};
    cam.fov_y_degrees = 45.0f;
    gaussian::ReferenceOptions o;
    o.width = 1200, o.height = 797;
    double project_ms = 0.0, sort_ms = 0.0, blend_ms = 0.0, readback_ms = 0.0, tile_prepare_ms = 0.0;
    if (auto s = gaussian::upload_gl(*r, g); !s) state.SkipWithError(s.message().c_str());
    // One frame untimed: llvmpipe compiles each shader on its first dispatch (hundreds of ms).
    if (auto img = gaussian::draw_gl(*r, cam, o); !img) state.SkipWithError(img.message().c_str());
    const double cpu0 = process_cpu_s();
    for (auto _ : state) {
        auto img = gaussian::draw_gl(*r, cam, o);
        if (!img) state.SkipWithError(img.message().c_str());
        project_ms += r->project_ms, sort_ms += r->sort_ms, blend_ms += r->blend_ms,
            readback_ms += r->readback_ms;
        tile_prepare_ms += r->tile_prepare_ms;
    }
    const double runs = double(state.iterations());
    state.SetItemsProcessed(int64_t(state.iterations()) * state.range(0));
    state.counters["process_cpu_ms"] = 1e3 * (process_cpu_s() - cpu0) / runs;
    state.counters["project_ms"] = project_ms / runs;
    state.counters["sort_ms"] = sort_ms / runs;
    state.counters["blend_ms"] = blend_ms / runs;
    state.counters["readback_ms"] = readback_ms / runs;
    state.counters["tile_prepare_ms"] = tile_prepare_ms / runs;  // part of blend_ms
    state.counters["tile_entries"] = double(r->tile_entries);
    // The quads' fragment work in images of this size (-1: past 2^32 pixels): what draw_gaussians weighs
    // against quad_coverage_budget().
    const std::uint64_t covered = gaussian::read_covered_pixels(*r);
    state.counters["covered_images"] = covered == std::numeric_limits<std::uint64_t>::max()
                                           ? -1.0
                                           : double(covered) / (double(o.width) * double(o.height));
    state.SetLabel(ctx->renderer());
    r.reset();
}
BENCHMARK(BM_GaussianGlFrame)
    ->ArgsProduct({{100000, 1000000, 6000000}, {0, 1}, {0, 1}})
    ->ArgNames({"n", "gpu_sort", "tiles"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);

// The sort alone on the GPU (radix_sort of N random 32-bit keys with payloads, waited for with glFinish)
// next to what the CPU path's sort costs (TBB parallel_sort of N (key << 32 | index) pairs).
void BM_RadixSortGl(benchmark::State& state) {
    auto ctx = bench::made_or_skip(
        state, gfx::create_context({.headless = true, .width = 16, .height = 16, .debug = false}));
    if (!ctx) return;
    std::optional<gfx::RadixSorter> sorter = bench::made_or_skip(state, gfx::create_radix_sorter());
    if (!sorter) return;
    const std::size_t n = std::size_t(state.range(0));
    std::vector<std::uint32_t> keys(n), values(n);
    std::uint32_t x = 12345u;
    for (std::size_t i = 0; i < n; ++i)
        x = x * 1664525u + 1013904223u, keys[i] = x, values[i] = std::uint32_t(i);
    std::optional<gfx::Buffer> kb(gfx::Buffer::create("bench.keys")), vb(gfx::Buffer::create("bench.values"));
    glNamedBufferData(kb->id(), GLsizeiptr(n * 4), keys.data(), GL_DYNAMIC_COPY);
    glNamedBufferData(vb->id(), GLsizeiptr(n * 4), values.data(), GL_DYNAMIC_COPY);
    if (auto s = gfx::radix_sort(*sorter, kb->id(), vb->id(), std::uint32_t(n)); !s)
        state.SkipWithError(s.message().c_str());
    glFinish();  // untimed: shader compilation on first use, scratch allocation
    double cpu = 0.0;
    for (auto _ : state) {
        state.PauseTiming();
        glNamedBufferData(kb->id(), GLsizeiptr(n * 4), keys.data(), GL_DYNAMIC_COPY);
        glNamedBufferData(vb->id(), GLsizeiptr(n * 4), values.data(), GL_DYNAMIC_COPY);
        glFinish();
        state.ResumeTiming();
        const double cpu0 = process_cpu_s();
        if (auto s = gfx::radix_sort(*sorter, kb->id(), vb->id(), std::uint32_t(n)); !s)
            state.SkipWithError(s.message().c_str());
        glFinish();
        cpu += process_cpu_s() - cpu0;
    }
    state.counters["process_cpu_ms"] = 1e3 * cpu / double(state.iterations());
    state.SetItemsProcessed(int64_t(state.iterations()) * state.range(0));
    state.SetLabel(ctx->renderer());
    kb.reset(), vb.reset(), sorter.reset();
}
BENCHMARK(BM_RadixSortGl)
    ->Arg(1000000)
    ->Arg(6000000)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(2);

}  // namespace
