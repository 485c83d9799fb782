// splatffd render [SCENE] --out DIR [--frames A:B] [--size WxH] [--quality hq|preview] [--format png,exr]
//                 [--background R,G,B] [--fps F] [--no-cull]
//                 [--camera EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV | --turntable N] [--video OUT.mp4|OUT.gif]
//                 [--shard K/N]
//
// Renders frames of a scene (built-in name or file; default `sphere`; 3D Gaussian files and scene files
// with Gaussian entities too, systems/gaussian/gaussian_scene.h) through the engine's standard
// schedule (systems/engine/engine.cpp: animation and deformation run before rendering), offscreen in a
// headless EGL context (no display needed). Frame k is rendered at clock time k / fps on the fixed-step
// grid with a clock of its own, so frame k alone is the same image as frame k of a sequence.
// Files: DIR/frame_NNNN.png (8-bit sRGB with alpha; transparent background unless --background) and
// DIR/frame_NNNN.exr (R G B A half linear, Z float view-axis depth, N.X N.Y N.Z half world normals).
// DIR/render_manifest.json: settings, frames written by this run, and "state": running | complete |
// failed (an interrupted run stays "running" with the frames it finished; SIGINT/SIGTERM exit 130/143);
// rewritten at a constant size after each frame, with every frame's fingerprint at the end
// (tools/splatffd/render_manifest.h). A range whose output would not fit the free disk space is refused.
// --shard K/N renders frames FIRST+K, FIRST+K+N, ... into the same file names, with a manifest of its own
// (DIR/render_manifest.shard-K-of-N.json); `splatffd assemble DIR` checks and joins the shards.
// A scene without a camera is framed automatically; without lights it gets a default key light.
// --camera replaces the scene's camera for every frame; --turntable N renders frames 0..N-1 orbiting the
// scene's bounds centre at the scene camera's distance and height (frame 0 = the scene camera's eye);
// --video encodes the PNG frames with ffmpeg (optional: not installed by tools/bootstrap.sh).
// Exit 0 ok, 1 bad scene or unwritable output (the message names the file), 2 usage.
#include <algorithm>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <filesystem>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "runtime/app/app.h"
#include "runtime/app/clock.h"
#include "runtime/assets/scene.h"
#include "runtime/core/atomic_file.h"
#include "runtime/ecs/registry.h"
#include "runtime/gfx/context.h"
#include "runtime/simd/simd.h"
#include "systems/gaussian/components.h"
#include "systems/splat_render/camera_math.h"
#include "systems/splat_render/gaussian_pass.h"
#include "systems/splat_render/image_io.h"
#include "systems/splat_render/splat_pack.h"
#include "systems/engine/engine.h"
#include "systems/splat_render/splat_render.h"
#include "tools/splatffd/command.h"
#include "tools/splatffd/frame_files.h"
#include "tools/splatffd/render_manifest.h"
#include "tools/splatffd/unkeyed_note.h"
#include "systems/lod/streaming.h"
#include "tools/splatffd/stream_options.h"
#include "tools/splatffd/video.h"
#include "systems/engine/engine_frame.h"

