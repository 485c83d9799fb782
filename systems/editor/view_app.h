// `splatffd view [SCENE]`: the editor window. Opens a GLFW window through the foundation's context
// (runtime/gfx/context.h), loads the scene (runtime/assets/scene.h), and runs the engine's standard
// Schedule with the editor's systems (systems/engine/engine.cpp lists them: input system; lattice overlay
// and request handling (save, screenshot, quit) in the rendering phase; in the present phase display copy
// -> blit -> ImGui panels -> swap).
//
// Deterministic runs for tests and demos: `--replay FILE` feeds a recorded input file (input_record.h)
// frame by frame on a fixed 1/60 s clock, `--frames N` exits after N frames, `--screenshot PATH` writes
// the last frame (PNG or EXR by extension; scene and lattice overlay, no panels), `--save PATH` is
// where ctrl+s saves. `--headless` runs the same thing without a window (EGL, no panels).
#pragma once

#include <cstdint>
#include <functional>
#include <string>

#include "runtime/app/frame_loop.h"
#include "runtime/assets/scene.h"
#include "runtime/ecs/registry.h"

namespace sffd::editor {

struct ViewOptions {
    std::string scene = "sphere";
    std::string replay;        // input recording to play
    std::string record;        // write the session's input here at exit
    std::uint64_t frames = 0;  // > 0: exit after this many frames
    std::string screenshot;    // write the last frame here at exit (.png / .exr)
    std::string save_path;  // ctrl+s target (default: the scene file if it is .glb/.gltf, else <scene>.glb)
    int width = 1280;
    int height = 720;
    bool headless = false;
    bool ui = true;             // ImGui panels (window only)
    bool overlay_cache = true;  // the lattice overlay's cache of unchanged x-ray edges (OverlayOptions)
    bool ui_cache = true;       // unchanged panels copied from an image (ui_cache.h, UiCacheOptions)
    bool preview = false;       // render quality preview instead of hq
    // Who rasterises the sprites of CPU-culled clouds (render::SpritePath): "auto", "raster" (GL point
    // sprites) or "cpu".
    std::string sprite_raster = "auto";
    std::string timing_json;   // write frame-time statistics (all frames / frames with a tool drag) here
    bool sync_timing = false;  // glFinish after every system: each system's time includes its own GL work
    std::string
        window_screenshot;         // with --frames: the whole window (panels included) of the last frame, PNG
    std::string panel_rects_json;  // with --frames: the panels' rectangles in the last frame (panels.h), JSON
    // What the editor's registries open and save (runtime/assets/scene.h): the editor cannot link the
    // engine, so the command passes its hooks (systems/engine: engine_scene_hooks()). The scene's registry
    // gets them as its SceneHooks resource; a registry the editor makes later copies them from it.
    SceneHooks scene_hooks;
    // Runs on the scene's registry before the scene loads: resources its loaders read (the command's
    // streaming settings for level-of-detail hierarchies).
    std::function<void(ecs::Registry&)> prepare;
};

// $XDG_CONFIG_HOME/splatffd/<name> (else ~/.config/splatffd/<name>), its folder created; empty when
// neither variable is set or the folder cannot be made (then nothing is remembered).
std::string user_config_file(const std::string& name);

// Runs the editor on `schedule`: the engine's standard frame with the editor's systems
// (make_engine_schedule({.editor = true}), systems/engine/engine.cpp lists them). Returns the process exit
// code (0 ok, 1 bad input or failure, with a message naming the problem).
int run_view(const ViewOptions& options, Schedule schedule);

// The editor's own systems besides the input system (editor_system.h) and the overlay (lattice_overlay.h),
// listed in the engine's schedule. Both do nothing outside run_view (no view session resource).
// Rendering phase, after the overlay: save / screenshot / quit requests, present source, drag log.
void requests_system(ecs::Registry& registry, const FrameContext& frame);
// Present phase, between the blit and the swap: the ImGui panels (window with panels only).
void ui_system(ecs::Registry& registry, const FrameContext& frame);

}  // namespace sffd::editor
