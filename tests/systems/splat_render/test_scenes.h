// Test clouds with known geometry (independent of the content engineer's built-in scenes).
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>

#include <glm/glm.hpp>

#include "runtime/scene/components.h"

namespace sffd::render::test {

// Fibonacci sphere of n splats (the paper's sphere has 59,650), radius `radius`, circular splats of
// radius k * sqrt(4 pi / n) * radius (k = 0.8: discs overlap about twice). uv = (longitude / 2pi,
// latitude mapped to [0,1] from south to north pole). Colour white unless `color` is given (RGBA8 sRGB).
inline SplatCloud fibonacci_sphere(std::size_t n, double radius = 1.0, double k = 0.8,
                                   std::uint32_t color = 0xffffffffu) {
    SplatCloud c;
    c.positions.resize(n), c.normals.resize(n), c.axis_u.resize(n), c.axis_v.resize(n), c.uvs.resize(n);
    c.colors.assign(n, color);
    const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
    const double splat_r = k * std::sqrt(4.0 * std::numbers::pi / double(n)) * radius;
    for (std::size_t i = 0; i < n; ++i) {
        const double y = 1.0 - 2.0 * (double(i) + 0.5) / double(n);
        const double rr = std::sqrt(std::max(0.0, 1.0 - y * y));
        const double phi = golden * double(i);
        const glm::dvec3 nrm(std::cos(phi) * rr, y, std::sin(phi) * rr);
        const glm::dvec3 a = std::abs(nrm.y) < 0.9 ? glm::dvec3(0, 1, 0) : glm::dvec3(1, 0, 0);
        const glm::dvec3 t = glm::normalize(glm::cross(a, nrm));
        const glm::dvec3 b = glm::cross(nrm, t);
        c.positions[i] = glm::vec3(nrm * radius);
        c.normals[i] = glm::vec3(nrm);
        c.axis_u[i] = glm::vec3(t * splat_r);
        c.axis_v[i] = glm::vec3(b * splat_r);
        double lon = std::atan2(nrm.z, nrm.x) / (2.0 * std::numbers::pi);
        if (lon < 0) lon += 1.0;
        c.uvs[i] = glm::vec2(float(lon), float(std::asin(std::clamp(y, -1.0, 1.0)) / std::numbers::pi + 0.5));
    }
    return c;
}

// A 64 x 32 checker texture (8-texel squares, a green ramp down the rows) on the cloud's uv, so that
// textured clouds sample something that shows misplaced or misfiltered texels.
inline void add_checker(SplatCloud& s) {
    const int tw = 64, th = 32;
    s.texture.width = tw, s.texture.height = th;
    for (int y = 0; y < th; ++y)
        for (int x = 0; x < tw; ++x) {
            const bool check = ((x / 8) + (y / 8)) % 2 == 0;
            s.texture.rgba8.insert(s.texture.rgba8.end(),
                                   {std::uint8_t(check ? 230 : 40), std::uint8_t(40 + 6 * y),
                                    std::uint8_t(check ? 40 : 220), 255});
        }
}

}  // namespace sffd::render::test
