// Writing splat clouds. Every save is atomic (temp + rename).
//
// PLY (binary little-endian by default, or ascii): vertex properties
//   x y z                 float (cloud.origin == 0) or double world coordinates (origin != 0, so other
//                         tools see the scan in place); "comment sffd_origin ox oy oz" records the origin
//   nx ny nz              float (when the cloud has normals)
//   red green blue alpha  uchar, sRGB (when it has colours)
//   u v                   float (when it has texture coordinates; texture row 0 at v = 0)
//   axis_ux .. axis_vz    float: the splat's tangent axes scaled by its radii
//   du_ds dv_ds du_dt dv_dt  float: the uv frame (SplatCloud::uv_axes; with the axes only)
// plus "comment TextureFile <texture_path>" when the texture names a file; texels without a file
// (a procedural or converted mesh's texture) are written to <stem>_texture.png beside the PLY and named
// by that comment. read_ply_geometry() reads all of these back.
// glTF: the uv frame is the float VEC4 attribute _UV_AXES.
// GLB/glTF: see gltf_io.h.
#pragma once

#include <filesystem>
#include <span>

#include "runtime/assets/formats/surface/ply.h"
#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd::assets {

// `weights`: empty, or one per point (PointWeights), written as a last float property `weight`
// (runtime/assets/formats/surface/ply_weights.h reads it back).
Status save_splat_ply(const SplatCloud& cloud, const std::filesystem::path& path,
                      ply::Format format = ply::Format::binary_little_endian,
                      std::span<const float> weights = {});
// The material goes into the glTF material; a PLY file has none (it reads back as the defaults).
// `weights` (empty, or one per point) as the `_WEIGHT` attribute (content/README.md).
Status save_splat_glb(const SplatCloud& cloud, const std::filesystem::path& path,
                      const std::string& name = "cloud", const SplatMaterial& material = {},
                      std::span<const float> weights = {});
// By extension: .ply, .glb, .gltf; the weights in each as above.
Status save_splat_cloud(const SplatCloud& cloud, const std::filesystem::path& path,
                        const std::string& name = "cloud", const SplatMaterial& material = {},
                        std::span<const float> weights = {});

}  // namespace sffd::assets
