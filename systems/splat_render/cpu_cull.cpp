// CPU twin of shaders/splat_render/cull.comp. Every function mirrors the GLSL function of the same name
// (splat_common.glsl, splat_color.glsl, lighting.glsl), in float, so both paths produce the same records.
#include "systems/splat_render/cpu_cull.h"
#include "systems/splat_render/texture_lookup.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>

#include <glm/gtc/packing.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/gfx/point_marks.h"
#include "runtime/gfx/splat_pack.h"

namespace sffd::render {

namespace {

constexpr std::size_t block_splats = 4096;

glm::vec3 xyz(const float (&v)[4]) { return glm::vec3(v[0], v[1], v[2]); }

float ellipse_max_radius(const glm::vec3& u, const glm::vec3& v) {
    const float a = glm::dot(u, u), b = glm::dot(u, v), c = glm::dot(v, v);
    const float h = 0.5f * (a + c);
    return std::sqrt(h + std::sqrt(std::max(0.25f * (a - c) * (a - c) + b * b, 0.0f)));
}

// GLSL round() leaves halves to the implementation; nearbyint rounds them to even, in one instruction.
// The 30 colour bits go to the mantissa and (plus one) the exponent: always a normal, finite float.
float pack_color(const glm::vec3& linear) {
    const glm::vec3 s = glm::sqrt(glm::clamp(linear, 0.0f, 1.0f)) * 1023.0f;
    const auto q = [](float x) { return std::uint32_t(std::nearbyint(x)); };
    const std::uint32_t bits = q(s.x) | (q(s.y) << 10) | (q(s.z) << 20);
    return std::bit_cast<float>((bits & 0x7fffffu) + (((bits >> 23) + 1u) << 23));
}

// pack_halves of splat_common.glsl: two halves (packHalf2x16) less their lowest mantissa bit, 30 bits in
// all, stored like pack_color so the float is normal and finite (a raw packHalf2x16 with a zero upper half
// is a denormal, which GLSL lets a driver flush to zero).
float pack_halves(const glm::vec2& v) {
    const std::uint32_t h = glm::packHalf2x16(v);
    const std::uint32_t bits = ((h & 0xffffu) >> 1) | ((h >> 17) << 15);
    return std::bit_cast<float>((bits & 0x7fffffu) + (((bits >> 23) + 1u) << 23));
}

bool all_finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// The shader's decode of per-splat colours: unpackUnorm4x8, then srgb_to_linear (no linear toe), as a
// table of the 256 byte values.
const std::array<float, 256>& splat_srgb_table() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i)
            t[std::size_t(i)] = std::pow((float(i) / 255.0f + 0.055f) * (1.0f / 1.055f), 2.4f);
        return t;
    }();
    return table;
}

// GL's sRGB decode of texels (exact curve), as a table.
const std::array<float, 256>& srgb8_table() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) {
            const double c = i / 255.0;
            t[std::size_t(i)] = float(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
        }
        return t;
    }();
    return table;
}

glm::vec3 shade_blinn_phong(const gpu::FrameBlock& f, const glm::vec3& albedo, const glm::vec3& n,
                            const glm::vec3& to_eye) {
    glm::vec3 color = glm::vec3(f.ambient) * albedo;
    for (std::uint32_t i = 0; i < SFFD_MAX_LIGHTS && i < f.counts.y; ++i) {
        const glm::vec3 l(f.light_dir[i]);
        const float ndl = std::max(glm::dot(n, l), 0.0f);
        const glm::vec3 h = glm::normalize(l + to_eye);
        const float spec =
            ndl > 0.0f ? std::exp2(f.material.y * std::log2(std::max(glm::dot(n, h), 1e-8f))) * f.material.x
                       : 0.0f;
        color += glm::vec3(f.light_color[i]) * (albedo * ndl + glm::vec3(spec));
    }
    return color;
}

