// Animation in scene files and built-in scenes (runtime/assets/scene.h hooks; assets never links animation).
//
// register_animation_scene_hooks(hooks) adds to a registry's SceneHooks, under the key "animation":
//   - a scene extension: save_scene writes every lattice's clip into the glTF file's
//     SFFD_scene.extensions.animation object, load_scene reads it back (exact round trip):
//       { "version": 1,
//         "clips": [ { "lattice": <scene id of the lattice entity>, "speed": 1.0,
//                      "time": <clip time the lattice's saved control points were shown at>,
//                      "clip": { ...clip_io.h schema... },
//                      "unkeyed_edit": { "time": t, "control_points": [[x, y, z], ...] } } ] }
//     "unkeyed_edit" (only when there is one, components.h UnkeyedEdit) holds every control point. A
//     file without "time" (older versions) was saved at 0 s: control points off the clip's pose there
//     load as an un-keyed edit at 0 s. Loading sets AnimationState::time to the saved time; the clip
//     still plays from 0 s.
//   - a built-in scene hook: `sphere` and `face` get make_paper_demo_clip() on their lattice, playing.
// Each registry that loads or saves scenes gets it in its set-up (systems/engine: use_engine_scene_hooks).
#pragma once

#include <functional>
#include <string>
#include <string_view>

#include "runtime/core/result.h"
#include "runtime/ecs/registry.h"

namespace sffd {

struct SceneHooks;
// Into a registry's context (runtime/assets/scene.h), e.g. register_animation_scene_hooks(SceneHooks::in(r)).
void register_animation_scene_hooks(SceneHooks& hooks);

// The extension's two halves, usable without the hook registry (tests, tools).
Result<std::string> save_animation_extension(const ecs::Registry& registry,
                                             const std::function<int(ecs::Entity)>& id_of);
Status load_animation_extension(ecs::Registry& registry, std::string_view json,
                                const std::function<ecs::Entity(int)>& entity_of);

}  // namespace sffd
