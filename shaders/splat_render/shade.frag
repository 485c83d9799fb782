#version 450
// HQ pass 3: normalise the blended attributes and shade (deferred Blinn-Phong, linear space). Pixels no
// splat reached keep the cleared background: the full-screen triangle lies on the far plane and the depth
// test (NOTEQUAL against the cleared 1.0) rejects them before shading.
#include "splat_render/lighting.glsl"

layout(binding = SFFD_TEX_ACCUM_COLOR) uniform sampler2D accum_color;
layout(binding = SFFD_TEX_ACCUM_NORMAL) uniform sampler2D accum_normal;

// World-space direction from the surface towards the eye for this pixel.
vec3 pixel_to_eye_world() {
    vec3 ray = vec3(gl_FragCoord.xy * frame.ray_map.xy + frame.ray_map.zw, -1.0);
    return -normalize(mat3(frame.view_to_world) * ray);
}

layout(location = 0) out vec4 out_color;
layout(location = 1) out vec4 out_aux;

void main() {
    // The pixel's own texel: nearest filtering at the texel centre. llvmpipe samples this faster than
    // texelFetch (measured: 52.9 vs 55.8 ms per HQ frame of the 59,650-splat sphere, median of 3 each).
    vec2 uv = gl_FragCoord.xy * frame.viewport.zw;
    vec4 c = textureLod(accum_color, uv, 0.0);
    if (c.w <= 0.0) {
        out_color = frame.background;
        out_aux = vec4(0.0, 0.0, 0.0, -1.0);
        return;
    }
    vec4 nz = textureLod(accum_normal, uv, 0.0);
    vec3 albedo = c.rgb / c.w;
    vec3 n = nz.xyz;
    float len = length(n);
    n = len > 0.0 ? n / len : vec3(0.0, 0.0, 1.0);
    out_color = vec4(shade_blinn_phong(albedo, n, pixel_to_eye_world()), 1.0);
    out_aux = vec4(n, nz.w / c.w);
}
