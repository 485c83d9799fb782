// Selection deltas, modes and the whole-cloud commands (all, none, invert, by colour). The screen tools are
// in screen_select.cpp, the world-distance ones (sphere, grow, shrink) in neighbourhood.cpp.
#include "systems/point_select/point_select.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_pages.h"
#include "systems/gaussian/sh.h"
#include "systems/point_select/shown_points.h"

namespace sffd::point_select {
namespace {

constexpr std::size_t kMaskThreshold =
    SelectionDelta::kMaskWords * 64 / 16;  // 4,096: where 2 B/point = 8 KiB

// Builds one page's record from its changed offsets (ascending).
SelectionDelta::Page make_page(std::uint32_t page, std::vector<std::uint16_t>&& offsets) {
    SelectionDelta::Page p;
    p.page = page;
    p.count = std::uint32_t(offsets.size());
    if (offsets.size() > kMaskThreshold) {
        p.mask.assign(SelectionDelta::kMaskWords, 0);
        for (const std::uint16_t o : offsets) p.mask[o >> 6] |= std::uint64_t(1) << (o & 63);
    } else {
        offsets.shrink_to_fit();
        p.offsets = std::move(offsets);
    }
    return p;
}

// A page's changed offsets as a 1,024-word mask.
void page_mask(const SelectionDelta::Page& p, std::uint64_t* mask) {
    if (!p.mask.empty()) {
        std::copy(p.mask.begin(), p.mask.end(), mask);
        return;
    }
    std::fill(mask, mask + SelectionDelta::kMaskWords, 0);
    for (const std::uint16_t o : p.offsets) mask[o >> 6] |= std::uint64_t(1) << (o & 63);
}

// Turns per-page masks into records (pages with nothing changed are left out).
void append_from_mask(SelectionDelta& d, std::uint32_t page, const std::uint64_t* mask) {
    std::size_t count = 0;
    for (std::size_t w = 0; w < SelectionDelta::kMaskWords; ++w) count += std::size_t(std::popcount(mask[w]));
    if (count == 0) return;
    SelectionDelta::Page p;
    p.page = page;
    p.count = std::uint32_t(count);
    if (count > kMaskThreshold) {
        p.mask.assign(mask, mask + SelectionDelta::kMaskWords);
    } else {
        p.offsets.reserve(count);
        for (std::size_t w = 0; w < SelectionDelta::kMaskWords; ++w)
            for (std::uint64_t bits = mask[w]; bits; bits &= bits - 1)
                p.offsets.push_back(std::uint16_t(w * 64 + std::size_t(std::countr_zero(bits))));
    }
    d.pages.push_back(std::move(p));
}

std::span<const std::uint8_t> flag_bits(const ecs::Registry& registry, ecs::Entity e, std::size_t n) {
    const PointFlags* flags = registry.try_get<PointFlags>(e);
    if (!flags || flags->bits.size() != n) return {};
    return flags->bits;
}

bool combine(Mode mode, bool selected, bool candidate) {
    switch (mode) {
        case Mode::set: return candidate;
        case Mode::add: return selected || candidate;
        case Mode::remove: return selected && !candidate;
        case Mode::intersect: return selected && candidate;
    }
    return selected;
}

// The delta that makes every point's bit `want(i, selected)`, gone points cleared.
template <class Want>
SelectionDelta delta_to(std::span<const std::uint8_t> bits, std::size_t n, Want&& want) {
    SelectionDelta d;
    d.points = n;
    std::vector<std::uint16_t> changed;
    for (std::size_t page = 0; page < page_count(n); ++page) {
        const PageRange r = page_range(page, n);
        changed.clear();
        for (std::size_t o = 0; o < r.count; ++o) {
            const std::size_t i = r.first + o;
            const std::uint8_t b = bits.empty() ? 0 : bits[i];
            const bool selected = (b & kPointSelected) != 0;
            const bool next = (b & kPointGone) == 0 && want(i, selected);
            if (next != selected) changed.push_back(std::uint16_t(o));
        }
        if (!changed.empty()) d.pages.push_back(make_page(std::uint32_t(page), std::vector(changed)));
    }
    return d;
}

float srgb_encode(float linear) {
    const float c = std::clamp(linear, 0.0f, 1.0f);
    return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

glm::vec3 unpack_rgb(std::uint32_t rgba) {
    return glm::vec3(float(rgba & 0xffu), float((rgba >> 8) & 0xffu), float((rgba >> 16) & 0xffu)) / 255.0f;
}

// The texel the renderer's nearest sample would show (repeat in u, clamp in v, row 0 at v = 0).
glm::vec3 texel(const SplatTexture& t, glm::vec2 uv) {
    const float u = uv.x - std::floor(uv.x);
    const int x = std::clamp(int(u * float(t.width)), 0, t.width - 1);
    const int y = std::clamp(int(std::floor(uv.y * float(t.height))), 0, t.height - 1);
    const std::uint8_t* p = &t.rgba8[(std::size_t(y) * std::size_t(t.width) + std::size_t(x)) * 4];
    return glm::vec3(p[0], p[1], p[2]) / 255.0f;
}

}  // namespace

// ---- SelectionDelta ---------------------------------------------------------------------------------

std::size_t SelectionDelta::changed() const {
    std::size_t n = 0;
    for (const Page& p : pages) n += p.count;
    return n;
}

std::size_t SelectionDelta::bytes() const {
    std::size_t b = sizeof(*this) + pages.capacity() * sizeof(Page);
    for (const Page& p : pages)
        b += p.offsets.capacity() * sizeof(std::uint16_t) + p.mask.capacity() * sizeof(std::uint64_t);
    return b;
}

std::vector<std::uint32_t> SelectionDelta::indices() const {
    std::vector<std::uint32_t> out;
    out.reserve(changed());
    for (const Page& p : pages) {
        const std::uint32_t base = p.page << kPageShift;
        if (p.mask.empty()) {
            for (const std::uint16_t o : p.offsets) out.push_back(base + o);
        } else {
            for (std::size_t w = 0; w < kMaskWords; ++w)
                for (std::uint64_t bits = p.mask[w]; bits; bits &= bits - 1)
                    out.push_back(base + std::uint32_t(w * 64 + std::size_t(std::countr_zero(bits))));
        }
    }
    return out;
}

SelectionDelta delta_between(std::span<const std::uint8_t> before, std::span<const std::uint8_t> after) {
    SelectionDelta d;
    d.points = std::min(before.size(), after.size());
    std::vector<std::uint16_t> changed;
    for (std::size_t page = 0; page < page_count(d.points); ++page) {
        const PageRange r = page_range(page, d.points);
        changed.clear();
        for (std::size_t o = 0; o < r.count; ++o)
            if (((before[r.first + o] ^ after[r.first + o]) & kPointSelected) != 0)
                changed.push_back(std::uint16_t(o));
        if (!changed.empty()) d.pages.push_back(make_page(std::uint32_t(page), std::vector(changed)));
    }
    return d;
}

SelectionDelta delta_from_indices(std::span<const std::uint32_t> indices, std::size_t points) {
    SelectionDelta d;
    d.points = points;
    std::size_t k = 0;
    while (k < indices.size()) {
        const std::uint32_t page = indices[k] >> kPageShift;
        std::vector<std::uint16_t> offsets;
        while (k < indices.size() && (indices[k] >> kPageShift) == page)
            offsets.push_back(std::uint16_t(indices[k++] & (kPagePoints - 1)));
        d.pages.push_back(make_page(page, std::move(offsets)));
    }
    return d;
}

void toggle(std::span<std::uint8_t> bits, const SelectionDelta& delta) {
    for (const SelectionDelta::Page& p : delta.pages) {
        std::uint8_t* base = bits.data() + (std::size_t(p.page) << kPageShift);
        if (p.mask.empty()) {
            for (const std::uint16_t o : p.offsets) base[o] ^= kPointSelected;
        } else {
            for (std::size_t w = 0; w < SelectionDelta::kMaskWords; ++w)
                for (std::uint64_t m = p.mask[w]; m; m &= m - 1)
                    base[w * 64 + std::size_t(std::countr_zero(m))] ^= kPointSelected;
        }
    }
}

SelectionDelta compose(const SelectionDelta& first, const SelectionDelta& then) {
    SelectionDelta d;
    d.points = std::max(first.points, then.points);
    std::vector<std::uint64_t> a(SelectionDelta::kMaskWords), b(SelectionDelta::kMaskWords);
    std::size_t i = 0, j = 0;
    while (i < first.pages.size() || j < then.pages.size()) {
        const std::uint32_t pa = i < first.pages.size() ? first.pages[i].page : UINT32_MAX;
        const std::uint32_t pb = j < then.pages.size() ? then.pages[j].page : UINT32_MAX;
        const std::uint32_t page = std::min(pa, pb);
        std::fill(a.begin(), a.end(), 0);
        if (pa == page) page_mask(first.pages[i++], a.data());
        if (pb == page) {
            page_mask(then.pages[j++], b.data());
            for (std::size_t w = 0; w < a.size(); ++w) a[w] ^= b[w];
        }
        append_from_mask(d, page, a.data());
    }
    return d;
}

bool apply_delta(ecs::Registry& registry, ecs::Entity e, const SelectionDelta& delta) {
    const std::size_t n = point_count(registry, e);
    if (n == 0 || n != delta.points) return false;
    if (delta.empty()) return true;
    PointFlags* flags =
        registry.try_get<PointFlags>(e) ? &registry.patch<PointFlags>(e) : &registry.emplace<PointFlags>(e);
    if (flags->bits.size() != n) flags->bits.assign(n, 0);  // empty (or stale): every point clear
    toggle(flags->bits, delta);
    for (const SelectionDelta::Page& p : delta.pages) {
        const PageRange r = page_range(p.page, n);
        mark_points_changed(registry, e, PointColumn::selection, r.first, r.count);
    }
    return true;
}

// ---- Modes ------------------------------------------------------------------------------------------

Mode select_mode(bool shift, bool ctrl) {
    if (ctrl) return Mode::remove;
    return shift ? Mode::add : Mode::set;
}

SelectionDelta commit(ecs::Registry& registry, ecs::Entity e, std::span<const std::uint32_t> candidates,
                      Mode mode) {
    const std::size_t n = point_count(registry, e);
    std::vector<std::uint64_t> mask((n + 63) / 64, 0);
    for (const std::uint32_t i : candidates)
        if (i < n) mask[i >> 6] |= std::uint64_t(1) << (i & 63);
    const SelectionDelta d = delta_to(flag_bits(registry, e, n), n, [&](std::size_t i, bool selected) {
        return combine(mode, selected, (mask[i >> 6] >> (i & 63)) & 1);
    });
    apply_delta(registry, e, d);
    return d;
}

// ---- Reading ----------------------------------------------------------------------------------------

std::size_t point_count(const ecs::Registry& registry, ecs::Entity e) {
    if (!registry.valid(e)) return 0;
    if (const SplatCloud* c = registry.try_get<SplatCloud>(e)) return c->size();
    if (const GaussianCloud* g = registry.try_get<GaussianCloud>(e)) return g->size();
    return 0;
}

std::vector<std::uint32_t> selected_points(const ecs::Registry& registry, ecs::Entity e) {
    const std::size_t n = point_count(registry, e);
    const std::span<const std::uint8_t> bits = flag_bits(registry, e, n);
    std::vector<std::uint32_t> out;
    for (std::size_t i = 0; i < bits.size(); ++i)
        if ((bits[i] & (kPointSelected | kPointGone)) == kPointSelected) out.push_back(std::uint32_t(i));
    return out;
}

std::size_t selected_count(const ecs::Registry& registry, ecs::Entity e) {
    return selected_points(registry, e).size();
}

// ---- Commands ---------------------------------------------------------------------------------------

SelectionDelta select_all(ecs::Registry& registry, ecs::Entity e) {
    const std::size_t n = point_count(registry, e);
    SelectionDelta d = delta_to(flag_bits(registry, e, n), n, [](std::size_t, bool) { return true; });
    apply_delta(registry, e, d);
    return d;
}

SelectionDelta select_none(ecs::Registry& registry, ecs::Entity e) {
    const std::size_t n = point_count(registry, e);
    SelectionDelta d = delta_to(flag_bits(registry, e, n), n, [](std::size_t, bool) { return false; });
    apply_delta(registry, e, d);
    return d;
}

SelectionDelta invert_selection(ecs::Registry& registry, ecs::Entity e) {
    const std::size_t n = point_count(registry, e);
    SelectionDelta d = delta_to(flag_bits(registry, e, n), n, [](std::size_t, bool s) { return !s; });
    apply_delta(registry, e, d);
    return d;
}

// ---- By colour --------------------------------------------------------------------------------------

namespace {

// What a point's colour is read from, looked up once per call.
struct ColourSource {
    const SplatCloud* splats = nullptr;
    const GaussianCloud* gaussians = nullptr;
    glm::vec3 base{0.0f};  // the material's base colour, sRGB-encoded
    bool texture = false;
    std::size_t coeffs = 1;

