// The world-distance tools: the sphere, and grow / shrink by a distance through a uniform grid of cell
// `distance` (sorted cell keys: a point's neighbours within the distance lie in its own or the 26
// adjacent cells).
#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "systems/point_select/point_select.h"
#include "systems/point_select/shown_points.h"

namespace sffd::point_select {
namespace {

using detail::kBlockPoints;
using detail::Shown;

glm::dvec3 world(const Shown& s, std::size_t i) {
    return glm::dvec3(s.model * glm::dvec4(glm::dvec3(s.positions[i]), 1.0));
}

bool finite(const glm::dvec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

// The world box of a block (its cloud-frame box through the model matrix).
void block_world_box(const Shown& s, const detail::Block& b, glm::dvec3& lo, glm::dvec3& hi) {
    lo = glm::dvec3(INFINITY), hi = glm::dvec3(-INFINITY);
    for (int c = 0; c < 8; ++c) {
        const glm::dvec3 q((c & 1) ? b.hi.x : b.lo.x, (c & 2) ? b.hi.y : b.lo.y, (c & 4) ? b.hi.z : b.lo.z);
        const glm::dvec3 w(s.model * glm::dvec4(q, 1.0));
        lo = glm::min(lo, w), hi = glm::max(hi, w);
    }
}

struct CellItem {
    std::int64_t x, y, z;
    std::uint32_t index;
    glm::dvec3 p;
    auto key() const { return std::tie(x, y, z); }
};

// For every point of `targets`, whether a point of `sources` lies within `d` of it (world positions).
std::vector<std::uint32_t> targets_near_sources(std::vector<CellItem>& targets,
                                                std::vector<CellItem>& sources, double d) {
    auto by_key = [](const CellItem& a, const CellItem& b) { return a.key() < b.key(); };
    std::sort(targets.begin(), targets.end(), by_key);
    std::sort(sources.begin(), sources.end(), by_key);
    std::vector<std::size_t> groups;  // first item of each target cell
    for (std::size_t k = 0; k < targets.size(); ++k)
        if (k == 0 || targets[k].key() != targets[k - 1].key()) groups.push_back(k);
    groups.push_back(targets.size());
    std::vector<std::uint8_t> hit(targets.size(), 0);
    const double d2 = d * d;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, groups.size() - 1, 16),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t g = r.begin(); g != r.end(); ++g) {
                              const CellItem& cell = targets[groups[g]];
                              std::array<std::pair<std::size_t, std::size_t>, 27> ranges{};
                              std::size_t m = 0;
                              for (int dx = -1; dx <= 1; ++dx)
                                  for (int dy = -1; dy <= 1; ++dy)
                                      for (int dz = -1; dz <= 1; ++dz) {
                                          CellItem probe{cell.x + dx, cell.y + dy, cell.z + dz, 0, {}};
                                          const auto [lo, hi] =
                                              std::equal_range(sources.begin(), sources.end(), probe, by_key);
                                          if (lo != hi)
                                              ranges[m++] = {std::size_t(lo - sources.begin()),
                                                             std::size_t(hi - sources.begin())};
                                      }
                              for (std::size_t t = groups[g]; t < groups[g + 1]; ++t) {
                                  const glm::dvec3 p = targets[t].p;
                                  for (std::size_t q = 0; q < m && !hit[t]; ++q)
                                      for (std::size_t s = ranges[q].first; s < ranges[q].second; ++s) {
                                          const glm::dvec3 v = sources[s].p - p;
                                          if (glm::dot(v, v) <= d2) {
                                              hit[t] = 1;
                                              break;
                                          }
                                      }
                              }
                          }
                      });
    std::vector<std::uint32_t> out;
    for (std::size_t t = 0; t < targets.size(); ++t)
        if (hit[t]) out.push_back(targets[t].index);
    std::sort(out.begin(), out.end());
    return out;
}

// Grow (sources: selected, targets: unselected) or shrink (the other way round); gone points take no
// part. Toggles the targets that have a source within `distance`.
SelectionDelta grow_or_shrink(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                              double distance, bool grow) {
    const Shown s = detail::shown_points(registry, state, e);
    SelectionDelta none;
    none.points = s.n;
    if (s.n == 0 || !(distance > 0.0) || !std::isfinite(distance)) return none;
    const glm::dvec3 anchor(s.model[3]);
    std::vector<CellItem> sources, targets;
    for (std::size_t i = 0; i < s.n; ++i) {
        if (s.gone(i)) continue;
        const glm::dvec3 w = world(s, i);
        if (!finite(w)) continue;
        const glm::dvec3 c = glm::floor((w - anchor) / distance);
        if (!(glm::all(glm::lessThan(glm::abs(c), glm::dvec3(4e18))))) continue;
        const bool selected = !s.flags.empty() && (s.flags[i] & kPointSelected);
        CellItem item{std::int64_t(c.x), std::int64_t(c.y), std::int64_t(c.z), std::uint32_t(i), w};
        (selected == grow ? sources : targets).push_back(item);
    }
    if (sources.empty() || targets.empty()) return none;
    const std::vector<std::uint32_t> toggled = targets_near_sources(targets, sources, distance);
    SelectionDelta d = delta_from_indices(toggled, s.n);
    apply_delta(registry, e, d);
    return d;
}

}  // namespace

std::vector<std::uint32_t> points_in_sphere(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                                            const glm::dvec3& centre, double radius) {
    const Shown s = detail::shown_points(registry, state, e);
    if (s.n == 0 || !(radius >= 0.0)) return {};
    const std::vector<detail::Block>& blocks = s.cache->blocks;
    std::vector<std::vector<std::uint32_t>> found(blocks.size());
    const double r2 = radius * radius;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks.size(), 1),
                      [&](const tbb::blocked_range<std::size_t>& range) {
                          for (std::size_t b = range.begin(); b != range.end(); ++b) {
                              if (blocks[b].empty()) continue;
                              glm::dvec3 lo, hi;
                              block_world_box(s, blocks[b], lo, hi);
                              const glm::dvec3 gap =
                                  glm::max(glm::max(lo - centre, centre - hi), glm::dvec3(0.0));
                              if (glm::dot(gap, gap) > r2 * (1.0 + 1e-9)) continue;
                              const std::size_t end = std::min(s.n, (b + 1) * kBlockPoints);
                              for (std::size_t i = b * kBlockPoints; i < end; ++i) {
                                  if (s.gone(i)) continue;
                                  const glm::dvec3 v = world(s, i) - centre;
                                  if (glm::dot(v, v) <= r2) found[b].push_back(std::uint32_t(i));
                              }
                          }
                      });
    std::vector<std::uint32_t> out;
    for (const auto& f : found) out.insert(out.end(), f.begin(), f.end());
    return out;
}

SelectionDelta select_sphere(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                             const glm::dvec3& centre, double radius, Mode mode) {
    const std::vector<std::uint32_t> c = points_in_sphere(registry, state, e, centre, radius);
    return commit(registry, e, c, mode);
}

SelectionDelta grow_selection(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                              double distance) {
    return grow_or_shrink(registry, state, e, distance, true);
}

SelectionDelta shrink_selection(ecs::Registry& registry, PointSelectState& state, ecs::Entity e,
                                double distance) {
    return grow_or_shrink(registry, state, e, distance, false);
}

}  // namespace sffd::point_select
