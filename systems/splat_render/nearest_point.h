// The nearest of a fixed set of points to a query, through a uniform grid (about two points a cell):
// the ground truth's test of which splat a surface point belongs to (ground_truth.h: the surface of a
// hidden or deleted splat is not traced). Built once, read from any number of threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace sffd::render {

class NearestPoint {
public:
    NearestPoint() = default;
    explicit NearestPoint(std::vector<glm::dvec3> points);
    bool empty() const { return points_.empty(); }
    // Index of the finite point nearest to q (the first of equally near ones in grid order); SIZE_MAX when
    // there is none or q is not finite.
    std::size_t nearest(const glm::dvec3& q) const;

private:
    std::vector<glm::dvec3> points_;
    std::vector<std::uint32_t> start_, items_;  // per cell, [start_[c], start_[c + 1]) of items_
    glm::dvec3 lo_{0.0}, cell_{1.0};
    glm::ivec3 dims_{1};
};

}  // namespace sffd::render
