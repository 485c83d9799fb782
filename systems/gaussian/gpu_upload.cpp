#include "systems/gaussian/gpu_upload.h"

#include <algorithm>

namespace sffd::gaussian {

namespace {

using gfx::fill_buffer;

}  // namespace

std::vector<gpu::GpuGaussian> pack_gaussians(const GaussianCloud& g, const std::vector<float>& opacities) {
    const std::size_t n = g.size();
    std::vector<gpu::GpuGaussian> out(n);
    for (std::size_t i = 0; i < n; ++i) {
        const glm::vec3 p = g.positions[i], s = g.scales[i];
        const glm::quat q = g.rotations[i];
        out[i] = {{p.x, p.y, p.z, i < opacities.size() ? opacities[i] : 0.0f},
                  {q.w, q.x, q.y, q.z},
                  {s.x, s.y, s.z, 0.0f}};
    }
    return out;
}

Status upload_rest(GpuGaussians& gpu, const GaussianCloud& cloud, std::uint64_t version) {
    const std::size_t n = cloud.size();
    if (cloud.scales.size() != n || cloud.rotations.size() != n || cloud.opacities.size() != n ||
        cloud.sh.size() != n * std::size_t(sh_coeffs(cloud.sh_degree)) * 3)
        return make_error("gaussian::upload_rest(): cloud arrays differ in size");
    if (n > 0xffffffffull) return make_error("gaussian::upload_rest(): more than 2^32 - 1 Gaussians");
    const std::vector<gpu::GpuGaussian> packed = pack_gaussians(cloud, cloud.opacities);
    fill_buffer(gpu.rest, "gaussian.rest", packed.data(), packed.size() * sizeof(gpu::GpuGaussian));
    fill_buffer(gpu.sh, "gaussian.rest_sh", cloud.sh.data(), cloud.sh.size() * sizeof(float));
    gfx::set_rest(gpu, version, std::uint32_t(n));
    gpu.sh_degree = cloud.sh_degree;
    gpu.sh_source = ShSource::authored;
    return {};
}

void upload_cpu_deformed(GpuGaussians& gpu, const DeformedGaussians& d, const GaussianCloud& authored) {
    const GaussianCloud& g = d.cloud;
    // The deformed cloud carries opacities only when some Gaussians were made transparent.
    const std::vector<gpu::GpuGaussian> packed =
        pack_gaussians(g, g.opacities.size() == g.size() ? g.opacities : authored.opacities);
    fill_buffer(gpu.deformed, "gaussian.deformed", packed.data(), packed.size() * sizeof(gpu::GpuGaussian));
    gpu.sh_source = ShSource::authored;
    if (g.sh.size() == authored.sh.size() && g.sh != authored.sh) {
        fill_buffer(gpu.deformed_sh, "gaussian.deformed_sh", g.sh.data(), g.sh.size() * sizeof(float));
        gpu.sh_source = ShSource::rotated;
    } else if (!g.sh_frames.empty() && g.sh_frames.size() == g.size()) {
        std::vector<glm::vec4> cols(g.size() * 3);
        for (std::size_t i = 0; i < g.size(); ++i)
            for (int c = 0; c < 3; ++c) cols[i * 3 + std::size_t(c)] = glm::vec4(g.sh_frames[i][c], 0.0f);
        fill_buffer(gpu.frames, "gaussian.sh_frames", cols.data(), cols.size() * sizeof(glm::vec4));
        gpu.sh_source = ShSource::frames;
    }
    gfx::set_deformed(gpu, gfx::Residency::deformed_cpu);
}

void upload_preview(GpuGaussians& gpu, const GaussianCloud& subset) {
    const std::vector<gpu::GpuGaussian> packed = pack_gaussians(subset, subset.opacities);
    fill_buffer(gpu.deformed, "gaussian.deformed", packed.data(), packed.size() * sizeof(gpu::GpuGaussian));
    // The authored `sh` is indexed by the whole cloud: the subset reads its own coefficients.
    fill_buffer(gpu.deformed_sh, "gaussian.deformed_sh", subset.sh.data(), subset.sh.size() * sizeof(float));
    gpu.sh_source = ShSource::rotated;
    gpu.preview_sh_degree = subset.sh_degree;
    gfx::set_preview(gpu, std::uint32_t(subset.size()));
}

}  // namespace sffd::gaussian
