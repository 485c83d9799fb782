// GL layer tests: each creates its own headless EGL context (label `gl`; no display needed).
#include <gtest/gtest.h>

#include <thread>

#include "runtime/core/log.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/render_target.h"
#include "tests/runtime/gl_version.h"
#include "runtime/gfx/shader.h"

using namespace sffd;

namespace {

const std::filesystem::path test_shaders = SFFD_RUNTIME_TEST_SHADERS;

gfx::GlContext make_headless() {
    auto ctx = gfx::create_context({.headless = true, .width = 64, .height = 32});
    EXPECT_TRUE(ctx.ok()) << (ctx.ok() ? "" : ctx.message());
    if (!ctx.ok()) return {};
    return std::move(ctx).value();
}

// Runs squares.comp over `count` elements and returns the SSBO contents.
std::vector<std::uint32_t> run_squares(std::uint32_t count, int offset) {
    auto program = gfx::load_program(test_shaders, {{GL_COMPUTE_SHADER, "squares.comp"}}, "test.squares",
                                     {{"OFFSET", std::to_string(offset)}});
    EXPECT_TRUE(program.ok()) << (program.ok() ? "" : program.message());
    if (!program.ok()) return {};
    gfx::Buffer buffer = gfx::Buffer::create("test.squares.out");
    const std::vector<std::uint32_t> poison(count, 0xdeadbeefu);
    glNamedBufferStorage(buffer.id(), GLsizeiptr(count * sizeof(std::uint32_t)), poison.data(), 0);
    glUseProgram(program->id());
    glUniform1ui(glGetUniformLocation(program->id(), "u_count"), count);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buffer.id());
    glDispatchCompute((count + 63) / 64, 1, 1);
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    std::vector<std::uint32_t> out(count);
    glGetNamedBufferSubData(buffer.id(), 0, GLsizeiptr(count * sizeof(std::uint32_t)), out.data());
    glUseProgram(0);
    return out;
}

}  // namespace

TEST(GlContext, HeadlessIsCore45DebugWithoutWindow) {
    gfx::GlContext ctx = make_headless();
    ASSERT_TRUE(ctx);
    EXPECT_TRUE(ctx.is_headless());
    EXPECT_EQ(ctx.window(), nullptr);
    EXPECT_FALSE(ctx.should_close());
    EXPECT_EQ(ctx.framebuffer_size().width, 64);
    EXPECT_EQ(ctx.framebuffer_size().height, 32);
    EXPECT_FALSE(ctx.renderer().empty());
    EXPECT_NE(ctx.version().find("4.5"), std::string::npos) << ctx.version();
    const test::CurrentContext current = test::current_context();
    EXPECT_EQ(current.version, 45);
    EXPECT_TRUE(current.core);
    EXPECT_TRUE(current.debug);
    ctx.request_close();
    EXPECT_TRUE(ctx.should_close());
}

TEST(GlContext, DebugCallbackLogsGlErrors) {
    gfx::GlContext ctx = make_headless();
    ASSERT_TRUE(ctx);
    log::ScopedLogCapture capture;
    const std::uint64_t before = gfx::debug_error_count();
    glBindBuffer(GL_ARRAY_BUFFER, 987654u);  // never generated: GL_INVALID_OPERATION in a core context
    EXPECT_EQ(gfx::debug_error_count(), before + 1);
    EXPECT_TRUE(capture.contains("GL error")) << "no GL error was logged";
}

TEST(GlContext, SeveralContextsOneAfterAnother) {
    for (int i = 0; i < 3; ++i) {
        gfx::GlContext ctx = make_headless();
        ASSERT_TRUE(ctx);
        const auto out = run_squares(100, i);
        ASSERT_EQ(out.size(), 100u);
        EXPECT_EQ(out[99], 99u * 99u + std::uint32_t(i));
    }
}

TEST(GlContext, MoveKeepsTheContextUsable) {
    gfx::GlContext a = make_headless();
    ASSERT_TRUE(a);
    gfx::GlContext b = std::move(a);
    EXPECT_FALSE(a);  // NOLINT(bugprone-use-after-move): moved-from is empty by contract
    ASSERT_TRUE(b);
    b.make_current();
    EXPECT_EQ(run_squares(10, 0)[9], 81u);
}

