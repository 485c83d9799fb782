#include "systems/splat_render/nearest_point.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sffd::render {

NearestPoint::NearestPoint(std::vector<glm::dvec3> points) : points_(std::move(points)) {
    // Non-finite points are never found (and never turned into a cell index: a NaN is no integer).
    const auto finite = [](const glm::dvec3& p) {
        return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    };
    glm::dvec3 hi(-std::numeric_limits<double>::infinity());
    lo_ = glm::dvec3(std::numeric_limits<double>::infinity());
    for (const glm::dvec3& p : points_)
        if (finite(p)) lo_ = glm::min(lo_, p), hi = glm::max(hi, p);
    if (!(lo_.x <= hi.x)) {  // none is finite
        points_.clear();
        return;
    }
    const glm::dvec3 extent = glm::max(hi - lo_, glm::dvec3(1e-12));
    // Cubic cells holding about two points each on average.
    const double side = std::cbrt(extent.x * extent.y * extent.z * 2.0 / double(points_.size()));
    const double s = std::max({side, extent.x / 1024.0, extent.y / 1024.0, extent.z / 1024.0});
    dims_ = glm::clamp(glm::ivec3(glm::ceil(extent / s)), glm::ivec3(1), glm::ivec3(1024));
    cell_ = extent / glm::dvec3(dims_);
    const std::size_t cells = std::size_t(dims_.x) * std::size_t(dims_.y) * std::size_t(dims_.z);
    auto cell_of = [&](const glm::dvec3& p) {
        const glm::ivec3 c = glm::clamp(glm::ivec3(glm::floor((p - lo_) / cell_)), glm::ivec3(0), dims_ - 1);
        return (std::size_t(c.z) * std::size_t(dims_.y) + std::size_t(c.y)) * std::size_t(dims_.x) +
               std::size_t(c.x);
    };
    start_.assign(cells + 1, 0);
    for (const glm::dvec3& p : points_)
        if (finite(p)) ++start_[cell_of(p) + 1];
    for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
    items_.resize(start_[cells]);
    std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
    for (std::size_t i = 0; i < points_.size(); ++i)
        if (finite(points_[i])) items_[fill[cell_of(points_[i])]++] = std::uint32_t(i);
}

std::size_t NearestPoint::nearest(const glm::dvec3& q) const {
    if (points_.empty() || !std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z))
        return std::numeric_limits<std::size_t>::max();
    const glm::ivec3 c = glm::clamp(glm::ivec3(glm::floor((q - lo_) / cell_)), glm::ivec3(0), dims_ - 1);
    const double min_cell = std::min({cell_.x, cell_.y, cell_.z});
    double best = std::numeric_limits<double>::infinity();
    std::size_t found = std::numeric_limits<std::size_t>::max();
    const int rings = std::max({dims_.x, dims_.y, dims_.z});
    for (int r = 0; r <= rings; ++r) {
        // Every point of ring r or further is at least r - 1 cells away along the axis of its offset (more
        // when the query lies outside the grid on it).
        if (found != std::numeric_limits<std::size_t>::max() && std::sqrt(best) <= (r - 1) * min_cell) break;
        for (int z = std::max(c.z - r, 0); z <= std::min(c.z + r, dims_.z - 1); ++z)
            for (int y = std::max(c.y - r, 0); y <= std::min(c.y + r, dims_.y - 1); ++y)
                for (int x = std::max(c.x - r, 0); x <= std::min(c.x + r, dims_.x - 1); ++x) {
                    if (std::max({std::abs(x - c.x), std::abs(y - c.y), std::abs(z - c.z)}) != r) continue;
                    const std::size_t cell =
                        (std::size_t(z) * std::size_t(dims_.y) + std::size_t(y)) * std::size_t(dims_.x) +
                        std::size_t(x);
                    for (std::uint32_t k = start_[cell]; k < start_[cell + 1]; ++k) {
                        const glm::dvec3 d = points_[items_[k]] - q;
                        const double d2 = glm::dot(d, d);
                        if (d2 < best) best = d2, found = items_[k];
                    }
                }
    }
    return found;
}

}  // namespace sffd::render
