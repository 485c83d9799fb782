// The undo step of a change of a lattice's un-keyed edit (UnkeyedEdit), as small as what moved. Between
// two edits the SparseUndo<UnkeyedEdit> delta of undo_delta.h applies. An edit made where there was none
// (or removed by keying it) holds the whole pose, so that side is stored as the points where the edit
// differs from the clip's pose at its time: the step evaluates the clip again when it brings the edit
// back. The stack is linear, so the clip and the rest lattice are then bit for bit what they were when the
// step was made, and so is the pose (evaluate.h is deterministic).
#pragma once

#include <memory>
#include <optional>
#include <string>

#include "systems/animation/components.h"
#include "systems/animation/evaluate.h"
#include "systems/editor/undo_stack.h"
#include "systems/ffd/components.h"

namespace sffd::editor {

class UnkeyedEditAppears final : public Command {
public:
    // `edit` is the one side that has an edit; `appears`: it is the after side (made), else the before
    // side (removed). `pose` is the clip's pose at edit.time.
    UnkeyedEditAppears(std::string label, ecs::Entity e, const UnkeyedEdit& edit,
                       const std::vector<glm::dvec3>& pose, bool appears)
        : Command(std::move(label)),
          m_entity(e),
          m_time(edit.time),
          m_appears(appears),
          m_delta(PointsDelta::between(pose, edit.points)) {
        m_delta.index.shrink_to_fit(), m_delta.before.shrink_to_fit(), m_delta.after.shrink_to_fit();
    }
    void undo(ecs::Registry& registry, EntityMap& map) const override { apply(registry, map, !m_appears); }
    void redo(ecs::Registry& registry, EntityMap& map) const override { apply(registry, map, m_appears); }
    std::size_t bytes() const override { return sizeof(*this) + label().capacity() + m_delta.bytes(); }

private:
    void apply(ecs::Registry& registry, const EntityMap& map, bool present) const {
        const ecs::Entity e = map(m_entity);
        if (!registry.valid(e)) return;
        if (!present) return registry.remove<UnkeyedEdit>(e);
        const AnimationClip* clip = registry.try_get<AnimationClip>(e);
        const Lattice* lattice = registry.try_get<Lattice>(e);
        if (!clip || !lattice) return;
        UnkeyedEdit edit{m_time, evaluate_pose(*clip, *lattice, m_time)};
        m_delta.apply(edit.points, true);
        if (registry.has<UnkeyedEdit>(e)) registry.patch<UnkeyedEdit>(e) = std::move(edit);
        else registry.emplace<UnkeyedEdit>(e, std::move(edit));
    }

    ecs::Entity m_entity;
    double m_time;
    bool m_appears;
    PointsDelta m_delta;  // before: the clip's pose, after: the edit
};

// The step from `before` to `after` (absent: no edit) of lattice `e`'s un-keyed edit, with the registry's
// clip and lattice as they are now (call before changing the clip).
inline std::unique_ptr<Command> unkeyed_edit_change(std::string label, const ecs::Registry& registry,
                                                    ecs::Entity e, std::optional<UnkeyedEdit> before,
                                                    std::optional<UnkeyedEdit> after) {
    const AnimationClip* clip = registry.try_get<AnimationClip>(e);
    const Lattice* lattice = registry.try_get<Lattice>(e);
    if (before.has_value() != after.has_value() && clip && lattice &&
        validate_clip(*clip, lattice->rest.size())) {
        const UnkeyedEdit& edit = after ? *after : *before;
        std::vector<glm::dvec3> pose = evaluate_pose(*clip, *lattice, edit.time);
        if (pose.size() == edit.points.size())
            return std::make_unique<UnkeyedEditAppears>(std::move(label), e, edit, pose, after.has_value());
    }
    return std::make_unique<ComponentChange<UnkeyedEdit>>(std::move(label), e, std::move(before),
                                                          std::move(after));
}

}  // namespace sffd::editor
