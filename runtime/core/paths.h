// Where the engine's data lives. Shaders and content are found relative to the executable, never the
// working directory: <exe>/../share/splatffd/{shaders,content} when installed, the source tree when run
// from a build directory (SFFD_SOURCE_DIR baked in at build time), or SPLATFFD_DATA_DIR if set.
#pragma once

#include <filesystem>

namespace sffd::paths {

std::filesystem::path executable_path();
std::filesystem::path data_root();    // folder that holds shaders/ and content/
std::filesystem::path shader_dir();   // data_root()/shaders
std::filesystem::path content_dir();  // data_root()/content
// Writable cache for content made at set-up time (e.g. the `face` scene): content/cache in the source
// tree, or $XDG_CACHE_HOME/splatffd (~/.cache/splatffd) when installed read-only.
std::filesystem::path cache_dir();

}  // namespace sffd::paths
