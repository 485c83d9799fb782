// GPU deformation of 3D Gaussians: the compute pass shaders/gaussian/deform.comp over the
// GpuGaussianStore buffers (gpu_store.h). Per Gaussian and per lattice, in order: centre through the
// lattice, Σ' = J Σ Jᵀ back to rotation + scale (one-sided Jacobi on the deformed axes J R S, in float),
// opacity carried, and the polar rotation of J either composed into `frames` (ShMode::rotate_view:
// the coefficients stay as authored, the renderer evaluates the SH at frameᵀ d) or applied to the SH
// coefficients. The SH coefficients
// themselves can be rotated instead (ShMode::rotate_coefficients: per band, the CPU's sh_rotation tables)
// into `deformed_sh`.
// The lattice evaluation is the ffd pass's own (shaders/ffd/ffd_common.glsl: Bernstein with the direct
// or shared-memory kernel, B-spline), with the same lattice set-up and control-point upload
// (systems/ffd/gpu_kernel.h). Needs a current GL 4.5 context for every call.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "runtime/core/result.h"
#include "runtime/gfx/gl_object.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gpu_store.h"
#include "systems/gaussian/gpu_upload.h"

namespace sffd::gaussian {

struct GpuDeformStats {
    std::size_t inside = 0;      // Gaussian × lattice pairs inside the lattice
    std::size_t inverted = 0;    // det J < 0
    std::size_t degenerate = 0;  // |det J| <= 1e-12 ‖J‖³ (the CPU's rule): frame left as it was
    std::size_t not_finite = 0;  // results that were not finite: written with opacity 0 and scale 0
};

// upload_rest() (the authored cloud into the store's rest/sh) is in gpu_upload.h.

// What GpuGaussianDeformer::deform() redoes: every page, or with `page_wise` only `pages` (ascending page
// indices, runtime/scene/point_pages.h) on top of the cloud's own last GPU output.
struct GpuRedo {
    bool page_wise = false;
    std::span<const std::uint32_t> pages;
};

class GpuGaussianDeformer {
public:
    // Compiles the compute program (context must be current).
    static Result<GpuGaussianDeformer> create();

    GpuGaussianDeformer(GpuGaussianDeformer&&) noexcept;
    GpuGaussianDeformer& operator=(GpuGaussianDeformer&&) noexcept;
    ~GpuGaussianDeformer();

    // The buffers of one dispatch. `in`/`out` GpuGaussian[count] (may be the same buffer: in place).
    // `frames` (vec4[3 * count], 0 = none) receives the polar rotations, composed onto what it holds when
    // `compose_frames`, else starting from identity. `sh_out` (0 = none): the coefficients of `sh_in`
    // (GaussianCloud::sh layout, degree `sh_degree`, 1..3) rotated by the polar rotation (may equal `sh_in`).
    // Each combination of frames and coefficients runs its own program (the code of unwritten outputs left
    // out).
    struct Buffers {
        GLuint in = 0, out = 0;
        GLuint frames = 0;
        bool compose_frames = false;
        GLuint sh_in = 0, sh_out = 0;
        int sh_degree = 0;
        // float[count] per-Gaussian weights (0 = none: the unweighted program): the centre moves by w D and
        // shape and SH follow J_w = I + w (J − I) (a program of its own, FFD_WEIGHTS).
        GLuint weights = 0;
        // The cloud's per-page counters (kCounters a page, ffd::resident_page_stats()), added to.
        GLuint stats = 0;
    };
    static constexpr std::size_t kCounters = 4;  // per page: inverted, inside, not finite, degenerate
    // One lattice over `count` Gaussians, positions relative to `cloud_origin`. Each `key` (e.g. the
    // lattice entity) keeps its control points, uploaded only when `lattice_stamp` moved (0 always
    // uploads). Does not wait for the GPU.
    // `ranges`: only these points (ascending, each starting on a page: ffd::page_runs()); empty: all.
    Status dispatch(const Lattice& lattice, std::uint64_t key, std::uint64_t lattice_stamp,
                    const glm::dvec3& cloud_origin, const Buffers& buffers, std::uint32_t count,
                    std::span<const gfx::SsboBatch> ranges = {});

