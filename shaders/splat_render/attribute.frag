#version 450
// HQ pass 2: additive blending of weighted attributes into two RGBA32F targets. Depth test against the
// visibility pass (LEQUAL, no depth writes) keeps only splats within eps of the visible surface.
//   accum_color  = sum(w * linear rgb), sum(w)
//   accum_normal = sum(w * world normal), sum(w * view-axis depth)
//   accum_material (MATERIALS 1) = sum(w * specular), sum(w * shininess)
// TEXTURED 1: the colour is the material texture at this pixel's uv, from the splat's uv frame (v_uv,
// splat_uv_frame) at the fragment's splat coordinates, filtered trilinearly at the splat's mip level
// (splat_texture_lod): texture detail finer than the splats survives. TEXTURED 0: the splat's
// one colour (v_plane.w, packed).
#include "splat_render/raycast.glsl"

#include "splat_render/splat_common.glsl"

layout(location = 3) flat in vec3 v_normal;
#if TEXTURED
layout(location = 5) flat in vec3 v_uv;        // uv at the centre, mip level (splat.vert)
layout(location = 6) flat in vec4 v_uv_axes;   // d(uv)/ds, d(uv)/dt
layout(binding = SFFD_TEX_MATERIAL) uniform sampler2D material_texture;
#endif


layout(location = 0) out vec4 accum_color;
layout(location = 1) out vec4 accum_normal;
#if MATERIALS
// Clouds with different materials in one frame: their specular and shininess blend like the colour.
layout(location = 2) out vec4 accum_material;
#endif

void main() {
    vec3 ray;
    float r2;
    vec2 st;
    float t = raycast_splat(ray, r2, st);
    gl_FragDepth = window_depth_inv(dot(v_plane.xyz, ray));
    // Smooth radial kernel that reaches 0 at the ellipse's edge: no visible disc borders.
    float w = (1.0 - r2) * (1.0 - r2) + 1e-6;
#if TEXTURED
    // uv at this pixel from the splat's uv frame; the mip level is the splat's (v_uv.z, set up once per
    // splat by the cull pass: splat_texture_lod), trilinear between levels.
    vec3 albedo = textureLod(material_texture, v_uv.xy + st.x * v_uv_axes.xy + st.y * v_uv_axes.zw, v_uv.z).rgb;
#else
    vec3 albedo = unpack_color(v_plane.w);
#endif
    accum_color = vec4(w * albedo, w);
    accum_normal = vec4(w * v_normal, w * t);
#if MATERIALS
    accum_material = vec4(w * frame.material.xy, 0.0, 0.0);
#endif
}
