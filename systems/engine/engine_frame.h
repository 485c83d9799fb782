// One frame of a schedule, headless, read back: what `splatffd render` does for each frame, as a function,
// so tests and tools reach the engine's frame through this library instead of through the command.
//
//   auto ctx = gfx::create_context({.headless = true, .width = w, .height = h});
//   ecs::Registry registry;                   // load_scene(registry, ...), RenderSettings{w, h, ...}
//   const Schedule schedule = make_engine_schedule({.present = false});
//   auto image = render_engine_frame(registry, schedule, *ctx, {.frame = 3});
//   render::release_render_state(registry);  // while the context is current
#pragma once

#include <cstdint>

#include "runtime/app/frame_loop.h"
#include "runtime/core/result.h"
#include "runtime/ecs/registry.h"
#include "systems/splat_render/image_io.h"

namespace sffd::gfx {
class GlContext;
}

namespace sffd {

struct SceneHooks;  // runtime/assets/scene.h

// The scene-file hooks of the systems that keep data in scene files (animation clips, Gaussian files and
// entities: runtime/assets/scene.h SceneHooks), as one value.
SceneHooks engine_scene_hooks();
// Makes them the registry's own (a SceneHooks resource, its context), so load_scene(registry, ...) and
// save_scene(registry, ...) open and write what the command does. Every registry that loads or saves a
// scene is given its hooks this way (or copies them from the registry it came from: SceneHooks::copy_to);
// there is no process-wide set to fall back on.
void use_engine_scene_hooks(ecs::Registry& registry);

struct EngineFrameOptions {
    std::uint64_t frame = 0;  // frame k runs at time k / fps and depends on k only (not on earlier frames)
    double fps = 60.0;
};

// Runs frame `options.frame` of `schedule` on `registry` in `context` (current) and reads it back
// (render::capture_frame). Sets app::AppContext when the registry has none; the render state is made by
// render_system on first use (call render::init_render_state() first to get shader errors as a Status).
Result<render::FrameImage> render_engine_frame(ecs::Registry& registry, const Schedule& schedule,
                                               gfx::GlContext& context,
                                               const EngineFrameOptions& options = {});

}  // namespace sffd
