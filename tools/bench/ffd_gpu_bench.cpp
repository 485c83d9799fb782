// FFD GPU benchmarks (headless EGL; on this machine Mesa llvmpipe, i.e. the GPU path runs on the CPU
// cores): the compute pass on the paper's case (59,650 splats, 11x11x11 lattice, global twist, positions +
// normals + axes), B-spline, 1M splats; and paper mode (deformation in the vertex shader every frame)
// against drawing the compute pass's output. Times are glFinish-bounded wall clock.
//   build/<dir>/tools/bench/bench_ffd_gpu --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <optional>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "runtime/gfx/context.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/render_target.h"
#include "shaders/common/bindings.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/ffd/paper_mode.h"
#include "tools/bench/paper_case.h"

namespace {

using namespace sffd;

struct Gl {
    std::optional<gfx::GlContext> ctx;
    std::optional<ffd::GpuDeformer> deformer;
    std::optional<ffd::PaperModeRenderer> paper;
    std::optional<gfx::RenderTarget> target;
    bool ok = false;
    std::string error;
};

Gl& gl() {
    static Gl g = [] {
        Gl s;
        auto c = gfx::create_context({.headless = true, .width = 512, .height = 512, .debug = false});
        if (!c) return s.error = c.message(), std::move(s);
        s.ctx.emplace(std::move(*c));
        auto d = ffd::GpuDeformer::create();
        if (!d) return s.error = d.message(), std::move(s);
        s.deformer.emplace(std::move(*d));
        auto p = ffd::PaperModeRenderer::create();
        if (!p) return s.error = p.message(), std::move(s);
        s.paper.emplace(std::move(*p));
        auto t = gfx::RenderTarget::create({.label = "bench.ffd",
                                            .width = 512,
                                            .height = 512,
                                            .color = {{"color", gfx::ColorFormat::rgba8}}});
        if (!t) return s.error = t.message(), std::move(s);
        s.target.emplace(std::move(*t));
        s.ok = true;
        return s;
    }();
    return g;
}

struct Splats {
    gfx::Buffer rest, deformed;
    std::uint32_t count = 0;
};

Splats& splats(std::size_t n) {
    static std::vector<std::pair<std::size_t, Splats>> cache;
    for (auto& [k, v] : cache)
        if (k == n) return v;
    std::vector<gpu::GpuSplat> packed(n);
    for (std::size_t i = 0; i < n; ++i) {
        const glm::vec3 p(bench::fibonacci_sphere(i, n));
        const glm::vec3 t =
            glm::normalize(glm::cross(p, std::abs(p.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0))) *
            0.01f;
        const glm::vec3 b = glm::cross(p, t);
        packed[i] = {{p.x, p.y, p.z, 0}, {p.x, p.y, p.z, 1}, {t.x, t.y, t.z, 0}, {b.x, b.y, b.z, 0}};
    }
    cache.emplace_back(n, Splats{});
    Splats& s = cache.back().second;
    s.rest = gfx::Buffer::create("bench.rest");
    s.deformed = gfx::Buffer::create("bench.deformed");
    glNamedBufferData(s.rest.id(), GLsizeiptr(n * sizeof(gpu::GpuSplat)), packed.data(), GL_STATIC_DRAW);
    glNamedBufferData(s.deformed.id(), GLsizeiptr(n * sizeof(gpu::GpuSplat)), nullptr, GL_DYNAMIC_COPY);
    s.count = std::uint32_t(n);
    return s;
}

Lattice twisted(LatticeBasis basis) { return bench::twisted_lattice(basis); }

void compute(benchmark::State& state, LatticeBasis basis, std::size_t n,
             ffd::GpuBernsteinKernel kernel = ffd::GpuBernsteinKernel::automatic) {
    Gl& g = gl();
    if (!g.ok) return state.SkipWithError(g.error.c_str());
    g.deformer->set_bernstein_kernel(kernel);
    Splats& s = splats(n);
    const Lattice l = twisted(basis);
    // Control points are uploaded once (stamp 1), as in the frame loop when only the view changes they
    // are not re-sent; each iteration is one dispatch + glFinish. Warm-up: compiles the program specialised
    // for this lattice shape.
    (void)g.deformer->dispatch(l, 1, 1, {}, s.rest.id(), s.deformed.id(), s.count);
    glFinish();
    // The wall time includes glFinish's round trip (tens of microseconds on a GPU, more than the kernels'
    // differences at 1M splats); gpu_ms is the dispatch alone, from a timer query (on a GPU: llvmpipe's
    // queries do not time its compute work, read the wall time there).
    GLuint query = 0;
    glCreateQueries(GL_TIME_ELAPSED, 1, &query);
    double gpu_ns = 0.0;
    for (auto _ : state) {
        glBeginQuery(GL_TIME_ELAPSED, query);
        (void)g.deformer->dispatch(l, 1, 1, {}, s.rest.id(), s.deformed.id(), s.count);
        glEndQuery(GL_TIME_ELAPSED);
        glFinish();
        GLuint64 ns = 0;
        glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
        gpu_ns += double(ns);
    }
    glDeleteQueries(1, &query);
    state.counters["points/s"] = benchmark::Counter(double(n), benchmark::Counter::kIsIterationInvariantRate);
    state.counters["gpu_ms"] = benchmark::Counter(gpu_ns * 1e-6, benchmark::Counter::kAvgIterations);
}

const glm::mat4 kViewProj = glm::scale(glm::mat4(1.0f), glm::vec3(0.6f, 0.6f, -0.3f));

void paper_frame(benchmark::State& state, int passes) {
    Gl& g = gl();
    if (!g.ok) return state.SkipWithError(g.error.c_str());
    Splats& s = splats(59650);
    const Lattice l = twisted(LatticeBasis::bernstein);
    const float black[4] = {0, 0, 0, 1};
    (void)g.paper->draw(l, 1, {}, s.rest.id(), s.count, kViewProj, 2.0f);  // warm-up
    glFinish();
    for (auto _ : state) {
        g.target->bind();
        g.target->clear_color("color", black);
        g.target->clear_depth();
        for (int p = 0; p < passes; ++p) (void)g.paper->draw(l, 1, {}, s.rest.id(), s.count, kViewProj, 2.0f);
        glFinish();
    }
}

void skinning_frame(benchmark::State& state, int passes) {
    Gl& g = gl();
    if (!g.ok) return state.SkipWithError(g.error.c_str());
    Splats& s = splats(59650);
    const Lattice l = twisted(LatticeBasis::bernstein);
    (void)g.deformer->dispatch(l, 1, 1, {}, s.rest.id(), s.deformed.id(), s.count);  // once per edit
    glFinish();
    const float black[4] = {0, 0, 0, 1};
    for (auto _ : state) {
        g.target->bind();
        g.target->clear_color("color", black);
        g.target->clear_depth();
        for (int p = 0; p < passes; ++p) g.paper->draw_deformed(s.deformed.id(), s.count, kViewProj, 2.0f);
        glFinish();
    }
}

void BM_GpuCompute_Bernstein11_Full(benchmark::State& s) { compute(s, LatticeBasis::bernstein, 59650); }
void BM_GpuCompute_BSpline11_Full(benchmark::State& s) { compute(s, LatticeBasis::bspline, 59650); }
void BM_GpuCompute_Bernstein11_1M_Full(benchmark::State& s) { compute(s, LatticeBasis::bernstein, 1000000); }
void BM_GpuCompute_BSpline11_1M_Full(benchmark::State& s) { compute(s, LatticeBasis::bspline, 1000000); }
// The two Bernstein kernels forced (automatic: shared on a hardware GPU, direct on llvmpipe).
void BM_GpuCompute_Bernstein11_Full_Direct(benchmark::State& s) {
    compute(s, LatticeBasis::bernstein, 59650, ffd::GpuBernsteinKernel::direct);
}
void BM_GpuCompute_Bernstein11_Full_Shared(benchmark::State& s) {
    compute(s, LatticeBasis::bernstein, 59650, ffd::GpuBernsteinKernel::shared);
}
void BM_GpuCompute_Bernstein11_1M_Full_Direct(benchmark::State& s) {
    compute(s, LatticeBasis::bernstein, 1000000, ffd::GpuBernsteinKernel::direct);
}
void BM_GpuCompute_Bernstein11_1M_Full_Shared(benchmark::State& s) {
    compute(s, LatticeBasis::bernstein, 1000000, ffd::GpuBernsteinKernel::shared);
}
// The B-spline grid read through the same kernels (set_bernstein_kernel picks for both bases), and packed
// in runs along u (automatic's choice).
void BM_GpuCompute_BSpline11_1M_Full_Direct(benchmark::State& s) {
    compute(s, LatticeBasis::bspline, 1000000, ffd::GpuBernsteinKernel::direct);
}
void BM_GpuCompute_BSpline11_1M_Full_Shared(benchmark::State& s) {
    compute(s, LatticeBasis::bspline, 1000000, ffd::GpuBernsteinKernel::shared);
}
void BM_GpuCompute_BSpline11_1M_Full_Packed(benchmark::State& s) {
    compute(s, LatticeBasis::bspline, 1000000, ffd::GpuBernsteinKernel::packed);
}
// A frame of 3 splat passes (visibility, attributes, shading in the HQ renderer): paper mode deforms in
// every pass; skinning-style reads the compute output (deformation cost paid once per edit).
void BM_PaperMode_Frame_3Passes(benchmark::State& s) { paper_frame(s, 3); }
void BM_Skinning_Frame_3Passes(benchmark::State& s) { skinning_frame(s, 3); }
void BM_PaperMode_Frame_1Pass(benchmark::State& s) { paper_frame(s, 1); }
void BM_Skinning_Frame_1Pass(benchmark::State& s) { skinning_frame(s, 1); }

BENCHMARK(BM_GpuCompute_Bernstein11_Full)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GpuCompute_BSpline11_Full)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GpuCompute_Bernstein11_1M_Full)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);
BENCHMARK(BM_GpuCompute_BSpline11_1M_Full)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GpuCompute_Bernstein11_Full_Direct)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GpuCompute_Bernstein11_Full_Shared)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GpuCompute_Bernstein11_1M_Full_Direct)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK(BM_GpuCompute_Bernstein11_1M_Full_Shared)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(1);
BENCHMARK(BM_GpuCompute_BSpline11_1M_Full_Direct)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GpuCompute_BSpline11_1M_Full_Shared)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GpuCompute_BSpline11_1M_Full_Packed)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PaperMode_Frame_1Pass)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Skinning_Frame_1Pass)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_PaperMode_Frame_3Passes)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_Skinning_Frame_3Passes)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
