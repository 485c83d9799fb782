// Splat rendering on the current GL driver (llvmpipe here), 1280x720, the paper's scene: a unit sphere of
// 59,650 splats seen from distance 3 (and 600,000 splats), preview and HQ, culling on and off, culled by
// the automatic path (the CPU cull on llvmpipe) or forced through the compute pass. splats = 0 is the
// built-in `sphere` itself (59,650 textured splats, the paper's object; the others are white Fibonacci
// spheres whose discs overlap about twice).
// Each iteration renders one frame and waits for it (glFinish) and is timed with a CPU clock
// (UseManualTime): llvmpipe's GL_TIME_ELAPSED under-reports point rasterisation. Counters: visible splats
// and per-pass milliseconds (a separate timed frame with glFinish between passes). bench_cpu_cull and
// bench_cpu_raster time the CPU cull and the CPU sprite rasteriser alone (no GL), the rasteriser also once
// per SIMD target this machine runs (bench_cpu_raster/.../simd:avx2).
//   build/<dir>/tools/bench/bench_render_splat --benchmark_repetitions=5
//   --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/ecs/registry.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/gl_object.h"
#include "runtime/scene/components.h"
#include "runtime/simd/simd.h"
#include "systems/splat_render/camera_math.h"
#include "systems/splat_render/cpu_cull.h"
#include "systems/splat_render/cpu_raster.h"
#include "systems/splat_render/splat_pack.h"
#include "systems/splat_render/splat_render.h"
#include "systems/residency/residency_system.h"

using namespace sffd;
using namespace sffd::render;

namespace {

// CPU time of the whole process (llvmpipe's rasteriser threads included): far steadier than wall time
// while other jobs load the machine; on a quiet machine wall time is about this divided by the threads.
double process_cpu_seconds() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return double(ts.tv_sec) + double(ts.tv_nsec) * 1e-9;
}

gfx::GlContext& context() {
    static std::optional<gfx::GlContext> ctx;
    if (!ctx) {
        auto c = gfx::create_context({.headless = true, .width = 64, .height = 64, .debug = false});
        if (!c) {
            std::fprintf(stderr, "%s\n", c.message().c_str());
            std::abort();
        }
        ctx.emplace(std::move(c.value()));
    }
    return *ctx;
}

