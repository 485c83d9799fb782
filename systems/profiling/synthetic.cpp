#include "systems/profiling/synthetic.h"

#include <cmath>

namespace sffd::profiling {

SplatCloud synthetic_sphere(std::size_t count, double radius) {
    SplatCloud c;
    c.positions.reserve(count);
    c.normals.reserve(count);
    c.axis_u.reserve(count);
    c.axis_v.reserve(count);
    c.colors.reserve(count);
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    // Each splat covers ~4 pi r^2 / count; 1.3x its equal-area disc radius overlaps the neighbours.
    const double splat_r = 1.3 * radius * std::sqrt(4.0 / std::max<double>(1.0, static_cast<double>(count)));
    for (std::size_t i = 0; i < count; ++i) {
        const double y = 1.0 - 2.0 * (static_cast<double>(i) + 0.5) / static_cast<double>(count);
        const double r = std::sqrt(std::max(0.0, 1.0 - y * y));
        const double phi = golden * static_cast<double>(i);
        const glm::dvec3 n(std::cos(phi) * r, y, std::sin(phi) * r);
        const glm::dvec3 ref = std::abs(n.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
        const glm::dvec3 u = glm::normalize(glm::cross(ref, n));
        const glm::dvec3 v = glm::cross(n, u);
        c.positions.emplace_back(n * radius);
        c.normals.emplace_back(n);
        c.axis_u.emplace_back(u * splat_r);
        c.axis_v.emplace_back(v * splat_r);
        const auto red = static_cast<std::uint32_t>(127.5 * (n.x + 1.0));
        const auto green = static_cast<std::uint32_t>(127.5 * (y + 1.0));
        c.colors.push_back(red | (green << 8) | (200u << 16) | (255u << 24));
    }
    return c;
}

}  // namespace sffd::profiling
