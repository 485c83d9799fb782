// Scenes: built-in names, importable files and our glTF scene files.
// The file format is documented in content/README.md.
//
//   load_scene(registry, "sphere")            built-in: textured sphere, 59,650 splats, 11x11x11 lattice
//   load_scene(registry, "face")              built-in: real head scan, 40,880 splats, 11x11x11 lattice
//                                             (made by tools/fetch_content.sh into paths::cache_dir())
//   load_scene(registry, "scan.ply")          any importable file (PLY, OBJ, OFF, glTF/GLB): one cloud
//   load_scene(registry, "saved.glb")         a saved scene: clouds, lattices, deformer bindings, camera,
//                                             lights and every registered extension's data
//   save_scene(registry, "out.glb")           atomic; .glb or .gltf
//
// Loaded entities: point clouds get Name, Transform, SplatCloud (+ Deformers when bound to lattices);
// lattices get Name, Transform, Lattice; cameras get Name + Camera; lights Name + DirectionalLight or
// AmbientLight. Loading adds to the registry; it does not clear it.
//
// Extensions: a system that cannot be a dependency of assets (animation, editor) stores its own data in
// the scene file through a pair of functions kept in a SceneHooks object (below), which lives in the
// registry's context: load_scene and save_scene use the registry's own SceneHooks resource, so what a
// registry opens is decided where it is set up (systems/engine: use_engine_scene_hooks(registry)):
//     hooks.add_extension("animation", save_clips, load_clips);
// There is no process-wide set: a registry without a SceneHooks resource is refused by load_scene and
// save_scene with "no scene loaders registered in this registry". A registry that should open only what
// assets imports itself holds an empty one: registry.set_resource<SceneHooks>().
// save_fn returns a JSON text (or an empty string for "nothing to store"); it refers to entities through
// `id_of(entity)` (-1 for entities the file does not hold). load_fn receives that JSON text and
// `entity_of(id)` to find the loaded entities again. It runs after all clouds, lattices, cameras and
// lights exist. Unknown extension keys in a file are kept out of the registry and reported at debug level.
#pragma once

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "runtime/assets/formats/surface/gltf_io.h"
#include "runtime/core/result.h"
#include "runtime/ecs/entity.h"
#include "runtime/ecs/registry.h"

namespace sffd {

Status load_scene(ecs::Registry& registry, const std::string& name_or_path);
Status save_scene(const ecs::Registry& registry, const std::filesystem::path& path);
std::vector<std::string> builtin_scene_names();

using SceneIdOf = std::function<int(ecs::Entity)>;
using SceneEntityOf = std::function<ecs::Entity(int)>;
using SceneSaveFn = std::function<Result<std::string>(const ecs::Registry&, const SceneIdOf& id_of)>;
using SceneLoadFn =
    std::function<Status(ecs::Registry&, std::string_view json, const SceneEntityOf& entity_of)>;

// SceneHooks::add_extension stores (or replaces) an extension under `key` in the file's
// SFFD_scene.extensions object.
//
// An extension that also stores glTF content in the scene file (systems/gaussian: clouds embedded as
// KHR_gaussian_splatting primitives) gets the scene file's path; saving, it may add GltfAppend functions
// (formats/surface/gltf_io.h) that write nodes, meshes and accessors into the document; loading, it gets the
// file's parsed model (gltf_model.h; never null there). Its JSON must find its content again without indices
// known at save time (systems/gaussian marks its nodes with extras). Same key space as above
// (SceneHooks::add_gltf_extension).
using SceneGltfSaveFn = std::function<Result<std::string>(const ecs::Registry&, const SceneIdOf& id_of,
                                                          const std::filesystem::path& scene_path,
                                                          std::vector<assets::GltfAppend>& append)>;
using SceneGltfLoadFn =
    std::function<Status(ecs::Registry&, std::string_view json, const SceneEntityOf& entity_of,
                         const std::filesystem::path& scene_path, const assets::GltfModel& model)>;

// Files assets cannot import itself (3D Gaussian files: 3DGS PLY, .splat, .spz, KHR_gaussian_splatting
// glTF; added by systems/gaussian, SceneHooks::add_file_loader): load_scene(registry, path) asks every
// loader, in key order, before its own importers; the first whose `claims(path)` is true loads the file (its
// entities, and a default Camera when the registry has none, like an imported point cloud). `types` names
// what the loader opens (e.g. ".spz, .sog"): the one list a refused file's message gives.
using SceneFileClaim = std::function<bool(const std::filesystem::path&)>;
using SceneFileLoader = std::function<Status(ecs::Registry&, const std::filesystem::path&)>;

// Every file type load_scene(registry, ...) opens: assets' own importers, then each of the registry's
// loaders' `types` (only assets' own without a SceneHooks resource).
std::string scene_file_types(const ecs::Registry& registry);

// Built-in scenes have no file for an extension to read, so a system that adds defaults to them (the
// animation's paper demo clip) adds a hook (SceneHooks::add_builtin_hook) that runs after a built-in
// scene's entities exist, with the scene name and exactly the entities that load created.
using BuiltinSceneHook =
    std::function<void(ecs::Registry&, const std::string& scene, const std::vector<ecs::Entity>& created)>;

// Everything above that a system adds (extensions, file loaders, built-in scene hooks), as one value. A
// registry holds one as a resource (its context): load_scene/save_scene use it, in key order. A registry
// that makes another registry (a probe, a copy) passes its hooks on: SceneHooks::copy_to.
struct SceneHooks {
    struct Extension {
        SceneGltfSaveFn save;
        SceneGltfLoadFn load;
    };
    struct FileLoader {
        SceneFileClaim claims;
        SceneFileLoader load;
        std::string types;
    };
    std::map<std::string, Extension> extensions;
    std::map<std::string, FileLoader> file_loaders;
    std::map<std::string, BuiltinSceneHook> builtin_hooks;

    // Each adds (or replaces) what is stored under `key`.
    void add_extension(const std::string& key, SceneSaveFn save_fn, SceneLoadFn load_fn);
    void add_gltf_extension(const std::string& key, SceneGltfSaveFn save_fn, SceneGltfLoadFn load_fn);
    void add_file_loader(const std::string& key, SceneFileClaim claims, SceneFileLoader load,
                         std::string types = {});
    void add_builtin_hook(const std::string& key, BuiltinSceneHook hook);
    // Drops every kind stored under `key`.
    void remove(const std::string& key);
    std::string file_types() const;

    // The registry's SceneHooks resource; null when it has none.
    static const SceneHooks* of(const ecs::Registry& registry);
    // The registry's SceneHooks resource, made (empty) when it has none: where a registry's set-up adds
    // a system's hooks, e.g. register_animation_scene_hooks(SceneHooks::in(registry)).
    static SceneHooks& in(ecs::Registry& registry);
    // Gives `to` a copy of `from`'s SceneHooks resource (nothing when `from` has none).
    static void copy_to(const ecs::Registry& from, ecs::Registry& to);
};

}  // namespace sffd
