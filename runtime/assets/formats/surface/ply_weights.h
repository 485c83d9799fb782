// The per-point deformation weight of a PLY file: a scalar vertex property `weight` (float; surface PLY or
// 3DGS PLY alike), read as PointWeights (runtime/scene/point_columns.h). The one reader of that column:
// `deform` streams it (systems/ffd/stream_deform.cpp: the property and the check), `render`, `view`,
// `convert` and `info` load it beside the cloud (runtime/assets/scene.cpp, systems/gaussian's file
// loader).
//
// A weight that is NaN or outside [0, 1] is refused, naming the file and the vertex:
// "FILE: vertex i: weight w is not in [0, 1]".
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

#include "runtime/assets/formats/surface/ply.h"
#include "runtime/core/result.h"
#include "runtime/scene/point_columns.h"

namespace sffd::assets {

inline constexpr const char* kPlyWeightProperty = "weight";

// The index of the vertex element's scalar `weight` property, or -1 (absent, or a list).
int ply_weight_property(const ply::Element& vertex);

// Checks rows [first, first + rows) of a file's weights (values[r] is row first + r).
Status check_ply_weights(std::span<const double> values, std::size_t rows, std::uint64_t first,
                         const std::string& path);

// The `weight` column of the file's vertex element, one value a vertex, as PointWeights; empty (no
// component to add) when the file has no such property. Errors name the file (and the vertex of a bad
// weight).
Result<PointWeights> read_ply_weights(const std::filesystem::path& path);

// The weights of a cloud of `points` points read from `path` (any file: only a PLY has them), for a
// loader to put beside it: the file's `weight` column when the cloud is one point a vertex in file order
// (a point cloud, a 3DGS PLY); empty without the column, or, with a warning naming the file, when the
// cloud's points are not the file's vertices (sampled from a mesh's faces, or thinned by convert).
Result<PointWeights> cloud_weights_of_file(const std::filesystem::path& path, std::size_t points);

}  // namespace sffd::assets
