// splatffd render [SCENE] --out DIR [--frames N|A:B] [--size WxH] [--quality hq|preview] [--format png,exr]
//                 [--background R,G,B] [--fps F] [--no-cull]
//                 [--camera EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV | --turntable N] [--video OUT.mp4|OUT.gif]
//
// Renders frames of a scene (built-in name or file; default `sphere`; 3D Gaussian files and scene files
// with Gaussian entities too, systems/gaussian/gaussian_scene.h) through the engine's standard
// schedule (tools/splatffd/engine.cpp: animation and deformation run before rendering), offscreen in a
// headless EGL context (no display needed). Frame k is rendered at clock time k / fps on the fixed-step
// grid with a clock of its own, so frame k alone is the same image as frame k of a sequence.
// Files: DIR/frame_NNNN.png (8-bit sRGB with alpha; transparent background unless --background) and
// DIR/frame_NNNN.exr (R G B A half linear, Z float view-axis depth, N.X N.Y N.Z half world normals).
// DIR/render_manifest.json: settings, frames written by this run, and "state": running | complete |
// failed (an interrupted run stays "running" with the frames it finished; SIGINT/SIGTERM exit 130/143).
// A scene without a camera is framed automatically; without lights it gets a default key light.
// --camera replaces the scene's camera for every frame; --turntable N renders frames 0..N-1 orbiting the
// scene's bounds centre at the scene camera's distance and height (frame 0 = the scene camera's eye);
// --video encodes the PNG frames with ffmpeg (tools/bootstrap.sh installs it), MP4 and GIF over the same
// background (--background, else black).
// Exit 0 ok, 1 bad scene or unwritable output (the message names the file), 2 usage.
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

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
#include "systems/gaussian/components.h"
#include "systems/splat_render/camera_math.h"
#include "systems/splat_render/gaussian_pass.h"
#include "systems/splat_render/image_io.h"
#include "systems/splat_render/splat_pack.h"
#include "systems/splat_render/splat_render.h"
#include "tools/splatffd/command.h"
#include "tools/splatffd/frame_files.h"
#include "tools/splatffd/engine.h"

namespace {

using namespace sffd;

constexpr const char* kUsage =
    "usage: splatffd render [SCENE] --out DIR [--frames N|A:B] [--size WxH] [--quality hq|preview] [--format png,exr]\n"
    "                       [--background R,G,B] [--fps F] [--no-cull]\n"
    "                       [--camera EX,EY,EZ,TX,TY,TZ,UX,UY,UZ,FOV | --turntable N] [--video FILE.mp4|FILE.gif]\n"
    "  SCENE            built-in name (sphere, face) or a file: scene .glb .gltf, point cloud .ply .obj .off,\n"
    "                   3D Gaussians .ply (3DGS) .splat .spz .glb (KHR_gaussian_splatting) (default: sphere)\n"
    "  --out DIR        output folder (created; required); files frame_NNNN.png / frame_NNNN.exr\n"
    "  --frames N|A:B   N: frames 0..N-1; A:B: frames A..B inclusive (default 1: frame 0); frame k is at\n"
    "                   time k / fps, and the scene's clips play\n"
    "  --size WxH       image size in pixels (default 1280x720)\n"
    "  --quality Q      hq (three-pass surface splatting, default) or preview (opaque discs)\n"
    "  --format LIST    png, exr or png,exr (default png,exr)\n"
    "  --background RGB sRGB colour 0..1 (e.g. 1,1,1) behind the object in the PNG and the video\n"
    "                   (default: transparent PNG, black video)\n"
    "  --fps F          frames per second of the fixed-step clock and the video (default 24, the demo clip's rate)\n"
    "  --no-cull        disable back-face/frustum culling (for comparisons; default on)\n"
    "  --camera E,T,U,F the camera for every frame: eye x,y,z, target x,y,z, up x,y,z, vertical fov in\n"
    "                   degrees (0..180); eye = target and up along the view direction are refused\n"
    "                   (default: the scene's camera, or one framing the scene)\n"
    "  --turntable N    N frames (0..N-1) orbiting the scene's bounds centre at the scene camera's\n"
    "                   distance and height, one turn; frame 0 is seen from the scene camera's eye; the\n"
    "                   scene's clips play along (frame k at time k / fps), as with --frames\n"
    "  --video FILE     also encode the PNG frames as FILE (.mp4 H.264 or .gif) at --fps, both over the\n"
    "                   same background; needs ffmpeg (tools/bootstrap.sh installs it)\n"
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
        auto n = cli::parse_number("--camera", text.substr(start, end == std::string::npos ? std::string::npos : end - start), -1e30, 1e30);
        if (!n) return n.error();
        v.push_back(*n);
        if (end == std::string::npos) break;
        start = end + 1;
    }
    if (v.size() != 10)
        return make_error("--camera expects 10 numbers eye x,y,z,target x,y,z,up x,y,z,fov; got " + std::to_string(v.size()) + " in '" + text + "'");
    Camera c;
    c.eye = glm::dvec3(v[0], v[1], v[2]);
    c.target = glm::dvec3(v[3], v[4], v[5]);
    c.up = glm::dvec3(v[6], v[7], v[8]);
    const double fov = v[9];
    const glm::dvec3 view = c.target - c.eye;
    if (!(glm::length(view) > 1e-12 * std::max(1.0, glm::length(c.eye))))
        return make_error("--camera: eye and target are the same point; the camera has no view direction");
    if (!(glm::length(c.up) > 0.0) || glm::length(glm::cross(glm::normalize(view), glm::normalize(c.up))) < 1e-6)
        return make_error("--camera: up (" + number_text(v[6]) + ", " + number_text(v[7]) + ", " + number_text(v[8]) +
                          ") is parallel to the view direction (or zero); the image's up is undefined");
    if (!(fov > 0.0 && fov < 180.0)) return make_error("--camera: fov " + number_text(fov) + " is outside (0, 180) degrees");
    c.fov_y_degrees = static_cast<float>(fov);
    return c;
}

