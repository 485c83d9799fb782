#include "runtime/scene/camera.h"

#include <cmath>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

namespace sffd {

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

Ray pixel_ray(const Camera& camera, const Viewport& viewport, glm::dvec2 pixel) {
    // NDC of the pixel (y flipped: pixel rows go down, NDC y goes up), then the view basis of lookAt.
    const double nx = 2.0 * pixel.x / viewport.width - 1.0;
    const double ny = 1.0 - 2.0 * pixel.y / viewport.height;
    const double tan_half = std::tan(glm::radians(double(camera.fov_y_degrees)) * 0.5);
    const glm::dvec3 forward = glm::normalize(camera.target - camera.eye);
    const glm::dvec3 right = glm::normalize(glm::cross(forward, camera.up));
    const glm::dvec3 up = glm::cross(right, forward);
    const glm::dvec3 dir = forward + right * (nx * tan_half * viewport.aspect()) + up * (ny * tan_half);
    return {camera.eye, glm::normalize(dir)};
}

std::optional<Projected> project(const Camera& camera, const Viewport& viewport, const glm::dvec3& world) {
    const glm::dvec4 eye_space = view_matrix(camera) * glm::dvec4(world, 1.0);
    const double depth = -eye_space.z;
    if (!(depth > 0.0)) return std::nullopt;
    const glm::dvec4 clip = projection_matrix(camera, viewport) * eye_space;
    const glm::dvec3 ndc = glm::dvec3(clip) / clip.w;
    return Projected{
        {(ndc.x + 1.0) * 0.5 * viewport.width, (1.0 - ndc.y) * 0.5 * viewport.height}, depth, ndc.z};
}

glm::dvec3 project_to_pixel(const Camera& camera, const Viewport& viewport, const glm::dvec3& world) {
    const std::optional<Projected> p = project(camera, viewport, world);
    return p ? glm::dvec3(p->screen, p->ndc_z) : glm::dvec3(0.0, 0.0, 2.0);
}

double view_depth(const Camera& camera, const glm::dvec3& world) {
    return glm::dot(world - camera.eye, glm::normalize(camera.target - camera.eye));
}

}  // namespace sffd
