// Test geometry for point selection, with the expected answers worked out here independently of the
// engine's camera code: a pinhole model of a camera looking straight down -z.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "runtime/scene/components.h"
#include "systems/picking/screen_view.h"

namespace sffd::point_select::test {

inline constexpr int kWidth = 640, kHeight = 480;

// Camera at (cx, cy, h) looking down -z, up +y, 90° vertical field of view.
inline picking::ScreenView top_view(double cx, double cy, double h) {
    Camera c;
    c.eye = {cx, cy, h};
    c.target = {cx, cy, 0.0};
    c.up = {0.0, 1.0, 0.0};
    c.fov_y_degrees = 90.0f;
    c.near_plane = 0.01f;
    c.far_plane = 100.0f;
    return picking::make_screen_view(c, {kWidth, kHeight});
}

// Where that camera shows the world point p: with tan 45° = 1, a unit offset at depth d is H/2 / d pixels.
inline glm::dvec2 pinhole(double cx, double cy, double h, const glm::dvec3& p) {
    const double d = h - p.z;
    const double f = kHeight * 0.5 / d;
    return {kWidth * 0.5 + (p.x - cx) * f, kHeight * 0.5 - (p.y - cy) * f};
}

// A flat grid of splats on z = 0: (x0 + i s, y0 + j s), index j * nx + i; discs of radius r facing +z.
inline SplatCloud grid_cloud(int nx, int ny, double x0, double y0, double s, float r) {
    SplatCloud c;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
            c.positions.emplace_back(float(x0 + i * s), float(y0 + j * s), 0.0f);
            c.normals.emplace_back(0.0f, 0.0f, 1.0f);
            c.axis_u.emplace_back(r, 0.0f, 0.0f);
            c.axis_v.emplace_back(0.0f, r, 0.0f);
            c.colors.push_back(0xff808080u);
        }
    return c;
}

// The same points as Gaussians (isotropic σ, opaque, SH degree 0 grey).
inline GaussianCloud gaussians_of(const SplatCloud& s, float sigma) {
    GaussianCloud g;
    g.positions = s.positions;
    for (std::size_t i = 0; i < s.size(); ++i) {
        g.scales.emplace_back(sigma);
        g.rotations.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
        g.opacities.push_back(1.0f);
        g.sh.insert(g.sh.end(), {0.0f, 0.0f, 0.0f});
    }
    return g;
}

// n splats on the unit sphere (Fibonacci spiral), discs of radius r tangent to it.
inline SplatCloud sphere_cloud(int n, float r) {
    SplatCloud c;
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (int k = 0; k < n; ++k) {
        const double z = 1.0 - 2.0 * (k + 0.5) / n, rho = std::sqrt(1.0 - z * z), phi = golden * k;
        const glm::vec3 p(float(rho * std::cos(phi)), float(rho * std::sin(phi)), float(z));
        const glm::vec3 t =
            glm::normalize(glm::cross(std::abs(p.z) < 0.9f ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0), p));
        c.positions.push_back(p);
        c.normals.push_back(p);
        c.axis_u.push_back(t * r);
        c.axis_v.push_back(glm::cross(p, t) * r);
    }
    return c;
}

}  // namespace sffd::point_select::test
