// Shared helpers for the file-format tests: a fresh folder per test, whole-file read and write.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace sffd::test {

// A fresh, empty folder <tmp>/sffd_<suite>_<pid>/<name> (the pid keeps parallel ctest runs apart).
inline std::filesystem::path fresh_dir(const std::string& suite, const std::string& name) {
    namespace fs = std::filesystem;
    const fs::path d =
        fs::temp_directory_path() / ("sffd_" + suite + "_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

inline void write(const std::filesystem::path& p, const std::string& bytes) {
    if (p.has_parent_path()) std::filesystem::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << bytes;
}

inline std::string slurp(const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), {});
}

}  // namespace sffd::test
