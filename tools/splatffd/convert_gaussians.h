// `splatffd convert IN OUT --gaussians`: writes 3D Gaussians (3DGS PLY, or glTF
// KHR_gaussian_splatting .glb). IN is either a Gaussian file (.splat, .spz, 3DGS or compressed PLY, KHR
// .glb/.gltf) or any surface-splat input, converted by gaussian::gaussians_from_splats (flat Gaussians, σ =
// 0.7 × radius).
#pragma once

#include <chrono>
#include <string>
#include <vector>

#include "tools/splatffd/lattice_source.h"

namespace sffd {
struct GaussianCloud;
struct SplatCloud;
struct SplatMaterial;
}  // namespace sffd

namespace sffd::cli {

// True when `in` is a file whose contents are already Gaussians (convert then keeps them Gaussians).
bool is_gaussian_file(const std::string& in);

// --lattice for a Gaussian output: `source` a fit spec (fitted around the Gaussians' centres) or the lattice
// JSON / scene whose `loaded` chain binds; empty `source`: no lattice.
struct GaussianLatticeRequest {
    std::string source;
    const LatticeChain* loaded = nullptr;
};

// Writes `out` from the Gaussian file `in` (when `surface` is null) or from `surface`. Returns the exit code.
// `turn_x180`: turn the cloud 180 degrees about x before writing (gaussian_axes.h; a y-up file). With a
// lattice, `out` is a scene (.glb/.gltf): the Gaussians embedded as KHR_gaussian_splatting, the lattice
// bound to them as in the editor's save, so render/view deform the Gaussians by it.
// `spz_version`: 3 or 4 for an `.spz` OUT (gaussian_spz.h).
// `material`: the surface cloud's material (its base colour for splats without colours).
// `weights`: the surface cloud's PointWeights (one per splat, or empty); a Gaussian file IN brings its own
// (a 3DGS PLY's `weight` column, runtime/assets/formats/surface/ply_weights.h).
int write_gaussians(const std::string& in, const SplatCloud* surface, const SplatMaterial& material,
                    const std::string& out, bool ascii, bool turn_x180 = false, int spz_version = 3,
                    const GaussianLatticeRequest& lattice = {}, bool morton_order = false,
                    std::vector<float> weights = {});
// The same for a cloud already in memory (a scene's, posed by the caller); `name` names it in a scene OUT,
// `note_after` ends the summary line ("wrote OUT: N Gaussians, SH degree D<note_after> (T s)"), `t0` starts
// its time. `morton_order` (convert --order morton): the Gaussians are written in Morton order of their
// centres as written (after any turn; runtime/scene/point_order.h), every column moved together.
// `weights` (PointWeights: empty, or one per Gaussian) move with their Gaussians and are written where the
// format holds them: a 3DGS PLY's `weight` property, a scene's `_WEIGHT`; SPZ, SOG and compressed PLY
// have no place for them.
int write_gaussian_cloud(GaussianCloud cloud, const std::string& name, const std::string& out, bool ascii,
                         bool turn_x180, int spz_version, const GaussianLatticeRequest& lattice,
                         const std::string& note_after, std::chrono::steady_clock::time_point t0,
                         bool morton_order = false, std::vector<float> weights = {});

}  // namespace sffd::cli
