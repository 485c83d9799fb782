// Gaussian splat files: the 3DGS PLY layout (read and write, binary little endian or ASCII,
// degrees 0..3) and antimatter15's `.splat` (read).
//
// 3DGS PLY (graphdeco-inria/gaussian-splatting, scene/gaussian_model.py save_ply/load_ply): element
// `vertex` with `x y z`, optional `nx ny nz` (ignored on read, written as 0 like the reference),
// `f_dc_0..2`, `f_rest_0..f_rest_{3(K−1)−1}` per channel (all R coefficients k=1..K−1, then G, then B;
// K = (degree+1)², so 0, 9, 24 or 45 of them give degrees 0..3), `opacity` (logit), `scale_0..2` (natural
// log), `rot_0..3` (quaternion w, x, y, z; normalised on read). Any scalar PLY type is accepted on read;
// we write float. Other properties and elements are ignored on read.
//
// .splat: 32 bytes per splat, little endian: position 3×f32, scale 3×f32 (linear), colour RGBA u8
// (RGB = 255·(0.5 + C0·f_dc), A = 255·opacity), rotation 4×u8 (w, x, y, z), component = (byte − 128)/128,
// normalised on read. Degree 0.
//
// Errors read `file: problem`: truncated data, missing or unexpected properties (an f_rest count that is
// not 0/9/24/45), non-finite values, zero-length quaternions, sizes that are not a multiple of 32 bytes.
// Declared counts are checked against the file size before anything is allocated (ply::Reader does it for
// PLY; `.splat` has no count). Reading goes through ply::Reader / one FILE* so the coming shared
// read-file helper (runtime/core) can replace the opening in one place (`open_splat_file`).
#pragma once

#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "runtime/assets/formats/surface/ply.h"
#include "runtime/core/result.h"
#include "runtime/scene/components.h"
#include "runtime/assets/formats/gaussian/gaussian_infinity.h"

namespace sffd::gaussian {

// Which columns of a vertex element hold the 3DGS properties.
struct PlyLayout {
    int x = -1, y = -1, z = -1;
    int dc[3] = {-1, -1, -1};
    std::vector<int> rest;  // f_rest_0 .. f_rest_{n-1}
    int opacity = -1;
    int scale[3] = {-1, -1, -1};
    int rot[4] = {-1, -1, -1, -1};
    int degree = 0;
};

// True when the element has the 3DGS properties (f_dc_0, opacity, scale_0, rot_0): what `deform` uses
// to pick the Gaussian path.
bool is_gaussian_element(const ply::Element& vertex);
// Validates and maps the properties; messages "name: problem".
Result<PlyLayout> ply_layout(const ply::Element& vertex, const std::string& name);

// Converts rows of a chunk into Gaussians appended to `out` (out.sh_degree must equal layout.degree).
// `first_row` numbers the rows in error messages.
// Logit opacities of ±inf and log scales of -inf are read as limits (gaussian_infinity.h) and counted
// in `mapped` when given.
Status append_from_chunk(const ply::Chunk& chunk, const PlyLayout& layout, std::uint64_t first_row,
                         const std::string& name, GaussianCloud& out, InfinityCount* mapped = nullptr);
// The vertex element we write for a degree (x y z nx ny nz f_dc_0..2 f_rest_.. opacity scale_0..2 rot_0..3).
ply::Element ply_element(int degree, std::uint64_t count);
// Fills `chunk` (reset to ply_element) with splats [first, first+count) of `cloud` in file units.
void fill_chunk(const GaussianCloud& cloud, std::size_t first, std::size_t count, ply::Chunk& chunk);

Result<GaussianCloud> read_ply(const std::filesystem::path& path);
// `weights`: empty, or one per Gaussian (PointWeights), written as a last float property `weight`
// (runtime/assets/formats/surface/ply_weights.h reads it back).
Status write_ply(const std::filesystem::path& path, const GaussianCloud& cloud,
                 ply::Format format = ply::Format::binary_little_endian, std::span<const float> weights = {});
Result<GaussianCloud> read_splat(const std::filesystem::path& path);
// Any Gaussian file by its extension: read_gaussians() in systems/gaussian/gaussian_read.h (a glTF node's
// matrix needs the Gaussian maths, which the formats do not link).

// Unit conversions between the files and GaussianCloud (double inside; logit saturates at p = 0 or 1 to
// ∓ kMaxLogit, the logit of 1 − 2⁻²⁴ in magnitude, so written files stay finite).
// Y_0 = 1/(2 sqrt(pi)), the DC basis value: a colour channel is 0.5 + kShDc * f_dc (the value of
// systems/gaussian/sh.h's kShC0, which the readers do not need the rest of).
inline constexpr double kShDc = 0.28209479177387814;
inline constexpr double kMaxLogit = 16.635532273834041;  // log(2²⁴ − 1)
float sigmoid(double logit);
double logit(double p);

// Budgets and bounds, stated once (messages quote them). Every cloud a reader returns has passed
// validate() after all its transforms (glTF nodes, the origin): values beyond these bounds are refused
// rather than left to overflow in a projection (a coordinate of 1e30 blanks a whole render).
inline constexpr std::uint64_t kMaxGaussians = std::uint64_t(1) << 26;  // 67M: ~16 GB as a degree-3 cloud
inline constexpr double kMaxCoordinate = 1e10;                          // |origin + position| per axis
inline constexpr double kMaxScale = 1e10;                               // linear standard deviation
inline constexpr double kMaxShMagnitude = 1e6;                          // |SH coefficient|

// The unit quaternion (w, x, y, z) in any finite magnitude: divides by the largest component first so
// 1e200 does not overflow to a zero quaternion. False when all four are zero or one is not finite.
bool normalize_quaternion(double w, double x, double y, double z, glm::quat& out);

// Checks a cloud's array sizes and values (finite, scales in [0, kMaxScale], coordinates within
// ±kMaxCoordinate, opacities in [0,1], unit quaternions within 1e-3, |SH| <= kMaxShMagnitude); messages
// "what: Gaussian i: field = value: problem", i counted from `first_index` (a chunk's first row).
Status validate(const GaussianCloud& cloud, const std::string& what, std::uint64_t first_index = 0);

}  // namespace sffd::gaussian

namespace sffd::gaussian {

// Writes Gaussians [0, chunk.rows) of `g` back into the columns `layout` names (x y z, f_dc, f_rest, scale,
// rot; opacity too when `opacity`), leaving every other column of the chunk as read: `deform` keeps
// the file's other properties and types.
void store_to_chunk(const GaussianCloud& g, const PlyLayout& layout, bool opacity, ply::Chunk& chunk);

}  // namespace sffd::gaussian
