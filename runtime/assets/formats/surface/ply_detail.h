// Internals shared by the PLY reader (ply_read.cpp), writer (ply_write.cpp) and header code (ply.cpp):
// the scalar type table, the range check and the I/O buffer size. Not part of the public interface.
#pragma once

#include <bit>
#include <cmath>
#include <cstddef>
#include <limits>

#include "runtime/assets/formats/surface/ply.h"

namespace sffd::ply::detail {

constexpr std::size_t kBufferBytes = 1 << 20;

struct TypeInfo {
    Type type;
    const char* name;
    const char* alias;
    std::size_t size;
    double lo, hi;  // representable range (integers); floats use +-inf
};

constexpr double kInf = std::numeric_limits<double>::infinity();
inline constexpr TypeInfo kTypes[] = {
    {Type::int8, "char", "int8", 1, -128.0, 127.0},
    {Type::uint8, "uchar", "uint8", 1, 0.0, 255.0},
    {Type::int16, "short", "int16", 2, -32768.0, 32767.0},
    {Type::uint16, "ushort", "uint16", 2, 0.0, 65535.0},
    {Type::int32, "int", "int32", 4, -2147483648.0, 2147483647.0},
    {Type::uint32, "uint", "uint32", 4, 0.0, 4294967295.0},
    {Type::float32, "float", "float32", 4, -kInf, kInf},
    {Type::float64, "double", "float64", 8, -kInf, kInf},
};

inline const TypeInfo& info(Type t) { return kTypes[static_cast<int>(t)]; }
inline bool is_integer(Type t) { return t != Type::float32 && t != Type::float64; }

// Integer-typed values must be integral and in range; NaN is only representable in float types.
inline bool fits(Type t, double v) {
    if (!is_integer(t)) return true;
    return std::isfinite(v) && v == std::floor(v) && v >= info(t).lo && v <= info(t).hi;
}

constexpr bool kLittleEndianHost = std::endian::native == std::endian::little;

}  // namespace sffd::ply::detail
