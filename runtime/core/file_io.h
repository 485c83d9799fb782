// Reading files that may be hostile, in one place: every reader of a whole file (JSON lattices and
// scenes, OBJ/OFF/MTL text, glTF and its buffers and images, clips, input recordings) goes through
// read_file(), which opens only regular files (a FIFO or device named as an input would block or never
// end) and refuses files larger than the caller's stated budget before allocating anything.
// Resources a file names (glTF buffer/image URIs, PLY `comment TextureFile`, OBJ `mtllib`/`map_Kd`) are
// found with resolve_resource(): only inside the folder of the file that names them.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include <sys/types.h>

#include "runtime/core/result.h"

namespace sffd {

// Budgets stated once (the messages quote them).
inline constexpr std::uint64_t kMaxTextFileBytes = std::uint64_t(4) << 30;  // OBJ/OFF text
inline constexpr std::uint64_t kMaxJsonFileBytes = std::uint64_t(256)
                                                   << 20;                   // lattices, clips, scenes (JSON)
inline constexpr std::uint64_t kMaxResourceBytes = std::uint64_t(2) << 30;  // one glTF buffer or image file

// Opens `path` (O_NONBLOCK, so a FIFO never blocks the open), checks that it is a regular file of at most
// `limit` bytes and reads it whole. Errors: `path: no such file`, `path: not a regular file`,
// `path: file is N bytes, more than the L-byte limit`, `path: cannot read: ...`, `path: out of memory`.
Result<std::string> read_file(const std::filesystem::path& path, std::uint64_t limit);

// What a non-regular file is, for messages ("a FIFO", "a character device", "a block device", "a socket",
// "a folder"; "not a regular file" for anything else): readers here and atomic saving name it alike.
const char* file_kind(mode_t mode);

// The resolved location of a resource named `uri` inside `owner` (a file): the path of a regular
// file inside owner's folder, after lexical normalisation and after following symlinks. Refused with
// `owner: resource 'uri' is outside the file's folder` for absolute paths, `..` escapes and symlinks
// that lead out, unless allow_outside_resources() is set (command-line flag --allow-outside-resources,
// for trusted files); a missing resource is `owner: resource 'uri' not found`. `uri` is used as given
// (glTF URIs are percent-decoded by the caller).
Result<std::filesystem::path> resolve_resource(const std::filesystem::path& owner, std::string_view uri);

// Process-wide switch for trusted files (default off).
void set_allow_outside_resources(bool allow);
bool allow_outside_resources();

// JSON nesting guard, run before any JSON parser sees the text: recursive-descent parsers (tinygltf's,
// nlohmann's) overflow the stack on ~16,000 nested arrays. Counts [ and { outside strings. Error:
// `name: JSON nesting deeper than N levels`.
inline constexpr int kMaxJsonDepth = 256;
Status check_json_depth(std::string_view text, const std::string& name, int max_depth = kMaxJsonDepth);

}  // namespace sffd
