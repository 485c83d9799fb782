#include "runtime/core/paths.h"

#include <unistd.h>

#include <cstdlib>
#include <system_error>

#ifndef SFFD_SOURCE_DIR
#define SFFD_SOURCE_DIR ""
#endif

namespace sffd::paths {
namespace fs = std::filesystem;

fs::path executable_path() {
    std::error_code ec;
    fs::path p = fs::read_symlink("/proc/self/exe", ec);
    return ec ? fs::path() : p;
}

static bool has_data(const fs::path& root) {
    std::error_code ec;
    // shaders/ is always there; content/ may be created later (its cache is made at set-up time).
    return fs::is_directory(root / "shaders" / "common", ec);
}

fs::path data_root() {
    static const fs::path root = [] {
        if (const char* env = std::getenv("SPLATFFD_DATA_DIR"); env && *env && has_data(env))
            return fs::path(env);
        const fs::path exe_dir = executable_path().parent_path();
        for (const fs::path& candidate :
             {exe_dir / ".." / "share" / "splatffd", exe_dir / "share" / "splatffd"})
            if (has_data(candidate)) {
                std::error_code
                    ec;  // data_root() reports nothing: on a filesystem error keep the path as found
                fs::path canonical = fs::weakly_canonical(candidate, ec);
                return ec ? candidate : canonical;
            }
        // Build tree: the executable sits somewhere under build/; the source tree is baked in.
        if (has_data(SFFD_SOURCE_DIR)) return fs::path(SFFD_SOURCE_DIR);
        return exe_dir;
    }();
    return root;
}

fs::path shader_dir() { return data_root() / "shaders"; }
fs::path content_dir() { return data_root() / "content"; }

fs::path cache_dir() {
    std::error_code ec;
    const fs::path in_tree = content_dir() / "cache";
    fs::create_directories(in_tree, ec);
    if (!ec && access(in_tree.c_str(), W_OK) == 0) return in_tree;
    fs::path base;
    if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg) base = xdg;
    else if (const char* home = std::getenv("HOME"); home && *home) base = fs::path(home) / ".cache";
    else base = fs::temp_directory_path();
    fs::create_directories(base / "splatffd", ec);
    return base / "splatffd";
}

}  // namespace sffd::paths
