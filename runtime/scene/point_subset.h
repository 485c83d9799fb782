// A subset of a cloud's points, of either kind, with every column carried along: what saving and export
// write (a saved scene holds no deleted point; an export holds neither hidden nor deleted points) and what
// "export the selected points" writes.
//
// A subset is a list of point indices (ascending when made from flags; any order is a gather). Every
// authored column moves with its point (surface: positions, normals, axes, colours, uvs, uv axes;
// Gaussians: positions, scales, rotations, opacities, SH at the cloud's degree, and the SH frames of a
// derived cloud), and so do the optional columns beside the cloud (PointFlags, PointWeights). What is not
// per point is kept as it is: the origin, the texture (its uvs still index it), the SH degree. An empty
// optional column (every point at the default) stays empty.
//
//   subset_points(cloud, keep)            the subset as a new value (the cloud is untouched)
//   drop_gone_points(registry, e, drop)   in place: e's cloud without its deleted points (scene save) or
//                                         without its hidden and deleted ones (export)
//   extract_points(registry, e)           in place: only e's selected points (selected, neither hidden
//                                         nor deleted: point_edit's meaning of "selected")
// The in-place forms mark the cloud replaced (point_pages.h) and patch the optional components, so every
// consumer (deformation, residency, picking) starts over from the new size.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"

namespace sffd {

// Indices (ascending) of the points of a cloud of `points` points whose flags have every bit of `want`
// and none of `drop`. Flags absent, empty or of another size: no point has a bit (so with want == 0 every
// point is kept, with want != 0 none).
std::vector<std::uint32_t> points_with(const PointFlags* flags, std::size_t points, std::uint8_t want,
                                       std::uint8_t drop);
// Indices (ascending) of the nonzero entries of a keep-mask, one byte a point.
std::vector<std::uint32_t> mask_indices(std::span<const std::uint8_t> keep);
// True when some point's flags have a bit of `bits` (flags of another size than `points` count as none).
bool any_point_flagged(const PointFlags* flags, std::size_t points, std::uint8_t bits);

// The points at `keep` (each < the cloud's size), in that order, as a new cloud. Fails, naming the
// problem, when an index is out of range, the cloud has more than 2^32 - 1 points, or a column is not one
// entry per point.
Result<SplatCloud> subset_points(const SplatCloud& cloud, std::span<const std::uint32_t> keep);
Result<GaussianCloud> subset_points(const GaussianCloud& cloud, std::span<const std::uint32_t> keep);
// An optional column of a cloud of `points` points, subset the same way; empty stays empty.
Result<PointFlags> subset_points(const PointFlags& flags, std::size_t points,
                                 std::span<const std::uint32_t> keep);
Result<PointWeights> subset_points(const PointWeights& weights, std::size_t points,
                                   std::span<const std::uint32_t> keep);

// Which points are gone for a purpose: a scene save drops the deleted ones (hidden points stay, hidden);
// an export drops every point that is not drawn.
enum class PointDrop : std::uint8_t { deleted = kPointDeleted, hidden_and_deleted = kPointGone };

// In place on e's cloud (SplatCloud or GaussianCloud) and its PointFlags / PointWeights. Each returns the
// number of points dropped (0: nothing was changed, no stamp moved), or an error (nothing changed) when e
// has no cloud or a column has the wrong size.
Result<std::size_t> keep_points(ecs::Registry& registry, ecs::Entity e, std::span<const std::uint32_t> keep);
Result<std::size_t> drop_gone_points(ecs::Registry& registry, ecs::Entity e, PointDrop drop);
Result<std::size_t> extract_points(ecs::Registry& registry, ecs::Entity e);

}  // namespace sffd
