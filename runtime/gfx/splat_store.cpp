#include "runtime/gfx/splat_store.h"

#include "runtime/gfx/splat_pack.h"

namespace sffd::gfx {

void upload_rest_splats(GpuSplats& gpu, const SplatCloud& cloud, std::uint64_t version, bool keep_cpu) {
    std::vector<gpu::GpuSplat> packed = pack_splats(cloud);
    fill_buffer(gpu.rest, "splats.rest", packed.data(), packed.size() * sizeof(gpu::GpuSplat));
    set_rest(gpu, version, static_cast<std::uint32_t>(packed.size()));
    gpu.cpu_deformed.clear();
    if (keep_cpu) gpu.cpu_rest = std::move(packed);
    else gpu.cpu_rest = {};
}

void upload_deformed_splats(GpuSplats& gpu, const SplatCloud& authored, const DeformedSplatArrays& d,
                            bool keep_cpu) {
    const std::size_t n = authored.size();
    // Packed where the last deformation was kept (its memory, already touched), uploaded, kept again.
    std::vector<gpu::GpuSplat> packed = std::move(gpu.cpu_deformed);
    pack_splats(
        SplatColumns{d.positions, d.normals.size() == n ? d.normals : authored.normals,
                     d.axis_u.size() == n ? d.axis_u : authored.axis_u,
                     d.axis_v.size() == n ? d.axis_v : authored.axis_v, authored.colors, authored.uvs},
        packed);
    fill_buffer(gpu.deformed, "splats.deformed", packed.data(), packed.size() * sizeof(gpu::GpuSplat));
    set_deformed(gpu, Residency::deformed_cpu);
    if (keep_cpu) gpu.cpu_deformed = std::move(packed);
    else gpu.cpu_deformed = {};
}

void upload_preview_splats(GpuSplats& gpu, const SplatCloud& authored, std::span<const std::uint32_t> indices,
                           const DeformedSplatArrays& d, float radius_scale, bool keep_cpu) {
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
    std::vector<gpu::GpuSplat> packed = pack_splats(moved);
    fill_buffer(gpu.deformed, "splats.deformed", packed.data(), packed.size() * sizeof(gpu::GpuSplat));
    set_preview(gpu, static_cast<std::uint32_t>(k));
    if (keep_cpu) gpu.cpu_deformed = std::move(packed);
    else gpu.cpu_deformed = {};
}

}  // namespace sffd::gfx
