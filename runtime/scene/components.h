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

// A GaussianCloud is the authored cloud as loaded (3DGS PLY, .splat, or converted from a surface cloud);
// the deformation writes a separate DeformedGaussians, the authored cloud is never overwritten.
//
// Conventions (every importer and exporter converts to and from these, see
// runtime/assets/formats/gaussian/gaussian_io.h):
// - positions relative to `origin` (double), like SplatCloud, so far-away scenes keep float precision;
// - scales: LINEAR standard deviations along the Gaussian's local x, y, z axes (3DGS PLY stores log);
// - rotations: unit quaternions, glm::quat (construct with glm::quat(w, x, y, z); 3DGS PLY stores
//   rot_0..3 = w, x, y, z; glTF stores x, y, z, w). The covariance is Σ = R S Sᵀ Rᵀ with R = mat3_cast(q)
//   and S = diag(scale);
// - opacities: LINEAR in [0, 1] (3DGS PLY stores the logit);
// - sh: spherical-harmonic colour coefficients in the 3DGS basis (systems/gaussian/sh.h), degree
//   `sh_degree` (0..3), K = (sh_degree+1)² coefficients per channel, stored per splat coefficient-major
//   with RGB interleaved: sh[(i*K + k)*3 + c] for splat i, coefficient k (k = 0 is the DC term), channel c.
//   The colour seen along direction d (from the camera to the splat) is max(0, 0.5 + Σ_k sh_k Y_k(d)).
//   (3DGS PLY stores f_dc_0..2 = k 0 for R,G,B, then f_rest per CHANNEL: all R coefficients k=1..K-1,
//   then G, then B.)
struct GaussianCloud {
    glm::dvec3 origin{0.0};
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> scales;
    std::vector<glm::quat> rotations;
    std::vector<float> opacities;
    int sh_degree = 0;
    std::vector<float> sh;  // size() * sh_coeffs(sh_degree) * 3
    // Derived clouds only (deformation with ShMode::rotate_view): when not empty, the colour of splat i
    // along d is evaluated at sh_frames[i]ᵀ d (its SH coefficients were left unrotated; the frame is the
    // orthogonal polar factor of the deformation, a reflection when the cell inverted). Authored clouds
    // and files never carry frames (writers refuse them: bake_sh_frames() first).
    std::vector<glm::mat3> sh_frames;

    std::size_t size() const { return positions.size(); }
};

// Coefficients per channel for a degree: 1, 4, 9, 16.
constexpr int sh_coeffs(int degree) { return (degree + 1) * (degree + 1); }

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
