// The engine's drawing of 3D Gaussians (systems/splat_render/gaussian_draw.h, through render_system's
// Gaussian pass) on a headless EGL context: one frame at 1200x797 (the resolution of
// UnityGaussianSplatting's published 6.1M figure) of N flat Gaussians on the unit sphere
// (gaussians_from_splats of the built-in sphere), camera framing it. The cloud is made resident once by
// residency_system (untimed); a frame is render_system (the compute projection, the depth sort (CPU: key
// readback + TBB sort + order upload; GPU: radix sort, no readback), the blending (instanced quads or the
// compute tile renderer), the composite) and capture_frame's readback. Stage times come from
// GlRenderer::stage_timing (a glFinish after each stage; GL timer queries are meaningless on llvmpipe).
// One untimed frame first.
//   build/release/tools/bench/bench_gaussian_gl --benchmark_filter='Frame/n:1000000/'
// Args: Gaussians, sort (0 CPU, 1 GPU), blend (0 quads, 1 tiles).
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "runtime/app/app.h"
#include "runtime/assets/builtin_scenes.h"
#include "runtime/ecs/registry.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/radix_sort.h"
#include "runtime/scene/camera.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/from_splats.h"
#include "systems/residency/residency_system.h"
#include "systems/splat_render/gaussian_draw.h"
#include "systems/splat_render/gaussian_pass.h"
#include "systems/splat_render/splat_render.h"
#include "tools/bench/bench_util.h"

namespace {

using namespace sffd;

using bench::process_cpu_s;

void BM_GaussianGlFrame(benchmark::State& state) {
    auto ctx = bench::made_or_skip(
        state, gfx::create_context({.headless = true, .width = 16, .height = 16, .debug = false}));
    if (!ctx) return;
    std::optional<ecs::Registry> reg;
    reg.emplace();
    Camera cam;
    cam.eye = {0.0, 0.8, 3.2};
    cam.target = {0.0, 0.0, 0.0};
    cam.fov_y_degrees = 45.0f;
    reg->emplace<Camera>(reg->create(), cam);
    reg->emplace<GaussianCloud>(reg->create(), gaussian::gaussians_from_splats(
                                                   assets::make_sphere_cloud(std::size_t(state.range(0)))));
    render::RenderSettings settings;
    settings.width = 1200, settings.height = 797, settings.quality = render::Quality::hq;
    reg->set_resource<render::RenderSettings>(settings);
    render::GlRenderer* r =
        bench::made_or_skip(state, render::gaussian_pass_renderer(*reg)).value_or(nullptr);
    if (!r) return;
    r->sort_path = state.range(1) ? render::SortPath::gpu : render::SortPath::cpu;
    r->blend_path = state.range(2) ? render::BlendPath::tiles : render::BlendPath::quads;
    r->stage_timing = true;
    residency_system(*reg, FrameContext{});  // the one upload (untimed)
    double project_ms = 0.0, sort_ms = 0.0, blend_ms = 0.0, readback_ms = 0.0, tile_prepare_ms = 0.0;
    std::uint64_t tile_clouds = 0;
    const auto frame = [&]() -> bool {
        render::render_system(*reg, FrameContext{});
        const auto t = std::chrono::steady_clock::now();
        auto img = render::capture_frame(*reg);
        if (!img) state.SkipWithError(img.message().c_str());
        readback_ms +=
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
        return bool(img);
    };
    // One frame untimed: llvmpipe compiles each shader on its first dispatch (hundreds of ms).
    if (!frame()) return;
    readback_ms = 0.0;
    const double cpu0 = process_cpu_s();
    for (auto _ : state) {
        if (!frame()) break;
        project_ms += r->project_ms, sort_ms += r->sort_ms, blend_ms += r->blend_ms;
        tile_prepare_ms += r->tile_prepare_ms;
        tile_clouds += r->last_blend == render::BlendPath::tiles;
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
    state.counters["tile_frames"] = double(tile_clouds);  // frames the tile renderer blended
    // The quads' fragment work in images of this size (-1: past 2^32 pixels): what draw_gaussians weighs
    // against quad_coverage_budget().
    const std::uint64_t covered = render::read_covered_pixels(*r);
    state.counters["covered_images"] =
        covered == std::numeric_limits<std::uint64_t>::max()
            ? -1.0
            : double(covered) / (double(settings.width) * double(settings.height));
    state.SetLabel(ctx->renderer());
    render::release_render_state(*reg);
    reg.reset();  // the residency's buffers, while the context is current
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
