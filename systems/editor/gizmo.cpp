#include "systems/editor/gizmo.h"

#include <cmath>

namespace sffd::editor {

const char* axis_mode_name(AxisMode mode) {
    switch (mode) {
        case AxisMode::view_plane: return "view plane";
        case AxisMode::x: return "x";
        case AxisMode::y: return "y";
        case AxisMode::z: return "z";
        case AxisMode::view: return "view";
        case AxisMode::custom: return "custom";
    }
    return "?";
}

glm::dvec3 axis_direction(AxisMode mode, const Camera& camera, const glm::dvec3& custom_axis) {
    switch (mode) {
        case AxisMode::x: return {1, 0, 0};
        case AxisMode::y: return {0, 1, 0};
        case AxisMode::z: return {0, 0, 1};
        case AxisMode::custom:
            if (glm::length(custom_axis) > 0.0) return glm::normalize(custom_axis);
            [[fallthrough]];
        case AxisMode::view_plane:
        case AxisMode::view: break;
    }
    return glm::normalize(camera.target - camera.eye);
}

glm::dvec3 point_on_view_plane(const Camera& camera, const Viewport& viewport, const glm::dvec3& pivot,
                               glm::dvec2 pixel) {
    const glm::dvec3 normal = glm::normalize(camera.target - camera.eye);
    const Ray ray = pixel_ray(camera, viewport, pixel);
    const double denom = glm::dot(ray.direction, normal);
    if (std::abs(denom) < 1e-12) return pivot;
    const double t = glm::dot(pivot - ray.origin, normal) / denom;
    return ray.origin + t * ray.direction;
}

glm::dvec3 drag_in_view_plane(const Camera& camera, const Viewport& viewport, const glm::dvec3& pivot,
                              glm::dvec2 from, glm::dvec2 to) {
    return point_on_view_plane(camera, viewport, pivot, to) -
           point_on_view_plane(camera, viewport, pivot, from);
}

namespace {
// Parameter along the line pivot + s*axis of the point closest to the ray; false when they are parallel.
bool closest_on_axis(const Ray& ray, const glm::dvec3& pivot, const glm::dvec3& axis, double& s) {
    const glm::dvec3 w = pivot - ray.origin;
    const double a = glm::dot(axis, axis), b = glm::dot(axis, ray.direction),
                 c = glm::dot(ray.direction, ray.direction);
    const double d = glm::dot(axis, w), e = glm::dot(ray.direction, w);
    const double denom = a * c - b * b;
    if (std::abs(denom) < 1e-9 * a * c) return false;
    s = (b * e - c * d) / denom;
    return true;
}
}  // namespace

glm::dvec3 drag_along_axis(const Camera& camera, const Viewport& viewport, const glm::dvec3& pivot,
                           const glm::dvec3& axis, glm::dvec2 from, glm::dvec2 to) {
    const glm::dvec3 unit = glm::normalize(axis);
    double s0 = 0.0, s1 = 0.0;
    if (!closest_on_axis(pixel_ray(camera, viewport, from), pivot, unit, s0) ||
        !closest_on_axis(pixel_ray(camera, viewport, to), pivot, unit, s1))
        return glm::dvec3(0.0);
    return (s1 - s0) * unit;
}

double drag_angle(const Camera& camera, const Viewport& viewport, const glm::dvec3& pivot,
                  const glm::dvec3& axis, glm::dvec2 from, glm::dvec2 to) {
    const glm::dvec3 centre = project_to_pixel(camera, viewport, pivot);
    const glm::dvec2 a = from - glm::dvec2(centre), b = to - glm::dvec2(centre);
    if (glm::length(a) < 1e-9 || glm::length(b) < 1e-9) return 0.0;
    // Pixel y points down, so a positive cross product here is a clockwise sweep as seen on screen.
    const double clockwise = std::atan2(a.x * b.y - a.y * b.x, glm::dot(a, b));
    // Seen from the eye, a right-handed rotation about an axis pointing at the viewer is counter-clockwise.
    const glm::dvec3 to_viewer = glm::normalize(camera.eye - pivot);
    const double facing = glm::dot(glm::normalize(axis), to_viewer);
    return facing >= 0.0 ? -clockwise : clockwise;
}

}  // namespace sffd::editor
