// GPU FFD deformer: the compute pass shaders/ffd/deform.comp plus its lattice uniform block and
// control-point buffer. Needs a current GL 4.5 context for every call (create_headless() makes one).
//
// ffd_system uses dispatch() on GpuSplatStore buffers (no CPU round trip) and queue_stats()/poll_stats()
// for its statistics (they arrive a few frames late, nothing waits); tests and `splatffd deform --backend
// gpu` use deform(), which uploads CPU arrays, dispatches and reads back.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/gfx/gl_object.h"
#include "runtime/gfx/residency.h"
#include "runtime/gfx/ssbo_batch.h"
#include "systems/ffd/deform.h"

namespace sffd::ffd {

// How the compute pass reads the control points (shaders/ffd/ffd_common.glsl, FFD_DP): the same
// arithmetic either way. Named for the dense Bernstein sum, where it matters most; the B-spline reads its
// zero-bordered grid the same ways (shared, or the SSBO when direct), or packed.
enum class GpuBernsteinKernel {
    automatic,  // Bernstein: shared on hardware GPUs, direct on a software rasterizer (llvmpipe: barrier()
                // is costly); B-spline: packed
    direct,  // every invocation reads them from a UBO (when they fit GL_MAX_UNIFORM_BLOCK_SIZE) or the SSBO
    shared,  // copied into shared memory once per 256-wide work group (when xyz fit
             // GL_MAX_COMPUTE_SHARED_MEMORY_SIZE, >= 32 KB: up to 2,730 points; otherwise direct, and
             // packed for a B-spline)
    packed,  // B-spline: each run of 4 grid points along the third axis stored as three vec4 (their x, y,
             // z), so a splat's 64 points take 48 loads instead of 64; Bernstein: direct
};

// Which points a dispatch deforms and where it counts: `ranges`, ascending point ranges that start on a
// page (page_runs(); empty: all `count`), and `stats`, the cloud's per-page counters
// (resident_page_stats(), GpuDeformer::kCounters a page; 0: the deformer's own, which reset_stats() clears).
struct DispatchPages {
    std::span<const gfx::SsboBatch> ranges;
    GLuint stats = 0;
};

class GpuDeformer {
public:
    // Compiles the compute program (context must be current).
    static Result<GpuDeformer> create();
    // Creates and owns a headless EGL context first (command-line use).
    static Result<GpuDeformer> create_headless();

    GpuDeformer(GpuDeformer&&) noexcept;
    GpuDeformer& operator=(GpuDeformer&&) noexcept;
    ~GpuDeformer();

    static constexpr std::size_t kCounters = 2;  // per page: inverted, inside
    using Pages = DispatchPages;
    // Deforms `count` GpuSplats from buffer `in` into `out` (may be the same buffer: in place) with the
    // lattice. Each `key` (e.g. the lattice entity) has its own control-point buffer, uploaded only when
    // `lattice_stamp` differs from its last upload (stamp 0 always uploads). Positions in the buffers are
    // relative to `cloud_origin`. `weights` (0 = none): float[count], the cloud's per-point weights
    // (resident_weights()), read by a program of their own (FFD_WEIGHTS). Does not wait for the GPU.
    Status dispatch(const Lattice& lattice, std::uint64_t key, std::uint64_t lattice_stamp,
                    const glm::dvec3& cloud_origin, GLuint in, GLuint out, std::uint32_t count,
                    GLuint weights = 0, const DispatchPages& pages = DispatchPages());
    // Single-lattice form (key 0), kept for callers written against the first version of this API.
    Status dispatch(const Lattice& lattice, std::uint64_t lattice_stamp, const glm::dvec3& cloud_origin,
                    GLuint in, GLuint out, std::uint32_t count) {
        return dispatch(lattice, 0, lattice_stamp, cloud_origin, in, out, count);
    }
    // Forgets control-point buffers whose key is not in `live` (lattices that were destroyed).
    void retain_keys(const std::vector<std::uint64_t>& live);
    // Inverted/inside counts accumulated since the last reset (reads back 8 bytes: waits for the GPU).
    // Not for the frame path: use queue_stats()/poll_stats() there.
    DeformStats read_stats();
    void reset_stats();

    // Non-blocking statistics: queue_stats() copies the counts accumulated since reset_stats() into a
    // persistently mapped read-back buffer behind a fence and tags them; poll_stats() returns the tagged
    // counts whose fence has signalled, without waiting (glClientWaitSync with a zero timeout).
    struct TaggedStats {
        std::uint64_t tag = 0;
        DeformStats stats;
    };
    bool queue_stats(std::uint64_t tag);  // false: no read-back slot (mapping failed, reported by GL)
    // The same for a cloud's per-page counters (`words` of them), summed over its pages.
    bool queue_stats(std::uint64_t tag, GLuint page_stats, std::size_t words);
    std::vector<TaggedStats> poll_stats();
    std::size_t pending_stats() const;
    // Synchronous read-backs so far (read_stats(), deform()): ffd_system's frame path must cause none.
    std::uint64_t sync_readbacks() const;

    // CPU arrays in and out (upload, dispatch, read back). Same contract as ffd::deform(), weights
    // included.
    Result<DeformStats> deform(const Lattice& lattice, const PointsIn& in, const PointsOut& out);
    // How many times dispatch() uploaded control points (tests check edits upload, unchanged frames don't).
    std::uint64_t upload_count() const;

    // Kernel choice for later dispatches (default automatic), and the kernel the last dispatch ran (direct
    // or shared; automatic before any).
    void set_bernstein_kernel(GpuBernsteinKernel kernel);
    GpuBernsteinKernel last_bernstein_kernel() const;

private:
    struct Impl;
    explicit GpuDeformer(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> m_impl;
};

// The weight column of a resident cloud on the GPU (both kinds): `weights` (PointWeights::values, one per
// point, or empty) in `cloud.weights`, uploaded when `key` (the stamps it is of) moved, released when the
// cloud has no weights (a cloud without weights holds no buffer and runs the unweighted programs). Returns
// the buffer the deform passes bind, 0 when there is none. Context current.
GLuint resident_weights(gfx::ResidentCloud& cloud, std::span<const float> weights, std::uint64_t key);

// The point ranges of a cloud of `count` points that `pages` (ascending page indices, point_pages.h) cover,
// adjacent pages merged: what a page-wise GPU redo dispatches.
std::vector<gfx::SsboBatch> page_runs(std::span<const std::uint32_t> pages, std::size_t count);
// The cloud's per-page counters of the compute deformations (`per_page` a page for `pages` pages), made
// zeroed when missing or of another size: false then (the counts of pages not redone are lost, so the
// caller redoes every page). Context current.
bool resident_page_stats(gfx::ResidentCloud& cloud, std::size_t pages, std::size_t per_page);
// Zeros the counters of the pages `ranges` cover, before they are deformed again.
void clear_page_stats(const gfx::ResidentCloud& cloud, std::span<const gfx::SsboBatch> ranges,
                      std::size_t per_page);

}  // namespace sffd::ffd
