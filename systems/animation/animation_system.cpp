#include "systems/animation/animation_system.h"

#include <cstring>

#include "runtime/core/log.h"
#include "systems/animation/components.h"
#include "systems/animation/evaluate.h"
#include "systems/animation/unkeyed_edit.h"
#include "systems/ffd/components.h"

namespace sffd {

namespace {

bool same_bits(const std::vector<glm::dvec3>& a, const std::vector<glm::dvec3>& b) {
    return a.size() == b.size() &&
           (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
}

}  // namespace

void animation_system(ecs::Registry& registry, const FrameContext& frame) {
    std::vector<glm::dvec3> pose;
    registry.view<const AnimationClip, AnimationState, const Lattice>().each(
        [&](ecs::Entity e, const AnimationClip& clip, AnimationState& state, const Lattice& lattice) {
            if (state.rebase) {
                state.anchor_clock = frame.time;
                state.rebase = false;
            }
            state.raw_time = clip_raw_time(clip, state, frame.time);
            state.time = map_clip_time(clip, state.raw_time);
            // Validation is cheap next to evaluation (both O(bound points)); a bad clip (e.g. after the
            // lattice was resampled to fewer points) is skipped and reported once per distinct error.
            if (Status valid = validate_clip(clip, lattice.rest.size()); !valid) {
                if (state.error != valid.message()) log::error("animation_system(): ", valid.message());
                state.error = valid.message();
                state.last_pose.clear();
                return;
            }
            state.error.clear();
            evaluate_pose(clip, lattice, state.time, pose);
            // An un-keyed edit stands in for the clip's pose at its own time only, so a frame's pose
            // still depends on its time alone (render's frame k is the same alone or in a sequence).
            if (const UnkeyedEdit* edit = registry.try_get<UnkeyedEdit>(e);
                edit && edit->points.size() == pose.size() && shows_unkeyed_edit(*edit, state.time))
                pose = edit->points;
            // The one writer of an animated lattice's current: it always shows the pose (a write by anyone
            // else is replaced here; edits go through the clip or the un-keyed edit), and is patched
            // only when it differs bit for bit, so the deformation re-runs only on change.
            if (!same_bits(lattice.current, pose)) registry.patch<Lattice>(e).current = pose;
            if (!same_bits(state.last_pose, pose)) state.last_pose.swap(pose);
        });
}

}  // namespace sffd
