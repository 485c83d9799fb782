// deform_cloud(): the CPU deformation step of a point cloud through its lattices, in order. The one CPU
// chain: ffd_system's CPU path runs it, and picking asks for it when the deformer's output lives only on
// the GPU (systems/picking/splat_source.cpp). The GPU chain is ffd_system's compute path (ffd_gpu.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "systems/ffd/components.h"

namespace sffd::ffd {

// Writes out.positions/normals/axis_u/axis_v (the authored arrays deformed by each lattice in `lattices`,
// in order: the first reads the authored cloud, the next ones work in place), out.origin and
// out.inverted; sets cpu_valid. `lattices` are in the cloud's frame: ffd::cloud_lattices()
// (lattice_frame.h) prepares them from the cloud's Deformers. A lattice that fails validation is skipped
// with a warning "`who`: problem (lattice skipped)". Normals and splat axes are deformed when they have
// the cloud's size (else copied as authored). Bounds, versions and the change-detection stamps are the
// caller's. `weights` (the cloud's PointWeights, runtime/scene/point_columns.h; null, empty or not one per
// point: weight 1) scale every lattice's step of each point: X + w D, J_w = I + w (J - I).
void deform_cloud(const SplatCloud& cloud, std::span<const Lattice* const> lattices, DeformedSplats& out,
                  const char* who = "ffd", const PointWeights* weights = nullptr);

// The same step for the pages `pages` only (runtime/scene/point_pages.h), in place in out's arrays, which
// hold the whole cloud's output already (sized as deform_cloud() sizes them): the pages' points are written
// exactly as deform_cloud() writes them (a page is a whole number of the kernels' blocks), the others are
// left as they are. out.paged.counts[p][0] gets page p's inverted count and out.inverted their sum.
// deform_cloud() is this over every page.
void deform_cloud_pages(const SplatCloud& cloud, std::span<const Lattice* const> lattices,
                        std::span<const std::uint32_t> pages, DeformedSplats& out, const char* who = "ffd",
                        const PointWeights* weights = nullptr);

// The same step for the points `indices` only (a budgeted preview, preview_budget.h): out's arrays hold
// them compacted, in the order of `indices`. Leaves cpu_valid false (the arrays are not the cloud).
void deform_cloud_subset(const SplatCloud& cloud, std::span<const Lattice* const> lattices,
                         std::span<const std::uint32_t> indices, DeformedSplats& out, const char* who = "ffd",
                         const PointWeights* weights = nullptr);

}  // namespace sffd::ffd
