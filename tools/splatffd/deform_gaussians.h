// `splatffd deform` on 3DGS PLY files: cmd_deform.cpp hands a file whose vertex element has
// the 3DGS properties (f_dc_0, opacity, scale_0, rot_0) to this path.
#pragma once

#include <string>
#include <vector>

namespace sffd {
struct Lattice;
struct GaussianCloud;
}  // namespace sffd

namespace sffd::cli {

// backend: "cpu" or "reference" (there is no GPU Gaussian deformer yet). Returns the exit code.
int deform_gaussian_ply(const std::string& in, const std::string& out, const Lattice& lattice,
                        const std::string& lattice_path, const std::string& backend, int bench, bool ascii);

// A scene's Gaussian cloud (a saved editor scene, `convert g.ply s.glb --lattice fit`) deformed by
// `lattices` in order on the CPU and written as Gaussians (OUT .ply 3DGS or .glb KHR_gaussian_splatting).
// `names` (the lattices') and `what` (all of them) name them in the summary and warnings. Returns the exit
// code.
int deform_gaussian_cloud(GaussianCloud cloud, const std::vector<Lattice>& lattices,
                          const std::vector<std::string>& names, const std::string& what,
                          const std::string& out, bool ascii);

}  // namespace sffd::cli
