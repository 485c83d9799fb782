// splatffd reference [SCENE] --out DIR [--frames N|A:B] [--size WxH] [--supersample N] [--anisotropic N]
// [--format png,exr]
//
// Ground-truth frames (systems/splat_render/ground_truth.h): the exact surface behind the scene's cloud
// (the built-in `sphere`; or the triangles of a mesh file, at rest, whose cloud is what `splatffd render
// MESH` samples from it), deformed by the lattices as the demo clip poses them at frame k (time k / fps),
// ray traced on the CPU with the render command's camera, lights, material and texture. Files are named
// like `splatffd render`'s (DIR/frame_NNNN.png / .exr), so `splatffd compare` can pair them.
// Exit 0 ok, 1 bad scene / no exact surface / unwritable output, 2 usage.
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

#include "runtime/app/clock.h"
#include "runtime/assets/builtin_scenes.h"
#include "runtime/assets/import.h"
#include "runtime/assets/scene.h"
#include "runtime/ecs/registry.h"
#include "systems/animation/animation_system.h"
#include "systems/splat_render/ground_truth.h"
#include "systems/splat_render/image_io.h"
#include "tools/splatffd/command.h"
#include "tools/splatffd/frame_files.h"
#include "systems/engine/engine_frame.h"

namespace {

using namespace sffd;

constexpr const char* kUsage =
    "usage: splatffd reference [SCENE] --out DIR [--frames N|A:B] [--size WxH] [--supersample N] "
    "[--anisotropic N]\n"
    "                          [--format png,exr] [--fps F]\n"
    "  SCENE            a scene whose cloud has an exact surface (built-in: sphere; default), or a\n"
    "                   mesh file (OBJ, OFF, PLY, glTF with triangles; one untinted texture or none)\n"
    "  --out DIR        output folder (created; required); files frame_NNNN.png / frame_NNNN.exr\n"
    "  --frames N|A:B   N: frames 0..N-1; A:B: frames A..B inclusive (default 1: frame 0); frame k is at\n"
    "                   time k / fps, and the scene's clips play\n"
    "  --size WxH       image size in pixels (default 1280x720)\n"
    "  --supersample N  N x N rays per pixel, box-filtered (default 0: one ray, trilinear mip)\n"
    "  --anisotropic N  one ray, up to N trilinear probes along the footprint (default 0: off)\n"
    "  --format LIST    png, exr or png,exr (default png,exr)\n"
    "  --fps F          frames per second of the clip clock (default 24)\n";

// A mesh file (OBJ, OFF, PLY or glTF with triangles) loads as the cloud sampled from it (load_scene, as
// `splatffd render` loads it): its triangles become that cloud's ExactMesh, the surface to trace.
Status attach_exact_mesh(ecs::Registry& registry, const std::string& scene) {
    if (assets::is_builtin_scene(scene) || registry.count<ExactSphere>() > 0) return {};
    std::vector<ecs::Entity> clouds;
    registry.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud&) { clouds.push_back(e); });
    if (clouds.size() != 1) return {};  // reference_scene() names what is missing
    auto g = assets::read_geometry(scene);
    if (!g) return g.error();
    if (g->triangle_count() == 0) return {};
    const SplatCloud& cloud = registry.get<SplatCloud>(clouds[0]);
    ExactMesh mesh;
    mesh.positions.reserve(g->positions.size());
    for (const glm::dvec3& p : g->positions) mesh.positions.push_back(p - cloud.origin);
    mesh.normals = std::move(g->normals);
    mesh.uvs = std::move(g->uvs);
    mesh.triangles = std::move(g->triangles);
    registry.emplace<ExactMesh>(clouds[0], std::move(mesh));
    return {};
}

