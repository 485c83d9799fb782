#include "systems/ffd/ffd_system.h"

#include <algorithm>
#include <string_view>
#include <utility>
#include <vector>

#include "runtime/app/pass_timer.h"
#include "runtime/core/log.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/residency.h"
#include "runtime/gfx/splat_store.h"
#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_pages.h"
#include "shaders/common/bindings.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform_backend.h"
#include "systems/ffd/deform_cloud.h"
#include "systems/ffd/deform_inputs.h"
#include "systems/ffd/deform_skeleton.h"
#include "systems/ffd/ffd_gpu.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/lattice_frame.h"
#include "systems/ffd/preview_budget.h"

namespace sffd {

namespace {

using FfdGpuState = ffd::GpuDeformerState<ffd::GpuDeformer>;

// Inverted counts of earlier GPU runs that have arrived (never waits): each applies if it is newer than
// the count the output holds.
void collect_gpu_stats(ecs::Registry& reg) {
    auto* st = reg.try_resource<FfdGpuState>();
    if (!st) return;
    st->collect([&](const FfdGpuState::Pending& p, const ffd::DeformStats& stats) {
        DeformedSplats* out = reg.valid(p.cloud) ? reg.try_get<DeformedSplats>(p.cloud) : nullptr;
        if (!out || p.version <= out->inverted_version) return;
        out->inverted = stats.inverted;  // statistics, not data: no change stamp
        out->inverted_version = p.version;
    });
}

}  // namespace

void ffd_release_gpu(ecs::Registry& registry) { registry.erase_resource<FfdGpuState>(); }

namespace {

struct SurfaceSettings {
    ffd::DeformBackend backend;
    gfx::GpuSplatStore* store = nullptr;  // when a GL context is current
};

// The cloud's per-point weights (runtime/scene/point_columns.h), read by every path; null when it has none.
const PointWeights* weights_of(const ecs::Registry& reg, ecs::Entity e) {
    const PointWeights* w = reg.try_get<PointWeights>(e);
    return w && !w->values.empty() ? w : nullptr;
}

// The surface kind of the deformation skeleton (deform_skeleton.h).
struct SurfaceKind {
    using Cloud = SplatCloud;
    using Output = DeformedSplats;
    using Resident = gfx::GpuSplats;
    using Stats = FfdStats;

    static constexpr PointColumn kReads[] = {PointColumn::position, PointColumn::frame};
    static std::span<const PointColumn> reads() { return kReads; }

    // The cloud's residency when residency_system uploaded its current rest splats (the GPU path reads
    // them, the CPU path uploads its output there).
    static Resident* resident(ecs::Registry&, ecs::Entity e, const SplatCloud& cloud, std::uint64_t version,
                              const SurfaceSettings& st) {
        if (!st.store) return nullptr;
        auto it = st.store->clouds.find(e);
        if (it != st.store->clouds.end() && it->second.rest && it->second.rest_version == version &&
            it->second.count == cloud.size())
            return &it->second;
        return nullptr;
    }
    static bool options_match(const Output& out, const SurfaceSettings& st) {
        return out.seen_force_cpu == st.backend.force_cpu;
    }
    // A budgeted preview (preview_budget.h) on the CPU path of a resident cloud (textured clouds index their
    // uv frames per splat, so they are always drawn whole).
    static std::uint32_t budget(ecs::Registry& reg, const SplatCloud& cloud, const Resident* splats,
                                const SurfaceSettings& st) {
        return splats && !st.backend.gpu() && cloud.texture.rgba8.empty()
                   ? preview_budget_for(reg, cloud.size())
                   : 0;
    }

    // Bounds from the control points only: the rest box (the pages' boxes, from one pass over the splats
    // when the cloud changes, cached) grown by each lattice's displacement hull, in order (never
    // under-covers), in the cloud's frame, then mapped to the world by the cloud's Transform (the renderer's
    // screen rectangle reads them there).
    static void begin(ecs::Registry& reg, ecs::Entity e, Output& out, const SplatCloud& cloud,
                      const ffd::CloudLattices& framed, const SurfaceSettings& st, FfdStats& stats) {
        out.origin = cloud.origin;
        out.seen_force_cpu = st.backend.force_cpu;
        const std::uint64_t cloud_v = out.seen.cloud;
        if (!out.has_rest_box || out.rest_box_cloud != cloud_v) {
            // The union of the pages' rest boxes (refresh_point_pages() computed them this frame, in the
            // same pass over the positions), finite points only.
            ffd::Box rest;
            const PointPages& pages = std::as_const(reg).get<PointPages>(e);
            for (std::size_t p = 0; p < pages.rest_lo.size(); ++p)
                if (!page_box_empty(pages, p)) rest.add(pages.rest_lo[p]), rest.add(pages.rest_hi[p]);
            out.rest_box_lo = rest.lo, out.rest_box_hi = rest.hi, out.rest_box_empty = rest.empty;
            out.has_rest_box = true, out.rest_box_cloud = cloud_v;
            ++stats.cpu_splat_passes;
        }
        ffd::Box box{out.rest_box_lo, out.rest_box_hi, out.rest_box_empty};
        for (const Lattice* l : framed.lattices)
            if (ffd::validate(*l).ok()) box = ffd::deformed_bounds(*l, box);
        box = ffd::world_box(box, model_matrix(reg.try_get<Transform>(e)));
        out.bounds_min = box.lo, out.bounds_max = box.hi;
    }

