// CPU twin of the cull pass (shaders/splat_render/cull.comp) for software rasterizers.
//
// On llvmpipe the "GPU" is these same two cores, and a compute shader pays for every branch on every lane
// (llvmpipe executes both sides of an `if` under a mask), so the cull pass cost 55 ms for 600k splats.
// This function does the same job with real branches and TBB: same inputs (the GpuSplat array and the
// FrameBlock the shader reads), same outputs (SplatRecords of the visible sprites, indices of the splats
// drawn as quads), written in splat order, so the result is also deterministic. render_system uploads the
// result into the buffers the indirect draws read; it picks this path on a software rasterizer when the
// cloud's current splats are on the CPU (not deformed, or deformed by the FFD system's CPU path), and the
// compute pass otherwise (RenderSettings::cull).
#pragma once

#include <cstdint>
#include <memory>
#include <new>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "shaders/common/bindings.h"
#include "shaders/splat_render/frame_block.h"
#include "shaders/splat_render/splat_record.h"

namespace sffd::render {

// The material texture as the shader samples it (sRGB RGBA8, row 0 at v = 0, repeat in u, clamp in v,
// bilinear at level 0). Null texels: untextured (per-splat colours).
struct TexturePyramid;
struct TexelView {
    const std::uint8_t* rgba8 = nullptr;
    int width = 0, height = 0;
    const glm::vec4* uv_axes = nullptr;  // SplatCloud::uv_axes, one per splat (null: zero derivatives)
    const std::uint16_t* uniform_radius = nullptr;  // uniform_texel_radius() of the texels (null: none)
    // Non-null (reduced previews, RenderSettings::reduced_preview_flat_texture): every textured sprite is
    // drawn flat, coloured by one lookup at its centre at its mip level (sample_texture).
    const TexturePyramid* pyramid = nullptr;
};

// A texture's mip levels 1.. on the CPU (level 0 is the texture itself): each the mean of 2x2 texels of
// the level above in linear light, sRGB-encoded RGBA8, sizes halved and rounded down to 1 as GL's.
struct TexturePyramid {
    std::vector<std::vector<std::uint8_t>> levels;  // levels[k - 1] is level k
    std::vector<glm::ivec2> sizes;                  // sizes[k - 1] is level k's
};
TexturePyramid build_texture_pyramid(const std::uint8_t* rgba8, int width, int height);
// The texture's linear RGB at uv (repeat in u, clamp in v), bilinear at `level` (clamped to the levels
// there are), as the preview's textureLod reads it; |uv| < 1e6.
glm::vec3 sample_texture(const TexelView& texture, glm::vec2 uv, int level);

// For each texel (row-major, level 0): its Chebyshev distance to the nearest texel whose 8-neighbourhood
// holds another colour (border texels count as such, so u's wrap needs no special case). Every texel
// closer than that to it has its colour. The CPU cull uses it to find splats whose whole texture footprint
// (at their mip level, with the filter's reach) is one colour: those are drawn with a flat colour by the
// programs without per-pixel texture lookups, which cost llvmpipe about as much as the rest of the
// attribute pass.
std::vector<std::uint16_t> uniform_texel_radius(const std::uint8_t* rgba8, int width, int height);

// A cloud's point marks as the CPU cull reads them (runtime/gfx/point_marks.h; the compute cull reads the
// residency's marks buffer, made from the same columns): drawn element i is point index[i] (a preview
// subset) or i; its flags and weight come from the columns (null, or `points` not their size: the
// defaults). frame.counts.z's mode (SFFD_MARKS_*) says what to do with them, as in cull.comp.
struct MarksView {
    const std::uint8_t* flags = nullptr;  // PointFlags::bits
    const float* weights = nullptr;       // PointWeights::values
    const std::uint32_t* index = nullptr;
    std::size_t index_count = 0;
    std::size_t points = 0;
    // SFFD_MARKS_TEXEL (a textured cloud drawn flat under an overlay): its texture, sampled at each splat's
    // centre uv at level 0 (sample_texture) for the colour the overlay starts from.
    TexelView texels;
};

// An allocator whose resize() leaves new elements default-initialised (uninitialised for the records): the
// cull writes only the visible splats' slots, so the memory of culled ones is never touched (and, on
// Linux, never made resident) instead of being zero-filled every time the cloud grows.
template <class T>
struct UninitAllocator : std::allocator<T> {
    template <class U>
    struct rebind {
        using other = UninitAllocator<U>;
    };
    UninitAllocator() = default;
    template <class U>
    UninitAllocator(const UninitAllocator<U>&) noexcept {}
    template <class U>
    void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
        ::new (static_cast<void*>(p)) U;
    }
    template <class U, class... Args>
    void construct(U* p, Args&&... args) {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};
template <class T>
using UninitVector = std::vector<T, UninitAllocator<T>>;

// Output of cull_splats_cpu. The splats are processed in fixed blocks of `block` splats; block b's
// visible sprites are records[b * block, b * block + record_counts[b]) (and likewise its quad indices), so
// each block is one contiguous run to upload and nothing is copied twice. The vectors keep their capacity
// between frames.
struct CpuCullResult {
    std::size_t block = 0;
    UninitVector<SplatRecord> records;         // size: the splat count (runs per block)
    UninitVector<std::uint32_t> quads;         // size: the splat count (runs per block)
    std::vector<std::uint32_t> record_counts;  // per block
    std::vector<std::uint32_t> quad_counts;    // per block
    // Textured clouds: sprites whose texture footprint is one colour (TexelView::uniform_radius) are not
    // in `records` but here, with that colour packed like an untextured splat's (runs per block).
    UninitVector<SplatRecord> flat_records;
    std::vector<std::uint32_t> flat_counts;  // per block
    std::uint32_t visible_records = 0;       // sums of the counts
    std::uint32_t visible_quads = 0;
    std::uint32_t visible_flat = 0;
    // The frame pixels the kept sprites may touch (GL's lower-left origin, [lo, hi) in x and y; lo > hi
    // when none was kept): every sprite's square, a pixel wider on each side. Quads carry no such square:
    // `pixels_bounded` is false when any was kept.
    glm::vec2 pixels_lo{0.0f}, pixels_hi{0.0f};
    bool pixels_bounded = true;
    std::vector<glm::vec4> block_pixels;  // per block: lo.xy, hi.xy

