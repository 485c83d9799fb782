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
    SplatCloud moved;
    moved.positions = d.positions;
    moved.normals = d.normals.size() == n ? d.normals : authored.normals;
    moved.axis_u = d.axis_u.size() == n ? d.axis_u : authored.axis_u;
    moved.axis_v = d.axis_v.size() == n ? d.axis_v : authored.axis_v;
    moved.colors = authored.colors;
    moved.uvs = authored.uvs;
    std::vector<gpu::GpuSplat> packed = pack_splats(moved);
    fill_buffer(gpu.deformed, "splats.deformed", packed.data(), packed.size() * sizeof(gpu::GpuSplat));
    set_deformed(gpu, Residency::deformed_cpu);
    if (keep_cpu) gpu.cpu_deformed = std::move(packed);
    else gpu.cpu_deformed = {};
}

}  // namespace sffd::gfx
