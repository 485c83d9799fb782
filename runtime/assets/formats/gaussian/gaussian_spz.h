// Niantic SPZ Gaussian files: versions 2 and 3 (one gzip stream) and 4 (zstd streams), read; 3 and 4
// written.
// Versions 2 and 3, after gunzip: 16-byte header (u32 magic 'NGSP' = 0x5053474e, u32 version,
// u32 numPoints, u8 shDegree, u8 fractionalBits, u8 flags, u8 reserved), then per attribute, all splats:
//   positions  3 × 24-bit signed fixed point (little endian), value = fixed / 2^fractionalBits
//   alphas     u8, opacity = a / 255
//   colours    3 × u8, DC coefficient = (c / 255 − 0.5) / 0.15 (SPZ's colour scale, not C0)
//   scales     3 × u8, log scale = s / 16 − 10
//   rotations  v2: 3 × u8 xyz = b / 127.5 − 1, w = sqrt(1 − |xyz|²);
//              v3: u32 "smallest three": 2-bit index of the largest component, three 10-bit
//              (9-bit magnitude × √½ / 511, sign bit) for the others
//   SH         (K − 1) × 3 × u8 per splat, coefficient-major with RGB inner, value = (b − 128) / 128
//              (SPZ allows degree 4, K = 25: read as degree 3, band 4 dropped and logged)
// Version 4 (the reference library's current default; gaussian_spz4.cpp): not gzipped. A 32-byte
// header (u32 magic, u32 version 4, u32 numPoints, u8 shDegree, u8 fractionalBits, u8 flags,
// u8 numStreams, u32 tocByteOffset, 12 reserved bytes), extension records (u32 type, u32 length,
// payload; flag 0x2) up to tocByteOffset, a table of numStreams × (u64 compressed, u64 decoded
// size), then one zstd frame per non-empty array above in the same order (5 streams at degree 0,
// else 6). Unknown extensions are skipped; SPZ_ADOBE_coordinate_system (0xADBE0003, data stored in
// another frame) is refused. Checked before allocating: the count against the reference's 1024:1 bound
// on the file size, each table size against the count, the streams tiling the file exactly; then each
// frame must decode to exactly its array (zstd checks a frame's checksum when it has one; ours do).
// Axes: SPZ is stored x right, y up, z back (RUB, the SPZ README); the reader turns the cloud 180
// degrees about x into the internal 3DGS PLY frame (gaussian_axes.h).
// Errors name the file: not gzip/SPZ, unsupported version or degree, a splat count the compressed
// size cannot hold (refused before allocating; deflate expands at most 1032:1), budgets (2 GiB file,
// 4 GiB decoded, gaussian_io.h's kMaxGaussians), truncated data, decoded data longer than declared, a
// bad gzip CRC or length.
#pragma once

#include <filesystem>

#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd::gaussian {

Result<GaussianCloud> read_spz(const std::filesystem::path& path);
// Version 3 (gzip level 6) or 4 (zstd level 12, frame checksums), turned into RUB
// (gaussian_spz_write.cpp); up to 12 fractional bits, fewer when a coordinate needs them. Version 3 is
// the default because every SPZ reader so far reads it; version 4 needs a recent one. Saved to a
// temporary and renamed.
Status write_spz(const std::filesystem::path& path, const GaussianCloud& cloud, int version = 3);

}  // namespace sffd::gaussian
