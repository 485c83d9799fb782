// CPU -> GpuGaussianStore uploads (gpu_store.h): the authored cloud into `rest`/`sh`, the CPU
// deformation's output (DeformedGaussians) into `deformed` (+ `deformed_sh`, `frames`). Whoever first
// needs a cloud on the GPU calls upload_rest() (the render system; the GPU deformation may too); the
// render system calls upload_cpu_deformed() when the GPU deformation did not write `deformed`.
// Need a current GL context.
#pragma once

#include <cstdint>
#include <vector>

#include "runtime/core/result.h"
#include "shaders/gaussian/gaussian_layout.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gpu_store.h"

namespace sffd::gaussian {

// GpuGaussian records (centre relative to the origin + opacity, rotation w x y z, linear scale) of a
// cloud's geometry with `opacities` (a DeformedGaussians carries none: pass the authored cloud's).
std::vector<gpu::GpuGaussian> pack_gaussians(const GaussianCloud& geometry, const std::vector<float>& opacities);

// Uploads `cloud` into rest + sh and records `version` (its change stamp, registry.version<GaussianCloud>,
// the same for every caller) in rest_version. Invalidates `deformed`, `deformed_sh` and `frames` (has_*
// and deformed_on_gpu false: nothing deformed from an older rest is drawn) until they are written again.
// Refuses clouds whose arrays differ in size or that hold 2^32 Gaussians or more.
Status upload_rest(GpuGaussians& gpu, const GaussianCloud& cloud, std::uint64_t version);

// Uploads the CPU deformation's output into `deformed`; its SH into `deformed_sh` when they differ from
// the authored ones (ShMode::rotate_coefficients), its sh_frames into `frames` (ShMode::rotate_view).
// Sets has_deformed / has_deformed_sh / has_frames, clears deformed_on_gpu, bumps deformed_version.
void upload_cpu_deformed(GpuGaussians& gpu, const DeformedGaussians& deformed, const GaussianCloud& authored);

// Back to the authored cloud (the entity lost its deformers): has_deformed etc. false.
void drop_deformed(GpuGaussians& gpu);

}  // namespace sffd::gaussian
