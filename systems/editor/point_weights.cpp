#include "systems/editor/point_weights.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <unordered_map>
#include <unordered_set>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "runtime/core/log.h"
#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_pages.h"
#include "systems/editor/editor_state.h"
#include "systems/editor/point_mode.h"

namespace sffd::editor {

PointWeightChange::PointWeightChange(std::string label, ecs::Entity cloud, std::size_t points,
                                     bool before_empty, bool after_empty, std::vector<std::uint32_t> indices,
                                     std::vector<float> before, std::vector<float> after)
    : Command(std::move(label)),
      m_cloud(cloud),
      m_points(points),
      m_before_empty(before_empty),
      m_after_empty(after_empty),
      m_indices(std::move(indices)),
      m_before(std::move(before)),
      m_after(std::move(after)) {}

void PointWeightChange::undo(ecs::Registry& registry, EntityMap& map) const { apply(registry, map, false); }
void PointWeightChange::redo(ecs::Registry& registry, EntityMap& map) const { apply(registry, map, true); }

std::size_t PointWeightChange::bytes() const {
    return sizeof(*this) + label().capacity() + m_indices.capacity() * sizeof(std::uint32_t) +
           (m_before.capacity() + m_after.capacity()) * sizeof(float);
}

// The column goes to the state on one side: empty, or (from empty: ones) with that side's values at the
// points that differ; every other point has the same value on both sides.
void PointWeightChange::apply(ecs::Registry& registry, const EntityMap& map, bool forward) const {
    const ecs::Entity e = map(m_cloud);
    if (!registry.valid(e) || point_select::point_count(registry, e) != m_points) return;
    const bool to_empty = forward ? m_after_empty : m_before_empty;
    const std::vector<float>& values = forward ? m_after : m_before;
    if (!registry.has<PointWeights>(e)) registry.emplace<PointWeights>(e);
    PointWeights& w = registry.patch<PointWeights>(e);
    if (to_empty) {
        w.values.clear();
    } else {
        if (w.values.size() != m_points) w.values.assign(m_points, 1.0f);
        for (std::size_t k = 0; k < m_indices.size(); ++k) w.values[m_indices[k]] = values[k];
    }
    mark_points_changed(registry, e, PointColumn::weight, 0, m_points);
}

std::vector<double> distance_to_selection(std::span<const glm::dvec3> world,
                                          std::span<const std::uint32_t> selected, double radius) {
    constexpr double inf = std::numeric_limits<double>::infinity();
    std::vector<double> out(world.size(), inf);
    if (selected.empty() || !(radius > 0.0)) {
        for (std::uint32_t s : selected) out[s] = 0.0;
        return out;
    }
    constexpr int rings = 4;  // cells of radius/4: a query reads at most 11^3 cells
    const double cell = radius / rings;
    auto cell_of = [&](const glm::dvec3& p) { return glm::ivec3(glm::floor(p / cell)); };
    auto key = [](glm::ivec3 c) {
        return (std::uint64_t(std::uint32_t(c.x) & 0x1FFFFF) << 42) |
               (std::uint64_t(std::uint32_t(c.y) & 0x1FFFFF) << 21) |
               std::uint64_t(std::uint32_t(c.z) & 0x1FFFFF);
    };
    std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> grid;
    grid.reserve(selected.size());
    // Cells of the radius that hold a selected point: a point none of whose 27 neighbours holds one has
    // no selected point within the radius (most of a cloud, far from a small selection: 27 look-ups, not
    // the fine search's 1,331).
    std::unordered_set<std::uint64_t> coarse;
    auto coarse_of = [&](const glm::dvec3& p) { return glm::ivec3(glm::floor(p / radius)); };
    for (std::uint32_t s : selected) {
        grid[key(cell_of(world[s]))].push_back(s);
        coarse.insert(key(coarse_of(world[s])));
        out[s] = 0.0;
    }
    auto near_selection = [&](const glm::dvec3& p) {
        const glm::ivec3 c = coarse_of(p);
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz)
                    if (coarse.count(key(c + glm::ivec3(dx, dy, dz)))) return true;
        return false;
    };
    // Each point's search reads the grids only: the points split over the cores (TBB, as the other CPU
    // kernels).
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, world.size(), 4096), [&](const auto& range) {
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
            if (out[i] == 0.0 || !near_selection(world[i])) continue;
            const glm::ivec3 c = cell_of(world[i]);
            double best = inf;
            // A point within the radius (rings cells) may lie one ring further: the query sits anywhere in
            // its cell.
            for (int ring = 0; ring <= rings + 1; ++ring) {
                // Every point of ring `ring` is at least (ring - 1) cells away.
                if (best <= (ring - 1) * cell) break;
                for (int dx = -ring; dx <= ring; ++dx)
                    for (int dy = -ring; dy <= ring; ++dy)
                        for (int dz = -ring; dz <= ring; ++dz) {
                            if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) != ring) continue;
                            const auto it = grid.find(key(c + glm::ivec3(dx, dy, dz)));
                            if (it == grid.end()) continue;
                            for (std::uint32_t s : it->second)
                                best = std::min(best, glm::distance(world[i], world[s]));
                        }
            }
            out[i] = best <= radius ? best : inf;
        }
    });
    return out;
}

