#include "systems/editor/camera_controller.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>

using namespace sffd;
using namespace sffd::editor;

namespace {
Camera test_camera() {
    Camera c;
    c.eye = {1.0, 2.0, 5.0};
    c.target = {0.2, -0.1, 0.3};
    c.fov_y_degrees = 50.0f;
    return c;
}
void expect_near(glm::dvec3 a, glm::dvec3 b, double tol) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}
}  // namespace

TEST(CameraController, PixelRayAndProjectionAgree) {
    const Camera c = test_camera();
    const Viewport vp{800, 600};
    const glm::dvec3 p(0.4, 0.3, -0.2);
    const glm::dvec3 px = project_to_pixel(c, vp, p);
    const Ray ray = pixel_ray(c, vp, glm::dvec2(px));
    const glm::dvec3 to_p = glm::normalize(p - c.eye);
    expect_near(ray.direction, to_p, 1e-9);
    // Centre pixel looks at the target; top-left pixel is up-left of it.
    expect_near(pixel_ray(c, vp, {400, 300}).direction, glm::normalize(c.target - c.eye), 1e-12);
    const glm::dvec3 tl = project_to_pixel(c, vp, c.eye + pixel_ray(c, vp, {0, 0}).direction);
    EXPECT_NEAR(tl.x, 0.0, 1e-6);
    EXPECT_NEAR(tl.y, 0.0, 1e-6);
}

TEST(CameraController, OrbitKeepsTargetAndDistance) {
    Camera c = test_camera();
    const double d0 = glm::length(c.eye - c.target);
    const glm::dvec3 target = c.target;
    orbit(c, {37.0, -12.0});
    EXPECT_NEAR(glm::length(c.eye - c.target), d0, 1e-12);
    expect_near(c.target, target, 0.0);
    // Pure yaw of angle a about +y: the horizontal offset rotates by a, height unchanged.
    Camera y = test_camera();
    const glm::dvec3 before = y.eye - y.target;
    OrbitSettings s;
    orbit(y, {-100.0, 0.0}, s);  // yaw = +0.8 rad
    const glm::dvec3 after = y.eye - y.target;
    EXPECT_NEAR(after.y, before.y, 1e-12);
    const double angle = std::atan2(after.x, after.z) - std::atan2(before.x, before.z);
    EXPECT_NEAR(angle, 100.0 * s.radians_per_pixel, 1e-12);
}

TEST(CameraController, OrbitStopsBeforeThePole) {
    Camera c = test_camera();
    orbit(c, {0.0, 1e5});
    const glm::dvec3 dir = glm::normalize(c.eye - c.target);
    EXPECT_LT(std::abs(dir.y), std::sin(glm::radians(89.0)) + 1e-12);
    EXPECT_GT(std::abs(dir.y), 0.99);
}

TEST(CameraController, PanKeepsTheTargetDepthPointUnderTheCursor) {
    Camera c = test_camera();
    const Viewport vp{640, 480};
    const glm::dvec3 world = c.target;  // a point at the target's depth
    const glm::dvec3 before = project_to_pixel(c, vp, world);
    pan(c, vp, {25.0, -40.0});
    const glm::dvec3 after = project_to_pixel(c, vp, world);
    EXPECT_NEAR(after.x - before.x, 25.0, 1e-6);
    EXPECT_NEAR(after.y - before.y, -40.0, 1e-6);
}

TEST(CameraController, ZoomScalesTheDistanceAndNeverPassesTheTarget) {
    Camera c = test_camera();
    OrbitSettings s;
    const double d0 = glm::length(c.eye - c.target);
    zoom(c, 2.0, s);
    EXPECT_NEAR(glm::length(c.eye - c.target), d0 * std::exp(-2.0 * s.zoom_per_notch), 1e-12);
    zoom(c, 1e4, s);
    EXPECT_NEAR(glm::length(c.eye - c.target), s.min_distance, 1e-15);
    EXPECT_GT(glm::dot(c.eye - c.target, glm::dvec3(1, 2, 5) - glm::dvec3(0.2, -0.1, 0.3)), 0.0);
}

TEST(CameraController, FramedPointsAreAllInsideTheViewAndFillIt) {
    Camera c = test_camera();
    const Viewport vp{1280, 720};
    std::vector<glm::dvec3> pts;
    for (int i = 0; i < 200; ++i) {
        const double a = i * 0.37, b = i * 0.11;
        pts.push_back(
            glm::dvec3(10.0 + 3.0 * std::cos(a) * std::sin(b), -4.0 + 0.5 * std::sin(a), 2.0 * std::cos(b)));
    }
    const glm::dvec3 dir0 = glm::normalize(c.eye - c.target);
    frame_points(c, vp, pts, 1.1);
    expect_near(glm::normalize(c.eye - c.target), dir0, 1e-12);
    double min_x = 1e9, max_x = -1e9, min_y = 1e9, max_y = -1e9;
    for (const auto& p : pts) {
        const glm::dvec3 px = project_to_pixel(c, vp, p);
        ASSERT_GE(px.x, 0.0);
        ASSERT_LE(px.x, vp.width);
        ASSERT_GE(px.y, 0.0);
        ASSERT_LE(px.y, vp.height);
        ASSERT_LT(px.z, 1.0);
        min_x = std::min(min_x, px.x), max_x = std::max(max_x, px.x);
        min_y = std::min(min_y, px.y), max_y = std::max(max_y, px.y);
    }
    // Not absurdly far away: the cloud spans a good part of the shorter screen side.
    EXPECT_GT(std::max(max_x - min_x, (max_y - min_y) * vp.aspect()), 0.3 * vp.height);
}
