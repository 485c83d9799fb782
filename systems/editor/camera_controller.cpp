#include "systems/editor/camera_controller.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>

namespace sffd::editor {

void orbit(Camera& camera, glm::dvec2 pixel_delta, const OrbitSettings& settings) {
    const glm::dvec3 up = glm::normalize(camera.up);
    glm::dvec3 offset = camera.eye - camera.target;
    const double distance = glm::length(offset);
    if (distance <= 0.0) return;
    glm::dvec3 dir = offset / distance;
    // Yaw about the up axis.
    const double yaw = -pixel_delta.x * settings.radians_per_pixel;
    dir = std::cos(yaw) * dir + std::sin(yaw) * glm::cross(up, dir) +
          (1.0 - std::cos(yaw)) * glm::dot(up, dir) * up;
    // Pitch: change the elevation angle, clamped away from the poles.
    const double elevation = std::asin(std::clamp(glm::dot(dir, up), -1.0, 1.0));
    const double limit = glm::radians(89.0);
    const double new_elevation =
        std::clamp(elevation + pixel_delta.y * settings.radians_per_pixel, -limit, limit);
    glm::dvec3 horizontal = dir - glm::dot(dir, up) * up;
    if (glm::length(horizontal) < 1e-12) horizontal = glm::dvec3(up.y, up.z, up.x);  // looking along up
    horizontal = glm::normalize(horizontal);
    dir = std::cos(new_elevation) * horizontal + std::sin(new_elevation) * up;
    camera.eye = camera.target + dir * distance;
}

void pan(Camera& camera, const Viewport& viewport, glm::dvec2 pixel_delta) {
    const glm::dvec3 offset = camera.eye - camera.target;
    const double distance = glm::length(offset);
    const glm::dvec3 forward = -offset / distance;
    const glm::dvec3 right = glm::normalize(glm::cross(forward, camera.up));
    const glm::dvec3 up = glm::cross(right, forward);
    // World size of one pixel at the target's depth.
    const double pixel =
        2.0 * distance * std::tan(glm::radians(double(camera.fov_y_degrees)) * 0.5) / viewport.height;
    // Dragging right moves the scene right, i.e. the camera left; pixel y goes down.
    const glm::dvec3 move = (-pixel_delta.x * right + pixel_delta.y * up) * pixel;
    camera.eye += move;
    camera.target += move;
}

void zoom(Camera& camera, double notches, const OrbitSettings& settings) {
    const glm::dvec3 offset = camera.eye - camera.target;
    const double distance = glm::length(offset);
    if (distance <= 0.0) return;
    const double next =
        std::max(distance * std::exp(-notches * settings.zoom_per_notch), settings.min_distance);
    camera.eye = camera.target + offset * (next / distance);
}

void frame_points(Camera& camera, const Viewport& viewport, std::span<const glm::dvec3> points,
                  double margin) {
    if (points.empty()) return;
    glm::dvec3 lo = points[0], hi = points[0];
    for (const auto& p : points) lo = glm::min(lo, p), hi = glm::max(hi, p);
    const glm::dvec3 centre = 0.5 * (lo + hi);
    double radius = 0.0;
    for (const auto& p : points) radius = std::max(radius, glm::length(p - centre));
    radius = std::max(radius, 1e-3) * margin;
    // A sphere of radius r fits in a cone of half-angle a when the distance is r / sin(a).
    const double half_y = glm::radians(double(camera.fov_y_degrees)) * 0.5;
    const double half_x = std::atan(std::tan(half_y) * viewport.aspect());
    const double distance = radius / std::sin(std::min(half_x, half_y));
    glm::dvec3 dir = camera.eye - camera.target;
    dir = glm::length(dir) > 0.0 ? glm::normalize(dir) : glm::dvec3(0, 0, 1);
    camera.target = centre;
    camera.eye = centre + dir * distance;
    // Keep the whole sphere between the clip planes.
    camera.far_plane = std::max(camera.far_plane, float(distance + 2.0 * radius));
}

}  // namespace sffd::editor