    // Only the subset, its splats enlarged; the rest is deformed by the next full frame.
    static void preview(ecs::Registry& reg, ecs::Entity e, Output& out, const SplatCloud& cloud,
                        const ffd::CloudLattices& framed, std::uint32_t budget, Resident& splats,
                        const SurfaceSettings& st, FfdStats& stats) {
        update_preview_subset(out.subset, cloud.positions, out.seen.cloud, budget);
        const std::vector<std::uint32_t>& kept = out.subset.indices;
        ffd::deform_cloud_subset(cloud, framed.span(), kept, out, "ffd_system", weights_of(reg, e));
        gfx::upload_preview_splats(splats, cloud, kept, {out.positions, out.normals, out.axis_u, out.axis_v},
                                   preview_radius_scale(cloud.size(), kept.size()), st.store->keep_cpu);
        if (auto* rs = reg.try_resource<gfx::ResidencyStats>()) ++rs->deformed_uploads;
        ++stats.preview_runs;
    }

    // The compute pass: over the pages the rule asks for when it builds on this path's own last output
    // (state deformed_gpu, the same per-page counters, every lattice valid), else over the whole cloud.
    // False when it cannot run (no residency, forced CPU, no deformer, no lattice dispatched).
    static bool gpu(ecs::Registry& reg, ecs::Entity e, Output& out, const SplatCloud& cloud,
                    const ffd::CloudLattices& framed, const ffd::DeformInputs& inputs,
                    const ffd::RedoPlan& plan, Resident* splats, const SurfaceSettings& st, FfdStats& stats) {
        if (!splats || st.backend.force_cpu) return false;
        ffd::GpuDeformer* gpu = ffd::gpu_deformer<ffd::GpuDeformer>(reg, "ffd_system");
        if (!gpu) return false;
        const std::size_t n = cloud.size(), np = page_count(n);
        constexpr std::size_t K = ffd::GpuDeformer::kCounters;
        const std::span<const Lattice* const> lattices = framed.span();
        bool paged = plan.what != ffd::Redo::everything && splats->state == gfx::Residency::deformed_gpu &&
                     std::all_of(lattices.begin(), lattices.end(),
                                 [](const Lattice* l) { return ffd::validate(*l).ok(); });
        paged = ffd::resident_page_stats(*splats, np, K) && paged;
        gfx::reserve_buffer(splats->deformed, "splats.deformed",
                            std::max<std::size_t>(n, 1) * sizeof(gpu::GpuSplat));
        auto pass_scope = profiling::gpu_scope(reg, "ffd.compute");  // names the pass for the profiler
        // The weight column, uploaded when the weights or the cloud changed (none without weights).
        const PointWeights* weights = weights_of(reg, e);
        const GLuint wbuf = ffd::resident_weights(
            *splats, weights ? std::span<const float>(weights->values) : std::span<const float>(),
            inputs.stamps.weights * 0x9E3779B97F4A7C15ull ^ inputs.stamps.cloud);
        const GLuint rest = splats->rest.id(), deformed = splats->deformed.id();
        auto copy = [&](std::span<const gfx::SsboBatch> ranges) {
            for (const gfx::SsboBatch& r : ranges)
                glCopyNamedBufferSubData(rest, deformed, GLintptr(r.first * sizeof(gpu::GpuSplat)),
                                         GLintptr(r.first * sizeof(gpu::GpuSplat)),
                                         GLsizeiptr(r.count * sizeof(gpu::GpuSplat)));
        };
        // Every lattice in order over `ranges`: the first reads the rest splats, the next ones the output in
        // place. A lattice that fails is skipped (logged); false when it fails on a page-wise run (the
        // pages left alone would no longer agree with the redone ones) or none could start the output.
        auto run = [&](std::span<const gfx::SsboBatch> ranges, bool page_wise) -> bool {
            if (ranges.empty()) return true;  // no page to redo (an empty range list means all to a dispatch)
            ffd::clear_page_stats(*splats, ranges, K);
            if (lattices.empty()) copy(ranges);
            GLuint in = rest;
            for (std::size_t d = 0; d < lattices.size(); ++d) {
                const ffd::GpuDeformer::Pages pages{ranges, splats->page_stats.id()};
                if (Status s =
                        gpu->dispatch(*lattices[d], framed.entities[d].bits(), inputs.stamps.lattices[d],
                                      cloud.origin, in, deformed, std::uint32_t(n), wbuf, pages);
                    !s) {
                    log::warn("ffd_system: ", s.message(), " (lattice skipped)");
                    if (page_wise) return false;
                    if (d == 0 && n == 0) return false;
                    if (d == 0) copy(ranges);
                }
                in = deformed;
            }
            return true;
        };
        const std::vector<gfx::SsboBatch> whole{{0, n}};
        std::vector<gfx::SsboBatch> ranges = paged ? ffd::page_runs(plan.pages, n) : whole;
        if (paged && !run(ranges, true)) paged = false, ranges = whole;
        if (!paged && !run(ranges, false)) return false;
        // The inverted count arrives a few frames later (collect_gpu_stats); until then `inverted` keeps the
        // latest count that arrived.
        reg.resource<FfdGpuState>().queue_stats(*gpu, e, out.version, splats->page_stats.id(),
                                                splats->page_stats_words);
        gfx::set_deformed(*splats, gfx::Residency::deformed_gpu);
        out.cpu_valid = false;
        out.positions.clear(), out.normals.clear(), out.axis_u.clear(), out.axis_v.clear();
        const std::size_t redone = paged ? plan.pages.size() : np;
        ++stats.gpu_runs, stats.gpu_sync_readbacks = gpu->sync_readbacks();
        stats.pages_redeformed += redone;
        stats.last_pages = {redone, np};
        return true;
    }

