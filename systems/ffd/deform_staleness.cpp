#include "systems/ffd/deform_staleness.h"

#include <algorithm>
#include <cmath>

#include "systems/ffd/lattice.h"

namespace sffd::ffd {

namespace {

// A box in a lattice's parameter space (s, t, u); empty when lo > hi on some axis.
struct ParamBox {
    glm::dvec3 lo{1.0}, hi{0.0};
    bool empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
};

bool meets(const ParamBox& a, const ParamBox& b) {
    return !a.empty() && !b.empty() && a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y &&
           b.lo.y <= a.hi.y && a.lo.z <= b.hi.z && b.lo.z <= a.hi.z;
}
bool within(const ParamBox& a, const ParamBox& b) {  // a inside b
    return !a.empty() && !b.empty() && glm::all(glm::greaterThanEqual(a.lo, b.lo)) &&
           glm::all(glm::lessThanEqual(a.hi, b.hi));
}
ParamBox widen(ParamBox b, double m) {
    if (!b.empty()) b.lo -= m, b.hi += m;
    return b;
}
ParamBox shrink(ParamBox b, double m) {
    if (!b.empty()) b.lo += m, b.hi -= m;
    return b;
}

// The lattice's box, where points are inside (faces inclusive with kInsideSlack).
ParamBox inside_box() { return {glm::dvec3(-kInsideSlack), glm::dvec3(1.0 + kInsideSlack)}; }

// The index box [lo, hi] of control points, mapped to the parameter interval where their B-spline bases can
// be nonzero: l·s in [lo - 2, hi + 2].
ParamBox bspline_support(const Lattice& l, const glm::ivec3& lo, const glm::ivec3& hi) {
    ParamBox b;
    for (int a = 0; a < 3; ++a) {
        const double n = l.divisions[a];
        b.lo[a] = (lo[a] - 2.0) / n;
        b.hi[a] = (hi[a] + 2.0) / n;
    }
    return b;
}

// The box of the control points whose displacement differs between the lattices (`only_moved`: of the
// points of `a` that are off their rest, the kernels' "moved" set).
void index_box(const Lattice& a, const Lattice* b, glm::ivec3& lo, glm::ivec3& hi) {
    lo = glm::ivec3(1 << 30), hi = glm::ivec3(-1);
    std::size_t c = 0;
    for (int i = 0; i <= a.divisions.x; ++i)
        for (int j = 0; j <= a.divisions.y; ++j)
            for (int k = 0; k <= a.divisions.z; ++k, ++c) {
                const bool differs =
                    b ? a.current[c] != b->current[c] : (a.current[c] - a.rest[c]) != glm::dvec3(0.0);
                if (!differs) continue;
                lo = glm::min(lo, glm::ivec3(i, j, k));
                hi = glm::max(hi, glm::ivec3(i, j, k));
            }
}

// The page box (cloud frame) in the lattice's parameter space: its eight corners mapped, an exact hull of
// the box's image since the map is affine.
ParamBox to_params(const Lattice& l, const glm::dvec3& lo, const glm::dvec3& hi) {
    ParamBox b{glm::dvec3(INFINITY), glm::dvec3(-INFINITY)};
    for (int c = 0; c < 8; ++c) {
        const glm::dvec3 p((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z);
        const glm::dvec3 s = local_coords(l, p);
        b.lo = glm::min(b.lo, s), b.hi = glm::max(b.hi, s);
    }
    return b;
}

}  // namespace

bool same_topology(const Lattice& a, const Lattice& b) {
    return a.origin == b.origin && a.axes == b.axes && a.divisions == b.divisions && a.basis == b.basis &&
           a.rest == b.rest && a.current.size() == b.current.size();
}

std::vector<std::uint8_t> pages_touched_by_edit(const Lattice& before, const Lattice& after,
                                                std::span<const glm::dvec3> boxes_lo,
                                                std::span<const glm::dvec3> boxes_hi,
                                                const PagePoints* points) {
    std::vector<std::uint8_t> touched(boxes_lo.size(), 0);
    glm::ivec3 lo, hi;
    index_box(after, &before, lo, hi);
    const bool changed = hi.x >= 0;
    // Regions a page must meet to be redone. Bernstein: the box, when anything changed (every basis function
    // is nonzero inside; the kernel's choice between its dense and sparse sums and the coordinates it sums
    // also follow the whole lattice). B-spline: the changed points' support, and where the cull box changed.
    ParamBox support, cull_old, cull_new;
    bool cull_changed = false;
    if (after.basis == LatticeBasis::bernstein) {
        if (!changed) return touched;
        support = inside_box();
    } else {
        if (changed) support = bspline_support(after, lo, hi);
        glm::ivec3 olo, ohi, nlo, nhi;
        index_box(before, nullptr, olo, ohi);
        index_box(after, nullptr, nlo, nhi);
        if (ohi.x >= 0) cull_old = bspline_support(before, olo, ohi);
        if (nhi.x >= 0) cull_new = bspline_support(after, nlo, nhi);
        cull_changed = (olo != nlo || ohi != nhi);
        if (!changed && !cull_changed) return touched;
    }
    const ParamBox box = inside_box();
    const glm::dmat3 minv = inverse_axes(after);  // local_coords() without its inverse per point
    for (std::size_t p = 0; p < boxes_lo.size(); ++p) {
        if (boxes_lo[p].x > boxes_hi[p].x) continue;  // no finite point
        const ParamBox page = to_params(after, boxes_lo[p], boxes_hi[p]);
        // The float kernels compute the local coordinates from float positions: allow for their rounding,
        // relative to the coordinates' size (1e-4 of a lattice edge at unit size, over a hundred float ulps).
        const double mag = std::max({1.0, std::abs(page.lo.x), std::abs(page.lo.y), std::abs(page.lo.z),
                                     std::abs(page.hi.x), std::abs(page.hi.y), std::abs(page.hi.z)});
        const double m = 1e-4 * mag;
        // Whether points spanning `wide` (already widened by m) can come out differently.
        const auto alters = [&](const ParamBox& wide) {
            if (!meets(wide, widen(box, m))) return false;  // outside the lattice: copied, whatever the edit
            if (changed && meets(wide, widen(support, m))) return true;
            if (!cull_changed) return false;
            const bool near = meets(wide, widen(cull_old, m)) || meets(wide, widen(cull_new, m));
            const bool in_both = within(wide, shrink(cull_old, m)) && within(wide, shrink(cull_new, m));
            return near && !in_both;
        };
        bool redo = alters(widen(page, m));
        if (redo && points) {
            // A page's box spans far more than its points do (a band of a sphere's surface has a box through
            // the sphere's middle), so the box only nominates: the page is redone when one of its own points,
            // under the same rule and margin, can change. Its points at rest are what the box bounds.
            redo = false;
            const PageRange r = page_range(p, points->positions.size());
            for (std::size_t i = r.first; i < r.first + r.count && !redo; ++i) {
                const glm::dvec3 x = points->origin + glm::dvec3(points->positions[i]);
                if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z))
                    continue;  // not in the box
                const glm::dvec3 st = minv * (x - after.origin);
                redo = alters(widen(ParamBox{st, st}, m));
            }
        }
        touched[p] = redo;
    }
    return touched;
}

