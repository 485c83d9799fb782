// splatffd render [SCENE] --out DIR [--frames A:B] [--size WxH] [--quality hq|preview] [--format png,exr]
//                 [--background R,G,B] [--fps F] [--no-cull]
//
// Renders frames of a scene (built-in name or file; default `sphere`) through the engine's standard
// schedule (tools/splatffd/engine.cpp: animation and deformation run before rendering), offscreen in a
// headless EGL context (no display needed). Frame k is rendered at clock time k / fps on the fixed-step
// grid with a clock of its own, so frame k alone is the same image as frame k of a sequence.
// Files: DIR/frame_NNNN.png (8-bit sRGB with alpha; transparent background unless --background) and
// DIR/frame_NNNN.exr (R G B A half linear, Z float view-axis depth, N.X N.Y N.Z half world normals).
// DIR/render_manifest.json: settings, frames written by this run, and "state": running | complete |
// failed (an interrupted run stays "running" with the frames it finished; SIGINT/SIGTERM exit 130/143).
// A scene without a camera is framed automatically; without lights it gets a default key light.
// Exit 0 ok, 1 bad scene or unwritable output (the message names the file), 2 usage.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>
#include <system_error>

#include "runtime/app/app.h"
#include "runtime/app/clock.h"
#include "runtime/assets/scene.h"
#include "runtime/core/atomic_file.h"
#include "runtime/ecs/registry.h"
#include "runtime/gfx/context.h"
#include "systems/splat_render/image_io.h"
#include "systems/splat_render/splat_render.h"
#include "tools/splatffd/command.h"
#include "tools/splatffd/convert_gaussians.h"
#include "tools/splatffd/render_gaussians.h"
#include "tools/splatffd/engine.h"

namespace {

using namespace sffd;

void usage() {
    std::fprintf(stderr,
                 "usage: splatffd render [SCENE] --out DIR [--frames A:B] [--size WxH] [--quality hq|preview]\n"
                 "                       [--format png,exr] [--background R,G,B] [--fps F] [--no-cull]\n"
                 "  SCENE            built-in name (sphere, face) or a scene/point-cloud file (default: sphere)\n"
                 "  --out DIR        output folder (created); files frame_NNNN.png / frame_NNNN.exr\n"
                 "  --frames A:B     frame range, inclusive (default 0:0); frame k is at time k / fps\n"
                 "  --size WxH       image size in pixels (default 1280x720)\n"
                 "  --quality Q      hq (three-pass surface splatting, default) or preview (opaque discs)\n"
                 "  --format LIST    png, exr or png,exr (default png,exr)\n"
                 "  --background RGB sRGB colour 0..1 (e.g. 1,1,1) filling the PNG background (default transparent)\n"
                 "  --fps F          frames per second of the fixed-step clock (default 24, the demo clip's rate)\n"
                 "  --no-cull        disable back-face/frustum culling (for comparisons)\n");
}

bool parse_int_pair(const std::string& s, char sep, long& a, long& b) {
    const auto at = s.find(sep);
    if (at == std::string::npos) return false;
    try {
        std::size_t n1 = 0, n2 = 0;
        const std::string first = s.substr(0, at), second = s.substr(at + 1);
        a = std::stol(first, &n1);
        b = std::stol(second, &n2);
        return n1 == first.size() && n2 == second.size();
    } catch (...) {
        return false;
    }
}

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
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        const bool has_value = i + 1 < args.size();
        auto bad = [&](const char* what) {
            std::fprintf(stderr, "splatffd render: %s '%s'\n", what, has_value ? args[i + 1].c_str() : "");
            return 2;
        };
        if (a == "--help" || a == "-h") {
            usage();
            return 0;
        } else if (a == "--out" && has_value) {
            out_dir = args[++i];
        } else if (a == "--frames" && has_value) {
            if (!parse_int_pair(args[i + 1], ':', first, last) || first < 0 || last < first)
                return bad("--frames expects A:B with 0 <= A <= B, got");
            ++i;
        } else if (a == "--size" && has_value) {
            if (!parse_int_pair(args[i + 1], 'x', width, height) || width < 1 || height < 1 || width > 16384 ||
                height > 16384)
                return bad("--size expects WxH (1..16384), got");
            ++i;
        } else if (a == "--quality" && has_value) {
            if (args[i + 1] == "hq") quality = render::Quality::hq;
            else if (args[i + 1] == "preview") quality = render::Quality::preview;
            else return bad("--quality expects hq or preview, got");
            ++i;
        } else if (a == "--format" && has_value) {
            const std::string& f = args[i + 1];
            png = f == "png" || f == "png,exr" || f == "exr,png";
            exr = f == "exr" || f == "png,exr" || f == "exr,png";
            if (!png && !exr) return bad("--format expects png, exr or png,exr, got");
            ++i;
        } else if (a == "--background" && has_value) {
            background = parse_rgb(args[i + 1]);
            if (!background) return bad("--background expects R,G,B in 0..1, got");
            ++i;
        } else if (a == "--fps" && has_value) {
            try {
                fps = std::stod(args[i + 1]);
            } catch (...) {
                fps = 0;
            }
            if (!(fps > 0.0 && fps < 1e6)) return bad("--fps expects a positive number, got");
            ++i;
        } else if (a == "--no-cull") {
            culling = false;
        } else if (!a.empty() && a[0] != '-' && !scene_given) {
            scene = a;
            scene_given = true;
        } else {
            std::fprintf(stderr, "splatffd render: unknown or incomplete option '%s'\n", a.c_str());
            usage();
            return 2;
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
        std::fprintf(stderr, "splatffd render: --out DIR is required\n");
        usage();
        return 2;
    }
    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    if (ec || !std::filesystem::is_directory(out_dir)) {
        std::fprintf(stderr, "%s: cannot create output folder (%s)\n", out_dir.c_str(), ec.message().c_str());
        return 1;
    }