// Fibonacci sphere, splat radius 0.8 * sqrt(4 pi / n) (discs overlap about twice), white.
SplatCloud sphere(std::size_t n) {
    SplatCloud c;
    c.positions.resize(n), c.normals.resize(n), c.axis_u.resize(n), c.axis_v.resize(n);
    c.colors.assign(n, 0xffc8c8c8u);
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    const double r = 0.8 * std::sqrt(4.0 * std::numbers::pi / double(n));
    for (std::size_t i = 0; i < n; ++i) {
        const double y = 1.0 - 2.0 * (double(i) + 0.5) / double(n);
        const double rr = std::sqrt(std::max(0.0, 1.0 - y * y));
        const glm::dvec3 nrm(std::cos(golden * double(i)) * rr, y, std::sin(golden * double(i)) * rr);
        const glm::dvec3 a = std::abs(nrm.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
        const glm::dvec3 t = glm::normalize(glm::cross(a, nrm));
        c.positions[i] = glm::vec3(nrm);
        c.normals[i] = glm::vec3(nrm);
        c.axis_u[i] = glm::vec3(t * r);
        c.axis_v[i] = glm::vec3(glm::cross(nrm, t) * r);
    }
    return c;
}

void render_frames(benchmark::State& state, CullPath path, RasterPath raster);

void bench_render(benchmark::State& state) {
    render_frames(state, state.range(3) ? CullPath::compute : CullPath::automatic, RasterPath::automatic);
}

// HQ through each raster path (RenderSettings::raster_path; compute_raster.h), automatic cull path.
void bench_raster_path(benchmark::State& state) {
    render_frames(state, CullPath::automatic, state.range(3) ? RasterPath::compute : RasterPath::raster);
}

// The compute rasteriser's break-even against the rasteriser (compute_raster.h's max footprints): the HQ
// frame of a sphere whose mean splat diameter is footprint_px at 1280x720 from distance 3 (n = (1643 /
// footprint)² splats: 6.7 px at 59,650), both raster paths in each iteration. Counters: raster_ms,
// compute_ms and compute_speedup = raster_ms / compute_ms; the break-even is the largest footprint_px
// whose speedup is still >= 1 (one line per footprint on stderr says so). Run it on the GPU to set
// compute_raster_hardware_max_footprint (systems/splat_render/README.md).
void bench_raster_break_even(benchmark::State& state) {
    context();
    const double footprint = double(state.range(0)) / 10.0;
    const auto n = std::size_t(std::llround(std::pow(1643.0 / footprint, 2.0)));
    ecs::Registry reg;
    reg.emplace<SplatCloud>(reg.create(), sphere(n));
    Camera cam;
    cam.eye = glm::dvec3(0, 0, 3);
    cam.near_plane = 0.1f;
    cam.far_plane = 10.0f;
    reg.emplace<Camera>(reg.create(), cam);
    reg.emplace<DirectionalLight>(reg.create(), DirectionalLight{});
    RenderSettings settings;
    settings.quality = Quality::hq, settings.width = 1280, settings.height = 720, settings.culling = true;
    FrameContext frame;
    const auto timed = [&](RasterPath path) {
        reg.resource<RenderSettings>().raster_path = path;
        const auto t0 = std::chrono::steady_clock::now();
        render_system(reg, frame);
        glFinish();
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    };
    reg.set_resource<RenderSettings>(settings);
    residency_system(reg, frame);  // upload: without it the frames drew nothing and timed only overhead
    timed(RasterPath::raster), timed(RasterPath::compute);  // compile, warm up
    if (reg.resource<RenderStats>().splats != n || reg.resource<RenderStats>().compute_rastered_clouds != 1) {
        // E.g. records over GL_MAX_SHADER_STORAGE_BLOCK_SIZE (logged): no comparison to make.
        state.SkipWithError("the compute rasteriser did not take the cloud (see the log)");
        return;
    }
    double raster = 0.0, compute = 0.0;
    for (auto _ : state) {
        const double r = timed(RasterPath::raster), c = timed(RasterPath::compute);
        raster += r, compute += c;
        state.SetIterationTime(r + c);
    }
    const auto it = double(state.iterations());
    state.counters["splats"] = double(n);
    state.counters["raster_ms"] = 1e3 * raster / it;
    state.counters["compute_ms"] = 1e3 * compute / it;
    state.counters["compute_speedup"] = compute > 0.0 ? raster / compute : 0.0;
    std::fprintf(
        stderr,
        "raster break-even: %.1f px (%zu splats): compute rasteriser %.2fx the rasteriser's speed (%s)\n",
        footprint, n, compute > 0.0 ? raster / compute : 0.0,
        glGetString(GL_RENDERER) ? reinterpret_cast<const char*>(glGetString(GL_RENDERER)) : "?");
}

void render_frames(benchmark::State& state, CullPath path, RasterPath raster) {
    context();
    const auto n = std::size_t(state.range(0));
    const auto quality = state.range(1) ? Quality::hq : Quality::preview;
    const bool culling = state.range(2) != 0;
    ecs::Registry reg;
    reg.emplace<SplatCloud>(reg.create(), n == 0 ? assets::make_sphere_cloud() : sphere(n));
    Camera cam;
    cam.eye = glm::dvec3(0, 0, 3);
    cam.near_plane = 0.1f;
    cam.far_plane = 10.0f;
    reg.emplace<Camera>(reg.create(), cam);
    reg.emplace<DirectionalLight>(reg.create(), DirectionalLight{});
    RenderSettings settings;
    settings.quality = quality, settings.width = 1280, settings.height = 720, settings.culling = culling;
    settings.cull_path = path;
    settings.raster_path = raster;
    reg.set_resource<RenderSettings>(settings);
    FrameContext frame;
    residency_system(reg, frame);  // upload
    render_system(reg, frame);     // compile, warm up
    glFinish();
    double cpu = 0.0;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        const double c0 = process_cpu_seconds();
        render_system(reg, frame);
        glFinish();
        cpu += process_cpu_seconds() - c0;
        state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    state.counters["cpu_ms"] = 1e3 * cpu / double(state.iterations());
    // One extra frame with per-pass timing for the counters.
    reg.resource<RenderSettings>().time_passes = true;
    render_system(reg, frame);
    const RenderStats& s = reg.resource<RenderStats>();
    state.counters["visible"] = double(s.visible_points + s.visible_quads);
    state.counters["quads"] = double(s.visible_quads);
    state.counters["cull_ms"] = s.cull_ms;
    state.counters["cpu_culled"] = double(s.cpu_culled_clouds);
    state.counters["compute_rastered"] = double(s.compute_rastered_clouds);
    state.counters["raster_sprites"] = double(s.raster_sprites);
    if (quality == Quality::hq) {
        state.counters["visibility_ms"] = s.visibility_ms;
        state.counters["attribute_ms"] = s.attribute_ms;
        state.counters["shade_ms"] = s.shade_ms;
    } else {
        state.counters["preview_ms"] = s.preview_ms;
    }
    release_render_state(reg);
}

// Calibration: the workload ../shared/notes/splatting.md measured on a quiet machine (60,000 round
// 6 px point sprites, one opaque depth-tested pass, 1280x720: ~55 ms). Its time here tells how loaded the
// machine is while the other benchmarks run.
void bench_reference_points(benchmark::State& state) {
    context();
    const SplatCloud cloud = sphere(60000);
    gfx::Buffer positions = gfx::Buffer::create("bench.positions");
    std::vector<glm::vec4> p;
    for (const glm::vec3& v : cloud.positions) p.emplace_back(v, 1.0f);
    glNamedBufferData(positions.id(), GLsizeiptr(p.size() * sizeof(glm::vec4)), p.data(), GL_STATIC_DRAW);
    const char* vs =
        "#version 450\nlayout(std430, binding = 0) readonly buffer P { vec4 pos[]; };\n"
        "uniform mat4 mvp;\nvoid main() { gl_Position = mvp * pos[gl_VertexID]; gl_PointSize = 6.0; }\n";
    const char* fs =
        "#version 450\nout vec4 color;\nvoid main() { vec2 d = gl_PointCoord * 2.0 - 1.0;\n"
        "if (dot(d, d) > 1.0) discard; color = vec4(1.0); }\n";
    gfx::Program program(glCreateProgram());
    for (auto [stage, src] :
         {std::pair{GLenum(GL_VERTEX_SHADER), vs}, std::pair{GLenum(GL_FRAGMENT_SHADER), fs}}) {
        const GLuint sh = glCreateShader(stage);
        glShaderSource(sh, 1, &src, nullptr);
        glCompileShader(sh);
        glAttachShader(program.id(), sh);
        glDeleteShader(sh);
    }
    glLinkProgram(program.id());
    gfx::Texture color = gfx::Texture::create("bench.color", GL_TEXTURE_2D),
                 depth = gfx::Texture::create("bench.depth", GL_TEXTURE_2D);
    glTextureStorage2D(color.id(), 1, GL_RGBA8, 1280, 720);
    glTextureStorage2D(depth.id(), 1, GL_DEPTH_COMPONENT32F, 1280, 720);
    gfx::Framebuffer fbo = gfx::Framebuffer::create("bench.fbo");
    glNamedFramebufferTexture(fbo.id(), GL_COLOR_ATTACHMENT0, color.id(), 0);
    glNamedFramebufferTexture(fbo.id(), GL_DEPTH_ATTACHMENT, depth.id(), 0);
    gfx::VertexArray vao = gfx::VertexArray::create("bench.vao");
    Camera cam;
    cam.eye = glm::dvec3(0, 0, 3);
    const glm::mat4 mvp = glm::mat4(glm::perspective(glm::radians(45.0), 1280.0 / 720.0, 0.1, 10.0) *
                                    glm::lookAt(cam.eye, cam.target, cam.up));
    glProgramUniformMatrix4fv(program.id(), glGetUniformLocation(program.id(), "mvp"), 1, GL_FALSE,
                              &mvp[0][0]);
    auto frame = [&] {
        const float clear[4] = {0, 0, 0, 0}, one = 1.0f;
        glClearNamedFramebufferfv(fbo.id(), GL_COLOR, 0, clear);
        glClearNamedFramebufferfv(fbo.id(), GL_DEPTH, 0, &one);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo.id());
        glViewport(0, 0, 1280, 720);
        glEnable(GL_DEPTH_TEST);
        glEnable(GL_PROGRAM_POINT_SIZE);
        glUseProgram(program.id());
        glBindVertexArray(vao.id());
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, positions.id());
        glDrawArrays(GL_POINTS, 0, 60000);
        glFinish();
    };
    frame();
    double cpu = 0.0;
    for (auto _ : state) {
        const auto t0 = std::chrono::steady_clock::now();
        const double c0 = process_cpu_seconds();
        frame();
        cpu += process_cpu_seconds() - c0;
        state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    state.counters["cpu_ms"] = 1e3 * cpu / double(state.iterations());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

// The frame the CPU benchmarks cull and draw: the sphere of n splats from distance 3 at 1280x720, one
// white light; `lit` for preview's lit colours, else HQ's.
gpu::FrameBlock sphere_frame(std::size_t n, bool lit) {
    Camera cam;
    cam.eye = glm::dvec3(0, 0, 3);
    gpu::FrameBlock f = camera_frame_block(view_matrix(cam), projection_matrix(cam, 1280.0 / 720.0), 1280,
                                           720, 1.0f, 255.0f, true);
    f.light_dir[0] = glm::vec4(glm::normalize(glm::vec3(1, 1, 1)), 0);
    f.light_color[0] = glm::vec4(1.0f);
    f.material = glm::vec4(0.3f, 32.0f, 0, 0);
    f.counts = glm::uvec4(std::uint32_t(n), 1u, 0u, lit ? 1u : 0u);
    return f;
}

// The CPU cull alone (cpu_cull.h, no GL): the sphere from distance 3, preview (lit) or HQ colours.
void bench_cpu_cull(benchmark::State& state) {
    const auto n = std::size_t(state.range(0));
    const SplatCloud cloud = sphere(n);
    const std::vector<gpu::GpuSplat> splats = pack_splats(cloud);
    const gpu::FrameBlock f = sphere_frame(n, state.range(1) == 0);
    CpuCullResult out;
    for (auto _ : state) {
        cull_splats_cpu(splats, f, {}, out);
        benchmark::DoNotOptimize(out.visible_records);
    }
    state.counters["visible"] = double(out.visible_records);
    state.SetItemsProcessed(std::int64_t(state.iterations() * n));
}

// The CPU sprite rasteriser alone (cpu_raster.h, no GL): the sprites the CPU cull makes of the sphere
// from distance 3 at 1280x720, drawn by one pass: preview (lit flat colours), the HQ visibility pass
// (depths pushed back by eps) or hq (that pass and the attribute sums). `target`: the SIMD target pinned
// for the body (null: the dispatch's own choice). Counters: sprites drawn, pixels of the rectangle.
void cpu_raster_frames(benchmark::State& state, std::size_t n, SpritePass pass, const simd::Target* target) {
    const SplatCloud cloud = sphere(n);
    const std::vector<gpu::GpuSplat> splats = pack_splats(cloud);
    const gpu::FrameBlock f = sphere_frame(n, pass == SpritePass::preview);
    CpuCullResult cull;
    cull_splats_cpu(splats, f, {}, cull);
    std::vector<SpriteRun> runs;
    CpuCullResult::for_each_run(cull.records, cull.record_counts, cull.block,
                                [&](std::size_t, const SplatRecord* p, std::size_t k) {
                                    runs.push_back({p, k});
                                });
    std::optional<simd::ScopedTarget> pin;
    if (target) pin.emplace(*target);
    CpuRasterImage img;
    rasterize_sprites_cpu(runs, f, 1280, 720, f.background, {1.0f, 255.0f}, pass, false, img);  // warm up
    for (auto _ : state) {
        rasterize_sprites_cpu(runs, f, 1280, 720, f.background, {1.0f, 255.0f}, pass, false, img);
        benchmark::DoNotOptimize(img.depth.data());
    }
    state.counters["sprites"] = double(img.sprites);
    state.counters["pixels"] = double(img.rect.z) * double(img.rect.w);
    state.SetItemsProcessed(std::int64_t(state.iterations()) * std::int64_t(img.sprites));
}

// Args: splats, pass (0 preview, 1 the HQ visibility pass, 2 hq: visibility and attribute sums).
void bench_cpu_raster(benchmark::State& state) {
    const SpritePass passes[] = {SpritePass::preview, SpritePass::visibility, SpritePass::hq};
    cpu_raster_frames(state, std::size_t(state.range(0)), passes[state.range(1)], nullptr);
}

}  // namespace

