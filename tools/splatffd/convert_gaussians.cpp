#include "tools/splatffd/convert_gaussians.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/surface/ply_weights.h"
#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_order.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/capture_up.h"
#include "systems/gaussian/from_splats.h"
#include "runtime/assets/formats/gaussian/gaussian_axes.h"
#include "systems/gaussian/gaussian_read.h"
#include "runtime/assets/formats/gaussian/gaussian_compressed_ply.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "runtime/assets/formats/gaussian/gaussian_sog.h"
#include "runtime/assets/formats/gaussian/gaussian_spz.h"
#include "systems/engine/engine_frame.h"

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
    if (e == ".splat" || e == ".spz" || e == ".ksplat" || e == ".sog") return true;
    if (std::filesystem::path(in).filename() == "meta.json") return true;      // a SOG folder
    if (std::filesystem::path(in).filename() == "lod-meta.json") return true;  // a streamed SOG (its level 0)
    if (std::error_code ec; std::filesystem::is_regular_file(std::filesystem::path(in) / "meta.json", ec))
        return true;  // a SOG folder given as the folder
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

namespace {

// The Gaussians and their lattice chain as one scene: the layout the editor saves (named lattices
// "<cloud>.lattice", ".lattice2", ..., bound in order), embedded because the cloud has no source file.
Status save_gaussian_scene(GaussianCloud g, const std::string& cloud_name, const GaussianLatticeRequest& req,
                           const std::string& out, std::string& note, std::vector<float> weights) {
    std::vector<Lattice> lattices;
    if (ffd::is_fit_spec(req.source)) {
        auto fit = ffd::parse_fit_spec(req.source);
        if (!fit) return fit.error();
        auto l = fit_lattice_for("convert", g.positions, g.origin, *fit);
        if (!l) return l.error();
        lattices.push_back(std::move(*l));
        note = ", lattice " + ffd::fit_spec_string(*fit) + " bound to them";
    } else {
        lattices = req.loaded ? req.loaded->lattices : std::vector<Lattice>{};
        note = ", " + std::to_string(lattices.size()) + " lattice(s) from " + req.source + " bound to them";
    }
    // Shown as the Gaussian file would be (capture_up.h), the lattices in the cloud's frame with it, as the
    // editor places a lattice it adds.
    const Transform shown = gaussian::capture_transform();
    ecs::Registry r;
    sffd::use_engine_scene_hooks(r);
    const ecs::Entity c = r.create();
    r.emplace<Name>(c, Name{cloud_name});
    r.emplace<Transform>(c, shown);
    r.emplace<GaussianCloud>(c, std::move(g));
    if (!weights.empty()) r.emplace<PointWeights>(c, PointWeights{std::move(weights)});
    Deformers d;
    for (std::size_t i = 0; i < lattices.size(); ++i) {
        const ecs::Entity l = r.create();
        r.emplace<Name>(l, Name{cloud_name + ".lattice" + (i ? std::to_string(i + 1) : std::string())});
        r.emplace<Transform>(l, shown);
        r.emplace<Lattice>(l, std::move(lattices[i]));
        d.lattices.push_back(l);
    }
    if (!d.lattices.empty()) r.emplace<Deformers>(c, std::move(d));
    return save_scene(r, out);
}

}  // namespace

