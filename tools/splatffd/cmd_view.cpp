// splatffd view [SCENE] [options]: the interactive editor (systems/editor/view_app.h).
#include <charconv>
#include <cstdio>
#include <string>

#include "tools/splatffd/command.h"

#include "systems/editor/view_app.h"
#include "systems/engine/engine.h"
#include "systems/engine/engine_frame.h"
#include "tools/splatffd/stream_options.h"

namespace {

constexpr const char* kUsage =
    "usage: splatffd view [SCENE] [--replay FILE] [--record FILE] [--frames N] [--out PATH] [--save PATH] "
    "[--size WxH]\n"
    "                     [--quality hq|preview] [--no-ui] [--headless] [--json F] [--sync-timing] "
    "[--window-screenshot PATH]\n"
    "                     [--panel-rects-json PATH] [--no-overlay-cache] [--no-ui-cache]\n"
    "                     [--sprite-raster auto|raster|cpu]\n"
    "                     [--splat-budget N] [--memory-budget MB] [--lod-error PX] [--full-detail]\n"
    "  SCENE              built-in name (sphere, face) or a file: scene .glb .gltf, point cloud .ply .obj "
    ".off,\n"
    "                     3D Gaussians .ply (3DGS) .splat .spz .ksplat .sog, a SOG folder or its\n"
    "                     meta.json, .glb (default: sphere); Gaussian captures open upright, stored y\n"
    "                     down (another up: splatffd --up y|z|-z view ...); clips open paused at the\n"
    "                     clip time the scene was saved at\n"
    "  --replay FILE      play a recorded input file (format: systems/editor/README.md)\n"
    "  --record FILE      write this session's input to FILE at exit\n"
    "  --frames N|0:B     exit after N frames (0:B: after frames 0..B; default: run until the window "
    "closes)\n"
    "  --out PATH         write the last frame to PATH (.png or .exr) at exit (old spelling: --screenshot)\n"
    "  --save PATH        where ctrl+s saves (default: the scene file, or <scene>.glb)\n"
    "  --size WxH         window size (default 1280x720)\n"
    "  --quality Q        hq (three-pass surface splatting, default) or preview (opaque discs, faster)\n"
    "  --no-ui            no ImGui panels (default: panels shown)\n"
    "  --no-overlay-cache draw every lattice edge every frame (default: edges drawn over the surface\n"
    "                     that did not move are kept in an image and only the moving ones drawn again)\n"
    "  --no-ui-cache      draw every panel every frame (default: a panel that did not change is copied from\n"
    "                     an image of it)\n"
    "  --sprite-raster R  who draws the splats' sprites (preview frames, the HQ visibility pass): raster\n"
    "                     (GL point sprites), cpu (the CPU's ray casts, uploaded), auto (default: cpu on a\n"
    "                     software rasterizer)\n"
    "  --headless         no window (EGL); input only from --replay; needs --frames or --replay\n"
    "                     (default: a window)\n"
    "  --json F           write frame-time statistics (all frames, frames with a live drag) (old spelling:\n"
    "                     --timing-json)\n"
    "  --sync-timing      finish the GL queue around every system and pass, so each one's time includes its "
    "GL\n"
    "                     work (a true per-system split; frames get slower; default off)\n"
    "  --window-screenshot PATH  with --frames: the last frame's whole window (panels too), PNG; not\n"
    "                     with --headless\n"
    "  --panel-rects-json PATH   with --frames: the panels' rectangles in the last frame, JSON\n"
    "Runs under X (use `xvfb-run -a` without a display). Keys and mouse: systems/editor/README.md\n";

int run_view_command(sffd::cli::Args args) {
    sffd::editor::ViewOptions o;
    o.scene_hooks = sffd::engine_scene_hooks();
    bool have_scene = false;
    sffd::cli::StreamCli stream = sffd::cli::interactive_stream_defaults();
    for (std::size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        const auto value = [&](const char* name) -> const std::string* {
            if (i + 1 >= args.size()) {
                std::fprintf(stderr, "splatffd view: %s needs a value\n", name);
                return nullptr;
            }
            return &args[++i];
        };
        if (sffd::cli::is_help(a)) {
            return sffd::cli::help(std::string(kUsage) + sffd::cli::kStreamUsage);
        } else if (a == "--replay") {
            const auto* v = value("--replay");
            if (!v) return 2;
            o.replay = *v;
        } else if (a == "--record") {
            const auto* v = value("--record");
            if (!v) return 2;
            o.record = *v;
        } else if (a == "--frames") {
            const auto* v = value("--frames");
            if (!v) return 2;
            auto range =
                sffd::cli::parse_frames(*v, 999'999'999);  // one meaning of --frames in every command
            if (!range) return sffd::cli::usage_error("view", range.message(), "");
            // The editor's clock starts at frame 0; a later first frame would need a seek it does not do.
            if (range->first != 0)
                return sffd::cli::usage_error(
                    "view", "--frames " + *v + ": the editor starts at frame 0; use N or 0:B", "");
            o.frames = std::uint64_t(range->count());
        } else if (a == "--out" || a == "--screenshot") {
            if (a == "--screenshot") sffd::cli::warn_deprecated("view", a, "--out");
            const auto* v = value(a.c_str());
            if (!v) return 2;
            o.screenshot = *v;
        } else if (a == "--save") {
            const auto* v = value("--save");
            if (!v) return 2;
            o.save_path = *v;
        } else if (a == "--window-screenshot") {
            const auto* v = value("--window-screenshot");
            if (!v) return 2;
            o.window_screenshot = *v;
        } else if (a == "--panel-rects-json") {
            const auto* v = value("--panel-rects-json");
            if (!v) return 2;
            o.panel_rects_json = *v;
        } else if (a == "--json" || a == "--timing-json") {
            if (a == "--timing-json") sffd::cli::warn_deprecated("view", a, "--json");
            const auto* v = value(a.c_str());
            if (!v) return 2;
            o.timing_json = *v;
        } else if (a == "--size") {
            const auto* v = value("--size");
            if (!v || std::sscanf(v->c_str(), "%dx%d", &o.width, &o.height) != 2 || o.width < 16 ||
                o.height < 16 || o.width > 8192 || o.height > 8192) {
                std::fprintf(stderr, "splatffd view: --size takes WxH (16..8192)\n");
                return 2;
            }
        } else if (a == "--quality") {
            const auto* v = value("--quality");
            if (!v || (*v != "hq" && *v != "preview")) {
                std::fprintf(stderr, "splatffd view: --quality takes hq or preview\n");
                return 2;
            }
            o.preview = *v == "preview";
        } else if (a == "--sprite-raster") {
            const auto* v = value("--sprite-raster");
            if (!v || (*v != "auto" && *v != "raster" && *v != "cpu")) {
                std::fprintf(stderr, "splatffd view: --sprite-raster takes auto, raster or cpu\n");
                return 2;
            }
            o.sprite_raster = *v;
        } else if (a == "--no-ui") {
            o.ui = false;
        } else if (a == "--no-overlay-cache") {
            o.overlay_cache = false;
        } else if (a == "--no-ui-cache") {
            o.ui_cache = false;
        } else if (a == "--sync-timing") {
            o.sync_timing = true;
        } else if (a == "--headless") {
            o.headless = true;
        } else if (const int taken = sffd::cli::parse_stream_option("view", args, i, stream); taken != 0) {
            if (taken < 0) return 2;
        } else if (!a.empty() && a[0] == '-') {
            return sffd::cli::usage_error("view", "unknown option '" + a + "'", kUsage);
        } else if (!have_scene) {
            o.scene = a;
            have_scene = true;
        } else {
            std::fprintf(stderr, "splatffd view: more than one scene given ('%s')\n", a.c_str());
            return 2;
        }
    }
    // Refused rather than run silently: a headless session takes input only from a replay, so without
    // --frames or --replay it would run forever with nothing to see; it has no window to capture.
    if (o.headless && o.frames == 0 && o.replay.empty())
        return sffd::cli::usage_error("view",
                                      "--headless needs --frames N or --replay FILE (it has no window to "
                                      "close, so it would run until interrupted)",
                                      "");
    if (o.headless && !o.window_screenshot.empty())
        return sffd::cli::usage_error("view",
                                      "--window-screenshot captures the window, and --headless has none; use "
                                      "--out PATH for the rendered frame",
                                      "");
    o.prepare = [stream](sffd::ecs::Registry& r) { sffd::cli::apply_stream_options(r, stream); };
    return sffd::editor::run_view(o, sffd::make_engine_schedule({.present = true, .editor = true}));
}

}  // namespace

SFFD_COMMAND(view, "open the interactive editor on a scene", run_view_command);
