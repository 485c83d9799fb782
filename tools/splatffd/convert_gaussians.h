// `splatffd convert IN OUT --gaussians`: writes 3D Gaussians (3DGS PLY, or glTF
// KHR_gaussian_splatting .glb). IN is either a Gaussian file (.splat, .spz, 3DGS or compressed PLY, KHR
// .glb/.gltf) or any surface-splat input, converted by gaussian::gaussians_from_splats (flat Gaussians, σ =
// 0.7 × radius).
#pragma once

#include <string>

namespace sffd {
struct SplatCloud;
struct SplatMaterial;
}  // namespace sffd

namespace sffd::cli {

// True when `in` is a file whose contents are already Gaussians (convert then skips the surface path).
bool is_gaussian_file(const std::string& in);
// Writes `out` from the Gaussian file `in` (when `surface` is null) or from `surface`. Returns the exit code.
// `turn_x180`: turn the cloud 180 degrees about x before writing (gaussian_axes.h; a y-up file).
int write_gaussians(const std::string& in, const SplatCloud* surface, const SplatMaterial& material,
                    const std::string& out, bool ascii, bool turn_x180 = false);

}  // namespace sffd::cli
