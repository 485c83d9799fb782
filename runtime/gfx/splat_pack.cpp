// SplatCloud -> GpuSplat packing (see splat_pack.h).
#include "runtime/gfx/splat_pack.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace sffd::gfx {

std::uint8_t encode_srgb8(float linear) {
    float c = std::clamp(linear, 0.0f, 1.0f);
    c = c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
    return static_cast<std::uint8_t>(std::lround(c * 255.0f));
}

namespace {

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
        s.center[3] = std::bit_cast<float>(has_colors ? cloud.colors[i] : uncoloured_splat);
        s.normal[0] = nrm.x, s.normal[1] = nrm.y, s.normal[2] = nrm.z, s.normal[3] = 1.0f;
        s.axis_u[0] = u.x, s.axis_u[1] = u.y, s.axis_u[2] = u.z, s.axis_u[3] = uv.x;
        s.axis_v[0] = v.x, s.axis_v[1] = v.y, s.axis_v[2] = v.z, s.axis_v[3] = uv.y;
    }
    return out;
}

}  // namespace sffd::gfx
