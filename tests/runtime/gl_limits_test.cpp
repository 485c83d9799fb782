// The GL portability layer (label `gl`): memory barriers go through gfx::memory_barrier and can be
// recorded; the implementation limits are queried at start-up, checked, and overridable by tests; a run
// that requires a hardware renderer refuses a software one.
#include <gtest/gtest.h>

#include <cstdlib>

#include "runtime/core/log.h"
#include "runtime/gfx/barrier.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/limits.h"

using namespace sffd;

namespace {

gfx::GlContext make_headless() {
    auto ctx = gfx::create_context({.headless = true, .width = 16, .height = 16});
    EXPECT_TRUE(ctx.ok()) << (ctx.ok() ? "" : ctx.message());
    if (!ctx.ok()) return {};
    return std::move(ctx).value();
}

// Sets an environment variable for one scope.
class ScopedEnv {
public:
    ScopedEnv(const char* name, const char* value) : m_name(name) {
        if (const char* old = std::getenv(name)) m_old = old, m_had = true;
        setenv(name, value, 1);
    }
    ~ScopedEnv() {
        if (m_had) setenv(m_name, m_old.c_str(), 1);
        else unsetenv(m_name);
    }

private:
    const char* m_name;
    std::string m_old;
    bool m_had = false;
};

}  // namespace

TEST(GlBarrier, RecordsSiteAndBitsWhileALogIsAlive) {
    gfx::GlContext ctx = make_headless();
    ASSERT_TRUE(ctx);
    const std::uint64_t errors = gfx::debug_error_count();
    gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT, "test.unrecorded");
    {
        gfx::BarrierLog log;
        gfx::memory_barrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT, "test.a");
        gfx::memory_barrier(GL_COMMAND_BARRIER_BIT, "test.b");
        gfx::memory_barrier(GL_BUFFER_UPDATE_BARRIER_BIT, "test.a");
        ASSERT_EQ(log.records().size(), 3u);
        EXPECT_EQ(log.count("test.a"), 2u);
        EXPECT_EQ(log.count("test.unrecorded"), 0u);
        EXPECT_EQ(log.bits_at("test.a"),
                  std::uint32_t(GL_SHADER_STORAGE_BARRIER_BIT | GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT |
                                GL_BUFFER_UPDATE_BARRIER_BIT));
        // issued(): one barrier carrying every bit, not bits spread over several.
        EXPECT_TRUE(log.issued("test.a", GL_SHADER_STORAGE_BARRIER_BIT | GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT));
        EXPECT_FALSE(log.issued("test.a", GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT));
        EXPECT_FALSE(log.issued("test.b", GL_SHADER_STORAGE_BARRIER_BIT));
    }
    EXPECT_EQ(gfx::debug_error_count(), errors);
    EXPECT_EQ(gfx::barrier_bit_names(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT),
              "COMMAND|SHADER_STORAGE");
    EXPECT_EQ(gfx::barrier_bit_names(GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT), "VERTEX_ATTRIB_ARRAY");
}

TEST(GlLimits, QueriedAtStartUpAndMeetTheEnginesNeeds) {
    gfx::GlContext ctx = make_headless();
    ASSERT_TRUE(ctx);
    const gfx::GlLimits& l = gfx::limits();
    const gfx::GlLimits now = gfx::query_limits();
    EXPECT_EQ(l.max_ssbo_block_size, now.max_ssbo_block_size);
    EXPECT_EQ(l.max_vertex_ssbo_blocks, now.max_vertex_ssbo_blocks);
    EXPECT_GE(l.max_ssbo_block_size, std::int64_t(1) << 24);  // GL's minimum
    EXPECT_GE(l.max_ssbo_bindings, 8);
    EXPECT_GT(l.ssbo_offset_alignment, 0);
    EXPECT_GE(l.max_compute_groups_x, 65535);
    EXPECT_TRUE(gfx::check_limits(l).ok());  // create_context() would have refused otherwise
    RecordProperty("max_ssbo_block_size", std::to_string(l.max_ssbo_block_size));
}

