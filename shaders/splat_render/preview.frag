#version 450
// Preview: one pass of opaque ray-cast ellipses with true depth; the cull pass (or the quad vertex shader)
// lit each splat once (splat.vert unpacks its values). TEXTURED 1: the texture is sampled per pixel through
// the splat's uv frame at its mip level rounded to one level (one bilinear lookup: 5-10% of the textured preview frame on llvmpipe,
// 47.3 -> 36.8 dB against the ground truth at rest) and lit with the splat's factors (colour = texture *
// diffuse + specular), so texture edges are not the splats' disc outlines.
#include "splat_render/raycast.glsl"

#include "splat_render/splat_common.glsl"

#if AUX
layout(location = 3) flat in vec3 v_normal;
#endif
layout(location = 4) flat in vec3 v_color;  // lit colour, or TEXTURED: the diffuse factor
#if TEXTURED
layout(location = 5) flat in vec3 v_uv;        // uv at the centre, mip level
layout(location = 6) flat in vec4 v_uv_axes;   // d(uv)/ds, d(uv)/dt
layout(location = 7) flat in vec3 v_specular;
layout(binding = SFFD_TEX_MATERIAL) uniform sampler2D material_texture;
#endif


layout(location = 0) out vec4 out_color;   // linear rgb, alpha 1
#if AUX
layout(location = 1) out vec4 out_aux;     // world normal, view-axis depth (only when frames are captured)
#endif

void main() {
    vec3 ray;
    float r2;
    vec2 st;
    float t = raycast_splat(ray, r2, st);
    gl_FragDepth = window_depth_inv(dot(v_plane.xyz, ray));
#if TEXTURED
    vec3 albedo = textureLod(material_texture, v_uv.xy + st.x * v_uv_axes.xy + st.y * v_uv_axes.zw, v_uv.z).rgb;
    out_color = vec4(albedo * v_color + v_specular, 1.0);
#else
    out_color = vec4(v_color, 1.0);
#endif
#if AUX
    out_aux = vec4(v_normal, t);
#endif
}
