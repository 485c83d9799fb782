// Render system's Gaussian pass. See gaussian_pass.h for the data flow.
#include "systems/splat_render/gaussian_pass.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "runtime/app/pass_timer.h"
#include "runtime/ecs/signal.h"
#include "runtime/gfx/gl_object.h"
#include "runtime/gfx/shader.h"
#include "runtime/scene/camera.h"
#include "systems/splat_render/gaussian_draw.h"
#include "systems/gaussian/gpu_store.h"

namespace sffd::render {

namespace {}  // namespace

// A Gaussian cloud's bounds cached for the framing camera: a component on the cloud entity, removed with
// its GaussianCloud (GaussianPassState::cloud_gone).
struct GaussianBoundsCache {
    BoundingSphere bounds;
    std::uint64_t bounds_version = 0;
    std::uint64_t flags_version = 0;  // registry.version<PointFlags>: gone Gaussians are left out
};

// Registry resource: the pass's GL objects (the clouds themselves live in GpuGaussianStore).
struct GaussianPassState {
    GlRenderer renderer;        // projection program, per-draw scratch buffers, the quad VAO
    gfx::Program accum;         // shaders/splat_render/gaussian/splat.vert + accum.frag
    gfx::Program accum_colour;  // the same without the depth sum (frames without aux outputs)
    gfx::Program composite;     // fullscreen + splat_render/gaussian/composite.frag
    gfx::VertexArray empty_vao;
    int width = 0, height = 0;
    gfx::Texture gauss_color, gauss_depth, surface_color, surface_aux;
    gfx::Framebuffer accum_fbo;
    GLuint depth_attached = 0;         // the render system's depth texture attached to accum_fbo
    ecs::ScopedConnection cloud_gone;  // removes a GaussianBoundsCache with its GaussianCloud
    std::uint32_t quad_clouds = 0, tile_clouds = 0;  // last frame, GaussianPassStats
    std::uint64_t covered_pixels = 0;
    bool failed = false;
};

namespace {

gfx::Texture make_texture(GLenum format, int w, int h, const char* label) {
    gfx::Texture t = gfx::Texture::create(label, GL_TEXTURE_2D);
    glTextureStorage2D(t.id(), 1, format, w, h);
    glTextureParameteri(t.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    return t;
}

Result<GaussianPassState*> pass_state(ecs::Registry& reg) {
    if (auto* s = reg.try_resource<GaussianPassState>()) {
        if (s->failed) return make_error("gaussian pass: initialisation failed earlier");
        return s;
    }
    GaussianPassState s;
    auto fail = [&](const std::string& message) -> Result<GaussianPassState*> {
        GaussianPassState failed;
        failed.failed = true;
        reg.set_resource<GaussianPassState>(std::move(failed));
        return make_error(message);
    };
    auto renderer = create_gl_renderer();
    if (!renderer) return fail(renderer.message());
    s.renderer = std::move(*renderer);
    auto accum = gfx::load_program({{GL_VERTEX_SHADER, "splat_render/gaussian/splat.vert"},
                                    {GL_FRAGMENT_SHADER, "splat_render/gaussian/accum.frag"}},
                                   "render.gaussian_accum");
    if (!accum) return fail(accum.message());
    auto accum_colour = gfx::load_program({{GL_VERTEX_SHADER, "splat_render/gaussian/splat.vert"},
                                           {GL_FRAGMENT_SHADER, "splat_render/gaussian/accum.frag"}},
                                          "render.gaussian_accum_colour", {{"SFFD_GAUSS_COLOUR_ONLY", ""}});
    if (!accum_colour) return fail(accum_colour.message());
    auto composite = gfx::load_program({{GL_VERTEX_SHADER, "splat_render/fullscreen.vert"},
                                        {GL_FRAGMENT_SHADER, "splat_render/gaussian/composite.frag"}},
                                       "render.gaussian_composite");
    if (!composite) return fail(composite.message());
    s.accum = std::move(*accum);
    s.accum_colour = std::move(*accum_colour);
    s.composite = std::move(*composite);
    s.empty_vao = gfx::VertexArray::create("render.gaussian_composite");
    s.cloud_gone = reg.on_destroy<GaussianCloud>().connect(
        [](ecs::Registry& r, ecs::Entity e) { r.remove<GaussianBoundsCache>(e); });
    return &reg.set_resource<GaussianPassState>(std::move(s));
}

void ensure_targets(GaussianPassState& s, const GaussianPassFrame& f) {
    const int w = std::max(f.target_width, f.width), h = std::max(f.target_height, f.height);
    if (s.width != w || s.height != h || !s.accum_fbo) {
        s.width = w, s.height = h;
        s.gauss_color = make_texture(GL_RGBA32F, w, h, "render.gaussian_color");
        s.gauss_depth = make_texture(GL_RGBA32F, w, h, "render.gaussian_depth");
        s.surface_color = make_texture(GL_RGBA16F, w, h, "render.surface_color_copy");
        s.surface_aux = make_texture(GL_RGBA32F, w, h, "render.surface_aux_copy");
        s.accum_fbo = gfx::Framebuffer::create("render.gaussian_accum");
        glNamedFramebufferTexture(s.accum_fbo.id(), GL_COLOR_ATTACHMENT0, s.gauss_color.id(), 0);
        glNamedFramebufferTexture(s.accum_fbo.id(), GL_COLOR_ATTACHMENT1, s.gauss_depth.id(), 0);
        // Its draw buffers are set each frame (gaussian_pass: the depth sum only with aux outputs).
        s.depth_attached = 0;
    }
    if (s.depth_attached != f.depth) {  // the render system recreates its targets on a resize
        glNamedFramebufferTexture(s.accum_fbo.id(), GL_DEPTH_ATTACHMENT, f.depth, 0);
        s.depth_attached = f.depth;
    }
}

}  // namespace

BoundingSphere gaussian_bounding_sphere(const GaussianCloud& cloud, const PointFlags* flags) {
    BoundingSphere b;
    if (cloud.size() == 0) return b;
    if (flags && flags->bits.size() != cloud.size()) flags = nullptr;  // of another size: none is gone
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    double max_scale = 0.0;
    bool any = false;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        if (flags && (flags->bits[i] & kPointGone)) continue;
        any = true;
        lo = glm::min(lo, glm::dvec3(cloud.positions[i]));
        hi = glm::max(hi, glm::dvec3(cloud.positions[i]));
        const glm::vec3 s = cloud.scales[i];
        max_scale = std::max(max_scale, double(std::max({s.x, s.y, s.z})));
    }
    if (!any) return b;
    b.center = 0.5 * (lo + hi);
    double r = 0.0;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (!flags || !(flags->bits[i] & kPointGone))
            r = std::max(r, glm::length(glm::dvec3(cloud.positions[i]) - b.center));
    b.max_splat_radius = 3.0 * max_scale;
    b.radius = r + b.max_splat_radius;
    return b;
}

BoundingSphere cached_gaussian_bounds(ecs::Registry& reg, ecs::Entity e) {
    const GaussianCloud* cloud = reg.try_get<GaussianCloud>(e);
    if (!cloud) return {glm::dvec3(0.0), -1.0, 0.0};
    // Cached only while the pass exists (its signal removes the cache with the cloud).
    const PointFlags* flags = std::as_const(reg).try_get<PointFlags>(e);
    if (!reg.try_resource<GaussianPassState>()) return gaussian_bounding_sphere(*cloud, flags);
    const std::uint64_t version = reg.version<GaussianCloud>(e);
    const std::uint64_t flags_version = std::as_const(reg).version<PointFlags>(e);
    if (const GaussianBoundsCache* c = std::as_const(reg).try_get<GaussianBoundsCache>(e);
        c && c->bounds_version == version && c->flags_version == flags_version)
        return c->bounds;
    GaussianBoundsCache* c = reg.try_get<GaussianBoundsCache>(e);
    if (!c) c = &reg.emplace<GaussianBoundsCache>(e);
    c->bounds = gaussian_bounding_sphere(*cloud, flags);
    c->bounds_version = version;
    c->flags_version = flags_version;
    return c->bounds;
}

Result<std::uint32_t> gaussian_pass(ecs::Registry& reg, const GaussianPassFrame& f) {
    if (reg.count<GaussianCloud>() == 0) return std::uint32_t(0);
    auto state = pass_state(reg);
    if (!state) return state.error();
    GaussianPassState& s = **state;
    // residency_system keeps the clouds resident; without it (no residency phase ran) nothing is drawn.
    const auto* store = reg.try_resource<gaussian::GpuGaussianStore>();
    if (!store) return std::uint32_t(0);
    ensure_targets(s, f);

    // Clouds nearest first (front-to-back blending), by the view depth of their bounding sphere's centre.
    struct Item {
        ecs::Entity entity;
        double depth;
    };
    std::vector<Item> items;
    reg.view<const GaussianCloud>().each([&](ecs::Entity e, const GaussianCloud& cloud) {
        if (cloud.size() == 0 || !store->clouds.contains(e)) return;
        const BoundingSphere b = cached_gaussian_bounds(reg, e);
        const glm::dmat4 m = model_matrix(reg.try_get<Transform>(e), cloud.origin);
        const glm::dvec4 c = f.view * m * glm::dvec4(b.center, 1.0);
        items.push_back({e, -c.z});
    });
    std::stable_sort(items.begin(), items.end(),
                     [](const Item& a, const Item& b) { return a.depth < b.depth; });

    auto scope = profiling::gpu_scope(reg, "render.gaussians");
    const float zero[4] = {0, 0, 0, 0};
    // Only the frame's pixels (a reduced preview's corner), as begin_splat_passes clears.
    glEnable(GL_SCISSOR_TEST);
    glScissor(0, 0, f.width, f.height);
    // The depth sum feeds only the aux output: without one, a Gaussian fragment blends into one target, not
    // two (on a CPU rasteriser the blending is most of the pass; measured below).
    const GLenum with_depth[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1},
                 colour_only[2] = {GL_COLOR_ATTACHMENT0, GL_NONE};
    glNamedFramebufferDrawBuffers(s.accum_fbo.id(), 2, f.aux_outputs ? with_depth : colour_only);
    glClearNamedFramebufferfv(s.accum_fbo.id(), GL_COLOR, 0, zero);
    if (f.aux_outputs) glClearNamedFramebufferfv(s.accum_fbo.id(), GL_COLOR, 1, zero);
    glDisable(GL_SCISSOR_TEST);
    glBindFramebuffer(GL_FRAMEBUFFER, s.accum_fbo.id());
    glViewport(0, 0, f.width, f.height);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_FALSE);  // test against the surface splats, never write: Gaussians are blended
    // NDC depth z = -P22 + P32 / depth of a perspective projection (glm::perspective, NDC z in [-1, 1]).
    const glm::dvec2 ndc_depth(-f.projection[2][2], f.projection[3][2]);
    std::uint32_t submitted = 0;
    Status status;
    s.quad_clouds = s.tile_clouds = 0;
    s.covered_pixels = 0;
    reset_tile_stats(s.renderer);
    // A cloud that covers too much of the image for quads (gl_render.h: quad_coverage_budget) goes to the
    // tile renderer, into the same targets with the same depth test.
    TileTargets tiles;
    tiles.color = s.gauss_color.id(), tiles.surface_depth = f.depth;
    tiles.depth_sum = f.aux_outputs ? s.gauss_depth.id() : 0;
    for (const Item& item : items) {
        const GaussianCloud& cloud = reg.get<GaussianCloud>(item.entity);
        const gaussian::GpuGaussians& gpu = store->clouds.at(item.entity);
        const glm::dmat4 model = model_matrix(reg.try_get<Transform>(item.entity), cloud.origin);
        GaussianView v;
        v.view = f.view * model;
        v.eye = glm::dvec3(glm::inverse(model) * glm::dvec4(f.camera.eye, 1.0));
        v.fov_y_degrees = double(f.camera.fov_y_degrees);
        v.near_plane = double(f.camera.near_plane);
        v.width = f.width, v.height = f.height;
        v.ndc_depth = ndc_depth;
        v.min_footprint_px = f.preview ? kPreviewMinFootprintPx : 0.0f;
        GaussianBuffers buffers = gaussian_buffers(gpu);
        if (f.show_selection && (buffers.marks_mode & SFFD_MARKS_PRESENT) && gpu.marks_state.any_selected())
            buffers.marks_mode |= SFFD_MARKS_SELECTION;
        if (f.show_weights) buffers.marks_mode |= SFFD_MARKS_WEIGHTS;
        if (Status st =
                draw_gaussians(s.renderer, buffers, v, f.aux_outputs ? &s.accum : &s.accum_colour, &tiles);
            !st)
            status = st;
        (s.renderer.last_blend == BlendPath::tiles ? s.tile_clouds : s.quad_clouds) += 1;
        constexpr std::uint64_t kMax = std::numeric_limits<std::uint64_t>::max();  // "past 2^32" stays so
        s.covered_pixels += std::min(s.renderer.covered_pixels, kMax - s.covered_pixels);
        submitted += gpu.drawn_count();
    }
    glDepthMask(GL_TRUE);
    glDisable(GL_DEPTH_TEST);

