// Saving never leaves a half-written file: write `<path>.tmp-<pid>` in the same folder, flush, fsync,
// then rename over `path`. On any failure the temporary is removed and the old file is untouched.
#pragma once

#include <cstdio>
#include <filesystem>
#include <functional>
#include <string_view>

#include "runtime/core/result.h"

namespace sffd {

// `write` receives an open FILE* (binary mode) and returns an error to abort the save.
Status write_file_atomic(const std::filesystem::path& path, const std::function<Status(std::FILE*)>& write);
Status write_file_atomic(const std::filesystem::path& path, std::string_view contents);

}  // namespace sffd
