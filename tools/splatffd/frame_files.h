// What `splatffd render` and `splatffd reference` share about the frames they write: the --format option,
// the output folder, and the frame file names (frame_0007.png / .exr), so both commands write the same
// files for the same options.
#pragma once

#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

namespace sffd::cli {

// --format png | exr | png,exr | exr,png; false (png and exr both off) for anything else.
inline bool parse_image_formats(const std::string& f, bool& png, bool& exr) {
    png = f == "png" || f == "png,exr" || f == "exr,png";
    exr = f == "exr" || f == "png,exr" || f == "exr,png";
    return png || exr;
}

// Creates --out DIR (and its parents); on failure prints "DIR: cannot create output folder (why)".
inline bool create_output_folder(const std::string& out_dir) {
    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    if (ec || !std::filesystem::is_directory(out_dir)) {
        std::fprintf(stderr, "%s: cannot create output folder (%s)\n", out_dir.c_str(), ec.message().c_str());
        return false;
    }
    return true;
}

// OUT/frame_0007 for frame 7 (the caller adds .png / .exr).
inline std::filesystem::path frame_file_base(const std::string& out_dir, long k) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04ld", k);
    return std::filesystem::path(out_dir) / name;
}

}  // namespace sffd::cli
