// runtime/scene/camera.h: the one camera maths (render, picking, editor and assets use it), checked against
// independent constructions: a hand-built pinhole camera and a model matrix assembled column by column.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <glm/gtc/quaternion.hpp>

#include "runtime/scene/camera.h"

namespace sffd {
namespace {

void expect_near(const glm::dvec3& a, const glm::dvec3& b, double tol) {
    EXPECT_NEAR(a.x, b.x, tol);
    EXPECT_NEAR(a.y, b.y, tol);
    EXPECT_NEAR(a.z, b.z, tol);
}

// Camera on +z looking at the origin, 90 degrees vertical field of view, 200 x 100 pixels: at depth d the
// half-height is d (tan 45 = 1) over 50 pixels and the half-width aspect * d = 2 d over 100 pixels, so a
// point lands at pixel (100 + 100 * x / (2 d), 50 - 50 * y / d).
TEST(Camera, PinholeProjectionAndRaysAgree) {
    Camera c;
    c.eye = {0.0, 0.0, 5.0};
    c.target = {0.0, 0.0, 0.0};
    c.fov_y_degrees = 90.0f;
    c.near_plane = 0.1f;
    c.far_plane = 100.0f;
    const Viewport vp{200, 100};
    const glm::dvec3 p(1.0, 0.5, 1.0);  // depth 4
    const auto q = project(c, vp, p);
    ASSERT_TRUE(q);
    EXPECT_NEAR(q->depth, 4.0, 1e-12);
    EXPECT_NEAR(q->screen.x, 100.0 + 100.0 * 1.0 / 8.0, 1e-9);
    EXPECT_NEAR(q->screen.y, 50.0 - 50.0 * 0.5 / 4.0, 1e-9);
    EXPECT_NEAR(view_depth(c, p), 4.0, 1e-12);
    const glm::dvec3 px = project_to_pixel(c, vp, p);
    EXPECT_NEAR(px.x, q->screen.x, 1e-12);
    EXPECT_NEAR(px.z, q->ndc_z, 1e-12);
    // The ray through that pixel passes through p.
    const Ray r = pixel_ray(c, vp, q->screen);
    expect_near(r.origin, c.eye, 0.0);
    expect_near(r.direction, glm::normalize(p - c.eye), 1e-12);
    // Behind the eye: no projection; project_to_pixel says "beyond the far plane".
    EXPECT_FALSE(project(c, vp, {0.0, 0.0, 6.0}));
    EXPECT_EQ(project_to_pixel(c, vp, {0.0, 0.0, 6.0}).z, 2.0);
}

// translate * rotate * scale * translate(origin), against columns built by hand.
TEST(Camera, ModelMatrixIsTranslationRotationScaleThenOrigin) {
    Transform t;
    t.translation = {1.0, -2.0, 3.0};
    t.rotation = glm::angleAxis(std::numbers::pi / 2.0, glm::dvec3(0.0, 0.0, 1.0));  // x -> y
    t.scale = {2.0, 3.0, 4.0};
    const glm::dvec3 origin(0.5, 0.25, -1.0);
    const glm::dmat4 m = model_matrix(&t, origin);
    // A point p relative to the origin: T + R(S (origin + p)); R maps (x, y, z) to (-y, x, z).
    const glm::dvec3 p(1.0, 1.0, 1.0), s = t.scale * (origin + p);
    expect_near(glm::dvec3(m * glm::dvec4(p, 1.0)), t.translation + glm::dvec3(-s.y, s.x, s.z), 1e-12);
    EXPECT_EQ(model_matrix(nullptr), glm::dmat4(1.0));
    expect_near(glm::dvec3(model_matrix(nullptr, origin)[3]), origin, 0.0);
}

}  // namespace
}  // namespace sffd
