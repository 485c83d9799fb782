// Orbit / pan / zoom camera control and "frame the selection", as pure functions on the scene's
// Camera component (eye, target, up, vertical fov). The window turns mouse gestures into these calls;
// tests call them directly. Viewport, pixel rays and projections: runtime/scene/camera.h (pixel
// coordinates with (0,0) at the top left of the viewport, y down, GLFW's cursor convention).
#pragma once

#include <span>

#include <glm/glm.hpp>

#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"

namespace sffd::editor {

struct OrbitSettings {
    double radians_per_pixel = 0.008;
    double zoom_per_notch = 0.12;  // each scroll notch scales the distance by exp(-zoom_per_notch)
    double min_distance = 1e-3;
};

// Rotates the eye about the target: yaw about the camera's up vector, pitch about its right vector.
// Pitch stops short of the poles so the view never flips.
void orbit(Camera& camera, glm::dvec2 pixel_delta, const OrbitSettings& settings = {});
// Moves eye and target together so the point under the cursor at the target's depth follows the cursor.
void pan(Camera& camera, const Viewport& viewport, glm::dvec2 pixel_delta);
// Moves the eye towards (notches > 0) or away from the target; never reaches it.
void zoom(Camera& camera, double notches, const OrbitSettings& settings = {});

// Re-targets the camera at the bounding sphere of `points` and sets the distance so the whole sphere
// is inside the view (both fov directions) with `margin` (1.1 = 10% room). The viewing direction is
// kept. No points: the camera is unchanged.
void frame_points(Camera& camera, const Viewport& viewport, std::span<const glm::dvec3> points,
                  double margin = 1.1);

}  // namespace sffd::editor
