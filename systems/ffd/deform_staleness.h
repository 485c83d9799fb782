// The one staleness rule of the deformation, for both kinds (surface splats and 3D Gaussians): from what an
// output was computed from (its DeformInputStamps and DeformPageRecord) and what the cloud's inputs are
// now (stamps, the cloud's PointPages, its lattices in the cloud's frame), what must be redone: nothing,
// some pages, or everything.
//
// Pages to redo:
//   - pages whose stamp of a column the deformation reads moved since the output (an edit of a range of
//     points, runtime/scene/point_pages.h);
//   - when only control points of a lattice moved (same divisions, basis, box and rest points: the same
//     topology), the pages whose rest box, carried through the lattices before it (deformed_bounds, which
//     never under-covers) and mapped into the lattice's parameter space, meets the changed points' support:
//     Bernstein, the whole box (every basis function is nonzero inside); cubic B-spline, l·s in
//     [i-2, i+2] around each changed index (the uniform cubic B-spline centred at the index has support
//     (-2, 2)). The B-spline kernel also skips points outside the box of the supports of ALL moved points
//     (its cull box), so a page where that box changed (inside one of the old and new boxes and not inside
//     both) is redone too. Both are widened by a margin that covers the float kernels' rounding of the
//     local coordinates, so the set is conservative: every page left alone would come out bit for bit as it
//     is (tested against a deformation from scratch). For the first lattice the box only nominates a page:
//     it is redone when one of its own rest points meets the same test (a page's box can span far more
//     than its points: a band of a sphere's surface has a box through the sphere's middle).
// Everything: no usable record (first run, another size, another backend, a preview), the
// Deformers changed, the PointWeights component was added, removed or patched (DeformInputStamps::weights), a
// lattice was added, removed or changed topology (a moved Transform maps the whole lattice), or the cloud
// changed without a mark (the page record is out of step). Pages outside every lattice never meet a support:
// deformed once (copied) and never again.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "runtime/scene/lattice.h"
#include "runtime/scene/point_pages.h"
#include "systems/ffd/components.h"

namespace sffd::ffd {

enum class Redo : std::uint8_t { nothing, pages, everything };

struct RedoPlan {
    Redo what = Redo::everything;
    std::vector<std::uint32_t> pages;  // ascending, when what == pages
};

// True when the two lattices differ at most in their current control points.
bool same_topology(const Lattice& a, const Lattice& b);

// A cloud's rest points in its own frame (origin + positions), which its page boxes bound.
struct PagePoints {
    glm::dvec3 origin{0.0};
    std::span<const glm::vec3> positions;
};

// The rule. `reads`: the columns the deformation reads (surface: position, frame; Gaussians: position,
// scale, rotation, sh). `record.points == 0` means no page-wise output to build on.
RedoPlan plan_redeform(const DeformInputStamps& seen, const DeformPageRecord& record,
                       const DeformInputStamps& now, const PointPages& pages,
                       std::span<const Lattice* const> lattices, std::span<const PointColumn> reads,
                       const PagePoints* rest = nullptr);

// The pages of `pages` that a change of `before` into `after` (same topology) can alter, for a lattice
// that reads page boxes `boxes_lo/hi` (in the cloud's frame): see the header comment. With `points` (the
// points those boxes bound), a page the box test nominates is redone only when one of its points meets the
// same test. Exposed for tests.
std::vector<std::uint8_t> pages_touched_by_edit(const Lattice& before, const Lattice& after,
                                                std::span<const glm::dvec3> boxes_lo,
                                                std::span<const glm::dvec3> boxes_hi,
                                                const PagePoints* points = nullptr);

// What the skeleton keeps after a page-wise run: the record the next plan builds on.
void record_pages(DeformPageRecord& record, const PointPages& pages,
                  std::span<const Lattice* const> lattices);

}  // namespace sffd::ffd
