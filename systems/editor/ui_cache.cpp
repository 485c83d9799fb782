#include "systems/editor/ui_cache.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/glm.hpp>
#include <imgui.h>
#include <backends/imgui_impl_opengl3.h>

#include "runtime/gfx/gl.h"
#include "runtime/gfx/gl_object.h"

namespace sffd::editor {

namespace {

// A rectangle of framebuffer pixels, top-down (ImGui's orientation): [x0, x1) x [y0, y1).
struct PixelRect {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    bool empty() const { return x1 <= x0 || y1 <= y0; }
    bool contains(const PixelRect& o) const { return o.x0 >= x0 && o.y0 >= y0 && o.x1 <= x1 && o.y1 <= y1; }
    bool intersects(const PixelRect& o) const { return o.x0 < x1 && x0 < o.x1 && o.y0 < y1 && y0 < o.y1; }
    bool operator==(const PixelRect&) const = default;
};

struct CachedPanel {
    PixelRect pixels;
    std::uint64_t hash = 0;
    bool cached = false;  // the texture holds this panel as `hash` draws it
};

// 64-bit words mixed into one hash (only equality between frames matters).
struct Hasher {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    void word(std::uint64_t w) {
        h ^= w + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
        h *= 0xff51afd7ed558ccdull;
    }
    void bytes(const void* p, std::size_t n) {
        const auto* b = static_cast<const unsigned char*>(p);
        std::size_t i = 0;
        for (; i + 8 <= n; i += 8) {
            std::uint64_t w;
            std::memcpy(&w, b + i, 8);
            word(w);
        }
        std::uint64_t tail = n;
        for (; i < n; ++i) tail = (tail << 8) | b[i];
        word(tail);
    }
    void f(float x) {
        std::uint32_t u;
        std::memcpy(&u, &x, 4);
        word(u);
    }
};

}  // namespace

struct UiCacheState {
    gfx::Texture color;  // RGBA8, the window's size: the cached panels' pixels
    gfx::Framebuffer framebuffer;
    int width = 0, height = 0;
    bool multisampled = false, checked_samples = false;
    std::vector<CachedPanel> panels;
    UiCacheStats stats;
    // Scratch, kept between frames.
    std::vector<int> group;             // per draw list: index into this frame's panels, or -1
    std::vector<PixelRect> list_rects;  // per draw list: the pixels its clip rectangles allow
    std::vector<ImDrawList*> lists;
};

namespace {

// The scissor ImGui's OpenGL backend sets for a clip rectangle (imgui_impl_opengl3.cpp), top-down.
PixelRect clip_pixels(const ImVec4& clip, const ImDrawData& d, int fb_w, int fb_h) {
    const ImVec2 o = d.DisplayPos, k = d.FramebufferScale;
    const float x0 = std::max((clip.x - o.x) * k.x, 0.0f), y0 = std::max((clip.y - o.y) * k.y, 0.0f);
    const float x1 = std::min((clip.z - o.x) * k.x, float(fb_w)),
                y1 = std::min((clip.w - o.y) * k.y, float(fb_h));
    if (x1 <= x0 || y1 <= y0) return {};
    // glScissor((int)x0, (int)(fb_h - y1), (int)(x1 - x0), (int)(y1 - y0)), back in top-down rows.
    const int sx = int(x0), sw = int(x1 - x0), sy = int(float(fb_h) - y1), sh = int(y1 - y0);
    return {sx, fb_h - (sy + sh), sx + sw, fb_h - sy};
}

// A panel's pixels: ImGui places windows at whole units; rounding keeps a fractional scale's edges on
// its pixels.
PixelRect panel_pixels(const PanelRect& r, const ImDrawData& d) {
    const ImVec2 o = d.DisplayPos, k = d.FramebufferScale;
    return {int(std::lround((r.x - o.x) * k.x)), int(std::lround((r.y - o.y) * k.y)),
            int(std::lround((r.x + r.w - o.x) * k.x)), int(std::lround((r.y + r.h - o.y) * k.y))};
}

void set_scissor(const PixelRect& r, int fb_h) { glScissor(r.x0, fb_h - r.y1, r.x1 - r.x0, r.y1 - r.y0); }

void clear_rects(GLuint fbo, const std::vector<PixelRect>& rects, int fb_h) {
    if (rects.empty()) return;
    const ImVec4 c = ImGui::GetStyle().Colors[ImGuiCol_WindowBg];
    const float color[4] = {c.x, c.y, c.z, 1.0f};
    glEnable(GL_SCISSOR_TEST);
    for (const PixelRect& r : rects) {
        set_scissor(r, fb_h);
        glClearNamedFramebufferfv(fbo, GL_COLOR, 0, color);
    }
    glDisable(GL_SCISSOR_TEST);
}

// ImGui's backend over a subset of the frame's lists, in their order, into the bound framebuffer.
void render_lists(const ImDrawData& frame, std::vector<ImDrawList*>& lists) {
    if (lists.empty()) return;
    ImDrawData d = frame;
    d.CmdLists = lists.data();
    d.CmdListsCount = int(lists.size());
    d.TotalVtxCount = d.TotalIdxCount = 0;
    for (const ImDrawList* l : lists)
        d.TotalVtxCount += l->VtxBuffer.Size, d.TotalIdxCount += l->IdxBuffer.Size;
    ImGui_ImplOpenGL3_RenderDrawData(&d);
}

// Everything drawn directly: the panels' backgrounds, then every list.
void draw_direct(const ImDrawData& data, const std::vector<PanelRect>& panels, GLuint target, int fb_h) {
    std::vector<PixelRect> rects;
    for (const PanelRect& r : panels)
        if (const PixelRect p = panel_pixels(r, data); !p.empty()) rects.push_back(p);
    clear_rects(target, rects, fb_h);
    ImGui_ImplOpenGL3_RenderDrawData(const_cast<ImDrawData*>(&data));
}

}  // namespace

void draw_ui(ecs::Registry& registry, ImDrawData& data, const std::vector<PanelRect>& panels) {
    UiCacheState* st = registry.try_resource<UiCacheState>();
    if (!st) st = &registry.set_resource<UiCacheState>();
    const int fb_w = int(data.DisplaySize.x * data.FramebufferScale.x),
              fb_h = int(data.DisplaySize.y * data.FramebufferScale.y);
    GLint bound = 0;
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &bound);
    const GLuint target = GLuint(bound);
    if (!st->checked_samples) {  // a blit cannot write a multisampled window
        GLint samples = 0;
        glGetIntegerv(GL_SAMPLE_BUFFERS, &samples);
        st->multisampled = samples > 0, st->checked_samples = true;
    }
    const UiCacheOptions* options = registry.try_resource<UiCacheOptions>();
    auto direct = [&] {
        for (CachedPanel& p : st->panels) p.cached = false;
        ++st->stats.direct_frames;
        draw_direct(data, panels, target, fb_h);
    };
    if ((options && !options->enabled) || st->multisampled || fb_w <= 0 || fb_h <= 0) return direct();

