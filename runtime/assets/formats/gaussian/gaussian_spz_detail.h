// What the SPZ readers and writer share (gaussian_spz.h describes the format): the attribute layout,
// which is the same in every version from 2 on, whether the arrays travel as one gzip stream (v2, v3)
// or as one zstd stream each (v4, gaussian_spz4.cpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd::gaussian::spz_detail {

inline constexpr std::uint32_t kMagic = 0x5053474e;  // "NGSP"
// Budgets (the messages quote them): the file and the decoded attribute data.
inline constexpr std::uint64_t kMaxFileBytes = std::uint64_t(2) << 30;
inline constexpr std::uint64_t kMaxDecodedBytes = std::uint64_t(4) << 30;
// The most decoded bytes a compressed byte may stand for (the reference loader's bound for version 4;
// version 3 holds its whole decoded size to it as well).
inline constexpr std::uint64_t kMaxRatio = 1024;

inline std::uint32_t u32(const unsigned char* p) {
    return std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 | std::uint32_t(p[2]) << 16 |
           std::uint32_t(p[3]) << 24;
}

// SH coefficients per colour channel beyond the DC term for a file's degree (0..4; SPZ allows 4).
inline std::size_t rest_coeffs(int degree) { return std::size_t((degree + 1) * (degree + 1) - 1); }

// Bytes of each attribute array for `n` splats, in file order: positions, alphas, colours, scales,
// rotations, SH.
struct Arrays {
    std::uint64_t bytes[6];
};
Arrays array_sizes(std::uint32_t version, std::uint64_t n, int degree);

// Decodes the six arrays, laid out back to back in `data` as array_sizes() says, into the internal
// frame. A file of degree 4 gives a degree-3 cloud: the SH basis is orthonormal, so dropping band 4
// leaves the closest degree-3 colour (the caller logs it).
GaussianCloud decode(std::uint32_t version, std::uint32_t n, int degree, int frac,
                     const std::vector<unsigned char>& data);

// Version 4: the 32-byte header, the table of contents and the zstd streams (gaussian_spz4.cpp).
// `file` is the whole file, which starts with the NGSP magic and version 4.
Result<GaussianCloud> read_v4(const std::string& name, const std::vector<unsigned char>& file);

// The six arrays of `cloud` (already in SPZ's RUB axes) for a version >= 3 file; false with `why` when a
// coordinate does not fit 24 bits.
struct Encoded {
    std::uint32_t n = 0;
    int degree = 0, frac = 0;
    std::string arrays[6];
};
Result<Encoded> encode(const GaussianCloud& rub);
// The version-4 container around the arrays (zstd level 12 with frame checksums).
Result<std::string> pack_v4(const Encoded& e);

}  // namespace sffd::gaussian::spz_detail
