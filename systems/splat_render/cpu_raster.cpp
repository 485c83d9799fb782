// CPU rasteriser of the splats' sprites (cpu_raster.h). Compiled once per SIMD target (runtime/simd/simd.h),
// one dispatch per call: the set-up, the binning and the bands, whose ray casts run a sprite's row a vector
// of pixels at a time. Every target draws the same image, bit for bit: each lane runs the sequence of IEEE
// operations the scalar code runs (separate multiplies and adds: sse4 and the scalar target have no FMA,
// so none is contracted, see CMakeLists.txt), and a NaN depth fails the depth test on every target.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "systems/splat_render/cpu_raster.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include <glm/gtc/packing.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/simd/simd.h"
#include "systems/splat_render/cpu_raster.h"
#include "systems/splat_render/texture_lookup.h"

// What the set-up and every target's bands share, compiled once.
#ifndef SFFD_SPLAT_RENDER_CPU_RASTER_SHARED
#define SFFD_SPLAT_RENDER_CPU_RASTER_SHARED

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

}  // namespace

}  // namespace sffd::render

#endif  // SFFD_SPLAT_RENDER_CPU_RASTER_SHARED

HWY_BEFORE_NAMESPACE();
namespace sffd::render::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

namespace {

using DF = hn::ScalableTag<float>;
constexpr std::size_t max_lanes = hn::MaxLanes(DF());

// Whether MaskedLoad and BlendedStore of 4- and 8-byte lanes touch no lane outside the mask: AVX2's and
// AVX-512's masked moves, and the scalar target's one lane (always a pixel of the row). Highway 1.0.3's
// sse4 and neon MaskedLoad read the whole vector (sse4's with an aligned load) and neon's BlendedStore
// writes it back: past the image row's last pixel that memory is the next band's (another thread's) or
// outside the image, so there a vector that crosses the row's end goes through a copy of its pixels.
constexpr bool masked_moves = HWY_TARGET == HWY_SCALAR || (HWY_ARCH_X86 && HWY_TARGET <= HWY_AVX2);
// Whether masks are bit masks (AVX-512's mask registers, smaller than a vector) rather than vectors of
// all-ones lanes: the mask of 64-bit lanes then comes from the float lanes' mask bits through a general
// register instead of widening its lanes.
constexpr bool bit_masks = sizeof(hn::Mask<DF>) < sizeof(hn::Vec<DF>);
// Whether a vector of pixels that lies inside the image row is written whole: loaded, blended and stored,
// the lanes outside the mask written back as they were (safe: every pixel of a band's rows is its own
// thread's). Where masks are vectors the masked stores are emulated (sse4, neon) or slow (AVX2's vmaskmov
// stores on AMD's cores); AVX-512's are as fast as a store.
constexpr bool whole_vectors = !bit_masks;

// std::clamp(v, 0, 1) in every lane, a NaN kept (it then fails every depth test). x86's min and max
// return their second operand when either is NaN, so min(1, max(0, v)) is exactly std::clamp's
// `v < 0 ? 0 : v` and `1 < v ? 1 : v`; elsewhere (the scalar target's hn::Max returns the number, NEON's
// the NaN) the comparisons are written out.
template <class D>
hn::Vec<D> clamp01(D d, hn::Vec<D> v) {
    const auto zero = hn::Zero(d), one = hn::Set(d, 1.0f);
    if constexpr (HWY_ARCH_X86 && HWY_TARGET != HWY_SCALAR && HWY_TARGET != HWY_EMU128) {
        return hn::Min(one, hn::Max(zero, v));
    } else {
        v = hn::IfThenElse(hn::Lt(v, zero), zero, v);
        return hn::IfThenElse(hn::Lt(one, v), one, v);
    }
}

// The lanes of mask m (a subset of the first `count`) of the pixels at p (`count` of them there), zero
// elsewhere; `whole` (the vector lies inside the image row): every lane, read whole. Otherwise masked
// moves where they are exact, else a copy of the `count` pixels.
template <class D, typename T = hn::TFromD<D>>
hn::Vec<D> load_lanes(D d, hn::Mask<D> m, const T* p, int count, bool whole) {
    if (whole) return hn::LoadU(d, p);
    if constexpr (masked_moves) {
        (void)count;
        return hn::MaskedLoad(m, d, p);
    } else {
        alignas(64) T copy[max_lanes] = {};
        std::copy_n(p, count, copy);
        return hn::IfThenElseZero(m, hn::Load(d, copy));
    }
}
// v into the lanes of mask m of the pixels at p (as load_lanes reads them); the others keep their values.
// Written whole, the lanes outside the mask are written back as they were.
template <class D, typename T = hn::TFromD<D>>
void store_lanes(hn::Vec<D> v, hn::Mask<D> m, D d, T* p, int count, bool whole) {
    if (whole) return hn::StoreU(hn::IfThenElse(m, v, hn::LoadU(d, p)), d, p);
    if constexpr (masked_moves) {
        (void)count;
        hn::BlendedStore(v, m, d, p);
    } else {
        alignas(64) T copy[max_lanes] = {};
        std::copy_n(p, count, copy);
        hn::Store(hn::IfThenElse(m, v, hn::Load(d, copy)), d, copy);
        std::copy_n(copy, count, p);
    }
}

// The mask of 64-bit lanes (d64) holding the float lanes' mask bits from bit `first` on.
template <class D64>
hn::Mask<D64> mask_from_bits(D64 d64, std::uint64_t bits, std::size_t first) {
    std::uint8_t bytes[8];
    const std::uint64_t b = bits >> first;
    std::memcpy(bytes, &b, sizeof bytes);
    return hn::LoadMaskBits(d64, bytes);
}
// The same lanes of mask m (float lanes) as 64-bit lanes (d64, as many lanes), through the vector of
// all-ones lanes widened.
template <class D, class D64>
hn::Mask<D64> widen_mask(D d, D64 d64, hn::Mask<D> m) {
    const hn::RebindToSigned<D> di;
    const hn::Rebind<std::int64_t, D> di64;
    return hn::RebindMask(d64, hn::MaskFromVec(hn::PromoteTo(di64, hn::BitCast(di, hn::VecFromMask(d, m)))));
}

// The colour into the pixels of mask m (float lanes, a subset of the first `count`) of the 64-bit colour
// row p. Twice as wide as the floats, the colours take one 64-bit-lane vector when the floats fill at most
// half a vector (the one-lane scalar target included), else two: the lower and the upper half of the
// float lanes (the upper one stored only when the vector holds pixels there).
template <class D>
void store_color(D d, hn::Mask<D> m, std::uint64_t color, std::uint64_t* p, int count, bool whole) {
    constexpr int n = int(hn::MaxLanes(D()));
    std::uint64_t bits = 0;
    if constexpr (bit_masks) {
        std::uint8_t bytes[8] = {};
        hn::StoreMaskBits(d, m, bytes);
        std::memcpy(&bits, bytes, sizeof bits);
    }
    if constexpr (n * sizeof(std::uint64_t) <= HWY_MAX_BYTES) {
        const hn::Rebind<std::uint64_t, D> d64;
        store_lanes(hn::Set(d64, color), bit_masks ? mask_from_bits(d64, bits, 0) : widen_mask(d, d64, m),
                    d64, p, count, whole);
    } else {
        const hn::Repartition<std::uint64_t, D> d64;  // n / 2 lanes
        const auto c = hn::Set(d64, color);
        const int lo = std::min(count, n / 2), hi = count - lo;
        if constexpr (bit_masks) {
            store_lanes(c, mask_from_bits(d64, bits, 0), d64, p, lo, whole);
            if (hi > 0) store_lanes(c, mask_from_bits(d64, bits, n / 2), d64, p + n / 2, hi, whole);
        } else {
#if HWY_TARGET != HWY_SCALAR  // one lane: never here (it has no halves)
            const hn::Half<hn::RebindToSigned<D>> dih;
            const hn::Repartition<std::int64_t, D> di64;
            const auto lanes = hn::BitCast(hn::RebindToSigned<D>(), hn::VecFromMask(d, m));
            const auto widen = [&](auto half) {
                return hn::RebindMask(d64, hn::MaskFromVec(hn::PromoteTo(di64, half)));
            };
            store_lanes(c, widen(hn::LowerHalf(dih, lanes)), d64, p, lo, whole);
            if (hi > 0) store_lanes(c, widen(hn::UpperHalf(dih, lanes)), d64, p + n / 2, hi, whole);
#endif
        }
    }
}

// The rows of the image a band writes (null: not written by this pass), addressed by frame row.
struct BandImage {
    std::uint64_t* color = nullptr;
    float* depth = nullptr;
    glm::vec4 *aux = nullptr, *accum_color = nullptr, *accum_normal = nullptr;
    int rx = 0, ry = 0, stride = 0;  // the image rectangle's corner and width
    template <class T>
    T* row(T* p, int y) const {
        return p ? p + std::size_t(y - ry) * std::size_t(stride) - rx : nullptr;
    }
};

// What a pixel (x, y) that passed a sprite's ray cast and depth test writes besides its depth, as the
// pass's fragment code does: the colour (a textured sprite's looked up and lit) and the aux output, or
// the attribute sums with weight w.
template <Write Mode>
void write_pixel(const CpuSprite& s, const BandImage& img, int x, int y, float t, float su, float sv,
                 float w) {
    if constexpr (Mode == Write::attribute) {
        glm::vec3 albedo = s.albedo;
        if (s.texture)
            albedo = sample_texture_lod(
                *s.texture, s.uv + su * glm::vec2(s.uv_axes) + sv * glm::vec2(s.uv_axes.z, s.uv_axes.w),
                s.lod);
        img.row(img.accum_color, y)[x] += glm::vec4(w * albedo, w);
        img.row(img.accum_normal, y)[x] += glm::vec4(w * s.normal, w * t);
        return;
    }
    std::uint64_t& color = img.row(img.color, y)[x];
    if (s.texture) {
        const glm::vec2 uv = s.uv + su * glm::vec2(s.uv_axes) + sv * glm::vec2(s.uv_axes.z, s.uv_axes.w);
        const glm::vec3 albedo = sample_texture(*s.texture, uv, s.level);
        color = pack_rgba16f(glm::vec4(albedo * s.diffuse + s.specular, 1.0f));
    } else {
        color = s.color;
    }
    if constexpr (Mode == Write::color_aux) img.row(img.aux, y)[x] = glm::vec4(s.normal, t);
}

// Rows [y0, y1) of one sprite, in vectors of d's lanes: the ray casts and depth tests in the vector, then
// the depths stored; a flat sprite's colour too (the visibility pass has none), else each pixel that
// passed is written by write_pixel (few: a sprite row is a few pixels wide). `ray_xs`: the x component of
// every column's view ray.
template <Write Mode, bool Flat, class D>
void draw_sprite(D d, const CpuSprite& s, int y0, int y1, const Depths& f, const float* ray_xs,
                 const BandImage& img) {
    using V = hn::Vec<D>;
    using M = hn::Mask<D>;
    const int lanes = int(hn::Lanes(d));
    const int row_end = img.rx + img.stride;  // past the image row's last pixel
    const V zero = hn::Zero(d), one = hn::Set(d, 1.0f), half = hn::Set(d, 0.5f);
    const V p32 = hn::Set(d, f.p32), p22 = hn::Set(d, f.p22);
    const V plane_x = hn::Set(d, s.plane.x), eps = hn::Set(d, s.plane.w);
    const V u_x = hn::Set(d, s.dual_u.x), u_w = hn::Set(d, s.dual_u.w);
    const V v_x = hn::Set(d, s.dual_v.x), v_w = hn::Set(d, s.dual_v.w);
    for (int y = y0; y < y1; ++y) {
        // raycast_splat(): inv_t = dot(plane, ray), s = t dot(dual_u, ray) - dual_u.w (likewise q).
        const float ray_y = (float(y) + 0.5f) * f.ray_y + f.ray_dy;
        const float plane_row = s.plane.y * ray_y - s.plane.z;
        const float u_row = s.dual_u.y * ray_y - s.dual_u.z, v_row = s.dual_v.y * ray_y - s.dual_v.z;
        float* drow = img.row(img.depth, y);
        std::uint64_t* crow = img.row(img.color, y);
        const V plane_rows = hn::Set(d, plane_row), u_rows = hn::Set(d, u_row), v_rows = hn::Set(d, v_row);
        const V ray_y2 = hn::Set(d, ray_y * ray_y + 1.0f);
        // A vector of pixels of the row at once, the ray cast's rejections as a lane mask.
        for (int x0 = s.x0; x0 < s.x1; x0 += lanes) {
            const int count = std::min(lanes, s.x1 - x0);
            M m = hn::FirstN(d, std::size_t(count));
            const V ray_x = hn::LoadU(d, ray_xs + x0);
            const V inv_t = hn::Add(hn::Mul(plane_x, ray_x), plane_rows);
            m = hn::And(m, hn::Gt(inv_t, zero));
            if (hn::AllFalse(d, m)) continue;
            const V t = hn::Div(one, inv_t);
            const V su = hn::Sub(hn::Mul(t, hn::Add(hn::Mul(u_x, ray_x), u_rows)), u_w);
            const V sv = hn::Sub(hn::Mul(t, hn::Add(hn::Mul(v_x, ray_x), v_rows)), v_w);
            const V r2 = hn::Add(hn::Mul(su, su), hn::Mul(sv, sv));
            m = hn::And(m, hn::Le(r2, one));  // a NaN radius misses
            if (hn::AllFalse(d, m)) continue;
            V dd;
            if constexpr (Mode == Write::visibility) {
                // visibility.frag: the hit pushed back by eps (plane.w) along the unit view ray.
                const V len = hn::Sqrt(hn::Add(hn::Mul(ray_x, ray_x), ray_y2));
                dd = hn::Div(p32, hn::Add(t, hn::Div(eps, len)));
            } else {
                dd = hn::Mul(p32, inv_t);
            }
            dd = clamp01(d, hn::Add(hn::Mul(half, hn::Sub(dd, p22)), half));
            const bool whole = whole_vectors && x0 + lanes <= row_end;
            const V held = load_lanes(d, m, drow + x0, count, whole);
            if constexpr (Mode == Write::attribute) {
                m = hn::And(m, hn::Le(dd, held));  // LEQUAL against the visibility pass, no depth write
            } else {
                m = hn::And(m, hn::Lt(dd, held));  // GL_LESS
                store_lanes(dd, m, d, drow + x0, count, whole);
            }
            if constexpr (Flat) {
                if constexpr (Mode == Write::color) store_color(d, m, s.color, crow + x0, count, whole);
            } else {
                if (hn::AllFalse(d, m)) continue;
                alignas(64) float l_t[max_lanes], l_su[max_lanes], l_sv[max_lanes], l_w[max_lanes];
                hn::Store(t, d, l_t), hn::Store(su, d, l_su), hn::Store(sv, d, l_sv);
                if constexpr (Mode == Write::attribute) {
                    // attribute.frag's weight, (1 - r²)² + 1e-6.
                    const V rest = hn::Sub(one, r2);
                    hn::Store(hn::Add(hn::Mul(rest, rest), hn::Set(d, 1e-6f)), d, l_w);
                }
                std::uint8_t mask_bytes[8] = {};
                hn::StoreMaskBits(d, m, mask_bytes);
                std::uint64_t bits = 0;
                std::memcpy(&bits, mask_bytes, sizeof bits);
                for (; bits; bits &= bits - 1) {
                    const std::size_t l = hwy::Num0BitsBelowLS1Bit_Nonzero64(bits);
                    write_pixel<Mode>(s, img, x0 + int(l), y, l_t[l], l_su[l], l_sv[l],
                                      Mode == Write::attribute ? l_w[l] : 0.0f);
                }
            }
        }
    }
}

// Rows [y0, y1) of one sprite in the narrowest vectors, down to 128 bits, that hold its rows: most
// sprites are a few pixels wide, and a narrower vector does their work for less (AMD's Zen 4 runs a
// 512-bit operation as two 256-bit ones; division and square roots cost more the wider they are).
template <Write Mode, bool Flat, class D>
void draw_narrowest(D d, const CpuSprite& s, int y0, int y1, const Depths& f, const float* ray_xs,
                    const BandImage& img) {
    using DH = hn::Half<D>;
    if constexpr (hn::MaxLanes(DH()) * sizeof(float) >= 16) {
        if (s.x1 - s.x0 <= int(hn::Lanes(DH())))
            return draw_narrowest<Mode, Flat>(DH(), s, y0, y1, f, ray_xs, img);
    }
    draw_sprite<Mode, Flat>(d, s, y0, y1, f, ray_xs, img);
}

// Every sprite of one band (rows [row0, row1) of the frame) into the image, in draw order.
template <Write Mode>
void draw_band(const CpuRasterImage& out, const std::uint32_t* list, std::size_t n, int row0, int row1,
               const Depths& f, const float* ray_xs, const BandImage& img) {
    for (std::size_t k = 0; k < n; ++k) {
        const CpuSprite& s = out.setup[list[k]];
        const int y0 = std::max(s.y0, row0), y1 = std::min(s.y1, row1);
        // The visibility pass writes depths only; the preview without aux outputs a flat sprite's colour.
        if constexpr (Mode == Write::visibility) {
            draw_narrowest<Mode, true>(DF(), s, y0, y1, f, ray_xs, img);
        } else if constexpr (Mode == Write::color) {
            if (s.texture) draw_narrowest<Mode, false>(DF(), s, y0, y1, f, ray_xs, img);
            else draw_narrowest<Mode, true>(DF(), s, y0, y1, f, ray_xs, img);
        } else {
            draw_narrowest<Mode, false>(DF(), s, y0, y1, f, ray_xs, img);
        }
    }
}

}  // namespace

