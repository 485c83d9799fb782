// gaussian_deform_system: the deformation phase for 3D Gaussian clouds, in the style of
// ffd_system (systems/ffd). Reads GaussianCloud + Deformers on Gaussian entities and Lattice on the
// lattice entities they name and GpuGaussianStore::clouds[e].rest/sh (uploaded by residency_system in the
// phase before); writes DeformedGaussians and the store entry's `deformed` (+ frames or deformed_sh) and
// residency state: deformed_gpu from the compute pass (gpu_deform.h), deformed_cpu when the CPU path
// uploads its output.
// Runs only when the cloud's GaussianCloud or Deformers, one of its lattices' change stamps, or the
// backend choice moved. Several deformers apply in order (the first reads the authored cloud, the next
// ones deform its output in place).
//
// Backend: ffd_system's rule and settings (FfdSettings::force_cpu / force_gpu): GPU when a GL context is
// current on this thread and it is not a software rasterizer (there the TBB path is faster; force_gpu
// keeps the compute pass), CPU otherwise. GPU path: GaussianDeformSettings::gpu_sh (default frames:
// has_frames when sh_degree > 0; or deformed_sh), state deformed_gpu with empty CPU arrays, no
// per-Gaussian CPU work and no read-back while only lattices change. CPU path: cpu_sh (default the
// coefficients rotated), CPU arrays, uploaded into the store when the cloud is resident (a GL context).
#pragma once

#include <cstdint>

#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"
#include "systems/gaussian/gaussian_deform.h"

namespace sffd {

// Optional resource: how view-dependent colour follows the deformation on each path, and what the system
// did (tests check the GPU frame path does no CPU pass and no read-back).
struct GaussianDeformSettings {
    // GPU: frames (36 bytes per Gaussian written per deformation, one 3x3 product per Gaussian per frame in
    // the renderer) or coefficients rotated into GpuGaussianStore::deformed_sh. CPU: the coefficients
    // rotated in DeformedGaussians::cloud.sh, or frames in DeformedGaussians::cloud.sh_frames.
    gaussian::ShMode gpu_sh = gaussian::ShMode::rotate_view;
    gaussian::ShMode cpu_sh = gaussian::ShMode::rotate_coefficients;
};

// Resource written by gaussian_deform_system (created on its first run), read by tests and `profile`.
// Kept apart from GaussianDeformSettings, which only the user writes.
struct GaussianDeformStats {
    std::uint64_t cpu_runs = 0;            // clouds deformed on the CPU
    std::uint64_t gpu_runs = 0;            // clouds deformed on the GPU
    std::uint64_t preview_runs = 0;        // budgeted previews (a subset on the CPU, ffd/preview_budget.h)
    std::uint64_t gpu_sync_readbacks = 0;  // synchronous read-backs by the system's GPU deformer (stays 0)
    // Pages (runtime/scene/point_pages.h) deformed so far, and by the last run of a cloud (of that cloud's
    // pages), as FfdStats counts them.
    std::uint64_t pages_redeformed = 0;
    struct LastPages {
        std::uint64_t redone = 0, total = 0;
    } last_pages;
};

void gaussian_deform_system(ecs::Registry& registry, const FrameContext& frame);

namespace gaussian {
// Whether e's current deformed Gaussians live on the GPU only (the residency's state deformed_gpu in
// GpuGaussianStore): the one answer.
bool output_on_gpu(const ecs::Registry& registry, ecs::Entity e);
}  // namespace gaussian

// Drops the system's GPU state (call while the GL context is still current, before destroying it).
void gaussian_release_gpu(ecs::Registry& registry);

}  // namespace sffd
