// 3D Gaussian clouds as scene entities: loading a Gaussian file as an entity, and Gaussian
// entities in our scene files (runtime/assets/scene.h hooks; assets never links this library).
//
// register_gaussian_scene_hooks(hooks) adds to a registry's SceneHooks, under the key "gaussians":
//   - a scene file loader: load_scene(registry, "x.ply" | "x.splat" | "x.spz" | "x.glb"/"x.gltf") on a
//     Gaussian file (a PLY with f_dc_0/opacity/scale_0/rot_0, .splat, .spz, a glTF whose JSON uses
//     KHR_gaussian_splatting and is not one of our scene files, .ksplat, .sog, a SOG folder or its
//     meta.json, a streamed SOG's lod-meta.json at full detail) creates one Gaussian entity (Name =
//     file stem, Transform, GaussianCloud, GaussianSource) and a default camera when there is none;
//   - a scene extension: save_scene writes every Gaussian entity into SFFD_scene.extensions.gaussians,
//     load_scene reads them back:
//       { "version": 1,
//         "clouds": [ { "name": "g", "file": "g.ply",               // relative to the scene file's folder
//                       "transform": { "translation": [x,y,z], "rotation": [x,y,z,w], "scale": [x,y,z] },
//                       "lattices": [ <scene ids of lattice entities>, ... ] } ] }   // its Deformers, in
//                       order
//     A Gaussian entity without a GaussianSource (made in memory, or converted) is embedded in the scene
//     file itself: its entry has "embedded": true instead of "file", and the glTF holds node "<name>"
//     (TRS = its Transform, extras {"sffd_gaussians": <entry index>}) with a child "<name>.origin"
//     (translation = GaussianCloud::origin) whose mesh is one KHR_gaussian_splatting POINTS primitive
//     (gaussian_gltf.h's layout), so other glTF viewers that know the extension show it in place. (.glb
//     and .gltf alike; a .gltf holds it in its base64 buffer.) Entities loaded from a Gaussian file stay
//     references to it. Errors name the scene, the entry and the Gaussian file or node
//     ("scene.glb: scene extension 'gaussians': clouds[0] (embedded, node 2) mesh 1: ...: problem").
// Call it once at start-up (tools/splatffd/main.cpp does; tests call it themselves).
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/assets/formats/surface/gltf_io.h"
#include "runtime/core/result.h"
#include "runtime/ecs/registry.h"

namespace sffd {
struct SceneHooks;  // runtime/assets/scene.h

// The file a GaussianCloud entity was loaded from (absolute), so a saved scene can refer to it.
struct GaussianSource {
    std::filesystem::path path;
};

namespace gaussian {

// Whether `path` is a Gaussian file load_gaussian_entity() reads (see above; PLY and glTF by content).
bool is_gaussian_scene_file(const std::filesystem::path& path);

// Reads the file and creates its entity (Name, Transform, GaussianCloud, GaussianSource).
Result<ecs::Entity> load_gaussian_entity(ecs::Registry& registry, const std::filesystem::path& path);

// The camera a Gaussian file opens with, added when `registry` has no Camera: assets::add_default_view
// around every cloud's world-space bounds (Gaussians to 3 sigma). Loading a Gaussian file and loading a
// scene whose Gaussians come without a camera both add it, so the two open alike.
void add_default_gaussian_view(ecs::Registry& registry);

// Into a registry's context (runtime/assets/scene.h), e.g. register_gaussian_scene_hooks(SceneHooks::in(r)).
void register_gaussian_scene_hooks(SceneHooks& hooks);

// The extension's two halves, usable without the hook registry (SceneHooks::add_gltf_extension's forms).
Result<std::string> save_gaussian_extension(const ecs::Registry& registry,
                                            const std::function<int(ecs::Entity)>& id_of,
                                            const std::filesystem::path& scene_path,
                                            std::vector<assets::GltfAppend>& append);
Status load_gaussian_extension(ecs::Registry& registry, std::string_view json,
                               const std::function<ecs::Entity(int)>& entity_of,
                               const std::filesystem::path& scene_path, const assets::GltfModel& model);

}  // namespace gaussian
}  // namespace sffd
