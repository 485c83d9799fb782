// Importing point clouds and meshes as splat clouds.
//
// Two steps, so `splatffd info` can look at a file without estimating anything:
//   1. read_geometry(path): PLY (ascii/binary, any vertex properties, faces allowed), OBJ (+ .mtl map_Kd),
//      OFF (OFF/COFF/NOFF), glTF 2.0 / GLB (POINTS primitives; triangle meshes with base-colour
//      textures). Positions are kept in double precision; every number is checked (NaN/inf refused).
//   2. make_splat_cloud(geometry, options): meshes are sampled on their surface (area-weighted, blue-noise
//      thinned, exactly `splats` samples; colour from vertex colours or the base-colour texture, normal
//      from the triangle; a mesh with one untinted texture keeps it, with per-splat uv and uv frame), point
//      sets are used as they are (or thinned to `splats`); missing normals and radii are estimated
//      (splat_estimation.h). Positions become float offsets from a double origin: the bounding-box centre
//      when the cloud is far from the world origin, else 0.
// Every error names the file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/progress.h"
#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd::assets {

struct Image {
    int width = 0, height = 0;
    std::vector<std::uint8_t> rgba8;  // row 0 at v = 0 (glTF/OBJ convention handled by the importer)
};

struct MeshMaterial {
    glm::vec4 base_color{1.0f};  // multiplies the texture / vertex colour (linear factor, glTF style)
    int texture = -1;            // index into Geometry::textures
};

// What a file holds before it becomes splats.
struct Geometry {
    std::string source;                     // file path, for messages
    std::vector<glm::dvec3> positions;      // world space
    std::vector<glm::vec3> normals;         // empty or one per position
    std::vector<std::uint32_t> colors;      // RGBA8 sRGB, R in the low byte; empty or one per position
    std::vector<glm::vec2> uvs;             // empty or one per position
    std::vector<glm::vec3> axis_u, axis_v;  // splat axes, when the file stores them (our PLY/GLB)
    // uv frame along those axes (SplatCloud::uv_axes), when the file stores it (our PLY/GLB; needs the axes).
    std::vector<glm::vec4> uv_axes;
    // Texture-space gradients (world space, in the surface's tangent plane): near point i,
    // uv(p) = uvs[i] + (dot(uv_grad_u[i], p - x_i), dot(uv_grad_v[i], p - x_i)). Made by mesh sampling from
    // each triangle's affine 3D -> uv map; make_splat_cloud turns them into uv_axes once the axes exist.
    std::vector<glm::vec3> uv_grad_u, uv_grad_v;
    std::vector<std::uint32_t> triangles;         // 3 vertex indices per triangle (meshes)
    std::vector<std::int32_t> triangle_material;  // empty or one per triangle, index into materials
    std::vector<MeshMaterial> materials;
    std::vector<Image> textures;
    SplatTexture splat_texture;    // stored texture of a splat file (kept, not baked)
    SplatMaterial splat_material;  // stored material of a splat file (our GLB), else the defaults
    bool has_origin = false;       // file recorded the cloud's origin (our PLY/GLB)
    glm::dvec3 origin{0.0};
    std::vector<std::string> attributes;  // per-point attribute names found (for `splatffd info`)

    std::size_t triangle_count() const { return triangles.size() / 3; }
};

Result<Geometry> read_geometry(const std::filesystem::path& path);
Result<Geometry> read_ply_geometry(const std::filesystem::path& path);
Result<Geometry> read_obj_geometry(const std::filesystem::path& path);
Result<Geometry> read_off_geometry(const std::filesystem::path& path);
Result<Geometry> read_gltf_geometry(const std::filesystem::path& path);  // .gltf and .glb
// A Potree 2 octree's metadata.json, every node (formats/surface/potree2.h); another tool's (no splat axes)
// gives points whose normals and radii make_splat_cloud estimates.
Result<Geometry> read_potree2_geometry(const std::filesystem::path& path);

struct ImportOptions {
    std::size_t splats = 0;  // exact splat count; 0 = one per point (point sets) or per vertex (meshes)
    bool estimate_normals = false;  // re-estimate normals even when the file has them
    bool estimate_radii = false;    // re-estimate radii even when the file has splat axes
    int neighbours = 16;            // k for PCA and orientation
    std::uint32_t seed = 1;         // surface sampling is deterministic for a given seed
    // Without `splats`, a mesh gives one splat per used vertex, unless it has fewer used vertices than
    // this (a textured box has 24): then its surface is sampled with this many splats instead.
    std::size_t min_mesh_splats = 20000;
    // Each step's progress (sampling, thinning, neighbours, normals, radii); splatffd convert prints it.
    ProgressFn progress;
};

Result<SplatCloud> make_splat_cloud(const Geometry& geometry, const ImportOptions& options);
// `material`, when given, receives the file's stored material (the defaults when it stores none): the cloud
// and its material are separate components (runtime/scene/components.h).
Result<SplatCloud> import_splat_cloud(const std::filesystem::path& path, const ImportOptions& options = {},
                                      SplatMaterial* material = nullptr);

// Mesh surface sampling used by make_splat_cloud: exactly `count` points, area-weighted, thinned from
// 4x candidates by weighted sample elimination (Yuksel 2015) so they are evenly spread.
Result<Geometry> sample_surface(const Geometry& mesh, std::size_t count, std::uint32_t seed,
                                const ProgressFn& progress = {});

// Chooses the origin for float positions (bbox centre when far from 0, else 0; see above).
glm::dvec3 choose_origin(const std::vector<glm::dvec3>& positions);

}  // namespace sffd::assets
