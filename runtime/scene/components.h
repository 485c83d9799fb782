// Components shared by several systems. Plain aggregates: no behaviour, no GL names, no pointers.
// Authored data (SplatCloud) is never overwritten by derived data: the deformer writes its own output
// component (systems/ffd), the renderer reads whichever is present.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

namespace sffd {

struct Name {
    std::string value;
};

// Placement in the world. Point positions are stored relative to SplatCloud::origin (double), so scans
// far from the world origin (offsets of 1e6) keep float precision.
struct Transform {
    glm::dvec3 translation{0.0};
    glm::dquat rotation{1.0, 0.0, 0.0, 0.0};
    glm::dvec3 scale{1.0};
};

// Texture of a splat cloud, looked up at each splat's uv. Authored with the cloud (its uvs index it, and
// nothing edits it), so it lives in SplatCloud; empty: per-splat colours (or the material's base colour).
struct SplatTexture {
    std::string path;  // the file it came from (empty: embedded or procedural)
    int width = 0, height = 0;
    std::vector<std::uint8_t> rgba8;  // decoded texels, row 0 at v = 0, sRGB-encoded
};

// Shading of a splat cloud: its own component on the cloud's entity (absent: these defaults), apart from
// SplatCloud so that editing it changes only the render: the cloud's change stamp, its deformation, its
// GPU upload and its picking scene stay as they are, and an undo step holds two of these, not the cloud.
struct SplatMaterial {
    glm::vec4 base_color{0.8f, 0.8f, 0.8f, 1.0f};  // linear RGBA when no texture and no colours
    float specular = 0.3f;
    float shininess = 32.0f;

    bool operator==(const SplatMaterial&) const = default;
};

// Authored point cloud: one splat per point. Arrays are structure-of-arrays and either empty or of
// length `size()`. Splat i is the ellipse centred at origin + positions[i], spanned by axis_u[i] and
// axis_v[i] (their lengths are the radii; a circular splat has |axis_u| = |axis_v|), facing normals[i].
struct SplatCloud {
    glm::dvec3 origin{0.0};  // world offset of every position (double precision)
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;     // unit length
    std::vector<glm::vec3> axis_u;      // tangent axis scaled by radius
    std::vector<glm::vec3> axis_v;      // bitangent axis scaled by radius (normal x axis_u direction)
    std::vector<std::uint32_t> colors;  // RGBA8, sRGB-encoded, R in the low byte
    std::vector<glm::vec2> uvs;         // texture coordinates (when there is a texture)
    // uv derivatives along the splat's axes: the point positions[i] + s * axis_u[i] + t * axis_v[i] has
    // uv = uvs[i] + s * uv_axes[i].xy + t * uv_axes[i].zw (first order). Per axis, so they hold for the
    // deformed axes too (FFD maps the axes by the Jacobian). Empty: one texture lookup per splat.
    std::vector<glm::vec4> uv_axes;
    SplatTexture texture;

    std::size_t size() const { return positions.size(); }
};

// On a point-cloud entity whose splats sample a known analytic surface (the built-in sphere): the sphere
// in cloud space (relative to SplatCloud::origin). Authored data, read by the ground-truth ray tracer
// (systems/splat_render/ground_truth.h), which renders this surface instead of the splats.
struct ExactSphere {
    glm::dvec3 center{0.0};
    double radius = 1.0;
};

// On a point-cloud entity whose splats sample a triangle mesh (`splatffd reference` attaches it to a mesh
// file's cloud): the mesh in cloud space (relative to SplatCloud::origin), read by the ground-truth ray
// tracer, which renders these triangles (textured through `uvs` with the cloud's texture and material)
// instead of the splats. Authored data.
struct ExactMesh {
    std::vector<glm::dvec3> positions;
    std::vector<glm::vec3> normals;        // empty: the triangles' own normals; else one per position
    std::vector<glm::vec2> uvs;            // empty or one per position
    std::vector<std::uint32_t> triangles;  // 3 indices per triangle
};

// Perspective camera looking down its local -Z; placed by the entity's Transform or by look-at fields.
struct Camera {
    glm::dvec3 eye{0.0, 0.0, 3.0};
    glm::dvec3 target{0.0};
    glm::dvec3 up{0.0, 1.0, 0.0};
    float fov_y_degrees = 45.0f;
    float near_plane = 0.01f;
    float far_plane = 100.0f;
};

// Directional light (direction the light travels, world space) in linear RGB.
struct DirectionalLight {
    glm::vec3 direction{-0.4f, -0.6f, -0.7f};
    glm::vec3 color{1.0f};
    float intensity = 1.0f;
};

struct AmbientLight {
    glm::vec3 color{1.0f};
    float intensity = 0.15f;
};

}  // namespace sffd
