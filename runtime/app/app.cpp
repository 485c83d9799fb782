#include "runtime/app/app.h"

#include <chrono>

#include "runtime/gfx/context.h"

namespace sffd::app {

Clock make_clock(const gfx::GlContext* context, double fixed_dt) {
    const bool window = context && !context->is_headless();
    ClockSettings settings;
    if (!window) settings.fixed_dt = fixed_dt > 0.0 ? fixed_dt : 1.0 / 60.0;
    return Clock(settings);
}

RunResult run(ecs::Registry& registry, const Schedule& schedule, Clock& clock, gfx::GlContext* context,
              const RunOptions& options) {
    AppContext& app = registry.try_resource<AppContext>() ? registry.resource<AppContext>()
                                                          : registry.set_resource<AppContext>();
    app.context = context;
    app.quit_requested = false;
    RunResult result;
    const auto start = std::chrono::steady_clock::now();
    while (options.max_frames == 0 || result.frames < options.max_frames) {
        if (context) {
            context->poll_events();
            if (context->should_close()) {
                result.closed = true;
                break;
            }
        }
        if (app.quit_requested) {
            result.closed = true;
            break;
        }
        schedule.run_frame(registry, clock.tick());
        ++result.frames;
    }
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

namespace {
gfx::GlContext* window_context(ecs::Registry& registry) {
    const AppContext* app = registry.try_resource<AppContext>();
    return app && app->context && !app->context->is_headless() ? app->context : nullptr;
}
}  // namespace

void present_blit_system(ecs::Registry& registry, const FrameContext& /*frame*/) {
    gfx::GlContext* context = window_context(registry);
    if (!context) return;
    const gfx::FramebufferSize size = context->framebuffer_size();
    const PresentSource* source = registry.try_resource<PresentSource>();
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, size.width, size.height);
    if (!source || source->in_window || source->framebuffer == 0 || size.width <= 0 || size.height <= 0)
        return;
    glNamedFramebufferReadBuffer(source->framebuffer, source->read_buffer);
    const bool same = source->width == size.width && source->height == size.height;
    glBlitNamedFramebuffer(source->framebuffer, 0, 0, 0, source->width, source->height, 0, 0, size.width,
                           size.height, GL_COLOR_BUFFER_BIT, same ? GL_NEAREST : GL_LINEAR);
}

void present_swap_system(ecs::Registry& registry, const FrameContext& /*frame*/) {
    if (gfx::GlContext* context = window_context(registry)) context->swap_buffers();
}

}  // namespace sffd::app
