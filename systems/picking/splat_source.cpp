#include "systems/picking/splat_source.h"

#include "runtime/gfx/residency.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/splat_store.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform_cloud.h"
#include "systems/ffd/deform_inputs.h"
#include "systems/ffd/lattice_frame.h"

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

// The deformed splats of a GPU-only output (state deformed_gpu), read back into `out` (waits for the GPU).
void read_back(const gfx::GpuSplats& gpu, PickCache::Entry& out) {
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

SplatSource splat_source(const ecs::Registry& registry, ecs::Entity cloud_entity, PickCache& cache) {
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
        cache.erase(PickCloudKind::surface, cloud_entity);
        return src;
    }

    const Deformers* deformers = registry.try_get<Deformers>(cloud_entity);
    if (deformers && !deformers->lattices.empty()) {
        const ffd::DeformInputs deform_inputs = ffd::deform_inputs<SplatCloud>(registry, cloud_entity);
        const DeformInputStamps& inputs = deform_inputs.stamps;
        PickCache::Entry& entry = cache.entry(PickCloudKind::surface, cloud_entity);
        if (const gfx::GpuSplats* gpu = gpu_only_output(registry, cloud_entity, n)) {
            if (!entry.holds_read_back(gpu->deformed_version, inputs) || entry.positions.size() != n) {
                read_back(*gpu, entry);
                cache.filled(entry, true, gpu->deformed_version, inputs);
                ++cache.read_backs;
            }
            src.kind = SplatSource::Kind::gpu_read_back;
        } else {
            if (!entry.holds_deformation(inputs) || entry.positions.size() != n) {
                DeformedSplats d;
                const ffd::CloudLattices framed =
                    ffd::cloud_lattices(registry, cloud_entity, deform_inputs.lattices);
                ffd::deform_cloud(*cloud, framed.span(), d, "picking",
                                  registry.try_get<PointWeights>(cloud_entity));
                entry.positions = std::move(d.positions);
                entry.normals = std::move(d.normals);
                entry.axis_u = std::move(d.axis_u);
                entry.axis_v = std::move(d.axis_v);
                cache.filled(entry, false, 0, inputs);
                ++cache.deformations;
            }
            src.kind = SplatSource::Kind::cpu_deformed;
        }
        src.version = entry.serial;
        src.positions = entry.positions;
        src.normals = if_sized(entry.normals, n);
        if (entry.axis_u.size() == n && entry.axis_v.size() == n)
            src.axis_u = entry.axis_u, src.axis_v = entry.axis_v;
        return src;
    }

    cache.erase(PickCloudKind::surface, cloud_entity);
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
