// CPU rasteriser of the splats' sprites (cpu_raster.h).
#include "systems/splat_render/cpu_raster.h"

#include "systems/splat_render/texture_lookup.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include <glm/gtc/packing.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace sffd::render {

namespace {

// Rows per band: the unit of parallel work. A band holds every sprite that reaches it, in draw order, so
// the first of equal depths wins inside each band as it does in GL.
constexpr int band_rows = 16;

std::uint64_t pack_rgba16f(glm::vec4 c) {
    return std::uint64_t(glm::packHalf1x16(c.x)) | std::uint64_t(glm::packHalf1x16(c.y)) << 16 |
           std::uint64_t(glm::packHalf1x16(c.z)) << 32 | std::uint64_t(glm::packHalf1x16(c.w)) << 48;
}

// The pixels [lo, hi) whose centres p + 0.5 satisfy centre - half <= p + 0.5 < centre + half.
void covered(float centre, float half, int limit, int& lo, int& hi) {
    const float a = std::ceil(centre - half - 0.5f), b = std::ceil(centre + half - 0.5f);
    lo = int(std::clamp(a, 0.0f, float(limit)));
    hi = int(std::clamp(b, 0.0f, float(limit)));
}

struct Depths {
    float ray_x, ray_y, ray_dx,
        ray_dy;      // ray_map: ray = ((x + 0.5) ray_x + ray_dx, (y + 0.5) ray_y + ray_dy, -1)
    float p32, p22;  // window_depth_inv's projection terms
};

// What a band writes: the preview's colour and depth (and aux), or the HQ visibility pass's depth only.
enum class Write { color, color_aux, visibility, attribute };

// textureLod() of a mipmapped texture filtered GL_LINEAR_MIPMAP_LINEAR (magnified: GL_LINEAR at level 0):
// bilinear in the two levels around lod, mixed by its fraction; past the last level, that level.
glm::vec3 sample_texture_lod(const TexelView& t, glm::vec2 uv, float lod) {
    const LevelBlend<float> b = trilinear_levels(lod, t.pyramid ? int(t.pyramid->levels.size()) : 0);
    const glm::vec3 lo = sample_texture(t, uv, b.lo);
    return b.hi == b.lo ? lo : glm::mix(lo, sample_texture(t, uv, b.hi), b.f);
}

// GCC 12's AVX-512 intrinsics (sqrt, min, max) pass _mm512_undefined_ps() as their unused merge source,
// which -Wmaybe-uninitialized reports at every use.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// Every sprite of one band (rows [row0, row1) of the frame) into the image.
template <Write Mode>
void draw_band(const CpuRasterImage& img, const std::uint32_t* list, std::size_t n, int row0, int row1,
               const Depths& f, std::uint64_t* color, float* depth, glm::vec4* aux,
               glm::vec4* accum_color = nullptr, glm::vec4* accum_normal = nullptr) {
    const int rx = img.rect.x, ry = img.rect.y, stride = img.rect.z;
    for (std::size_t k = 0; k < n; ++k) {
        const CpuSprite& s = img.setup[list[k]];
        const int y0 = std::max(s.y0, row0), y1 = std::min(s.y1, row1);
        for (int y = y0; y < y1; ++y) {
            // raycast_splat(): inv_t = dot(plane, ray), s = t dot(dual_u, ray) - dual_u.w (likewise q).
            const float ray_y = (float(y) + 0.5f) * f.ray_y + f.ray_dy;
            const float plane_row = s.plane.y * ray_y - s.plane.z;
            const float u_row = s.dual_u.y * ray_y - s.dual_u.z, v_row = s.dual_v.y * ray_y - s.dual_v.z;
            float* drow = depth + std::size_t(y - ry) * std::size_t(stride) - rx;
            std::uint64_t* crow = color ? color + std::size_t(y - ry) * std::size_t(stride) - rx : nullptr;
            glm::vec4* arow =
                Mode == Write::color_aux ? aux + std::size_t(y - ry) * std::size_t(stride) - rx : nullptr;
            glm::vec4* acrow = Mode == Write::attribute
                                   ? accum_color + std::size_t(y - ry) * std::size_t(stride) - rx
                                   : nullptr;
            glm::vec4* anrow = Mode == Write::attribute
                                   ? accum_normal + std::size_t(y - ry) * std::size_t(stride) - rx
                                   : nullptr;
            const float ray_y2 = ray_y * ray_y + 1.0f;
            // One pixel of the row: after the ray cast, its depth test and writes.
            auto write = [&](int x, float inv_t, float t, float su, float sv, float ray_x) {
                if constexpr (Mode == Write::visibility) {
                    // visibility.frag: the hit pushed back by eps (plane.w) along the unit view ray.
                    const float pushed = t + s.plane.w / std::sqrt(ray_x * ray_x + ray_y2);
                    const float d = std::clamp(0.5f * (f.p32 / pushed - f.p22) + 0.5f, 0.0f, 1.0f);
                    if (d < drow[x]) drow[x] = d;
                    return;
                }
                const float d = std::clamp(0.5f * (f.p32 * inv_t - f.p22) + 0.5f, 0.0f, 1.0f);
                if constexpr (Mode == Write::attribute) {
                    if (!(d <= drow[x])) return;  // LEQUAL against the visibility pass, no depth write
                    const float r2 = su * su + sv * sv, w = (1.0f - r2) * (1.0f - r2) + 1e-6f;
                    glm::vec3 albedo = s.albedo;
                    if (s.texture)
                        albedo = sample_texture_lod(
                            *s.texture,
                            s.uv + su * glm::vec2(s.uv_axes) + sv * glm::vec2(s.uv_axes.z, s.uv_axes.w),
                            s.lod);
                    acrow[x] += glm::vec4(w * albedo, w);
                    anrow[x] += glm::vec4(w * s.normal, w * t);
                    return;
                }
                if (!(d < drow[x])) return;
                drow[x] = d;
                if (s.texture) {
                    const glm::vec2 uv =
                        s.uv + su * glm::vec2(s.uv_axes) + sv * glm::vec2(s.uv_axes.z, s.uv_axes.w);
                    const glm::vec3 albedo = sample_texture(*s.texture, uv, s.level);
                    crow[x] = pack_rgba16f(glm::vec4(albedo * s.diffuse + s.specular, 1.0f));
                } else {
                    crow[x] = s.color;
                }
                if constexpr (Mode == Write::color_aux) arow[x] = glm::vec4(s.normal, t);
            };
#if defined(__AVX512F__)
            // Sixteen pixels of the row at once, the ray cast's rejections as a lane mask; the pixels that
            // pass are written one by one (few: a sprite row is a few pixels wide).
            const __m512 lanes = _mm512_setr_ps(0.5f, 1.5f, 2.5f, 3.5f, 4.5f, 5.5f, 6.5f, 7.5f, 8.5f, 9.5f,
                                                10.5f, 11.5f, 12.5f, 13.5f, 14.5f, 15.5f);
            for (int x0 = s.x0; x0 < s.x1; x0 += 16) {
                const int count = std::min(16, s.x1 - x0);
                __mmask16 m = __mmask16(count == 16 ? 0xffffu : (1u << count) - 1u);
                const __m512 ray_x = _mm512_add_ps(
                    _mm512_mul_ps(_mm512_add_ps(_mm512_set1_ps(float(x0)), lanes), _mm512_set1_ps(f.ray_x)),
                    _mm512_set1_ps(f.ray_dx));
                const __m512 inv_t =
                    _mm512_add_ps(_mm512_mul_ps(_mm512_set1_ps(s.plane.x), ray_x), _mm512_set1_ps(plane_row));
                m &= _mm512_cmp_ps_mask(inv_t, _mm512_setzero_ps(), _CMP_GT_OQ);
                if (!m) continue;
                const __m512 t = _mm512_div_ps(_mm512_set1_ps(1.0f), inv_t);
                const __m512 su = _mm512_sub_ps(
                    _mm512_mul_ps(t, _mm512_add_ps(_mm512_mul_ps(_mm512_set1_ps(s.dual_u.x), ray_x),
                                                   _mm512_set1_ps(u_row))),
                    _mm512_set1_ps(s.dual_u.w));
                const __m512 sv = _mm512_sub_ps(
                    _mm512_mul_ps(t, _mm512_add_ps(_mm512_mul_ps(_mm512_set1_ps(s.dual_v.x), ray_x),
                                                   _mm512_set1_ps(v_row))),
                    _mm512_set1_ps(s.dual_v.w));
                const __m512 r2 = _mm512_add_ps(_mm512_mul_ps(su, su), _mm512_mul_ps(sv, sv));
                m &= _mm512_cmp_ps_mask(r2, _mm512_set1_ps(1.0f), _CMP_LE_OQ);
                if (!m) continue;
                // Depth test and writes in the vector where no per-pixel texture lookup or aux output is
                // needed: the visibility pass and flat-coloured sprites.
                if (Mode != Write::color_aux && Mode != Write::attribute && !s.texture) {
                    __m512 d;
                    if constexpr (Mode == Write::visibility) {
                        const __m512 len = _mm512_sqrt_ps(
                            _mm512_add_ps(_mm512_mul_ps(ray_x, ray_x), _mm512_set1_ps(ray_y2)));
                        const __m512 pushed = _mm512_add_ps(t, _mm512_div_ps(_mm512_set1_ps(s.plane.w), len));
                        d = _mm512_div_ps(_mm512_set1_ps(f.p32), pushed);
                    } else {
                        d = _mm512_mul_ps(_mm512_set1_ps(f.p32), inv_t);
                    }
                    d = _mm512_add_ps(
                        _mm512_mul_ps(_mm512_set1_ps(0.5f), _mm512_sub_ps(d, _mm512_set1_ps(f.p22))),
                        _mm512_set1_ps(0.5f));
                    d = _mm512_min_ps(_mm512_max_ps(d, _mm512_setzero_ps()), _mm512_set1_ps(1.0f));
                    const __m512 old = _mm512_maskz_loadu_ps(m, drow + x0);
                    m &= _mm512_cmp_ps_mask(d, old, _CMP_LT_OQ);
                    _mm512_mask_storeu_ps(drow + x0, m, d);
                    if constexpr (Mode == Write::color) {
                        const __m512i c = _mm512_set1_epi64(std::int64_t(s.color));
                        _mm512_mask_storeu_epi64(crow + x0, __mmask8(m), c);
                        _mm512_mask_storeu_epi64(crow + x0 + 8, __mmask8(m >> 8), c);
                    }
                    continue;
                }
                alignas(64) float l_inv_t[16], l_t[16], l_su[16], l_sv[16], l_ray_x[16];
                _mm512_store_ps(l_inv_t, inv_t), _mm512_store_ps(l_t, t), _mm512_store_ps(l_su, su);
                _mm512_store_ps(l_sv, sv), _mm512_store_ps(l_ray_x, ray_x);
                for (unsigned bits = m; bits; bits &= bits - 1) {
                    const int l = __builtin_ctz(bits);
                    write(x0 + l, l_inv_t[l], l_t[l], l_su[l], l_sv[l], l_ray_x[l]);
                }
            }
#else
            for (int x = s.x0; x < s.x1; ++x) {
                const float ray_x = (float(x) + 0.5f) * f.ray_x + f.ray_dx;
                const float inv_t = s.plane.x * ray_x + plane_row;
                if (!(inv_t > 0.0f)) continue;
                const float t = 1.0f / inv_t;
                const float su = t * (s.dual_u.x * ray_x + u_row) - s.dual_u.w;
                const float sv = t * (s.dual_v.x * ray_x + v_row) - s.dual_v.w;
                if (su * su + sv * sv > 1.0f) continue;
                write(x, inv_t, t, su, sv, ray_x);
            }
#endif
        }
    }
}

#pragma GCC diagnostic pop

}  // namespace

