// SplatCloud -> GpuSplat packing (see splat_pack.h).
#include "runtime/gfx/splat_pack.h"

#include <algorithm>
#include <bit>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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
    std::vector<gpu::GpuSplat> out;
    pack_splats(
        SplatColumns{cloud.positions, cloud.normals, cloud.axis_u, cloud.axis_v, cloud.colors, cloud.uvs},
        out);
    return out;
}

void pack_splats(const SplatColumns& c, std::vector<gpu::GpuSplat>& out) {
    out.resize(c.positions.size());
    pack_splats(c, std::span(out));
}

void pack_splats(const SplatColumns& c, std::span<gpu::GpuSplat> out) {
    const std::size_t n = std::min(c.positions.size(), out.size());
    const bool has_normals = c.normals.size() == n;
    const bool has_axes = c.axis_u.size() == n && c.axis_v.size() == n;
    const bool has_colors = c.colors.size() == n;
    const bool has_uvs = c.uvs.size() == n;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1 << 13), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
            gpu::GpuSplat& s = out[i];
            const glm::vec3 p = c.positions[i];
            const glm::vec3 nrm = has_normals ? c.normals[i] : glm::vec3(0, 0, 1);
            glm::vec3 u, v;
            if (has_axes) {
                u = c.axis_u[i];
                v = c.axis_v[i];
            } else {  // no radii authored: a tiny disc, visible as a point (importers estimate radii)
                u = any_tangent(nrm) * 1e-3f;
                v = glm::cross(nrm, glm::normalize(u)) * 1e-3f;
            }
            const glm::vec2 uv = has_uvs ? c.uvs[i] : glm::vec2(0.0f);
            s.center[0] = p.x, s.center[1] = p.y, s.center[2] = p.z;
            s.center[3] = std::bit_cast<float>(has_colors ? c.colors[i] : uncoloured_splat);
            s.normal[0] = nrm.x, s.normal[1] = nrm.y, s.normal[2] = nrm.z, s.normal[3] = 1.0f;
            s.axis_u[0] = u.x, s.axis_u[1] = u.y, s.axis_u[2] = u.z, s.axis_u[3] = uv.x;
            s.axis_v[0] = v.x, s.axis_v[1] = v.y, s.axis_v[2] = v.z, s.axis_v[3] = uv.y;
        }
    });
}

}  // namespace sffd::gfx
