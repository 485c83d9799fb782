#version 450
// HQ pass 3: normalise the blended attributes and shade (deferred Blinn-Phong, linear space). Pixels no
// splat reached keep the cleared background: the full-screen triangle lies on the far plane and the depth
// test (NOTEQUAL against the cleared 1.0) rejects them before shading. MATERIALS 1: the clouds of the
// frame differ in material, whose parameters the attribute pass blended into a third target.
#include "splat_render/lighting.glsl"

layout(binding = SFFD_TEX_ACCUM_COLOR) uniform sampler2D accum_color;
layout(binding = SFFD_TEX_ACCUM_NORMAL) uniform sampler2D accum_normal;
#if MATERIALS
layout(binding = SFFD_TEX_ACCUM_MATERIAL) uniform sampler2D accum_material;
#endif

layout(location = 0) out vec4 out_color;
layout(location = 1) out vec4 out_aux;

void main() {
    // The pixel's own texel: nearest filtering at the texel centre. llvmpipe samples this faster than
    // texelFetch (measured: 52.9 vs 55.8 ms per HQ frame of the 59,650-splat sphere, median of 3 each).
    vec2 uv = gl_FragCoord.xy * frame.viewport.zw;
    vec4 c = textureLod(accum_color, uv, 0.0);
    vec4 nz = textureLod(accum_normal, uv, 0.0);
    // Reciprocals and inverse square roots, not divisions and lengths: llvmpipe shades every lane of a
    // block, and this pass touches every covered pixel.
    float inv_w = 1.0 / c.w;
    float n2 = dot(nz.xyz, nz.xyz);
    vec3 n = n2 > 0.0 ? nz.xyz * inversesqrt(n2) : vec3(0.0, 0.0, 1.0);
    // World-space direction towards the eye: view_to_world is a rotation, so |R ray| = |ray|.
    vec3 ray = vec3(gl_FragCoord.xy * frame.ray_map.xy + frame.ray_map.zw, -1.0);
    vec3 to_eye = (mat3(frame.view_to_world) * ray) * -inversesqrt(dot(ray, ray));
#if MATERIALS
    vec2 material = textureLod(accum_material, uv, 0.0).xy * inv_w;  // blended specular, shininess
#else
    vec2 material = frame.material.xy;  // every cloud has this material
#endif
    vec3 color = shade_blinn_phong(c.rgb * inv_w, n, to_eye, material.x, material.y);
    bool hit = c.w > 0.0;  // else a pixel with depth but no weight (cannot happen: kept for safety)
    out_color = hit ? vec4(color, 1.0) : frame.background;
    out_aux = hit ? vec4(n, nz.w * inv_w) : vec4(0.0, 0.0, 0.0, -1.0);
}
