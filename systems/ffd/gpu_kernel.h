// Shared by the two compute deformers, ffd::GpuDeformer (ffd_gpu.cpp, splats) and
// gaussian::GpuGaussianDeformer (systems/gaussian/gpu_deform.cpp, Gaussians): they run the same FFD over
// different point layouts, so the lattice set-up (block UBO, control points uploaded when edited, the
// kernel choice and the programs specialised per lattice shape and basis) and the non-blocking statistics
// read-back are
// written once here. Each deformer binds its own point buffers and dispatches.
#pragma once

#include <cstdint>
#include <functional>
#include <glm/vec3.hpp>
#include <span>
#include <string>
#include <unordered_map>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/gl_object.h"
#include "runtime/gfx/shader.h"
#include "runtime/gfx/ssbo_batch.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/ffd/gpu_block.h"

namespace sffd::ffd::detail {

// Which control-point kernel a dispatch runs (GpuBernsteinKernel, resolved): their xyz in shared memory,
// Bernstein's in a UBO, or the SSBO (the B-spline's packed in runs along u, or point by point).
struct KernelChoice {
    bool shared = false, ubo = false, runs = false;
};
// The deform shaders' own shared words beside the control points (ffd: 2 counters, Gaussians: 4),
// rounded up: a program whose shared memory passes GL_MAX_COMPUTE_SHARED_MEMORY_SIZE fails to link, and
// lattices whose points fill the limit exactly exist (16^3 points: 48 KB, NVIDIA's limit).
inline constexpr std::size_t kDeformShaderSharedBytes = 64;
// The choice for `lattice` under the implementation's limits (bytes): shared memory when asked or, on a
// hardware GPU, for Bernstein, when the points' xyz and the shader's own words fit; else a UBO for
// Bernstein when it fits one; the B-spline reads packed runs unless `direct` is asked.
KernelChoice choose_kernel(const Lattice& lattice, GpuBernsteinKernel kernel, bool software,
                           std::size_t max_shared, std::size_t max_ubo);

// One deform shader's programs (generic; specialised per lattice shape, basis and kernel) and the
// lattice state they read. Labels: `program_label` (+ ".shared" / ".specialised"), `prefix` +
// ".lattice_block" / ".control_points".
struct DeformPrograms {
    std::string shader, program_label, prefix;
    // Generic (any divisions and basis): compiled by create(), so a broken shader fails there and the
    // caller stays on the CPU path; bind() runs the specialised ones.
    gfx::Program program;
    std::unordered_map<std::uint64_t, gfx::Program> specialised;  // per (l, m, n, basis, kernel, variant)
    gfx::Buffer ubo;                                              // FfdBlock
    struct Controls {
        gfx::Buffer buffer;
        std::size_t capacity = 0;
        std::uint64_t stamp = 0;
        bool runs = false;  // holds bspline_runs() (gpu_block.h), not the grid
    };
    std::unordered_map<std::uint64_t, Controls> controls;  // per key (lattice entity)
    std::uint64_t uploads = 0;
    // Limits queried once (a glGet can stall a threaded driver). GL_MAX_UNIFORM_BLOCK_SIZE is read from
    // gfx::limits() instead, which tests shrink (gfx::ScopedLimits) to run the SSBO kernel on small lattices.
    GLint max_shared = 0;   // GL_MAX_COMPUTE_SHARED_MEMORY_SIZE
    GLint ubo_align = 256;  // GL_UNIFORM_BUFFER_OFFSET_ALIGNMENT (GL 4.5's largest allowed value)
    bool software = false;  // gfx::software_rasterizer(), for GpuBernsteinKernel::automatic
    GpuBernsteinKernel kernel = GpuBernsteinKernel::automatic, last_kernel = GpuBernsteinKernel::automatic;

    // Compiles the generic program and creates the block UBO (context current).
    static Result<DeformPrograms> create(std::string shader, std::string program_label, std::string prefix);

