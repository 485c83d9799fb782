// GL renderer of 3D Gaussians (systems/gaussian/gl_render.h) on a headless EGL context: one frame at
// 1200x797 (the resolution of UnityGaussianSplatting's published 6.1M figure) of N flat Gaussians on
// the unit sphere (gaussians_from_splats of the built-in sphere), camera framing it. The cloud is
// uploaded once (upload_gl); a frame (draw_gl) is the compute projection, the readback + CPU depth sort
// + order upload (`sort_ms`), the splatting and the image readback.
//   build/release/tools/bench/bench_gaussian_gl --benchmark_repetitions=3
#include <benchmark/benchmark.h>

#include <optional>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/gfx/context.h"
#include "systems/gaussian/from_splats.h"
#include "systems/gaussian/gl_render.h"

namespace {

using namespace sffd;

void BM_GaussianGlFrame(benchmark::State& state) {
    auto ctx = gfx::create_context({.headless = true, .width = 16, .height = 16, .debug = false});
    if (!ctx) {
        state.SkipWithError(ctx.message().c_str());
        return;
    }
    std::optional<gaussian::GlRenderer> r;
    {
        auto made = gaussian::create_gl_renderer();
        if (!made) {
            state.SkipWithError(made.message().c_str());
            return;
        }
        r.emplace(std::move(*made));
    }
    const GaussianCloud g = gaussian::gaussians_from_splats(assets::make_sphere_cloud(std::size_t(state.range(0))));
    Camera cam;
    cam.eye = {0.0, 0.8, 3.2};
    cam.target = {0.0, 0.0, 0.0};
    cam.fov_y_degrees = 45.0f;
    gaussian::ReferenceOptions o;
    o.width = 1200, o.height = 797;
    double sort_ms = 0.0;
    if (auto s = gaussian::upload_gl(*r, g); !s) state.SkipWithError(s.message().c_str());
    for (auto _ : state) {
        auto img = gaussian::draw_gl(*r, cam, o);
        if (!img) state.SkipWithError(img.message().c_str());
        sort_ms += r->sort_ms;
    }
    state.SetItemsProcessed(int64_t(state.iterations()) * state.range(0));
    state.counters["sort_ms"] = sort_ms / double(state.iterations());
    state.SetLabel(ctx->renderer());
    r.reset();
}
BENCHMARK(BM_GaussianGlFrame)->Arg(100000)->Arg(1000000)->Arg(6000000)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

}  // namespace