    glm::vec3 operator()(std::size_t i) const {
        if (splats) {
            if (splats->colors.size() == splats->size()) return unpack_rgb(splats->colors[i]);
            return texture ? texel(splats->texture, splats->uvs[i]) : base;
        }
        if (gaussians->sh.size() < (i + 1) * coeffs * 3) return glm::vec3(0.5f);
        const float* dc = &gaussians->sh[i * coeffs * 3];
        const float c0 = float(gaussian::kShC0);
        return glm::clamp(glm::vec3(0.5f) + c0 * glm::vec3(dc[0], dc[1], dc[2]), glm::vec3(0.0f),
                          glm::vec3(1.0f));
    }
};

ColourSource colour_source(const ecs::Registry& registry, ecs::Entity e) {
    ColourSource s;
    if ((s.splats = registry.try_get<SplatCloud>(e))) {
        const SplatTexture& t = s.splats->texture;
        s.texture = s.splats->uvs.size() == s.splats->size() && t.width > 0 && t.height > 0 &&
                    t.rgba8.size() == std::size_t(t.width) * std::size_t(t.height) * 4;
        const SplatMaterial* m = registry.try_get<SplatMaterial>(e);
        const glm::vec4 c = m ? m->base_color : SplatMaterial{}.base_color;
        s.base = glm::vec3(srgb_encode(c.x), srgb_encode(c.y), srgb_encode(c.z));
    } else {
        s.gaussians = registry.try_get<GaussianCloud>(e);
        if (s.gaussians) s.coeffs = std::size_t(sh_coeffs(s.gaussians->sh_degree));
    }
    return s;
}

}  // namespace

std::optional<glm::vec3> point_colour(const ecs::Registry& registry, ecs::Entity e, std::uint32_t index) {
    if (index >= point_count(registry, e)) return std::nullopt;
    return colour_source(registry, e)(index);
}

std::vector<std::uint32_t> points_by_colour(const ecs::Registry& registry, ecs::Entity e, glm::vec3 colour,
                                            double tolerance) {
    const std::size_t n = point_count(registry, e);
    const std::span<const std::uint8_t> bits = flag_bits(registry, e, n);
    const ColourSource source = colour_source(registry, e);
    const double tol2 = tolerance * tolerance;
    std::vector<std::uint32_t> out;
    for (std::size_t i = 0; i < n; ++i) {
        if (!bits.empty() && (bits[i] & kPointGone)) continue;
        const glm::dvec3 d = glm::dvec3(source(i)) - glm::dvec3(colour);
        if (glm::dot(d, d) <= tol2) out.push_back(std::uint32_t(i));
    }
    return out;
}

SelectionDelta select_by_colour(ecs::Registry& registry, ecs::Entity e, glm::vec3 colour, double tolerance,
                                Mode mode) {
    const std::vector<std::uint32_t> c = points_by_colour(registry, e, colour, tolerance);
    return commit(registry, e, c, mode);
}

}  // namespace sffd::point_select
