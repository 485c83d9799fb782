// splatffd convert IN OUT [--splats N] [--normals] [--radii] [--ascii] [--progress] [--seed S] [--neighbours
// K] [--gaussians]
//                        [--lattice fit[:L,M,N][,pad=P][,obb][,bspline] | L.json | scene.glb] [--lattice-name
//                        NAME]
// Converts point clouds and meshes (PLY, OBJ, OFF, glTF/GLB, or a built-in scene name) into splat
// clouds (PLY, GLB, glTF). Meshes are sampled on their surface; raw points get normals and radii.
// --lattice stores a lattice bound to the cloud in the scene file (OUT .glb/.gltf): fitted around the
// cloud, or taken from a lattice JSON / another scene. OUT .json exports a lattice instead: IN's own
// (a scene file; --lattice-name picks one of several) or the --lattice one.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <optional>
#include <cstdio>
#include <string>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/formats/surface/export.h"
#include "runtime/assets/formats/surface/ply_weights.h"
#include "runtime/assets/import.h"
#include "runtime/assets/scene.h"
#include "runtime/scene/point_order.h"
#include "runtime/scene/point_subset.h"
#include "systems/ffd/lattice_io.h"
#include "systems/ffd/operations.h"
#include "systems/animation/components.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/lattice_frame.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "tools/splatffd/command.h"
#include "tools/splatffd/convert_gaussians.h"
#include "tools/splatffd/convert_lod.h"
#include "tools/splatffd/convert_potree.h"
#include "tools/splatffd/lattice_source.h"
#include "tools/splatffd/progress.h"
#include "tools/splatffd/scene_subset.h"
#include "tools/splatffd/unkeyed_note.h"
#include "systems/engine/engine_frame.h"

