// `splatffd view [SCENE]`: the editor window. Opens a GLFW window through the foundation's context
// (runtime/gfx/context.h), loads the scene (runtime/assets/scene.h), and runs the engine's standard
// Schedule (tools/splatffd/engine.h; the editor input system is its input-phase line) plus the editor's
// own systems: lattice overlay and request handling (save, screenshot, quit) in the rendering phase, and
// in the present phase blit -> ImGui panels -> swap.
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

namespace sffd::editor {

struct ViewOptions {
    std::string scene = "sphere";
    std::string replay;       // input recording to play
    std::string record;       // write the session's input here at exit
    std::uint64_t frames = 0; // > 0: exit after this many frames
    std::string screenshot;   // write the last frame here at exit (.png / .exr)
    std::string save_path;    // ctrl+s target (default: the scene file if it is .glb/.gltf, else <scene>.glb)
    int width = 1280;
    int height = 720;
    bool headless = false;
    bool ui = true;           // ImGui panels (window only)
    bool preview = false;     // render quality preview instead of hq
    std::string timing_json;  // write frame-time statistics (all frames / frames with a tool drag) here
    std::string window_screenshot;  // with --frames: the whole window (panels included) of the last frame, PNG
};

// Runs the editor on `schedule` (the engine's standard frame built without its present systems, see
// tools/splatffd/cmd_view.cpp); the editor adds its rendering- and present-phase systems. Returns the
// process exit code (0 ok, 1 bad input or failure, with a message naming the problem).
int run_view(const ViewOptions& options, Schedule schedule);

}  // namespace sffd::editor
