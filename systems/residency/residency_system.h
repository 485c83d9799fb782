// residency_system: the residency phase (runtime/app/frame_loop.h), between animation and deformation.
// The one upload step of the authored clouds: owns GpuSplatStore (runtime/gfx/splat_store.h) and
// GpuGaussianStore (systems/gaussian/gpu_store.h) and their per-cloud state (runtime/gfx/residency.h).
//   reads   SplatCloud, GaussianCloud (and their change stamps), Deformers (presence only)
//   writes  the stores: an entry per cloud entity, `rest` uploaded once per change of the authored
//           component (state rest), entries of gone entities dropped, state back to rest when a cloud
//           lost its deformers; ResidencyStats (counters); ResidencyConnections (its destroy signals)
// The deformation systems then write `deformed` and the deformed states; render and picking only read.
// Needs a current GL context; does nothing without one (the CPU-only frame has no stores).
#pragma once

#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"
#include "runtime/ecs/signal.h"

namespace sffd {

// A store entry goes with its cloud's authored component (removed, or the entity destroyed): the
// registry's destroy signals, connected once per registry by the system; this resource holds the
// connections. Named here so that the schedule can declare the system's access to it.
struct ResidencyConnections {
    ecs::ScopedConnection splats, gaussians;
};

void residency_system(ecs::Registry& registry, const FrameContext& frame);

}  // namespace sffd
