#include "runtime/scene/point_pages.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "runtime/core/log.h"
#include "runtime/scene/point_columns.h"

namespace sffd {

namespace {

// The positions and size of e's cloud, whichever kind it is; stamps it changed when `stamp`.
struct CloudView {
    const glm::dvec3* origin = nullptr;
    const std::vector<glm::vec3>* positions = nullptr;
    std::uint64_t version = 0;
};

CloudView cloud_of(ecs::Registry& reg, ecs::Entity e, bool stamp) {
    const ecs::Registry& r = reg;  // reads through the const registry: only a mark writes the cloud
    if (!r.valid(e)) return {};
    if (r.has<SplatCloud>(e)) {
        if (stamp) reg.mark_changed<SplatCloud>(e);
        const SplatCloud& c = r.get<SplatCloud>(e);
        return {&c.origin, &c.positions, r.version<SplatCloud>(e)};
    }
    if (r.has<GaussianCloud>(e)) {
        if (stamp) reg.mark_changed<GaussianCloud>(e);
        const GaussianCloud& c = r.get<GaussianCloud>(e);
        return {&c.origin, &c.positions, r.version<GaussianCloud>(e)};
    }
    return {};
}

void compute_bounds(PointPages& p, const CloudView& c, std::size_t page) {
    const PageRange r = page_range(page, p.points);
    constexpr double inf = std::numeric_limits<double>::infinity();
    glm::dvec3 lo(inf), hi(-inf);
    const glm::vec3* pos = c.positions->data() + r.first;
    for (std::size_t i = 0; i < r.count; ++i) {
        const glm::vec3 v = pos[i];
        if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) continue;
        const glm::dvec3 d = *c.origin + glm::dvec3(v);
        lo = glm::min(lo, d), hi = glm::max(hi, d);
    }
    p.rest_lo[page] = lo, p.rest_hi[page] = hi;
}

// Every page of every column changed at a new clock value; the boxes are recomputed by the next refresh.
void replace(PointPages& p, std::size_t points, std::uint64_t cloud_version) {
    p.points = points;
    p.cloud_version = cloud_version;
    ++p.clock;
    const std::size_t pages = page_count(points);
    for (auto& s : p.stamps) s.assign(pages, p.clock);
    p.rest_lo.assign(pages, glm::dvec3(0.0)), p.rest_hi.assign(pages, glm::dvec3(0.0));
}

}  // namespace

void mark_cloud_replaced(ecs::Registry& reg, ecs::Entity e) {
    const CloudView c = cloud_of(reg, e, true);
    if (!c.positions) return;
    if (!reg.has<PointPages>(e)) reg.emplace<PointPages>(e);
    replace(reg.get<PointPages>(e), c.positions->size(), c.version);
}

namespace {

// The stamps of pages [first, first + count) of `column` at the record's clock.
void stamp_pages(PointPages& p, PointColumn column, std::size_t first, std::size_t count) {
    const std::size_t n = p.points;
    if (count == 0 || first >= n) return;
    const std::size_t last = std::min(n, first + count) - 1;
    auto& s = p.stamps[std::size_t(column)];
    for (std::size_t page = first >> kPageShift; page <= last >> kPageShift; ++page) s[page] = p.clock;
}

// An optional column's group: its own component is stamped, never the cloud (the header says why).
void mark_optional_changed(ecs::Registry& reg, ecs::Entity e, PointColumn column, std::size_t first,
                           std::size_t count) {
    const CloudView c = cloud_of(reg, e, false);
    if (!c.positions) return;
    const ecs::Registry& r = reg;
    const bool flags = column != PointColumn::weight;
    std::size_t values = 0;
    if (flags && r.has<PointFlags>(e)) {
        reg.mark_changed<PointFlags>(e);
        values = r.get<PointFlags>(e).bits.size();
    } else if (!flags && r.has<PointWeights>(e)) {
        reg.mark_changed<PointWeights>(e);
        values = r.get<PointWeights>(e).values.size();
    }
    const std::size_t n = c.positions->size();
    PointPages* p = reg.try_get<PointPages>(e);
    if (!p || p->points != n || p->stamps[0].size() != page_count(n)) {
        if (!p) p = &reg.emplace<PointPages>(e);
        replace(*p, n, c.version);
    } else {
        // The cloud's stamp is left as the record has it: an unmarked change of the cloud itself must
        // still be found by the next refresh.
        ++p->clock;
        if (values != 0 && values != n) {
            log::warn("mark_points_changed(): entity ", e.index, ": ", flags ? "PointFlags" : "PointWeights",
                      " holds ", values, " values for a cloud of ", n,
                      " points; the column reads as absent and every page of it is stamped");
            first = 0, count = n;
        }
        stamp_pages(*p, column, first, count);
    }
    (flags ? p->flags_version : p->weights_version) =
        flags ? r.version<PointFlags>(e) : r.version<PointWeights>(e);
}

}  // namespace

void mark_points_changed(ecs::Registry& reg, ecs::Entity e, PointColumn column, std::size_t first,
                         std::size_t count) {
    if (optional_point_column(column)) return mark_optional_changed(reg, e, column, first, count);
    const CloudView c = cloud_of(reg, e, true);
    if (!c.positions) return;
    PointPages* p = reg.try_get<PointPages>(e);
    const std::size_t n = c.positions->size();
    // No record or a size change: the pages cannot say what changed. A change of the cloud component since
    // the last mark that was not marked is taken to be this edit (the refresh of the next frame catches
    // one that no mark follows).
    if (!p || p->points != n || p->stamps[0].size() != page_count(n)) {
        if (!p) p = &reg.emplace<PointPages>(e);
        replace(*p, n, c.version);
        return;
    }
    p->cloud_version = c.version;
    ++p->clock;
    stamp_pages(*p, column, first, count);
}

const PointPages* refresh_point_pages(ecs::Registry& reg, ecs::Entity e) {
    const CloudView c = cloud_of(reg, e, false);
    if (!c.positions) return nullptr;
    PointPages* p = reg.try_get<PointPages>(e);
    if (!p) p = &reg.emplace<PointPages>(e);
    const std::size_t n = c.positions->size();
    if (p->points != n || p->cloud_version != c.version || p->stamps[0].size() != page_count(n) ||
        p->clock == 0) {
        replace(*p, n, c.version);
        p->bounds_clock = 0;
    }
    if (p->bounds_clock != p->clock) {
        const auto& s = p->stamps[std::size_t(PointColumn::position)];
        for (std::size_t page = 0; page < s.size(); ++page)
            if (s[page] > p->bounds_clock) compute_bounds(*p, c, page);
        p->bounds_clock = p->clock;
    }
    return p;
}

std::vector<std::uint32_t> pages_changed_since(const PointPages& p, std::uint64_t since,
                                               std::span<const PointColumn> columns) {
    std::vector<std::uint32_t> out;
    const std::size_t pages = p.stamps[0].size();
    for (std::size_t page = 0; page < pages; ++page)
        for (PointColumn col : columns)
            if (p.stamps[std::size_t(col)][page] > since) {
                out.push_back(std::uint32_t(page));
                break;
            }
    return out;
}

}  // namespace sffd
