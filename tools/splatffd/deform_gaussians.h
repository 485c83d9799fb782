// `splatffd deform` on 3DGS PLY files: cmd_deform.cpp hands a file whose vertex element has
// the 3DGS properties (f_dc_0, opacity, scale_0, rot_0) to this path.
#pragma once

#include <string>

namespace sffd {
struct Lattice;
}

namespace sffd::cli {

// backend: "cpu" or "reference" (there is no GPU Gaussian deformer yet). Returns the exit code.
int deform_gaussian_ply(const std::string& in, const std::string& out, const Lattice& lattice,
                        const std::string& lattice_path, const std::string& backend, int bench, bool ascii);

}  // namespace sffd::cli