// blinn_phong_factors of lighting.glsl: colour = albedo * diffuse + specular.
void blinn_phong_factors(const gpu::FrameBlock& f, const glm::vec3& n, const glm::vec3& to_eye,
                         glm::vec3& diffuse, glm::vec3& specular) {
    diffuse = glm::vec3(f.ambient);
    specular = glm::vec3(0.0f);
    for (std::uint32_t i = 0; i < SFFD_MAX_LIGHTS && i < f.counts.y; ++i) {
        const glm::vec3 l(f.light_dir[i]);
        const float ndl = std::max(glm::dot(n, l), 0.0f);
        const glm::vec3 h = glm::normalize(l + to_eye);
        const float spec =
            ndl > 0.0f ? std::exp2(f.material.y * std::log2(std::max(glm::dot(n, h), 1e-8f))) * f.material.x
                       : 0.0f;
        diffuse += glm::vec3(f.light_color[i]) * ndl;
        specular += glm::vec3(f.light_color[i]) * spec;
    }
}

struct SplatView {
    glm::vec3 c, u, v, shading_n;
    float r;
};

}  // namespace

glm::vec3 ellipse_sprite(const gpu::FrameBlock& f, const glm::vec3& c, const glm::vec3& u,
                         const glm::vec3& v) {
    const float near_plane = f.projection[3][2] / (f.projection[2][2] - 1.0f);
    const glm::vec2 z(u.z, v.z);
    if (-c.z - glm::length(z) <= near_plane) return glm::vec3(0.0f, 0.0f, -1.0f);
    const float q = glm::dot(z, z) - c.z * c.z;
    const glm::vec2 x0 = glm::vec2(f.projection[0][0] * c.x, f.projection[1][1] * c.y) / -c.z;
    const glm::vec2 ax = f.projection[0][0] * glm::vec2(u.x, v.x) + x0.x * z;
    const glm::vec2 ay = f.projection[1][1] * glm::vec2(u.y, v.y) + x0.y * z;
    const glm::vec2 off = glm::vec2(glm::dot(ax, z), glm::dot(ay, z)) / -q;
    const glm::vec2 half_extent = glm::sqrt(off * off + glm::vec2(glm::dot(ax, ax), glm::dot(ay, ay)) / -q);
    return glm::vec3(x0 + off, std::max(half_extent.x * f.viewport.x, half_extent.y * f.viewport.y));
}

