#include "systems/picking/splat_source.h"

#include "runtime/gfx/residency.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/splat_store.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform_cloud.h"

namespace sffd::picking {
namespace {

std::uint64_t mix(std::uint64_t h, std::uint64_t v) {
    h ^= v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    return h;
}

template <class T>
std::span<const T> if_sized(const std::vector<T>& v, std::size_t n) {
    return v.size() == n ? std::span<const T>(v) : std::span<const T>();
}

// Key of the inputs of the CPU deformation: cloud, deformer list and every lattice's stamp.
std::uint64_t deform_key(const ecs::Registry& registry, ecs::Entity cloud, const Deformers& deformers) {
    std::uint64_t h = mix(registry.version<SplatCloud>(cloud), registry.version<Deformers>(cloud));
    for (const ecs::Entity l : deformers.lattices) {
        h = mix(h, l.bits());
        h = mix(h, registry.valid(l) ? registry.version<Lattice>(l) : 0);
    }
    return h;
}

// The deformed splats of a GPU-only output (state deformed_gpu), read back into `out` (waits for the GPU).
void read_back(const gfx::GpuSplats& gpu, DeformedSplats& out) {
    const std::size_t n = gpu.count;
    std::vector<gpu::GpuSplat> rows(n);
    // The compute pass wrote the buffer through shader storage: make those writes visible to the copy.
    glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
    if (n) glGetNamedBufferSubData(gpu.deformed.id(), 0, GLsizeiptr(n * sizeof(gpu::GpuSplat)), rows.data());
    out.positions.resize(n), out.normals.resize(n), out.axis_u.resize(n), out.axis_v.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const gpu::GpuSplat& r = rows[i];
        out.positions[i] = {r.center[0], r.center[1], r.center[2]};
        out.normals[i] = {r.normal[0], r.normal[1], r.normal[2]};
        out.axis_u[i] = {r.axis_u[0], r.axis_u[1], r.axis_u[2]};
        out.axis_v[i] = {r.axis_v[0], r.axis_v[1], r.axis_v[2]};
    }
}

// The cloud's resident GPU-only deformed output, if there is one to read.
const gfx::GpuSplats* gpu_only_output(const ecs::Registry& registry, ecs::Entity cloud, std::size_t n) {
    if (!gfx::context_current()) return nullptr;
    const auto* store = registry.try_resource<gfx::GpuSplatStore>();
    if (!store) return nullptr;
    const auto it = store->clouds.find(cloud);
    if (it == store->clouds.end()) return nullptr;
    const gfx::GpuSplats& gpu = it->second;
    const bool current = gpu.state == gfx::Residency::deformed_gpu && gpu.count == n &&
                         gpu.rest_version == registry.version<SplatCloud>(cloud);
    return current ? &gpu : nullptr;
}

}  // namespace

SplatSource splat_source(const ecs::Registry& registry, ecs::Entity cloud_entity, DeformCache& cache) {
    SplatSource src;
    const SplatCloud* cloud = registry.try_get<SplatCloud>(cloud_entity);
    if (!cloud) return src;
    const std::size_t n = cloud->size();
    src.origin = cloud->origin;

    const DeformedSplats* deformed = registry.try_get<DeformedSplats>(cloud_entity);
    if (deformed && deformed->cpu_valid && deformed->positions.size() == n) {
        src.kind = SplatSource::Kind::deformed;
        src.version = mix(registry.version<DeformedSplats>(cloud_entity), deformed->version);
        src.origin = deformed->origin;
        src.positions = deformed->positions;
        src.normals = if_sized(deformed->normals, n);
        if (deformed->axis_u.size() == n && deformed->axis_v.size() == n)
            src.axis_u = deformed->axis_u, src.axis_v = deformed->axis_v;
        cache.clouds.erase(cloud_entity.bits());
        return src;
    }

    const Deformers* deformers = registry.try_get<Deformers>(cloud_entity);
    if (const gfx::GpuSplats* gpu = deformers && !deformers->lattices.empty()
                                        ? gpu_only_output(registry, cloud_entity, n)
                                        : nullptr) {
        DeformCache::Entry& entry = cache.clouds[cloud_entity.bits()];
        const std::uint64_t key = mix(0x9b1d5a7e3c2f4d61ull, gpu->deformed_version);
        if (entry.key != key || entry.deformed.positions.size() != n) {
            read_back(*gpu, entry.deformed);
            entry.key = key;
            ++cache.read_backs;
        }
        src.kind = SplatSource::Kind::gpu_read_back;
        src.version = key;
        const DeformedSplats& d = entry.deformed;
        src.positions = d.positions, src.normals = d.normals, src.axis_u = d.axis_u, src.axis_v = d.axis_v;
        return src;
    }
    if (deformers && !deformers->lattices.empty()) {
        DeformCache::Entry& entry = cache.clouds[cloud_entity.bits()];
        const std::uint64_t key = deform_key(registry, cloud_entity, *deformers);
        if (entry.key != key || entry.deformed.positions.size() != n) {
            ffd::deform_cloud(registry, *cloud, deformers->lattices, entry.deformed, "picking");
            entry.key = key;
            ++cache.deformations;
        }
        src.kind = SplatSource::Kind::cpu_deformed;
        src.version = key;
        const DeformedSplats& d = entry.deformed;
        src.positions = d.positions;
        src.normals = if_sized(d.normals, n);
        if (d.axis_u.size() == n && d.axis_v.size() == n) src.axis_u = d.axis_u, src.axis_v = d.axis_v;
        return src;
    }

    cache.clouds.erase(cloud_entity.bits());
    src.kind = SplatSource::Kind::authored;
    src.version = registry.version<SplatCloud>(cloud_entity);
    src.positions = cloud->positions;
    src.normals = if_sized(cloud->normals, n);
    if (cloud->axis_u.size() == n && cloud->axis_v.size() == n)
        src.axis_u = cloud->axis_u, src.axis_v = cloud->axis_v;
    return src;
}

std::uint64_t splat_source_storage_version(const ecs::Registry& registry) {
    return mix(registry.storage_version<DeformedSplats>(), registry.storage_version<Deformers>());
}

}  // namespace sffd::picking
