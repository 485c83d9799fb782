// GpuSplatStore: registry resource holding every surface point cloud's GPU buffers: the splats in the
// GpuSplat layout (shaders/common/bindings.h), and a textured cloud's texture and uv frames. The surface
// kind of the shared residency (residency.h):
//   - residency_system (phase `residency`, before the deformation) uploads the authored SplatCloud with
//     upload_rest_splats() and upload_splat_texture() when the cloud's change stamp moves;
//   - ffd_system's compute pass reads `rest` and writes `deformed` (state deformed_gpu); its CPU path
//     uploads its output with upload_deformed_splats() (state deformed_cpu);
//   - render and picking read draw_buffer(), `texture`, `uv_axes`, and the CPU cull reads the draw buffer
//     through read_splats_on_cpu(). No reader keeps a copy of any of them.
// Owned by the registry (a resource), so GL names live exactly as long as the context's registry.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "runtime/ecs/entity.h"
#include "runtime/gfx/residency.h"
#include "runtime/scene/components.h"
#include "shaders/common/bindings.h"

namespace sffd::gfx {

struct GpuSplats : ResidentCloud {
    // A textured cloud's material (sRGB, mipmapped) and its uv frames (vec4[count]: SplatCloud::uv_axes,
    // zeros when absent), the SFFD_SSBO_UV_AXES buffer of the textured passes; both empty otherwise.
    Texture texture;
    Buffer uv_axes;
    std::uint64_t texture_version = 0;  // change stamp of the SplatCloud `texture` and `uv_axes` hold

    // Where the CPU cannot read the draw buffer in place (cpu_reads_in_place() false: a hardware GPU),
    // the copy read_splats_on_cpu() read back, and which draw buffer it is a copy of.
    std::vector<gpu::GpuSplat> cpu_copy;
    std::uint64_t cpu_copy_key = ~std::uint64_t(0);
    bool mapped = false;  // read_splats_on_cpu() mapped the draw buffer (until its CpuSplatRead ends)
};

struct GpuSplatStore {
    std::unordered_map<ecs::Entity, GpuSplats> clouds;
    // No CPU mirrors are kept (the CPU reads the buffers, read_splats_on_cpu()); read by callers of the
    // former upload spellings below.
    static constexpr bool keep_cpu = false;
};

// The draw buffer of a resident cloud as the CPU reads it (the CPU cull), for the lifetime of this
// object: mapped in place on a software rasterizer (no copy), else the store's copy, read back once per
// version of the draw buffer. No GL command may read or write the buffer while the object lives (it may
// be mapped). Needs the context current, as every store operation does.
class CpuSplatRead {
public:
    CpuSplatRead() = default;
    CpuSplatRead(GpuSplats* mapped, GLuint buffer, std::span<const gpu::GpuSplat> splats)
        : m_gpu(mapped), m_buffer(buffer), m_splats(splats) {}
    CpuSplatRead(CpuSplatRead&& o) noexcept
        : m_gpu(std::exchange(o.m_gpu, nullptr)), m_buffer(o.m_buffer), m_splats(o.m_splats) {}
    CpuSplatRead& operator=(CpuSplatRead&&) = delete;
    CpuSplatRead(const CpuSplatRead&) = delete;
    CpuSplatRead& operator=(const CpuSplatRead&) = delete;
    ~CpuSplatRead();
    std::span<const gpu::GpuSplat> splats() const { return m_splats; }

private:
    GpuSplats* m_gpu = nullptr;  // the cloud whose draw buffer is mapped (null: a copy is read)
    GLuint m_buffer = 0;
    std::span<const gpu::GpuSplat> m_splats;
};
// drawn_count() splats of the draw buffer (empty when none is resident or the mapping failed).
CpuSplatRead read_splats_on_cpu(GpuSplats& gpu);

// The one rest upload of a surface cloud: packs it straight into `rest`, state rest at `version`.
void upload_rest_splats(GpuSplats& gpu, const SplatCloud& cloud, std::uint64_t version);
// The one texture upload: `texture` and `uv_axes` from the cloud's SplatTexture and uv frames (released
// when it has no texture), at `version`.
void upload_splat_texture(GpuSplats& gpu, const SplatCloud& cloud, std::uint64_t version);

// A CPU deformation's output (positions; normals and axes when the deformation wrote them, else the
// authored ones; colours and uvs always authored) packed straight into `deformed`, state deformed_cpu.
struct DeformedSplatArrays {
    const std::vector<glm::vec3>& positions;
    const std::vector<glm::vec3>& normals;
    const std::vector<glm::vec3>& axis_u;
    const std::vector<glm::vec3>& axis_v;
};
void upload_deformed_splats(GpuSplats& gpu, const SplatCloud& authored, const DeformedSplatArrays& deformed);

// A budgeted preview's output (state preview_cpu): `deformed` holds the splats `indices` of `authored`
// (arrays compacted in that order; normals and axes as above), their axes scaled by `radius_scale`.
void upload_preview_splats(GpuSplats& gpu, const SplatCloud& authored, std::span<const std::uint32_t> indices,
                           const DeformedSplatArrays& deformed, float radius_scale);

// The former spellings, whose last argument chose CPU mirrors: none are kept any more (the CPU reads the
// buffers themselves, read_splats_on_cpu()), so it is ignored.
inline void upload_deformed_splats(GpuSplats& gpu, const SplatCloud& authored, const DeformedSplatArrays& d,
                                   bool /*keep_cpu*/) {
    upload_deformed_splats(gpu, authored, d);
}
inline void upload_preview_splats(GpuSplats& gpu, const SplatCloud& authored,
                                  std::span<const std::uint32_t> indices, const DeformedSplatArrays& d,
                                  float radius_scale, bool /*keep_cpu*/) {
    upload_preview_splats(gpu, authored, indices, d, radius_scale);
}

}  // namespace sffd::gfx
