// SplatRecord and the cull pass's work-group size, shared by GLSL (cull.comp, splat.vert through
// splat_common.glsl) and C++ (splat_render.cpp, cpu_cull.h), like common/bindings.h. Owned by
// systems/splat_render.
// GLSL: #include "splat_render/splat_record.h". C++: include <glm/glm.hpp>, then
// "shaders/splat_render/splat_record.h" (the GLSL include resolver does not evaluate #ifdef).
#ifndef SFFD_SPLAT_RECORD_H
#define SFFD_SPLAT_RECORD_H

// local_size_x of shaders/splat_render/cull.comp; render_system dispatches ceil(count / this) groups.
#define SFFD_CULL_GROUP_SIZE 128

// The cull pass's per-group counts and their scan (cull.comp): the stats binding, which the cull does not use.
#define SFFD_SSBO_CULL_GROUPS SFFD_SSBO_STATS
// uint uniform of cull.comp: 1 for its count pass, 0 for the pass that writes the lists.
#define SFFD_LOC_CULL_PASS 0
// uint uniform of splat.vert's quads (SHAPE_QUAD): the first splat of the range their indices count from.
#define SFFD_LOC_QUAD_MARK_BASE 0

// A visible sprite splat, prepared by the cull pass (or its CPU twin, cpu_cull.h) so the vertex shaders of
// both HQ passes only copy it (llvmpipe spends its time per primitive: vertex work runs once, in the cull).
// std430, 96 bytes, bound as a vertex buffer (attributes 0..5). The ray through a pixel is d = (x, y, -1)
// in view space; the ray cast is linear in d:
//   t = 1 / dot(plane.xyz, d)                     view-axis depth of the hit p = t * d
//   s = t * dot(dual_u.xyz, d) - dual_u.w,  q = t * dot(dual_v.xyz, d) - dual_v.w,  inside: s^2 + q^2 <= 1
// A fragment is drawn only where dot(plane.xyz, d) > 0 (the plane lies in front along the ray).
// plane.xyz = (0, 0, 0) is the explicit "hidden" mark (SFFD_RECORD_HIDDEN): a back-facing splat kept with
// culling off, rasterised so its cost shows, whose every fragment discards because dot(0, d) = 0 exactly.
// (It was a NaN plane once; GLSL leaves NaN comparisons undefined and NVIDIA folds them: nothing drew.)
// Colour travels packed (pack_color in splat_common.glsl: 10-10-10 bits of sqrt(linear rgb), stored as a
// normal float) so that, with the normal, every pass hands at most four vec4 varyings per sprite to the
// rasteriser (each costs per-primitive set-up on llvmpipe).
// Textured clouds sample the texture per pixel through the uv frame, so some slots change meaning:
//   HQ (unlit records):   normal.w = mip level (splat_texture_lod)
//   preview (lit):        normal.w = pack_light(diffuse factor), plane.w = pack_light(specular term) (the
//                         preview has no visibility pass, so no eps), center.z = mip level
// (pixel colour = texture * diffuse + specular: splat_light_factors). The CPU cull's flat-coloured sprites
// of a textured cloud (third indirect draw) keep the untextured meaning and uv = 0.
#define SFFD_SPLAT_RECORD_BYTES 96

#ifdef __cplusplus
namespace sffd::render {
struct SplatRecord {
#define SFFD_VEC4 glm::vec4
#else
struct SplatRecord {
#define SFFD_VEC4 vec4
#endif
    SFFD_VEC4 center;  // xy: NDC centre of the sprite (ellipse_sprite), z: view-space z of the splat centre,
                       // w: sprite side in pixels
    SFFD_VEC4 plane;   // xyz: plane normal / dot(center, normal) (0: hidden, see above), w: visibility offset
                       // eps (view units)
    SFFD_VEC4 dual_u;  // xyz: dual axis (s = dot(dual_u, p - center)), w: dot(dual_u, center)
    SFFD_VEC4 dual_v;
    SFFD_VEC4 normal;  // xyz world-space shading normal, w: packed colour (HQ albedo, preview lit)
    SFFD_VEC4 uv;      // textured clouds: xy uv at the centre, z / w: the uv derivatives along axis_u / axis_v,
                       // two halves each (pack_halves, splat_uv_frame); untextured: 0
};
#undef SFFD_VEC4
#ifdef __cplusplus
static_assert(sizeof(SplatRecord) == SFFD_SPLAT_RECORD_BYTES);
}  // namespace sffd::render
#endif

#endif  // SFFD_SPLAT_RECORD_H
