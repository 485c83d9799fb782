// The order of a cloud's points. Pages (point_pages.h) are index ranges, so the order decides how compact a
// page is in space, and with it how many pages an edit of a small region reaches: a cloud stored in scan
// or latitude order has pages that are thin slabs across the whole cloud. Morton (Z-order) of the points'
// quantised positions keeps nearby points at nearby indices, so a page covers a compact block; it is the
// order splat-transform writes SOG in, and the one a level-of-detail hierarchy builds its nodes from.
//
// The order is a permutation `perm` of [0, n): the point stored at index t after the reorder is the one
// that was at perm[t] (a gather). permute() applies it to EVERY per-point column of a cloud at once.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/core/result.h"
#include "runtime/scene/components.h"

namespace sffd {

inline constexpr unsigned kMortonBits = 21;  // per axis: 63-bit codes

// The Morton code of a point with quantised coordinates q (each < 2^21): the bits interleaved from the
// most significant down, x before y before z at each level.
std::uint64_t morton_code(glm::u32vec3 q);

// Each position quantised to 21 bits per axis in the bounding box of the finite positions (an axis of zero
// extent quantises to 0), then its Morton code; non-finite positions get UINT64_MAX (they sort last).
std::vector<std::uint64_t> morton_codes(std::span<const glm::vec3> positions);

// The permutation that sorts the positions by Morton code; equal codes keep their input order, so the
// result is a function of the positions alone (deterministic).
std::vector<std::uint32_t> morton_order(std::span<const glm::vec3> positions);

// True when `perm` holds each of 0..n-1 exactly once.
bool is_permutation_of(std::span<const std::uint32_t> perm, std::size_t n);

// How spatially compact the pages of a cloud of these positions are (point_pages.h: consecutive runs of
// kPagePoints): the mean over pages of each page's box (finite points) as a share of the cloud's box, by
// volume (axes where the cloud is flat left out) and by diagonal. Points in scan or band order give pages
// as wide as the cloud (shares near 1 on some axis); spatially ordered points give small boxes.
struct PageCompactness {
    std::size_t pages = 0;
    double mean_volume_share = 0.0;
    double mean_diagonal_share = 0.0;
};
PageCompactness page_compactness(std::span<const glm::vec3> positions);

// Reorders every per-point column (surface: positions, normals, axes, colours, uvs, uv axes; Gaussians:
// positions, scales, rotations, opacities, SH, SH frames) by `perm`. Empty optional columns stay empty;
// the texture and the origin are untouched. Fails, changing nothing, when `perm` is not a permutation of
// the cloud's points or a column's length does not match the cloud's size.
Status permute(SplatCloud& cloud, std::span<const std::uint32_t> perm);
Status permute(GaussianCloud& cloud, std::span<const std::uint32_t> perm);

}  // namespace sffd
