// Colour of a splat: the texture at its uv (sRGB texture: sampled linear) or its packed RGBA8 sRGB colour
// times frame.base_color; in preview (frame.counts.w == 1) lit once per splat with its normal (Blinn-Phong).
#ifndef SFFD_SPLAT_COLOR_GLSL
#define SFFD_SPLAT_COLOR_GLSL

#include "splat_render/splat_common.glsl"
#include "splat_render/lighting.glsl"
#include "common/point_marks.glsl"

layout(binding = SFFD_TEX_MATERIAL) uniform sampler2D material_texture;

// TEXTURED and LIT (0 or 1) fix the two choices at compile time (the cull pass compiles a variant per
// combination: llvmpipe would otherwise sample the texture and light every splat whatever the branch
// says); left undefined, they are read per draw from frame.params.w and frame.counts.w.
// `mark`: the splat's point mark (point_marks.glsl), shown as frame.counts.z's mode asks (weight ramp,
// selection tint) before the lighting.
vec4 splat_color(GpuSplat s, SplatView o, vec3 world_n, uint mark) {
    vec4 color;
#if defined(TEXTURED)
    const bool textured = TEXTURED != 0;
#else
    bool textured = frame.params.w != 0.0;
#endif
#if defined(LIT)
    const bool lit = LIT != 0;
#else
    bool lit = frame.counts.w == 1u;
#endif
    // SFFD_MARKS_TEXEL: a textured cloud drawn by the untextured programs under an overlay.
    if (textured || (frame.counts.z & SFFD_MARKS_TEXEL) != 0u)
        color = textureLod(material_texture, vec2(s.axis_u.w, s.axis_v.w), 0.0);
    else {
        color = unpackUnorm4x8(s.color);
        color.rgb = srgb_to_linear(color.rgb) * frame.base_color.rgb;
    }
    color.rgb = mark_overlay(color.rgb, mark, frame.counts.z);
    if (lit) color.rgb = shade_blinn_phong(color.rgb, world_n, -normalize(mat3(frame.view_to_world) * o.c));
    return color;
}

// The textured preview's per-splat lighting: pixel colour = texture * diffuse + specular.
void splat_light_factors(SplatView o, vec3 world_n, out vec3 diffuse, out vec3 specular) {
    blinn_phong_factors(world_n, -normalize(mat3(frame.view_to_world) * o.c), frame.material.x, frame.material.y,
                        diffuse, specular);
}

#endif
