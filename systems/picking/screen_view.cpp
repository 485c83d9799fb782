#include "systems/picking/screen_view.h"

#include <algorithm>

#include <glm/gtc/matrix_transform.hpp>

namespace sffd::picking {

ScreenView make_screen_view(const Camera& camera, glm::ivec2 size) {
    ScreenView v;
    v.size = glm::max(size, glm::ivec2(1));
    v.eye = camera.eye;
    v.view = glm::lookAt(camera.eye, camera.target, camera.up);
    const double aspect = double(v.size.x) / double(v.size.y);
    v.projection = glm::perspective(glm::radians(double(camera.fov_y_degrees)), aspect,
                                    double(camera.near_plane), double(camera.far_plane));
    return v;
}

Ray ray_through(const ScreenView& view, glm::dvec2 screen) {
    const glm::dvec2 ndc{2.0 * screen.x / view.size.x - 1.0, 1.0 - 2.0 * screen.y / view.size.y};
    const glm::dmat4 inv = glm::inverse(view.projection * view.view);
    glm::dvec4 near_h = inv * glm::dvec4(ndc, -1.0, 1.0);
    glm::dvec4 far_h = inv * glm::dvec4(ndc, 1.0, 1.0);
    const glm::dvec3 near_p = glm::dvec3(near_h) / near_h.w;
    const glm::dvec3 far_p = glm::dvec3(far_h) / far_h.w;
    // Rays start at the eye (not the near plane) so distances are measured from the camera.
    const glm::dvec3 eye = glm::dvec3(glm::inverse(view.view)[3]);
    return {eye, glm::normalize(far_p - near_p)};
}

std::optional<Projected> project(const ScreenView& view, const glm::dvec3& world) {
    const glm::dvec4 eye_space = view.view * glm::dvec4(world, 1.0);
    const double depth = -eye_space.z;
    if (!(depth > 0.0)) return std::nullopt;
    const glm::dvec4 clip = view.projection * eye_space;
    const glm::dvec2 ndc = glm::dvec2(clip) / clip.w;
    return Projected{{(ndc.x + 1.0) * 0.5 * view.size.x, (1.0 - ndc.y) * 0.5 * view.size.y}, depth};
}

}  // namespace sffd::picking
