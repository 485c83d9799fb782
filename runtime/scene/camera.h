// Camera math, written once for every system (render, picking, editor, assets): the view and projection
// matrices of a scene Camera, the model matrix of a Transform, and the two conversions between window
// pixels and the world (the ray through a pixel, the projection of a world point). Plain data and pure
// functions, in double precision (the renderer composes view * model in double and uploads the product as
// float, so scenes far from the origin keep float precision).
//
// Conventions: the view is glm::lookAt(eye, target, up); the projection glm::perspective(fov_y, aspect,
// near, far), OpenGL clip space (z in [-w, w]). Pixel coordinates are continuous window pixels with (0, 0)
// at the top-left corner, x right, y DOWN (mouse and image row order): pixel (X, Y)'s centre is
// (X + 0.5, Y + 0.5).
#pragma once

#include <optional>

#include <glm/glm.hpp>

#include "runtime/scene/components.h"

namespace sffd {

struct Viewport {
    int width = 1280;
    int height = 720;
    double aspect() const { return height > 0 ? double(width) / double(height) : 1.0; }
};

struct Ray {
    glm::dvec3 origin{0.0};
    glm::dvec3 direction{0.0, 0.0, -1.0};  // unit length when made by pixel_ray()
};

glm::dmat4 view_matrix(const Camera& camera);
// Symmetric frustum, vertical field of view, OpenGL clip convention.
glm::dmat4 projection_matrix(const Camera& camera, double aspect);
inline glm::dmat4 projection_matrix(const Camera& camera, const Viewport& viewport) {
    return projection_matrix(camera, viewport.aspect());
}

// Transform * translate(origin): the model matrix of an entity (identity without a Transform); `origin` is
// a point cloud's SplatCloud::origin (its positions are relative to it).
glm::dmat4 model_matrix(const Transform* transform, const glm::dvec3& origin = glm::dvec3(0.0));

// The ray from the eye through a pixel (continuous coordinates, see above).
Ray pixel_ray(const Camera& camera, const Viewport& viewport, glm::dvec2 pixel);

// Where a world point lands: pixel coordinates, the depth along the view axis (> 0 in front of the eye)
// and the NDC depth. nullopt for points at or behind the eye plane.
struct Projected {
    glm::dvec2 screen{0.0};
    double depth = 0.0;
    double ndc_z = 0.0;
};
std::optional<Projected> project(const Camera& camera, const Viewport& viewport, const glm::dvec3& world);

// project() as (x, y, NDC z); a point at or behind the eye plane gives (0, 0, 2) (beyond the far plane).
glm::dvec3 project_to_pixel(const Camera& camera, const Viewport& viewport, const glm::dvec3& world);

// Depth along the camera's view axis (positive in front) of a world point.
double view_depth(const Camera& camera, const glm::dvec3& world);

}  // namespace sffd
