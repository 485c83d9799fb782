// The in-place path of read_ply_geometry's vertex element (internal to runtime/assets): binary little-endian
// vertex rows without lists (ply_mapped.h) are decoded from the mapped file into the Geometry's arrays in
// parallel over rows, every scalar type converted as ply::Reader converts it (exactly, through double).
#pragma once

#include <filesystem>
#include <optional>

#include "runtime/assets/import.h"
#include "runtime/assets/formats/surface/ply.h"
#include "runtime/core/result.h"

namespace sffd::assets::detail {

// Vertex property indices read_ply_geometry found (-1: absent) and the colour channels' scales to [0, 1].
struct PlyVertexColumns {
    int pos[3] = {-1, -1, -1};
    int normal[3] = {-1, -1, -1};
    int color[4] = {-1, -1, -1, -1};  // r g b and a (a may be -1: opaque)
    double color_scale[4] = {1, 1, 1, 1};
    int uv[2] = {-1, -1};
    int axes[6] = {-1, -1, -1, -1, -1, -1};
    int uv_frame[4] = {-1, -1, -1, -1};
    bool has_normals = false, has_colors = false, has_uvs = false, has_axes = false, has_uv_frame = false;
};

// Empty when the vertex rows cannot be mapped (the caller reads them through ply::Reader); otherwise the
// outcome, with g.positions (and normals, colors, uvs, axes, uv_axes as present) filled. Errors as the
// column path's: "file: vertex N has a non-finite colour".
std::optional<Status> read_ply_vertices_mapped(const std::filesystem::path& path, const ply::Header& header,
                                               const PlyVertexColumns& c, Geometry& g);

}  // namespace sffd::assets::detail
