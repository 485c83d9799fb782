// Internal to the glTF reader and writer (gltf_io.cpp reads clouds, gltf_load.cpp is the guarded tinygltf
// load, gltf_accessor.cpp the checked accessor readers, gltf_write.cpp writes): the accessor component types,
// and the sRGB <-> linear 16-bit colour mapping both directions must agree on.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace sffd::assets::gltf_detail {

constexpr int kFloat = 5126, kUByte = 5121, kUShort = 5123, kUInt = 5125, kByte = 5120, kShort = 5122;

// Bytes of one component of `type`; 0 for a type glTF does not define.
inline std::size_t component_size(int type) {
    switch (type) {
        case kByte:
        case kUByte: return 1;
        case kShort:
        case kUShort: return 2;
        case kUInt:
        case kFloat: return 4;
        default: return 0;
    }
}

// sRGB bytes <-> linear unsigned short: 16 bits are enough for every one of the 256 sRGB levels to
// come back exactly (tested), so COLOR_0 is both standard (linear) and lossless.
inline double srgb_to_linear(double c) {
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}
inline double linear_to_srgb(double c) {
    return c <= 0.0031308 ? c * 12.92 : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
}

inline std::uint16_t srgb8_to_linear16(std::uint32_t c) {
    return static_cast<std::uint16_t>(std::lround(srgb_to_linear(static_cast<double>(c) / 255.0) * 65535.0));
}
inline std::uint32_t linear_to_srgb8(double linear) {
    return static_cast<std::uint32_t>(
        std::lround(std::clamp(linear_to_srgb(std::clamp(linear, 0.0, 1.0)), 0.0, 1.0) * 255.0));
}

}  // namespace sffd::assets::gltf_detail
