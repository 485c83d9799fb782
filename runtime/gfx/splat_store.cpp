#include "runtime/gfx/splat_store.h"

#include <algorithm>
#include <cmath>

#include "runtime/gfx/splat_pack.h"

namespace sffd::gfx {

namespace {

// Packs `columns` straight into `buffer` (mapped for writing): no packed copy on the CPU.
void fill_splats(Buffer& buffer, const char* label, const SplatColumns& columns) {
    const std::size_t n = columns.positions.size();
    fill_buffer_in_place(buffer, label, n * sizeof(gpu::GpuSplat), [&](void* dst) {
        pack_splats(columns, std::span(static_cast<gpu::GpuSplat*>(dst), n));
    });
}

// The draw buffer a CPU copy would hold: which buffer, and which version of it.
std::uint64_t draw_key(const GpuSplats& gpu) {
    return gpu.is_deformed() ? (gpu.deformed_version << 1) | 1u : gpu.rest_version << 1;
}

}  // namespace

void upload_rest_splats(GpuSplats& gpu, const SplatCloud& cloud, std::uint64_t version) {
    fill_splats(
        gpu.rest, "splats.rest",
        SplatColumns{cloud.positions, cloud.normals, cloud.axis_u, cloud.axis_v, cloud.colors, cloud.uvs});
    set_rest(gpu, version, static_cast<std::uint32_t>(cloud.size()));
}

void upload_splat_texture(GpuSplats& gpu, const SplatCloud& cloud, std::uint64_t version) {
    gpu.texture_version = version;
    const SplatTexture& m = cloud.texture;
    if (m.rgba8.empty() || m.width <= 0 || m.height <= 0 ||
        m.rgba8.size() < std::size_t(m.width) * std::size_t(m.height) * 4) {
        gpu.texture.reset();
        gpu.uv_axes.reset();
        return;
    }
    gpu.texture = Texture::create("splats.texture", GL_TEXTURE_2D);
    const int levels = 1 + int(std::floor(std::log2(std::max(m.width, m.height))));
    glTextureStorage2D(gpu.texture.id(), levels, GL_SRGB8_ALPHA8, m.width, m.height);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    // Row 0 of the texels is v = 0, which is also GL's first row (t = 0).
    glTextureSubImage2D(gpu.texture.id(), 0, 0, 0, m.width, m.height, GL_RGBA, GL_UNSIGNED_BYTE,
                        m.rgba8.data());
    glGenerateTextureMipmap(gpu.texture.id());
    // Mipmapped: the HQ attribute pass filters per pixel with textureGrad (the cull's per-splat lookups ask
    // for level 0 explicitly).
    glTextureParameteri(gpu.texture.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTextureParameteri(gpu.texture.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(gpu.texture.id(), GL_TEXTURE_WRAP_S, GL_REPEAT);
    glTextureParameteri(gpu.texture.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);

    // The uv frames the textured passes read, zeros for a cloud without them (then every fragment samples
    // the splat's centre uv at level 0).
    const std::size_t n = cloud.size();
    if (cloud.uv_axes.size() == n) {
        fill_buffer(gpu.uv_axes, "splats.uv_axes", cloud.uv_axes.data(), n * sizeof(glm::vec4));
    } else {
        fill_buffer_in_place(gpu.uv_axes, "splats.uv_axes", n * sizeof(glm::vec4), [&](void* dst) {
            std::fill_n(static_cast<glm::vec4*>(dst), n, glm::vec4(0.0f));
        });
    }
}

void upload_deformed_splats(GpuSplats& gpu, const SplatCloud& authored, const DeformedSplatArrays& d) {
    const std::size_t n = authored.size();
    fill_splats(
        gpu.deformed, "splats.deformed",
        SplatColumns{d.positions, d.normals.size() == n ? d.normals : authored.normals,
                     d.axis_u.size() == n ? d.axis_u : authored.axis_u,
                     d.axis_v.size() == n ? d.axis_v : authored.axis_v, authored.colors, authored.uvs});
    set_deformed(gpu, Residency::deformed_cpu);
}

void upload_preview_splats(GpuSplats& gpu, const SplatCloud& authored, std::span<const std::uint32_t> indices,
                           const DeformedSplatArrays& d, float radius_scale) {
    const std::size_t n = authored.size(), k = indices.size();
    auto pick = [&](const std::vector<glm::vec3>& deformed, const std::vector<glm::vec3>& rest,
                    std::vector<glm::vec3>& to) {
        if (deformed.size() == k) to = deformed;
        else if (rest.size() == n) {
            to.resize(k);
            for (std::size_t i = 0; i < k; ++i) to[i] = rest[indices[i]];
        }
    };
    SplatCloud moved;
    moved.positions = d.positions;
    pick(d.normals, authored.normals, moved.normals);
    pick(d.axis_u, authored.axis_u, moved.axis_u);
    pick(d.axis_v, authored.axis_v, moved.axis_v);
    // Fewer, larger splats cover the same surface: each stands for about n / k of them.
    for (glm::vec3& a : moved.axis_u) a *= radius_scale;
    for (glm::vec3& a : moved.axis_v) a *= radius_scale;
    if (authored.colors.size() == n) {
        moved.colors.resize(k);
        for (std::size_t i = 0; i < k; ++i) moved.colors[i] = authored.colors[indices[i]];
    }
    if (authored.uvs.size() == n) {
        moved.uvs.resize(k);
        for (std::size_t i = 0; i < k; ++i) moved.uvs[i] = authored.uvs[indices[i]];
    }
    fill_splats(
        gpu.deformed, "splats.deformed",
        SplatColumns{moved.positions, moved.normals, moved.axis_u, moved.axis_v, moved.colors, moved.uvs});
    set_preview(gpu, static_cast<std::uint32_t>(k));
    gpu.preview_indices.assign(indices.begin(), indices.end());  // whose marks each drawn splat shows
    sync_preview_index(gpu);
}

CpuSplatRead read_splats_on_cpu(GpuSplats& gpu) {
    const std::uint32_t n = gpu.drawn_count();
    const GLuint buffer = gpu.draw_buffer();
    if (n == 0 || buffer == 0 || gpu.mapped) return {};
    const std::size_t bytes = std::size_t(n) * sizeof(gpu::GpuSplat);
    if (cpu_reads_in_place()) {
        gpu.cpu_copy = {}, gpu.cpu_copy_key = ~std::uint64_t(0);
        const void* p = glMapNamedBufferRange(buffer, 0, GLsizeiptr(bytes), GL_MAP_READ_BIT);
        if (!p) return {};
        gpu.mapped = true;
        return {&gpu, buffer, std::span(static_cast<const gpu::GpuSplat*>(p), n)};
    }
    // Whoever wrote the buffer made the writes visible to read-backs (the deformation's barrier includes
    // BUFFER_UPDATE; uploads are ordered by GL).
    if (gpu.cpu_copy_key != draw_key(gpu) || gpu.cpu_copy.size() != n) {
        gpu.cpu_copy.resize(n);
        glGetNamedBufferSubData(buffer, 0, GLsizeiptr(bytes), gpu.cpu_copy.data());
        gpu.cpu_copy_key = draw_key(gpu);
    }
    return {nullptr, 0, std::span<const gpu::GpuSplat>(gpu.cpu_copy.data(), n)};
}

CpuSplatRead::~CpuSplatRead() {
    if (m_gpu && m_gpu->mapped) {
        glUnmapNamedBuffer(m_buffer);
        m_gpu->mapped = false;
    }
}

}  // namespace sffd::gfx
