// Splat render system: the frame's pass order, the window display copy and frame capture. See
// splat_render.h for the data flow; the passes live in the sources named in splat_render_detail.h.
#include "systems/splat_render/splat_render.h"

#include "systems/splat_render/splat_render_detail.h"

namespace sffd::render {

using namespace detail;

void render_system(ecs::Registry& reg, const FrameContext& frame) {
    SplatRenderState& s = render_state(reg);
    if (s.failed) return;
    if (!reg.try_resource<RenderSettings>()) reg.set_resource<RenderSettings>();
    if (!reg.try_resource<RenderStats>()) reg.set_resource<RenderStats>();
    RenderStats& stats = reg.resource<RenderStats>();
    stats = RenderStats{};
    stats.frame = frame.frame;

    s.cpu_splat_passes = 0;
    FramePlan plan;
    plan.settings = reg.resource<RenderSettings>();
    PassLaps laps(plan.settings.time_passes);
    const int full_width = std::max(plan.settings.width, 1), full_height = std::max(plan.settings.height, 1);
    ensure_targets(s, full_width, full_height);
    // A reduced preview renders into the targets' lower-left corner with the full frame's projection (the
    // aspect of the full size): scaling x and y back up by their own ratios undoes the viewport's squeeze.
    const int divider =
        plan.settings.quality == Quality::preview ? std::clamp(plan.settings.preview_divider, 1, 8) : 1;
    plan.width = std::max(full_width / divider, 1), plan.height = std::max(full_height / divider, 1);
    plan.settings.width = plan.width, plan.settings.height = plan.height;
    s.frame_width = plan.width, s.frame_height = plan.height;
    auto* store = reg.try_resource<gfx::GpuSplatStore>();  // null: residency_system has not run
    s.cull_over_limit = false;
    reg.view<const SplatCloud>().each(
        [&](const SplatCloud& c) { s.cull_over_limit |= !compute_cull_fits(c.size()).ok(); });
    // The CPU cull also takes a cloud over the limit on a forced compute cull (it falls back).
    sync_clouds(reg, s, store, cpu_cull_wanted(s, plan.settings.cull_path) || s.cull_over_limit,
                plan.settings);
    plan.view = choose_camera(reg, s, double(full_width) / double(full_height));
    plan.common = frame_block(reg, plan.settings, plan.view, s.max_point_size);
    plan.cpu_raster = plan.settings.sprite_path == SpritePath::cpu ||
                      (plan.settings.sprite_path == SpritePath::automatic && s.software);

    cull_pass(reg, s, plan, stats);
    const bool materials = plan.settings.quality == Quality::hq && clouds_differ_in_material(plan);
    plan_compute_raster(s, plan, materials, stats);
    if (!plan.compute.empty()) {  // the compute rasteriser's HQ visibility pass covers the sprites
        plan.cpu_raster = false;
        for (CloudGpu* gpu : plan.drawn) gpu->cpu_raster = false;
    }
    plan.cpu_hq =
        plan.settings.quality == Quality::hq && plan.cpu_raster && !materials && !plan.drawn.empty() &&
        std::all_of(plan.drawn.begin(), plan.drawn.end(),
                    [](const CloudGpu* gpu) { return gpu->cpu_raster && gpu->cpu_cull.visible_quads == 0; });
    stats.cpu_attribute = plan.cpu_hq;
    upload_gl_sprites(plan);
    // The counts ring's copies follow the passes that write the counts (cull; compute visibility).
    if (plan.compute.empty()) issue_counts(s, plan.gpu_counts, plan.cpu_points, plan.cpu_quads, stats.frame);
    laps.lap(stats.cull_ms);
    begin_splat_passes(s, plan);
    if (plan.settings.quality == Quality::preview) {
        preview_pass(reg, s, plan, stats);
        laps.lap(stats.preview_ms);
    } else {
        warm_preview_programs(s, plan);
        const glm::ivec4 rect =
            intersect_rects(screen_rect(reg, plan.view, plan.width, plan.height), plan_drawn_rect(plan));
        visibility_pass(reg, s, plan, rect, stats);
        if (!plan.compute.empty())
            issue_counts(s, plan.gpu_counts, plan.cpu_points, plan.cpu_quads, stats.frame);
        laps.lap(stats.visibility_ms);
        attribute_pass(reg, s, plan, rect, materials);
        laps.lap(stats.attribute_ms);
        shade_pass(reg, s, plan, materials);
        laps.lap(stats.shade_ms);
    }
    end_splat_passes();
    s.drawn = plan_drawn_rect(plan);
    // 3D Gaussians over the surface splats, depth-tested against them (gaussian_pass.h).
    if (reg.count<GaussianCloud>() > 0) {
        s.drawn = glm::ivec4(0, 0, plan.width, plan.height);
        GaussianPassFrame gf;
        gf.camera = plan.view.camera, gf.view = plan.view.view, gf.projection = plan.view.projection;
        gf.output_fbo = s.output_fbo.id(), gf.color = s.color.id(), gf.aux = s.aux.id(),
        gf.depth = s.depth.id();
        gf.width = plan.width, gf.height = plan.height, gf.aux_outputs = plan.settings.aux_outputs;
        gf.target_width = full_width, gf.target_height = full_height;
        gf.preview = plan.settings.quality == Quality::preview;
        gf.show_selection = plan.settings.show_selection, gf.show_weights = plan.settings.show_weights;
        auto drawn = gaussian_pass(reg, gf);
        if (!drawn) {
            if (drawn.message() != s.gaussian_refusal) log::error("render_system(): ", drawn.message());
            s.gaussian_refusal = drawn.message();
        } else {
            stats.gaussians = *drawn;
            s.gaussian_refusal.clear();
        }
        laps.lap(stats.gaussian_ms);
    }
    // Visible counts of the newest frame whose read-back has landed (with time_passes: this frame, the
    // glFinish of the laps has completed it; otherwise usually a frame or two back). Never waits.
    collect_counts(s);
    stats.counts_frame = s.counts_frame;
    stats.counts_valid = s.counts_serial != 0;
    stats.visible_points = s.counts_points;
    stats.visible_quads = s.counts_quads;
    stats.raster_sprites = s.counts_raster_sprites;
    stats.cpu_splat_passes = s.cpu_splat_passes;
    s.last_background = plan.common.background;
    if (plan.settings.time_passes) stats.total_ms = laps.total_ms();
}

glm::ivec4 display_viewport_pixels(const DisplayViewport& v, int width, int height) {
    if (!(v.window_width > 0.0f) || !(v.window_height > 0.0f)) return {0, 0, width, height};
    const double sx = width / double(v.window_width), sy = height / double(v.window_height);
    auto clamp_to = [](double value, int lo, int hi) {
        return value <= lo ? lo : value >= hi ? hi : int(value);  // NaN: lo
    };
    const double x = v.x, y = v.y, w = v.width, h = v.height;
    const int x0 = clamp_to(std::floor(x * sx), 0, width);
    const int x1 = clamp_to(std::ceil((x + w) * sx), x0, width);
    const int y1 = clamp_to(height - std::floor(y * sy), 0, height);  // GL rows count from the bottom
    const int y0 = clamp_to(height - std::ceil((y + h) * sy), 0, y1);
    return {x0, y0, x1 - x0, y1 - y0};
}

void display_system(ecs::Registry& reg, const FrameContext&) {
    SplatRenderState* s = reg.try_resource<SplatRenderState>();
    if (!s || s->failed || !s->output_fbo) return;
    // Only a window shows the frame (headless runs capture the linear target).
    const auto* app_ctx = reg.try_resource<app::AppContext>();
    if (!app_ctx || !app_ctx->context || app_ctx->context->is_headless()) return;
    const int w = s->width, h = s->height;
    // Straight into the window's back buffer when it has the frame's size: no second full-size copy (the
    // blit) after this one. A window of another size (resized since the targets were made) gets the
    // encoded image in a texture that present_blit_system scales.
    const gfx::FramebufferSize window = app_ctx->context->framebuffer_size();
    const bool direct = window.width == w && window.height == h;
    if (!direct && (!s->display_fbo || s->display_width != w || s->display_height != h)) {
        s->display_color = make_target(GL_RGBA8, w, h, "render.display");
        s->display_fbo = gfx::Framebuffer::create("render.display");
        glNamedFramebufferTexture(s->display_fbo.id(), GL_COLOR_ATTACHMENT0, s->display_color.id(), 0);
        s->display_width = w, s->display_height = h;
    }
    if (!s->display_ubo) {
        s->display_ubo = gfx::Buffer::create("render.display_block");
        glNamedBufferData(s->display_ubo.id(), sizeof(gpu::FrameBlock), nullptr, GL_DYNAMIC_DRAW);
        s->display_background = glm::vec4(-1.0f);  // never a background: the first frame uploads
    }
    if (s->display_background != s->last_background) {
        gpu::FrameBlock b{};
        b.background = s->last_background;
        glNamedBufferSubData(s->display_ubo.id(), 0, sizeof b, &b);
        s->display_background = s->last_background;
    }
    const GLuint target = direct ? 0 : s->display_fbo.id();
    glBindFramebuffer(GL_FRAMEBUFFER, target);
    glViewport(0, 0, w, h);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glDisable(GL_SCISSOR_TEST);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    glBindBufferBase(GL_UNIFORM_BUFFER, SFFD_UBO_FRAME, s->display_ubo.id());
    glBindTextureUnit(SFFD_TEX_ACCUM_COLOR, s->color.id());
    glBindVertexArray(s->vao.id());  // empty: the triangle comes from gl_VertexID
    // Outside the part of the window the frame is seen in, a clear to the background costs a small part
    // of the copy (a CPU rasteriser runs the copy per pixel: the editor's panels cover half the window).
    // Likewise where the frame holds only the background (drawn_pixels(), scaled up as the copy scales).
    glm::ivec4 r(0, 0, w, h);
    if (const auto* dv = reg.try_resource<DisplayViewport>()) r = display_viewport_pixels(*dv, w, h);
    {
        const glm::ivec4 d = s->drawn;
        const double sx = double(w) / double(std::max(s->frame_width, 1)),
                     sy = double(h) / double(std::max(s->frame_height, 1));
        const int x0 = std::max(int(std::floor(d.x * sx)) - 1, 0),
                  y0 = std::max(int(std::floor(d.y * sy)) - 1, 0);
        const int x1 = std::min(int(std::ceil((d.x + d.z) * sx)) + 1, w),
                  y1 = std::min(int(std::ceil((d.y + d.w) * sy)) + 1, h);
        r = intersect_rects(r, glm::ivec4(x0, y0, std::max(x1 - x0, 0), std::max(y1 - y0, 0)));
    }
    if (r != glm::ivec4(0, 0, w, h)) {
        const glm::vec4& bg = s->last_background;
        glClearColor(linear_to_srgb(bg.x), linear_to_srgb(bg.y), linear_to_srgb(bg.z), 1.0f);
        glClear(GL_COLOR_BUFFER_BIT);
        glEnable(GL_SCISSOR_TEST);
        glScissor(r.x, r.y, r.z, r.w);
    }
    glUseProgram(s->display.id());
    glUniform2f(SFFD_LOC_DISPLAY_SCALE, float(s->frame_width) / float(w), float(s->frame_height) / float(h));
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDisable(GL_SCISSOR_TEST);
    glEnable(GL_DEPTH_TEST);
    glBindVertexArray(0);
    glUseProgram(0);
    auto& present = reg.try_resource<app::PresentSource>() ? reg.resource<app::PresentSource>()
                                                           : reg.set_resource<app::PresentSource>();
    present = direct ? app::PresentSource{.in_window = true}
                     : app::PresentSource{s->display_fbo.id(), GL_COLOR_ATTACHMENT0, w, h};
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

namespace {

// Reads `texture` (the targets' size) into a top-down image of that size, scaling the last frame's
// rectangle up as the display copy does (display.frag: nearest).
std::vector<glm::vec4> read_frame(const SplatRenderState& s, GLuint texture) {
    const int w = s.width, h = s.height;
    std::vector<glm::vec4> raw(std::size_t(w) * std::size_t(h)), out(raw.size());
    glGetTextureImage(texture, 0, GL_RGBA, GL_FLOAT, GLsizei(raw.size() * sizeof(glm::vec4)), raw.data());
    const float sx = float(s.frame_width) / float(w), sy = float(s.frame_height) / float(h);
    for (int y = 0; y < h; ++y) {  // GL rows are bottom-up, images top-down
        const int gl_y = h - 1 - y;
        const int src_y = std::min(int((float(gl_y) + 0.5f) * sy), h - 1);
        for (int x = 0; x < w; ++x) {
            const int src_x = std::min(int((float(x) + 0.5f) * sx), w - 1);
            out[std::size_t(y) * std::size_t(w) + std::size_t(x)] =
                raw[std::size_t(src_y) * std::size_t(w) + std::size_t(src_x)];
        }
    }
    return out;
}

}  // namespace

Result<std::vector<glm::vec4>> capture_output_color(ecs::Registry& registry) {
    const SplatRenderState* s = registry.try_resource<SplatRenderState>();
    if (!s || s->failed || !s->output_fbo) return make_error("capture_output_color(): nothing rendered yet");
    return read_frame(*s, s->color.id());
}

Result<FrameImage> capture_frame(ecs::Registry& registry) {
    const SplatRenderState* s = registry.try_resource<SplatRenderState>();
    if (!s || s->failed || !s->output_fbo) return make_error("capture_frame(): nothing rendered yet");
    const int w = s->width, h = s->height;
    const std::size_t n = std::size_t(w) * std::size_t(h);
    const std::vector<glm::vec4> color = read_frame(*s, s->color.id());
    const std::vector<glm::vec4> aux = s->aux_valid ? read_frame(*s, s->aux.id()) : std::vector<glm::vec4>(n);
    FrameImage img;
    img.width = w, img.height = h;
    img.color.resize(n), img.depth.resize(n), img.normal.resize(n);
    for (int y = 0; y < h; ++y) {
        const std::size_t row = std::size_t(y) * std::size_t(w);
        for (int x = 0; x < w; ++x) {
            const glm::vec4& c = color[row + std::size_t(x)];
            const glm::vec4& a = aux[row + std::size_t(x)];
            const bool hit = c.w > 0.0f && (!s->aux_valid || a.w >= 0.0f);
            img.color[row + std::size_t(x)] = hit ? c : glm::vec4(0.0f);
            img.depth[row + std::size_t(x)] =
                hit && s->aux_valid ? a.w : std::numeric_limits<float>::infinity();
            img.normal[row + std::size_t(x)] = hit && s->aux_valid ? glm::vec3(a) : glm::vec3(0.0f);
        }
    }
    return img;
}

GLuint output_framebuffer(const ecs::Registry& registry) {
    const SplatRenderState* s = registry.try_resource<SplatRenderState>();
    return s ? s->output_fbo.id() : 0;
}

glm::ivec2 output_frame_size(const ecs::Registry& registry) {
    const SplatRenderState* s = registry.try_resource<SplatRenderState>();
    return s ? glm::ivec2(s->frame_width, s->frame_height) : glm::ivec2(0);
}

glm::ivec4 drawn_pixels(const ecs::Registry& registry) {
    const SplatRenderState* s = registry.try_resource<SplatRenderState>();
    return s ? s->drawn : glm::ivec4(0);
}

void include_drawn_pixels(ecs::Registry& registry, const glm::ivec4& pixels) {
    SplatRenderState* s = registry.try_resource<SplatRenderState>();
    if (!s || pixels.z <= 0 || pixels.w <= 0) return;
    const glm::ivec4 d = s->drawn;
    if (d.z <= 0 || d.w <= 0) {
        s->drawn = intersect_rects(pixels, glm::ivec4(0, 0, s->frame_width, s->frame_height));
        return;
    }
    const int x0 = std::min(d.x, pixels.x), y0 = std::min(d.y, pixels.y);
    const int x1 = std::max(d.x + d.z, pixels.x + pixels.z), y1 = std::max(d.y + d.w, pixels.y + pixels.w);
    s->drawn = intersect_rects(glm::ivec4(x0, y0, x1 - x0, y1 - y0),
                               glm::ivec4(0, 0, s->frame_width, s->frame_height));
}

}  // namespace sffd::render