    // The one CPU deformation step (also what picking asks for), over the pages the rule asks for.
    static std::size_t cpu(ecs::Registry& reg, ecs::Entity e, Output& out, const SplatCloud& cloud,
                           const ffd::CloudLattices& framed, const ffd::RedoPlan& plan, Resident* splats,
                           const SurfaceSettings& st, FfdStats& stats) {
        // Pages are redone in place only into arrays shaped as a whole run shapes them (an edit that
        // dropped or added a column redoes everything).
        const std::size_t n = cloud.size();
        auto shaped = [n](const std::vector<glm::vec3>& o, const std::vector<glm::vec3>& a) {
            return o.size() == (a.size() == n ? n : 0);
        };
        bool redo_all = false;
        const bool in_place = plan.what != ffd::Redo::everything && out.cpu_valid &&
                              shaped(out.positions, cloud.positions) && shaped(out.normals, cloud.normals) &&
                              shaped(out.axis_u, cloud.axis_u) && shaped(out.axis_v, cloud.axis_v);
        if (!in_place) {
            ffd::deform_cloud(cloud, framed.span(), out, "ffd_system", weights_of(reg, e));
            redo_all = true;
        } else
            ffd::deform_cloud_pages(cloud, framed.span(), plan.pages, out, "ffd_system", weights_of(reg, e));
        out.inverted_version = out.version;
        if (splats) {  // the resident cloud draws this output from now on (state deformed_cpu)
            gfx::upload_deformed_splats(*splats, cloud, {out.positions, out.normals, out.axis_u, out.axis_v},
                                        st.store->keep_cpu);
            if (auto* rs = reg.try_resource<gfx::ResidencyStats>()) ++rs->deformed_uploads;
        }
        ++stats.cpu_runs, ++stats.cpu_splat_passes;
        return redo_all ? page_count(n) : plan.pages.size();
    }
};

}  // namespace

bool ffd::output_on_gpu(const ecs::Registry& reg, ecs::Entity e) {
    const auto* store = reg.try_resource<gfx::GpuSplatStore>();
    if (!store) return false;
    auto it = store->clouds.find(e);
    return it != store->clouds.end() && it->second.state == gfx::Residency::deformed_gpu;
}

void ffd_system(ecs::Registry& reg, const FrameContext&) {
    FfdStats* stats = reg.try_resource<FfdStats>();
    if (!stats) stats = &reg.set_resource<FfdStats>();
    SurfaceSettings st;
    st.backend = ffd::choose_deform_backend(reg.try_resource<FfdSettings>());
    if (st.backend.have_gl) {
        collect_gpu_stats(reg);
        st.store = reg.try_resource<gfx::GpuSplatStore>();
    }
    ffd::run_deformation<SurfaceKind>(reg, st, *stats);
}

}  // namespace sffd
