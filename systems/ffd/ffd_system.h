// ffd_system: the deformation phase (runtime/app/frame_loop.h). Reads SplatCloud + Deformers on point-cloud
// entities and Lattice on the lattice entities they name; writes DeformedSplats (always: bounds, inverted
// count, version) and the cloud's residency (runtime/gfx/splat_store.h): GpuSplatStore::clouds[e].deformed
// from the compute pass (state deformed_gpu), or DeformedSplats' CPU arrays uploaded there when the cloud
// is resident (state deformed_cpu).
//
// Skinning-style: a cloud is re-deformed only when its SplatCloud, its Deformers or one of its lattices'
// change stamps (registry.version<Lattice>) moved; several deformers apply in order (each deforms the
// previous one's output). GPU path when a GL context is current on this thread and GpuSplatStore holds
// the cloud's up-to-date `rest` buffer (residency_system uploads it in the phase before); CPU otherwise
// (headless tools, tests without the residency phase). Control points go to the GPU only when edited.
// GPU mode does no per-splat CPU work per frame: bounds come from the lattices' control points and a rest
// box cached per cloud change, and the inverted count is read back a few frames late through a fence.
// On a software rasterizer (Mesa llvmpipe/softpipe) the GPU path runs on the same CPU cores through a
// shader JIT and is 10-15x slower than the vectorised CPU path (measured: 124 ms vs 8 ms for the
// paper's 59,650 splats in an 11^3 Bernstein lattice), so there the CPU path is chosen and uploads its
// output; FfdSettings::force_gpu keeps the compute pass (tests, comparisons).
#pragma once

#include <cstdint>
#include <memory>

#include "runtime/app/frame_loop.h"
#include "runtime/ecs/registry.h"

namespace sffd {

// Optional resource: settings and counters of the deformation phase.
struct FfdSettings {
    bool force_cpu = false;  // never use the GPU path (picking-heavy tools, comparisons)
    bool force_gpu = false;  // use the GPU path even on a software rasterizer (llvmpipe)
};

// Resource written by ffd_system (created on its first run), read by tests and `profile`: what the
// system did so far. Kept apart from FfdSettings, which only the user writes.
struct FfdStats {
    std::uint64_t cpu_runs = 0;      // clouds deformed on the CPU so far
    std::uint64_t gpu_runs = 0;      // clouds deformed on the GPU so far
    std::uint64_t preview_runs = 0;  // budgeted previews (a subset deformed on the CPU, preview_budget.h)
    // GPU-resident frame, checked by tests: passes of the system over a cloud's splats on the CPU (the
    // rest box when a cloud changes, each CPU deformation) and synchronous GPU read-backs by its deformer.
    // In GPU mode both stay flat while only lattices change.
    std::uint64_t cpu_splat_passes = 0;
    std::uint64_t gpu_sync_readbacks = 0;
    // Pages (runtime/scene/point_pages.h) deformed so far, and by the last run of a cloud (with that cloud's
    // page count): a control-point edit redoes only the pages its support reaches on the CPU path; the GPU
    // path and previews redo every page.
    std::uint64_t pages_redeformed = 0;
    struct LastPages {
        std::uint64_t redone = 0, total = 0;
    } last_pages;
};

void ffd_system(ecs::Registry& registry, const FrameContext& frame);

namespace ffd {
// Whether e's current deformed splats live on the GPU only (the residency's state deformed_gpu): the one
// answer, read from GpuSplatStore.
bool output_on_gpu(const ecs::Registry& registry, ecs::Entity e);
}  // namespace ffd

// Drops the system's GPU state (call while the GL context is still current, before destroying it).
void ffd_release_gpu(ecs::Registry& registry);

}  // namespace sffd