// The CPU rasteriser once as dispatched and once per SIMD target this machine runs
// (bench_cpu_raster/splats:59650/pass:0/simd:avx2).
BENCHMARK(bench_cpu_raster)
    ->ArgNames({"splats", "pass"})
    ->Args({59650, 0})
    ->Args({59650, 1})
    ->Args({59650, 2})
    ->Args({600000, 0})
    ->Args({600000, 1})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
const int cpu_raster_per_target = [] {
    const SpritePass passes[] = {SpritePass::preview, SpritePass::visibility, SpritePass::hq};
    const std::pair<std::size_t, int> args[] = {{59650, 0}, {59650, 1}, {59650, 2}, {600000, 0}, {600000, 1}};
    for (const simd::Target& t : simd::runnable())
        for (const auto& [n, pass] : args)
            benchmark::RegisterBenchmark(("bench_cpu_raster/splats:" + std::to_string(n) +
                                          "/pass:" + std::to_string(pass) + "/simd:" + t.name)
                                             .c_str(),
                                         [t, n = n, pass = passes[pass]](benchmark::State& state) {
                                             cpu_raster_frames(state, n, pass, &t);
                                         })
                ->Unit(benchmark::kMillisecond)
                ->MeasureProcessCPUTime()
                ->UseRealTime();
    return 0;
}();