int run_reference(sffd::cli::Args args) {
    std::string scene = "sphere", out_dir;
    bool scene_given = false, png = true, exr = true;
    long first = 0, last = 0, width = 1280, height = 720, supersample = 0, anisotropic = 0;
    double fps = 24.0;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        const bool has_value = i + 1 < args.size();
        auto bad = [&](const char* what) {
            std::fprintf(stderr, "splatffd reference: %s '%s'\n", what, has_value ? args[i + 1].c_str() : "");
            return 2;
        };
        auto fail = [](const Status& st) {
            std::fprintf(stderr, "splatffd reference: %s\n", st.message().c_str());
            return 2;
        };
        if (cli::is_help(a)) {
            return cli::help(kUsage);
        } else if (a == "--out" && has_value) {
            out_dir = args[++i];
        } else if (a == "--frames" && has_value) {
            auto range = cli::parse_frames(args[++i]);  // one meaning of --frames in every command
            if (!range) return fail(range.error());
            first = range->first, last = range->last;
        } else if (a == "--size" && has_value) {
            if (Status st = cli::parse_integer_pair("--size", args[i + 1], 'x', 1, 16384, width, height); !st)
                return fail(st);
            ++i;
        } else if (a == "--supersample" && has_value) {
            auto n = cli::parse_integer("--supersample", args[++i], 0, 16);
            if (!n) return fail(n.error());
            supersample = static_cast<long>(*n);
        } else if (a == "--anisotropic" && has_value) {
            auto n = cli::parse_integer("--anisotropic", args[++i], 0, 64);
            if (!n) return fail(n.error());
            anisotropic = static_cast<long>(*n);
        } else if (a == "--format" && has_value) {
            if (!cli::parse_image_formats(args[i + 1], png, exr))
                return bad("--format expects png, exr or png,exr, got");
            ++i;
        } else if (a == "--fps" && has_value) {
            auto f = cli::parse_number("--fps", args[++i], 1e-6, 1e6);
            if (!f) return fail(f.error());
            fps = *f;
        } else if (!a.empty() && a[0] != '-' && !scene_given) {
            scene = a;
            scene_given = true;
        } else {
            return cli::usage_error("reference", "unknown or incomplete option '" + a + "'", kUsage);
        }
    }
    if (out_dir.empty()) {
        return cli::usage_error("reference", "--out DIR is required", kUsage);
    }
    if (!cli::create_output_folder(out_dir)) return 1;
    ecs::Registry registry;
    sffd::use_engine_scene_hooks(registry);
    if (Status st = load_scene(registry, scene); !st) {
        cli::command_error("reference", st.message());
        return 1;
    }
    if (Status st = attach_exact_mesh(registry, scene); !st) {
        std::fprintf(stderr, "splatffd reference: %s\n", st.message().c_str());
        return 1;
    }
    render::ReferenceSettings settings;
    settings.supersample = int(supersample);
    settings.anisotropic = int(anisotropic);
    for (long k = first; k <= last; ++k) {
        // The clip's pose at frame k, as `splatffd render` reaches it (a clock of its own, seeked to k /
        // fps).
        Clock clock(ClockSettings{.fixed_dt = 1.0 / fps});
        clock.seek(double(k) / fps);
        FrameContext frame = clock.tick();
        frame.frame = std::uint64_t(k);
        animation_system(registry, frame);
        auto ref = render::reference_scene(registry, int(width), int(height));
        if (!ref) {
            cli::command_error("reference", scene + ": " + ref.message());
            return 1;
        }
        auto image = render::render_reference(*ref, settings);
        if (!image) {
            cli::command_error("reference", scene + ": " + image.message());
            return 1;
        }
        const std::filesystem::path base = cli::frame_file_base(out_dir, k);
        if (png) {
            if (Status st = render::write_png(base.string() + ".png", render::to_rgba8(*image)); !st) {
                cli::command_error("reference", st.message());
                return 1;
            }
        }
        if (exr) {
            if (Status st = render::write_exr(base.string() + ".exr", *image); !st) {
                cli::command_error("reference", st.message());
                return 1;
            }
        }
        std::fprintf(stderr, "splatffd reference: frame %ld\n", k);
    }
    return 0;
}

}  // namespace

SFFD_COMMAND(reference, "ray trace the exact surface behind a scene (ground truth for image quality)",
             run_reference);
