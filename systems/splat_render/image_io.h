// CPU images of rendered frames and their files. A FrameImage is what the render system's frame capture
// returns: linear RGBA (straight alpha, 0 where nothing was drawn), view-axis depth Z (+inf where nothing
// was drawn: the OpenEXR convention) and world-space normals. Row 0 is the TOP row.
//
// PNG: 8-bit sRGB with alpha (libpng). EXR: R G B A as half, Z as float, N.X N.Y N.Z as half (OpenEXR).
// Both writers save atomically (runtime/core/atomic_file.h). libpng and OpenEXR headers stay in the .cpp.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/result.h"

namespace sffd::render {

struct FrameImage {
    int width = 0;
    int height = 0;
    std::vector<glm::vec4> color;   // linear RGB, straight alpha
    std::vector<float> depth;       // distance along the camera's view axis; +inf for background
    std::vector<glm::vec3> normal;  // world space unit normals; 0 for background

    std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(width) + std::size_t(x); }
    bool covered(int x, int y) const { return color[index(x, y)].w > 0.0f; }
};

// 8-bit RGBA image, sRGB-encoded, row 0 at the top (PNG files, golden images).
struct Rgba8Image {
    int width = 0;
    int height = 0;
    std::vector<std::uint8_t> pixels;  // width*height*4

    const std::uint8_t* at(int x, int y) const {
        return &pixels[(std::size_t(y) * std::size_t(width) + std::size_t(x)) * 4];
    }
};

float linear_to_srgb(float linear);
float srgb_to_linear(float srgb);
std::uint8_t encode_srgb8(float linear);

// Converts linear straight-alpha colour to 8-bit sRGB. With a background (linear RGB), uncovered and
// partially covered pixels are composited over it and alpha becomes 255.
Rgba8Image to_rgba8(const FrameImage& image, std::optional<glm::vec3> background = std::nullopt);

Status write_png(const std::filesystem::path& path, const Rgba8Image& image);
Result<Rgba8Image> read_png(const std::filesystem::path& path);

Status write_exr(const std::filesystem::path& path, const FrameImage& image);
// Reads the channels write_exr writes (missing Z/N channels stay empty); for tests and tools.
Result<FrameImage> read_exr(const std::filesystem::path& path);

}  // namespace sffd::render
