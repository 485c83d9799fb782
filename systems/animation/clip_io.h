// Clip storage as JSON (the scene file stores this object; content/README.md documents the schema).
//
//   { "name": "paper demo", "duration": 4.0, "mode": "loop" | "once" | "ping_pong", "speed": 1.0,
//     "tracks": [ { "name": "local stretch", "kind": "stretch" | "twist", "points": [12, 13, ...],
//                   "axis": [0, 0, 1], "pivot": [x, y, z],              (twist only; pivot optional)
//                   "keys": [ { "time": 0.5, "value": [dx, dy, dz],      (stretch)
//                               "angle": 720.0,                         (twist, degrees)
//                               "interpolation": "step" | "linear" | "smooth",
//                               "easing": "none" | "ease_in" | "ease_out" | "ease_in_out" } ] } ] }
//
// Round trip is exact: doubles are written with enough digits (max_digits10 or the shortest form that
// reads back to the same bits). Twist keys store only the angle (Keyframe::value.x; y and z read as 0).
// Reading validates types, names and numbers (finite, duration > 0, key times increasing) and reports
// "SOURCE: tracks[1].keys[0].time: expected a number". Point indices are checked against the lattice
// by validate_clip() when the clip is attached.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json_fwd.hpp>

#include "runtime/core/result.h"
#include "systems/animation/components.h"

namespace sffd {

nlohmann::json clip_to_json(const AnimationClip& clip);
// `source` names the file (or file + location) in error messages.
Result<AnimationClip> clip_from_json(const nlohmann::json& json, const std::string& source);

std::string clip_to_string(const AnimationClip& clip);  // pretty-printed JSON
Result<AnimationClip> parse_clip(std::string_view text, const std::string& source);

Status save_clip(const AnimationClip& clip, const std::filesystem::path& path);  // write_file_atomic
Result<AnimationClip> load_clip(const std::filesystem::path& path);

}  // namespace sffd