    // Calls fn(first_output_index, pointer, count) for each non-empty run, in order.
    template <class Data, class Fn>
    static void for_each_run(const Data& data, const std::vector<std::uint32_t>& counts, std::size_t block,
                             Fn&& fn) {
        std::size_t out = 0;
        for (std::size_t b = 0; b < counts.size(); ++b) {
            if (counts[b] == 0) continue;
            fn(out, data.data() + b * block, std::size_t(counts[b]));
            out += counts[b];
        }
    }
};

// Culls and compacts `splats` exactly as cull.comp does with `frame` (model_view, projection, params,
// counts.w = 1 lights the colours for preview, ...). frame.counts.x is ignored: the span's size counts.
// One difference: with TexelView::uniform_radius, a textured cloud's one-colour sprites go to
// flat_records (cull.comp keeps every textured sprite in the textured list).
// Hidden and deleted points (`marks`, when frame.counts.z has SFFD_MARKS_PRESENT) are dropped as cull.comp
// drops them, and the kept ones' colours show the mode's overlays.
void cull_splats_cpu(std::span<const gpu::GpuSplat> splats, const gpu::FrameBlock& frame,
                     const TexelView& texture, CpuCullResult& out, const MarksView& marks = {});

// Screen box of a splat's projected ellipse, the twin of ellipse_sprite() in splat_common.glsl: NDC centre
// (xy) and the side in pixels of the square sprite around it (z, -1 when the ellipse reaches the near plane).
glm::vec3 ellipse_sprite(const gpu::FrameBlock& frame, const glm::vec3& c, const glm::vec3& u,
                         const glm::vec3& v);

}  // namespace sffd::render
