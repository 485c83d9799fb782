#include "systems/editor/lattice_overlay.h"

#include "systems/editor/panel_layout.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>

#include <glm/gtc/matrix_transform.hpp>

#include "runtime/core/log.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/gl_object.h"
#include "runtime/gfx/shader.h"
#include "shaders/common/bindings.h"
#include "systems/editor/camera_controller.h"
#include "systems/editor/editor_system.h"
#include "systems/ffd/components.h"
#include "systems/picking/components.h"
#include "systems/picking/world_space.h"
#include "systems/splat_render/splat_render.h"

namespace sffd::editor {

// The edges of a lattice drawn untested at one opacity (x-ray, or the faint hidden edges of a still frame)
// that did not move since they were drawn into `color`: while a few control points are dragged, the frame
// puts the cached edges over the surface in one pass and draws only the moving points' edges. On a CPU
// rasteriser every edge costs its whole length in fragments: the sphere's 3,630 edges took about 4 ms of a
// half-resolution drag frame.
struct OverlayLineCache {
    // What the cached pixels depend on besides the edges themselves.
    struct Key {
        glm::mat4 view_proj{0.0f};
        glm::ivec4 viewport{0}, scissor{0};
        glm::ivec2 target{0};
        float pixel = 0.0f, opacity = 0.0f;
        std::size_t lines = 0;
        bool operator==(const Key&) const = default;
    };
    gfx::Texture color;  // RGBA16F: premultiplied edge colour, coverage
    gfx::Framebuffer framebuffer;
    gfx::Program composite;
    gfx::Buffer indices;  // vertex indices: the cached edges', then the others'
    Key key;
    bool valid = false;                            // `color` holds the edges marked in `cached` under `key`
    std::vector<OverlayVertex> previous;           // last frame's edge vertices
    std::vector<std::uint8_t> cached;              // per edge
    std::vector<std::uint8_t> moved;               // per edge, this frame (kept: no allocation per frame)
    std::size_t cached_count = 0, live_count = 0;  // index counts
    glm::ivec2 size{0};                            // of `color`
    OverlayCacheStats stats;
};

struct LatticeOverlayState {
    gfx::Program program;
    gfx::VertexArray vao;
    gfx::Buffer buffer;
    std::size_t capacity = 0;  // vertices
    bool failed = false;
    OverlayLineCache lines;
};

std::vector<glm::dvec3> proportional_circle(const Camera& camera, const glm::dvec3& centre, double radius,
                                            int segments) {
    const glm::dvec3 forward = glm::normalize(camera.target - camera.eye);
    glm::dvec3 right = glm::cross(forward, camera.up);
    if (glm::length(right) < 1e-12) right = glm::cross(forward, glm::dvec3(1.0, 0.0, 0.0));
    right = glm::normalize(right);
    const glm::dvec3 up = glm::cross(right, forward);
    std::vector<glm::dvec3> out(std::size_t(std::max(segments, 3)));
    for (std::size_t i = 0; i < out.size(); ++i) {
        const double a = 2.0 * 3.14159265358979323846 * double(i) / double(out.size());
        out[i] = centre + radius * (std::cos(a) * right + std::sin(a) * up);
    }
    return out;
}

OverlayGeometry build_lattice_overlay(const ecs::Registry& registry, const EditorState& state,
                                      ecs::Entity entity) {
    OverlayGeometry g;
    const Lattice* lattice = registry.try_get<Lattice>(entity);
    if (!lattice || lattice->current.size() != lattice->size()) return g;
    const glm::dmat4 model = model_matrix(registry.try_get<Transform>(entity));
    g.anchor = glm::dvec3(model * glm::dvec4(lattice->origin, 1.0));
    std::vector<glm::vec3> p(lattice->current.size());
    for (std::size_t c = 0; c < p.size(); ++c)
        p[c] = glm::vec3(glm::dvec3(model * glm::dvec4(lattice->current[c], 1.0)) - g.anchor);

    std::vector<std::uint8_t> selected(p.size(), 0);
    if (const auto* sel = registry.try_get<picking::LatticeSelection>(entity))
        for (std::uint32_t i : sel->indices)
            if (i < selected.size()) selected[i] = 1;
    const bool pins = state.pin_outer_layer && state.scope == ToolScope::local;
    const std::vector<std::uint8_t> outer = outer_layer_mask(*lattice);
    glm::dvec3 lo, hi;
    std::vector<std::uint8_t> inside(p.size(), 0);
    if (scene_bounds(registry, lo, hi)) {
        // The box test is in world space: compare the transformed control points.
        for (std::size_t c = 0; c < p.size(); ++c) {
            const glm::dvec3 w = g.anchor + glm::dvec3(p[c]);
            inside[c] = glm::all(glm::greaterThanEqual(w, lo)) && glm::all(glm::lessThanEqual(w, hi));
        }
    }
    const bool active = entity == state.active_lattice;
    const glm::ivec3 d = lattice->divisions;
    // Cage only: the 12 edges of the lattice's box (points where at least two indices are on a face);
    // selected points are still drawn so the selection stays visible.
    // Point mode draws the cage too: the points being selected are the subject, the lattice only frames
    // them (its x-ray edges would hide them).
    const bool cage_only = state.lattice_cage_only || state.mode == EditMode::points;
    const auto on_cage = [&](int i, int j, int k) {
        return int(i == 0 || i == d.x) + int(j == 0 || j == d.y) + int(k == 0 || k == d.z) >= 2;
    };
    g.points.reserve(p.size());
    for (std::size_t c = 0; c < p.size(); ++c) {
        bool faint = false;  // cage only: a selected point inside the cage, small and translucent
        if (cage_only) {
            const int i = int(c / std::size_t((d.y + 1) * (d.z + 1)));
            const int j = int((c / std::size_t(d.z + 1)) % std::size_t(d.y + 1));
            const int k = int(c % std::size_t(d.z + 1));
            if (!on_cage(i, j, k)) {
                if (!selected[c]) continue;
                faint = true;
            }
        }
        glm::vec4 color = selected[c]          ? overlay_selected
                          : (pins && outer[c]) ? overlay_pinned
                          : inside[c]          ? overlay_inside
                                               : overlay_outside;
        if (!active) color.w *= 0.5f;
        if (faint) color.w *= 0.35f;
        g.points.push_back({p[c], color, faint ? 3.0f : selected[c] ? 9.0f : 5.0f});
    }
    const glm::vec4 line_color =
        active ? glm::vec4(0.3f, 0.75f, 0.95f, 0.7f) : glm::vec4(0.5f, 0.5f, 0.5f, 0.4f);
    auto edge = [&](std::size_t a, std::size_t b) {
        g.lines.push_back({p[a], line_color, 1.0f});
        g.lines.push_back({p[b], line_color, 1.0f});
    };
    for (int i = 0; i <= d.x; ++i)
        for (int j = 0; j <= d.y; ++j)
            for (int k = 0; k <= d.z; ++k) {
                const std::size_t c = lattice->index(i, j, k);
                const bool cage = cage_only;
                const bool fi = i == 0 || i == d.x, fj = j == 0 || j == d.y, fk = k == 0 || k == d.z;
                if (i < d.x && (!cage || (fj && fk))) edge(c, lattice->index(i + 1, j, k));
                if (j < d.y && (!cage || (fi && fk))) edge(c, lattice->index(i, j + 1, k));
                if (k < d.z && (!cage || (fi && fj))) edge(c, lattice->index(i, j, k + 1));
            }
    // Proportional editing's radius while a tool drag of this lattice runs (Blender's circle): a circle
    // of the radius about the pivot, facing the drag's view.
    const Drag& drag = state.drag;
    if (drag.lattice == entity && drag.proportional.enabled &&
        (drag.kind == Drag::Kind::move || drag.kind == Drag::Kind::twist || drag.kind == Drag::Kind::scale)) {
        const std::vector<glm::dvec3> circle =
            proportional_circle(drag.camera, drag.pivot_world, drag.proportional.radius);
        for (std::size_t i = 0; i < circle.size(); ++i) {
            g.lines.push_back({glm::vec3(circle[i] - g.anchor), overlay_proportional, 1.0f});
            g.lines.push_back(
                {glm::vec3(circle[(i + 1) % circle.size()] - g.anchor), overlay_proportional, 1.0f});
        }
    }
    return g;
}

std::vector<OverlayDraw> overlay_draws(const EditorState& state) {
    if (state.xray) return {{true, false, 1.0f}, {false, false, 1.0f}};
    std::vector<OverlayDraw> draws;
    if (!(state.light_overlay_while_moving && state.previewing)) draws.push_back({true, false, 0.3f});
    draws.push_back({false, false, 0.3f});
    draws.push_back({true, true, 1.0f});
    draws.push_back({false, true, 1.0f});
    return draws;
}

Status init_lattice_overlay(ecs::Registry& registry) {
    if (registry.try_resource<LatticeOverlayState>()) return {};
    auto program = gfx::load_program(
        {{GL_VERTEX_SHADER, "editor/lattice.vert"}, {GL_FRAGMENT_SHADER, "editor/lattice.frag"}},
        "editor.lattice");
    LatticeOverlayState& s = registry.set_resource<LatticeOverlayState>();
    if (!program) {
        s.failed = true;
        return make_error(program.message());
    }
    s.program = std::move(*program);
    s.vao = gfx::VertexArray::create("editor.lattice.vao");
    s.buffer = gfx::Buffer::create("editor.lattice.vertices");
    const GLuint vao = s.vao.id();
    glEnableVertexArrayAttrib(vao, 0);
    glEnableVertexArrayAttrib(vao, 1);
    glEnableVertexArrayAttrib(vao, 2);
    glVertexArrayAttribFormat(vao, 0, 3, GL_FLOAT, GL_FALSE, offsetof(OverlayVertex, position));
    glVertexArrayAttribFormat(vao, 1, 4, GL_FLOAT, GL_FALSE, offsetof(OverlayVertex, color));
    glVertexArrayAttribFormat(vao, 2, 1, GL_FLOAT, GL_FALSE, offsetof(OverlayVertex, size));
    for (GLuint a = 0; a < 3; ++a) glVertexArrayAttribBinding(vao, a, 0);
    return {};
}

void release_lattice_overlay(ecs::Registry& registry) { registry.erase_resource<LatticeOverlayState>(); }

OverlayCacheStats overlay_cache_stats(const ecs::Registry& registry) {
    const auto* s = registry.try_resource<LatticeOverlayState>();
    return s ? s->lines.stats : OverlayCacheStats{};
}

namespace {

bool same_vertex(const OverlayVertex& a, const OverlayVertex& b) {
    return std::memcmp(&a, &b, sizeof a) == 0;
}

// The edges (vertex pairs from offset 0 of the bound vertex buffer) of one untested draw, through the
// line cache. The overlay's program, vertex array, scissor, blend state (constant opacity) and target
// framebuffer are bound by the caller and left so.
void draw_lines_cached(LatticeOverlayState& s, const std::vector<OverlayVertex>& lines,
                       const OverlayLineCache::Key& key, GLuint target_fbo) {
    OverlayLineCache& c = s.lines;
    const std::size_t n = lines.size() / 2;
    auto direct = [&] {
        c.valid = false;
        ++c.stats.direct;
        glDrawArrays(GL_LINES, 0, GLsizei(lines.size()));
    };
    if (!c.indices) {  // first use
        c.indices = gfx::Buffer::create("editor.lattice_cache.indices");
        glVertexArrayElementBuffer(s.vao.id(), c.indices.id());
        auto program = gfx::load_program({{GL_VERTEX_SHADER, "splat_render/fullscreen.vert"},
                                          {GL_FRAGMENT_SHADER, "editor/lattice_cache.frag"}},
                                         "editor.lattice_cache");
        if (program) c.composite = std::move(*program);
        else log::error("lattice overlay: ", program.message(), " (edges are drawn without the cache)");
    }
    // A view that changed this frame (an orbit) is drawn directly: caching it would cost a pass more.
    if (!c.composite || !(c.key == key) || c.previous.size() != lines.size()) {
        c.key = key;
        c.previous = lines;
        return direct();
    }
    std::vector<std::uint8_t>& moved = c.moved;
    moved.assign(n, 0);
    bool cached_moved = false;
    for (std::size_t e = 0; e < n; ++e) {
        moved[e] = !same_vertex(lines[2 * e], c.previous[2 * e]) ||
                   !same_vertex(lines[2 * e + 1], c.previous[2 * e + 1]);
        cached_moved |= c.valid && moved[e] && c.cached[e];
    }
    c.previous = lines;
    if (!c.valid || cached_moved) {
        // Cache what did not move since last frame; the rest is drawn every frame until the next rebuild.
        c.cached.assign(n, 0);
        std::vector<GLuint> order;
        order.reserve(lines.size());
        for (int pass = 0; pass < 2; ++pass)
            for (std::size_t e = 0; e < n; ++e)
                if (bool(moved[e]) == bool(pass)) {
                    c.cached[e] = pass == 0;
                    order.push_back(GLuint(2 * e)), order.push_back(GLuint(2 * e + 1));
                }
        c.live_count = std::size_t(std::count(moved.begin(), moved.end(), 1)) * 2;
        c.cached_count = order.size() - c.live_count;
        if (c.cached_count == 0) return direct();
        glNamedBufferData(c.indices.id(), GLsizeiptr(order.size() * sizeof(GLuint)), order.data(),
                          GL_DYNAMIC_DRAW);
        if (!c.color || c.size != key.target) {
            c.color = gfx::Texture::create("editor.lattice_cache", GL_TEXTURE_2D);
            glTextureStorage2D(c.color.id(), 1, GL_RGBA16F, key.target.x, key.target.y);
            c.framebuffer = gfx::Framebuffer::create("editor.lattice_cache");
            glNamedFramebufferTexture(c.framebuffer.id(), GL_COLOR_ATTACHMENT0, c.color.id(), 0);
            c.size = key.target;
        }
        // Premultiplied: every edge blends colour and coverage at the constant opacity over transparent.
        glBindFramebuffer(GL_FRAMEBUFFER, c.framebuffer.id());
        const float transparent[4] = {0.0f, 0.0f, 0.0f, 0.0f};
        glClearNamedFramebufferfv(c.framebuffer.id(), GL_COLOR, 0, transparent);  // inside the scissor
        glBlendFuncSeparate(GL_CONSTANT_ALPHA, GL_ONE_MINUS_CONSTANT_ALPHA, GL_CONSTANT_ALPHA,
                            GL_ONE_MINUS_CONSTANT_ALPHA);
        glDrawElements(GL_LINES, GLsizei(c.cached_count), GL_UNSIGNED_INT, nullptr);
        glBindFramebuffer(GL_FRAMEBUFFER, target_fbo);
        c.valid = true;
        ++c.stats.rebuilt;
    } else {
        ++c.stats.reused;
    }
    glUseProgram(c.composite.id());
    glBindTextureUnit(SFFD_TEX_OVERLAY_CACHE, c.color.id());
    glBlendFuncSeparate(GL_ONE, GL_SRC1_COLOR, GL_ONE, GL_ZERO);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glBlendFuncSeparate(GL_CONSTANT_ALPHA, GL_ONE_MINUS_CONSTANT_ALPHA, GL_ONE, GL_ZERO);
    glUseProgram(s.program.id());
    if (c.live_count > 0)
        glDrawElements(GL_LINES, GLsizei(c.live_count), GL_UNSIGNED_INT,
                       reinterpret_cast<const void*>(c.cached_count * sizeof(GLuint)));
    c.stats.cached_edges += c.cached_count / 2, c.stats.live_edges += c.live_count / 2;
}

}  // namespace

namespace {

// The frame pixels (x, y, width, height from the lower left) the overlay's points and lines may touch
// (render::include_drawn_pixels): their projections, grown by the largest point's radius and a pixel;
// the whole frame when a vertex is not in front of the camera (its line may cross any pixel).
glm::ivec4 overlay_pixels(const OverlayGeometry& g, const glm::mat4& view_proj, int width, int height,
                          float pixel) {
    glm::vec2 lo(1e30f), hi(-1e30f);
    float radius = 1.0f;
    bool behind = false;
    auto add = [&](const OverlayVertex& v, bool point) {
        const glm::vec4 clip = view_proj * glm::vec4(v.position, 1.0f);
        if (!(clip.w > 1e-6f)) {  // (also NaN)
            behind = true;
            return;
        }
        const glm::vec2 p = (glm::vec2(clip) / clip.w * 0.5f + 0.5f) * glm::vec2(width, height);
        lo = glm::min(lo, p), hi = glm::max(hi, p);
        if (point) radius = std::max(radius, 0.5f * v.size * pixel);
    };
    for (const OverlayVertex& v : g.lines) add(v, false);
    for (const OverlayVertex& v : g.points) add(v, true);
    if (behind || !std::isfinite(lo.x) || !std::isfinite(lo.y) || !std::isfinite(hi.x) ||
        !std::isfinite(hi.y))
        return glm::ivec4(0, 0, width, height);
    if (lo.x > hi.x) return glm::ivec4(0);
    const glm::vec2 size(width, height);
    const glm::vec2 a = glm::clamp(glm::floor(lo - radius - 1.0f), glm::vec2(0.0f), size),
                    b = glm::clamp(glm::ceil(hi + radius + 1.0f), glm::vec2(0.0f), size);
    return glm::ivec4(int(a.x), int(a.y), int(b.x - a.x), int(b.y - a.y));
}

}  // namespace

void lattice_overlay_system(ecs::Registry& registry, const FrameContext&) {
    const EditorState* state = registry.try_resource<EditorState>();
    if (!state || !state->show_lattice) return;
    const GLuint fbo = render::output_framebuffer(registry);
    if (fbo == 0 || !registry.valid(state->camera) || !registry.has<Camera>(state->camera)) return;
    if (!registry.try_resource<LatticeOverlayState>()) {
        if (Status st = init_lattice_overlay(registry); !st) log::error("lattice overlay: ", st.message());
    }
    LatticeOverlayState& s = registry.resource<LatticeOverlayState>();
    if (s.failed) return;

    // The frame's pixels in the targets (fewer than the targets hold for a reduced preview frame), with
    // the projection of the full frame's aspect, as the render system draws it.
    const glm::ivec2 frame_size = render::output_frame_size(registry);
    const int width = frame_size.x, height = frame_size.y;
    if (width <= 0 || height <= 0) return;
    GLint target_width = 0, target_height = 0, color_tex = 0;
    glGetNamedFramebufferAttachmentParameteriv(fbo, GL_COLOR_ATTACHMENT0,
                                               GL_FRAMEBUFFER_ATTACHMENT_OBJECT_NAME, &color_tex);
    if (color_tex == 0) return;
    glGetTextureLevelParameteriv(GLuint(color_tex), 0, GL_TEXTURE_WIDTH, &target_width);
    glGetTextureLevelParameteriv(GLuint(color_tex), 0, GL_TEXTURE_HEIGHT, &target_height);
    const Camera& camera = registry.get<Camera>(state->camera);
    const Viewport vp{target_width, target_height};
    const glm::dmat4 view_proj = projection_matrix(camera, vp) * view_matrix(camera);

    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    const GLenum draw0 = GL_COLOR_ATTACHMENT0;
    glNamedFramebufferDrawBuffers(fbo, 1, &draw0);  // only the colour: normals/depth stay the surface's
    glViewport(0, 0, width, height);
    // Clipped to the part of the window no panel covers (panel_layout.h; the whole window without
    // panels). Panel rectangles are window pixels from the top; GL's scissor counts from the bottom.
    glm::ivec4 scissor(0, 0, width, height);
    if (const EditorViewRect* v = registry.try_resource<EditorViewRect>();
        v && v->width > 0 && v->height > 0) {
        const float sx = float(width) / v->width, sy = float(height) / v->height;
        const PanelRect& r = v->rect;
        scissor = glm::ivec4(GLint(r.x * sx), GLint(float(height) - (r.y + r.h) * sy),
                             GLsizei(std::max(0.0f, r.w * sx)), GLsizei(std::max(0.0f, r.h * sy)));
        glEnable(GL_SCISSOR_TEST);
        glScissor(scissor.x, scissor.y, scissor.z, scissor.w);
    }
    // Opacity comes from a constant blend factor and the result is opaque (alpha 1): the colour target
    // holds straight alpha, and captures treat alpha > 0 as covered, so the lattice also shows where
    // there is no surface behind it.
    glEnable(GL_BLEND);
    glBlendFuncSeparate(GL_CONSTANT_ALPHA, GL_ONE_MINUS_CONSTANT_ALPHA, GL_ONE, GL_ZERO);
    glEnable(GL_PROGRAM_POINT_SIZE);
    glDepthMask(GL_FALSE);
    glUseProgram(s.program.id());
    glBindVertexArray(s.vao.id());

    const std::vector<OverlayDraw> draws = overlay_draws(*state);
    // One lattice only: with several, a cached edge of one would land over the points of one drawn before.
    const auto* options = registry.try_resource<OverlayOptions>();
    const bool line_cache = (!options || options->line_cache) && registry.count<Lattice>() == 1;
    registry.view<const Lattice>().each([&](ecs::Entity e, const Lattice&) {
        const OverlayGeometry g = build_lattice_overlay(registry, *state, e);
        if (g.points.empty() || g.lines.empty()) return;
        const std::size_t count = g.points.size() + g.lines.size();
        if (count > s.capacity) {
            s.capacity = count * 2;
            glNamedBufferData(s.buffer.id(), GLsizeiptr(s.capacity * sizeof(OverlayVertex)), nullptr,
                              GL_STREAM_DRAW);
        }
        glNamedBufferSubData(s.buffer.id(), 0, GLsizeiptr(g.lines.size() * sizeof(OverlayVertex)),
                             g.lines.data());
        glNamedBufferSubData(s.buffer.id(), GLintptr(g.lines.size() * sizeof(OverlayVertex)),
                             GLsizeiptr(g.points.size() * sizeof(OverlayVertex)), g.points.data());
        glVertexArrayVertexBuffer(s.vao.id(), 0, s.buffer.id(), 0, sizeof(OverlayVertex));
        const glm::mat4 m = glm::mat4(view_proj * glm::translate(glm::dmat4(1.0), g.anchor));
        render::include_drawn_pixels(
            registry, overlay_pixels(g, m, width, height, float(width) / float(std::max(target_width, 1))));
        glUniformMatrix4fv(SFFD_LOC_OVERLAY_VIEW_PROJ, 1, GL_FALSE, &m[0][0]);
        const float pixel = float(width) / float(std::max(target_width, 1));
        glUniform1f(SFFD_LOC_OVERLAY_PIXEL, pixel);
        for (const OverlayDraw& d : draws) {
            if (d.depth_test) glEnable(GL_DEPTH_TEST), glDepthFunc(GL_LEQUAL);
            else glDisable(GL_DEPTH_TEST);
            const OverlayVertex& first = d.lines ? g.lines.front() : g.points.front();
            glUniform1i(SFFD_LOC_OVERLAY_POINTS, d.lines ? 0 : 1);
            const float opacity = d.strength * first.color.w;
            glBlendColor(0.0f, 0.0f, 0.0f, opacity);
            if (d.lines && !d.depth_test && line_cache) {
                const OverlayLineCache::Key key{m,
                                                glm::ivec4(0, 0, width, height),
                                                scissor,
                                                glm::ivec2(target_width, target_height),
                                                pixel,
                                                opacity,
                                                g.lines.size()};
                draw_lines_cached(s, g.lines, key, fbo);
            } else if (d.lines) {
                glDrawArrays(GL_LINES, 0, GLsizei(g.lines.size()));
            } else {
                glDrawArrays(GL_POINTS, GLint(g.lines.size()), GLsizei(g.points.size()));
            }
        }
    });

    glBindVertexArray(0);
    glUseProgram(0);
    glDepthMask(GL_TRUE);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glDisable(GL_PROGRAM_POINT_SIZE);
    glDisable(GL_SCISSOR_TEST);
    // Restore the render system's draw buffers (every colour attachment it has).
    GLint max_attach = 0;
    glGetIntegerv(GL_MAX_COLOR_ATTACHMENTS, &max_attach);
    std::vector<GLenum> bufs;
    for (GLint i = 0; i < max_attach; ++i) {
        GLint type = GL_NONE;
        glGetNamedFramebufferAttachmentParameteriv(fbo, GL_COLOR_ATTACHMENT0 + GLenum(i),
                                                   GL_FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE, &type);
        if (type == GL_NONE) break;
        bufs.push_back(GL_COLOR_ATTACHMENT0 + GLenum(i));
    }
    glNamedFramebufferDrawBuffers(fbo, GLsizei(bufs.size()), bufs.data());

    glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

}  // namespace sffd::editor
