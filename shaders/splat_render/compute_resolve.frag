#version 450
// Compute rasteriser, pass 3 (resolve): adds the fixed-point sums of compute_attribute.comp, as floats, to
// the accumulation targets the raster attribute pass blended into (additive blending ONE, ONE), in the
// layout attribute.frag writes (sum(w rgb), sum(w); sum(w normal), sum(w depth)), and zeroes the words for
// the next frame. Runs where the depth target is not the cleared 1.0 (early depth test NOTEQUAL against the
// far-plane triangle) inside the scissor rectangle: every pixel the attribute pass may have written.
layout(early_fragment_tests) in;
#include "splat_render/compute_raster.glsl"

layout(location = 0) out vec4 accum_color;
layout(location = 1) out vec4 accum_normal;

void main() {
    uint p = raster_pixel(ivec2(gl_FragCoord.xy));
    uint base = p * uint(SFFD_RASTER_SUM_WORDS);
    uint w = raster_sums[base + 3u];
    if (w == 0u) discard;  // no compute sprite here: every contribution has w >= 1
    uvec4 c = uvec4(raster_sums[base], raster_sums[base + 1u], raster_sums[base + 2u], w);
    uvec3 n = uvec3(raster_sums[base + 4u], raster_sums[base + 5u], raster_sums[base + 6u]);
    float wf = float(raster_sums[base + 7u]) + float(raster_sums[base + 8u]) * (1.0 / 65536.0);  // sum(w f)
    for (uint k = 0u; k < uint(SFFD_RASTER_SUM_WORDS); ++k) raster_sums[base + k] = 0u;
    const float inv_one = 1.0 / SFFD_RASTER_FIXED_ONE;
    float R = raster_view_depth(uintBitsToFloat(raster_depth[p]));
    accum_color = vec4(c) * inv_one;
    accum_normal = vec4((2.0 * vec3(n.xyz) - float(w)) * inv_one, R * (float(w) - wf) * inv_one);
}
