#include "systems/splat_render/splat_pack.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sffd::render {

BoundingSphere bounding_sphere(const SplatCloud& cloud, const PointFlags* flags) {
    if (cloud.positions.empty()) return {};
    const std::size_t n = cloud.positions.size();
    if (flags && flags->bits.size() != n) flags = nullptr;  // of another size: no point is gone
    const auto kept = [&](std::size_t i) { return !flags || (flags->bits[i] & kPointGone) == 0; };
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    bool any = false;
    for (std::size_t i = 0; i < n; ++i)
        if (kept(i)) {
            lo = glm::min(lo, glm::dvec3(cloud.positions[i]));
            hi = glm::max(hi, glm::dvec3(cloud.positions[i]));
            any = true;
        }
    if (!any) return {};
    BoundingSphere b;
    b.center = 0.5 * (lo + hi);
    double r2 = 0.0, splat_r2 = 0.0;
    for (std::size_t i = 0; i < n; ++i)
        if (kept(i)) {
            const glm::dvec3 d = glm::dvec3(cloud.positions[i]) - b.center;
            r2 = std::max(r2, glm::dot(d, d));
        }
    for (std::size_t i = 0; i < cloud.axis_u.size() && i < cloud.axis_v.size() && i < n; ++i)
        if (kept(i))
            splat_r2 = std::max(splat_r2, double(std::max(glm::dot(cloud.axis_u[i], cloud.axis_u[i]),
                                                          glm::dot(cloud.axis_v[i], cloud.axis_v[i]))));
    b.max_splat_radius = std::sqrt(splat_r2);
    b.radius = std::sqrt(r2) + b.max_splat_radius;
    return b;
}

}  // namespace sffd::render
