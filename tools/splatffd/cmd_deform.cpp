// splatffd deform IN OUT [--lattice SOURCE [--lattice-name NAME]] [--backend cpu|gpu|reference] [--bench N]
// [--ascii]
//                        [--estimate-radii]
//
// SOURCE: a lattice JSON file, a scene file (.glb/.gltf: the lattices bound to its cloud, in order, or
// the one named by --lattice-name), or a fit spec `fit[:L,M,N][,pad=P][,obb][,bspline]` (a rest lattice
// fitted around IN: the identity, useful to add splat axes). Without --lattice, IN must be a scene file
// holding a lattice (the editor's save): its own lattices are used.
//
// PLY in, PLY out: ffd::stream_deform (systems/ffd/stream_deform.h) streams the file through the lattices
// in chunks (peak memory stays far below 256 MB whatever the file size) with the engine's own kernels:
// `vertex` rows get deformed x y z, nx ny nz and the splat axes (created from normals and a radius, or
// radii estimated from neighbour spacing: by default up to 4M points, beyond that with --estimate-radii),
// 3DGS rows their covariances and SH; every other property and element is copied with its type. Points
// outside the lattice are unchanged, points on its faces are inside. The output is binary little-endian
// (or ASCII with --ascii) and atomic. This file parses the arguments and prints what was done.
// Any other input or output (.glb/.gltf/.obj/.off): the cloud is loaded whole (import estimates normals
// and radii where missing), deformed (positions, normals, axes) and saved by OUT's extension.
// The last line on stderr says what was written (positions, normals, axes: deformed / created / absent).
// --bench N re-runs the deformation of every chunk N more times and prints one JSON line on stdout:
// {"points":..,"backend":..,"median_ms":..,"points_per_s":..} (deformation only, no I/O).
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <span>
#include <vector>

#include "runtime/assets/formats/surface/export.h"
#include "runtime/assets/formats/surface/ply.h"
#include "runtime/assets/formats/surface/ply_weights.h"
#include "runtime/assets/import.h"
#include "runtime/assets/scene.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_subset.h"
#include "systems/ffd/operations.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/lattice_io.h"
#include "systems/ffd/stream_deform.h"
#include "systems/gaussian/components.h"
#include "tools/splatffd/command.h"
#include "tools/splatffd/deform_gaussians.h"
#include "tools/splatffd/deform_hierarchy.h"
#include "tools/splatffd/lattice_source.h"
#include "tools/splatffd/progress.h"
#include "tools/splatffd/unkeyed_note.h"
#include "systems/engine/engine_frame.h"

