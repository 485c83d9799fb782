#include "systems/splat_render/camera_math.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "systems/splat_render/gaussian_pass.h"
#include "systems/splat_render/splat_pack.h"

namespace sffd::render {

Camera framing_camera(const glm::dvec3& center, double radius, double aspect, glm::dvec3 direction,
                      float fov_y_degrees) {
    radius = std::max(radius, 1e-6);
    const double half_y = glm::radians(double(fov_y_degrees)) * 0.5;
    const double half_x = std::atan(std::tan(half_y) * aspect);
    const double half = std::min(half_y, half_x);
    const double distance = radius / std::sin(half) * 1.1;
    Camera c;
    c.fov_y_degrees = fov_y_degrees;
    c.target = center;
    c.eye = center + glm::normalize(direction) * distance;
    c.up = std::abs(glm::normalize(direction).y) > 0.99 ? glm::dvec3(0, 0, -1) : glm::dvec3(0, 1, 0);
    c.near_plane = float(std::max((distance - radius) * 0.5, distance * 1e-3));
    c.far_plane = float(distance + radius * 2.0);
    return c;
}

Camera scene_camera(const ecs::Registry& registry, double aspect, const CloudBounds& bounds,
                    const GaussianBounds& gaussian_bounds) {
    bool found = false;
    Camera camera;
    registry.view<const Camera>().each([&](const Camera& c) {
        if (!found) camera = c, found = true;
    });
    if (found) return camera;
    const SceneSphere s = scene_sphere(registry, bounds, gaussian_bounds);
    return framing_camera(s.center, s.radius, aspect);
}

SceneSphere scene_sphere(const ecs::Registry& registry, const CloudBounds& bounds,
                         const GaussianBounds& gaussian_bounds) {
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    std::vector<std::pair<glm::dvec3, double>> balls;
    // A cloud's sphere `b` (cloud space) in world space: centre through the model matrix, radius by its
    // largest axis scale.
    auto add = [&](ecs::Entity e, const glm::dvec3& origin, const BoundingSphere& b) {
        if (b.radius < 0.0) return;
        const glm::dmat4 m = model_matrix(registry.try_get<Transform>(e), origin);
        const double scale = std::max(
            {glm::length(glm::dvec3(m[0])), glm::length(glm::dvec3(m[1])), glm::length(glm::dvec3(m[2]))});
        const glm::dvec3 c = glm::dvec3(m * glm::dvec4(b.center, 1.0));
        balls.emplace_back(c, b.radius * scale);
        lo = glm::min(lo, c - b.radius * scale);
        hi = glm::max(hi, c + b.radius * scale);
    };
    registry.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& cloud) {
        if (cloud.size() > 0)
            add(e, cloud.origin,
                bounds ? bounds(e, cloud) : bounding_sphere(cloud, registry.try_get<PointFlags>(e)));
    });
    registry.view<const GaussianCloud>().each([&](ecs::Entity e, const GaussianCloud& cloud) {
        if (cloud.size() > 0)
            add(e, cloud.origin,
                gaussian_bounds ? gaussian_bounds(e, cloud)
                                : gaussian_bounding_sphere(cloud, registry.try_get<PointFlags>(e)));
    });
    SceneSphere out;
    if (balls.empty()) return out;
    out.center = 0.5 * (lo + hi);
    out.radius = 0.0;
    for (const auto& [c, r] : balls) out.radius = std::max(out.radius, glm::length(c - out.center) + r);
    out.radius = std::max(out.radius, 1e-9);
    return out;
}

}  // namespace sffd::render
