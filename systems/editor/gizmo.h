// Gizmo math for the stretch (move) and twist tools: mouse drags in pixels -> displacement vectors and
// rotation angles in world space. Pure functions (tests call them directly); the editor's input system
// applies the result to the lattice through lattice_tools.h, always from the snapshot taken when the
// drag started, so a long drag never drifts.
#pragma once

#include <glm/glm.hpp>

#include "runtime/scene/components.h"
#include "systems/editor/camera_controller.h"

namespace sffd::editor {

// Axis constraint of the move tool and axis of the twist tool. `view` is the viewing direction;
// `view_plane` (move only) is "free in the plane facing the camera through the pivot".
enum class AxisMode : std::uint8_t { view_plane, x, y, z, view, custom };
const char* axis_mode_name(AxisMode mode);

// Unit axis for a mode (view_plane and view both give the viewing direction, from eye to target).
glm::dvec3 axis_direction(AxisMode mode, const Camera& camera, const glm::dvec3& custom_axis);

// Where the pixel's ray meets the plane through `pivot` facing the camera; nullopt-free: a ray parallel
// to the plane (impossible for the camera-facing plane) returns the pivot.
glm::dvec3 point_on_view_plane(const Camera& camera, const Viewport& viewport, const glm::dvec3& pivot,
                               glm::dvec2 pixel);

// Move in the view plane: the world displacement that keeps the grabbed point under the cursor.
glm::dvec3 drag_in_view_plane(const Camera& camera, const Viewport& viewport, const glm::dvec3& pivot,
                              glm::dvec2 from, glm::dvec2 to);

// Move along an axis through `pivot`: the displacement along `axis` between the axis points closest to
// the two pixel rays. An axis seen end-on (parallel to the ray) gives no motion.
glm::dvec3 drag_along_axis(const Camera& camera, const Viewport& viewport, const glm::dvec3& pivot,
                           const glm::dvec3& axis, glm::dvec2 from, glm::dvec2 to);

// Twist by dragging around the pivot's image on screen: the signed angle (radians, in (-pi, pi]) swept
// by the cursor from `from` to `to` about the pivot, positive when the rotation about `axis` (right-hand
// rule) looks the same way on screen. Callers accumulate per-frame increments, so several turns add up.
// Cursor on the pivot: 0.
double drag_angle(const Camera& camera, const Viewport& viewport, const glm::dvec3& pivot,
                  const glm::dvec3& axis, glm::dvec2 from, glm::dvec2 to);

}  // namespace sffd::editor
