// ScreenView: the camera as the picking system needs it — view and projection matrices plus the viewport
// size in pixels — and the two conversions between the screen and the world: the ray through a screen
// point and the projection of a world point. Plain data and pure functions (no registry, no Embree).
//
// Screen coordinates are window pixels: origin at the top-left corner, x right, y DOWN (mouse and image
// row order), continuous, so the centre of pixel (X, Y) is (X + 0.5, Y + 0.5). The projection is
// OpenGL's (glm::lookAt + glm::perspective, clip z in [-w, w]), the same the splat renderer uses.
#pragma once

#include <optional>

#include <glm/glm.hpp>

#include "runtime/scene/components.h"

namespace sffd::picking {

struct Ray {
    glm::dvec3 origin{0.0};
    glm::dvec3 direction{0.0, 0.0, -1.0};  // unit length when made by ray_through()
};

struct ScreenView {
    glm::dmat4 view{1.0};
    glm::dmat4 projection{1.0};
    glm::ivec2 size{1, 1};  // viewport in pixels
    glm::dvec3 eye{0.0};    // camera position in the world (the origin of every ray)
};

// The look-at camera seen through a viewport of `size` pixels (aspect = width / height).
ScreenView make_screen_view(const Camera& camera, glm::ivec2 size);

// The ray from the eye through the screen point (continuous pixel coordinates, see above).
Ray ray_through(const ScreenView& view, glm::dvec2 screen);

// Where a world point lands on screen: (x, y) in pixels and the eye-space depth (distance along the
// view direction, > 0 in front of the camera). nullopt for points at or behind the eye plane.
struct Projected {
    glm::dvec2 screen{0.0};
    double depth = 0.0;
};
std::optional<Projected> project(const ScreenView& view, const glm::dvec3& world);

}  // namespace sffd::picking
