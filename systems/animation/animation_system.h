// animation_system: the animation phase (runtime/app/frame_loop.h).
//   reads   AnimationClip, UnkeyedEdit, Lattice::rest (lattice entities), FrameContext::time
//   writes  AnimationState (derived fields; anchor_clock when a play/scrub is pending),
//           Lattice::current via registry.patch<Lattice>(e), only when it differs bit for bit from the
//           evaluated pose (so the deformation phase re-runs only on change). It is the one writer of an
//           animated lattice's current (README.md, "One writer of the pose"): an edit is a key or an
//           UnkeyedEdit, and any other write to current is replaced by the pose in the next frame.
// The pose is a pure function of the frame time, the clip (evaluate.h) and an un-keyed edit (shown at its
// own clip time only), so frame k of a fixed-step run is the same whether rendered alone or in a sequence.
#pragma once

#include "runtime/app/frame_loop.h"

namespace sffd {

void animation_system(ecs::Registry& registry, const FrameContext& frame);

}  // namespace sffd