glm::vec2 unpack_halves(float packed) {
    std::uint32_t stored;
    std::memcpy(&stored, &packed, sizeof stored);
    const std::uint32_t bits = (stored & 0x7fffffu) + (((stored >> 23) - 1u) << 23);
    const std::uint32_t halves = ((bits & 0x7fffu) << 1) | ((bits >> 15) << 17);
    return {glm::unpackHalf1x16(std::uint16_t(halves)), glm::unpackHalf1x16(std::uint16_t(halves >> 16))};
}

glm::vec3 unpack_color(float packed) {
    std::uint32_t stored;
    std::memcpy(&stored, &packed, sizeof stored);
    const std::uint32_t bits = (stored & 0x7fffffu) + (((stored >> 23) - 1u) << 23);
    const glm::vec3 c =
        glm::vec3(float(bits & 1023u), float((bits >> 10) & 1023u), float((bits >> 20) & 1023u)) *
        (1.0f / 1023.0f);
    return c * c;
}

void rasterize_sprites_cpu(std::span<const SpriteRun> runs, const gpu::FrameBlock& frame, int width,
                           int height, glm::vec4 background, PointSizeRange sizes, SpritePass pass, bool aux,
                           CpuRasterImage& out) {
    const bool visibility = pass != SpritePass::preview, hq = pass == SpritePass::hq;
    aux = aux && !visibility;
    std::size_t n = 0;
    std::vector<std::size_t> run_first;
    run_first.reserve(runs.size());
    for (const SpriteRun& r : runs) run_first.push_back(n), n += r.count;
    out.setup.resize(n);
    out.sprites = 0;
    // Each sprite's covered pixels and unpacked values, in parallel (run by run).
    for (std::size_t r = 0; r < runs.size(); ++r) {
        const SpriteRun run = runs[r];
        CpuSprite* setup = out.setup.data() + run_first[r];
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, run.count, 2048),
                          [&](const tbb::blocked_range<std::size_t>& range) {
                              for (std::size_t i = range.begin(); i != range.end(); ++i) {
                                  const SplatRecord& rec = run.records[i];
                                  CpuSprite& s = setup[i];
                                  // The hidden mark (plane 0) discards every fragment: nothing to draw.
                                  if (rec.plane.x == 0.0f && rec.plane.y == 0.0f && rec.plane.z == 0.0f) {
                                      s.x0 = s.x1 = s.y0 = s.y1 = 0;
                                      continue;
                                  }
                                  const float side = std::clamp(rec.center.w, sizes.min, sizes.max);
                                  const float cx = (rec.center.x + 1.0f) * 0.5f * float(width);
                                  const float cy = (rec.center.y + 1.0f) * 0.5f * float(height);
                                  covered(cx, 0.5f * side, width, s.x0, s.x1);
                                  covered(cy, 0.5f * side, height, s.y0, s.y1);
                                  s.plane = rec.plane, s.dual_u = rec.dual_u, s.dual_v = rec.dual_v;
                                  s.normal = glm::vec3(rec.normal);
                                  s.texture = run.texture;
                                  if (hq) {  // splat.vert's attribute set-up: albedo or uv frame, level
                                      if (!run.texture) {
                                          s.albedo = unpack_color(rec.normal.w);
                                          continue;
                                      }
                                      s.uv = glm::vec2(rec.uv);
                                      s.uv_axes = glm::vec4(unpack_halves(rec.uv.z), unpack_halves(rec.uv.w));
                                      s.lod = rec.normal.w;
                                      continue;
                                  }
                                  if (visibility) continue;
                                  if (!run.texture) {
                                      s.color = pack_rgba16f(glm::vec4(unpack_color(rec.normal.w), 1.0f));
                                      continue;
                                  }
                                  // splat.vert's preview set-up of a textured record: the level rounded,
                                  // the factors unpacked (unpack_light: a quarter scale).
                                  s.uv = glm::vec2(rec.uv);
                                  s.uv_axes = glm::vec4(unpack_halves(rec.uv.z), unpack_halves(rec.uv.w));
                                  s.level = int(std::round(rec.center.z));
                                  s.diffuse = unpack_color(rec.normal.w) * 4.0f;
                                  s.specular = unpack_color(rec.plane.w) * 4.0f;
                              }
                          });
    }
    // Bands: the sprites that reach each, in draw order; the bounds of every covered pixel.
    const int bands = (height + band_rows - 1) / band_rows;
    out.bin_first.assign(std::size_t(bands) + 1, 0u);
    glm::ivec2 lo(width, height), hi(0, 0);
    for (std::size_t i = 0; i < n; ++i) {
        const CpuSprite& s = out.setup[i];
        if (s.x0 >= s.x1 || s.y0 >= s.y1) continue;
        ++out.sprites;
        lo = glm::min(lo, glm::ivec2(s.x0, s.y0)), hi = glm::max(hi, glm::ivec2(s.x1, s.y1));
        for (int b = s.y0 / band_rows; b <= (s.y1 - 1) / band_rows; ++b) ++out.bin_first[std::size_t(b) + 1];
    }
    for (int b = 0; b < bands; ++b) out.bin_first[std::size_t(b) + 1] += out.bin_first[std::size_t(b)];
    out.bins.resize(out.bin_first[std::size_t(bands)]);
    {
        std::vector<std::uint32_t> fill(out.bin_first.begin(), out.bin_first.end() - 1);
        for (std::size_t i = 0; i < n; ++i) {
            const CpuSprite& s = out.setup[i];
            if (s.x0 >= s.x1 || s.y0 >= s.y1) continue;
            for (int b = s.y0 / band_rows; b <= (s.y1 - 1) / band_rows; ++b)
                out.bins[fill[std::size_t(b)]++] = std::uint32_t(i);
        }
    }
    if (out.sprites == 0) {
        out.rect = glm::ivec4(0);
        out.color.clear(), out.depth.clear(), out.aux.clear();
        out.accum_color.clear(), out.accum_normal.clear();
        return;
    }
    out.rect = glm::ivec4(lo, hi - lo);
    const std::size_t pixels = std::size_t(out.rect.z) * std::size_t(out.rect.w);
    out.depth.resize(pixels);
    if (visibility) out.color.clear();
    else out.color.resize(pixels);
    if (aux) out.aux.resize(pixels);
    else out.aux.clear();
    if (hq) out.accum_color.resize(pixels), out.accum_normal.resize(pixels);
    else out.accum_color.clear(), out.accum_normal.clear();
    const std::uint64_t clear_color = pack_rgba16f(background);
    const Depths f{frame.ray_map.x, frame.ray_map.y,        frame.ray_map.z,
                   frame.ray_map.w, frame.projection[3][2], frame.projection[2][2]};
    tbb::parallel_for(
        tbb::blocked_range<int>(lo.y / band_rows, (hi.y - 1) / band_rows + 1, 1),
        [&](const tbb::blocked_range<int>& range) {
            for (int b = range.begin(); b != range.end(); ++b) {
                const int row0 = std::max(b * band_rows, lo.y);
                const int row1 = std::min((b + 1) * band_rows, hi.y);
                const std::size_t first = std::size_t(row0 - lo.y) * std::size_t(out.rect.z);
                const std::size_t count = std::size_t(row1 - row0) * std::size_t(out.rect.z);
                if (!visibility) std::fill_n(out.color.data() + first, count, clear_color);
                std::fill_n(out.depth.data() + first, count, 1.0f);
                const std::uint32_t* list = out.bins.data() + out.bin_first[std::size_t(b)];
                const std::size_t listed = out.bin_first[std::size_t(b) + 1] - out.bin_first[std::size_t(b)];
                if (visibility) {
                    draw_band<Write::visibility>(out, list, listed, row0, row1, f, nullptr, out.depth.data(),
                                                 nullptr);
                    // The band's visible depths are final: its attribute pass can run at once.
                    if (hq) {
                        std::fill_n(out.accum_color.data() + first, count, glm::vec4(0.0f));
                        std::fill_n(out.accum_normal.data() + first, count, glm::vec4(0.0f));
                        draw_band<Write::attribute>(out, list, listed, row0, row1, f, nullptr,
                                                    out.depth.data(), nullptr, out.accum_color.data(),
                                                    out.accum_normal.data());
                    }
                } else if (aux) {
                    std::fill_n(out.aux.data() + first, count, glm::vec4(0.0f, 0.0f, 0.0f, -1.0f));
                    draw_band<Write::color_aux>(out, list, listed, row0, row1, f, out.color.data(),
                                                out.depth.data(), out.aux.data());
                } else {
                    draw_band<Write::color>(out, list, listed, row0, row1, f, out.color.data(),
                                            out.depth.data(), nullptr);
                }
            }
        });
}

}  // namespace sffd::render
