// `splatffd deform` on Gaussian files: a 3DGS PLY (a vertex element with f_dc_0, opacity, scale_0, rot_0)
// into a 3DGS PLY is streamed by ffd::stream_deform (report_gaussian_stream prints it); every other Gaussian
// input (compressed PLY, SOG, SPZ v2-v4, .splat, .ksplat, KHR glTF; or a 3DGS PLY written to another format)
// is read whole, deformed on the CPU and written by OUT's extension (deform_gaussian_file).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "runtime/core/result.h"

namespace sffd {
struct Lattice;
struct GaussianCloud;
}  // namespace sffd
namespace sffd::ffd {
struct StreamDeformResult;
}  // namespace sffd::ffd

namespace sffd::cli {

struct LatticeChain;

// The Gaussian formats deform writes, by OUT's name: .ply (3DGS), .compressed.ply (PlayCanvas), .spz (v3),
// .glb (KHR_gaussian_splatting), .sog or a SOG folder's meta.json.
bool is_gaussian_output(const std::string& out);

// True when IN (not a scene file) holds Gaussians that deform reads whole: every Gaussian format except a
// 3DGS PLY going to a 3DGS PLY, which deform_gaussian_ply streams.
bool deform_reads_gaussians_whole(const std::string& in, const std::string& out);

// IN read whole (gaussian::read_gaussians: the file's frame, as the streamed path deforms it), the lattices
// `chain` gives for its centres applied in order on the CPU, OUT written by its extension. backend and bench
// are checked (only the CPU runs here; --bench is the streamed path's). Returns the exit code.
int deform_gaussian_file(const std::string& in, const std::string& out,
                         const std::function<Result<LatticeChain>(const GaussianCloud&)>& chain,
                         const std::string& backend, int bench, bool ascii);

// Prints the summary (and with bench > 0 the JSON timing line) of a 3DGS PLY that ffd::stream_deform
// streamed through the lattice `lattice_path` names. Returns the exit code.
int report_gaussian_stream(const ffd::StreamDeformResult& result, const std::string& lattice_path,
                           const std::string& backend, int bench);

// A scene's Gaussian cloud (a saved editor scene, `convert g.ply s.glb --lattice fit`) deformed by
// `lattices` in order on the CPU and written as Gaussians (OUT as is_gaussian_output() lists).
// `names` (the lattices') and `what` (all of them) name them in the summary and warnings. Returns the exit
// code. `weights`: one per Gaussian (the cloud's PointWeights) or null (weight 1): P + w (FFD(P) - P).
int deform_gaussian_cloud(GaussianCloud cloud, const std::vector<Lattice>& lattices,
                          const std::vector<std::string>& names, const std::string& what,
                          const std::string& out, bool ascii, const float* weights = nullptr);

}  // namespace sffd::cli
