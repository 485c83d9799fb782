#include "systems/splat_render/splat_pack.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "systems/splat_render/image_io.h"

namespace sffd::render {

namespace {

std::uint32_t pack_base_color(const glm::vec4& linear) {
    const std::uint32_t r = encode_srgb8(linear.x), g = encode_srgb8(linear.y), b = encode_srgb8(linear.z);
    const auto a = static_cast<std::uint32_t>(std::lround(std::clamp(linear.w, 0.0f, 1.0f) * 255.0f));
    return r | (g << 8) | (b << 16) | (a << 24);
}

// A unit tangent perpendicular to n (used when a cloud has normals but no axes).
glm::vec3 any_tangent(const glm::vec3& n) {
    const glm::vec3 a = std::abs(n.x) < 0.9f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
    return glm::normalize(glm::cross(n, a));
}

}  // namespace

std::vector<gpu::GpuSplat> pack_splats(const SplatCloud& cloud) {
    const std::size_t n = cloud.size();
    std::vector<gpu::GpuSplat> out(n);
    const bool has_normals = cloud.normals.size() == n;
    const bool has_axes = cloud.axis_u.size() == n && cloud.axis_v.size() == n;
    const bool has_colors = cloud.colors.size() == n;
    const bool has_uvs = cloud.uvs.size() == n;
    const std::uint32_t base = pack_base_color(cloud.material.base_color);
    for (std::size_t i = 0; i < n; ++i) {
        gpu::GpuSplat& s = out[i];
        const glm::vec3 p = cloud.positions[i];
        const glm::vec3 nrm = has_normals ? cloud.normals[i] : glm::vec3(0, 0, 1);
        glm::vec3 u, v;
        if (has_axes) {
            u = cloud.axis_u[i];
            v = cloud.axis_v[i];
        } else {  // no radii authored: a tiny disc, visible as a point (importers estimate radii)
            u = any_tangent(nrm) * 1e-3f;
            v = glm::cross(nrm, glm::normalize(u)) * 1e-3f;
        }
        const glm::vec2 uv = has_uvs ? cloud.uvs[i] : glm::vec2(0.0f);
        s.center[0] = p.x, s.center[1] = p.y, s.center[2] = p.z;
        s.center[3] = std::bit_cast<float>(has_colors ? cloud.colors[i] : base);
        s.normal[0] = nrm.x, s.normal[1] = nrm.y, s.normal[2] = nrm.z, s.normal[3] = 1.0f;
        s.axis_u[0] = u.x, s.axis_u[1] = u.y, s.axis_u[2] = u.z, s.axis_u[3] = uv.x;
        s.axis_v[0] = v.x, s.axis_v[1] = v.y, s.axis_v[2] = v.z, s.axis_v[3] = uv.y;
    }
    return out;
}

BoundingSphere bounding_sphere(const SplatCloud& cloud) {
    if (cloud.positions.empty()) return {};
    glm::dvec3 lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (const glm::vec3& p : cloud.positions) {
        lo = glm::min(lo, glm::dvec3(p));
        hi = glm::max(hi, glm::dvec3(p));
    }
    BoundingSphere b;
    b.center = 0.5 * (lo + hi);
    double r2 = 0.0, splat_r2 = 0.0;
    for (const glm::vec3& p : cloud.positions) r2 = std::max(r2, glm::dot(glm::dvec3(p) - b.center, glm::dvec3(p) - b.center));
    for (std::size_t i = 0; i < cloud.axis_u.size() && i < cloud.axis_v.size(); ++i)
        splat_r2 = std::max(splat_r2, double(std::max(glm::dot(cloud.axis_u[i], cloud.axis_u[i]),
                                                      glm::dot(cloud.axis_v[i], cloud.axis_v[i]))));
    b.max_splat_radius = std::sqrt(splat_r2);
    b.radius = std::sqrt(r2) + b.max_splat_radius;
    return b;
}

}  // namespace sffd::render
