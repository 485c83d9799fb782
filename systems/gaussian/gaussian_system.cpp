#include "systems/gaussian/gaussian_system.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/parallel_for.h>

#include "runtime/app/pass_timer.h"
#include "runtime/core/log.h"
#include "runtime/gfx/residency.h"
#include "runtime/scene/point_columns.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform_backend.h"
#include "systems/ffd/deform_inputs.h"
#include "systems/ffd/deform_skeleton.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/ffd/lattice.h"
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

// The cloud's per-Gaussian weights (runtime/scene/point_columns.h) when it has one per Gaussian, else null
// (weight 1: the unweighted code).
const float* weights_of(const ecs::Registry& reg, ecs::Entity e, std::size_t n) {
    const PointWeights* w = reg.try_get<PointWeights>(e);
    return w && n > 0 && w->values.size() == n ? w->values.data() : nullptr;
}

}  // namespace

void gaussian_release_gpu(ecs::Registry& registry) { registry.erase_resource<GaussianGpuState>(); }

namespace {

struct GaussianSettings {
    ffd::DeformBackend backend;
    gaussian::ShMode gpu_sh = gaussian::ShMode::rotate_view;
    gaussian::ShMode cpu_sh = gaussian::ShMode::rotate_coefficients;
    gaussian::GpuGaussianStore* store = nullptr;  // when a GL context is current
    std::uint8_t sh_mode() const { return std::uint8_t(backend.gpu() ? gpu_sh : cpu_sh); }
};

// Page p's statistics slots in DeformPageRecord::counts.
enum : std::size_t { kInverted, kDegenerate, kNotFinite };

// The Gaussian kind of the deformation skeleton (systems/ffd/deform_skeleton.h).
struct GaussianKind {
    using Cloud = GaussianCloud;
    using Output = DeformedGaussians;
    using Resident = gaussian::GpuGaussians;
    using Stats = GaussianDeformStats;

    static constexpr PointColumn kReads[] = {PointColumn::position, PointColumn::scale, PointColumn::rotation,
                                             PointColumn::sh};
    static std::span<const PointColumn> reads() { return kReads; }
    // The cloud's residency when residency_system uploaded its current rest cloud (the GPU path reads it,
    // the CPU path uploads its output there).
    static Resident* resident(ecs::Registry&, ecs::Entity e, const GaussianCloud& cloud,
                              std::uint64_t version, const GaussianSettings& st) {
        if (!st.store) return nullptr;
        auto it = st.store->clouds.find(e);
        if (it != st.store->clouds.end() && it->second.rest && it->second.rest_version == version &&
            it->second.count == cloud.size())
            return &it->second;
        return nullptr;
    }
    static bool options_match(const Output& out, const GaussianSettings& st) {
        return out.seen_force_cpu == st.backend.force_cpu && out.seen_sh_mode == st.sh_mode();
    }
    // A budgeted preview (ffd/preview_budget.h) on the CPU path of a resident cloud.
    static std::uint32_t budget(ecs::Registry& reg, const GaussianCloud& cloud, const Resident* resident,
                                const GaussianSettings& st) {
        return resident && !st.backend.gpu() ? gaussian_preview_budget_for(reg, cloud.size()) : 0;
    }
    static void begin(ecs::Registry&, ecs::Entity, Output& out, const GaussianCloud&,
                      const ffd::CloudLattices&, const GaussianSettings& st, GaussianDeformStats&) {
        out.seen_force_cpu = st.backend.force_cpu;
        out.seen_sh_mode = st.sh_mode();
        out.inverted = out.degenerate = out.not_finite = 0;
        out.stats_arrived = false;
    }
    static void empty_output(Output& out, const GaussianCloud& cloud) {
        out.cloud = GaussianCloud{};
        out.cloud.origin = cloud.origin;
        out.cloud.sh_degree = cloud.sh_degree;
    }

