// Shader programs loaded from files under shaders/ (paths::shader_dir(), or an explicit root in tests).
//
//   auto program = gfx::load_program({{GL_VERTEX_SHADER, "splat_render/visibility.vert"},
//                                     {GL_FRAGMENT_SHADER, "splat_render/visibility.frag"}},
//                                    "render.visibility", {{"HIGH_QUALITY", "1"}});
//   if (!program) return make_error(program.message());   // "/.../visibility.frag:12: error: ..."
//
// The loader resolves `#include "file"` (relative to the including file first, then to the shaders
// root; `#pragma once` and include guards both work; cycles are reported), injects `#define NAME VALUE`
// lines right after `#version`, and emits `#line N <file-number>` so the driver's log maps back to the
// real file and line. Errors read `path:line: message`, naming the included file when the problem is
// there; a missing include names the including file and line.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/gfx/gl_object.h"

namespace sffd::gfx {

struct ShaderSource {
    GLenum stage;      // GL_VERTEX_SHADER, GL_FRAGMENT_SHADER, GL_GEOMETRY_SHADER, GL_COMPUTE_SHADER...
    std::string path;  // relative to the shaders root (or absolute)
};

using Defines = std::vector<std::pair<std::string, std::string>>;  // {name, value}; value may be empty

// Source after #include resolution, ready for glShaderSource. `files[i]` is the file that `#line N i`
// refers to (files[0] is the main file).
struct PreprocessedSource {
    std::string text;
    std::vector<std::filesystem::path> files;
};

// CPU-only step (testable without GL): reads `path` (relative to `root` unless absolute) and expands it.
Result<PreprocessedSource> preprocess_shader(const std::filesystem::path& root,
                                             const std::filesystem::path& path, const Defines& defines = {});

// Rewrites a driver info log ("0:12(5): error: ..." from Mesa, "ERROR: 0:12: ..." elsewhere) into
// "path:line: message" lines using the file table from preprocess_shader().
std::string map_shader_log(std::string_view log, const std::vector<std::filesystem::path>& files);

// Compiles and links every stage; the program is labelled `label` (debug output, captures).
Result<Program> load_program(const std::vector<ShaderSource>& sources, std::string_view label,
                             const Defines& defines = {});
Result<Program> load_program(const std::filesystem::path& root, const std::vector<ShaderSource>& sources,
                             std::string_view label, const Defines& defines = {});

// Convenience for a single compute shader.
Result<Program> load_compute_program(const std::string& path, std::string_view label,
                                     const Defines& defines = {});

}  // namespace sffd::gfx
