#include "systems/editor/gizmo.h"

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

using namespace sffd;
using namespace sffd::editor;

namespace {
Camera oblique_camera() {
    Camera c;
    c.eye = {2.0, 1.5, 4.0};
    c.target = {0.0, 0.2, 0.0};
    return c;
}
Camera front_camera() {  // looking down -z from +z
    Camera c;
    c.eye = {0.0, 0.0, 5.0};
    c.target = {0.0, 0.0, 0.0};
    return c;
}
glm::dvec2 px(const Camera& c, const Viewport& vp, glm::dvec3 p) {
    return glm::dvec2(project_to_pixel(c, vp, p));
}
}  // namespace

TEST(Gizmo, ViewPlaneDragKeepsTheGrabbedPointUnderTheCursor) {
    const Camera c = oblique_camera();
    const Viewport vp{1024, 768};
    const glm::dvec3 pivot(0.3, 0.4, -0.2);
    const glm::dvec2 from = px(c, vp, pivot), to = from + glm::dvec2(80.0, -33.0);
    const glm::dvec3 d = drag_in_view_plane(c, vp, pivot, from, to);
    const glm::dvec2 moved = px(c, vp, pivot + d);
    EXPECT_NEAR(moved.x, to.x, 1e-6);
    EXPECT_NEAR(moved.y, to.y, 1e-6);
    // The displacement lies in the plane facing the camera.
    EXPECT_NEAR(glm::dot(d, glm::normalize(c.target - c.eye)), 0.0, 1e-12);
}

TEST(Gizmo, AxisDragMovesAlongTheAxisOnly) {
    const Camera c = oblique_camera();
    const Viewport vp{1024, 768};
    const glm::dvec3 pivot(0.1, 0.0, 0.0);
    const glm::dvec3 target_point = pivot + glm::dvec3(0.0, 0.75, 0.0);
    // Cursor from the pivot's image to the image of a point 0.75 up the y axis, plus a sideways wobble
    // perpendicular to the axis on screen: the result is still (0, 0.75, 0) to first order.
    const glm::dvec3 d = drag_along_axis(c, vp, pivot, {0, 1, 0}, px(c, vp, pivot), px(c, vp, target_point));
    EXPECT_NEAR(d.x, 0.0, 1e-12);
    EXPECT_NEAR(d.y, 0.75, 1e-9);
    EXPECT_NEAR(d.z, 0.0, 1e-12);
    // Axis seen end-on: no motion.
    const Camera f = front_camera();
    const glm::dvec3 none = drag_along_axis(f, vp, {0, 0, 0}, {0, 0, 1}, {512, 384}, {600, 300});
    EXPECT_EQ(none, glm::dvec3(0.0));
}

TEST(Gizmo, DragAngleFollowsTheRightHandRuleOnScreen) {
    const Camera c = front_camera();  // +z points at the viewer
    const Viewport vp{800, 800};
    const glm::dvec3 pivot(0.0);
    const glm::dvec2 centre = px(c, vp, pivot);
    // Counter-clockwise on screen (right -> up; pixel y goes down) is +90 degrees about +z...
    const glm::dvec2 right = centre + glm::dvec2(100, 0), up = centre + glm::dvec2(0, -100);
    EXPECT_NEAR(drag_angle(c, vp, pivot, {0, 0, 1}, right, up), std::numbers::pi / 2, 1e-12);
    // ...and -90 degrees about -z.
    EXPECT_NEAR(drag_angle(c, vp, pivot, {0, 0, -1}, right, up), -std::numbers::pi / 2, 1e-12);
    // Two full turns in 16 steps accumulate to 4 pi (unbounded twist).
    double total = 0.0;
    for (int s = 0; s < 16; ++s) {
        const double a0 = s * std::numbers::pi / 4, a1 = (s + 1) * std::numbers::pi / 4;
        total += drag_angle(c, vp, pivot, {0, 0, 1}, centre + 100.0 * glm::dvec2(std::cos(a0), -std::sin(a0)),
                            centre + 100.0 * glm::dvec2(std::cos(a1), -std::sin(a1)));
    }
    EXPECT_NEAR(total, 4 * std::numbers::pi, 1e-9);
    EXPECT_EQ(drag_angle(c, vp, pivot, {0, 0, 1}, centre, up), 0.0);
}

TEST(Gizmo, AxisDirections) {
    const Camera c = oblique_camera();
    EXPECT_EQ(axis_direction(AxisMode::x, c, {}), glm::dvec3(1, 0, 0));
    EXPECT_EQ(axis_direction(AxisMode::z, c, {}), glm::dvec3(0, 0, 1));
    const glm::dvec3 view = axis_direction(AxisMode::view, c, {});
    EXPECT_NEAR(glm::length(view - glm::normalize(c.target - c.eye)), 0.0, 1e-15);
    const glm::dvec3 custom = axis_direction(AxisMode::custom, c, {0, 3, 4});
    EXPECT_NEAR(custom.y, 0.6, 1e-15);
    EXPECT_NEAR(custom.z, 0.8, 1e-15);
    EXPECT_EQ(axis_direction(AxisMode::custom, c, {0, 0, 0}), view);  // degenerate custom axis
}
