// Where a command's `--lattice SOURCE` comes from (shared by `deform`, `convert` and `info`):
//   L.json                 a lattice JSON file (systems/ffd/README.md)
//   scene.glb|scene.gltf   a scene file (the editor's save, `convert … --lattice fit`): the lattices bound
//                          to its cloud, in order, or the one named by --lattice-name
//   fit[:L,M,N][,pad=P][,obb][,bspline]
//                          a rest lattice fitted around the cloud being processed (ffd::parse_fit_spec)
// Errors read `file: problem` and say what to do (no lattice, several without a name, unknown name).
#pragma once

#include <span>
#include <string>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"
#include "systems/ffd/operations.h"

namespace sffd::cli {

struct LatticeChain {
    std::vector<Lattice> lattices;   // applied in order (a cloud's Deformers order), in the frame of
                                     // `cloud`'s points (ffd::lattice_to_cloud: both Transforms)
    std::vector<std::string> names;  // same order
    ecs::Entity cloud{};             // the cloud they are bound to in the scene (null when none)
};

// The lattices of a loaded scene (`file` names it in messages). With `name`: exactly the lattice of that
// name. Without: the chain bound to the scene's one deformed cloud, or the scene's only lattice;
// several bound clouds or several unbound lattices without a name are an error listing the names.
Result<LatticeChain> pick_scene_lattices(const ecs::Registry& registry, const std::string& file,
                                         const std::string& name);

// Loads `source` when it is a lattice JSON or a scene file (not a fit spec: the caller fits, it has the
// points). `name` (--lattice-name) applies to scene files only.
Result<LatticeChain> load_lattice_source(const std::string& source, const std::string& name);

// ffd::fit_lattice for a command's `--lattice fit:...`: an ",obb" request that comes back axis-aligned
// (a near-isotropic cloud: its principal axes give no box 5% smaller) says so on stderr, once, instead of
// letting the printed spec claim an oriented box.
Result<Lattice> fit_lattice_for(const std::string& command, const std::vector<glm::vec3>& positions,
                                const glm::dvec3& origin, const ffd::FitOptions& fit);

bool is_scene_path(const std::string& path);  // .glb / .gltf (any case)
bool is_json_path(const std::string& path);   // .json (any case)

// A scene holding `cloud` (Name `cloud_name`) and, when given, `lattices` bound to it in order (Name
// "<cloud_name>.lattice", then ".lattice2", …), saved atomically as .glb/.gltf. `weights` (empty, or one
// per point): the cloud's PointWeights.
Status save_cloud_with_lattices(SplatCloud cloud, const std::string& cloud_name,
                                const std::vector<Lattice>& lattices, const std::string& path,
                                const SplatMaterial& material = {}, std::span<const float> weights = {});

}  // namespace sffd::cli
