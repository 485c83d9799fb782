// GPU pass timing in a headless GL 4.5 context (label gl): timestamp queries come back without the
// profiler ever waiting during frames; --sync brackets each pass with glFinish so real GPU work shows.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <vector>

#include "runtime/app/clock.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/gl_object.h"
#include "runtime/app/pass_timer.h"
#include "systems/profiling/profiler.h"
#include "systems/profiling/report.h"
#include "tests/test_util/gl_required.h"

namespace sffd::profiling {
namespace {

// A compute shader that burns a tunable number of iterations per invocation and writes the result.
constexpr const char* burn_source = R"(#version 450
layout(local_size_x = 64) in;
layout(std430, binding = 0) buffer Out { float v[]; };
uniform int iterations;
void main() {
    float x = float(gl_GlobalInvocationID.x);
    for (int i = 0; i < iterations; ++i) x = sin(x) * 1.0001 + 0.5;
    v[gl_GlobalInvocationID.x] = x;
}
)";

struct Burner {
    gfx::Program program;
    gfx::Buffer out;
    Burner() {
        gfx::Shader cs = gfx::Shader::create("test.burn", GL_COMPUTE_SHADER);
        glShaderSource(cs.id(), 1, &burn_source, nullptr);
        glCompileShader(cs.id());
        GLint ok = 0;
        glGetShaderiv(cs.id(), GL_COMPILE_STATUS, &ok);
        EXPECT_EQ(ok, GL_TRUE);
        program = gfx::Program::create("test.burn");
        glAttachShader(program.id(), cs.id());
        glLinkProgram(program.id());
        out = gfx::Buffer::create("test.burn.out");
        glNamedBufferData(out.id(), 64 * 256 * sizeof(float), nullptr, GL_DYNAMIC_DRAW);
    }
    // Iterations that keep this GPU busy for at least `ms` (quadrupling from 1500, measured with glFinish),
    // so the heavy pass is measurable on any implementation: 1500 take ~10 ms on llvmpipe, 0.04 ms on an
    // H100.
    int calibrate(double ms) const {
        int iterations = 1500;
        for (; iterations < (1 << 26); iterations *= 4) {
            glFinish();
            const auto t0 = std::chrono::steady_clock::now();
            run(iterations);
            glFinish();
            if (std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() >=
                ms)
                break;
        }
        return iterations;
    }
    void run(int iterations) const {
        glUseProgram(program.id());
        glUniform1i(glGetUniformLocation(program.id(), "iterations"), iterations);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, out.id());
        glDispatchCompute(256, 1, 1);
        glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    }
};

class GpuTiming : public ::testing::Test {
protected:
    void SetUp() override {
        auto ctx = gfx::create_context({.headless = true, .width = 64, .height = 64});
        if (!ctx) SFFD_GL_UNAVAILABLE("no headless GL context: " << ctx.message());
        m_ctx = std::move(ctx.value());
    }
    gfx::GlContext m_ctx;
};

Schedule burn_schedule(const Burner& burner, int iterations = 1500) {
    Schedule s;
    s.add(Phase::deformation, "burn", [&burner, iterations](ecs::Registry& r, const FrameContext&) {
        {
            auto heavy = gpu_scope(r, "burn.heavy");
            burner.run(iterations);
        }
        { auto empty = gpu_scope(r, "burn.empty"); }
    });
    return s;
}

TEST_F(GpuTiming, QueriesResolveForEveryPassWithoutWaitingDuringFrames) {
    Burner burner;
    ecs::Registry registry;
    Schedule schedule = burn_schedule(burner);
    {
        Profiler profiler({.gpu = profiling::GpuTiming::queries, .query_latency = 2});
        profiler.attach(schedule, registry);
        Clock clock({.fixed_dt = 1.0 / 60.0});
        for (int i = 0; i < 8; ++i) schedule.run_frame(registry, clock.tick());
        profiler.resolve_all();
        EXPECT_EQ(profiler.pending_queries(), 0u);
        ASSERT_EQ(profiler.frames().size(), 8u);
        for (const auto& f : profiler.frames())
            for (const auto& s : f.scopes) {
                if (s.kind == ScopeKind::pass) {
                    EXPECT_GE(s.gpu_ms, 0.0) << profiler.name(s.name);
                }
            }
        const ProfileReport r = build_report(profiler, {}, machine_info(true));
        EXPECT_EQ(r.gpu_timing, "queries");
        EXPECT_FALSE(r.machine.gl_renderer.empty());
        ASSERT_EQ(r.passes.size(), 2u);
        EXPECT_TRUE(r.passes[0].gpu_ms.has_value());
        ASSERT_EQ(r.systems.size(), 1u);
        EXPECT_TRUE(r.systems[0].gpu_ms.has_value());
        profiler.detach(schedule, registry);
    }
    EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
}