    // Only the subset, enlarged; every Gaussian is deformed again by the next full frame.
    static void preview(ecs::Registry& reg, ecs::Entity e, Output& out, const GaussianCloud& cloud,
                        const ffd::CloudLattices& framed, std::uint32_t budget, Resident& resident,
                        const GaussianSettings&, GaussianDeformStats& stats) {
        update_preview_subset(out.subset, cloud.positions, out.seen.cloud, budget);
        GaussianCloud kept = preview_gaussians(cloud, out.subset.indices);
        gaussian::DeformOptions options{ffd::Backend::automatic, true, gaussian::ShMode::rotate_coefficients};
        std::vector<float> kept_weights;  // the subset's weights, in its order
        if (const float* w = weights_of(reg, e, cloud.size())) {
            for (std::uint32_t i : out.subset.indices) kept_weights.push_back(w[i]);
            options.weights = kept_weights.data();
        }
        for (const Lattice* l : framed.lattices)
            if (auto st = gaussian::deform(*l, kept, kept, options); !st)
                log::warn("gaussian_deform_system: ", st.message(), " (lattice skipped)");
        empty_output(out, cloud);
        gaussian::upload_preview(resident, kept, out.subset.indices);
        if (auto* rs = reg.try_resource<gfx::ResidencyStats>()) ++rs->deformed_uploads;
        ++stats.preview_runs;
    }

    // GPU path: residency_system uploaded the authored cloud into GpuGaussianStore::rest this frame when its
    // change stamp moved; one dispatch per lattice into `deformed` (+ `frames` or `deformed_sh` when the SH
    // have view-dependent terms), over the pages the rule asks for when it builds on this path's own last
    // output, else over the whole cloud. No read-back.
    static bool gpu(ecs::Registry& reg, ecs::Entity e, Output& out, const GaussianCloud& cloud,
                    const ffd::CloudLattices& framed, const ffd::DeformInputs& inputs,
                    const ffd::RedoPlan& plan, Resident* resident, const GaussianSettings& st,
                    GaussianDeformStats& stats) {
        if (!st.backend.gpu() || !resident) return false;
        gaussian::GpuGaussianDeformer* gpu =
            ffd::gpu_deformer<gaussian::GpuGaussianDeformer>(reg, "gaussian_deform_system");
        if (!gpu) return false;
        std::vector<std::uint64_t> keys;
        for (ecs::Entity le : framed.entities) keys.push_back(le.bits());
        auto pass_scope = profiling::gpu_scope(reg, "gaussian.deform");
        // The weight column, uploaded when the weights or the cloud changed (none without weights).
        const float* w = weights_of(reg, e, cloud.size());
        ffd::resident_weights(*resident,
                              w ? std::span<const float>(w, cloud.size()) : std::span<const float>(),
                              inputs.stamps.weights * 0x9E3779B97F4A7C15ull ^ inputs.stamps.cloud);
        const gaussian::GpuGaussianDeformer::Redo redo{plan.what != ffd::Redo::everything, plan.pages};
        std::size_t redone = 0;
        if (Status s = gpu->deform(*resident, cloud.origin, framed.lattices, keys, inputs.stamps.lattices,
                                   st.gpu_sh, redo, &redone);
            !s)
            log::warn("gaussian_deform_system: ", s.message(), " (lattice skipped)");
        // The counts arrive a few frames later (collect_gpu_stats); nothing waits for them.
        reg.resource<GaussianGpuState>().queue_stats(*gpu, e, out.version, resident->page_stats.id(),
                                                     resident->page_stats_words);
        empty_output(out, cloud);
        ++stats.gpu_runs, stats.gpu_sync_readbacks = gpu->sync_readbacks();
        stats.pages_redeformed += redone;
        stats.last_pages = {redone, page_count(cloud.size())};
        return true;
    }