    // This frame's panels, matched to the last frame's by their pixels.
    std::vector<CachedPanel> now;
    now.reserve(panels.size());
    for (const PanelRect& r : panels) {
        const PixelRect p = panel_pixels(r, data);
        if (p.empty()) continue;
        CachedPanel c{p};
        for (const CachedPanel& old : st->panels)
            if (old.pixels == p) c = old;
        now.push_back(c);
    }

    // Each list belongs to the panel that holds every pixel it may touch, or to none.
    const int n = data.CmdListsCount;
    st->group.assign(std::size_t(n), -1);
    st->list_rects.assign(std::size_t(n), PixelRect{});
    for (int i = 0; i < n; ++i) {
        const ImDrawList* l = data.CmdLists[i];
        // Per command, its clip rectangle meets its triangles' box: window decorations are drawn under a
        // full-display clip rectangle, and a panel's scrolled-out content lies outside it but is clipped.
        PixelRect box{fb_w, fb_h, 0, 0};
        const ImVec2 o = data.DisplayPos, scale = data.FramebufferScale;
        for (const ImDrawCmd& c : l->CmdBuffer) {
            if (c.UserCallback) return direct();  // the callback's effect is unknown
            if (c.ElemCount == 0) continue;
            PixelRect p = clip_pixels(c.ClipRect, data, fb_w, fb_h);
            if (p.empty()) continue;
            ImVec2 lo(1e30f, 1e30f), hi(-1e30f, -1e30f);
            for (unsigned e = 0; e < c.ElemCount; ++e) {
                const ImDrawVert& v = l->VtxBuffer[int(c.VtxOffset + l->IdxBuffer[int(c.IdxOffset + e)])];
                lo = ImVec2(std::min(lo.x, v.pos.x), std::min(lo.y, v.pos.y));
                hi = ImVec2(std::max(hi.x, v.pos.x), std::max(hi.y, v.pos.y));
            }
            p.x0 = std::max(p.x0, int(std::floor((lo.x - o.x) * scale.x)));
            p.y0 = std::max(p.y0, int(std::floor((lo.y - o.y) * scale.y)));
            p.x1 = std::min(p.x1, int(std::ceil((hi.x - o.x) * scale.x)));
            p.y1 = std::min(p.y1, int(std::ceil((hi.y - o.y) * scale.y)));
            if (p.empty()) continue;
            box = {std::min(box.x0, p.x0), std::min(box.y0, p.y0), std::max(box.x1, p.x1),
                   std::max(box.y1, p.y1)};
        }
        st->list_rects[std::size_t(i)] = box;
        if (box.empty()) continue;
        for (std::size_t k = 0; k < now.size(); ++k)
            if (now[k].pixels.contains(box)) st->group[std::size_t(i)] = int(k);
    }
    // A list drawn directly goes after every copied panel: it must not be under a later panel's list.
    for (int i = 0; i < n; ++i) {
        if (st->group[std::size_t(i)] >= 0 || st->list_rects[std::size_t(i)].empty()) continue;
        for (int j = i + 1; j < n; ++j) {
            const int k = st->group[std::size_t(j)];
            if (k >= 0 && now[std::size_t(k)].pixels.intersects(st->list_rects[std::size_t(i)]))
                return direct();
        }
    }

