// Pages of a point cloud: fixed-size index ranges over its contiguous columns, each with a change stamp per
// column group and a rest box. Both kinds (SplatCloud, GaussianCloud) use the same pages.
//
// A page is NOT a separate allocation. SplatCloud's and GaussianCloud's columns stay single contiguous
// std::vectors; page i is the index range [i*P, min(n, (i+1)*P)) of every column at once. That keeps what
// depends on contiguity working unchanged: the SIMD kernels stream a range with interleaved vector loads,
// a GL upload of a page is one glNamedBufferSubData at offset i*P*stride, and Embree shares the arrays
// zero-copy. What pages add is bookkeeping: which ranges and which columns changed since a consumer last
// looked (stamps), and where a page's points lie at rest (bounds), so the deformation, the upload and
// picking can redo only what an edit touched.
//
// Page size P = 65,536 points (2^16), chosen so that
//   - a page of the widest column fits any GL storage block: degree-3 SH is 48 floats = 192 bytes a point,
//     12.6 MB a page, far below the 128 MB GL_MAX_SHADER_STORAGE_BLOCK_SIZE of common drivers (and the
//     64-byte GpuSplat is 4 MB), so a cloud split on page boundaries never needs a block larger than one;
//   - it is a multiple of every SIMD width (4..16 lanes), of the CPU kernels' TBB chunk (2,048 points)
//     and of the compute passes' work groups (64 and 256 threads): a page deformed alone is evaluated in
//     exactly the blocks the whole cloud is, so redoing a page gives the whole run's bits;
//   - it is big enough that the per-page work (a kernel call, a dispatch, a sub-upload) is amortised over
//     64k points, and small enough that a 1M-point cloud has 16 pages to choose from (10M: 153).
// It equals the Gaussian deformation's block (gaussian_deform.cpp) for the same reason.
//
// Ownership: the stamps are written only by mark_points_changed()/mark_cloud_replaced() (editors and
// loaders call them after writing the columns; they stamp the cloud component too). The rest boxes are
// derived and refreshed by refresh_point_pages(), called by the deformation phase (systems/ffd's
// deformation skeleton) for each cloud it deforms before it decides what is stale. A cloud whose
// component was patched without a mark is detected (its stamp no longer equals `cloud_version`) and
// treated as wholly replaced: unmarked edits stay correct, they only lose the page granularity.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"

namespace sffd {

inline constexpr unsigned kPageShift = 16;
inline constexpr std::size_t kPagePoints = std::size_t(1) << kPageShift;  // points per page

constexpr std::size_t page_count(std::size_t points) { return (points + kPagePoints - 1) >> kPageShift; }

// The points of page `page` of a cloud of `points` points: [first, first + count).
struct PageRange {
    std::size_t first = 0;
    std::size_t count = 0;
};
constexpr PageRange page_range(std::size_t page, std::size_t points) {
    const std::size_t first = page << kPageShift;
    return {first, first >= points ? 0 : (points - first < kPagePoints ? points - first : kPagePoints)};
}

// Column groups with their own stamps. Surface splats use position, frame (normals, axis_u, axis_v) and
// colour (colours, uvs, uv axes); Gaussians use position (centres), scale, rotation, opacity and sh. Both
// kinds share the optional groups (point_columns.h): selection (the kPointSelected bit of PointFlags),
// visibility (its kPointHidden and kPointDeleted bits: one byte, two facts, so a selection change never
// looks like a visibility change) and weight (PointWeights). Which named column belongs to which group:
// point_columns.h, kSurfaceColumns / kGaussianColumns / kOptionalColumns.
enum class PointColumn : std::uint8_t {
    position,
    frame,
    colour,
    scale,
    rotation,
    opacity,
    sh,
    selection,
    visibility,
    weight
};
inline constexpr std::size_t kPointColumns = 10;

// Per-cloud record of its pages, a plain component beside SplatCloud or GaussianCloud.
struct PointPages {
    std::size_t points = 0;           // the cloud's size the pages cover
    std::uint64_t cloud_version = 0;  // the cloud component's change stamp this record is in step with
    // The optional components' change stamps (registry.version<PointFlags>, <PointWeights>; 0: absent) as
    // of the last mark of their groups. A consumer that finds another stamp on the entity takes the group
    // as changed everywhere (an unmarked edit), as an unmarked cloud change is a replacement.
    std::uint64_t flags_version = 0, weights_version = 0;
    std::uint64_t clock = 0;  // bumped by every mark; page stamps are values of it
    // stamps[column][page]: the clock of the last change of that column in that page.
    std::array<std::vector<std::uint64_t>, kPointColumns> stamps;
    // Rest box of each page in the cloud's frame (origin + position, double), finite points only; a page
    // with no finite point has lo > hi. Of the positions as of clock `bounds_clock`.
    std::vector<glm::dvec3> rest_lo, rest_hi;
    std::uint64_t bounds_clock = 0;
};

inline bool page_box_empty(const PointPages& p, std::size_t page) {
    return p.rest_lo[page].x > p.rest_hi[page].x;
}

// An edit wrote `column` of points [first, first + count) of entity e's cloud (SplatCloud or
// GaussianCloud): stamps those pages of that column and the cloud component (registry.patch), and keeps
// the record in step with the cloud's stamp. Call after writing. A cloud whose size changed, or with no
// record yet, is marked replaced instead. Does nothing when e has no cloud.
//
// The optional groups (selection, visibility, weight) stamp their component (PointFlags or PointWeights,
// registry.mark_changed, when present) instead of the cloud, so a selection or weight edit never makes
// the cloud look replaced (no re-upload of its rest data, no new picking scene). The component must hold
// one value per point or none (absent or empty: the default everywhere, e.g. after a clear). Another size
// is a caller's bug that must not become a read past the end: it is logged as a warning naming the entity
// and both sizes, and every page of that group is stamped (consumers then see the column as absent:
// point_columns.h's views are empty for a column of the wrong size).
void mark_points_changed(ecs::Registry& registry, ecs::Entity e, PointColumn column, std::size_t first,
                         std::size_t count);

// True for the groups of the optional columns (selection, visibility, weight).
constexpr bool optional_point_column(PointColumn c) {
    return c == PointColumn::selection || c == PointColumn::visibility || c == PointColumn::weight;
}
// The whole cloud was replaced (loaded, resized, rebuilt): every page of every column is stamped.
void mark_cloud_replaced(ecs::Registry& registry, ecs::Entity e);

// Brings e's record in step with its cloud (creating it the first time): an unmarked change of the cloud
// component, or a size change, counts as a replacement; rest boxes of pages whose positions changed since
// they were computed are recomputed. Returns the record (nullptr when e has no cloud). The deformation
// phase is its one caller in the frame.
const PointPages* refresh_point_pages(ecs::Registry& registry, ecs::Entity e);

// Pages whose stamp of any of `columns` is later than `since` (ascending).
std::vector<std::uint32_t> pages_changed_since(const PointPages& pages, std::uint64_t since,
                                               std::span<const PointColumn> columns);

}  // namespace sffd