int write_gaussians(const std::string& in, const SplatCloud* surface, const SplatMaterial& material,
                    const std::string& out, bool ascii, bool turn_x180, int spz_version,
                    const GaussianLatticeRequest& lattice, bool morton_order, std::vector<float> weights) {
    const auto t0 = std::chrono::steady_clock::now();
    Result<GaussianCloud> g =
        surface ? Result<GaussianCloud>(gaussian::gaussians_from_splats(*surface, {.material = material}))
                : gaussian::read_gaussians(in);
    if (!g) {
        std::fprintf(stderr, "splatffd convert: %s\n", g.message().c_str());
        return 1;
    }
    if (!surface) {  // a 3DGS PLY's own weights (one reader of the column: ply_weights.h)
        auto w = assets::cloud_weights_of_file(in, g->size());
        if (!w) {
            std::fprintf(stderr, "splatffd convert: %s\n", w.message().c_str());
            return 1;
        }
        weights = std::move(w->values);
    }
    // Surface splats live in the engine's y-up world; a Gaussian file is a capture, y down (capture_up.h),
    // so it opens upright here and in every other viewer. The turn is exact, and loading turns it back.
    if (surface && gaussian::capture_up() == gaussian::CaptureUp::minus_y)
        gaussian::turn_axes(*g, gaussian::AxisTurn::x180);
    else if (surface && gaussian::capture_up() != gaussian::CaptureUp::plus_y) {
        std::fprintf(
            stderr,
            "splatffd convert: --up %s: surface splats are written as Gaussians y down (the default) "
            "or, with --up y, y up\n",
            gaussian::capture_up_name(gaussian::capture_up()));
        return 2;
    }
    return write_gaussian_cloud(std::move(*g), std::filesystem::path(in).stem().string(), out, ascii,
                                turn_x180, spz_version, lattice, "", t0, morton_order, std::move(weights));
}

int write_gaussian_cloud(GaussianCloud cloud, const std::string& name, const std::string& out, bool ascii,
                         bool turn_x180, int spz_version, const GaussianLatticeRequest& lattice,
                         const std::string& note_after, std::chrono::steady_clock::time_point t0,
                         bool morton_order, std::vector<float> weights) {
    GaussianCloud* g = &cloud;
    if (!weights.empty() && weights.size() != g->size()) weights.clear();  // not one a Gaussian: none
    if (turn_x180) gaussian::turn_axes(*g, gaussian::AxisTurn::x180);
    if (morton_order) {
        const std::vector<std::uint32_t> order = sffd::morton_order(g->positions);
        if (Status s = permute(*g, order); !s) {
            std::fprintf(stderr, "splatffd convert: %s: %s\n", out.c_str(), s.message().c_str());
            return 1;
        }
        if (!weights.empty()) {
            std::vector<float> moved(weights.size());
            for (std::size_t k = 0; k < order.size(); ++k) moved[k] = weights[order[k]];
            weights = std::move(moved);
        }
    }
    const std::string e = lower_ext(out);
    if (!lattice.source.empty()) {
        const std::size_t count = g->size();
        const int degree = g->sh_degree;
        std::string note;
        if (Status s = save_gaussian_scene(std::move(*g), name, lattice, out, note, std::move(weights)); !s) {
            std::fprintf(stderr, "splatffd convert: %s\n", s.message().c_str());
            return 1;
        }
        std::fprintf(stderr, "wrote %s: %zu Gaussians, SH degree %d%s%s (%.2f s)\n", out.c_str(), count,
                     degree, note.c_str(), note_after.c_str(),
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        return 0;
    }
    const bool compressed = out.size() >= 15 && lower_ext(out.substr(0, out.size() - 4)) == ".compressed";
    Status s =
        make_error(out +
                   ": Gaussians are written as .ply (3DGS), .compressed.ply (PlayCanvas), .spz (v3 or v4) "
                   "or .glb (KHR_gaussian_splatting), and as PlayCanvas SOG: .sog or a folder's "
                   "meta.json");
    if (compressed) s = gaussian::write_compressed_ply(out, *g);
    else if (e == ".ply")
        s = gaussian::write_ply(out, *g, ascii ? ply::Format::ascii : ply::Format::binary_little_endian,
                                weights);
    else if (e == ".glb") s = gaussian::write_glb(out, *g);
    else if (e == ".spz") s = gaussian::write_spz(out, *g, spz_version);
    else if (e == ".sog" || std::filesystem::path(out).filename() == "meta.json")
        s = gaussian::write_sog(out, *g, {.morton_order = true});  // splat-transform's order: smaller
    if (!s) {
        std::fprintf(stderr, "splatffd convert: %s\n", s.message().c_str());
        return 1;
    }
    std::fprintf(stderr, "wrote %s: %zu Gaussians, SH degree %d%s (%.2f s)\n", out.c_str(), g->size(),
                 g->sh_degree, note_after.c_str(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    return 0;
}

}  // namespace sffd::cli
