// `splatffd convert SCENE OUT --selected` and `--entity NAME`: the part of a loaded scene that convert
// writes. Both narrow the registry in place, before convert's usual steps (deformation, writers):
//   --entity NAME   the one cloud (surface splats or Gaussians) named NAME, e.g. a part the editor
//                   separated ("<name>.part"); the other clouds go, and so do the lattices bound only to
//                   them (a scene OUT keeps the cloud's own lattices, clips and bindings)
//   --selected      only the selected points (kPointSelected, neither hidden nor deleted: point_edit's
//                   meaning) of each cloud that has some, every column with them (point_subset.h
//                   extract_points); clouds without a selected point go
// Errors name the file: no cloud of that name, several of that name, no selected point, selected points
// in several clouds for a cloud file OUT (which holds one).
#pragma once

#include <string>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/ecs/registry.h"

namespace sffd::cli {

struct SceneSubset {
    bool selected = false;  // --selected
    std::string entity;     // --entity NAME (empty: every cloud)
    bool active() const { return selected || !entity.empty(); }
};

// Narrows `r` (the scene `in`, loaded) to `subset`. `scene_out`: OUT is a scene file (several clouds
// allowed). Returns the clouds left, in entity order.
Result<std::vector<ecs::Entity>> narrow_scene(ecs::Registry& r, const std::string& in,
                                              const SceneSubset& subset, bool scene_out);

}  // namespace sffd::cli
