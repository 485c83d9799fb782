#include "systems/gaussian/from_splats.h"

#include <algorithm>
#include <cmath>

#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/sh.h"

namespace sffd::gaussian {

GaussianCloud gaussians_from_splats(const SplatCloud& c, const FromSplatsOptions& o) {
    GaussianCloud g;
    const std::size_t n = c.size();
    g.origin = c.origin;
    g.sh_degree = 0;
    g.positions = c.positions;
    g.scales.resize(n), g.rotations.resize(n), g.opacities.assign(n, o.opacity), g.sh.resize(n * 3);
    const bool axes = c.axis_u.size() == n && c.axis_v.size() == n;
    double fallback = 0.01;
    if (!axes && n > 0) {
        glm::vec3 lo = c.positions[0], hi = lo;
        for (const glm::vec3& p : c.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
        const glm::dvec3 e = glm::max(glm::dvec3(hi - lo), glm::dvec3(1e-6));
        fallback = std::cbrt(e.x * e.y * e.z / double(n)) * 0.5;
    }
    // The material's linear base colour to display (sRGB-like) values, when there are no colours.
    const glm::vec3 base =
        glm::pow(glm::clamp(glm::vec3(o.material.base_color), 0.0f, 1.0f), glm::vec3(1.0f / 2.2f));
    for (std::size_t i = 0; i < n; ++i) {
        if (axes && glm::length(c.axis_u[i]) > 0.0f && glm::length(c.axis_v[i]) > 0.0f) {
            const glm::dvec3 u(c.axis_u[i]), v(c.axis_v[i]);
            glm::dvec3 nrm = c.normals.size() == n ? glm::dvec3(c.normals[i]) : glm::cross(u, v);
            const glm::dvec3 uh = glm::normalize(u);
            nrm = glm::normalize(nrm - glm::dot(nrm, uh) * uh);
            const glm::dmat3 r(uh, glm::cross(nrm, uh), nrm);
            const double su = o.sigma_per_radius * glm::length(u), sv = o.sigma_per_radius * glm::length(v);
            g.scales[i] = glm::vec3(glm::dvec3(su, sv, o.thickness * std::min(su, sv)));
            g.rotations[i] = glm::quat(quat_from_rotation(r));
        } else {
            g.scales[i] = glm::vec3(float(fallback));
            g.rotations[i] = glm::quat(1, 0, 0, 0);
        }
        glm::vec3 col = base;
        if (c.colors.size() == n) {
            const std::uint32_t rgba = c.colors[i];
            col = glm::vec3(float(rgba & 0xffu), float((rgba >> 8) & 0xffu), float((rgba >> 16) & 0xffu)) /
                  255.0f;
        }
        for (int ch = 0; ch < 3; ++ch) g.sh[i * 3 + std::size_t(ch)] = float((double(col[ch]) - 0.5) / kShC0);
    }
    return g;
}

}  // namespace sffd::gaussian