    // Every lattice in order over a store entry whose `rest` (and `sh`) are current: writes `deformed`
    // (grown when needed) and, when the SH have view-dependent terms (degree > 0), `frames`
    // (ShMode::rotate_view) or `deformed_sh` (ShMode::rotate_coefficients); state deformed_gpu with
    // the matching sh_source, bumps deformed_version. The cloud's weights, when `dst.weights` holds them
    // (ffd::resident_weights()), weight every lattice's step. No read-back. `keys`/`stamps`
    // as in dispatch(), one per lattice. A lattice that fails validation is skipped (the first error is
    // returned after the others ran). The counts go into the cloud's per-page counters (`page_stats`).
    // With `redo.page_wise`, only `redo.pages` are deformed again, on top of what `deformed` holds: done
    // when that is this pass's own last output (state deformed_gpu, the same SH outputs and counters) and
    // every lattice is valid, else every page is. `pages_redone` (optional) says how many were.
    using Redo = GpuRedo;
    Status deform(GpuGaussians& dst, const glm::dvec3& cloud_origin,
                  const std::vector<const Lattice*>& lattices, const std::vector<std::uint64_t>& keys,
                  const std::vector<std::uint64_t>& stamps, ShMode sh, const GpuRedo& redo = GpuRedo(),
                  std::size_t* pages_redone = nullptr);

    // The cloud's counts, summed over its pages: read_stats() waits for the GPU (tests, commands).
    GpuDeformStats read_stats(const GpuGaussians& cloud);
    // Non-blocking statistics for the frame path (as ffd::GpuDeformer): queue_stats() copies `words`
    // per-page counters of `page_stats` into a persistently mapped buffer behind a fence, tagged;
    // poll_stats() returns their sums whose fence has signalled, never waiting. false: no read-back slot.
    struct TaggedStats {
        std::uint64_t tag = 0;
        GpuDeformStats stats;
    };
    bool queue_stats(std::uint64_t tag, GLuint page_stats, std::size_t words);
    std::vector<TaggedStats> poll_stats();
    // Forgets control-point buffers whose key is not in `live`.
    void retain_keys(const std::vector<std::uint64_t>& live);
    // Bernstein kernel (ffd::GpuBernsteinKernel: automatic = shared on hardware GPUs, direct on llvmpipe).
    void set_bernstein_kernel(ffd::GpuBernsteinKernel kernel);
    ffd::GpuBernsteinKernel last_bernstein_kernel() const;
    std::uint64_t upload_count() const;    // control-point uploads so far
    std::uint64_t sync_readbacks() const;  // read_stats() calls so far (the frame path makes none)

private:
    struct Impl;
    explicit GpuGaussianDeformer(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> m_impl;
};

// Read-back for tests and commands (waits for the GPU): the Gaussians `src` draws (deformed when
// deformed, else rest) as a GaussianCloud with `origin`: positions, scales, rotations, opacities, the
// SH (sh_buffer()) and sh_frames when has_frames().
Result<GaussianCloud> read_back(const GpuGaussians& src, const glm::dvec3& origin);

// Upload + deform through every lattice + read back, on a scratch store entry (tests, commands, the
// benchmark's correctness check): rotate_view gives the result sh_frames (degree > 0), rotate_coefficients
// rotated sh. `weights`: one per Gaussian (PointWeights::values), or empty.
Result<GaussianCloud> deform_on_gpu(GpuGaussianDeformer& deformer,
                                    const std::vector<const Lattice*>& lattices, const GaussianCloud& cloud,
                                    ShMode sh, GpuDeformStats* stats = nullptr,
                                    std::span<const float> weights = {});

}  // namespace sffd::gaussian
