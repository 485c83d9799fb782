// Reading any Gaussian file into a GaussianCloud ready for the scene: the format readers
// (runtime/assets/formats/gaussian) chosen by extension, with a glTF node's world matrix applied by the
// Gaussian maths that lives here (Σ' = A Σ Aᵀ, SH rotated by the polar rotation of A). Commands, systems
// and tests read files through these two; the formats alone cannot place a non-rigid glTF node.
#pragma once

#include <filesystem>

#include <glm/glm.hpp>

#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd::gaussian {

// By extension: .ply (3DGS or compressed, gaussian_compressed_ply.h), .splat, .spz (v2-v4, gaussian_spz.h),
// .ksplat (gaussian_ksplat.h), .sog, a SOG folder or its meta.json (any .json; gaussian_sog.h), .glb/.gltf
// (KHR_gaussian_splatting, gaussian_gltf.h) or a streamed SOG's lod-meta.json (its finest level, every
// leaf's level-0 Gaussians in tree order: runtime/assets/formats/lod/streamed_sog.h read_level). Every
// cloud returned has passed validate().
Result<GaussianCloud> read_gaussians(const std::filesystem::path& path);

// A KHR_gaussian_splatting file, each primitive placed by apply_affine (gaussian_gltf.h's reader).
Result<GaussianCloud> read_gltf(const std::filesystem::path& path);

// Applies x -> A x + t (world space, double) to a cloud in place: centres, Σ' = A Σ Aᵀ, SH rotated by the
// polar rotation of A. Used for glTF node matrices.
void apply_affine(GaussianCloud& cloud, const glm::dmat3& a, const glm::dvec3& t);

}  // namespace sffd::gaussian
