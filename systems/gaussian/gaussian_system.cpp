#include "systems/gaussian/gaussian_system.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/parallel_for.h>

#include "runtime/app/pass_timer.h"
#include "runtime/core/log.h"
#include "runtime/gfx/residency.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform_backend.h"
#include "systems/ffd/deform_inputs.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/lattice_frame.h"
#include "systems/ffd/preview_budget.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gpu_deform.h"
#include "systems/gaussian/gpu_store.h"
#include "systems/gaussian/gpu_upload.h"

namespace sffd {

namespace {

using GaussianGpuState = ffd::GpuDeformerState<gaussian::GpuGaussianDeformer>;

// Counts of earlier GPU runs that have arrived (never waits): they apply to the output they were counted
// for if it has not been rewritten since. Statistics, not data: no change stamp.
void collect_gpu_stats(ecs::Registry& reg) {
    auto* st = reg.try_resource<GaussianGpuState>();
    if (!st) return;
    st->collect([&](const GaussianGpuState::Pending& p, const gaussian::GpuDeformStats& stats) {
        if (stats.not_finite)
            log::warn("gaussian_deform_system: ", stats.not_finite,
                      " Gaussians deformed to non-finite values (drawn transparent)");
        DeformedGaussians* out = reg.valid(p.cloud) ? reg.try_get<DeformedGaussians>(p.cloud) : nullptr;
        if (!out || out->version != p.version) return;
        out->inverted = stats.inverted;
        out->degenerate = stats.degenerate;
        out->not_finite = stats.not_finite;
        out->stats_arrived = true;
    });
}

// The Gaussians `indices` of `cloud` (opacities and SH with them), their scales enlarged by sqrt(n / k) so
// the fewer Gaussians cover the area the whole cloud covers. Without the surface splats' margin
// (preview_radius_scale): a Gaussian's edge fades instead of leaving a hard hole, and the blending's cost
// is its area (measured: 1.4x the scale took the 1M preview's Gaussian pass from 0.8 to 3.5 s here).
// Only the DC term of the SH is kept (degree 0): a moving preview shows each Gaussian's base colour, and
// neither the deformation (no SH rotation), the upload (3 floats instead of up to 48) nor the projection
// evaluates the view-dependent terms; the next still frame draws the full degree again.
GaussianCloud preview_gaussians(const GaussianCloud& cloud, const std::vector<std::uint32_t>& indices) {
    const std::size_t k = indices.size(), n = cloud.size();
    const auto coeffs = std::size_t(sh_coeffs(cloud.sh_degree)) * 3;
    constexpr std::size_t kDc = 3;  // sh[(i*K + 0)*3 + c]: the DC term's RGB leads each Gaussian's block
    const float scale = k == 0 || k >= n ? 1.0f : float(std::sqrt(double(n) / double(k)));
    GaussianCloud out;
    out.origin = cloud.origin;
    out.sh_degree = 0;
    out.positions.resize(k), out.scales.resize(k), out.rotations.resize(k), out.opacities.resize(k);
    out.sh.resize(cloud.sh.size() == n * coeffs ? k * kDc : 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, k, 1 << 13), [&](const auto& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
            const std::size_t j = indices[i];
            out.positions[i] = cloud.positions[j];
            out.scales[i] = cloud.scales[j] * scale;
            out.rotations[i] = cloud.rotations[j];
            out.opacities[i] = cloud.opacities[j];
            if (!out.sh.empty())
                std::copy_n(cloud.sh.begin() + std::ptrdiff_t(j * coeffs), kDc,
                            out.sh.begin() + std::ptrdiff_t(i * kDc));
        }
    });
    return out;
}

}  // namespace

void gaussian_release_gpu(ecs::Registry& registry) { registry.erase_resource<GaussianGpuState>(); }

