#include "systems/splat_render/splat_pack.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sffd::render {

BoundingSphere bounding_sphere(const SplatCloud& cloud) {
    if (cloud.positions.empty()) return {};
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (const glm::vec3& p : cloud.positions) {
        lo = glm::min(lo, glm::dvec3(p));
        hi = glm::max(hi, glm::dvec3(p));
    }
    BoundingSphere b;
    b.center = 0.5 * (lo + hi);
    double r2 = 0.0, splat_r2 = 0.0;
    for (const glm::vec3& p : cloud.positions)
        r2 = std::max(r2, glm::dot(glm::dvec3(p) - b.center, glm::dvec3(p) - b.center));
    for (std::size_t i = 0; i < cloud.axis_u.size() && i < cloud.axis_v.size(); ++i)
        splat_r2 = std::max(splat_r2, double(std::max(glm::dot(cloud.axis_u[i], cloud.axis_u[i]),
                                                      glm::dot(cloud.axis_v[i], cloud.axis_v[i]))));
    b.max_splat_radius = std::sqrt(splat_r2);
    b.radius = std::sqrt(r2) + b.max_splat_radius;
    return b;
}

}  // namespace sffd::render