    // What one deform shader specialises beyond the lattice (the Gaussian deformer: which outputs a
    // dispatch writes; none: nullptr): `id` (< 2^16) tells the programs apart, `defines` make them, `label`
    // is appended to the program's label.
    struct Variant {
        std::uint32_t id = 0;
        gfx::Defines defines;
        std::string label;
    };
    struct Bound {
        GLuint program = 0;
        std::uint32_t local_size = 64;  // deform.comp's FFD_LOCAL_SIZE
        FfdBlock block{};               // uploaded by dispatch_batches(), one copy per batch
    };
    // Prepares the block for `count` points, uploads the control points of `key` when `stamp` moved (0:
    // always), picks the program and binds it with the control points (SFFD_SSBO_CONTROL_POINTS,
    // SFFD_UBO_FFD_CONTROL). The lattice must be valid.
    Result<Bound> bind(const Lattice& lattice, std::uint64_t key, std::uint64_t stamp,
                       const glm::dvec3& cloud_origin, std::uint32_t count, const Variant* variant = nullptr);
    // After bind(): the dispatch of `count` points in batches of element ranges (runtime/gfx/ssbo_batch.h;
    // more than one only when a buffer of byte `strides` per point exceeds GL_MAX_SHADER_STORAGE_BLOCK_SIZE).
    // With `ranges` (ascending point ranges that start on a page, page_runs()), only their points: each is
    // cut into batches the same way. Every batch's block (its own count, and the cloud index of its first
    // point, which the per-page counters read) goes into fresh UBO storage in one upload, each bound by
    // range at SFFD_UBO_FFD: no write lands in storage that an issued dispatch reads. `bind_batch` binds
    // the per-point buffers for each batch (its `first` is the cloud index). Fails, dispatching nothing,
    // when no batch fits (the message names the limit).
    Status dispatch_batches(const Bound& bound, std::uint32_t count, std::span<const std::uint64_t> strides,
                            const std::function<void(const gfx::SsboBatch&)>& bind_batch,
                            std::span<const gfx::SsboBatch> ranges = {});
    void retain_keys(const std::vector<std::uint64_t>& live);
};

// The per-page counters of the deform passes (shaders/ffd/page_stats.glsl): `words` counters, `per_page` a
// page, summed into out[0..per_page).
void sum_page_counters(const std::uint32_t* counters, std::size_t words, std::size_t per_page,
                       std::uint32_t* out);
// Reads `words` counters of `buffer` back (waits for the GPU) and sums them as sum_page_counters().
void read_page_counters(GLuint buffer, std::size_t words, std::size_t per_page, std::uint32_t* out);

// queue_stats()/poll_stats(): the statistics buffer's `words` counters copied into persistently mapped
// host buffers behind fences (a copy to host memory, not a video-to-host migration); a slot is free when
// its fence is null.
class StatsReadbacks {
public:
    StatsReadbacks() = default;
    StatsReadbacks(StatsReadbacks&&) noexcept = default;
    StatsReadbacks& operator=(StatsReadbacks&&) noexcept = default;
    StatsReadbacks(const StatsReadbacks&) = delete;
    StatsReadbacks& operator=(const StatsReadbacks&) = delete;
    ~StatsReadbacks();

    // false: no slot, and these statistics are lost: every one of the kMaxSlots is still in flight (a
    // loop with no swap to hold it back, far ahead of the GPU) or mapping failed (the GL error callback
    // has said why). Capped, so such a loop neither maps a buffer every frame nor grows without bound.
    static constexpr std::size_t kMaxSlots = 8;
    bool queue(GLuint stats, std::size_t words, std::uint64_t tag, const std::string& label);
    // Calls done(tag, counters, words) for each queued copy whose fence has signalled; never waits, and
    // flushes the command stream only when every slot is in flight (see signalled()).
    template <class Done>
    void poll(Done&& done) {
        const bool flush = pending() >= kMaxSlots;
        for (Slot& r : m_slots)
            if (r.fence && signalled(r, flush)) done(r.tag, r.mapped, r.words);
    }
    std::size_t pending() const;

private:
    struct Slot {
        gfx::Buffer buffer;
        const std::uint32_t* mapped = nullptr;
        std::size_t capacity = 0;  // words the buffer holds
        std::size_t words = 0;     // words of the queued copy
        GLsync fence = nullptr;
        std::uint64_t tag = 0;
    };
    // Deletes the fence (frees the slot) when it has signalled. A fence reaches the GPU with the frame's
    // next flush (a swap, a read-back, the profiler's frame pacing); asking with the flush bit every frame
    // made the deformation's own CPU time pay for a flush, so only a loop that never flushes (every slot
    // in flight) gets one, or its fences might never signal.
    static bool signalled(Slot& r, bool flush);
    std::vector<Slot> m_slots;
};

}  // namespace sffd::ffd::detail
