// glTF 2.0 `KHR_gaussian_splatting` (Khronos, ratified): read (.glb / .gltf through tinygltf) and
// write (.glb) 3D Gaussian clouds.
//
// Conventions of the extension (ratified text; the earlier review draft stored SCALE in log space,
// which the ratified text and @playcanvas/splat-transform 3.x do not):
//   POSITION                                  VEC3 float
//   KHR_gaussian_splatting:ROTATION           VEC4 (x, y, z, w), float or normalised byte/short
//   KHR_gaussian_splatting:SCALE              VEC3 LINEAR standard deviations, float or (normalised)
//   byte/short KHR_gaussian_splatting:OPACITY            SCALAR LINEAR [0, 1], float or normalised
//   ubyte/ushort KHR_gaussian_splatting:SH_DEGREE_0_COEF_0 VEC3 float, the DC coefficients (colour = 0.5 +
//   C0·dc) KHR_gaussian_splatting:SH_DEGREE_l_COEF_n VEC3 float (RGB) per coefficient, l = 1..3, n = 0..2l
//     (n in the 3DGS / Condon–Shortley order, i.e. our k = l² + n)
//   COLOR_0                                   optional fallback (we write it; we read it only when
//                                             SH_DEGREE_0_COEF_0 is absent)
// Reading: every POINTS primitive with the extension in the default scene (without `scenes`: the nodes
// that are nobody's child), each node visited once (a node with two parents is refused, so a DAG cannot
// multiply the work), placed by its node's world
// matrix (a non-rigid node matrix is applied like a deformation: Σ' = A Σ Aᵀ, SH rotated by the polar
// rotation of A); primitives of different SH degrees are merged at the lowest degree. Errors name the
// file and the problem (missing attribute, count mismatch, partial SH degree, a degree present without
// the one below it, more than kMaxGaussians, negative scale, opacity
// outside [0,1], non-finite values, accessors outside their buffers).
// Axes: glTF is y up with +z the asset's front (x left); the internal frame is the 3DGS PLY one (x right,
// y down, z forward), the same axes turned 180° about z, which is also how splat-transform converts PLY
// to GLB. read_gltf turns the placed cloud into the internal frame and write_glb back (positions,
// rotations and SH signs together, exact: gaussian_axes.h). Scene files are not turned:
// read_primitive/append_primitive keep a cloud as stored, because a scene's clouds are placed against
// its lattices by the same nodes, so both are in the scene's one frame (gaussian_scene.h).
#pragma once

#include <filesystem>
#include <string>

#include <glm/glm.hpp>
#include <nlohmann/json_fwd.hpp>

#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace tinygltf {
struct Primitive;
}  // namespace tinygltf
namespace sffd::assets {
struct GltfModel;
}  // namespace sffd::assets

namespace sffd::gaussian {

// How a node's world matrix x -> A x + t is applied to the cloud of one of its primitives. A non-rigid
// matrix needs the covariance and SH rotation maths of systems/gaussian, which the formats do not link:
// that layer passes its gaussian::apply_affine (systems/gaussian/gaussian_read.h, whose read_gltf(path)
// and read_gaussians(path) are what commands and systems call).
using NodePlacement = void (*)(GaussianCloud& cloud, const glm::dmat3& a, const glm::dvec3& t);

Result<GaussianCloud> read_gltf(const std::filesystem::path& path, NodePlacement place);

// What a glTF/GLB file declares, read from its JSON (the GLB's JSON chunk) without tinygltf: whether
// `extensionsUsed` or `extensionsRequired` lists KHR_gaussian_splatting, and whether it is one of our
// scene files (top-level `extensions.SFFD_scene`). A file that declares the extension is read as
// Gaussians or refused, never reinterpreted by the surface importer. Unreadable or invalid JSON declares
// nothing (the reader that opens it next reports the problem).
struct GltfDeclaration {
    bool gaussian_splatting = false;
    bool sffd_scene = false;
};
GltfDeclaration gltf_declaration(const std::filesystem::path& path);
// One node (translation = the turned cloud.origin) with one POINTS primitive, in glTF's frame (above);
// written atomically. .glb only.
Status write_glb(const std::filesystem::path& path, const GaussianCloud& cloud);

// The halves behind read_gltf / write_glb, for glTF documents that hold more than one cloud (scene files,
// systems/gaussian/gaussian_scene.cpp). append_primitive() writes `cloud` (validated; no sh_frames) as
// accessors and buffer views into `doc` ("accessors" and "bufferViews" arrays created when absent; views
// refer to buffer 0 = `bin`, 4-byte aligned) and returns the POINTS primitive's JSON (positions as stored,
// relative to cloud.origin). read_primitive() reads one such primitive with every check read_gltf makes;
// errors read "where: problem".
Status append_primitive(nlohmann::json& doc, std::string& bin, const GaussianCloud& cloud,
                        nlohmann::json& primitive, const std::string& where);
Result<GaussianCloud> read_primitive(const assets::GltfModel& model, const tinygltf::Primitive& primitive,
                                     const std::string& where);

}  // namespace sffd::gaussian
