// The picking system (picking phase). Reads: PickRequests (resource), SplatCloud / DeformedSplats,
// GaussianCloud / DeformedGaussians, Lattice, Transform. Writes: PickResults (resource), PickingState
// (resource, Embree scenes); empties PickRequests. Does nothing unless a request is pending; the Embree
// scenes are refreshed only then, and only for the entities whose data changed since the last pick.
//
// Rules of a pick (pick()):
//   1. With a screen point: the control point whose projection is nearest the cursor, within
//      tolerance_px, wins — if it is visible (no surface between the eye and it) or in x-ray mode.
//   2. Otherwise the ray: a control-point sphere in front of the first surface (anywhere along the ray in
//      x-ray mode) wins over the surface; else the first surface hit; else nothing.
#pragma once

#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"
#include "systems/picking/components.h"
#include "systems/picking/picking_state.h"

namespace sffd::picking {

// Refreshes the state's scenes (lazily) and answers one query.
PickHit pick(ecs::Registry& registry, PickingState& state, const PickQuery& query);

// The registry's PickingState resource, created on first use.
PickingState& picking_state(ecs::Registry& registry);

// Posts a pick for the next picking phase (creates PickRequests when absent); returns its id.
std::uint64_t post_pick(ecs::Registry& registry, const PickQuery& query);

// The answer to pick `id` from the last picking phase that had requests; nullptr when that phase did not
// answer it (not run yet, or the pick was posted before an earlier phase).
const PickHit* find_pick_answer(const ecs::Registry& registry, std::uint64_t id);

// Phase `picking`: answers every pending request, in order, into PickResults (after the deformation
// phase, so a pick sees the geometry this frame renders).
void picking_system(ecs::Registry& registry, const FrameContext& frame);

}  // namespace sffd::picking