struct SceneBounds {
    glm::dvec3 center{0.0};
    double radius = 1.0;
};

// The union of every non-empty cloud's world-space bounding sphere (as render::scene_camera frames it).
SceneBounds scene_bounds(const ecs::Registry& registry) {
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    std::vector<std::pair<glm::dvec3, double>> balls;
    // A cloud's local bounding sphere `b` in world space (centre through the model matrix, radius by its
    // largest axis scale).
    const auto add = [&](ecs::Entity e, const render::BoundingSphere& b, const glm::dvec3& origin) {
        const glm::dmat4 m = model_matrix(registry.try_get<Transform>(e), origin);
        const double scale = std::max({glm::length(glm::dvec3(m[0])), glm::length(glm::dvec3(m[1])), glm::length(glm::dvec3(m[2]))});
        const glm::dvec3 c = glm::dvec3(m * glm::dvec4(b.center, 1.0));
        balls.emplace_back(c, b.radius * scale);
        lo = glm::min(lo, c - b.radius * scale);
        hi = glm::max(hi, c + b.radius * scale);
    };
    registry.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& cloud) {
        if (cloud.size() > 0) add(e, render::bounding_sphere(cloud), cloud.origin);
    });
    registry.view<const GaussianCloud>().each([&](ecs::Entity e, const GaussianCloud& cloud) {  // 3D Gaussians too
        if (cloud.size() > 0) add(e, render::gaussian_bounding_sphere(cloud), cloud.origin);
    });
    SceneBounds out;
    if (balls.empty()) return out;
    out.center = 0.5 * (lo + hi);
    out.radius = 0.0;
    for (const auto& [c, r] : balls) out.radius = std::max(out.radius, glm::length(c - out.center) + r);
    out.radius = std::max(out.radius, 1e-9);
    return out;
}

