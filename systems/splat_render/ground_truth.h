// Ground-truth renderer: a CPU ray tracer of the exact surface behind a splat cloud (ExactSphere, or the
// ExactMesh a mesh file was sampled from: its triangles through Embree, uv interpolated, the texture's
// uv derivatives from each triangle's affine 3D -> uv map; under FFD a subdivision of each triangle whose
// vertices are F of the rest points), seen
// through the same camera, lit by the same lights with the same Blinn-Phong model and textured with the
// same texture as the splat renderer, so its images are what the splats approximate.
//
// Geometry. At rest (no deformer moved any control point) the sphere is intersected analytically. Under
// FFD the exact surface is F(sphere), F the cloud's lattices applied in order (ffd::deform, the function
// the splats go through). It is traced through Embree as a tessellation of F(sphere): a longitude x
// colatitude grid (default 2048 x 1024) whose vertices are F of exact sphere points; a hit's rest point
// is the barycentric mix of the triangle's rest points pushed back onto the sphere, so uv is the exact
// spherical mapping of that point, and the normal is the mix of the vertices' FFD normals (cofactor of
// the Jacobian). The flat triangles lie within L^2 / 8 of the curved surface (L the edge length: 1.2e-5
// for a 2x stretch of the default grid, against pixels of ~5e-3 at the built-in camera).
//
// Texture filtering: `supersample == 0` (default) traces one ray through each pixel centre and samples
// the texture like GL's GL_LINEAR_MIPMAP_LINEAR with the exact screen-space uv derivatives (the uv map's
// gradient applied to the neighbouring pixels' rays cut with the tangent plane); `supersample = N` traces
// N x N sub-pixel rays, shades each with a bilinear lookup of level 0 and averages those that hit (a box
// filter of the pixel). Coverage is always the pixel centre's ray, as in the splat renderer.
//
// Output: a FrameImage like capture_frame(): linear RGB, alpha 1 on the surface and 0 elsewhere, view-axis
// depth, world normal; row 0 at the top.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/result.h"
#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"
#include "systems/splat_render/image_io.h"

namespace sffd::render {

// Lights as the splat renderer gathers them (render_system's frame block): up to 4 directional lights
// and the summed ambient; a scene with neither gets the default DirectionalLight and AmbientLight.
struct ReferenceLights {
    glm::dvec3 ambient{0.0};
    std::vector<glm::dvec3> to_light;  // unit, world space, towards the light
    std::vector<glm::dvec3> color;     // linear rgb * intensity
};
ReferenceLights scene_lights(const ecs::Registry& registry);

struct ReferenceScene {
    int width = 0, height = 0;
    glm::dmat4 view{1.0}, projection{1.0};  // camera_math.h's view_matrix / projection_matrix
    glm::dvec3 center{0.0};                 // world space sphere
    double radius = 1.0;
    std::vector<Lattice> lattices;          // deformers in order (world space; a mesh's: its space, below);
                                            // empty: the rest sphere
    const SplatTexture* texture = nullptr;  // the cloud's texture (sRGB, row 0 at v = 0), maybe empty
    SplatMaterial material;                 // base colour, specular, shininess
    ReferenceLights lights;
    // Instead of the sphere: a cloud's ExactMesh (deformed by `lattices` like the sphere), and the
    // cloud's model matrix (Transform and origin) that places it in the world.
    const ExactMesh* mesh = nullptr;
    glm::dmat4 mesh_model{1.0};
    // The cloud's hidden and deleted points (PointFlags kPointGone): a surface point whose nearest rest
    // splat (rest positions in the world, Transform and origin applied) is gone is not traced, as the
    // splat renderer draws none there. Both empty when no point is gone.
    std::vector<glm::dvec3> point_rest;
    std::vector<std::uint8_t> point_gone;
};

struct ReferenceSettings {
    int supersample = 0;  // 0: pixel-centre rays, trilinear mip filtering; N: N x N rays, level 0
    int anisotropic =
        0;  // with supersample 0: up to this many trilinear probes along the footprint's major axis
    int longitude_steps = 2048;  // tessellation of the deformed sphere
    int colatitude_steps = 1024;
    int mesh_triangle_budget =
        1 << 21;  // a deformed ExactMesh: k x k sub-triangles each, about this many in all
};

// The scene of the first cloud carrying an ExactSphere (else an ExactMesh), after the current frame's
// animation (Lattice::current as it is now), through scene_camera() at width x height. Errors name what
// is missing; a mesh cloud whose colours were baked per splat (no texture to trace: a tinted or
// multi-texture mesh) is an error.
Result<ReferenceScene> reference_scene(const ecs::Registry& registry, int width, int height);

Result<FrameImage> render_reference(const ReferenceScene& scene, const ReferenceSettings& settings = {});

// The built-in sphere's uv map (runtime/assets/builtin_scenes.cpp): u = longitude atan2(z, x) / 2 pi in
// [0, 1), v = colatitude from +Y / pi, of a unit direction d (sphere space).
glm::dvec2 sphere_uv(const glm::dvec3& d);

// A texture sampled the way the splat renderer's GL texture is (sRGB texels decoded to linear, repeat in
// u, clamp in v, mip levels by 2x2 averaging in linear space).
class ReferenceTexture {
public:
    explicit ReferenceTexture(const SplatTexture& texture);
    bool empty() const { return levels_.empty(); }
    glm::dvec4 bilinear(const glm::dvec2& uv, int level = 0) const;
    // GL_LINEAR_MIPMAP_LINEAR with explicit derivatives of uv along window x and y (GL 4.5 section 8.14).
    glm::dvec4 trilinear(const glm::dvec2& uv, const glm::dvec2& duv_dx, const glm::dvec2& duv_dy) const;
    // Anisotropic filtering (EXT_texture_filter_anisotropic's model): min(ceil(major / minor), max_probes)
    // trilinear probes along the footprint's major axis, each at the level of major / probes.
    glm::dvec4 anisotropic(const glm::dvec2& uv, const glm::dvec2& duv_dx, const glm::dvec2& duv_dy,
                           int max_probes) const;

private:
    struct Level {
        int width = 0, height = 0;
        std::vector<glm::vec4> texels;
    };
    std::vector<Level> levels_;
};

// Blinn-Phong as shaders/splat_render/lighting.glsl computes it (world-space unit vectors).
glm::dvec3 shade_reference(const ReferenceLights& lights, const glm::dvec3& albedo, const glm::dvec3& n,
                           const glm::dvec3& to_eye, double specular, double shininess);

}  // namespace sffd::render
