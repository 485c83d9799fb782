#include "systems/engine/engine_frame.h"

#include "runtime/app/app.h"
#include "runtime/assets/scene.h"
#include "runtime/app/clock.h"
#include "systems/animation/scene_extension.h"
#include "systems/gaussian/gaussian_scene.h"
#include "systems/splat_render/splat_render.h"

namespace sffd {

SceneHooks engine_scene_hooks() {
    SceneHooks hooks;
    register_animation_scene_hooks(hooks);
    gaussian::register_gaussian_scene_hooks(
        hooks);  // Gaussian files as entities, Gaussian entities in scenes
    return hooks;
}

void use_engine_scene_hooks(ecs::Registry& registry) {
    registry.set_resource<SceneHooks>(engine_scene_hooks());
}

Result<render::FrameImage> render_engine_frame(ecs::Registry& registry, const Schedule& schedule,
                                               gfx::GlContext& context, const EngineFrameOptions& options) {
    if (!(options.fps > 0.0)) return make_error("render_engine_frame(): fps must be positive");
    if (!registry.try_resource<app::AppContext>())
        registry.set_resource<app::AppContext>(app::AppContext{&context, false});
    // A clock of its own, seeked to the frame: the frame's time is k / fps whatever ran before.
    Clock clock(ClockSettings{.fixed_dt = 1.0 / options.fps});
    clock.seek(double(options.frame) / options.fps);
    FrameContext frame = clock.tick();
    frame.frame = options.frame;
    schedule.run_frame(registry, frame);
    return render::capture_frame(registry);
}

}  // namespace sffd