namespace {

using namespace sffd;
using Clock = std::chrono::steady_clock;

constexpr std::uint64_t kEstimateMaxPoints = 4'000'000;  // default limit of the in-memory radius estimate

constexpr const char* kUsage =
    "usage: splatffd deform IN OUT [--lattice SOURCE [--lattice-name NAME]] [--backend cpu|gpu|reference] "
    "[--bench N] [--ascii]\n"
    "                              [--estimate-radii]\n"
    "  IN, OUT  .ply (streamed, every property kept; 3DGS Gaussians too) or .glb .gltf (OUT also .ply);\n"
    "           IN also .obj .off and every Gaussian format (.compressed.ply .spz .sog meta.json .splat\n"
    "           .ksplat KHR .glb: read whole, CPU), written as OUT names (.ply .compressed.ply .spz .sog);\n"
    "           a hierarchy (DIR/lod-meta.json, our Potree 2 DIR/metadata.json) into another folder's one "
    "of\n"
    "           the same kind: its finest detail deformed piece by piece and the levels built again\n"
    "  --lattice SOURCE  L.json | scene.glb (the lattices bound to its cloud) | "
    "fit[:L,M,N][,pad=P][,obb][,bspline]\n"
    "           (default: the lattices stored in IN when IN is a scene file); a scene's lattices deform\n"
    "           as saved: their clip's pose at the clip time the scene was saved at (an un-keyed edit made\n"
    "           there included; `splatffd info` lists both)\n"
    "  --lattice-name NAME  the lattice of that name in a scene file (default: every lattice bound to the "
    "cloud)\n"
    "  --backend B  cpu (float, every core; default), gpu (compute shader on a headless GL context) or\n"
    "           reference (double precision, one thread: for checking the others)\n"
    "  --bench N    re-run the deformation N more times and print a JSON timing line on stdout (default 0)\n"
    "  --ascii      write ASCII PLY (default binary little-endian)\n"
    "  splat axes (axis_u*, axis_v*) are deformed; from normals (+ radius, or radii estimated from\n"
    "  neighbour spacing) they are created first\n"
    "  --estimate-radii  estimate radii for PLY input with normals only even beyond 4M points\n"
    "                    (the estimate holds every position: ~75 bytes per point)\n";

int usage(bool asked = false) { return asked ? cli::help(kUsage) : cli::usage_error("deform", "", kUsage); }

int fail(const std::string& message) {
    std::fprintf(stderr, "splatffd deform: %s\n", message.c_str());
    return 1;
}

struct Options {
    std::vector<std::string> files;
    std::string lattice_source, lattice_name, backend = "cpu";
    int bench = 0;
    bool ascii = false;
    bool estimate_radii = false;  // --estimate-radii: whatever the point count
};

// -1: parsed; otherwise the exit code (0 after --help, 2 after a usage error).
int parse_options(sffd::cli::Args args, Options& o) {
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        auto next = [&]() -> std::optional<std::string> {
            if (i + 1 >= args.size()) return std::nullopt;
            return args[++i];
        };
        if (cli::is_help(a)) return usage(true);
        if (a == "--lattice" || a == "--lattice-name") {
            auto v = next();
            if (!v) return std::fprintf(stderr, "splatffd deform: %s needs a value\n", a.c_str()), usage();
            (a == "--lattice" ? o.lattice_source : o.lattice_name) = *v;
        } else if (a == "--backend") {
            auto v = next();
            if (!v || (*v != "cpu" && *v != "gpu" && *v != "reference"))
                return cli::usage_error("deform", "--backend takes cpu, gpu or reference", kUsage);
            o.backend = *v;
        } else if (a == "--bench") {
            auto v = next();
            auto n = v ? cli::parse_integer("--bench", *v, 0, 1'000'000)
                       : Result<long long>(make_error("--bench needs a value"));
            if (!n) return std::fprintf(stderr, "splatffd deform: %s\n", n.message().c_str()), 2;
            o.bench = int(*n);
        } else if (a == "--ascii") {
            o.ascii = true;
        } else if (a == "--estimate-radii") {
            o.estimate_radii = true;
        } else if (!a.empty() && a[0] == '-') {
            std::fprintf(stderr, "splatffd deform: unknown option '%s'\n", a.c_str());
            return usage();
        } else {
            o.files.push_back(a);
        }
    }
    if (o.files.size() != 2) return usage();
    return -1;
}

std::string lower_ext(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    return ext;
}

std::string joined(const std::vector<std::string>& names) {
    std::string s;
    for (const std::string& n : names) s += (s.empty() ? "'" : ", '") + n + "'";
    return s;
}

// The lattices for a cloud whose points are `positions` (relative to `origin`; used by a fit spec only).
// `scene` is IN's registry when IN is a scene file (its own lattices are the default source).
Result<cli::LatticeChain> lattice_chain(const Options& o, const std::vector<glm::vec3>& positions,
                                        const glm::dvec3& origin, const ecs::Registry* scene) {
    if (o.lattice_source.empty()) {
        if (!scene)
            return make_error(
                o.files[0] +
                ": no --lattice given (a lattice JSON, a scene file or fit:…), and IN is not a scene file");
        return cli::pick_scene_lattices(*scene, o.files[0], o.lattice_name);
    }
    if (ffd::is_fit_spec(o.lattice_source)) {
        auto fit = ffd::parse_fit_spec(o.lattice_source);
        if (!fit) return fit.error();
        auto l = cli::fit_lattice_for("deform", positions, origin, *fit);
        if (!l) return make_error(o.files[0] + ": " + l.message());
        return cli::LatticeChain{{std::move(*l)}, {ffd::fit_spec_string(*fit)}, {}};
    }
    return cli::load_lattice_source(o.lattice_source, o.lattice_name);
}

