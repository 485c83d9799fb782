// FFD components: plain data. The authored ones (Lattice, Deformers) live in runtime/scene/lattice.h so
// that scene loading needs no system; DeformedSplats, the FFD system's output, is defined here.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/entity.h"
#include "runtime/scene/lattice.h"
#include "systems/ffd/preview_budget.h"

namespace sffd {

// Change stamps of the inputs a deformation output was computed from: the authored cloud, its Deformers,
// its Transform (the output's world bounds, and the frame its lattices are mapped into), and per live
// lattice (in Deformers order) its Lattice version mixed with its entity bits, so that swapping one
// lattice for another also counts as a change, and with both entities' Transform versions. Kept by
// DeformedSplats and DeformedGaussians (systems/gaussian); filled by ffd::deform_inputs()
// (systems/ffd/deform_inputs.h). `weights`: the cloud's PointWeights component stamp (0 without one): an
// added, removed or patched weight column re-deforms the whole cloud; a range of weights edited in place
// and marked (mark_points_changed) moves the cloud's stamp and redoes its pages.
struct DeformInputStamps {
    std::uint64_t cloud = 0;
    std::uint64_t deformers = 0;
    std::uint64_t transform = 0;
    std::uint64_t weights = 0;
    std::vector<std::uint64_t> lattices;
    bool operator==(const DeformInputStamps&) const = default;
};

// What a page-wise CPU output was computed from beyond its stamps, so the next run can redo only the pages
// an edit reaches (deform_staleness.h): the page record's clock, the lattices as they were (in the cloud's
// frame: the changed control points are found by comparing), and per-page statistics, summed over the
// lattices, so the totals stay right when only some pages are redone. `points == 0`: nothing to build on
// (no output yet, the GPU path, a preview).
struct DeformPageRecord {
    std::size_t points = 0;
    std::uint64_t pages_clock = 0;
    std::vector<Lattice> lattices;
    std::vector<std::array<std::uint32_t, 3>> counts;  // per page; the kind says what each slot counts
};

// Derived output of the deformation phase on a point-cloud entity (authored SplatCloud stays as loaded).
// Written by ffd_system only. Positions are relative to `origin` (= the cloud's SplatCloud::origin).
// When the GPU path ran, the deformed splats live in GpuSplatStore::clouds[e].deformed and the CPU arrays
// are left empty (`cpu_valid == false`); bounds and version are always valid. Whether the output is on the
// GPU is the residency's answer (state deformed_gpu; ffd::output_on_gpu() in ffd_system.h). The inverted
// count is the one of output `inverted_version`: on the CPU path the current one, on the GPU path it arrives
// a few frames later (read back through a fence, never waited for).
struct DeformedSplats {
    glm::dvec3 origin{0.0};
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;
    std::vector<glm::vec3> axis_u;
    std::vector<glm::vec3> axis_v;
    bool cpu_valid = false;              // the arrays above hold the current deformation
    glm::dvec3 bounds_min{0.0};          // world-space box (through the cloud's Transform) that never
    glm::dvec3 bounds_max{0.0};          // under-covers the deformed splats (displacement hull, README)
    std::size_t inverted = 0;            // inside splats whose Jacobian has det < 0 (normal flipped)
    std::uint64_t inverted_version = 0;  // the `version` whose splats `inverted` counts
    std::uint64_t version = 0;           // bumped every time the output is rewritten

    // Box of the authored cloud in its own frame (origin + positions), cached: computed once per
    // SplatCloud change (the only per-splat CPU work of the GPU path), then grown by the lattices' control
    // points (in the same frame) every run and mapped to the world.
    glm::dvec3 rest_box_lo{0.0}, rest_box_hi{0.0};
    bool rest_box_empty = true;
    bool has_rest_box = false;
    std::uint64_t rest_box_cloud = 0;  // SplatCloud change stamp the box is of

    // Inputs this output was computed from (change stamps), so the system skips unchanged clouds.
    DeformInputStamps seen;
    bool seen_force_cpu = false;
    DeformPageRecord paged;  // counts[p][0]: inverted splats of page p

    // Budgeted preview (preview_budget.h): when `preview` is true the last run deformed only
    // `subset.indices` (the arrays above hold those, compacted; cpu_valid is false), so the
    // next frame that is not a budgeted preview deforms every point again.
    bool preview = false;
    PreviewSubset subset;
};

}  // namespace sffd