    // 3D Gaussian files (3DGS PLY, .splat, KHR glb): one frame through the Gaussian renderer.
    if (scene_given && cli::is_gaussian_file(scene)) return cli::render_gaussians(scene, out_dir, int(width), int(height), background);
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
        for (long k = first; k <= last; ++k) {
            // A clock of its own per frame, seeked to frame k: the frame depends on k only.
            Clock clock(ClockSettings{.fixed_dt = 1.0 / fps});
            clock.seek(double(k) / fps);
            FrameContext frame = clock.tick();
            frame.frame = std::uint64_t(k);
            schedule.run_frame(registry, frame);
            auto image = render::capture_frame(registry);
            if (!image) {
                std::fprintf(stderr, "\nsplatffd render: %s\n", image.message().c_str());
                status = 1;
                break;
            }
            char name[32];
            std::snprintf(name, sizeof name, "frame_%04ld", k);
            const std::filesystem::path base = std::filesystem::path(out_dir) / name;
            if (png) {
                if (Status st = render::write_png(base.string() + ".png", render::to_rgba8(*image, settings.background)); !st) {
                    std::fprintf(stderr, "\n%s\n", st.message().c_str());
                    status = 1;
                    break;
                }
            }
            if (exr) {
                if (Status st = render::write_exr(base.string() + ".exr", *image); !st) {
                    std::fprintf(stderr, "\n%s\n", st.message().c_str());
                    status = 1;
                    break;
                }
            }
            written_last = k;
            if (Status st = write_manifest(written_last, k == last ? "complete" : "running"); !st) {
                std::fprintf(stderr, "\nsplatffd render: %s\n", st.message().c_str());
                status = 1;
                break;
            }
            const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            const long done = k - first + 1;
            std::fprintf(stderr, "\rsplatffd render: frame %ld (%ld/%ld, %.0f%%) %.2f s/frame, ETA %.0f s   ", k, done,
                         count, 100.0 * double(done) / double(count), elapsed / double(done),
                         elapsed / double(done) * double(count - done));
            std::fflush(stderr);
        }
        std::fprintf(stderr, "\n");
        if (status != 0) (void)write_manifest(written_last, "failed");
        render::release_render_state(registry);
    }
    return status;
}

}  // namespace

SFFD_COMMAND(render, "render frames of a scene to PNG/EXR (headless)", run_render);