// `set_up_ms` < 0: no GPU programs were set up (CPU backends).
void print_summary(const char* what, std::size_t points, const std::string& backend, double first_ms,
                   double total_s, std::size_t inverted, double set_up_ms = -1.0) {
    char set_up[96] = "";
    if (set_up_ms >= 0.0)
        std::snprintf(set_up, sizeof set_up,
                      ", GPU program set-up (shader compilation, first dispatch) %.1f ms", set_up_ms);
    std::fprintf(
        stderr,
        "splatffd deform: %zu points (%s backend), deformation %.1f ms (%.3g points/s)%s, total with "
        "I/O %.2f s (%.3g points/s), %zu inverted\n",
        points, backend.c_str(), first_ms, first_ms > 0 ? double(points) / (first_ms * 1e-3) : 0.0, set_up,
        total_s, total_s > 0 ? double(points) / total_s : 0.0, inverted);
    std::fprintf(stderr, "splatffd deform: wrote %s\n", what);
}

// "deformed by 1 lattice" must not hide a lattice that moved nothing: one warning per lattice that holds
// none of the points (a lattice of another scan, or fitted to another cloud).
void warn_empty_lattices(const cli::LatticeChain& chain, const std::vector<std::size_t>& inside,
                         std::size_t points) {
    for (std::size_t i = 0; i < chain.lattices.size() && i < inside.size(); ++i)
        if (inside[i] == 0 && points > 0)
            std::fprintf(
                stderr,
                "splatffd deform: warning: lattice '%s' contains none of the %zu points: it deformed "
                "nothing (is it the lattice of another cloud?)\n",
                i < chain.names.size() ? chain.names[i].c_str() : "?", points);
}

// PLY in, PLY out, streamed by the library (systems/ffd/stream_deform.h); this prints what it did.
int deform_ply_stream(const Options& o) {
    const std::string& in_path = o.files[0];
    auto input = ffd::inspect_stream_input(in_path);
    if (!input) return fail(input.message());
    std::vector<glm::vec3> fit_points;
    glm::dvec3 fit_origin(0.0);
    if (ffd::is_fit_spec(o.lattice_source)) {
        auto pts = ffd::read_ply_positions(in_path, fit_origin);
        if (!pts) return fail(pts.message());
        fit_points = std::move(*pts);
    }
    auto chain = lattice_chain(o, fit_points, fit_origin, nullptr);
    if (!chain) return fail(chain.message());
    // 3D Gaussian splats (3DGS PLY): covariances and SH follow the lattice too.
    const bool gaussians = input->kind == ffd::StreamKind::gaussians;
    if (gaussians && chain->lattices.size() != 1)
        return fail(in_path + ": 3D Gaussian files are deformed by one lattice at a time (got " +
                    std::to_string(chain->lattices.size()) + "); choose one with --lattice-name");
    ffd::StreamDeformRequest req;
    req.input = in_path;
    req.output = o.files[1];
    req.lattices = chain->lattices;
    req.backend = o.backend == "gpu"         ? ffd::StreamBackend::gpu
                  : o.backend == "reference" ? ffd::StreamBackend::reference
                                             : ffd::StreamBackend::cpu;
    req.timing_runs = o.bench;
    req.ascii = o.ascii;
    req.estimate_always = o.estimate_radii;
    req.estimate_max_points = kEstimateMaxPoints;
    req.positions = std::move(fit_points);
    req.lattice_label = gaussians || !o.lattice_source.empty() ? o.lattice_source : in_path;
    // A percentage line on a terminal for a stream that runs over a second; nothing in logs or pipes.
    cli::ProgressPrinter progress("splatffd deform", cli::ProgressPrinter::mode_for(false));
    auto report = [&](std::uint64_t done, std::uint64_t total) {
        progress.report("deforming " + std::to_string(total) + " points",
                        total > 0 ? double(done) / double(total) : 1.0);
    };
    auto done = ffd::stream_deform(req, gaussians ? ffd::StreamProgress{} : ffd::StreamProgress{report});
    if (!done) return fail(done.message());
    if (gaussians) return cli::report_gaussian_stream(*done, o.lattice_source, o.backend, o.bench);

    const std::size_t points = std::size_t(done->points);
    std::string what = o.files[1] + ": positions";
    what += done->normals ? ", normals" : " (no normals in the input)";
    switch (done->axes) {
        case ffd::StreamAxes::deformed: what += ", splat axes"; break;
        case ffd::StreamAxes::from_estimate:
            what += ", splat axes (created from normals and radii estimated from neighbour spacing)";
            break;
        case ffd::StreamAxes::from_radius: what += ", splat axes (created from normals and radius)"; break;
        case ffd::StreamAxes::absent_too_many:
            what +=
                "; no splat axes (no radius property, and " + std::to_string(input->points) +
                " points are more than deform estimates radii for while streaming: pass --estimate-radii, "
                "~75 bytes per point)";
            break;
        case ffd::StreamAxes::absent_no_normals:
            what += "; no splat axes (the input has no normals: `splatffd convert IN OUT` estimates them)";
            break;
    }
    what += " deformed by " + std::to_string(chain->lattices.size()) + " lattice" +
            (chain->lattices.size() == 1 ? " " : "s ") + joined(chain->names);
    print_summary(what.c_str(), points, o.backend, done->deform_ms, done->total_s, done->inverted,
                  done->set_up_ms);
    warn_empty_lattices(*chain, done->inside, points);
    if (o.bench > 0) {
        std::vector<double> rep_ms = done->timing_ms;
        std::sort(rep_ms.begin(), rep_ms.end());
        const double median = rep_ms.size() % 2
                                  ? rep_ms[rep_ms.size() / 2]
                                  : 0.5 * (rep_ms[rep_ms.size() / 2 - 1] + rep_ms[rep_ms.size() / 2]);
        std::printf(
            "{\"points\":%zu,\"backend\":\"%s\",\"median_ms\":%.4f,\"min_ms\":%.4f,\"runs\":%d,\"points_per_"
            "s\":%.4g}\n",
            points, o.backend.c_str(), median, rep_ms.front(), o.bench,
            median > 0 ? double(points) / (median * 1e-3) : 0.0);
    }
    return 0;
}