void cull_splats_cpu(std::span<const gpu::GpuSplat> splats, const gpu::FrameBlock& f,
                     const TexelView& texture, CpuCullResult& out, const MarksView& marks) {
    const std::size_t n = splats.size();
    const std::size_t blocks = (n + block_splats - 1) / block_splats;
    out.block = block_splats;
    if (out.records.size() < n) out.records.resize(n);
    if (out.quads.size() < n) out.quads.resize(n);
    out.record_counts.assign(blocks, 0u);
    out.quad_counts.assign(blocks, 0u);
    out.flat_counts.assign(blocks, 0u);
    out.block_pixels.assign(blocks, glm::vec4(1e30f, 1e30f, -1e30f, -1e30f));

    const glm::mat3 mv3(f.model_view), nv3(f.normal_view), v2w3(f.view_to_world);
    const bool culling = f.params.z != 0.0f,
               textured = f.params.w != 0.0f && texture.rgba8 && texture.width > 0 && texture.height > 0;
    const bool lit = f.counts.w == 1u;
    const float p00 = f.projection[0][0], p11 = f.projection[1][1];
    const float near_plane = f.projection[3][2] / (f.projection[2][2] - 1.0f);
    const float far_plane = f.projection[3][2] / (f.projection[2][2] + 1.0f);
    const float side_x = 1.0f / std::sqrt(p00 * p00 + 1.0f), side_y = 1.0f / std::sqrt(p11 * p11 + 1.0f);
    const std::array<float, 256>& splat_lut = splat_srgb_table();
    const std::array<float, 256>& texel_lut = srgb8_table();
    // point_mark() of point_marks.glsl: element i's mark, the default without marks.
    const std::uint32_t marks_mode = f.counts.z;
    const bool marked = (marks_mode & SFFD_MARKS_PRESENT) != 0;
    const bool indexed = (marks_mode & SFFD_MARKS_INDEXED) != 0;
    const bool texel_colours = (marks_mode & SFFD_MARKS_TEXEL) != 0 && marks.texels.rgba8 &&
                               marks.texels.width > 0 && marks.texels.height > 0;
    const auto mark_of = [&](std::size_t i) -> std::uint16_t {
        if (!marked) return gfx::kDefaultPointMark;
        std::size_t j = i;
        if (indexed) {
            if (!marks.index || i >= marks.index_count) return gfx::kDefaultPointMark;
            j = marks.index[i];
        }
        if (j >= marks.points) return gfx::kDefaultPointMark;
        return gfx::pack_point_mark(marks.flags ? marks.flags[j] : 0,
                                    marks.weights ? marks.weights[j] : 1.0f);
    };
    const bool flat_all = textured && texture.pyramid;
    const bool flat_ok = textured && (texture.uniform_radius || flat_all);
    if (flat_ok && out.flat_records.size() < n) out.flat_records.resize(n);

    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1), [&](const tbb::blocked_range<
                                                                         std::size_t>& range) {
        for (std::size_t b = range.begin(); b != range.end(); ++b) {
            const std::size_t begin = b * block_splats, end = std::min(n, begin + block_splats);
            SplatRecord* records = out.records.data() + begin;
            std::uint32_t* quads = out.quads.data() + begin;
            SplatRecord* flat_records = flat_ok ? out.flat_records.data() + begin : nullptr;
            std::uint32_t kept = 0, kept_quads = 0, kept_flat = 0;
            glm::vec2 lo(1e30f), hi(-1e30f);
            for (std::size_t i = begin; i < end; ++i) {
                const gpu::GpuSplat& s = splats[i];
                const std::uint16_t mark = mark_of(i);
                if (gfx::mark_gone(mark)) continue;  // hidden or deleted: never drawn
                // Back face from centre and normal only (a flipped splat, normal.w == 0, is two-sided).
                const glm::vec3 c = glm::vec3(f.model_view * glm::vec4(xyz(s.center), 1.0f));
                if (!all_finite(xyz(s.center)) || !all_finite(xyz(s.normal)) || !all_finite(c))
                    continue;  // nothing to draw
                const bool back = s.normal[3] != 0.0f && glm::dot(nv3 * xyz(s.normal), c) > 0.0f;
                if (back && culling) continue;
                const glm::vec3 u = mv3 * xyz(s.axis_u), v = mv3 * xyz(s.axis_v);
                if (!all_finite(xyz(s.axis_u)) || !all_finite(xyz(s.axis_v)) || !all_finite(u) ||
                    !all_finite(v))
                    continue;
                const float r = ellipse_max_radius(u, v);
                const glm::vec3 cr = glm::cross(u, v);
                if (r <= 0.0f || glm::dot(cr, cr) <= 1e-12f * r * r * r * r) continue;  // degenerate
                if (culling) {
                    const float depth = -c.z;
                    if (depth + r < near_plane || depth - r > far_plane ||
                        (depth - p00 * std::abs(c.x)) * side_x < -r ||
                        (depth - p11 * std::abs(c.y)) * side_y < -r)
                        continue;
                }
                const glm::vec3 box = ellipse_sprite(f, c, u, v);
                if (box.z < 0.0f || box.z > f.params.y || std::abs(box.x) > 1.0f || std::abs(box.y) > 1.0f) {
                    quads[kept_quads++] = std::uint32_t(i);
                    continue;
                }
                {  // the sprite's square (the point's size is its side) in frame pixels, one pixel wider
                    const glm::vec2 centre((box.x + 1.0f) * 0.5f * f.viewport.x,
                                           (box.y + 1.0f) * 0.5f * f.viewport.y);
                    const float half = 0.5f * box.z + 1.0f;
                    lo = glm::min(lo, centre - half), hi = glm::max(hi, centre + half);
                }
                // splat_view + splat_raycast_setup
                SplatView o{c, u, v, glm::normalize(nv3 * xyz(s.normal)), r};
                glm::vec3 pn = cr;
                if (glm::dot(pn, o.shading_n) < 0.0f) pn = -pn;
                const glm::vec3 cu = glm::cross(o.v, pn), cv = glm::cross(pn, o.u);
                const glm::vec3 du = cu / glm::dot(cu, o.u), dv = cv / glm::dot(cv, o.v);
                SplatRecord& rec = records[kept++];
                // Seen edge-on: hidden, as splat_raycast_setup does (no infinite plane).
                const float cn = glm::dot(o.c, pn);
                const bool edge_on = std::abs(cn) <= 1e-6f * glm::length(o.c) * glm::length(pn);
                rec.plane = glm::vec4(edge_on ? glm::vec3(0.0f) : pn / cn, f.params.x * o.r);
                rec.dual_u = glm::vec4(du, glm::dot(du, o.c));
                rec.dual_v = glm::vec4(dv, glm::dot(dv, o.c));
                if (back)
                    rec.plane.x = rec.plane.y = rec.plane.z = 0.0f;  // hidden (culling off, splat_record.h)
                rec.center = glm::vec4(box.x, box.y, o.c.z, box.z);
                const glm::vec3 world_n = glm::normalize(v2w3 * o.shading_n);
                if (textured) {
                    // splat_uv_frame, splat_texture_lod; the texture is sampled per pixel (SplatRecord)
                    const glm::vec4 a = texture.uv_axes ? texture.uv_axes[i] : glm::vec4(0.0f);
                    rec.uv = glm::vec4(s.axis_u[3], s.axis_v[3], pack_halves(glm::vec2(a.x, a.y)),
                                       pack_halves(glm::vec2(a.z, a.w)));
                    const glm::vec2 scale = -o.c.z * glm::vec2(f.ray_map.x, f.ray_map.y);
                    const glm::vec2 ds =
                        scale * (glm::vec2(rec.dual_u) - glm::vec2(rec.plane) * rec.dual_u.w);
                    const glm::vec2 dq =
                        scale * (glm::vec2(rec.dual_v) - glm::vec2(rec.plane) * rec.dual_v.w);
                    const glm::vec2 size(float(texture.width), float(texture.height));
                    const glm::vec2 ddx = (ds.x * glm::vec2(a.x, a.y) + dq.x * glm::vec2(a.z, a.w)) * size;
                    const glm::vec2 ddy = (ds.y * glm::vec2(a.x, a.y) + dq.y * glm::vec2(a.z, a.w)) * size;
                    const float lod =
                        0.5f * std::log2(std::max(std::max(glm::dot(ddx, ddx), glm::dot(ddy, ddy)), 1e-20f));
                    if (flat_ok && lod < 16.0f && std::abs(rec.uv.x) < 1e6f &&
                        std::abs(rec.uv.y) < 1e6f) {  // (false for NaN)
                        // One colour under the whole footprint (|s|, |t| <= 1) and the filter's reach (two
                        // texels of the coarser level, in level-0 texels), or a reduced preview's one
                        // lookup at the centre (TexelView::pyramid): draw it flat
                        // (CpuCullResult::flat_records).
                        bool one_colour = flat_all;
                        glm::vec3 color(0.0f);
                        if (flat_all) {  // the level the preview samples (round(lod), at least 0)
                            color = sample_texture(texture, glm::vec2(rec.uv),
                                                   int(std::lround(std::max(lod, 0.0f))));
                        } else {
                            const float reach = (std::abs(a.x) + std::abs(a.z)) * size.x,
                                        reach_v = (std::abs(a.y) + std::abs(a.w)) * size.y;
                            const float margin = 2.0f * std::exp2(std::ceil(std::max(lod, 0.0f))) + 1.0f;
                            const float fu = rec.uv.x - std::floor(rec.uv.x);
                            const int tx = std::min(int(fu * size.x), texture.width - 1);
                            const int ty =
                                std::clamp(int(std::floor(rec.uv.y * size.y)), 0, texture.height - 1);
                            const std::size_t texel =
                                std::size_t(ty) * std::size_t(texture.width) + std::size_t(tx);
                            one_colour =
                                std::max(reach, reach_v) + margin < float(texture.uniform_radius[texel]);
                            const std::uint8_t* p = texture.rgba8 + 4 * texel;
                            if (one_colour)
                                color = glm::vec3(texel_lut[p[0]], texel_lut[p[1]], texel_lut[p[2]]);
                        }
                        if (one_colour) {
                            if (lit)
                                color = shade_blinn_phong(f, color, world_n, -glm::normalize(v2w3 * o.c));
                            SplatRecord& flat = flat_records[kept_flat++];
                            flat = rec;
                            flat.plane.w = f.params.x * o.r;
                            flat.normal = glm::vec4(world_n, pack_color(color));
                            flat.uv = glm::vec4(0.0f);
                            --kept;  // the slot in `records` is reused
                            continue;
                        }
                    }
                    if (lit) {  // preview: lighting factors (splat_light_factors), the mip level in center.z
                        glm::vec3 diffuse, specular;
                        blinn_phong_factors(f, world_n, -glm::normalize(v2w3 * o.c), diffuse, specular);
                        rec.normal = glm::vec4(world_n, pack_color(diffuse * 0.25f));  // pack_light
                        rec.plane.w = pack_color(specular * 0.25f);
                        rec.center.z = lod;
                    } else {  // HQ: the colour slot carries the mip level
                        rec.normal = glm::vec4(world_n, lod);
                    }
                    continue;
                }
                // splat_color
                glm::vec3 color;
                if (texel_colours) {  // splat_color: the texel at the centre, as textureLod(uv, 0)
                    color = sample_texture(marks.texels, glm::vec2(s.axis_u[3], s.axis_v[3]), 0);
                } else {
                    const std::uint32_t bits = std::bit_cast<std::uint32_t>(s.center[3]);
                    color = glm::vec3(splat_lut[bits & 255u], splat_lut[(bits >> 8) & 255u],
                                      splat_lut[(bits >> 16) & 255u]) *
                            glm::vec3(f.base_color);
                }
                color = gfx::mark_overlay(color, mark, marks_mode);
                if (lit) color = shade_blinn_phong(f, color, world_n, -glm::normalize(v2w3 * o.c));
                rec.normal = glm::vec4(world_n, pack_color(color));
                rec.uv = glm::vec4(0.0f);
            }
            out.record_counts[b] = kept;
            out.block_pixels[b] = glm::vec4(lo, hi);
            out.quad_counts[b] = kept_quads;
            out.flat_counts[b] = kept_flat;
        }
    });
    out.visible_records = out.visible_quads = out.visible_flat = 0;
    out.pixels_lo = glm::vec2(1e30f), out.pixels_hi = glm::vec2(-1e30f);
    for (std::size_t b = 0; b < blocks; ++b) {
        out.visible_records += out.record_counts[b], out.visible_quads += out.quad_counts[b],
            out.visible_flat += out.flat_counts[b];
        out.pixels_lo = glm::min(out.pixels_lo, glm::vec2(out.block_pixels[b]));
        out.pixels_hi = glm::max(out.pixels_hi, glm::vec2(out.block_pixels[b].z, out.block_pixels[b].w));
    }
    out.pixels_bounded = out.visible_quads == 0;
}

