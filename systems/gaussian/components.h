// 3D Gaussian splat components: plain data. Owned by systems/gaussian; other systems read them. The
// authored GaussianCloud itself lives with SplatCloud in runtime/scene/components.h.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "runtime/scene/components.h"  // GaussianCloud
#include "systems/ffd/components.h"    // DeformInputStamps

namespace sffd {

// Derived output of the Gaussian deformation (gaussian_deform_system) on a GaussianCloud entity that has
// Deformers: same layout as GaussianCloud (opacities are unchanged by a deformation and not copied).
// Covariance Σ' = J Σ Jᵀ stored back as scale + rotation; SH rotated by the polar rotation of J.
struct DeformedGaussians {
    GaussianCloud cloud;            // opacities left empty (read the authored cloud's) unless some
                                    // results were not finite (then theirs are 0); EMPTY when the GPU pass
                                    // wrote GpuGaussianStore::clouds[e].deformed (state deformed_gpu, the
                                    // one answer: gaussian::output_on_gpu(); read_back() makes a copy)
    bool seen_force_cpu = false;    // the backend choice this output was made with (a switch re-runs)
    std::uint8_t seen_sh_mode = 0;  // the gaussian::ShMode it used (GaussianDeformSettings; a switch re-runs)
    // Statistics (summed over the deformers). GPU path: they arrive a few frames after the deformation
    // (fenced, never waited for) and stay 0 with stats_arrived false until then.
    std::size_t inverted = 0;    // Gaussians whose Jacobian has det < 0
    std::size_t degenerate = 0;  // Gaussians whose Jacobian is (near) singular
    std::size_t not_finite = 0;  // results that were not finite (written transparent, CPU and GPU)
    bool stats_arrived = false;
    std::uint64_t version = 0;  // bumped on every rewrite

    // Change stamps this output was computed from (the system skips unchanged clouds).
    DeformInputStamps seen;
    DeformPageRecord paged;  // counts[p]: inverted, degenerate, not finite of page p (CPU path)

    // Budgeted preview (systems/ffd/preview_budget.h): the last run deformed only `subset.indices` into
    // the GPU store (state preview_cpu); `cloud` is then EMPTY and the next frame that is not a budgeted
    // preview deforms every Gaussian again.
    bool preview = false;
    PreviewSubset subset;
};

}  // namespace sffd
