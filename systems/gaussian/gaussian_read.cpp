#include "systems/gaussian/gaussian_read.h"

#include <algorithm>
#include <cctype>
#include <string>

#include "runtime/assets/formats/gaussian/gaussian_ksplat.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"
#include "runtime/assets/formats/gaussian/gaussian_spz.h"
#include "runtime/assets/formats/lod/streamed_sog.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/sh.h"

namespace sffd::gaussian {
namespace fs = std::filesystem;

void apply_affine(GaussianCloud& g, const glm::dmat3& a, const glm::dvec3& t) {
    const int K = sh_coeffs(g.sh_degree);
    const Polar p = polar_decomposition(a);
    const ShRotation rot = sh_rotation(p.rotation, g.sh_degree);
    for (std::size_t i = 0; i < g.size(); ++i) {
        g.positions[i] = glm::vec3(a * (g.origin + glm::dvec3(g.positions[i])) + t - g.origin);
        const ScaleRotation sr = decompose_covariance(
            a * covariance(glm::dvec3(g.scales[i]), glm::dquat(g.rotations[i])) * glm::transpose(a));
        g.scales[i] = glm::vec3(sr.scale);
        g.rotations[i] = glm::quat(sr.rotation);
        if (K > 1 && p.ok) sh_rotate(rot, &g.sh[i * std::size_t(K) * 3], &g.sh[i * std::size_t(K) * 3]);
    }
}

Result<GaussianCloud> read_gltf(const fs::path& path) { return read_gltf(path, &apply_affine); }

Result<GaussianCloud> read_gaussians(const fs::path& path) {
    std::string ext = path.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    Result<GaussianCloud> g =
        make_error(path.string() + ": unknown Gaussian splat format '" + ext +
                   "' (expected .ply, .splat, .spz, .ksplat, .sog, a SOG folder's meta.json, .glb or .gltf)");
    if (path.filename() == "lod-meta.json") {
        // A streamed SOG at full detail: every leaf's level-0 Gaussians as one cloud.
        auto s = lod::open_streamed_sog(path);
        g = s ? lod::read_level(*s, 0) : Result<GaussianCloud>(s.error());
    } else if (ext == ".ply") g = read_ply(path);
    else if (ext == ".splat") g = read_splat(path);
    else if (ext == ".glb" || ext == ".gltf") g = read_gltf(path, &apply_affine);
    else if (ext == ".spz") g = read_spz(path);
    else if (ext == ".ksplat") g = read_ksplat(path);
    else if (ext == ".sog" || ext == ".json") g = read_sog(path);
    else if (std::error_code ec; fs::is_regular_file(path / "meta.json", ec))
        g = read_sog(path / "meta.json");
    if (!g) return g;
    // The one validation every cloud from a file passes, after the readers' transforms.
    if (Status s = validate(*g, path.string()); !s) return s.error();
    return g;
}

}  // namespace sffd::gaussian
