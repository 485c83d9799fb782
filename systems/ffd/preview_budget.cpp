#include "systems/ffd/preview_budget.h"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

namespace sffd {

std::uint32_t preview_budget_for(const ecs::Registry& registry, std::size_t n) {
    const PreviewBudget* b = registry.try_resource<PreviewBudget>();
    if (!b || !b->active || b->points == 0 || n <= b->points) return 0;
    return b->points;
}

std::uint32_t gaussian_preview_budget_for(const ecs::Registry& registry, std::size_t n) {
    const PreviewBudget* b = registry.try_resource<PreviewBudget>();
    if (!b || !b->active || b->points == 0) return 0;
    const std::uint32_t budget = b->gaussians == 0 ? b->points : std::min(b->points, b->gaussians);
    return n <= budget ? 0 : budget;
}

void set_preview_active(ecs::Registry& registry, bool active) {
    PreviewBudget* b = registry.try_resource<PreviewBudget>();
    if (!b && !active) return;
    if (!b) b = &registry.set_resource<PreviewBudget>();
    b->active = active;
}

float preview_radius_scale(std::size_t n, std::size_t kept) {
    // Morton runs are not evenly spaced: sqrt(n / kept) alone left 4% of a 200k-splat sphere's image open
    // under a 20k budget, 1.3x 0.2%, 1.4x 0.04% (the full frame: none; ffd_preview_budget_gl_tests).
    constexpr double margin = 1.4;
    return kept == 0 || kept >= n ? 1.0f : float(margin * std::sqrt(double(n) / double(kept)));
}

namespace {

// Spreads the low 10 bits of v so that two zero bits follow each one.
std::uint32_t spread_bits(std::uint32_t v) {
    v &= 0x3ffu;
    v = (v | (v << 16)) & 0x030000ffu;
    v = (v | (v << 8)) & 0x0300f00fu;
    v = (v | (v << 4)) & 0x030c30c3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
}

}  // namespace

std::vector<std::uint32_t> spread_subset(std::span<const glm::vec3> positions, std::uint32_t budget) {
    const std::size_t n = positions.size();
    std::vector<std::uint32_t> out;
    if (budget >= n) {
        out.resize(n);
        for (std::size_t i = 0; i < n; ++i) out[i] = std::uint32_t(i);
        return out;
    }
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    auto finite = [](const glm::vec3& p) {
        return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    };
    for (const glm::vec3& p : positions)
        if (finite(p)) lo = glm::min(lo, p), hi = glm::max(hi, p);
    const glm::vec3 extent = hi - lo;
    const float largest = std::max({extent.x, extent.y, extent.z});
    const float scale = largest > 0.0f && std::isfinite(largest) ? 1023.0f / largest : 0.0f;
    // (code, index) pairs: the index breaks ties, so the order is the same on every run.
    std::vector<std::uint64_t> keyed(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 14), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            // A non-finite point (bad input) goes to cell 0 rather than into an undefined conversion.
            const glm::vec3 q = finite(positions[i]) ? glm::clamp((positions[i] - lo) * scale,
                                                                  glm::vec3(0.0f), glm::vec3(1023.0f))
                                                     : glm::vec3(0.0f);
            const std::uint32_t code = spread_bits(std::uint32_t(q.x)) << 2 |
                                       spread_bits(std::uint32_t(q.y)) << 1 | spread_bits(std::uint32_t(q.z));
            keyed[i] = std::uint64_t(code) << 32 | std::uint64_t(i);
        }
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    out.resize(budget);
    for (std::size_t k = 0; k < budget; ++k) {
        const std::size_t at = std::min(n - 1, std::size_t((double(k) + 0.5) * double(n) / double(budget)));
        out[k] = std::uint32_t(keyed[at] & 0xffffffffu);
    }
    std::sort(out.begin(), out.end());
    return out;
}

void update_preview_subset(PreviewSubset& subset, std::span<const glm::vec3> positions, std::uint64_t cloud,
                           std::uint32_t budget) {
    if (subset.cloud == cloud && subset.budget == budget && !subset.indices.empty()) return;
    subset.indices = spread_subset(positions, budget);
    subset.cloud = cloud;
    subset.budget = budget;
}

}  // namespace sffd
