// The float32 fast path of read_ply (gaussian_io.h): a binary little-endian 3DGS PLY whose 3DGS properties
// are all float32 (what every trainer writes) is decoded from the memory-mapped file straight into the
// cloud's arrays, in parallel over rows, without ply::Reader's double columns. Same checks, same messages,
// same values as the column path (float32 -> double -> the same conversions). Internal to the system.
#pragma once

#include <filesystem>
#include <optional>

#include "runtime/core/result.h"
#include "runtime/scene/components.h"
#include "runtime/assets/formats/gaussian/gaussian_infinity.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"

namespace sffd::gaussian::detail {

// Empty when the file does not qualify (the caller reads it through ply::Reader); otherwise the read's
// outcome, `out` filled (sh_degree = layout.degree) and `mapped` counted.
std::optional<Status> read_ply_float32(const std::filesystem::path& path, const ply::Header& header,
                                       const PlyLayout& layout, GaussianCloud& out, InfinityCount& mapped);

}  // namespace sffd::gaussian::detail