namespace {

constexpr const char* kUsage =
    "usage: splatffd convert IN OUT [--splats N] [--normals] [--radii] [--neighbours K] [--seed S] "
    "[--ascii]\n"
    "                        [--progress] [--gaussians [--turn-x180] [--spz-version 3|4]]\n"
    "                        [--lattice SRC [--lattice-name N]] [--rest] [--order keep|morton]\n"
    "                        [--selected] [--entity NAME]\n"
    "  IN   .ply .obj .off .gltf .glb, or a built-in scene name (sphere, face)\n"
    "  OUT  .ply (binary little-endian; --ascii for text) .glb .gltf, or .json: a lattice (see below)\n"
    "  --splats N       exactly N splats (meshes: sampled on the surface; points: thinned evenly; default:\n"
    "                   one per point, or per mesh vertex (at least 20000 on the surface))\n"
    "  --normals        re-estimate normals (PCA of k nearest neighbours, MST-oriented; default: estimated\n"
    "                   only where missing)\n"
    "  --radii          re-estimate splat radii and axes from neighbour spacing (default: only where "
    "missing)\n"
    "  --neighbours K   neighbourhood size for normals (default 16)\n"
    "  --seed S         surface sampling seed (default 1)\n"
    "  --ascii          write ASCII PLY (default binary little-endian)\n"
    "  --progress       a line per step at its start, every 10 % and its end (default: only when stderr\n"
    "                   is a terminal, for steps over a second); the timing summary is always printed\n"
    "  --gaussians      write 3D Gaussians (.ply 3DGS layout, .compressed.ply PlayCanvas's quantised "
    "layout,\n"
    "                   .spz, .sog or DIR/meta.json PlayCanvas SOG, .glb KHR_gaussian_splatting; default:\n"
    "                   surface splats, or Gaussians when IN is a Gaussian file: .splat, .spz, .ksplat,\n"
    "                   .sog, a SOG folder's meta.json, 3DGS or compressed .ply, KHR .glb); with\n"
    "                   --lattice, OUT .glb/.gltf holds the Gaussians and their lattice\n"
    "  --spz-version V  with --gaussians: the SPZ version written, 3 (gzip, every reader) or 4 (zstd\n"
    "                   streams, the SPZ library's current default) (default 3)\n"
    "  --turn-x180      with --gaussians: turn the Gaussians 180 degrees about x, (x, y, z) -> (x, -y, -z),\n"
    "                   for a file stored y-up (RUB) that should be y-down like a 3DGS PLY, or back (default "
    "off)\n"
    "  --lattice SRC    store a lattice bound to the cloud (OUT .glb/.gltf) or write it (OUT .json):\n"
    "                   fit[:L,M,N][,pad=P][,obb][,bspline]  fitted around the cloud: L,M,N divisions\n"
    "                   (default 10,10,10), pad x the largest extent per side (0.05), obb: oriented box\n"
    "                   (principal axes), bspline: cubic B-spline basis (default Bernstein);\n"
    "                   L.json or scene.glb: that lattice (a scene's lattices bound to its cloud)\n"
    "  --lattice-name N the lattice of that name in a scene file (IN for OUT .json, or --lattice)\n"
    "  OUT .json without --lattice exports IN's lattice (IN a scene file or a built-in scene)\n"
    "  IN a scene file (the editor's save, convert --lattice; surface splats or Gaussians, embedded or\n"
    "  beside it): OUT .glb/.gltf is the scene as loaded (every lattice, clip and un-keyed edit); any\n"
    "  other OUT gets its one cloud deformed by its lattices as saved (the pose render shows at the clip\n"
    "  time the scene was saved at, and deform uses), or:\n"
    "  --rest           with a scene IN: the cloud as authored, without its lattices (default: deformed)\n"
    "  --order O        the order of the points in OUT: keep (as read or made) or morton (Z-order of the\n"
    "                   positions written, 21 bits per axis in the cloud's box, ties in input order), so\n"
    "                   each page of 65,536 points is a compact block and a local edit re-deforms few\n"
    "                   pages; every column moves with its point, lattices are untouched (default keep)\n"
    "  --selected       with a scene IN: only the selected points (as saved by splatffd view; hidden and\n"
    "                   deleted ones never count), every column with them; a cloud file OUT needs them in\n"
    "                   one cloud (or --entity), a scene OUT keeps each cloud that has some\n"
    "  --entity NAME    with a scene IN: only the cloud named NAME (e.g. a separated part, NAME.part) and\n"
    "                   its lattices\n"
    "  A cloud file OUT never holds hidden or deleted points; a scene OUT keeps hidden ones, still hidden\n"
    "  OUT DIR/lod-meta.json  a Gaussian level-of-detail hierarchy (PlayCanvas streamed SOG), with its own\n"
    "                   options: splatffd convert IN DIR/lod-meta.json --help\n"
    "  OUT DIR/metadata.json  a Potree 2 octree of surface splats, with its own options:\n"
    "                   splatffd convert IN DIR/metadata.json --help\n";

// --order morton on a surface cloud: every column moved together (runtime/scene/point_order.h), and the
// weights beside it (empty, or one a point) with them.
sffd::Status reorder(sffd::SplatCloud& cloud, bool morton, std::vector<float>& weights) {
    if (!morton) return {};
    const std::vector<std::uint32_t> order = sffd::morton_order(cloud.positions);
    if (sffd::Status s = sffd::permute(cloud, order); !s) return s;
    if (weights.size() == order.size()) {
        std::vector<float> moved(weights.size());
        for (std::size_t k = 0; k < order.size(); ++k) moved[k] = weights[order[k]];
        weights = std::move(moved);
    }
    return {};
}

struct LatticeRequest {
    std::string source;  // --lattice
    std::string name;    // --lattice-name
};

// OUT .json: a lattice from IN (a scene) or from --lattice, written as lattice JSON.
int export_lattice_json(const std::string& in, const std::string& out, const LatticeRequest& req) {
    using namespace sffd;
    cli::LatticeChain chain;
    if (req.source.empty() || sffd::ffd::is_fit_spec(req.source)) {
        if (req.source.empty() && !cli::is_scene_path(in) && !assets::is_builtin_scene(in)) {
            std::fprintf(stderr,
                         "splatffd convert: %s: not a scene file; to write a fitted lattice add --lattice "
                         "fit[:L,M,N]\n",
                         in.c_str());
            return 1;
        }
        ecs::Registry r;
        sffd::use_engine_scene_hooks(r);
        if (Status s = load_scene(r, in); !s) {
            std::fprintf(stderr, "splatffd convert: %s\n", s.message().c_str());
            return 1;
        }
        if (req.source.empty()) {
            auto c = cli::pick_scene_lattices(r, in, req.name);
            if (!c) {
                std::fprintf(stderr, "splatffd convert: %s\n", c.message().c_str());
                return 1;
            }
            chain = std::move(*c);
        } else {
            auto fit = ffd::parse_fit_spec(req.source);
            std::vector<glm::vec3> pts;
            glm::dvec3 origin(0.0);
            r.each_entity([&](ecs::Entity e) {
                if (const SplatCloud* c = r.try_get<SplatCloud>(e); c && pts.empty())
                    pts = c->positions, origin = c->origin;
                if (const GaussianCloud* g = r.try_get<GaussianCloud>(e); g && pts.empty())
                    pts = g->positions, origin = g->origin;
            });
            auto l = fit ? cli::fit_lattice_for("convert", pts, origin, *fit) : Result<Lattice>(fit.error());
            if (!l) {
                std::fprintf(stderr, "splatffd convert: %s\n", l.message().c_str());
                return 1;
            }
            chain.lattices.push_back(std::move(*l));
            chain.names.push_back(req.source);
        }
    } else {
        auto c = cli::load_lattice_source(req.source, req.name);
        if (!c) {
            std::fprintf(stderr, "splatffd convert: %s\n", c.message().c_str());
            return 1;
        }
        chain = std::move(*c);
    }
    if (chain.lattices.size() != 1) {
        std::string names;
        for (const auto& n : chain.names) names += (names.empty() ? "'" : ", '") + n + "'";
        std::fprintf(stderr,
                     "splatffd convert: %s: the cloud is deformed by %zu lattices (%s) in order; a lattice "
                     "JSON holds one: choose it with --lattice-name NAME\n",
                     in.c_str(), chain.lattices.size(), names.c_str());
        return 1;
    }
    if (Status s = ffd::save_lattice(out, chain.lattices[0]); !s) {
        std::fprintf(stderr, "splatffd convert: %s\n", s.message().c_str());
        return 1;
    }
    const Lattice& l = chain.lattices[0];
    std::fprintf(stderr, "wrote %s: lattice '%s', %s, divisions %d x %d x %d\n", out.c_str(),
                 chain.names[0].c_str(), l.basis == LatticeBasis::bernstein ? "bernstein" : "bspline",
                 l.divisions.x, l.divisions.y, l.divisions.z);
    return 0;
}

// OUT .glb/.gltf with --lattice: the cloud and its lattice(s), bound in order. `loaded`: the JSON or
// scene source, read before the import (a bad file fails before the work).
sffd::Status save_with_lattice(const sffd::SplatCloud& cloud, const sffd::SplatMaterial& material,
                               const std::string& name, const LatticeRequest& req,
                               const sffd::cli::LatticeChain& loaded, const std::string& out,
                               std::string& note, std::span<const float> weights) {
    using namespace sffd;
    cli::LatticeChain chain;
    if (ffd::is_fit_spec(req.source)) {
        auto fit = ffd::parse_fit_spec(req.source);
        if (!fit) return fit.error();
        auto l = cli::fit_lattice_for("convert", cloud.positions, cloud.origin, *fit);
        if (!l) return l.error();
        chain.lattices.push_back(std::move(*l));
        note = ", lattice " + ffd::fit_spec_string(*fit) + " bound to it";
    } else {
        chain = loaded;
        note =
            ", " + std::to_string(chain.lattices.size()) + " lattice(s) from " + req.source + " bound to it";
    }
    return cli::save_cloud_with_lattices(cloud, name, chain.lattices, out, material, weights);
}

// What a scene IN is converted with (the command's options that apply to it).
struct SceneConvert {
    bool rest = false, gaussians = false, ascii = false, turn_x180 = false, morton = false;
    int spz_version = 3;
    LatticeRequest lattice;
    const sffd::cli::LatticeChain* loaded = nullptr;  // --lattice SRC, read before
    sffd::cli::SceneSubset subset;                    // --selected, --entity
};

// The cloud's weights (PointWeights) when they are one a point, for the deformers and the writers; else
// null (weight 1).
const float* weights_of(const sffd::ecs::Registry& r, sffd::ecs::Entity e, std::size_t n) {
    const sffd::PointWeights* w = r.try_get<sffd::PointWeights>(e);
    return w && w->values.size() == n && n > 0 ? w->values.data() : nullptr;
}

// IN a scene file (the editor's save, `convert --lattice`): loaded as render, deform and info load it, so
// its Gaussians are where those commands show them however they are stored (embedded KHR primitives, a
// .sog beside it). OUT a scene without --lattice: the scene as loaded (lattices, clips, un-keyed edits).
// OUT a cloud file: the scene's one cloud deformed by its lattices as saved (what render's frame at the
// saved clip time and deform show), or as authored with --rest; with --lattice, at rest under that lattice.
int convert_scene(const std::string& in, const std::string& out, const SceneConvert& o) {
    using namespace sffd;
    const auto t0 = std::chrono::steady_clock::now();
    ecs::Registry r;
    sffd::use_engine_scene_hooks(r);
    if (Status st = load_scene(r, in); !st) return cli::command_error("convert", st.message());
    if (!o.rest) cli::note_unkeyed_edits("convert", r);
    const bool scene_out = cli::is_scene_path(out);
    std::string subset_note;
    if (o.subset.active()) {
        auto kept = cli::narrow_scene(r, in, o.subset, scene_out);
        if (!kept) return cli::command_error("convert", kept.message());
        if (!o.subset.entity.empty()) subset_note += ", cloud '" + o.subset.entity + "' only";
        if (o.subset.selected) subset_note += ", selected points only";
    }
    std::vector<ecs::Entity> clouds;
    r.each_entity([&](ecs::Entity e) {
        if (r.has<SplatCloud>(e) || r.has<GaussianCloud>(e)) clouds.push_back(e);
    });
    const bool surface_to_gaussians = o.gaussians && clouds.size() == 1 && r.has<SplatCloud>(clouds[0]);
    if (scene_out && o.lattice.source.empty() && !surface_to_gaussians) {
        // The scene as loaded, its cloud in the order asked for (lattices do not depend on it).
        // Reordered through keep_points, so the flags and weights beside the cloud move with their points.
        for (ecs::Entity e : clouds) {
            if (!o.morton) continue;
            const SplatCloud* sc = r.try_get<SplatCloud>(e);
            const auto order = morton_order(sc ? sc->positions : r.try_get<GaussianCloud>(e)->positions);
            if (auto st = keep_points(r, e, order); !st)
                return cli::command_error("convert", in + ": " + st.message());
        }
        if (Status st = save_scene(r, out); !st) return cli::command_error("convert", st.message());
        std::fprintf(stderr, "wrote %s: the scene as loaded%s (%zu cloud(s), %zu lattice(s), %zu clip(s))\n",
                     out.c_str(), subset_note.c_str(), clouds.size(), r.count<Lattice>(),
                     r.count<AnimationClip>());
        return 0;
    }
    if (clouds.size() != 1)
        return cli::command_error("convert",
                                  in + ": " + std::to_string(clouds.size()) +
                                      " clouds; a cloud file holds one (convert writes a scene with "
                                      "all of them to .glb/.gltf)");
    const ecs::Entity cloud_entity = clouds[0];
    // Everything below writes the cloud out of the scene: an export, which holds no point that is not
    // drawn (point_subset.h); only a scene save keeps hidden points.
    auto gone = drop_gone_points(r, cloud_entity, PointDrop::hidden_and_deleted);
    if (!gone) return cli::command_error("convert", in + ": " + gone.message());
    if (*gone) subset_note += ", " + std::to_string(*gone) + " hidden or deleted point(s) left out";
    const Name* cloud_name = r.try_get<Name>(cloud_entity);
    const std::string name = cloud_name ? cloud_name->value : std::filesystem::path(in).stem().string();
    // A scene OUT keeps the scene's own lattices, bound to the cloud at rest, as they were.
    cli::LatticeChain own;
    cli::GaussianLatticeRequest keep{o.lattice.source, o.loaded};
    if (scene_out && o.lattice.source.empty()) {
        auto c = cli::pick_scene_lattices(r, in, o.lattice.name);
        if (c) own = std::move(*c), keep = {in, &own};
    }
    // The cloud's lattices, in order, as saved (Lattice::current: the scene's saved pose), in the cloud's
    // frame as the engine deforms it (both Transforms: systems/ffd/lattice_frame.h).
    ffd::CloudLattices framed;
    if (const Deformers* d = r.try_get<Deformers>(cloud_entity))
        framed = ffd::cloud_lattices(r, cloud_entity, d->lattices);
    const std::vector<const Lattice*>& chain = framed.lattices;
    std::string names;
    for (ecs::Entity l : framed.entities) {
        const Name* n = r.try_get<Name>(l);
        names += (names.empty() ? "'" : ", '") + (n ? n->value : std::string("lattice")) + "'";
    }
    const bool deform = !o.rest && keep.source.empty() && !chain.empty();
    const auto moved = [](const Lattice& l) { return l.current != l.rest; };
    std::string pose;
    if (!keep.source.empty()) pose = "";
    else if (chain.empty()) pose = ", no lattice";
    else if (std::none_of(chain.begin(), chain.end(), [&](const Lattice* l) { return moved(*l); }))
        pose = ", its lattices " + names + " at rest";
    else if (o.rest) pose = ", at rest (without --rest: deformed by " + names + " as saved)";
    else pose = ", deformed by " + names + " as saved (--rest: the cloud at rest)";
    pose = subset_note + pose;

    if (GaussianCloud* g = r.try_get<GaussianCloud>(cloud_entity)) {
        GaussianCloud posed = *g;
        if (deform) {
            gaussian::DeformOptions options;
            options.weights = weights_of(r, cloud_entity, posed.size());  // P + w (FFD(P) - P)
            for (const Lattice* l : chain) {
                if (!moved(*l)) continue;
                auto st = gaussian::deform(*l, posed, posed, options);
                if (!st) return cli::command_error("convert", in + ": " + st.message());
            }
            gaussian::bake_sh_frames(posed);
        }
        const float* gw = weights_of(r, cloud_entity, posed.size());
        std::vector<float> written = gw ? std::vector<float>(gw, gw + posed.size()) : std::vector<float>{};
        return cli::write_gaussian_cloud(std::move(posed), name, out, o.ascii, o.turn_x180, o.spz_version,
                                         keep, pose, t0, o.morton, std::move(written));
    }
    SplatCloud cloud = r.get<SplatCloud>(cloud_entity);
    SplatMaterial material;
    if (const SplatMaterial* m = r.try_get<SplatMaterial>(cloud_entity)) material = *m;
    if (deform) {
        const std::size_t n = cloud.size();
        if (cloud.axis_u.size() != n || cloud.axis_v.size() != n) cloud.axis_u.clear(), cloud.axis_v.clear();
        if (cloud.normals.size() != n) cloud.normals.clear();
        auto ptr = [](std::vector<glm::vec3>& v) { return v.empty() ? nullptr : v.data(); };
        for (const Lattice* l : chain) {
            if (!moved(*l)) continue;
            ffd::PointsIn pin{cloud.positions.data(),
                              ptr(cloud.normals),
                              ptr(cloud.axis_u),
                              ptr(cloud.axis_v),
                              n,
                              cloud.origin};
            pin.weights = weights_of(r, cloud_entity, n);  // P + w (FFD(P) - P)
            const ffd::PointsOut pout{cloud.positions.data(), ptr(cloud.normals), ptr(cloud.axis_u),
                                      ptr(cloud.axis_v)};
            if (auto st = ffd::deform(*l, pin, pout); !st)
                return cli::command_error("convert", in + ": " + st.message());
        }
    }
    const float* sw = weights_of(r, cloud_entity, cloud.size());
    std::vector<float> weights = sw ? std::vector<float>(sw, sw + cloud.size()) : std::vector<float>{};
    if (o.gaussians)
        return cli::write_gaussians(in, &cloud, material, out, o.ascii, o.turn_x180, o.spz_version, keep,
                                    o.morton, std::move(weights));
    if (Status st = reorder(cloud, o.morton, weights); !st)
        return cli::command_error("convert", in + ": " + st.message());
    std::string lattice_note;
    Status s = !o.lattice.source.empty() ? save_with_lattice(cloud, material, name, o.lattice, *o.loaded, out,
                                                             lattice_note, weights)
               : o.ascii                 ? assets::save_splat_ply(cloud, out, ply::Format::ascii, weights)
                                         : assets::save_splat_cloud(cloud, out, name, material, weights);
    if (!s) return cli::command_error("convert", s.message());
    std::fprintf(stderr, "wrote %s: %zu splats%s%s (%.2f s)\n", out.c_str(), cloud.size(),
                 lattice_note.c_str(), pose.c_str(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    return 0;
}

int run_convert(sffd::cli::Args args) {
    using namespace sffd;
    if (cli::names_lod_output(args)) return cli::run_convert_lod(args);  // tools/splatffd/convert_lod.h
    if (cli::names_potree_output(args))
        return cli::run_convert_potree(args);  // tools/splatffd/convert_potree.h
    std::string in, out;
    assets::ImportOptions opt;
    bool ascii = false, gaussians = false, progress = false, turn_x180 = false, rest = false, morton = false;
    int spz_version = 3;
    LatticeRequest lattice;
    cli::SceneSubset subset;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        // Every number goes through cli::parse_integer (one message format, the option named).
        auto value = [&](long long min, long long max) -> std::optional<long long> {
            if (i + 1 >= args.size()) {
                std::fprintf(stderr, "splatffd convert: %s needs a value\n", a.c_str());
                return std::nullopt;
            }
            auto v = cli::parse_integer(a, args[++i], min, max);
            if (!v) std::fprintf(stderr, "splatffd convert: %s\n", v.message().c_str());
            return v ? std::optional<long long>(*v) : std::nullopt;
        };
        auto text = [&]() -> std::optional<std::string> {
            if (i + 1 >= args.size()) {
                std::fprintf(stderr, "splatffd convert: %s needs a value\n", a.c_str());
                return std::nullopt;
            }
            return args[++i];
        };
        if (cli::is_help(a)) {
            return cli::help(kUsage);
        } else if (a == "--splats") {
            auto v = value(1, 1'000'000'000);
            if (!v) return 2;
            opt.splats = static_cast<std::size_t>(*v);
        } else if (a == "--neighbours") {
            auto v = value(4, 128);
            if (!v) return 2;
            opt.neighbours = static_cast<int>(*v);
        } else if (a == "--seed") {
            auto v = value(0, 4294967295LL);
            if (!v) return 2;
            opt.seed = static_cast<std::uint32_t>(*v);
        } else if (a == "--lattice" || a == "--lattice-name") {
            auto v = text();
            if (!v) return 2;
            (a == "--lattice" ? lattice.source : lattice.name) = *v;
        } else if (a == "--order") {
            auto v = text();
            if (!v) return 2;
            if (*v != "keep" && *v != "morton")
                return cli::usage_error("convert", "--order '" + *v + "': expected keep or morton", kUsage);
            morton = *v == "morton";
        } else if (a == "--normals") {
            opt.estimate_normals = true;
        } else if (a == "--radii") {
            opt.estimate_radii = true;
        } else if (a == "--ascii") {
            ascii = true;
        } else if (a == "--progress") {
            progress = true;
        } else if (a == "--gaussians") {
            gaussians = true;
        } else if (a == "--turn-x180") {
            turn_x180 = true;
        } else if (a == "--rest") {
            rest = true;
        } else if (a == "--selected") {
            subset.selected = true;
        } else if (a == "--entity") {
            auto v = text();
            if (!v) return 2;
            if (v->empty()) return cli::usage_error("convert", "--entity needs a cloud's name", kUsage);
            subset.entity = *v;
        } else if (a == "--spz-version") {
            auto v = value(3, 4);
            if (!v) return 2;
            spz_version = static_cast<int>(*v);
        } else if (!a.empty() && a[0] == '-') {
            return cli::usage_error("convert", "unknown option '" + a + "'", kUsage);
        } else if (in.empty()) {
            in = a;
        } else if (out.empty()) {
            out = a;
        } else {
            return cli::usage_error("convert", "more than two files given ('" + a + "')", kUsage);
        }
    }
    if (in.empty() || out.empty()) return cli::usage_error("convert", "expected IN and OUT", kUsage);
    const bool scene_in =
        !assets::is_builtin_scene(in) && cli::is_scene_path(in) && gaussian::gltf_declaration(in).sffd_scene;
    if (rest && !scene_in)
        return cli::usage_error("convert", "--rest applies to a scene IN (its cloud without its lattices)",
                                "");
    if (subset.active() && !scene_in)
        return cli::usage_error("convert",
                                std::string(subset.selected ? "--selected" : "--entity") +
                                    " applies to a scene IN (" + in +
                                    " is not a scene file: its points have no selection or names)",
                                "");
    // A Gaussian input stays Gaussian: read as points it would lose colour, opacity and SH. In a scene
    // each cloud keeps its own kind (a surface cloud beside Gaussians stays surface splats unless
    // --gaussians is given), so the scene is converted with the option as given.
    const bool gaussian_in = !assets::is_builtin_scene(in) && cli::is_gaussian_file(in);
    const bool gaussians_asked = gaussians;
    gaussians = gaussians || gaussian_in;
    if (turn_x180 && !gaussians)
        return cli::usage_error("convert", "--turn-x180 applies to Gaussians: add --gaussians", "");
    // A SOG folder's meta.json is the Gaussians' file, not a lattice.
    const bool sog_folder = gaussians && std::filesystem::path(out).filename() == "meta.json";
    if (cli::is_json_path(out) && !sog_folder && subset.active())
        return cli::usage_error("convert", "--selected and --entity choose points; OUT .json is a lattice",
                                "");
    if (cli::is_json_path(out) && !sog_folder) return export_lattice_json(in, out, lattice);
    if (!lattice.source.empty() && !cli::is_scene_path(out)) {
        std::fprintf(stderr,
                     "splatffd convert: %s: a %s file cannot hold a lattice; write a scene (.glb/.gltf) or "
                     "the lattice alone (.json)\n",
                     out.c_str(), std::filesystem::path(out).extension().string().c_str());
        return 2;
    }
    if (!lattice.name.empty() && lattice.source.empty() && !scene_in) {
        std::fprintf(stderr, "splatffd convert: --lattice-name needs --lattice SCENE.glb (or OUT .json)\n");
        return 2;
    }
    // The lattice source is checked before the (possibly long) import.
    cli::LatticeChain loaded;
    if (ffd::is_fit_spec(lattice.source)) {
        if (auto fit = ffd::parse_fit_spec(lattice.source); !fit) {
            std::fprintf(stderr, "splatffd convert: --lattice %s\n", fit.message().c_str());
            return 2;
        }
    } else if (!lattice.source.empty()) {
        auto c = cli::load_lattice_source(lattice.source, lattice.name);
        if (!c) {
            std::fprintf(stderr, "splatffd convert: %s\n", c.message().c_str());
            return 1;
        }
        loaded = std::move(*c);
    }
    if (scene_in)
        return convert_scene(in, out,
                             SceneConvert{rest, gaussians_asked, ascii, turn_x180, morton, spz_version,
                                          lattice, &loaded, subset});
    const cli::GaussianLatticeRequest gaussian_lattice{lattice.source, &loaded};
    if (gaussian_in)
        return cli::write_gaussians(in, nullptr, SplatMaterial{}, out, ascii, turn_x180, spz_version,
                                    gaussian_lattice, morton);
    cli::ProgressPrinter printer("convert", cli::ProgressPrinter::mode_for(progress));
    opt.progress = printer.fn();
    const auto t0 = std::chrono::steady_clock::now();
    Result<SplatCloud> cloud = make_error("");
    SplatMaterial material;  // the input's, carried into a .glb output
    if (in == "sphere") {
        cloud = assets::make_sphere_cloud(opt.splats ? opt.splats : assets::kSphereSplats);
    } else if (assets::is_builtin_scene(in)) {
        // Other built-in scenes (face) come from their cached file: the scene's first cloud, as stored.
        ecs::Registry r;
        sffd::use_engine_scene_hooks(r);
        if (Status st = load_scene(r, in); !st) {
            std::fprintf(stderr, "splatffd convert: %s\n", st.message().c_str());
            return 1;
        }
        r.each_entity([&](ecs::Entity e) {
            if (const SplatCloud* c = r.try_get<SplatCloud>(e); c && !cloud) {
                cloud = *c;
                if (const SplatMaterial* m = r.try_get<SplatMaterial>(e)) material = *m;
            }
        });
        if (!cloud) cloud = make_error(in + ": built-in scene has no point cloud");
    } else {
        printer.report("reading", 0.0);
        auto g = assets::read_geometry(in);
        printer.report("reading", 1.0);
        if (!g) {
            std::fprintf(stderr, "splatffd convert: %s\n", g.message().c_str());
            return 1;
        }
        const auto t1 = std::chrono::steady_clock::now();
        std::fprintf(stderr, "read %s: %zu points, %zu triangles in %.2f s\n", in.c_str(),
                     g->positions.size(), g->triangle_count(),
                     std::chrono::duration<double>(t1 - t0).count());
        // Memory budget stated up front: sampling a mesh peaks at about 1.1 KB per requested splat
        // (candidates, neighbour lists of the sample elimination; /usr/bin/time: 2.19 GB for 2M splats),
        // so a request that cannot fit in this machine's memory is refused before any work.
        if (g->triangle_count() > 0 && opt.splats > 0) {
            constexpr std::uint64_t kBytesPerSampledSplat = 1200;
            const std::uint64_t need = std::uint64_t(opt.splats) * kBytesPerSampledSplat;
            const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
            const std::uint64_t have = pages > 0 && page > 0 ? std::uint64_t(pages) * std::uint64_t(page) : 0;
            if (have > 0 && need > have) {
                std::fprintf(stderr,
                             "splatffd convert: %s: sampling %zu splats needs about %.1f GB (1.2 KB per "
                             "splat), more than this "
                             "machine's %.1f GB of memory\n",
                             in.c_str(), opt.splats, double(need) / 1e9, double(have) / 1e9);
                return 1;
            }
        }
        cloud = assets::make_splat_cloud(*g, opt);
        material = g->splat_material;
    }
    if (!cloud) {
        std::fprintf(stderr, "splatffd convert: %s\n", cloud.message().c_str());
        return 1;
    }
    // A PLY's `weight` column (ply_weights.h), carried into every OUT that holds weights (PLY, glTF).
    std::vector<float> weights;
    if (!assets::is_builtin_scene(in)) {
        auto w = assets::cloud_weights_of_file(in, cloud->size());
        if (!w) {
            std::fprintf(stderr, "splatffd convert: %s\n", w.message().c_str());
            return 1;
        }
        weights = std::move(w->values);
    }
    if (gaussians)
        return cli::write_gaussians(in, &*cloud, material, out, ascii, turn_x180, spz_version,
                                    gaussian_lattice, morton, std::move(weights));
    if (Status st = reorder(*cloud, morton, weights); !st) {
        std::fprintf(stderr, "splatffd convert: %s: %s\n", in.c_str(), st.message().c_str());
        return 1;
    }
    const auto t2 = std::chrono::steady_clock::now();
    std::string lattice_note;
    printer.report("writing", 0.0);
    Status s = lattice.source.empty()
                   ? (ascii ? assets::save_splat_ply(*cloud, out, ply::Format::ascii, weights)
                            : assets::save_splat_cloud(*cloud, out, std::filesystem::path(in).stem().string(),
                                                       material, weights))
                   : save_with_lattice(*cloud, material, std::filesystem::path(in).stem().string(), lattice,
                                       loaded, out, lattice_note, weights);
    if (!s) {
        std::fprintf(stderr, "splatffd convert: %s\n", s.message().c_str());
        return 1;
    }
    printer.report("writing", 1.0);
    const auto t3 = std::chrono::steady_clock::now();
    std::fprintf(stderr, "wrote %s: %zu splats%s (import + estimation %.2f s, write %.2f s)\n", out.c_str(),
                 cloud->size(), lattice_note.c_str(), std::chrono::duration<double>(t2 - t0).count(),
                 std::chrono::duration<double>(t3 - t2).count());
    printer.summary();
    return 0;
}

}  // namespace

SFFD_COMMAND(convert, "convert point clouds and meshes, estimating normals and radii; add or export lattices",
             run_convert);
