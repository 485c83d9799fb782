// PlayCanvas compressed PLY (SuperSplat / splat-transform `.compressed.ply`), read and write.
//
// Layout (splat-transform's decompress-ply; binary little endian, elements in this order):
//   element chunk  ceil(N / 256) rows of float bounds for 256 consecutive splats:
//     min_x min_y min_z max_x max_y max_z, min_scale_x.. max_scale_z (natural-log scales),
//     optionally min_r min_g min_b max_r max_g max_b (colour bounds; without them colour is 0..1)
//   element vertex N rows of uint: packed_position (11/10/11-bit unorm x/y/z within the chunk bounds),
//     packed_rotation (2-bit index of the largest of w,x,y,z, then three 10-bit components,
//     (u − 0.5)·√2 each), packed_scale (11/10/11 within the chunk's log-scale bounds),
//     packed_color (8-bit r g b within the colour bounds, 8-bit linear opacity)
//   element sh     (optional) N rows of uchar f_rest_0.. (9, 24 or 45: SH degree 1..3, the 3DGS PLY
//     per-channel order), value = (b/256 + 1/512 − 0.5)·8, with 0 → −4 and 255 → +4 exactly
// Colour is RGB = 0.5 + C0·f_dc, so f_dc = (c − 0.5)/C0. Axes: stored as the 3DGS PLY convention
// (gaussian_io.h), like every PLY. Quantisation (what a writer loses, half a step): positions
// (max − min)/2047 per x/z axis and /1023 per y of a chunk, log scales likewise, colour 1/510 of the
// chunk range, opacity 1/510, SH 1/64, rotation components √2/2046.
//
// Errors read `file: problem`: missing or list properties, a chunk count that is not ceil(N/256), an sh
// element whose count differs from the vertex count or whose f_rest count is not 9/24/45, non-finite
// position or colour bounds, and whatever ply::Reader refuses (declared counts the file cannot hold are
// refused before anything is allocated). A -inf log-scale bound (flat splats) is read as a zero axis
// through gaussian_infinity.h and counted in the log line.
#pragma once

#include <filesystem>

#include "runtime/assets/formats/surface/ply.h"
#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd::gaussian {

// True when the header has a `chunk` element and a vertex element with packed_position.
bool is_compressed_ply(const ply::Header& header);
Result<GaussianCloud> read_compressed_ply(const std::filesystem::path& path);
// Writes the layout above (with colour bounds) in the cloud's order: 256 consecutive splats share one
// chunk's bounds, so a spatially sorted cloud quantises finer (splat-transform sorts by Morton code; we
// keep the order so indices stay meaningful). Zero scales are written as the log of 1e-30 (finite).
// The file goes to a temporary and is renamed (ply::Writer).
Status write_compressed_ply(const std::filesystem::path& path, const GaussianCloud& cloud);

}  // namespace sffd::gaussian
