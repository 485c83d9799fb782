// The interactive preview's point budget (Potree's point budget, the reduced preview of 3DGS viewers):
// while the lattice or the camera moves, the deformation systems deform and the renderer draws only a
// spatially spread subset of each large cloud, its splats (or Gaussians) enlarged by sqrt(N / budget) so
// the surface stays closed; the first still frame deforms and draws every point again, exactly the frame
// that would have been drawn without the preview.
//
// Who writes what: the front end that knows the frame is interactive (the editor while moving, `profile
// --quality preview`) sets PreviewBudget::active before the deformation phase; ffd_system and
// gaussian_deform_system read it and, on their CPU path, write the subset into the cloud's residency
// (state preview_cpu, runtime/gfx/residency.h), leaving their full outputs marked not current, so
// picking, exports and `render` (which never sets `active`) always see every point deformed.
#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"

namespace sffd {

// Sized so that a 1M-splat cloud in an 11^3 lattice deforms and draws a preview frame in about 100 ms on
// a 2-core machine with a software rasterizer (README, "Preview budget").
inline constexpr std::uint32_t kDefaultPreviewBudget = 100'000;

// Gaussians cost far more to blend than surface splats to draw, and the blend dominates their preview:
// a 1M-Gaussian preview frame on the same 2-core machine (loaded) took p50 585 ms at 100,000 kept and
// 427 ms at 30,000 (README, "Preview budget"). Their own, smaller cap; the kept ones are enlarged by
// sqrt(N / kept) all the same, so the surface stays covered.
inline constexpr std::uint32_t kDefaultGaussianPreviewBudget = 30'000;

// Registry resource (optional: absent means no budget). `points` is the user's setting (0 = off);
// `gaussians` caps it for Gaussian clouds (0 = no cap of their own); `active` is set per frame by the
// interactive front end.
struct PreviewBudget {
    std::uint32_t points = kDefaultPreviewBudget;
    bool active = false;
    std::uint32_t gaussians = kDefaultGaussianPreviewBudget;  // last: {points, active} keeps its meaning
};

// The budget that applies to a cloud of `n` points this frame: 0 when there is none (no resource, not
// active, off, or the cloud fits it).
std::uint32_t preview_budget_for(const ecs::Registry& registry, std::size_t n);

// The same for a cloud of `n` Gaussians: the smaller of `points` and `gaussians` (0 when `points` is 0).
std::uint32_t gaussian_preview_budget_for(const ecs::Registry& registry, std::size_t n);

// Marks whether this frame is an interactive preview (creates the resource with the default budget when
// absent and `active`).
void set_preview_active(ecs::Registry& registry, bool active);

// The enlargement of each kept splat's radii: sqrt(n / kept) (the same area in all) times a margin for
// the subset's uneven spacing (preview_budget.cpp).
float preview_radius_scale(std::size_t n, std::size_t kept);

// A budgeted cloud's kept points, cached by the deformation system that owns the output: computed once
// per authored cloud change and budget, stable from frame to frame.
struct PreviewSubset {
    std::vector<std::uint32_t> indices;  // ascending
    std::uint64_t cloud = 0;             // change stamp of the authored cloud they were chosen from
    std::uint32_t budget = 0;
};

// `budget` of the `positions`, spread over space: the points in Morton order (a 10-bit grid per axis of
// their box), one taken from each of `budget` equal runs of that order (the middle one), so every kept
// point stands for a compact neighbourhood of about n / budget points. Returned ascending. All of them
// when budget >= n. Deterministic.
std::vector<std::uint32_t> spread_subset(std::span<const glm::vec3> positions, std::uint32_t budget);

// Refreshes `subset` for the cloud's stamp and budget (recomputed only when either changed).
void update_preview_subset(PreviewSubset& subset, std::span<const glm::vec3> positions, std::uint64_t cloud,
                           std::uint32_t budget);

}  // namespace sffd