TexturePyramid build_texture_pyramid(const std::uint8_t* rgba8, int width, int height) {
    TexturePyramid p;
    if (!rgba8 || width <= 0 || height <= 0) return p;
    const std::array<float, 256>& lut = srgb8_table();
    const std::uint8_t* above = rgba8;
    glm::ivec2 size(width, height);
    while (size.x > 1 || size.y > 1) {
        const glm::ivec2 next = next_level_size(size);
        std::vector<std::uint8_t> level(std::size_t(next.x) * std::size_t(next.y) * 4);
        const auto texel = [&](int tx, int ty) {
            const std::uint8_t* t = above + 4 * (std::size_t(ty) * std::size_t(size.x) + std::size_t(tx));
            return glm::vec4(lut[t[0]], lut[t[1]], lut[t[2]], float(t[3]) / 255.0f);
        };
        for (int y = 0; y < next.y; ++y)
            for (int x = 0; x < next.x; ++x) {
                const glm::vec4 mean = mean_2x2(x, y, size.x, size.y, texel);
                std::uint8_t* o = &level[4 * (std::size_t(y) * std::size_t(next.x) + std::size_t(x))];
                for (int c = 0; c < 3; ++c) o[c] = gfx::encode_srgb8(mean[c]);
                o[3] = std::uint8_t(std::lround(std::clamp(mean.w, 0.0f, 1.0f) * 255.0f));
            }
        p.levels.push_back(std::move(level));
        p.sizes.push_back(next);
        above = p.levels.back().data();
        size = next;
    }
    return p;
}

