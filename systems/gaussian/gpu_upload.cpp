#include "systems/gaussian/gpu_upload.h"

#include <algorithm>

namespace sffd::gaussian {

namespace {

// (Re)allocates when the size changes (never a zero-sized store: GL needs one to bind) and uploads.
void fill(gfx::Buffer& b, const char* label, const void* data, std::size_t bytes) {
    if (!b) b = gfx::Buffer::create(label);
    GLint64 have = 0;
    glGetNamedBufferParameteri64v(b.id(), GL_BUFFER_SIZE, &have);
    const std::size_t want = std::max<std::size_t>(bytes, 16);
    if (std::size_t(have) != want) glNamedBufferData(b.id(), GLsizeiptr(want), nullptr, GL_DYNAMIC_DRAW);
    if (bytes > 0 && data) glNamedBufferSubData(b.id(), 0, GLsizeiptr(bytes), data);
}

}  // namespace

std::vector<gpu::GpuGaussian> pack_gaussians(const GaussianCloud& g, const std::vector<float>& opacities) {
    const std::size_t n = g.size();
    std::vector<gpu::GpuGaussian> out(n);
    for (std::size_t i = 0; i < n; ++i) {
        const glm::vec3 p = g.positions[i], s = g.scales[i];
        const glm::quat q = g.rotations[i];
        out[i] = {{p.x, p.y, p.z, i < opacities.size() ? opacities[i] : 0.0f}, {q.w, q.x, q.y, q.z}, {s.x, s.y, s.z, 0.0f}};
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
    fill(gpu.rest, "gaussian.rest", packed.data(), packed.size() * sizeof(gpu::GpuGaussian));
    fill(gpu.sh, "gaussian.rest_sh", cloud.sh.data(), cloud.sh.size() * sizeof(float));
    drop_deformed(gpu);
    gpu.deformed_on_gpu = false;
    gpu.count = std::uint32_t(n);
    gpu.sh_degree = cloud.sh_degree;
    gpu.rest_version = version;
    return {};
}

void upload_cpu_deformed(GpuGaussians& gpu, const DeformedGaussians& d, const GaussianCloud& authored) {
    const GaussianCloud& g = d.cloud;
    // The deformed cloud carries opacities only when some Gaussians were made transparent.
    const std::vector<gpu::GpuGaussian> packed = pack_gaussians(g, g.opacities.size() == g.size() ? g.opacities : authored.opacities);
    fill(gpu.deformed, "gaussian.deformed", packed.data(), packed.size() * sizeof(gpu::GpuGaussian));
    gpu.has_deformed_sh = g.sh.size() == authored.sh.size() && g.sh != authored.sh;
    if (gpu.has_deformed_sh) fill(gpu.deformed_sh, "gaussian.deformed_sh", g.sh.data(), g.sh.size() * sizeof(float));
    gpu.has_frames = !g.sh_frames.empty() && g.sh_frames.size() == g.size();
    if (gpu.has_frames) {
        std::vector<glm::vec4> cols(g.size() * 3);
        for (std::size_t i = 0; i < g.size(); ++i)
            for (int c = 0; c < 3; ++c) cols[i * 3 + std::size_t(c)] = glm::vec4(g.sh_frames[i][c], 0.0f);
        fill(gpu.frames, "gaussian.sh_frames", cols.data(), cols.size() * sizeof(glm::vec4));
    }
    gpu.has_deformed = true;
    gpu.deformed_on_gpu = false;
    ++gpu.deformed_version;
}

void drop_deformed(GpuGaussians& gpu) {
    gpu.has_deformed = gpu.has_deformed_sh = gpu.has_frames = gpu.deformed_on_gpu = false;
}

}  // namespace sffd::gaussian