TEST(GlContext, OneContextPerThread) {
    std::vector<std::uint32_t> results[2];
    std::thread threads[2];
    for (int t = 0; t < 2; ++t)
        threads[t] = std::thread([t, &results] {
            auto ctx = gfx::create_context({.headless = true});
            if (!ctx.ok()) return;
            results[t] = run_squares(1000, 100 * (t + 1));
        });
    for (auto& th : threads) th.join();
    for (int t = 0; t < 2; ++t) {
        ASSERT_EQ(results[t].size(), 1000u) << "thread " << t;
        EXPECT_EQ(results[t][999], 999u * 999u + std::uint32_t(100 * (t + 1)));
    }
}

TEST(Shader, ComputeWritesSsboReadBackOnCpu) {
    gfx::GlContext ctx = make_headless();
    ASSERT_TRUE(ctx);
    const std::uint64_t errors = gfx::debug_error_count();
    const std::uint32_t count = 1000;  // not a multiple of the work-group size: the guard matters
    const auto out = run_squares(count, 7);
    ASSERT_EQ(out.size(), count);
    for (std::uint32_t i = 0; i < count; ++i) ASSERT_EQ(out[i], i * i + 7u) << "element " << i;
    EXPECT_EQ(gfx::debug_error_count(), errors);
}

TEST(Shader, MissingIncludeNamesIncludingFileAndLine) {
    gfx::GlContext ctx = make_headless();
    ASSERT_TRUE(ctx);
    auto program =
        gfx::load_program(test_shaders, {{GL_COMPUTE_SHADER, "broken_include.comp"}}, "test.broken");
    ASSERT_FALSE(program.ok());
    EXPECT_NE(
        program.message().find("broken_include.comp:3: cannot open include \"lib/does_not_exist.glsl\""),
        std::string::npos)
        << program.message();
}

TEST(Shader, CompileErrorInIncludedFileNamesThatFileAndLine) {
    gfx::GlContext ctx = make_headless();
    ASSERT_TRUE(ctx);
    auto program =
        gfx::load_program(test_shaders, {{GL_COMPUTE_SHADER, "bad_in_include.comp"}}, "test.bad_include");
    ASSERT_FALSE(program.ok());
    const std::string expected = (test_shaders / "lib" / "bad.glsl").string() + ":4: ";
    EXPECT_EQ(program.message().rfind(expected, 0), 0u) << program.message();
}

TEST(Shader, CompileErrorAfterIncludeMapsToMainFileLine) {
    gfx::GlContext ctx = make_headless();
    ASSERT_TRUE(ctx);
    auto program = gfx::load_program(test_shaders, {{GL_COMPUTE_SHADER, "bad_after_include.comp"}},
                                     "test.bad_after_include");
    ASSERT_FALSE(program.ok());
    const std::string expected = (test_shaders / "bad_after_include.comp").string() + ":6: ";
    EXPECT_EQ(program.message().rfind(expected, 0), 0u) << program.message();
    EXPECT_NE(program.message().find("undeclared_identifier"), std::string::npos) << program.message();
}

TEST(Shader, MissingFileIsAnError) {
    gfx::GlContext ctx = make_headless();
    ASSERT_TRUE(ctx);
    auto program = gfx::load_program(test_shaders, {{GL_VERTEX_SHADER, "nope.vert"}}, "test.nope");
    ASSERT_FALSE(program.ok());
    EXPECT_NE(program.message().find("nope.vert: cannot open shader file"), std::string::npos)
        << program.message();
}

TEST(Shader, LinkErrorNamesTheProgram) {
    gfx::GlContext ctx = make_headless();
    ASSERT_TRUE(ctx);
    // A fragment shader alone with two outputs is fine; a vertex shader alone links. Mismatched
    // interfaces are driver-lenient, so force a link error with a missing main(): a library-only stage.
    auto program = gfx::load_program(test_shaders, {{GL_COMPUTE_SHADER, "lib_only.comp"}}, "test.link");
    ASSERT_FALSE(program.ok());
    EXPECT_NE(program.message().find("load_program(test.link): link failed"), std::string::npos)
        << program.message();
}

