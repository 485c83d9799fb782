// Which splats picking sees for a point-cloud entity, in this order:
//   1. the deformer's CPU output (DeformedSplats with cpu_valid, written by systems/ffd);
//   2. a cloud with Deformers whose output lives only on the GPU (GpuSplatStore state deformed_gpu, a GL
//      context current): read back once per GpuSplats::deformed_version into the PickCache;
//   3. otherwise a cloud with Deformers and no CPU output (no context, e.g. a headless tool): picking asks
//      the FFD system for its CPU output (ffd::deform_cloud, the step ffd_system's CPU path runs) into
//      the PickCache, keyed by the change stamps of the cloud, its Deformers and every lattice —
//      recomputed only when a pick needs it;
//   4. the authored SplatCloud.
// The spans point into the components or the cache; valid until either changes.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/registry.h"
#include "systems/ffd/components.h"
#include "systems/picking/pick_cache.h"

namespace sffd::picking {

struct SplatSource {
    enum class Kind : int { none, authored, deformed, cpu_deformed, gpu_read_back };
    Kind kind = Kind::none;
    std::uint64_t version = 0;  // identifies the data (a change stamp or a hash of stamps)
    glm::dvec3 origin{0.0};     // positions are relative to this (entity space)
    std::span<const glm::vec3> positions, normals, axis_u, axis_v;
};

SplatSource splat_source(const ecs::Registry& registry, ecs::Entity cloud, PickCache& cache);

// Changes whenever any deformer-related storage changes (DeformedSplats, Deformers).
std::uint64_t splat_source_storage_version(const ecs::Registry& registry);

}  // namespace sffd::picking
