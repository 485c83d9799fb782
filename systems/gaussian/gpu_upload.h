// CPU -> GpuGaussianStore uploads (gpu_store.h): the authored cloud into `rest`/`sh` (residency_system,
// and scratch entries of tools and tests), the CPU deformation's output (DeformedGaussians) into
// `deformed` (+ `deformed_sh`, `frames`; gaussian_deform_system's CPU path). Need a current GL context.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "runtime/core/result.h"
#include "shaders/gaussian/gaussian_layout.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gpu_store.h"

namespace sffd::gaussian {

// GpuGaussian records (centre relative to the origin + opacity, rotation w x y z, linear scale) of a
// cloud's geometry with `opacities` (a DeformedGaussians carries none: pass the authored cloud's).
std::vector<gpu::GpuGaussian> pack_gaussians(const GaussianCloud& geometry,
                                             const std::vector<float>& opacities);
// The same into `out` (geometry.size() records: a mapped GL buffer, say).
void pack_gaussians(const GaussianCloud& geometry, const std::vector<float>& opacities,
                    std::span<gpu::GpuGaussian> out);

// Uploads `cloud` into rest + sh and records `version` (its change stamp, registry.version<GaussianCloud>,
// the same for every caller) in rest_version. State rest: nothing deformed from an older rest is drawn
// until the deformation writes `deformed` again.
// Refuses clouds whose arrays differ in size or that hold 2^32 Gaussians or more.
Status upload_rest(GpuGaussians& gpu, const GaussianCloud& cloud, std::uint64_t version);

// Uploads the CPU deformation's output into `deformed`; its SH into `deformed_sh` when they differ from
// the authored ones (ShMode::rotate_coefficients), its sh_frames into `frames` (ShMode::rotate_view).
// State deformed_cpu (sh_source says which SH data to read), bumps deformed_version.
void upload_cpu_deformed(GpuGaussians& gpu, const DeformedGaussians& deformed, const GaussianCloud& authored);

// A budgeted preview's output (systems/ffd/preview_budget.h): `subset`, a deformed subset of the cloud
// with its own opacities and SH (rotated coefficients, of its own degree: preview_sh_degree), into
// `deformed` and `deformed_sh`. State preview_cpu with subset.size() elements; `indices`: the authored
// index of each (the subset's marks are read through them, runtime/gfx/residency.h).
void upload_preview(GpuGaussians& gpu, const GaussianCloud& subset, std::span<const std::uint32_t> indices);

}  // namespace sffd::gaussian