// Any other input or output: the whole cloud in memory (a scene's cloud, or an import that estimates
// missing normals and radii), deformed with its axes, saved by OUT's extension.
int deform_in_memory(const Options& o) {
    const std::string& in_path = o.files[0];
    if (o.bench > 0) return fail("--bench works on PLY input and output only");
    // A JSON or scene lattice source is read before the (possibly long) import.
    std::optional<cli::LatticeChain> early;
    if (!o.lattice_source.empty() && !ffd::is_fit_spec(o.lattice_source)) {
        auto c = cli::load_lattice_source(o.lattice_source, o.lattice_name);
        if (!c) return fail(c.message());
        early = std::move(*c);
    }
    ecs::Registry scene;
    sffd::use_engine_scene_hooks(scene);
    SplatCloud cloud;
    std::vector<float> weights;  // PointWeights of the cloud (empty: weight 1)
    SplatMaterial material;      // the input's, carried into a .glb output
    std::string cloud_name = std::filesystem::path(in_path).stem().string();
    const bool in_scene = cli::is_scene_path(in_path);
    std::string estimated;
    if (in_scene) {
        if (Status s = load_scene(scene, in_path); !s) return fail(s.message());
        cli::note_unkeyed_edits("deform", scene);
        std::vector<ecs::Entity> clouds;
        scene.each_entity([&](ecs::Entity e) {
            if (scene.has<SplatCloud>(e)) clouds.push_back(e);
        });
        if (clouds.empty()) {
            // A Gaussian scene: its Gaussians follow the lattices as in render and view.
            std::vector<ecs::Entity> gs;
            scene.each_entity([&](ecs::Entity e) {
                if (scene.has<GaussianCloud>(e)) gs.push_back(e);
            });
            if (gs.size() != 1) return fail(in_path + ": no point cloud (deform works on one)");
            // An export: no hidden or deleted Gaussian is written (runtime/scene/point_subset.h).
            if (auto gone = drop_gone_points(scene, gs[0], PointDrop::hidden_and_deleted); !gone)
                return fail(in_path + ": " + gone.message());
            const GaussianCloud& g = scene.get<GaussianCloud>(gs[0]);
            const PointWeights* gw = scene.try_get<PointWeights>(gs[0]);
            auto chain = early ? Result<cli::LatticeChain>(std::move(*early))
                               : lattice_chain(o, g.positions, g.origin, &scene);
            if (!chain) return fail(chain.message());
            return cli::deform_gaussian_cloud(
                g, chain->lattices, chain->names,
                std::to_string(chain->lattices.size()) + " lattice(s) " + joined(chain->names), o.files[1],
                o.ascii,
                gw && gw->values.size() == g.size() && !gw->values.empty() ? gw->values.data() : nullptr);
        }
        ecs::Entity chosen = clouds.size() == 1 ? clouds[0] : ecs::null_entity;
        if (!chosen && o.lattice_source.empty()) {
            auto own = cli::pick_scene_lattices(scene, in_path, o.lattice_name);
            if (own && own->cloud) chosen = own->cloud;
        }
        if (!chosen)
            return fail(in_path + ": " + std::to_string(clouds.size()) +
                        " point clouds; deform works on one (the one bound to the chosen lattice)");
        if (auto gone = drop_gone_points(scene, chosen, PointDrop::hidden_and_deleted); !gone)
            return fail(in_path + ": " + gone.message());
        cloud = scene.get<SplatCloud>(chosen);
        if (const PointWeights* w = scene.try_get<PointWeights>(chosen)) weights = w->values;
        if (const SplatMaterial* m = scene.try_get<SplatMaterial>(chosen)) material = *m;
        if (const Name* n = scene.try_get<Name>(chosen)) cloud_name = n->value;
    } else {
        auto c = assets::import_splat_cloud(in_path, {}, &material);
        if (!c) return fail(c.message());
        cloud = std::move(*c);
        auto w = assets::cloud_weights_of_file(in_path, cloud.size());  // a PLY's `weight` column
        if (!w) return fail(w.message());
        weights = std::move(w->values);
        estimated = " (normals/radii estimated by import where the input had none)";
    }
    auto chain = early ? Result<cli::LatticeChain>(std::move(*early))
                       : lattice_chain(o, cloud.positions, cloud.origin, in_scene ? &scene : nullptr);
    if (!chain) return fail(chain.message());

    const auto t_start = Clock::now();
    const std::size_t n = cloud.size();
    if (cloud.axis_u.size() != n || cloud.axis_v.size() != n) cloud.axis_u.clear(), cloud.axis_v.clear();
    if (cloud.normals.size() != n) cloud.normals.clear();
    std::optional<ffd::GpuDeformer> gpu;
    double set_up_ms = -1.0;
    if (o.backend == "gpu") {
        auto g = ffd::GpuDeformer::create_headless();
        if (!g) return fail(g.message());
        gpu.emplace(std::move(*g));
        set_up_ms = ffd::set_up_gpu_programs(*gpu, chain->lattices, weights.size() == n && n > 0);
    }
    double ms = 0.0;
    std::size_t inverted = 0;
    std::vector<std::size_t> inside;
    auto ptr = [](std::vector<glm::vec3>& v) { return v.empty() ? nullptr : v.data(); };
    for (const Lattice& l : chain->lattices) {
        ffd::PointsIn in{cloud.positions.data(),
                         ptr(cloud.normals),
                         ptr(cloud.axis_u),
                         ptr(cloud.axis_v),
                         n,
                         cloud.origin};
        in.weights = weights.size() == n && n > 0 ? weights.data() : nullptr;  // P + w (FFD(P) - P)
        const ffd::PointsOut out{cloud.positions.data(), ptr(cloud.normals), ptr(cloud.axis_u),
                                 ptr(cloud.axis_v)};
        const auto t0 = Clock::now();
        auto stats = o.backend == "gpu"         ? gpu->deform(l, in, out)
                     : o.backend == "reference" ? ffd::deform(l, in, out, ffd::Backend::reference)
                                                : ffd::deform(l, in, out);
        ms += std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
        if (!stats)
            return fail((o.lattice_source.empty() ? in_path : o.lattice_source) + ": " + stats.message());
        inverted += stats->inverted;
        inside.push_back(stats->inside);
    }
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(cloud.positions[i].x) || !std::isfinite(cloud.positions[i].y) ||
            !std::isfinite(cloud.positions[i].z))
            return fail((o.lattice_source.empty() ? in_path : o.lattice_source) + ": deformed point " +
                        std::to_string(i) + " of " + in_path + " is not finite; nothing was written to " +
                        o.files[1]);
    const std::string ext = lower_ext(o.files[1]);
    // The weights go out with the points they belong to (PLY `weight`, glTF `_WEIGHT`), as streamed
    // deform writes them back.
    const std::span<const float> kept =
        weights.size() == n ? std::span<const float>(weights) : std::span<const float>();
    Status saved = o.ascii && ext == ".ply"
                       ? assets::save_splat_ply(cloud, o.files[1], ply::Format::ascii, kept)
                       : assets::save_splat_cloud(cloud, o.files[1], cloud_name, material, kept);
    if (!saved) return fail(saved.message());
    const double total_s = std::chrono::duration<double>(Clock::now() - t_start).count();
    std::string what = o.files[1] + ": positions";
    what += cloud.normals.empty() ? "" : ", normals";
    what += cloud.axis_u.empty() ? "; no splat axes" : ", splat axes";
    what += " deformed by " + std::to_string(chain->lattices.size()) + " lattice" +
            (chain->lattices.size() == 1 ? " " : "s ") + joined(chain->names) + estimated;
    print_summary(what.c_str(), n, o.backend, ms, total_s, inverted, set_up_ms);
    warn_empty_lattices(*chain, inside, n);
    return 0;
}