// rasterize_sprites_cpu() compiled for this target: the sprites set up and binned, then the bands filled
// and drawn in parallel.
void Rasterize(std::span<const SpriteRun> runs, const gpu::FrameBlock& frame, int width, int height,
               glm::vec4 background, PointSizeRange sizes, SpritePass pass, bool aux, CpuRasterImage& out) {
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
    // The x component of each column's view ray, as the scalar code computes it; a vector past the last
    // column reads padding.
    std::vector<float> ray_xs(std::size_t(hi.x) + max_lanes);
    for (std::size_t x = 0; x < ray_xs.size(); ++x) ray_xs[x] = (float(x) + 0.5f) * f.ray_x + f.ray_dx;
    BandImage img;
    img.color = visibility ? nullptr : out.color.data();
    img.depth = out.depth.data();
    img.aux = aux ? out.aux.data() : nullptr;
    img.accum_color = hq ? out.accum_color.data() : nullptr;
    img.accum_normal = hq ? out.accum_normal.data() : nullptr;
    img.rx = out.rect.x, img.ry = out.rect.y, img.stride = out.rect.z;
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
                    draw_band<Write::visibility>(out, list, listed, row0, row1, f, ray_xs.data(), img);
                    // The band's visible depths are final: its attribute pass can run at once.
                    if (hq) {
                        std::fill_n(out.accum_color.data() + first, count, glm::vec4(0.0f));
                        std::fill_n(out.accum_normal.data() + first, count, glm::vec4(0.0f));
                        draw_band<Write::attribute>(out, list, listed, row0, row1, f, ray_xs.data(), img);
                    }
                } else if (aux) {
                    std::fill_n(out.aux.data() + first, count, glm::vec4(0.0f, 0.0f, 0.0f, -1.0f));
                    draw_band<Write::color_aux>(out, list, listed, row0, row1, f, ray_xs.data(), img);
                } else {
                    draw_band<Write::color>(out, list, listed, row0, row1, f, ray_xs.data(), img);
                }
            }
        });
}

}  // namespace sffd::render::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE

namespace sffd::render {

HWY_EXPORT(Rasterize);

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
    simd::honour_environment();
    HWY_DYNAMIC_DISPATCH(Rasterize)(runs, frame, width, height, background, sizes, pass, aux, out);
}

}  // namespace sffd::render

#endif  // HWY_ONCE