glm::vec3 sample_texture(const TexelView& t, glm::vec2 uv, int level) {
    const std::array<float, 256>& lut = srgb8_table();
    const int levels = t.pyramid ? int(t.pyramid->levels.size()) : 0;
    level = std::clamp(level, 0, levels);
    const std::uint8_t* texels = level == 0 ? t.rgba8 : t.pyramid->levels[std::size_t(level - 1)].data();
    const glm::ivec2 size =
        level == 0 ? glm::ivec2(t.width, t.height) : t.pyramid->sizes[std::size_t(level - 1)];
    const BilinearTaps<float> b = bilinear_taps(uv.x, uv.y, size.x, size.y);
    auto texel = [&](int tx, int ty) {
        const std::uint8_t* p = texels + 4 * (std::size_t(ty) * std::size_t(size.x) + std::size_t(tx));
        return glm::vec3(lut[p[0]], lut[p[1]], lut[p[2]]);
    };
    return glm::mix(glm::mix(texel(b.x0, b.y0), texel(b.x1, b.y0), b.ax),
                    glm::mix(texel(b.x0, b.y1), texel(b.x1, b.y1), b.ax), b.ay);
}

std::vector<std::uint16_t> uniform_texel_radius(const std::uint8_t* rgba8, int w, int h) {
    const std::size_t n = std::size_t(std::max(w, 0)) * std::size_t(std::max(h, 0));
    std::vector<std::uint16_t> d(n, 0);
    if (!rgba8 || n == 0) return d;
    auto px = [&](int x, int y) {
        std::uint32_t v;
        std::memcpy(&v, rgba8 + 4 * (std::size_t(y) * std::size_t(w) + std::size_t(x)), 4);
        return v;
    };
    constexpr std::uint16_t far = 65535;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            bool edge = x == 0 || y == 0 || x == w - 1 || y == h - 1;
            for (int dy = -1; dy <= 1 && !edge; ++dy)
                for (int dx = -1; dx <= 1 && !edge; ++dx) edge = px(x + dx, y + dy) != px(x, y);
            d[std::size_t(y) * std::size_t(w) + std::size_t(x)] = edge ? 0 : far;
        }
    // Two chamfer passes with unit weights over the 8-neighbourhood: exact Chebyshev distances.
    auto at = [&](int x, int y) -> std::uint16_t& {
        return d[std::size_t(y) * std::size_t(w) + std::size_t(x)];
    };
    auto relax = [&](int x, int y, int nx, int ny) {
        if (nx < 0 || ny < 0 || nx >= w || ny >= h) return;
        at(x, y) = std::uint16_t(std::min<int>(at(x, y), at(nx, ny) + 1));
    };
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            relax(x, y, x - 1, y), relax(x, y, x - 1, y - 1), relax(x, y, x, y - 1),
                relax(x, y, x + 1, y - 1);
    for (int y = h - 1; y >= 0; --y)
        for (int x = w - 1; x >= 0; --x)
            relax(x, y, x + 1, y), relax(x, y, x + 1, y + 1), relax(x, y, x, y + 1),
                relax(x, y, x - 1, y + 1);
    return d;
}

}  // namespace sffd::render
