// Colour of a splat: the material texture at its uv (sRGB texture: sampled linear) or its packed RGBA8
// sRGB colour; in preview (frame.counts.w == 1) lit once per splat with its normal (Blinn-Phong).
#ifndef SFFD_SPLAT_COLOR_GLSL
#define SFFD_SPLAT_COLOR_GLSL

#include "splat_render/splat_common.glsl"
#include "splat_render/lighting.glsl"

layout(binding = SFFD_TEX_MATERIAL) uniform sampler2D material_texture;

vec4 splat_color(GpuSplat s, SplatView o, vec3 world_n) {
    vec4 color;
    if (frame.params.w != 0.0)
        color = textureLod(material_texture, vec2(s.axis_u.w, s.axis_v.w), 0.0);
    else {
        color = unpackUnorm4x8(floatBitsToUint(s.center.w));
        color.rgb = srgb_to_linear(color.rgb);
    }
    if (frame.counts.w == 1u) color.rgb = shade_blinn_phong(color.rgb, world_n, -normalize(mat3(frame.view_to_world) * o.c));
    return color;
}

#endif