    // Composite over the surface colour (and aux) copied aside: the output target is written.
    glCopyImageSubData(f.color, GL_TEXTURE_2D, 0, 0, 0, 0, s.surface_color.id(), GL_TEXTURE_2D, 0, 0, 0, 0,
                       f.width, f.height, 1);
    if (f.aux_outputs)
        glCopyImageSubData(f.aux, GL_TEXTURE_2D, 0, 0, 0, 0, s.surface_aux.id(), GL_TEXTURE_2D, 0, 0, 0, 0,
                           f.width, f.height, 1);
    glBindFramebuffer(GL_FRAMEBUFFER, f.output_fbo);
    glViewport(0, 0, f.width, f.height);
    glDisable(GL_BLEND);
    glBindTextureUnit(0, s.gauss_color.id());
    glBindTextureUnit(1, s.gauss_depth.id());
    glBindTextureUnit(2, s.surface_color.id());
    glBindTextureUnit(3, s.surface_aux.id());
    glProgramUniform1i(s.composite.id(), glGetUniformLocation(s.composite.id(), "u_aux"),
                       f.aux_outputs ? 1 : 0);
    glUseProgram(s.composite.id());
    glBindVertexArray(s.empty_vao.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBindVertexArray(0);
    glUseProgram(0);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    if (!status) return status.error();
    return submitted;
}

GaussianPassStats gaussian_pass_stats(ecs::Registry& registry) {
    auto* s = registry.try_resource<GaussianPassState>();
    if (!s || s->failed) return {};
    const TileStats t = tile_stats(s->renderer);
    return {s->quad_clouds, s->tile_clouds, s->covered_pixels,
            t.entries,      t.staged,       quad_coverage_budget(s->renderer.software)};
}

Result<GlRenderer*> gaussian_pass_renderer(ecs::Registry& registry) {
    auto state = pass_state(registry);
    if (!state) return state.error();
    return &(*state)->renderer;
}

void release_gaussian_pass(ecs::Registry& registry) {
    std::vector<ecs::Entity> cached;
    registry.view<const GaussianBoundsCache>().each(
        [&](ecs::Entity e, const GaussianBoundsCache&) { cached.push_back(e); });
    for (ecs::Entity e : cached) registry.remove<GaussianBoundsCache>(e);
    registry.erase_resource<GaussianPassState>();
}

}  // namespace sffd::render
