// Niantic SPZ Gaussian files, versions 2 and 3 (one gzip stream), read only.
// Layout after gunzip: 16-byte header (u32 magic 'NGSP' = 0x5053474e, u32 version, u32 numPoints,
// u8 shDegree, u8 fractionalBits, u8 flags, u8 reserved), then per attribute, all splats:
//   positions  3 × 24-bit signed fixed point (little endian), value = fixed / 2^fractionalBits
//   alphas     u8, opacity = a / 255
//   colours    3 × u8, DC coefficient = (c / 255 − 0.5) / 0.15 (SPZ's colour scale, not C0)
//   scales     3 × u8, log scale = s / 16 − 10
//   rotations  v2: 3 × u8 xyz = b / 127.5 − 1, w = sqrt(1 − |xyz|²);
//              v3: u32 "smallest three": 2-bit index of the largest component, three 10-bit
//              (9-bit magnitude × √½ / 511, sign bit) for the others
//   SH         (K − 1) × 3 × u8 per splat, coefficient-major with RGB inner, value = (b − 128) / 128
// Axes: SPZ is stored x right, y up, z back (RUB, the SPZ README); the reader turns the cloud 180
// degrees about x into the internal 3DGS PLY frame (gaussian_axes.h).
// Version 4 (per-stream zstd with a table of contents) is refused with a hint (no zstd here):
// `splat-transform in.spz --spz-version 3 out.spz` re-encodes. Errors name the file: not gzip/SPZ,
// unsupported version or degree, a splat count the compressed size cannot hold (refused before
// allocating; deflate expands at most 1032:1), budgets (2 GiB file, 4 GiB decoded, gaussian_io.h's
// kMaxGaussians), truncated data, decoded data longer than declared, a bad gzip CRC or length.
#pragma once

#include <filesystem>

#include "runtime/core/result.h"
#include "systems/gaussian/components.h"

namespace sffd::gaussian {

Result<GaussianCloud> read_spz(const std::filesystem::path& path);
// Version 3, gzip level 6, turned into RUB (gaussian_spz_write.cpp); up to 12 fractional bits, fewer
// when a coordinate needs them. Saved to a temporary and renamed.
Status write_spz(const std::filesystem::path& path, const GaussianCloud& cloud);

}  // namespace sffd::gaussian
