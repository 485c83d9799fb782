#include "systems/splat_render/camera_math.h"

#include <algorithm>
#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

namespace sffd::render {

glm::dmat4 view_matrix(const Camera& camera) { return glm::lookAt(camera.eye, camera.target, camera.up); }

glm::dmat4 projection_matrix(const Camera& camera, double aspect) {
    return glm::perspective(glm::radians(double(camera.fov_y_degrees)), aspect, double(camera.near_plane),
                            double(camera.far_plane));
}

glm::dmat4 model_matrix(const Transform* transform, const glm::dvec3& origin) {
    glm::dmat4 m(1.0);
    if (transform) {
        m = glm::translate(m, transform->translation);
        m = m * glm::mat4_cast(transform->rotation);
        m = glm::scale(m, transform->scale);
    }
    return glm::translate(m, origin);
}

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

double view_depth(const Camera& camera, const glm::dvec3& world) {
    return glm::dot(world - camera.eye, glm::normalize(camera.target - camera.eye));
}

}  // namespace sffd::render