void gaussian_deform_system(ecs::Registry& reg, const FrameContext&) {
    // The backend choice of ffd_system (systems/ffd/deform_backend.h).
    const ffd::DeformBackend backend = ffd::choose_deform_backend(reg.try_resource<FfdSettings>());
    const bool have_gl = backend.have_gl, force_cpu = backend.force_cpu;
    const GaussianDeformSettings* settings = reg.try_resource<GaussianDeformSettings>();
    const gaussian::ShMode gpu_sh = settings ? settings->gpu_sh : gaussian::ShMode::rotate_view;
    const gaussian::ShMode cpu_sh = settings ? settings->cpu_sh : gaussian::ShMode::rotate_coefficients;
    GaussianDeformStats* counters = reg.try_resource<GaussianDeformStats>();
    if (!counters) counters = &reg.set_resource<GaussianDeformStats>();
    if (have_gl) collect_gpu_stats(reg);
    // Collect first: emplacing DeformedGaussians while iterating is a structural change.
    std::vector<ecs::Entity> clouds;
    reg.view<const GaussianCloud, const Deformers>().each(
        [&](ecs::Entity e, const GaussianCloud&, const Deformers&) { clouds.push_back(e); });
    for (ecs::Entity e : clouds) {
        const GaussianCloud& cloud = reg.get<GaussianCloud>(e);
        const ffd::DeformInputs inputs = ffd::deform_inputs<GaussianCloud>(reg, e);
        // The cloud's residency (residency_system uploaded its rest cloud this frame when it changed): the
        // GPU path needs it current, the CPU path uploads its output there.
        gaussian::GpuGaussianStore* store =
            have_gl ? reg.try_resource<gaussian::GpuGaussianStore>() : nullptr;
        gaussian::GpuGaussians* resident = nullptr;
        if (store)
            if (auto it = store->clouds.find(e); it != store->clouds.end() && it->second.rest &&
                                                 it->second.rest_version == inputs.stamps.cloud &&
                                                 it->second.count == cloud.size())
                resident = &it->second;
        const DeformedGaussians* seen = reg.try_get<DeformedGaussians>(e);
        const bool gpu_path = backend.gpu();
        const auto sh_mode = std::uint8_t(gpu_path ? gpu_sh : cpu_sh);
        // A budgeted preview (ffd/preview_budget.h) on the CPU path of a resident cloud.
        const std::uint32_t budget =
            resident && !gpu_path ? gaussian_preview_budget_for(reg, cloud.size()) : 0;
        // A resident cloud at rest has no deformed data yet (its entry is new): deform even if nothing moved.
        // A full output serves every frame; a preview one only preview frames.
        if (seen && seen->seen == inputs.stamps && seen->seen_force_cpu == force_cpu &&
            seen->seen_sh_mode == sh_mode && (!resident || resident->is_deformed()) &&
            (!seen->preview || budget > 0))
            continue;  // nothing moved
        if (!seen) reg.emplace<DeformedGaussians>(e);
        DeformedGaussians& out = reg.patch<DeformedGaussians>(e);
        // Every path below reads the lattices in the cloud's frame (systems/ffd/lattice_frame.h).
        const ffd::CloudLattices framed = ffd::cloud_lattices(reg, e, inputs.lattices);
        out.seen = inputs.stamps;
        out.seen_force_cpu = force_cpu;
        out.seen_sh_mode = sh_mode;
        out.inverted = out.degenerate = out.not_finite = 0;
        out.stats_arrived = false;
        ++out.version;

        out.preview = budget > 0;
        if (budget > 0) {
            // Only the subset, enlarged; every Gaussian is deformed again by the next full frame.
            update_preview_subset(out.subset, cloud.positions, inputs.stamps.cloud, budget);
            GaussianCloud kept = preview_gaussians(cloud, out.subset.indices);
            for (const Lattice* l : framed.lattices)
                if (auto st = gaussian::deform(
                        *l, kept, kept,
                        {ffd::Backend::automatic, true, gaussian::ShMode::rotate_coefficients});
                    !st)
                    log::warn("gaussian_deform_system: ", st.message(), " (lattice skipped)");
            out.on_gpu = false;
            out.cloud = GaussianCloud{};
            out.cloud.origin = cloud.origin;
            out.cloud.sh_degree = cloud.sh_degree;
            out.stats_arrived = false;
            gaussian::upload_preview(*resident, kept);
            if (auto* rs = reg.try_resource<gfx::ResidencyStats>()) ++rs->deformed_uploads;
            ++counters->preview_runs;
            continue;
        }

        // GPU path: residency_system uploaded the authored cloud into GpuGaussianStore::rest this frame
        // when its change stamp moved; one dispatch per lattice into `deformed` (+ `frames` or
        // `deformed_sh` when the SH have view-dependent terms). No read-back.
        if (gpu_path && resident) {
            if (gaussian::GpuGaussianDeformer* gpu =
                    ffd::gpu_deformer<gaussian::GpuGaussianDeformer>(reg, "gaussian_deform_system")) {
                const std::vector<const Lattice*>& ls = framed.lattices;
                std::vector<std::uint64_t> keys;
                for (ecs::Entity le : framed.entities) keys.push_back(le.bits());
                auto pass_scope = profiling::gpu_scope(reg, "gaussian.deform");
                gpu->reset_stats();
                if (Status s = gpu->deform(*resident, cloud.origin, ls, keys, inputs.stamps.lattices, gpu_sh);
                    !s)
                    log::warn("gaussian_deform_system: ", s.message(), " (lattice skipped)");
                // The counts arrive a few frames later (collect_gpu_stats); nothing waits for them.
                reg.resource<GaussianGpuState>().queue_stats(*gpu, e, out.version);
                out.on_gpu = true;
                out.cloud = GaussianCloud{};
                out.cloud.origin = cloud.origin;
                out.cloud.sh_degree = cloud.sh_degree;
                ++counters->gpu_runs, counters->gpu_sync_readbacks = gpu->sync_readbacks();
                continue;
            }
        }

        // CPU path (TBB).
        out.on_gpu = false;
        // The first lattice reads the authored cloud and writes the output, with no copy of the cloud before
        // it: the SH coefficients are most of a Gaussian's bytes (192 of 236 at degree 3), and the copy was a
        // whole extra read and write of them, in memory for a large cloud. Later lattices deform the output
        // in place. Opacities are carried only so that Gaussians whose result is not finite can be made
        // transparent (as the GPU pass does); dropped again when none was (readers use the authored
        // cloud's: a deformation never changes them).
        auto copy_authored = [&] {  // the output before any lattice, where the first one failed
            out.cloud.origin = cloud.origin;
            out.cloud.sh_degree = cloud.sh_degree;
            out.cloud.positions = cloud.positions;
            out.cloud.scales = cloud.scales;
            out.cloud.rotations = cloud.rotations;
            out.cloud.sh = cloud.sh;
            out.cloud.opacities = cloud.opacities;
            out.cloud.sh_frames.clear();
        };
        bool written = false;
        for (const Lattice* l : framed.lattices) {
            auto stats = gaussian::deform(*l, written ? out.cloud : cloud, out.cloud,
                                          {ffd::Backend::automatic, true, cpu_sh});
            if (!stats) {
                log::warn("gaussian_deform_system: ", stats.message(), " (lattice skipped)");
                if (!written) copy_authored();  // it may have written part of the output
                written = true;
                continue;
            }
            written = true;
            out.inverted += stats->inverted;
            out.degenerate += stats->degenerate;
            out.not_finite += stats->not_finite;
        }
        if (!written) copy_authored();
        if (out.not_finite)
            log::warn("gaussian_deform_system: ", out.not_finite,
                      " Gaussians deformed to non-finite values (drawn transparent)");
        else out.cloud.opacities.clear();
        out.stats_arrived = true;
        // The resident cloud draws this output from now on (state deformed_cpu).
        if (resident) {
            gaussian::upload_cpu_deformed(*resident, out, cloud);
            if (auto* rs = reg.try_resource<gfx::ResidencyStats>()) ++rs->deformed_uploads;
        }
        ++counters->cpu_runs;
    }
}

}  // namespace sffd
