// GpuSplatStore: registry resource holding every surface point cloud's splats on the GPU, in the GpuSplat
// layout (shaders/common/bindings.h). The surface kind of the shared residency (residency.h):
//   - residency_system (phase `residency`, before the deformation) uploads the authored SplatCloud into
//     `rest` with upload_rest_splats() when the cloud's change stamp moves;
//   - ffd_system's compute pass reads `rest` and writes `deformed` (state deformed_gpu); its CPU path
//     uploads its output with upload_deformed_splats() (state deformed_cpu);
//   - render and picking read draw_buffer() and, for the CPU cull, cpu_current().
// Owned by the registry (a resource), so GL names live exactly as long as the context's registry.
#pragma once

#include <cstdint>
#include <span>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/entity.h"
#include "runtime/gfx/residency.h"
#include "runtime/scene/components.h"
#include "shaders/common/bindings.h"

namespace sffd::gfx {

struct GpuSplats : ResidentCloud {
    // CPU mirrors of `rest` / `deformed` (deformed_cpu only), kept when GpuSplatStore::keep_cpu: the CPU
    // cull reads them, and they cost nothing extra since the upload packed them anyway.
    std::vector<gpu::GpuSplat> cpu_rest;
    std::vector<gpu::GpuSplat> cpu_deformed;

    // The CPU copy of the draw buffer, if one exists (none when the compute pass wrote `deformed`).
    const std::vector<gpu::GpuSplat>* cpu_current() const {
        if (state == Residency::rest) return cpu_rest.size() == count && count ? &cpu_rest : nullptr;
        if (state == Residency::deformed_cpu)
            return cpu_deformed.size() == count && count ? &cpu_deformed : nullptr;
        if (state == Residency::preview_cpu)
            return cpu_deformed.size() == preview_count && preview_count ? &cpu_deformed : nullptr;
        return nullptr;
    }
};

struct GpuSplatStore {
    std::unordered_map<ecs::Entity, GpuSplats> clouds;
    bool keep_cpu =
        false;  // keep CPU mirrors (residency_system: on a software rasterizer the cull runs there)
};

// The one rest upload of a surface cloud: packs it, fills `rest`, state rest at `version`.
void upload_rest_splats(GpuSplats& gpu, const SplatCloud& cloud, std::uint64_t version, bool keep_cpu);

// A CPU deformation's output (positions; normals and axes when the deformation wrote them, else the
// authored ones; colours and uvs always authored) into `deformed`, state deformed_cpu.
struct DeformedSplatArrays {
    const std::vector<glm::vec3>& positions;
    const std::vector<glm::vec3>& normals;
    const std::vector<glm::vec3>& axis_u;
    const std::vector<glm::vec3>& axis_v;
};
void upload_deformed_splats(GpuSplats& gpu, const SplatCloud& authored, const DeformedSplatArrays& deformed,
                            bool keep_cpu);

// A budgeted preview's output (state preview_cpu): `deformed` holds the splats `indices` of `authored`
// (arrays compacted in that order; normals and axes as above), their axes scaled by `radius_scale`.
void upload_preview_splats(GpuSplats& gpu, const SplatCloud& authored, std::span<const std::uint32_t> indices,
                           const DeformedSplatArrays& deformed, float radius_scale, bool keep_cpu);

}  // namespace sffd::gfx