    // CPU path (TBB), page by page. The first lattice reads the authored cloud and writes the output, with no
    // copy of the cloud before it: the SH coefficients are most of a Gaussian's bytes (192 of 236 at degree
    // 3), and the copy was a whole extra read and write of them. Later lattices deform the output in place.
    // Opacities are carried only so that Gaussians whose result is not finite can be made transparent (as
    // the GPU pass does); dropped again when none was (readers use the authored cloud's).
    static std::size_t cpu(ecs::Registry& reg, ecs::Entity e, Output& out, const GaussianCloud& cloud,
                           const ffd::CloudLattices& framed, const ffd::RedoPlan& plan, Resident* resident,
                           const GaussianSettings& st, GaussianDeformStats& stats) {
        const std::size_t n = cloud.size(), np = page_count(n);
        std::vector<const Lattice*> ok;
        for (const Lattice* l : framed.lattices)
            if (Status s = ffd::validate(*l); !s)
                log::warn("gaussian_deform_system: ", s.message(), " (lattice skipped)");
            else ok.push_back(l);
        gaussian::DeformOptions options{ffd::Backend::automatic, true, st.cpu_sh};
        options.weights = weights_of(reg, e, n);
        // A page-wise redo builds on an output with every Gaussian finite (no opacities carried).
        bool everything =
            plan.what == ffd::Redo::everything || !out.cloud.opacities.empty() || out.cloud.size() != n;
        auto run = [&](std::span<const std::uint32_t> pages) -> bool {
            out.paged.counts.resize(np, {0, 0, 0});
            for (std::uint32_t p : pages) {
                const PageRange r = page_range(p, n);
                auto& c = out.paged.counts[p];
                c = {0, 0, 0};
                bool written = false;
                for (const Lattice* l : ok) {
                    auto ds = gaussian::deform_range(*l, written ? out.cloud : cloud, out.cloud, options,
                                                     r.first, r.count);
                    if (!ds) {
                        log::warn("gaussian_deform_system: ", ds.message(), " (lattice skipped)");
                        return false;
                    }
                    written = true;
                    c[kInverted] += std::uint32_t(ds->inverted);
                    c[kDegenerate] += std::uint32_t(ds->degenerate);
                    c[kNotFinite] += std::uint32_t(ds->not_finite);
                }
            }
            return true;
        };
        bool done = false;
        std::size_t redone = 0;
        if (!everything && !ok.empty()) {
            done = run(plan.pages);
            redone = plan.pages.size();
            std::uint64_t bad = 0;
            for (const auto& c : out.paged.counts) bad += c[kNotFinite];
            if (bad) done = false;  // carry opacities: redo the whole cloud
        }
        if (!done && !ok.empty()) {
            // The output set up as gaussian::deform() sets it up, then every page.
            out.cloud.origin = cloud.origin;
            out.cloud.sh_degree = cloud.sh_degree;
            out.cloud.positions.resize(n), out.cloud.scales.resize(n), out.cloud.rotations.resize(n);
            out.cloud.sh.resize(cloud.sh.size());
            out.cloud.opacities = cloud.opacities;
            out.cloud.sh_frames = cloud.sh_frames;
            if (st.cpu_sh == gaussian::ShMode::rotate_view) out.cloud.sh_frames.assign(n, glm::mat3(1.0f));
            std::vector<std::uint32_t> all(np);
            for (std::size_t p = 0; p < np; ++p) all[p] = std::uint32_t(p);
            done = run(all);
            redone = np;
        }
        if (!done) {  // no lattice ran: the output is the authored cloud
            out.cloud = cloud;
            out.paged.counts.assign(np, {0, 0, 0});
        }
        for (const auto& c : out.paged.counts)
            out.inverted += c[kInverted], out.degenerate += c[kDegenerate], out.not_finite += c[kNotFinite];
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
        ++stats.cpu_runs;
        return redone;
    }
};

}  // namespace

bool gaussian::output_on_gpu(const ecs::Registry& reg, ecs::Entity e) {
    const auto* store = reg.try_resource<gaussian::GpuGaussianStore>();
    if (!store) return false;
    auto it = store->clouds.find(e);
    return it != store->clouds.end() && it->second.state == gfx::Residency::deformed_gpu;
}

void gaussian_deform_system(ecs::Registry& reg, const FrameContext&) {
    // The backend choice of ffd_system (systems/ffd/deform_backend.h).
    GaussianSettings st;
    st.backend = ffd::choose_deform_backend(reg.try_resource<FfdSettings>());
    if (const auto* settings = reg.try_resource<GaussianDeformSettings>())
        st.gpu_sh = settings->gpu_sh, st.cpu_sh = settings->cpu_sh;
    GaussianDeformStats* counters = reg.try_resource<GaussianDeformStats>();
    if (!counters) counters = &reg.set_resource<GaussianDeformStats>();
    if (st.backend.have_gl) {
        collect_gpu_stats(reg);
        st.store = reg.try_resource<gaussian::GpuGaussianStore>();
    }
    ffd::run_deformation<GaussianKind>(reg, st, *counters);
}

}  // namespace sffd