BENCHMARK(bench_cpu_cull)
    ->ArgNames({"splats", "hq"})
    ->Args({59650, 0})
    ->Args({59650, 1})
    ->Args({600000, 0})
    ->Args({600000, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK(bench_reference_points)->UseManualTime()->Unit(benchmark::kMillisecond)->MinTime(1.0);

// Args: splats (0: the built-in textured sphere), hq (1) / preview (0), culling on (1) / off (0), cull path
// automatic (0) / compute pass forced (1).
BENCHMARK(bench_render)
    ->ArgNames({"splats", "hq", "cull", "compute"})
    ->Args({59650, 0, 1, 0})
    ->Args({59650, 1, 1, 0})
    ->Args({59650, 0, 1, 1})
    ->Args({59650, 1, 1, 1})
    ->Args({59650, 0, 0, 0})
    ->Args({59650, 1, 0, 0})
    ->Args({0, 0, 1, 0})
    ->Args({0, 1, 1, 0})
    ->Args({600000, 0, 1, 0})
    ->Args({600000, 1, 1, 0})
    ->Args({600000, 0, 1, 1})
    ->Args({600000, 1, 1, 1})
    ->Args({600000, 0, 0, 0})
    ->Args({600000, 1, 0, 0})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);

// Arg: mean splat diameter in tenths of a pixel (1 px to 24 px).
BENCHMARK(bench_raster_break_even)
    ->ArgName("footprint_px_x10")
    ->Arg(10)
    ->Arg(20)
    ->Arg(30)
    ->Arg(40)
    ->Arg(60)
    ->Arg(80)
    ->Arg(120)
    ->Arg(160)
    ->Arg(240)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);

// Args: splats, hq (always 1), cull (always 1), raster path: 0 the rasteriser, 1 the compute rasteriser
// (hybrid). The sphere from distance 3: mean splat diameter 59,650 splats 6.7 px, 250,000 3.3 px, 1M 1.7 px.
BENCHMARK(bench_raster_path)
    ->ArgNames({"splats", "hq", "cull", "compute_raster"})
    ->Args({59650, 1, 1, 0})
    ->Args({59650, 1, 1, 1})
    ->Args({250000, 1, 1, 0})
    ->Args({250000, 1, 1, 1})
    ->Args({1000000, 1, 1, 0})
    ->Args({1000000, 1, 1, 1})
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0);
