// glTF 2.0 / GLB reading and writing of splat clouds.
// tinygltf reads (it validates the JSON and resolves buffers, data URIs and images); we write the JSON
// ourselves with nlohmann::json so the layout below is exactly what content/README.md documents.
//
// A splat cloud is written as two nodes, so it shows in any glTF viewer as a point cloud:
//   node "<name>"        TRS = the entity's Transform, extras {"sffd_cloud": <id>}, children [origin node]
//   node "<name>.origin" translation = SplatCloud::origin (double), mesh = one POINTS primitive with
//                        POSITION (float, relative to the origin), NORMAL, COLOR_0 (unsigned short
//                        normalised, linear RGBA, converts back to the sRGB bytes exactly), TEXCOORD_0,
//                        _AXIS_U and _AXIS_V (float VEC3: tangent axes scaled by the splat radii), and a
//                        material (baseColorFactor, baseColorTexture as an embedded PNG, extras
//                        sffd_specular / sffd_shininess).
// Reading such a file back gives the same bytes for every stored array (round-trip tests).
#pragma once

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "runtime/assets/import.h"
#include "runtime/core/result.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"

namespace sffd::assets {

struct GltfModel;  // gltf_model.h

struct GltfCloudOut {
    std::string name;
    int id = -1;  // written as extras.sffd_cloud (scene files refer to clouds by it)
    const Transform* transform = nullptr;
    const SplatCloud* cloud = nullptr;
    const SplatMaterial* material = nullptr;  // nullptr: the defaults
    // The optional columns beside the cloud (gltf_point_columns.h: `_FLAGS`, `_WEIGHT`); nullptr: none.
    const PointFlags* flags = nullptr;
    const PointWeights* weights = nullptr;
};

// More content for the document write_gltf() builds (systems/gaussian: Gaussian clouds embedded in a scene
// file as KHR_gaussian_splatting primitives). Called after the clouds are in `doc` (whose "nodes",
// "meshes", "accessors", "bufferViews" and "extensionsUsed" arrays may be absent); it appends to them
// and to `bin` (buffer 0; keep views 4-byte aligned) and adds its root nodes to doc["scenes"][0]["nodes"].
using GltfAppend = std::function<Status(nlohmann::json& doc, std::string& bin)>;

// Writes .glb (binary) or .gltf (JSON with an embedded base64 buffer) by extension, atomically.
// `sffd_scene_json`, when not empty, becomes the top-level extensions.SFFD_scene object.
Status write_gltf(const std::filesystem::path& path, const std::vector<GltfCloudOut>& clouds,
                  const std::string& sffd_scene_json = {}, const std::vector<GltfAppend>& append = {});

// A GLB container written atomically and piece by piece (never assembled in memory): the header, `text`
// (the JSON, padded to 4 bytes with spaces) and, when `write_bin` is set, a BIN chunk of `bin_bytes` (a
// multiple of 4) that write_bin puts into the file (false: a write failed). Past GLB's 4 GiB it writes
// nothing and says "`path`: `what` too large for a GLB file (4 GiB)". Shared by write_gltf() and the Gaussian
// writer.
Status write_glb_file(const std::filesystem::path& path, std::string text, std::uint64_t bin_bytes,
                      const std::function<bool(std::FILE*)>& write_bin, const std::string& what);

struct GltfCloudIn {
    std::string name;
    int id = -1;
    Transform transform;
    SplatCloud cloud;
    SplatMaterial material;  // the cloud's material (the defaults when the file stores none)
    PointFlags flags;        // `_FLAGS` (empty when the file stores none)
    PointWeights weights;    // `_WEIGHT` (empty when the file stores none)
};

struct GltfContents {
    std::vector<GltfCloudIn> clouds;         // our splat nodes, exactly as stored
    Geometry other;                          // every other mesh/point primitive, in world space
    std::string sffd_scene_json;             // extensions.SFFD_scene as JSON text (empty when absent)
    std::shared_ptr<const GltfModel> model;  // the whole file, for scene extensions that store glTF content
};
// In a scene file (one with SFFD_scene), KHR_gaussian_splatting primitives are not surface geometry:
// read_gltf() leaves them out of `other` (systems/gaussian reads them through `model`).

Result<GltfContents> read_gltf(const std::filesystem::path& path);

// The guarded tinygltf load behind read_gltf(), for every reader of glTF (also systems/gaussian): the file
// size limit, the JSON nesting check before tinygltf's recursive parser, buffer and image URIs resolved
// inside the glTF's folder only (resolve_resource), an image pixel budget, images decoded to RGBA8.
// Errors read "file: problem". A GLB's BIN chunk stays in the file's mapping (gltf_model.h).
Status load_gltf_model(const std::filesystem::path& path, GltfModel& model);

// Accessor `index` of `model` as `components` doubles per element, every offset checked against its
// buffer (hostile files point accessors past the end). Normalised integers map to [0,1] / [-1,1]; float,
// (unsigned) byte, (unsigned) short and unsigned int components. Errors read "src: what: problem", or
// "src: <kChangedWhileRead>" when the mapped file was shortened while the accessor was read.
Result<std::vector<double>> read_gltf_accessor(const GltfModel& model, int index, int components,
                                               const std::string& src, const std::string& what);
// The same checks and messages, as floats decoded straight into `dst` (replaced) as vectors of 2, 3 or 4
// floats: what splat arrays hold, with no array in between (nor a double copy).
// On an error `dst` holds no meaningful values.
Status read_gltf_accessor_into(const GltfModel& model, int index, const std::string& src,
                               const std::string& what, std::vector<glm::vec2>& dst);
Status read_gltf_accessor_into(const GltfModel& model, int index, const std::string& src,
                               const std::string& what, std::vector<glm::vec3>& dst);
Status read_gltf_accessor_into(const GltfModel& model, int index, const std::string& src,
                               const std::string& what, std::vector<glm::vec4>& dst);
// The same checks and messages, as floats written element by element into memory the caller owns: element
// i's `components` values at dst + i * stride (stride >= components), for interleaving attributes into one
// array (a Gaussian's SH coefficients). The accessor must hold exactly `count` elements (the caller checks
// the count first, model.gltf.accessors[index].count, with its own message; a mismatch here is refused).
Status read_gltf_accessor_strided(const GltfModel& model, int index, int components, const std::string& src,
                                  const std::string& what, float* dst, std::size_t stride, std::size_t count);
// COLOR_0 (VEC3 or VEC4, linear) as the cloud's sRGB bytes, R | G << 8 | B << 16 | A << 24 (alpha 255 for
// VEC3), into `dst` (replaced): the same checks and messages, and the same bytes as converting each
// read_gltf_accessor() value with the writer's mapping (gltf_detail.h), without the array of doubles.
Status read_gltf_colors_into(const GltfModel& model, int index, int components, const std::string& src,
                             const std::string& what, std::vector<std::uint32_t>& dst);

}  // namespace sffd::assets
