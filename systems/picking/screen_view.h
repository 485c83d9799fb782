// ScreenView: the camera as the picking system sees it, the scene's Camera and the viewport in pixels, and
// the two conversions between the screen and the world (runtime/scene/camera.h, the one camera maths):
// the ray through a screen point and the projection of a world point.
//
// Screen coordinates are window pixels: origin at the top-left corner, x right, y DOWN (mouse and image
// row order), continuous, so the centre of pixel (X, Y) is (X + 0.5, Y + 0.5). The projection is
// OpenGL's (glm::lookAt + glm::perspective), the same the splat renderer uses.
#pragma once

#include <optional>

#include <glm/glm.hpp>

#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"

namespace sffd::picking {

struct ScreenView {
    Camera camera;
    Viewport viewport{1, 1};
};

// The camera seen through a viewport of `size` pixels (at least 1 x 1; aspect = width / height).
inline ScreenView make_screen_view(const Camera& camera, glm::ivec2 size) {
    const glm::ivec2 s = glm::max(size, glm::ivec2(1));
    return {camera, Viewport{s.x, s.y}};
}

// The ray from the eye through the screen point (continuous pixel coordinates, see above).
inline Ray ray_through(const ScreenView& view, glm::dvec2 screen) {
    return pixel_ray(view.camera, view.viewport, screen);
}

// Where a world point lands on screen: (x, y) in pixels and the eye-space depth (distance along the view
// direction, > 0 in front of the camera). nullopt for points at or behind the eye plane.
inline std::optional<Projected> project(const ScreenView& view, const glm::dvec3& world) {
    return sffd::project(view.camera, view.viewport, world);
}

}  // namespace sffd::picking
