// residency_system: the residency phase (runtime/app/frame_loop.h), between animation and deformation.
// The one upload step of the authored clouds: owns GpuSplatStore (runtime/gfx/splat_store.h) and
// GpuGaussianStore (systems/gaussian/gpu_store.h) and their per-cloud state (runtime/gfx/residency.h).
//   reads   SplatCloud, GaussianCloud (and their change stamps), Deformers (presence only)
//   writes  the stores: an entry per cloud entity, `rest` uploaded once per change of the authored
//           component (state rest), entries of gone entities dropped, state back to rest when a cloud
//           lost its deformers; ResidencyStats (counters)
// The deformation systems then write `deformed` and the deformed states; render and picking only read.
// Needs a current GL context; does nothing without one (the CPU-only frame has no stores).
#pragma once

#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"

namespace sffd {

void residency_system(ecs::Registry& registry, const FrameContext& frame);

}  // namespace sffd
