// Per-draw uniform block of the splat render passes (binding SFFD_UBO_FRAME), shared by GLSL and C++
// (std140: only vec4/mat4 members so both sides agree without padding rules). Owned by systems/splat_render.
#ifndef SFFD_SPLAT_FRAME_BLOCK_H
#define SFFD_SPLAT_FRAME_BLOCK_H

#define SFFD_MAX_LIGHTS 4

#ifdef __cplusplus
// C++: include <glm/glm.hpp> before this header (the GLSL include resolver does not evaluate #ifdef).
namespace sffd::gpu {
struct FrameBlock {
#define SFFD_MAT4 glm::mat4
#define SFFD_VEC4 glm::vec4
#define SFFD_UVEC4 glm::uvec4
#else
layout(std140, binding = SFFD_UBO_FRAME) uniform FrameBlock {
#define SFFD_MAT4 mat4
#define SFFD_VEC4 vec4
#define SFFD_UVEC4 uvec4
#endif
    SFFD_MAT4 model_view;     // cloud space (positions relative to SplatCloud::origin) -> view space
    SFFD_MAT4 projection;     // symmetric perspective, GL clip convention
    SFFD_MAT4 normal_view;    // inverse transpose of model_view (upper 3x3 used)
    SFFD_MAT4 view_to_world;  // inverse view matrix (world normals, shading)
    SFFD_VEC4 viewport;       // width, height, 1/width, 1/height
    SFFD_VEC4 ray_map;        // view ray of a pixel: (x, y) = gl_FragCoord.xy * ray_map.xy + ray_map.zw, z = -1
    SFFD_VEC4 params;         // x: visibility offset eps (times the splat radius), y: max point size,
                              // z: culling on (1) / off (0), w: material has a texture (1) / not (0)
    SFFD_VEC4 ambient;        // linear rgb * intensity
    SFFD_VEC4 light_dir[SFFD_MAX_LIGHTS];    // world space, pointing towards the light
    SFFD_VEC4 light_color[SFFD_MAX_LIGHTS];  // linear rgb * intensity
    SFFD_VEC4 material;       // x: specular, y: shininess
    SFFD_VEC4 base_color;     // linear rgb that packed splat colours are multiplied by: the material's base
                              // colour for a cloud without colours (packed white), else 1
    SFFD_VEC4 background;     // linear rgba written where no splat covers the pixel
    SFFD_UVEC4 counts;        // x: splats in the draw buffer, y: lights, w: 1 = preview (colours are lit)
#ifdef __cplusplus
};
static_assert(sizeof(FrameBlock) == 4 * 64 + 8 * 16 + 2 * SFFD_MAX_LIGHTS * 16);
}  // namespace sffd::gpu
#else
} frame;
#endif
#undef SFFD_MAT4
#undef SFFD_VEC4
#undef SFFD_UVEC4

#endif  // SFFD_SPLAT_FRAME_BLOCK_H
