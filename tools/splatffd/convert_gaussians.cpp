#include "tools/splatffd/convert_gaussians.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "runtime/assets/ply.h"
#include "runtime/scene/components.h"
#include "systems/gaussian/from_splats.h"
#include "systems/gaussian/gaussian_axes.h"
#include "systems/gaussian/gaussian_compressed_ply.h"
#include "systems/gaussian/gaussian_gltf.h"
#include "systems/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_spz.h"

namespace sffd::cli {

namespace {
std::string lower_ext(const std::string& p) {
    std::string e = std::filesystem::path(p).extension().string();
    std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return e;
}
}  // namespace

bool is_gaussian_file(const std::string& in) {
    const std::string e = lower_ext(in);
    if (e == ".splat" || e == ".spz" || e == ".ksplat") return true;
    if (e == ".ply") {
        auto r = ply::Reader::open(in);
        const int v = r ? r->header().find("vertex") : -1;
        return v >= 0 && (gaussian::is_gaussian_element(r->header().elements[std::size_t(v)]) ||
                          gaussian::is_compressed_ply(r->header()));
    }
    // By declaration, not by whether the Gaussian reader accepts it: a file that declares
    // KHR_gaussian_splatting is read as Gaussians or refused, never reinterpreted as surface splats.
    if (e == ".glb" || e == ".gltf") return gaussian::gltf_declaration(in).gaussian_splatting;
    return false;
}

int write_gaussians(const std::string& in, const SplatCloud* surface, const SplatMaterial& material,
                    const std::string& out, bool ascii, bool turn_x180) {
    const auto t0 = std::chrono::steady_clock::now();
    Result<GaussianCloud> g =
        surface ? Result<GaussianCloud>(gaussian::gaussians_from_splats(*surface, {.material = material}))
                : gaussian::read_gaussians(in);
    if (!g) {
        std::fprintf(stderr, "splatffd convert: %s\n", g.message().c_str());
        return 1;
    }
    if (turn_x180) gaussian::turn_axes(*g, gaussian::AxisTurn::x180);
    const std::string e = lower_ext(out);
    const bool compressed = out.size() >= 15 && lower_ext(out.substr(0, out.size() - 4)) == ".compressed";
    Status s =
        compressed ? gaussian::write_compressed_ply(out, *g)
        : e == ".ply"
            ? gaussian::write_ply(out, *g, ascii ? ply::Format::ascii : ply::Format::binary_little_endian)
        : e == ".glb" ? gaussian::write_glb(out, *g)
        : e == ".spz" ? gaussian::write_spz(out, *g)
                      : Status(make_error(out + ": Gaussians are written as .ply (3DGS), .compressed.ply "
                                                "(PlayCanvas), .spz (v3) or .glb (KHR_gaussian_splatting)"));
    if (!s) {
        std::fprintf(stderr, "splatffd convert: %s\n", s.message().c_str());
        return 1;
    }
    std::fprintf(stderr, "wrote %s: %zu Gaussians, SH degree %d (%.2f s)\n", out.c_str(), g->size(),
                 g->sh_degree, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    return 0;
}

}  // namespace sffd::cli
