// Internal to sffd_point_select: the points of a cloud as the user sees them (picking's source of
// positions, the cloud's model matrix, the footprint radii) and the cached block bounds that let a query
// skip the blocks it cannot meet. The tools (screen_select.cpp, neighbourhood.cpp) read only this.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "runtime/scene/point_columns.h"
#include "systems/picking/pick_cache.h"
#include "systems/point_select/point_select.h"

namespace sffd::point_select::detail {

inline constexpr std::size_t kBlockPoints = 2048;  // culling granularity; divides a page (65,536)

// Bounds of kBlockPoints consecutive points in the cloud's frame (positions relative to its origin),
// finite points only (lo > hi: none), and the largest footprint radius among them (cloud frame).
struct Block {
    glm::vec3 lo{0.0f}, hi{0.0f};
    float max_radius = 0.0f;
    bool empty() const { return lo.x > hi.x; }
};

// Per-cloud cache, valid for one shown data set (source kind, version, array and size).
struct CloudCache {
    int kind = -1;
    std::uint64_t version = 0;
    const void* data = nullptr;
    std::size_t n = 0;
    std::vector<float> radius;  // footprint radius per point, cloud frame (before the Transform's scale)
    // Unit normal of a flat footprint (cloud frame): a splat's, a flat Gaussian's shortest axis; zero for
    // a round Gaussian (drawn facing the eye). The depth buffer writes the footprint's plane, so the
    // visibility test needs no slope allowance on surfaces seen at an angle.
    std::vector<glm::vec3> normal;
    std::vector<Block> blocks;
};

struct Shown {
    std::size_t n = 0;
    std::span<const glm::vec3> positions;  // relative to the origin, in the cloud's frame
    glm::dmat4 model{1.0};                 // model_matrix(Transform, origin)
    double scale = 1.0;                    // the model matrix's largest axis scale (for radii)
    std::span<const std::uint8_t> flags;   // PointFlags bits (empty: none gone)
    const CloudCache* cache = nullptr;

    bool gone(std::size_t i) const { return !flags.empty() && (flags[i] & kPointGone) != 0; }
};

// The shown points of e (n == 0: no cloud). Refreshes e's cache when the shown data changed.
Shown shown_points(ecs::Registry& registry, PointSelectState& state, ecs::Entity e);

}  // namespace sffd::point_select::detail

namespace sffd::point_select {

struct PointSelectState::Impl {
    picking::PickCache sources;  // read-backs and CPU deformations of clouds without a readable output
    std::unordered_map<std::uint64_t, detail::CloudCache> clouds;  // by entity bits
    Stats stats;
};

}  // namespace sffd::point_select