TEST(RenderTarget, DrawReadBackBottomRowFirst) {
    gfx::GlContext ctx = make_headless();
    ASSERT_TRUE(ctx);
    const std::uint64_t errors = gfx::debug_error_count();
    auto program = gfx::load_program(
        test_shaders, {{GL_VERTEX_SHADER, "bottom_half.vert"}, {GL_FRAGMENT_SHADER, "bottom_half.frag"}},
        "test.bottom_half");
    ASSERT_TRUE(program.ok()) << program.message();
    const int w = 16, h = 8;
    auto target = gfx::RenderTarget::create(
        {.label = "test.target",
         .width = w,
         .height = h,
         .color = {{"color", gfx::ColorFormat::rgba8}, {"column", gfx::ColorFormat::r32f}}});
    ASSERT_TRUE(target.ok()) << target.message();
    const float clear[4] = {0.0f, 0.0f, 1.0f, 1.0f};
    const float minus_one[4] = {-1.0f, 0.0f, 0.0f, 0.0f};
    target->clear_color("color", clear);
    target->clear_color("column", minus_one);
    target->clear_depth(1.0f);
    target->bind();
    gfx::VertexArray vao = gfx::VertexArray::create("test.empty_vao");
    glBindVertexArray(vao.id());
    glUseProgram(program->id());
    glUniform4f(glGetUniformLocation(program->id(), "u_color"), 1.0f, 0.5f, 0.0f, 1.0f);
    glEnable(GL_DEPTH_TEST);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    glDisable(GL_DEPTH_TEST);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);

    const std::vector<std::uint8_t> rgba = target->read_rgba8("color");
    const std::vector<float> column = target->read_float("column");
    const std::vector<float> depth = target->read_depth();
    ASSERT_EQ(rgba.size(), std::size_t(w * h * 4));
    ASSERT_EQ(column.size(), std::size_t(w * h));
    ASSERT_EQ(depth.size(), std::size_t(w * h));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y * w + x);
            const bool drawn = y < h / 2;  // row 0 is the bottom row
            SCOPED_TRACE(testing::Message() << "pixel " << x << "," << y);
            if (drawn) {
                EXPECT_EQ(rgba[p * 4 + 0], 255);
                EXPECT_NEAR(rgba[p * 4 + 1], 128, 1);
                EXPECT_EQ(rgba[p * 4 + 2], 0);
                EXPECT_EQ(column[p], float(x));
                EXPECT_NEAR(depth[p], 0.75f, 1e-6f);  // NDC z 0.5 -> window depth 0.75
            } else {
                EXPECT_EQ(rgba[p * 4 + 0], 0);
                EXPECT_EQ(rgba[p * 4 + 2], 255);
                EXPECT_EQ(column[p], -1.0f);
                EXPECT_EQ(depth[p], 1.0f);
            }
        }
    // Top-down for image writers.
    std::vector<std::uint8_t> flipped = rgba;
    gfx::flip_rows(flipped, std::size_t(w) * 4);
    EXPECT_EQ(flipped[0 * 4 + 2], 255);                         // top row: clear colour
    EXPECT_EQ(flipped[std::size_t((h - 1) * w) * 4 + 0], 255);  // bottom row: drawn
    EXPECT_EQ(gfx::debug_error_count(), errors);
}

TEST(RenderTarget, ResizeAndFormats) {
    gfx::GlContext ctx = make_headless();
    ASSERT_TRUE(ctx);
    auto target = gfx::RenderTarget::create(
        {.label = "test.formats",
         .width = 4,
         .height = 4,
         .color = {{"a", gfx::ColorFormat::rgba16f}, {"b", gfx::ColorFormat::rgba32f}}});
    ASSERT_TRUE(target.ok()) << target.message();
    EXPECT_EQ(target->attachment_index("b"), 1);
    EXPECT_EQ(target->attachment_index("zzz"), -1);
    EXPECT_NE(target->color_texture("a"), 0u);
    ASSERT_TRUE(target->resize(10, 6).ok());
    EXPECT_EQ(target->width(), 10);
    const float value[4] = {0.25f, -2.0f, 1e5f, 3.5f};
    target->clear_color("b", value);
    const std::vector<float> b = target->read_float("b");
    ASSERT_EQ(b.size(), 10u * 6u * 4u);
    EXPECT_EQ(b[4 * 37 + 0], 0.25f);
    EXPECT_EQ(b[4 * 37 + 1], -2.0f);
    EXPECT_EQ(b[4 * 37 + 2], 1e5f);
    EXPECT_EQ(b[4 * 37 + 3], 3.5f);
    // Invalid sizes are errors, and the target keeps its old size.
    const Status bad = target->resize(0, 6);
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.message().find("invalid size 0x6"), std::string::npos) << bad.message();
    EXPECT_EQ(target->width(), 10);
    auto dup =
        gfx::RenderTarget::create({.label = "dup",
                                   .width = 2,
                                   .height = 2,
                                   .color = {{"x", gfx::ColorFormat::rgba8}, {"x", gfx::ColorFormat::r32f}}});
    ASSERT_FALSE(dup.ok());
    EXPECT_NE(dup.message().find("duplicate attachment name 'x'"), std::string::npos);
}
