// Shader preprocessing without GL: #include resolution, #pragma once, cycles, defines, #line mapping.
#include <gtest/gtest.h>

#include "runtime/gfx/shader.h"

using namespace sffd;

namespace {
const std::filesystem::path root = SFFD_RUNTIME_TEST_SHADERS;

std::size_t count(const std::string& text, const std::string& needle) {
    std::size_t n = 0;
    for (std::size_t p = text.find(needle); p != std::string::npos; p = text.find(needle, p + 1)) ++n;
    return n;
}
}  // namespace

TEST(ShaderPreprocess, ResolvesNestedIncludesOnceWithLineDirectives) {
    auto pre = gfx::preprocess_shader(root, "squares.comp", {{"OFFSET", "7"}, {"FLAG", ""}});
    ASSERT_TRUE(pre.ok()) << pre.message();
    const std::string& text = pre->text;
    // #version first, defines right after it, then the line of the main file that follows #version.
    EXPECT_EQ(text.rfind("#version 450 core\n#define OFFSET 7\n#define FLAG\n#line 2 0\n", 0), 0u) << text;
    EXPECT_EQ(count(text, "uint helper_mul("), 1u);
    EXPECT_EQ(count(text, "uint square("), 1u);
    ASSERT_EQ(pre->files.size(), 3u);
    EXPECT_EQ(pre->files[0], root / "squares.comp");
    EXPECT_EQ(pre->files[1], root / "lib" / "square.glsl");
    EXPECT_EQ(pre->files[2], root / "lib" / "helper_once.glsl");
    // Enter lib/square.glsl at its line 1, nested file at its line 1, back to square.glsl line 4, back
    // to squares.comp line 4 (the line after the #include on line 3).
    EXPECT_NE(text.find("#line 1 1\n"), std::string::npos);
    EXPECT_NE(text.find("#line 1 2\n"), std::string::npos);
    EXPECT_NE(text.find("#line 4 1\n"), std::string::npos);
    EXPECT_NE(text.find("#line 4 0\n"), std::string::npos);
    EXPECT_EQ(text.find("#include"), std::string::npos);
    EXPECT_EQ(text.find("\n#pragma once"), std::string::npos);
}

TEST(ShaderPreprocess, MissingIncludeNamesIncludingFileAndLine) {
    auto pre = gfx::preprocess_shader(root, "broken_include.comp");
    ASSERT_FALSE(pre.ok());
    EXPECT_EQ(pre.message().rfind((root / "broken_include.comp").string() +
                                      ":3: cannot open include \"lib/does_not_exist.glsl\"",
                                  0),
              0u)
        << pre.message();
}

TEST(ShaderPreprocess, IncludeCycleIsReported) {
    auto pre = gfx::preprocess_shader(root, "cycle_a.glsl");
    ASSERT_FALSE(pre.ok());
    EXPECT_NE(
        pre.message().find("cycle_b.glsl:2: #include cycle: cycle_a.glsl -> cycle_b.glsl -> cycle_a.glsl"),
        std::string::npos)
        << pre.message();
}

TEST(ShaderPreprocess, MissingMainFile) {
    auto pre = gfx::preprocess_shader(root, "does/not/exist.vert");
    ASSERT_FALSE(pre.ok());
    EXPECT_NE(pre.message().find("exist.vert: cannot open shader file"), std::string::npos) << pre.message();
}

TEST(ShaderPreprocess, MissingVersionIsAnError) {
    auto pre = gfx::preprocess_shader(root, "lib/bad.glsl");
    ASSERT_FALSE(pre.ok());
    EXPECT_NE(pre.message().find("bad.glsl: missing #version"), std::string::npos) << pre.message();
}

TEST(ShaderPreprocess, IncludesResolveAgainstTheRealShaderRoot) {
    // The engine's shared binding header is includable from GLSL the way its comment says.
    const std::filesystem::path shaders =
        std::filesystem::path(SFFD_RUNTIME_TEST_SHADERS) / ".." / ".." / ".." / "shaders";
    ASSERT_TRUE(std::filesystem::exists(shaders / "common" / "bindings.h"));
    const auto tmp = std::filesystem::temp_directory_path() / "sffd_shader_root_test.comp";
    {
        std::FILE* f = std::fopen(tmp.c_str(), "w");
        ASSERT_NE(f, nullptr);
        std::fputs("#version 450 core\n#include \"common/bindings.h\"\nvoid main() {}\n", f);
        std::fclose(f);
    }
    auto pre = gfx::preprocess_shader(shaders, tmp);
    std::filesystem::remove(tmp);
    ASSERT_TRUE(pre.ok()) << pre.message();
    EXPECT_NE(pre->text.find("#define SFFD_SSBO_SPLATS_IN"), std::string::npos);
}

TEST(ShaderLog, MapsMesaAndOtherFormatsToFileAndLine) {
    const std::vector<std::filesystem::path> files = {"main.vert", "lib/inc.glsl"};
    EXPECT_EQ(gfx::map_shader_log("1:4(12): error: syntax error, unexpected '*'\n", files),
              "lib/inc.glsl:4: error: syntax error, unexpected '*'");
    EXPECT_EQ(gfx::map_shader_log("ERROR: 0:7: 'x' : undeclared identifier", files),
              "main.vert:7: 'x' : undeclared identifier");
    EXPECT_EQ(gfx::map_shader_log("0(9) : error C0000: oops", files), "main.vert:9: error C0000: oops");
    EXPECT_EQ(gfx::map_shader_log("some unrelated line", files), "some unrelated line");
}