// Near and far planes that hold the whole scene from wherever the eye is (a camera given on the command
// line has none of its own).
void fit_clip_planes(Camera& c, const SceneBounds& b) {
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
Camera turntable_camera(const Camera& scene, const SceneBounds& b, long k, long n) {
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

// ---- --video ---------------------------------------------------------------------------------------

// The full path of `name` on PATH (an executable regular file), or "".
std::string find_on_path(const std::string& name) {
    const char* path = std::getenv("PATH");
    std::string dirs = path ? path : "/usr/bin:/bin";
    std::size_t start = 0;
    while (start <= dirs.size()) {
        const std::size_t end = std::min(dirs.find(':', start), dirs.size());
        const std::string dir = dirs.substr(start, end - start);
        const std::filesystem::path candidate = std::filesystem::path(dir.empty() ? "." : dir) / name;
        std::error_code ec;
        if (std::filesystem::is_regular_file(candidate, ec) && ::access(candidate.c_str(), X_OK) == 0) return candidate.string();
        start = end + 1;
    }
    return {};
}

// Encodes DIR/frame_FIRST..LAST.png into `video` (.mp4: H.264 yuv420p, even size; .gif: per-clip palette)
// through a temporary file renamed at the end, so a failed encode leaves no half video. ffmpeg runs with
// an argument vector (no shell): paths with spaces or quotes are safe.
// Both formats are flattened over the same opaque `background` (sRGB) first: H.264 has no alpha and a GIF's
// one transparent index cannot hold soft edges, and left to ffmpeg the MP4 came out black where the GIF
// was transparent. The PNG's straight alpha is blended in display (sRGB) space, as 3DGS viewers do.
Status encode_video(const std::string& ffmpeg, const std::filesystem::path& dir, long first, long last, double fps,
                    const std::filesystem::path& video, glm::vec3 background) {
    const bool gif = video.extension() == ".gif";
    const std::filesystem::path tmp = video.parent_path() / (video.filename().string() + ".tmp" + std::to_string(::getpid()));
    char rate[64];
    std::snprintf(rate, sizeof rate, "%.9g", fps);
    std::vector<std::string> argv = {ffmpeg, "-nostdin", "-loglevel", "error", "-y", "-framerate", rate, "-start_number", std::to_string(first),
                                     "-i", (dir / "frame_%04d.png").string(), "-frames:v", std::to_string(last - first + 1)};
    char colour[16];
    const auto byte = [](float c) { return static_cast<unsigned>(std::lround(std::clamp(c, 0.0f, 1.0f) * 255.0f)); };
    std::snprintf(colour, sizeof colour, "0x%02X%02X%02X", byte(background.x), byte(background.y), byte(background.z));
    // [bg] is the colour as a stream as long as the frames; overlay=shortest=1 ends with the last frame.
    const std::string flatten = std::string("[0:v]split[in][size];[size]format=rgb24,drawbox=c=") + colour +
                                ":t=fill[bg];[bg][in]overlay=shortest=1:format=rgb";
    if (gif) {
        argv.insert(argv.end(), {"-filter_complex", flatten + ",split[a][b];[a]palettegen=reserve_transparent=0[p];[b][p]paletteuse",
                                 "-loop", "0", "-f", "gif"});
    } else {
        argv.insert(argv.end(), {"-filter_complex", flatten + ",pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264", "-pix_fmt", "yuv420p",
                                 "-movflags", "+faststart", "-f", "mp4"});
    }
    argv.push_back(tmp.string());
    std::vector<char*> args;
    for (std::string& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    pid_t pid = 0;
    if (int err = posix_spawn(&pid, ffmpeg.c_str(), nullptr, nullptr, args.data(), environ); err != 0)
        return make_error(video.string() + ": cannot run " + ffmpeg + ": " + std::strerror(err));
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {}
    std::error_code ec;
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::filesystem::remove(tmp, ec);
        return make_error(video.string() + ": ffmpeg failed (" +
                          (WIFEXITED(status) ? "exit " + std::to_string(WEXITSTATUS(status)) : std::string("killed")) + "); its messages are above");
    }
    std::filesystem::rename(tmp, video, ec);
    if (ec) {
        std::filesystem::remove(tmp, ec);
        return make_error(video.string() + ": cannot write: " + ec.message());
    }
    return {};
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

int run_render(sffd::cli::Args args) {
    std::string scene = "sphere", out_dir;
    bool scene_given = false, png = true, exr = true, culling = true;
    long first = 0, last = 0, width = 1280, height = 720;
    double fps = 24.0;  // the built-in demo clip (systems/animation/paper_demo.h) is authored at 24 fps
    render::Quality quality = render::Quality::hq;
    std::optional<glm::vec3> background;
    std::optional<Camera> camera;
    long turntable = 0;
    bool frames_given = false;
    std::string video;
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        const bool has_value = i + 1 < args.size();
        auto bad = [&](const char* what) {
            std::fprintf(stderr, "splatffd render: %s '%s'\n", what, has_value ? args[i + 1].c_str() : "");
            return 2;
        };
        if (cli::is_help(a)) {
            return cli::help(kUsage);
        } else if (a == "--out" && has_value) {
            out_dir = args[++i];
        } else if (a == "--frames" && has_value) {
            auto range = cli::parse_frames(args[++i]);
            if (!range) return cli::usage_error("render", range.message(), "");
            first = range->first, last = range->last;
            frames_given = true;
        } else if (a == "--size" && has_value) {
            if (Status st = cli::parse_integer_pair("--size", args[i + 1], 'x', 1, 16384, width, height); !st) {
                std::fprintf(stderr, "splatffd render: %s\n", st.message().c_str());
                return 2;
            }
            ++i;
        } else if (a == "--camera" && has_value) {
            auto c = parse_camera(args[++i]);
            if (!c) {
                std::fprintf(stderr, "splatffd render: %s\n", c.message().c_str());
                return 2;
            }
            camera = *c;
        } else if (a == "--turntable" && has_value) {
            auto n = cli::parse_integer("--turntable", args[++i], 1, 100'000);
            if (!n) {
                std::fprintf(stderr, "splatffd render: %s\n", n.message().c_str());
                return 2;
            }
            turntable = static_cast<long>(*n);
        } else if (a == "--video" && has_value) {
            video = args[++i];
        } else if (a == "--quality" && has_value) {
            if (args[i + 1] == "hq") quality = render::Quality::hq;
            else if (args[i + 1] == "preview") quality = render::Quality::preview;
            else return bad("--quality expects hq or preview, got");
            ++i;
        } else if (a == "--format" && has_value) {
            if (!cli::parse_image_formats(args[i + 1], png, exr)) return bad("--format expects png, exr or png,exr, got");
            ++i;
        } else if (a == "--background" && has_value) {
            background = parse_rgb(args[i + 1]);
            if (!background) return bad("--background expects R,G,B in 0..1, got");
            ++i;
        } else if (a == "--fps" && has_value) {
            auto f = cli::parse_number("--fps", args[++i], 1e-6, 1e6);
            if (!f) {
                std::fprintf(stderr, "splatffd render: %s\n", f.message().c_str());
                return 2;
            }
            fps = *f;
        } else if (a == "--no-cull") {
            culling = false;
        } else if (!a.empty() && a[0] != '-' && !scene_given) {
            scene = a;
            scene_given = true;
        } else {
            return cli::usage_error("render", "unknown or incomplete option '" + a + "'", kUsage);
        }
    }
    // Memory budget stated up front: the HQ passes keep about 40 bytes per pixel on the GPU and the capture
    // about 30 on the CPU, so 8192x8192 (67M pixels, ~4.5 GB) is the most one frame may ask for.
    constexpr long long kMaxPixels = 8192LL * 8192LL;
    if (static_cast<long long>(width) * height > kMaxPixels) {
        std::fprintf(stderr, "splatffd render: --size %ldx%ld is %lld pixels, more than the budget of %lld (8192x8192)\n", width, height,
                     static_cast<long long>(width) * height, kMaxPixels);
        return 2;
    }
    if (out_dir.empty()) {
        return cli::usage_error("render", "--out DIR is required", kUsage);
    }
    if (turntable > 0 && camera) {
        std::fprintf(stderr, "splatffd render: --turntable orbits the scene camera; it cannot be combined with --camera\n");
        return 2;
    }
    if (turntable > 0 && frames_given) {
        std::fprintf(stderr, "splatffd render: --turntable N renders frames 0..N-1; it cannot be combined with --frames\n");
        return 2;
    }
    if (turntable > 0) first = 0, last = turntable - 1;
    // --video: checked before any frame is rendered (format, ffmpeg, the folder it goes to).
    std::string ffmpeg;
    if (!video.empty()) {
        const std::string ext = std::filesystem::path(video).extension().string();
        if (ext != ".mp4" && ext != ".gif") {
            std::fprintf(stderr, "splatffd render: --video %s: the file must end in .mp4 or .gif\n", video.c_str());
            return 2;
        }
        if (!png) {
            std::fprintf(stderr, "splatffd render: --video encodes the PNG frames; --format must include png\n");
            return 2;
        }
        ffmpeg = find_on_path("ffmpeg");
        if (ffmpeg.empty()) {
            std::fprintf(stderr, "splatffd render: --video needs ffmpeg, which is not on PATH; install it (Debian/Ubuntu: "
                                 "apt-get install ffmpeg) or encode the PNG frames yourself\n");
            return 1;
        }
        const std::filesystem::path parent = std::filesystem::absolute(video).parent_path();
        std::error_code vec;
        if (!std::filesystem::is_directory(parent, vec) || ::access(parent.c_str(), W_OK) != 0) {
            std::fprintf(stderr, "%s: cannot write the video: folder %s does not exist or is not writable\n", video.c_str(), parent.c_str());
            return 1;
        }
    }
    if (!cli::create_output_folder(out_dir)) return 1;

    // Offscreen rendering needs no window: EGL surfaceless works with or without a display.
    auto ctx = gfx::create_context({.headless = true, .width = int(width), .height = int(height), .debug = false});
    if (!ctx) {
        std::fprintf(stderr, "splatffd render: %s\n", ctx.message().c_str());
        return 1;
    }
    int status = 0;
    {
        ecs::Registry registry;
        if (Status st = load_scene(registry, scene); !st) {
            std::fprintf(stderr, "%s\n", st.message().c_str());
            return 1;
        }
        render::RenderSettings settings;
        settings.quality = quality, settings.width = int(width), settings.height = int(height);
        settings.background = background ? std::optional<glm::vec3>(glm::vec3(render::srgb_to_linear(background->x),
                                                                               render::srgb_to_linear(background->y),
                                                                               render::srgb_to_linear(background->z)))
                                         : std::nullopt;
        settings.culling = culling;
        settings.aux_outputs = exr;  // Z and N channels
        registry.set_resource<render::RenderSettings>(settings);
        // --camera / --turntable replace the scene camera (its clip planes are fitted to the scene).
        const SceneBounds bounds = camera || turntable > 0 ? scene_bounds(registry) : SceneBounds{};
        const Camera scene_view = turntable > 0 ? render::scene_camera(registry, double(width) / double(height)) : Camera{};
        if (camera) {
            fit_clip_planes(*camera, bounds);
            use_camera(registry, *camera);
        }
        registry.set_resource<app::AppContext>(app::AppContext{&ctx.value(), false});
        if (Status st = render::init_render_state(registry); !st) {
            std::fprintf(stderr, "splatffd render: %s\n", st.message().c_str());
            return 1;
        }
        const Schedule schedule = make_engine_schedule({.present = false});
        const long count = last - first + 1;
        // DIR/render_manifest.json says which frames this run wrote and whether it finished, so frames of
        // an interrupted run are not mistaken for a complete sequence (older frames may share the folder).
        const std::filesystem::path manifest = std::filesystem::path(out_dir) / "render_manifest.json";
        const std::string started = std::to_string(std::chrono::duration_cast<std::chrono::seconds>(
                                                       std::chrono::system_clock::now().time_since_epoch()).count());
        auto write_manifest = [&](long written_last, const char* state) {
            std::string frames = "[";
            for (long k = first; k <= written_last; ++k) {
                if (k > first) frames += ',';
                frames += std::to_string(k);
            }
            frames += "]";
            char fields[512];
            std::snprintf(fields, sizeof fields,
                          "\"first\": %ld, \"last\": %ld, \"size\": [%ld, %ld], \"quality\": \"%s\", \"formats\": \"%s\", \"fps\": %.17g, "
                          "\"culling\": %s",
                          first, last, width, height, quality == render::Quality::hq ? "hq" : "preview",
                          png && exr ? "png,exr" : png ? "png" : "exr", fps, culling ? "true" : "false");
            std::string scene_escaped;
            for (char ch : scene) {
                if (ch == '"' || ch == '\\') scene_escaped += '\\';
                if (static_cast<unsigned char>(ch) >= 0x20) scene_escaped += ch;
            }
            const std::string text = std::string("{\"generator\": \"splatffd render " SFFD_VERSION "\", \"state\": \"") + state +
                                     "\", \"complete\": " + (std::string(state) == "complete" ? "true" : "false") +
                                     ", \"started_unix\": " + started + ", \"scene\": \"" + scene_escaped + "\", " + fields +
                                     ", \"frames_written\": " + frames + "}\n";
            return write_file_atomic(manifest, text);
        };
        if (Status st = write_manifest(first - 1, "running"); !st) {
            std::fprintf(stderr, "splatffd render: %s\n", st.message().c_str());
            render::release_render_state(registry);
            return 1;
        }
        long written_last = first - 1;
        const auto start = std::chrono::steady_clock::now();
        // Progress rewrites one line with \r: on a terminal only, so log files get no control characters.
        const bool show_progress = cli::stderr_is_terminal();
        bool line_open = false;
        const auto end_line = [&] {
            if (line_open) std::fputc('\n', stderr);
            line_open = false;
        };
        for (long k = first; k <= last; ++k) {
            // A clock of its own per frame, seeked to frame k: the frame depends on k only.
            Clock clock(ClockSettings{.fixed_dt = 1.0 / fps});
            clock.seek(double(k) / fps);
            FrameContext frame = clock.tick();
            frame.frame = std::uint64_t(k);
            if (turntable > 0) use_camera(registry, turntable_camera(scene_view, bounds, k, turntable));
            schedule.run_frame(registry, frame);
            auto image = render::capture_frame(registry);
            if (!image) {
                end_line();
                std::fprintf(stderr, "splatffd render: %s\n", image.message().c_str());
                status = 1;
                break;
            }
            const std::filesystem::path base = cli::frame_file_base(out_dir, k);
            if (png) {
                if (Status st = render::write_png(base.string() + ".png", render::to_rgba8(*image, settings.background)); !st) {
                    end_line();
                    std::fprintf(stderr, "%s\n", st.message().c_str());
                    status = 1;
                    break;
                }
            }
            if (exr) {
                if (Status st = render::write_exr(base.string() + ".exr", *image); !st) {
                    end_line();
                    std::fprintf(stderr, "%s\n", st.message().c_str());
                    status = 1;
                    break;
                }
            }
            written_last = k;
            if (Status st = write_manifest(written_last, k == last ? "complete" : "running"); !st) {
                end_line();
                std::fprintf(stderr, "splatffd render: %s\n", st.message().c_str());
                status = 1;
                break;
            }
            const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            const long done = k - first + 1;
            if (show_progress) {
                std::fprintf(stderr, "\rsplatffd render: frame %ld (%ld/%ld, %.0f%%) %.2f s/frame, ETA %.0f s   ", k, done,
                             count, 100.0 * double(done) / double(count), elapsed / double(done),
                             elapsed / double(done) * double(count - done));
                std::fflush(stderr);
                line_open = true;
            }
        }
        end_line();
        if (status == 0)
            std::fprintf(stderr, "splatffd render: wrote frames %ld..%ld to %s in %.1f s\n", first, last, out_dir.c_str(),
                         std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
        if (status != 0) (void)write_manifest(written_last, "failed");
        render::release_render_state(registry);
    }
    if (status == 0 && !video.empty()) {
        if (Status st = encode_video(ffmpeg, out_dir, first, last, fps, video, background.value_or(glm::vec3(0.0f))); !st) {
            std::fprintf(stderr, "splatffd render: %s\n", st.message().c_str());
            return 1;
        }
        std::fprintf(stderr, "wrote %s: %ld frames at %g fps\n", video.c_str(), last - first + 1, fps);
    }
    return status;
}

}  // namespace

SFFD_COMMAND(render, "render frames of a scene to PNG/EXR (headless)", run_render);
