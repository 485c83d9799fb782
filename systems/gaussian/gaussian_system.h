// gaussian_deform_system: the deformation phase for 3D Gaussian clouds (issue 17), in the style of
// ffd_system (systems/ffd). Reads GaussianCloud + Deformers on Gaussian entities and Lattice on the
// lattice entities they name; writes DeformedGaussians (CPU arrays). Runs only when the cloud's
// GaussianCloud or Deformers, or one of its lattices' change stamps, moved. Several deformers apply in
// order (the first reads the authored cloud, the next ones deform its output in place). CPU only.
#pragma once

#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"

namespace sffd {

void gaussian_deform_system(ecs::Registry& registry, const FrameContext& frame);

}  // namespace sffd