namespace {

using namespace sffd;

constexpr const char* kUsage =
    "usage: splatffd render [SCENE] --out DIR [--frames N|A:B] [--size WxH] [--quality hq|preview] [--format "
    "png,exr]\n"
    "                       [--background R,G,B] [--fps F] [--no-cull]\n"
    "                       [--camera EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV | --turntable N] [--video "
    "FILE.mp4|FILE.gif] [--shard K/N]\n"
    "                       [--splat-budget N] [--memory-budget MB] [--lod-error PX] [--full-detail]\n"
    "  SCENE            built-in name (sphere, face) or a file: scene .glb .gltf, point cloud .ply .obj "
    ".off,\n"
    "                   3D Gaussians .ply (3DGS) .splat .spz .ksplat .sog, a SOG folder or its meta.json,\n"
    "                   .glb (KHR_gaussian_splatting), a streamed SOG's DIR/lod-meta.json or a Potree 2\n"
    "                   octree's DIR/metadata.json (streamed: every node in view at full detail unless\n"
    "                   the options below say otherwise) (default: sphere); Gaussian captures open upright,\n"
    "                   stored y down (another up: splatffd --up y|z|-z render ...)\n"
    "  --out DIR        output folder (created; required); files frame_NNNN.png / frame_NNNN.exr\n"
    "  --frames N|A:B   N: frames 0..N-1; A:B: frames A..B inclusive (default 1: frame 0); frame k is at\n"
    "                   time k / fps, and the scene's clips play (an un-keyed edit saved with the scene\n"
    "                   shows at its own clip time only, the clip's pose at every other)\n"
    "  --size WxH       image size in pixels (default 1280x720)\n"
    "  --quality Q      hq (three-pass surface splatting, default) or preview (opaque discs)\n"
    "  --format LIST    png, exr or png,exr (default png,exr)\n"
    "  --background RGB sRGB colour 0..1 (e.g. 1,1,1) behind the object in the PNG and the video\n"
    "                   (default: transparent PNG, black video)\n"
    "  --fps F          frames per second of the fixed-step clock and the video (default 24, the demo clip's "
    "rate)\n"
    "  --no-cull        disable back-face/frustum culling (for comparisons; default on)\n"
    "  --camera E,T,U,F the camera for every frame: eye x,y,z, target x,y,z, up x,y,z, vertical fov in\n"
    "                   degrees (0..180); eye = target and up along the view direction are refused\n"
    "                   (default: the scene's camera, or one framing the scene)\n"
    "  --turntable N    N frames (0..N-1) orbiting the scene's bounds centre at the scene camera's\n"
    "                   distance and height, one turn; frame 0 is seen from the scene camera's eye; the\n"
    "                   scene's clips play along (frame k at time k / fps), as with --frames\n"
    "  --video FILE     also encode the PNG frames as FILE (.mp4 H.264 or .gif) at --fps, both over the\n"
    "                   same background; needs ffmpeg (tools/bootstrap.sh installs it)\n"
    "  --shard K/N      render only frames FIRST+K, FIRST+K+N, ... (shard K of N, for render farms;\n"
    "                   default: every frame); `splatffd assemble DIR` checks the shards and writes the "
    "manifest\n"
    "Progress is shown on a terminal only (nothing is written into logs or pipes).\n";

// ---- --camera, --turntable ------------------------------------------------------------------------

// Parses "ex,ey,ez,tx,ty,tz,ux,uy,uz,fov" and refuses cameras that have no view: eye = target, up
// parallel to the view direction (or zero), fov outside (0, 180).
std::string number_text(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

Result<Camera> parse_camera(const std::string& text) {
    std::vector<double> v;
    std::size_t start = 0;
    while (true) {
        const std::size_t end = text.find(',', start);
        auto n = cli::parse_number(
            "--camera", text.substr(start, end == std::string::npos ? std::string::npos : end - start), -1e30,
            1e30);
        if (!n) return n.error();
        v.push_back(*n);
        if (end == std::string::npos) break;
        start = end + 1;
    }
    if (v.size() != 10)
        return make_error("--camera expects 10 numbers eye x,y,z,target x,y,z,up x,y,z,fov; got " +
                          std::to_string(v.size()) + " in '" + text + "'");
    Camera c;
    c.eye = glm::dvec3(v[0], v[1], v[2]);
    c.target = glm::dvec3(v[3], v[4], v[5]);
    c.up = glm::dvec3(v[6], v[7], v[8]);
    const double fov = v[9];
    const glm::dvec3 view = c.target - c.eye;
    if (!(glm::length(view) > 1e-12 * std::max(1.0, glm::length(c.eye))))
        return make_error("--camera: eye and target are the same point; the camera has no view direction");
    if (!(glm::length(c.up) > 0.0) ||
        glm::length(glm::cross(glm::normalize(view), glm::normalize(c.up))) < 1e-6)
        return make_error("--camera: up (" + number_text(v[6]) + ", " + number_text(v[7]) + ", " +
                          number_text(v[8]) +
                          ") is parallel to the view direction (or zero); the image's up is undefined");
    if (!(fov > 0.0 && fov < 180.0))
        return make_error("--camera: fov " + number_text(fov) + " is outside (0, 180) degrees");
    c.fov_y_degrees = static_cast<float>(fov);
    return c;
}

// Near and far planes that hold the whole scene from wherever the eye is (a camera given on the command
// line has none of its own).
void fit_clip_planes(Camera& c, const render::SceneSphere& b) {
    const double d = glm::length(c.eye - b.center);
    c.near_plane = static_cast<float>(std::max(d - 2.0 * b.radius, 1e-3 * std::max(d, b.radius)));
    c.far_plane = static_cast<float>(d + 2.0 * b.radius);
}

// Makes `c` the camera every frame is seen through: render::scene_camera uses the first Camera entity.
void use_camera(ecs::Registry& registry, const Camera& c) {
    bool found = false;
    registry.view<Camera>().each([&](Camera& existing) {
        if (!found) existing = c, found = true;
    });
    if (!found) registry.emplace<Camera>(registry.create(), c);
}

// Frame k of n of the turntable: the scene camera's eye turned by 2 pi k / n about the axis through the
// bounds centre along the camera's up; it looks at the centre (the orbit keeps distance and height).
Camera turntable_camera(const Camera& scene, const render::SceneSphere& b, long k, long n) {
    const glm::dvec3 up = glm::normalize(scene.up);
    const glm::dvec3 offset = scene.eye - b.center;
    const double height = glm::dot(offset, up);
    glm::dvec3 radial = offset - height * up;
    double r = glm::length(radial);
    glm::dvec3 a = r > 1e-9 * std::max(1.0, glm::length(offset)) ? radial / r : glm::dvec3(0.0);
    double h = height;
    if (r <= 1e-9 * std::max(1.0, glm::length(offset))) {
        // Looking straight along up: orbit at the same distance in the horizontal plane instead.
        const glm::dvec3 t = std::abs(up.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
        a = glm::normalize(glm::cross(up, t));
        r = std::max(glm::length(offset), b.radius * 2.0);
        h = 0.0;
    }
    const glm::dvec3 bb = glm::cross(up, a);
    const double angle = 2.0 * glm::pi<double>() * double(k) / double(n);
    Camera c = scene;
    c.eye = b.center + h * up + r * (std::cos(angle) * a + std::sin(angle) * bb);
    c.target = b.center;
    c.up = up;
    fit_clip_planes(c, b);
    return c;
}

// "A<sep>B", each part through cli::parse_integer (one message format, the option named).
std::optional<glm::vec3> parse_rgb(const std::string& s) {
    glm::vec3 c(0.0f);
    std::size_t start = 0;
    for (int k = 0; k < 3; ++k) {
        const auto end = k < 2 ? s.find(',', start) : s.size();
        if (end == std::string::npos) return std::nullopt;
        try {
            std::size_t used = 0;
            const std::string part = s.substr(start, end - start);
            const double v = std::stod(part, &used);
            if (used != part.size() || !(v >= 0.0 && v <= 1.0)) return std::nullopt;
            c[k] = float(v);
        } catch (...) {
            return std::nullopt;
        }
        start = end + 1;
    }
    return c;
}

// ---- the command, step by step: parse, check, set up the scene, render the frames, encode --------------

// Everything the options decide.
struct RenderOptions {
    std::string scene = "sphere", out_dir, video;
    bool scene_given = false, png = true, exr = true, culling = true, frames_given = false;
    long first = 0, last = 0, width = 1280, height = 720, turntable = 0;
    double fps = 24.0;  // the built-in demo clip (systems/animation/paper_demo.h) is authored at 24 fps
    render::Quality quality = render::Quality::hq;
    std::optional<glm::vec3> background;
    std::optional<Camera> camera;
    std::optional<cli::Shard> shard;
    cli::StreamCli stream = cli::final_render_stream_defaults();
    std::string command;  // the shell line that re-runs this render (in the manifest)
};

// Fills `o` from the arguments; an exit code when the command ends here (--help, a bad value).
std::optional<int> parse_render_args(cli::Args args, RenderOptions& o) {
    o.command = "splatffd render";
    for (const std::string& a : args) {
        o.command += ' ';  // appended in two steps: GCC 12 flags " " + string&& with a false -Wrestrict
        o.command += cli::shell_quote(a);
    }
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        const bool has_value = i + 1 < args.size();
        auto bad = [&](const char* what) {
            std::fprintf(stderr, "splatffd render: %s '%s'\n", what, has_value ? args[i + 1].c_str() : "");
            return 2;
        };
        auto refuse = [](const std::string& message) {
            std::fprintf(stderr, "splatffd render: %s\n", message.c_str());
            return 2;
        };
        if (cli::is_help(a)) {
            return cli::help(std::string(kUsage) + cli::kStreamUsage);
        } else if (const int taken = cli::parse_stream_option("render", args, i, o.stream); taken != 0) {
            if (taken < 0) return 2;
        } else if (a == "--out" && has_value) {
            o.out_dir = args[++i];
        } else if (a == "--frames" && has_value) {
            auto range = cli::parse_frames(args[++i]);
            if (!range) return cli::usage_error("render", range.message(), "");
            o.first = range->first, o.last = range->last;
            o.frames_given = true;
        } else if (a == "--size" && has_value) {
            if (Status st = cli::parse_integer_pair("--size", args[i + 1], 'x', 1, 16384, o.width, o.height);
                !st)
                return refuse(st.message());
            ++i;
        } else if (a == "--camera" && has_value) {
            auto c = parse_camera(args[++i]);
            if (!c) return refuse(c.message());
            o.camera = *c;
        } else if (a == "--turntable" && has_value) {
            auto n = cli::parse_integer("--turntable", args[++i], 1, 100'000);
            if (!n) return refuse(n.message());
            o.turntable = static_cast<long>(*n);
        } else if (a == "--shard" && has_value) {
            auto s = cli::parse_shard(args[++i]);
            if (!s) return refuse(s.message());
            o.shard = *s;
        } else if (a == "--video" && has_value) {
            o.video = args[++i];
        } else if (a == "--quality" && has_value) {
            if (args[i + 1] == "hq") o.quality = render::Quality::hq;
            else if (args[i + 1] == "preview") o.quality = render::Quality::preview;
            else return bad("--quality expects hq or preview, got");
            ++i;
        } else if (a == "--format" && has_value) {
            if (!cli::parse_image_formats(args[i + 1], o.png, o.exr))
                return bad("--format expects png, exr or png,exr, got");
            ++i;
        } else if (a == "--background" && has_value) {
            o.background = parse_rgb(args[i + 1]);
            if (!o.background) return bad("--background expects R,G,B in 0..1, got");
            ++i;
        } else if (a == "--fps" && has_value) {
            auto f = cli::parse_number("--fps", args[++i], 1e-6, 1e6);
            if (!f) return refuse(f.message());
            o.fps = *f;
        } else if (a == "--no-cull") {
            o.culling = false;
        } else if (!a.empty() && a[0] != '-' && !o.scene_given) {
            o.scene = a;
            o.scene_given = true;
        } else {
            return cli::usage_error("render", "unknown or incomplete option '" + a + "'", kUsage);
        }
    }
    return std::nullopt;
}

// Combinations and budgets, all before any work; `ffmpeg` is set when --video is given.
std::optional<int> check_render_options(RenderOptions& o, std::string& ffmpeg) {
    // Memory budget stated up front: the HQ passes keep about 40 bytes per pixel on the GPU and the capture
    // about 30 on the CPU, so 8192x8192 (67M pixels, ~4.5 GB) is the most one frame may ask for.
    constexpr long long kMaxPixels = 8192LL * 8192LL;
    if (static_cast<long long>(o.width) * o.height > kMaxPixels) {
        std::fprintf(
            stderr,
            "splatffd render: --size %ldx%ld is %lld pixels, more than the budget of %lld (8192x8192)\n",
            o.width, o.height, static_cast<long long>(o.width) * o.height, kMaxPixels);
        return 2;
    }
    if (o.out_dir.empty()) return cli::usage_error("render", "--out DIR is required", kUsage);
    if (o.turntable > 0 && o.camera) {
        std::fprintf(
            stderr,
            "splatffd render: --turntable orbits the scene camera; it cannot be combined with --camera\n");
        return 2;
    }
    if (o.turntable > 0 && o.frames_given) {
        std::fprintf(
            stderr,
            "splatffd render: --turntable N renders frames 0..N-1; it cannot be combined with --frames\n");
        return 2;
    }
    if (o.turntable > 0) o.first = 0, o.last = o.turntable - 1;
    if (o.shard && !o.video.empty()) {
        // A shard has only some of the frames: the video is made once all shards are in (`splatffd
        // assemble`).
        std::fprintf(
            stderr,
            "splatffd render: --video cannot be combined with --shard; encode the assembled clip with "
            "`splatffd assemble DIR --video FILE`\n");
        return 2;
    }
    if (!o.video.empty()) {
        if (!o.png) {
            std::fprintf(stderr,
                         "splatffd render: --video encodes the PNG frames; --format must include png\n");
            return 2;
        }
        bool usage_error = false;
        auto f = cli::check_video_output(o.video, usage_error);
        if (!f) {
            std::fprintf(stderr, "splatffd render: %s\n", f.message().c_str());
            return usage_error ? 2 : 1;
        }
        ffmpeg = *f;
    }
    return std::nullopt;
}

// Before the first frame, the estimate is deliberately low (0.05 bytes per pixel of PNG, 0.5 of EXR; the
// sphere at 1280x720 writes 0.16 and 1.65), so no run that fits is refused; after the first frame the
// real size is used.
double estimated_frame_bytes(const RenderOptions& o) {
    const double pixels = double(o.width) * double(o.height);
    return pixels * ((o.png ? 0.05 : 0.0) + (o.exr ? 0.5 : 0.0));
}

// The manifest's "settings": everything that decides the pixels, and the binary's version. Shards of one
// clip have equal settings (`splatffd assemble` compares them).
nlohmann::ordered_json settings_json(const RenderOptions& o) {
    nlohmann::ordered_json s;
    s["scene"] = o.scene;
    s["first"] = o.first, s["last"] = o.last;
    s["size"] = {o.width, o.height};
    s["quality"] = o.quality == render::Quality::hq ? "hq" : "preview";
    s["formats"] = o.png && o.exr ? "png,exr" : o.png ? "png" : "exr";
    s["fps"] = o.fps;
    s["culling"] = o.culling;
    s["background"] = o.background ? nlohmann::ordered_json{o.background->x, o.background->y, o.background->z}
                                   : nlohmann::ordered_json();
    s["camera"] = o.camera
                      ? nlohmann::ordered_json{o.camera->eye.x,        o.camera->eye.y,    o.camera->eye.z,
                                               o.camera->target.x,     o.camera->target.y, o.camera->target.z,
                                               o.camera->up.x,         o.camera->up.y,     o.camera->up.z,
                                               o.camera->fov_y_degrees}
                      : nlohmann::ordered_json();
    s["turntable"] = o.turntable;
    s["version"] = SFFD_VERSION;
    return s;
}

// The loaded scene and what every frame needs from it.
struct RenderScene {
    ecs::Registry registry;
    render::RenderSettings settings;
    render::SceneSphere bounds;
    Camera scene_view;  // the scene camera the turntable orbits from
};

// Loads the scene, applies the options to it and makes the render state (needs the GL context current).
Status set_up_scene(const RenderOptions& o, gfx::GlContext& ctx, RenderScene& s) {
    sffd::use_engine_scene_hooks(s.registry);
    // A hierarchy streams; each frame waits for its whole cut, so frame k is the same whoever renders it.
    cli::apply_stream_options(s.registry, o.stream);
    if (Status st = load_scene(s.registry, o.scene); !st) return st;
    s.settings.quality = o.quality, s.settings.width = int(o.width), s.settings.height = int(o.height);
    s.settings.background = o.background
                                ? std::optional<glm::vec3>(glm::vec3(render::srgb_to_linear(o.background->x),
                                                                     render::srgb_to_linear(o.background->y),
                                                                     render::srgb_to_linear(o.background->z)))
                                : std::nullopt;
    s.settings.culling = o.culling;
    s.settings.aux_outputs = o.exr;  // Z and N channels
    s.registry.set_resource<render::RenderSettings>(s.settings);
    // --camera / --turntable replace the scene camera (its clip planes are fitted to the scene).
    s.bounds = o.camera || o.turntable > 0 ? render::scene_sphere(s.registry) : render::SceneSphere{};
    s.scene_view =
        o.turntable > 0 ? render::scene_camera(s.registry, double(o.width) / double(o.height)) : Camera{};
    if (o.camera) {
        Camera c = *o.camera;
        fit_clip_planes(c, s.bounds);
        use_camera(s.registry, c);
    }
    s.registry.set_resource<app::AppContext>(app::AppContext{&ctx, false});
    if (Status st = render::init_render_state(s.registry); !st)
        return make_error("splatffd render: " + st.message());
    return {};
}

// Renders frame k on a clock of its own (the frame depends on k only) and writes its files.
Result<cli::FramePrint> render_frame(const RenderOptions& o, RenderScene& s, const Schedule& schedule,
                                     long k) {
    Clock clock(ClockSettings{.fixed_dt = 1.0 / o.fps});
    clock.seek(double(k) / o.fps);
    FrameContext frame = clock.tick();
    frame.frame = std::uint64_t(k);
    if (o.turntable > 0) use_camera(s.registry, turntable_camera(s.scene_view, s.bounds, k, o.turntable));
    schedule.run_frame(s.registry, frame);
    // A hierarchy whose cut could not be drawn whole (a failed piece, a cut over the memory budget) would
    // give frame k other bytes on another machine: the frame is refused.
    if (Status st = lod::stream_status(s.registry); !st)
        return make_error("frame " + std::to_string(k) + ": " + st.message());
    auto image = render::capture_frame(s.registry);
    if (!image) return make_error("splatffd render: " + image.message());
    const std::filesystem::path base = cli::frame_file_base(o.out_dir, k);
    cli::FramePrint print{k, std::nullopt, std::nullopt};
    if (o.png) {
        const std::filesystem::path file = base.string() + ".png";
        if (Status st = render::write_png(file, render::to_rgba8(*image, s.settings.background)); !st)
            return st.error();
        auto p = cli::fingerprint(file);
        if (!p) return p.error();
        print.png = *p;
    }
    if (o.exr) {
        const std::filesystem::path file = base.string() + ".exr";
        if (Status st = render::write_exr(file, *image); !st) return st.error();
        auto p = cli::fingerprint(file);
        if (!p) return p.error();
        print.exr = *p;
    }
    return print;
}

// Renders the run's frames (all of FIRST..LAST, or the shard's share), keeping the manifest current:
// "running" with the count done after each frame (constant size), "complete" or "failed" with every
// written frame's fingerprint at the end. Returns the exit status.
int render_frames(const RenderOptions& o, RenderScene& s, cli::RunRecord& run) {
    const std::filesystem::path manifest = cli::manifest_path(o.out_dir, run.shard, run.sharded);
    const Schedule schedule = make_engine_schedule({.present = false});
    const long count = run.frames.count;
    if (count == 0) run.state = "complete";  // a shard with no frame (more shards than frames) is done
    if (Status st = cli::write_manifest(manifest, run); !st) {
        std::fprintf(stderr, "splatffd render: %s\n", st.message().c_str());
        return 1;
    }
    int status = 0;
    const auto start = std::chrono::steady_clock::now();
    // Progress rewrites one line with \r: on a terminal only, so log files get no control characters.
    const bool show_progress = cli::stderr_is_terminal();
    bool line_open = false;
    const auto end_line = [&] {
        if (line_open) std::fputc('\n', stderr);
        line_open = false;
    };
    for (long i = 0; i < count; ++i) {
        const long k = run.frames.at(i);
        auto print = render_frame(o, s, schedule, k);
        if (!print) {
            end_line();
            cli::command_error("render", print.message());
            status = 1;
            break;
        }
        run.files.push_back(*print);
        run.written = i + 1;
        if (i == 0 && count > 1) {
            // The first frame's real size, for the rest of the run.
            const double bytes =
                double((print->png ? print->png->bytes : 0) + (print->exr ? print->exr->bytes : 0));
            if (Status st = cli::check_free_space(o.out_dir, count - 1, bytes,
                                                  "at the size of the first frame", "render");
                !st) {
                end_line();
                std::fprintf(stderr, "splatffd render: %s\n", st.message().c_str());
                status = 1;
                break;
            }
        }
        if (i + 1 == count) run.state = "complete";
        if (Status st = cli::write_manifest(manifest, run); !st) {
            end_line();
            std::fprintf(stderr, "splatffd render: %s\n", st.message().c_str());
            status = 1;
            break;
        }
        const double elapsed =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const long done = i + 1;
        if (show_progress) {
            std::fprintf(stderr, "\rsplatffd render: frame %ld (%ld/%ld, %.0f%%) %.2f s/frame, ETA %.0f s   ",
                         k, done, count, 100.0 * double(done) / double(count), elapsed / double(done),
                         elapsed / double(done) * double(count - done));
            std::fflush(stderr);
            line_open = true;
        }
    }
    end_line();
    if (status == 0 && count > 0)
        std::fprintf(stderr, "splatffd render: wrote frames %ld..%ld to %s in %.1f s\n", run.frames.at(0),
                     run.frames.at(count - 1), o.out_dir.c_str(),
                     std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    if (status != 0) {
        run.state = "failed";
        (void)cli::write_manifest(manifest, run);
    }
    return status;
}

int run_render(sffd::cli::Args args) {
    RenderOptions o;
    if (auto rc = parse_render_args(args, o)) return *rc;
    std::string ffmpeg;
    if (auto rc = check_render_options(o, ffmpeg)) return *rc;
    if (!cli::create_output_folder(o.out_dir)) return 1;

    cli::RunRecord run;
    run.started_unix =
        std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch())
            .count();
    run.command = o.command;
    run.settings = settings_json(o);
    run.sharded = o.shard.has_value();
    run.shard = o.shard.value_or(cli::Shard{});
    run.frames = cli::shard_frames(o.first, o.last, run.shard);
    if (Status st = cli::check_free_space(o.out_dir, run.frames.count, estimated_frame_bytes(o),
                                          "a low estimate for this size and format", "render");
        !st) {
        std::fprintf(stderr, "splatffd render: %s\n", st.message().c_str());
        return 1;
    }

    // Offscreen rendering needs no window: EGL surfaceless works with or without a display.
    auto ctx = gfx::create_context(
        {.headless = true, .width = int(o.width), .height = int(o.height), .debug = false});
    if (!ctx) {
        std::fprintf(stderr, "splatffd render: %s\n", ctx.message().c_str());
        return 1;
    }
    run.machine = cli::MachineRecord{simd::chosen(), ctx.value().renderer()};
    int status = 0;
    {
        RenderScene scene;
        if (Status st = set_up_scene(o, ctx.value(), scene); !st) {
            return cli::command_error("render", st.message());
        }
        cli::note_unkeyed_edits("render", scene.registry, o.fps);
        status = render_frames(o, scene, run);
        render::release_render_state(scene.registry);
    }
    if (status == 0 && !o.video.empty()) {
        if (Status st = cli::encode_video(ffmpeg, o.out_dir, o.first, o.last, o.fps, o.video,
                                          o.background.value_or(glm::vec3(0.0f)));
            !st) {
            std::fprintf(stderr, "splatffd render: %s\n", st.message().c_str());
            return 1;
        }
        std::fprintf(stderr, "wrote %s: %ld frames at %g fps\n", o.video.c_str(), o.last - o.first + 1,
                     o.fps);
        if (const std::string note = cli::video_size_note(o.video, long(o.width), long(o.height));
            !note.empty())
            std::fprintf(stderr, "splatffd render: note: %s\n", note.c_str());
    }
    return status;
}

}  // namespace

SFFD_COMMAND(render, "render frames of a scene to PNG/EXR (headless)", run_render);
