// Known geometry for the picking tests: disc grids on planes and box lattices, built by hand so every
// expected hit can be worked out on paper.
#pragma once

#include <cstdint>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"

namespace sffd::picking::test {

// n x n circular splats of radius `radius` on the plane z = z, centres at (x0 + i h, y0 + j h), facing +z.
// Splat index = j * n + i.
inline SplatCloud disc_grid(int n, double h, double radius, double z, glm::dvec2 xy0 = {0.0, 0.0},
                            glm::dvec3 origin = glm::dvec3(0.0)) {
    SplatCloud c;
    c.origin = origin;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            c.positions.emplace_back(glm::dvec3(xy0.x + i * h, xy0.y + j * h, z) - origin);
            c.normals.emplace_back(0.0f, 0.0f, 1.0f);
            c.axis_u.emplace_back(float(radius), 0.0f, 0.0f);
            c.axis_v.emplace_back(0.0f, float(radius), 0.0f);
            c.colors.push_back(0xffffffffu);
        }
    return c;
}

// Axis-aligned box lattice [lo, hi] with the given divisions, current = rest.
inline Lattice box_lattice(glm::dvec3 lo, glm::dvec3 hi, glm::ivec3 divisions,
                           LatticeBasis basis = LatticeBasis::bernstein) {
    Lattice l;
    l.origin = lo;
    l.axes = {glm::dvec3(hi.x - lo.x, 0, 0), glm::dvec3(0, hi.y - lo.y, 0), glm::dvec3(0, 0, hi.z - lo.z)};
    l.divisions = divisions;
    l.basis = basis;
    for (int i = 0; i <= divisions.x; ++i)
        for (int j = 0; j <= divisions.y; ++j)
            for (int k = 0; k <= divisions.z; ++k)
                l.rest.push_back(lo + double(i) / divisions.x * l.axes[0] +
                                 double(j) / divisions.y * l.axes[1] + double(k) / divisions.z * l.axes[2]);
    l.current = l.rest;
    return l;
}

// A camera at (cx, cy, height) looking down -z with a 90° vertical field of view (see expected_pixel()).
inline Camera top_camera(double cx, double cy, double height) {
    Camera cam;
    cam.eye = {cx, cy, height};
    cam.target = {cx, cy, 0.0};
    cam.up = {0.0, 1.0, 0.0};
    cam.fov_y_degrees = 90.0f;
    cam.near_plane = 0.01f;
    cam.far_plane = 1000.0f;
    return cam;
}

// Independent pinhole model of top_camera on a square W x W viewport: tan(45°) = 1, so the
// normalised offset is (x - cx) / depth; pixel y grows downwards.
inline glm::dvec2 expected_pixel(const Camera& cam, int w, glm::dvec3 p) {
    const double depth = cam.eye.z - p.z;
    return {(1.0 + (p.x - cam.eye.x) / depth) * 0.5 * w, (1.0 - (p.y - cam.eye.y) / depth) * 0.5 * w};
}

}  // namespace sffd::picking::test