int run_deform(sffd::cli::Args args) {
    Options o;
    if (int code = parse_options(args, o); code >= 0) return code;
    if (o.lattice_source.empty() && !cli::is_scene_path(o.files[0])) {
        std::fprintf(stderr,
                     "splatffd deform: --lattice is needed unless IN is a scene file holding a lattice\n");
        return usage();
    }
    // A hierarchy into a hierarchy, piece by piece (tools/splatffd/deform_hierarchy.h).
    if (cli::is_hierarchy_path(o.files[0]) && cli::is_hierarchy_path(o.files[1]))
        return cli::deform_hierarchy(o.files[0], o.files[1],
                                     [&](const std::vector<glm::vec3>& p, const glm::dvec3& origin) {
                                         return lattice_chain(o, p, origin, nullptr);
                                     });
    const bool ply_in = lower_ext(o.files[0]) == ".ply", ply_out = lower_ext(o.files[1]) == ".ply";
    if (cli::is_json_path(o.files[1]) && std::filesystem::path(o.files[1]).filename() != "meta.json")
        return fail(o.files[1] +
                    ": deform writes a point cloud (.ply .glb .gltf); to export a lattice: splatffd convert "
                    "SCENE.glb L.json");
    // The output's format follows its extension; anything else would put bytes under a misleading name.
    if (const std::string ext = lower_ext(o.files[1]); ext != ".gltf" && !cli::is_gaussian_output(o.files[1]))
        return fail(o.files[1] + ": deform writes .ply, .glb or .gltf files (got '" + ext +
                    "'); Gaussians also .compressed.ply, .spz, .sog or meta.json");
    // Writing over the input while streaming it would destroy the input on success.
    {
        std::error_code ec;
        const bool same = std::filesystem::equivalent(o.files[0], o.files[1], ec) ||
                          std::filesystem::weakly_canonical(o.files[0], ec) ==
                              std::filesystem::weakly_canonical(o.files[1], ec);
        if (same) return fail(o.files[1] + ": output is the input file; choose another output name");
    }
    // Every Gaussian format import reads, read whole (tools/splatffd/deform_gaussians.h).
    if (!cli::is_scene_path(o.files[0]) && cli::deform_reads_gaussians_whole(o.files[0], o.files[1]))
        return cli::deform_gaussian_file(
            o.files[0], o.files[1],
            [&](const GaussianCloud& g) { return lattice_chain(o, g.positions, g.origin, nullptr); },
            o.backend, o.bench, o.ascii);
    return ply_in && ply_out ? deform_ply_stream(o) : deform_in_memory(o);
}

}  // namespace

SFFD_COMMAND(deform,
             "deform a point cloud by a lattice JSON, a scene's lattices or fit:… (PLY streamed, axes too)",
             run_deform);