// A headless run is paced as a swap chain would be: when a frame's systems run, at most max - 1 earlier
// frames may still be on the GPU, and the frame max frames back has finished (its GL work, here a fence the
// frame's system put in after its dispatch, is signalled: asked without flushing or waiting). Unpaced
// (the default, for windows whose present paces them) the profiler keeps no fences.
TEST_F(GpuTiming, PacedQueriesKeepAtMostMaxFramesInFlight) {
    Burner burner;
    const int iterations = burner.calibrate(2.0);
    for (int max : {0, 1, 2, 3}) {
        SCOPED_TRACE(max);
        ecs::Registry registry;
        Profiler profiler({.gpu = profiling::GpuTiming::queries, .max_frames_in_flight = max});
        std::vector<GLsync> fences;  // one per frame, after the frame's GPU work
        std::vector<std::size_t> in_flight;
        std::vector<GLint> status;  // of the fence max frames back, as the frame's system sees it
        Schedule schedule;
        schedule.add(Phase::deformation, "burn", [&](ecs::Registry&, const FrameContext&) {
            in_flight.push_back(profiler.frames_in_flight());
            GLint st = GL_SIGNALED;
            if (max > 0 && fences.size() >= std::size_t(max))
                glGetSynciv(fences[fences.size() - std::size_t(max)], GL_SYNC_STATUS, 1, nullptr, &st);
            status.push_back(st);
            burner.run(iterations);
            fences.push_back(glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0));
        });
        profiler.attach(schedule, registry);
        Clock clock({.fixed_dt = 1.0 / 60.0});
        for (int i = 0; i < 6; ++i) schedule.run_frame(registry, clock.tick());
        profiler.detach(schedule, registry);
        ASSERT_EQ(in_flight.size(), 6u);
        for (std::size_t i = 0; i < in_flight.size(); ++i) {
            EXPECT_EQ(in_flight[i], max == 0 ? 0u : std::min<std::size_t>(i, std::size_t(max - 1))) << i;
            EXPECT_EQ(status[i], GL_SIGNALED) << i;
        }
        for (GLsync f : fences) glDeleteSync(f);
    }
    EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
}

TEST_F(GpuTiming, SyncModeChargesGpuWorkToThePassThatIssuedIt) {
    Burner burner;
    ecs::Registry registry;
    Schedule schedule = burn_schedule(burner, burner.calibrate(5.0));
    Profiler profiler({.gpu = profiling::GpuTiming::sync});
    profiler.attach(schedule, registry);
    Clock clock({.fixed_dt = 1.0 / 60.0});
    for (int i = 0; i < 5; ++i) schedule.run_frame(registry, clock.tick());
    const ProfileReport r = build_report(profiler, {}, machine_info(true));
    EXPECT_EQ(r.gpu_timing, "sync");
    const TimingRow* heavy = nullptr;
    const TimingRow* empty = nullptr;
    for (const auto& p : r.passes) (p.name == "burn.heavy" ? heavy : empty) = &p;
    ASSERT_TRUE(heavy && empty && heavy->gpu_ms && empty->gpu_ms);
    // The compute pass really runs inside its bracket: real work takes longer than none. Only the order
    // is asserted, never a duration or a ratio, which a loaded machine could break.
    EXPECT_GT(heavy->gpu_ms->p50, empty->gpu_ms->p50);
    EXPECT_GE(r.systems[0].cpu_ms.p50, heavy->gpu_ms->p50);
    profiler.detach(schedule, registry);
}

}  // namespace
}  // namespace sffd::profiling