namespace {

template <class Cloud>
std::vector<glm::dvec3> world_positions(const ecs::Registry& registry, ecs::Entity e, const Cloud& cloud) {
    const glm::dmat4 model = model_matrix(registry.try_get<Transform>(e));
    std::vector<glm::dvec3> out(cloud.positions.size());
    for (std::size_t i = 0; i < out.size(); ++i)
        out[i] = glm::dvec3(model * glm::dvec4(cloud.origin + glm::dvec3(cloud.positions[i]), 1.0));
    return out;
}

std::vector<glm::dvec3> cloud_world(const ecs::Registry& registry, ecs::Entity e) {
    if (const SplatCloud* c = registry.try_get<SplatCloud>(e)) return world_positions(registry, e, *c);
    if (const GaussianCloud* g = registry.try_get<GaussianCloud>(e)) return world_positions(registry, e, *g);
    return {};
}

// Applies `target` (empty: no weights) to e's column as one step added to `group`.
void set_weights(ecs::Registry& registry, CommandGroup& group, ecs::Entity e, const std::string& label,
                 std::vector<float> target) {
    const std::size_t n = point_select::point_count(registry, e);
    const PointWeights* w = registry.try_get<PointWeights>(e);
    const bool before_empty = !w || w->values.size() != n;
    const bool after_empty = target.empty();
    std::vector<std::uint32_t> indices;
    std::vector<float> before, after;
    for (std::size_t i = 0; i < n; ++i) {
        const float b = before_empty ? 1.0f : w->values[i];
        const float a = after_empty ? 1.0f : target[i];
        if (std::memcmp(&a, &b, sizeof a) == 0) continue;
        indices.push_back(std::uint32_t(i));
        before.push_back(b), after.push_back(a);
    }
    auto step = std::make_unique<PointWeightChange>(label, e, n, before_empty, after_empty,
                                                    std::move(indices), std::move(before), std::move(after));
    if (step->empty()) return;
    EntityMap none;
    step->redo(registry, none);
    group.add(std::move(step));
}

}  // namespace

bool weights_from_selection(ecs::Registry& registry, EditorState& state, double radius, Falloff falloff) {
    auto group = std::make_unique<CommandGroup>("weights from selection");
    std::size_t clouds = 0, weighted = 0;
    for (ecs::Entity e : point_clouds(registry)) {
        const std::vector<std::uint32_t> selected = point_select::selected_points(registry, e);
        if (selected.empty()) continue;
        ++clouds;
        const std::vector<glm::dvec3> world = cloud_world(registry, e);
        const std::vector<double> d = distance_to_selection(world, selected, radius);
        std::vector<float> w(world.size());
        for (std::size_t i = 0; i < w.size(); ++i) {
            w[i] = std::isfinite(d[i]) ? float(falloff_weight(falloff, d[i], radius)) : 0.0f;
            weighted += w[i] > 0.0f;
        }
        set_weights(registry, *group, e, "weights from selection", std::move(w));
    }
    if (clouds == 0) {
        state.status = "weights: nothing selected (select points first)";
        log::info("editor: ", state.status);
        return false;
    }
    state.undo.push(std::move(group));
    state.status = log::str("weights from the selection: ", weighted, " points weighted (",
                            falloff_name(falloff), ", radius ", radius, "), the rest 0");
    log::info("editor: ", state.status);
    return true;
}

bool clear_weights(ecs::Registry& registry, EditorState& state) {
    auto group = std::make_unique<CommandGroup>("clear weights");
    for (ecs::Entity e : point_clouds(registry))
        if (const PointWeights* w = registry.try_get<PointWeights>(e); w && !w->values.empty())
            set_weights(registry, *group, e, "clear weights", {});
    const bool any = state.undo.push(std::move(group));
    state.status = any ? "weights cleared (1 everywhere)" : "weights: no cloud has weights";
    log::info("editor: ", state.status);
    return any;
}

}  // namespace sffd::editor
