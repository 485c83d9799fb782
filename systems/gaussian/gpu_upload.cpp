#include "systems/gaussian/gpu_upload.h"

#include <algorithm>
#include <span>

namespace sffd::gaussian {

namespace {

using gfx::fill_buffer;

// Packs the records straight into `buffer` (mapped for writing): no packed copy on the CPU.
void fill_gaussians(gfx::Buffer& buffer, const char* label, const GaussianCloud& g,
                    const std::vector<float>& opacities) {
    const std::size_t n = g.size();
    gfx::fill_buffer_in_place(buffer, label, n * sizeof(gpu::GpuGaussian), [&](void* dst) {
        pack_gaussians(g, opacities, std::span(static_cast<gpu::GpuGaussian*>(dst), n));
    });
}

}  // namespace

void pack_gaussians(const GaussianCloud& g, const std::vector<float>& opacities,
                    std::span<gpu::GpuGaussian> out) {
    const std::size_t n = std::min(g.size(), out.size());
    for (std::size_t i = 0; i < n; ++i) {
        const glm::vec3 p = g.positions[i], s = g.scales[i];
        const glm::quat q = g.rotations[i];
        out[i] = {{p.x, p.y, p.z, i < opacities.size() ? opacities[i] : 0.0f},
                  {q.w, q.x, q.y, q.z},
                  {s.x, s.y, s.z, 0.0f}};
    }
}

std::vector<gpu::GpuGaussian> pack_gaussians(const GaussianCloud& g, const std::vector<float>& opacities) {
    std::vector<gpu::GpuGaussian> out(g.size());
    pack_gaussians(g, opacities, out);
    return out;
}

Status upload_rest(GpuGaussians& gpu, const GaussianCloud& cloud, std::uint64_t version) {
    const std::size_t n = cloud.size();
    if (cloud.scales.size() != n || cloud.rotations.size() != n || cloud.opacities.size() != n ||
        cloud.sh.size() != n * std::size_t(sh_coeffs(cloud.sh_degree)) * 3)
        return make_error("gaussian::upload_rest(): cloud arrays differ in size");
    if (n > 0xffffffffull) return make_error("gaussian::upload_rest(): more than 2^32 - 1 Gaussians");
    fill_gaussians(gpu.rest, "gaussian.rest", cloud, cloud.opacities);
    fill_buffer(gpu.sh, "gaussian.rest_sh", cloud.sh.data(), cloud.sh.size() * sizeof(float));
    gfx::set_rest(gpu, version, std::uint32_t(n));
    gpu.sh_degree = cloud.sh_degree;
    gpu.sh_source = ShSource::authored;
    return {};
}

void upload_cpu_deformed(GpuGaussians& gpu, const DeformedGaussians& d, const GaussianCloud& authored) {
    const GaussianCloud& g = d.cloud;
    // The deformed cloud carries opacities only when some Gaussians were made transparent.
    fill_gaussians(gpu.deformed, "gaussian.deformed", g,
                   g.opacities.size() == g.size() ? g.opacities : authored.opacities);
    gpu.sh_source = ShSource::authored;
    if (g.sh.size() == authored.sh.size() && g.sh != authored.sh) {
        fill_buffer(gpu.deformed_sh, "gaussian.deformed_sh", g.sh.data(), g.sh.size() * sizeof(float));
        gpu.sh_source = ShSource::rotated;
    } else if (!g.sh_frames.empty() && g.sh_frames.size() == g.size()) {
        gfx::fill_buffer_in_place(
            gpu.frames, "gaussian.sh_frames", g.size() * 3 * sizeof(glm::vec4), [&](void* dst) {
                auto* cols = static_cast<glm::vec4*>(dst);
                for (std::size_t i = 0; i < g.size(); ++i)
                    for (int c = 0; c < 3; ++c)
                        cols[i * 3 + std::size_t(c)] = glm::vec4(g.sh_frames[i][c], 0.0f);
            });
        gpu.sh_source = ShSource::frames;
    }
    gfx::set_deformed(gpu, gfx::Residency::deformed_cpu);
}

void upload_preview(GpuGaussians& gpu, const GaussianCloud& subset, std::span<const std::uint32_t> indices) {
    fill_gaussians(gpu.deformed, "gaussian.deformed", subset, subset.opacities);
    // The authored `sh` is indexed by the whole cloud: the subset reads its own coefficients.
    fill_buffer(gpu.deformed_sh, "gaussian.deformed_sh", subset.sh.data(), subset.sh.size() * sizeof(float));
    gpu.sh_source = ShSource::rotated;
    gpu.preview_sh_degree = subset.sh_degree;
    gfx::set_preview(gpu, std::uint32_t(subset.size()));
    gpu.preview_indices.assign(indices.begin(), indices.end());  // whose marks each drawn Gaussian shows
    gfx::sync_preview_index(gpu);
}

}  // namespace sffd::gaussian
