// The note every command prints about a loaded scene's un-keyed edits (systems/animation/unkeyed_edit.h),
// so `render`, `deform`, `convert` and `pick` say which pose they show. One line each on stderr:
//   splatffd render: note: 'sphere.lattice' has an un-keyed edit at clip time 0 s (48 control points off
//   the clip's pose, up to 1.794): shown at that time only, the clip's pose at every other (frame 0 at 24
//   fps)
#pragma once

#include <optional>
#include <string_view>

#include "runtime/ecs/registry.h"

namespace sffd::cli {

// `fps`: the command plays the clip (render): the note names the edit's frame. Without it the command
// uses the control points as saved, and the note says whether those are the edit.
void note_unkeyed_edits(std::string_view command, const ecs::Registry& registry,
                        std::optional<double> fps = std::nullopt);

}  // namespace sffd::cli