RedoPlan plan_redeform(const DeformInputStamps& seen, const DeformPageRecord& record,
                       const DeformInputStamps& now, const PointPages& pages,
                       std::span<const Lattice* const> lattices, std::span<const PointColumn> reads,
                       const PagePoints* rest) {
    RedoPlan plan;  // everything
    const std::size_t n = pages.points, np = page_count(n);
    if (record.points == 0 || record.points != n || record.counts.size() != np ||
        seen.deformers != now.deformers || seen.weights != now.weights ||
        record.lattices.size() != lattices.size() || pages.rest_lo.size() != np)
        return plan;
    for (std::size_t d = 0; d < lattices.size(); ++d)
        if (!same_topology(record.lattices[d], *lattices[d])) return plan;
    std::vector<std::uint8_t> redo(np, 0);
    if (now.cloud != seen.cloud) {
        // The record must be in step with the cloud (every change since the output marked).
        if (pages.cloud_version != now.cloud || record.pages_clock > pages.clock) return plan;
        for (std::uint32_t p : pages_changed_since(pages, record.pages_clock, reads)) redo[p] = 1;
    }
    // Each lattice reads its page boxes carried through the lattices before it.
    std::vector<glm::dvec3> lo(pages.rest_lo), hi(pages.rest_hi);
    for (std::size_t d = 0; d < lattices.size(); ++d) {
        const Lattice& now_l = *lattices[d];
        const bool valid = validate(now_l).ok(), was_valid = validate(record.lattices[d]).ok();
        if (valid != was_valid) return plan;
        if (!valid) continue;  // skipped by every run
        if (record.lattices[d].current != now_l.current) {
            // The first lattice reads the rest points themselves; later ones read deformed points, which
            // only their carried boxes bound.
            const std::vector<std::uint8_t> t =
                pages_touched_by_edit(record.lattices[d], now_l, lo, hi, d == 0 ? rest : nullptr);
            for (std::size_t p = 0; p < np; ++p) redo[p] |= t[p];
        }
        if (d + 1 < lattices.size())
            for (std::size_t p = 0; p < np; ++p) {
                if (lo[p].x > hi[p].x) continue;
                const Box b = deformed_bounds(now_l, Box{lo[p], hi[p], false});
                lo[p] = b.lo, hi[p] = b.hi;
            }
    }
    plan.what = Redo::nothing;
    for (std::size_t p = 0; p < np; ++p)
        if (redo[p]) plan.pages.push_back(std::uint32_t(p));
    if (!plan.pages.empty()) plan.what = Redo::pages;
    return plan;
}

void record_pages(DeformPageRecord& record, const PointPages& pages,
                  std::span<const Lattice* const> lattices) {
    record.points = pages.points;
    record.pages_clock = pages.clock;
    record.lattices.clear();
    for (const Lattice* l : lattices) record.lattices.push_back(*l);
    record.counts.resize(page_count(pages.points));
}

}  // namespace sffd::ffd
