#include "systems/animation/unkeyed_edit.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "runtime/scene/components.h"
#include "systems/animation/editing.h"
#include "systems/animation/evaluate.h"
#include "systems/ffd/components.h"

namespace sffd {

bool shows_unkeyed_edit(const UnkeyedEdit& edit, double clip_time) {
    return std::abs(clip_time - edit.time) <= key_time_epsilon;
}

std::optional<UnkeyedEdit> current_unkeyed_edit(const ecs::Registry& registry, ecs::Entity e) {
    const AnimationClip* clip = registry.try_get<AnimationClip>(e);
    const AnimationState* state = registry.try_get<AnimationState>(e);
    const Lattice* lattice = registry.try_get<Lattice>(e);
    if (!clip || !state || !lattice || !validate_clip(*clip, lattice->rest.size())) return std::nullopt;
    if (lattice->current.size() == lattice->rest.size() &&
        lattice->current != evaluate_pose(*clip, *lattice, state->time))
        return UnkeyedEdit{state->time, lattice->current};
    const UnkeyedEdit* held = registry.try_get<UnkeyedEdit>(e);
    if (held && held->points.size() == lattice->rest.size() && !shows_unkeyed_edit(*held, state->time))
        return *held;
    return std::nullopt;
}

std::vector<UnkeyedEditReport> unkeyed_edits(const ecs::Registry& registry) {
    std::vector<UnkeyedEditReport> reports;
    registry.view<const AnimationClip, const Lattice>().each(
        [&](ecs::Entity e, const AnimationClip& clip, const Lattice& lattice) {
            const std::optional<UnkeyedEdit> edit = current_unkeyed_edit(registry, e);
            if (!edit) return;
            UnkeyedEditReport r;
            r.lattice = e;
            const Name* name = registry.try_get<Name>(e);
            r.name = name && !name->value.empty() ? "'" + name->value + "'" : "the lattice";
            r.time = edit->time;
            const std::vector<glm::dvec3> pose = evaluate_pose(clip, lattice, edit->time);
            for (std::size_t i = 0; i < pose.size() && i < edit->points.size(); ++i) {
                if (edit->points[i] == pose[i]) continue;
                ++r.points;
                r.max_offset = std::max(r.max_offset, glm::length(edit->points[i] - pose[i]));
            }
            reports.push_back(std::move(r));
        });
    return reports;
}

std::string describe_unkeyed_edit(const UnkeyedEditReport& r) {
    char text[160];
    std::snprintf(text, sizeof text,
                  "un-keyed edit at clip time %.6g s (%zu control points off the clip's pose, up to %.4g)",
                  r.time, r.points, r.max_offset);
    return std::string(text) + ": shown at that time only, the clip's pose at every other";
}

}  // namespace sffd
