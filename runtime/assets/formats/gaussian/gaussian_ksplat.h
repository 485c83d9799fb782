// GaussianSplats3D `.ksplat` (Mark Kellogg's viewer), read only. Layout as splat-transform 3.7.0's reader
// documents it (little endian):
//   main header, 4096 bytes: u8 major 0, u8 minor >= 1, u32 maxSections at 4, u32 splat count at 16,
//     u16 compression mode (0..2) at 20, f32 min / max SH value at 36 / 40 (0 means -1.5 / 1.5)
//   maxSections section headers of 1024 bytes: u32 splats at 0, u32 capacity at 4, u32 bucket capacity
//     at 8, u32 bucket count at 12, f32 spatial block size at 16, u16 bucket storage size at 20, u32
//     quantisation range at 24 (0: the mode's), u32 full buckets at 32, u32 partial buckets at 36, u16
//     SH degree at 40
//   per section: u32 sizes of the partial buckets, f32 xyz bucket centres, then `capacity` records:
//     mode 0: position 3 x f32, scale 3 x f32, rotation 4 x f32 (w x y z), RGBA u8, SH f32;
//     modes 1 and 2: position 3 x u16 ((u - range) * block / 2 / range + bucket centre), scale and
//     rotation as f16, RGBA u8, SH f16 (mode 1) or u8 within [min, max] (mode 2).
//   SH per record: band 1 per channel (R 3, G 3, B 3), then band 2 per channel (5 each), then band 3 (7).
// Scales are linear, colour RGB = 0.5 + C0 f_dc, opacity = A / 255. Axes: the 3DGS PLY frame (as stored).
// Errors read `file: problem`: bad version or mode, counts that do not add up, sections, buckets or
// records outside the file (checked before anything is allocated), non-finite or negative scales,
// zero rotations.
#pragma once

#include <filesystem>

#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd::gaussian {

Result<GaussianCloud> read_ksplat(const std::filesystem::path& path);

}  // namespace sffd::gaussian
