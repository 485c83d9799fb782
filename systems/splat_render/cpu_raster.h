// CPU rasteriser of the preview's sprites, for software GL.
//
// On llvmpipe a point sprite costs far more than its pixels: its vertex work, set-up and binning run on
// the thread that issues the draw, and the fragment code runs per 4x4 block a sprite touches. The sphere's
// half-size drag preview (23.5k sprites, about 7 px each) took 13 ms, the face's (20k sprites, 30 px each)
// 18 ms. The CPU cull already made every sprite's record (cpu_cull.h), so the same cores can ray-cast them
// directly: the preview.frag arithmetic per pixel of each sprite's square, depth-tested, into a colour
// (RGBA16F) and depth image that the render system uploads into its output targets. Whatever the CPU does
// not draw (quads, a textured cloud's per-pixel textured sprites, clouds culled by the compute pass) GL
// draws afterwards, depth-tested against the uploaded depth: every preview splat is opaque, so the order
// between the two only matters for exactly equal depths.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "shaders/splat_render/frame_block.h"
#include "shaders/splat_render/splat_record.h"
#include "systems/splat_render/cpu_cull.h"

namespace sffd::render {

// One run of sprite records, drawn in order. Without a texture their colour is packed in normal.w (an
// untextured cloud's records, a textured cloud's flat-coloured ones); with one they are a textured cloud's
// lit preview records (splat_record.h: uv frame, mip level in center.z, lighting factors), sampled per
// pixel as preview.frag does (sample_texture: the TexelView needs its pyramid for levels past 0).
struct SpriteRun {
    const SplatRecord* records = nullptr;
    std::size_t count = 0;
    const TexelView* texture = nullptr;
};

// One sprite as the rasteriser reads it (scratch of CpuRasterImage).
struct CpuSprite {
    int x0 = 0, x1 = 0, y0 = 0, y1 = 0;  // the pixels whose centres its square holds: [x0, x1) x [y0, y1)
    glm::vec4 plane{0.0f}, dual_u{0.0f}, dual_v{0.0f};
    glm::vec3 normal{0.0f};   // world-space shading normal (the aux output)
    std::uint64_t color = 0;  // RGBA16F (flat-coloured sprites)
    // Textured sprites: the run's texture (null: flat), uv at the centre, d(uv)/ds and d(uv)/dt, the mip
    // level, and the lighting factors (colour = texture * diffuse + specular).
    const TexelView* texture = nullptr;
    glm::vec2 uv{0.0f};
    glm::vec4 uv_axes{0.0f};
    int level = 0;
    glm::vec3 diffuse{0.0f}, specular{0.0f};
    // HQ attribute pass: the flat albedo, or a textured sprite's (fractional) mip level.
    glm::vec3 albedo{0.0f};
    float lod = 0.0f;
};

// The rasterised part of the frame: `rect` (x, y, width, height from the frame's lower-left corner, inside
// the frame) holds every pixel a sprite covered; rows bottom first, as glTextureSubImage2D reads them.
// Outside it the frame is the background. The vectors keep their capacity between frames.
struct CpuRasterImage {
    glm::ivec4 rect{0};
    std::vector<std::uint64_t> color;  // RGBA16F (four IEEE halves, r in the low bits): linear rgb, alpha 1
    std::vector<float> depth;          // window depth in [0, 1], 1 where nothing was drawn
    // With aux outputs: the world normal and view-axis depth (preview.frag's out_aux), (0, 0, 0, -1)
    // where nothing was drawn; empty without.
    std::vector<glm::vec4> aux;
    // SpritePass::hq: the attribute pass's sums (attribute.frag), Σw·rgb, Σw and Σw·normal, Σw·t; 0 where
    // nothing was drawn.
    std::vector<glm::vec4> accum_color, accum_normal;
    std::uint32_t sprites = 0;  // sprites that covered at least one pixel centre of the frame
    // Scratch of the rasteriser, kept for the next frame.
    std::vector<CpuSprite> setup;
    std::vector<std::uint32_t> bins, bin_first;
};

// Which pass's fragment code the sprites run: the preview's (colour, true depth), the HQ visibility pass's
// (visibility.frag: depth only, pushed back by the record's eps in plane.w along the view ray), or hq: that
// visibility pass, then the attribute pass (attribute.frag: every hit whose true depth is within the
// visible one, LEQUAL, adds its weight (1 - r²)² + 1e-6 times albedo, normal and view depth; textured
// albedo filtered trilinearly at the record's level).
enum class SpritePass { preview, visibility, hq };

// The sizes GL clamps gl_PointSize to (GL_POINT_SIZE_RANGE), so that a sprite covers the pixels it would
// cover as a point.
struct PointSizeRange {
    float min = 1.0f, max = 1.0f;
};

// Draws the runs into a width x height frame with the frame block's ray map and projection (the preview
// program's uniforms): for each pixel whose centre lies in a sprite's square (its side the clamped point
// size), the ray-cast of preview.frag (raycast.glsl), kept where its window depth is less than what the
// pixel holds (GL_LESS: the first of equal depths stays). Colours are unpack_color() of normal.w, or the
// texture lit as SpriteRun says; `aux` also writes CpuRasterImage::aux.
void rasterize_sprites_cpu(std::span<const SpriteRun> runs, const gpu::FrameBlock& frame, int width,
                           int height, glm::vec4 background, PointSizeRange sizes, SpritePass pass, bool aux,
                           CpuRasterImage& out);

// unpack_color() of splat_common.glsl: the 10-10-10 bit square roots of a packed colour, squared.
glm::vec3 unpack_color(float packed);
// unpack_halves() of splat_common.glsl: the two halves pack_halves() stored (their lowest mantissa bit
// dropped).
glm::vec2 unpack_halves(float packed);

}  // namespace sffd::render