    // What each panel draws: its lists' triangles, commands and textures, at this display and colour.
    const ImVec4 bg = ImGui::GetStyle().Colors[ImGuiCol_WindowBg];
    std::vector<Hasher> hashes(now.size());
    for (Hasher& h : hashes) {
        h.f(data.DisplayPos.x), h.f(data.DisplayPos.y), h.f(data.DisplaySize.x), h.f(data.DisplaySize.y);
        h.f(data.FramebufferScale.x), h.f(data.FramebufferScale.y);
        h.f(bg.x), h.f(bg.y), h.f(bg.z);
    }
    for (int i = 0; i < n; ++i) {
        const int k = st->group[std::size_t(i)];
        if (k < 0) continue;
        const ImDrawList* l = data.CmdLists[i];
        Hasher& h = hashes[std::size_t(k)];
        h.bytes(l->VtxBuffer.Data, std::size_t(l->VtxBuffer.Size) * sizeof(ImDrawVert));
        h.bytes(l->IdxBuffer.Data, std::size_t(l->IdxBuffer.Size) * sizeof(ImDrawIdx));
        for (const ImDrawCmd& c : l->CmdBuffer) {
            h.f(c.ClipRect.x), h.f(c.ClipRect.y), h.f(c.ClipRect.z), h.f(c.ClipRect.w);
            h.word(reinterpret_cast<std::uintptr_t>(c.TextureId));
            h.word((std::uint64_t(c.VtxOffset) << 32) | c.IdxOffset);
            h.word(c.ElemCount);
        }
    }

    if (!st->color || st->width != fb_w || st->height != fb_h) {
        st->color = gfx::Texture::create("editor.ui_cache", GL_TEXTURE_2D);
        glTextureStorage2D(st->color.id(), 1, GL_RGBA8, fb_w, fb_h);
        st->framebuffer = gfx::Framebuffer::create("editor.ui_cache");
        glNamedFramebufferTexture(st->framebuffer.id(), GL_COLOR_ATTACHMENT0, st->color.id(), 0);
        st->width = fb_w, st->height = fb_h;
        for (CachedPanel& p : now) p.cached = false;
    }

    // Unchanged and cached: copied. Unchanged for the second frame: drawn into the texture, then copied.
    // Changed: drawn into the window (a panel that changes every frame never pays for the texture).
    enum Use : std::uint8_t { reuse, cache, draw };
    std::vector<Use> use(now.size());
    std::vector<PixelRect> to_cache, to_draw;
    for (std::size_t k = 0; k < now.size(); ++k) {
        CachedPanel& p = now[k];
        const std::uint64_t h = hashes[k].h;
        if (p.hash == h && p.cached) {
            use[k] = reuse, ++st->stats.reused;
        } else if (p.hash == h) {
            use[k] = cache, ++st->stats.cached, to_cache.push_back(p.pixels);
            p.cached = true;
        } else {
            use[k] = draw, ++st->stats.drawn, to_draw.push_back(p.pixels);
            p.hash = h, p.cached = false;
        }
    }
    if (!to_cache.empty()) {
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, st->framebuffer.id());
        clear_rects(st->framebuffer.id(), to_cache, fb_h);
        st->lists.clear();
        for (int i = 0; i < n; ++i)
            if (const int k = st->group[std::size_t(i)]; k >= 0 && use[std::size_t(k)] == cache)
                st->lists.push_back(data.CmdLists[i]);
        render_lists(data, st->lists);
        glBindFramebuffer(GL_DRAW_FRAMEBUFFER, target);
    }
    glDisable(GL_SCISSOR_TEST);  // a blit is scissored
    for (std::size_t k = 0; k < now.size(); ++k) {
        if (use[k] == draw) continue;
        const PixelRect& r = now[k].pixels;
        glBlitNamedFramebuffer(st->framebuffer.id(), target, r.x0, fb_h - r.y1, r.x1, fb_h - r.y0, r.x0,
                               fb_h - r.y1, r.x1, fb_h - r.y0, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    }
    clear_rects(target, to_draw, fb_h);
    st->lists.clear();
    for (int i = 0; i < n; ++i)
        if (const int k = st->group[std::size_t(i)]; k < 0 || use[std::size_t(k)] == draw)
            st->lists.push_back(data.CmdLists[i]);
    render_lists(data, st->lists);
    st->panels = std::move(now);
    ++st->stats.frames;
}

UiCacheStats ui_cache_stats(const ecs::Registry& registry) {
    const UiCacheState* st = registry.try_resource<UiCacheState>();
    return st ? st->stats : UiCacheStats{};
}

void release_ui_cache(ecs::Registry& registry) { registry.erase_resource<UiCacheState>(); }

}  // namespace sffd::editor
