// The optional point columns (runtime/scene/point_columns.h: PointFlags, PointWeights) as glTF vertex
// attributes of a cloud's POINTS primitive, the same for both kinds (surface splat nodes, embedded
// KHR_gaussian_splatting primitives). Application-specific attribute names start with an underscore:
//   _FLAGS   unsigned byte SCALAR, not normalised, in a buffer view of byteStride 4 (glTF's alignment of
//            vertex attributes): the kPointSelected (1) and kPointHidden (2) bits. Written only when a
//            point has one; deleted points are never saved (the caller drops them: point_subset.h).
//   _WEIGHT  float SCALAR in [0, 1]: the deformation weight. Written only when the cloud has weights.
// A file without them loads with no PointFlags / PointWeights component (every point at the default).
#pragma once

#include <cstddef>
#include <map>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "runtime/core/result.h"
#include "runtime/scene/point_columns.h"

namespace sffd::assets {

struct GltfModel;  // gltf_model.h

// Appends the accessors (and their buffer views, 4-byte aligned, to `bin`) of the cloud's optional
// columns, naming them in `attributes`. Fails when a column is neither empty nor one value per point, or a
// weight is outside [0, 1]; `what` names the cloud in the message.
Status append_point_columns(nlohmann::json& accessors, nlohmann::json& views, std::string& bin,
                            nlohmann::json& attributes, std::size_t points, const PointFlags* flags,
                            const PointWeights* weights, const std::string& what);

// Reads `_FLAGS` and `_WEIGHT` from a primitive's attributes (replacing `flags` and `weights`; left empty
// when absent), every value checked once: a count other than `points`, a flag value with another bit
// than selected and hidden, a weight outside [0, 1] (or not finite) is refused with "`what`: ...".
Status read_point_columns(const GltfModel& model, const std::map<std::string, int>& attributes,
                          std::size_t points, const std::string& what, PointFlags& flags,
                          PointWeights& weights);

}  // namespace sffd::assets