// An implementation with GL 4.5's minimums (no vertex-stage SSBOs, 8 bindings) is refused with every
// missing limit named.
TEST(GlLimits, MissingLimitsAreNamed) {
    gfx::GlLimits minimum;
    minimum.max_ssbo_block_size = std::int64_t(1) << 24;
    minimum.max_ssbo_bindings = 8;
    minimum.max_vertex_ssbo_blocks = 0;
    minimum.max_fragment_ssbo_blocks = 8;
    minimum.max_compute_ssbo_blocks = 8;
    minimum.max_combined_ssbo_blocks = 8;
    const Status s = gfx::check_limits(minimum);
    ASSERT_FALSE(s.ok());
    EXPECT_NE(s.message().find("GL_MAX_VERTEX_SHADER_STORAGE_BLOCKS is 0, splat_render/splat.vert needs 3"),
              std::string::npos)
        << s.message();
    EXPECT_NE(s.message().find("GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS is 8"), std::string::npos)
        << s.message();
    EXPECT_EQ(s.message().find("GL_MAX_COMPUTE_SHADER_STORAGE_BLOCKS"), std::string::npos) << s.message();
}

TEST(GlLimits, ScopedOverrideAndBlockSizeChecks) {
    gfx::GlContext ctx = make_headless();
    ASSERT_TRUE(ctx);
    const std::int64_t real = gfx::limits().max_ssbo_block_size;
    {
        gfx::GlLimits small = gfx::limits();
        small.max_ssbo_block_size = 1000;
        gfx::ScopedLimits scope(small);
        EXPECT_EQ(gfx::limits().max_ssbo_block_size, 1000);
        EXPECT_TRUE(gfx::ssbo_fits(1000));
        EXPECT_FALSE(gfx::ssbo_fits(1001));
        EXPECT_EQ(gfx::ssbo_too_large("test.buffer", 1001),
                  "test.buffer: 1001 bytes exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE (1000)");
    }
    EXPECT_EQ(gfx::limits().max_ssbo_block_size, real);
}

// SFFD_REQUIRE_HARDWARE_GL=1 (GPU test runs): a software renderer is refused, naming it; a hardware one
// starts as usual.
TEST(GlContext, RequireHardwareRefusesASoftwareRenderer) {
    std::string renderer;
    bool software = false;
    {
        gfx::GlContext ctx = make_headless();
        ASSERT_TRUE(ctx);
        renderer = ctx.renderer();
        software = gfx::software_rasterizer();
    }
    ScopedEnv require("SFFD_REQUIRE_HARDWARE_GL", "1");
    EXPECT_TRUE(gfx::hardware_gl_required());
    auto ctx = gfx::create_context({.headless = true, .width = 16, .height = 16});
    if (software) {
        ASSERT_FALSE(ctx.ok());
        EXPECT_NE(ctx.message().find("SFFD_REQUIRE_HARDWARE_GL"), std::string::npos) << ctx.message();
        EXPECT_NE(ctx.message().find(renderer), std::string::npos) << ctx.message();
    } else {
        EXPECT_TRUE(ctx.ok()) << ctx.message();
    }
}

TEST(GlContext, SoftwareRendererNames) {
    EXPECT_TRUE(gfx::software_renderer_name("llvmpipe (LLVM 15.0.6, 256 bits)"));
    EXPECT_TRUE(gfx::software_renderer_name("softpipe"));
    EXPECT_FALSE(gfx::software_renderer_name("NVIDIA H100 80GB HBM3/PCIe/SSE2"));
    EXPECT_FALSE(
        gfx::software_renderer_name("AMD Radeon RX 7900 XTX (radeonsi, navi31, LLVM 15.0.7, DRM 3.54)"));
}
