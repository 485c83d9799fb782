#include "systems/ffd/ffd_system.h"

#include <algorithm>
#include <string_view>
#include <vector>

#include "runtime/app/pass_timer.h"
#include "runtime/core/log.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/residency.h"
#include "runtime/gfx/splat_store.h"
#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"
#include "shaders/common/bindings.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform_backend.h"
#include "systems/ffd/deform_cloud.h"
#include "systems/ffd/deform_inputs.h"
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

void ffd_system(ecs::Registry& reg, const FrameContext&) {
    FfdSettings* settings = reg.try_resource<FfdSettings>();
    FfdStats* stats = reg.try_resource<FfdStats>();
    if (!stats) stats = &reg.set_resource<FfdStats>();
    const ffd::DeformBackend backend = ffd::choose_deform_backend(settings);
    const bool have_gl = backend.have_gl, force_cpu = backend.force_cpu;
    if (have_gl) collect_gpu_stats(reg);
    // Collect first: emplacing DeformedSplats while iterating is a structural change.
    std::vector<ecs::Entity> clouds;
    reg.view<const SplatCloud, const Deformers>().each(
        [&](ecs::Entity e, const SplatCloud&, const Deformers&) { clouds.push_back(e); });
    for (ecs::Entity e : clouds) {
        const SplatCloud& cloud = reg.get<SplatCloud>(e);
        const ffd::DeformInputs inputs = ffd::deform_inputs<SplatCloud>(reg, e);
        const std::uint64_t cloud_v = inputs.stamps.cloud;
        const std::size_t n = cloud.size();
        // The cloud's residency (residency_system uploaded its rest splats this frame when they changed):
        // the GPU path needs them current, the CPU path uploads its output there.
        gfx::GpuSplatStore* store = have_gl ? reg.try_resource<gfx::GpuSplatStore>() : nullptr;
        gfx::GpuSplats* splats = nullptr;
        if (store) {
            auto it = store->clouds.find(e);
            if (it != store->clouds.end() && it->second.rest && it->second.rest_version == cloud_v &&
                it->second.count == n)
                splats = &it->second;
        }
        const DeformedSplats* seen = reg.try_get<DeformedSplats>(e);
        // A budgeted preview (preview_budget.h) on the CPU path of a resident cloud (textured clouds index
        // their uv frames per splat, so they are always drawn whole).
        const std::uint32_t budget =
            splats && (force_cpu || !have_gl) && cloud.texture.rgba8.empty() ? preview_budget_for(reg, n) : 0;
        // A resident cloud at rest has no deformed data yet (its entry is new): deform even if nothing moved.
        // A full output serves every frame; a preview one only preview frames.
        if (seen && seen->seen == inputs.stamps && seen->seen_force_cpu == force_cpu &&
            (!splats || splats->is_deformed()) && (!seen->preview || budget > 0))
            continue;  // nothing this cloud depends on moved

        if (!seen) reg.emplace<DeformedSplats>(e);
        DeformedSplats& out = reg.patch<DeformedSplats>(e);
        // Every path below reads the lattices in the cloud's frame (lattice_frame.h).
        const ffd::CloudLattices framed = ffd::cloud_lattices(reg, e, inputs.lattices);
        const std::span<const Lattice* const> lattices = framed.span();
        out.origin = cloud.origin;
        out.seen = inputs.stamps;
        out.seen_force_cpu = force_cpu;
        ++out.version;

        // Bounds from the control points only: the rest box (one pass over the splats when the cloud
        // changes, cached) grown by each lattice's displacement hull, in order (never under-covers), in the
        // cloud's frame, then mapped to the world by the cloud's Transform (the renderer's screen rectangle
        // reads them there).
        if (!out.has_rest_box || out.rest_box_cloud != cloud_v) {
            ffd::Box rest;
            for (const glm::vec3& p : cloud.positions) rest.add(cloud.origin + glm::dvec3(p));
            out.rest_box_lo = rest.lo, out.rest_box_hi = rest.hi, out.rest_box_empty = rest.empty;
            out.has_rest_box = true, out.rest_box_cloud = cloud_v;
            ++stats->cpu_splat_passes;
        }
        ffd::Box box{out.rest_box_lo, out.rest_box_hi, out.rest_box_empty};
        for (const Lattice* l : lattices)
            if (ffd::validate(*l).ok()) box = ffd::deformed_bounds(*l, box);
        box = ffd::world_box(box, model_matrix(reg.try_get<Transform>(e)));
        out.bounds_min = box.lo, out.bounds_max = box.hi;

        out.preview = budget > 0;
        if (budget > 0) {
            // Only the subset, its splats enlarged; the rest is deformed by the next full frame.
            update_preview_subset(out.subset, cloud.positions, cloud_v, budget);
            const std::vector<std::uint32_t>& kept = out.subset.indices;
            ffd::deform_cloud_subset(cloud, lattices, kept, out, "ffd_system");
            out.gpu_valid = false;
            gfx::upload_preview_splats(*splats, cloud, kept,
                                       {out.positions, out.normals, out.axis_u, out.axis_v},
                                       preview_radius_scale(n, kept.size()), store->keep_cpu);
            if (auto* rs = reg.try_resource<gfx::ResidencyStats>()) ++rs->deformed_uploads;
            ++stats->preview_runs;
            continue;
        }

        ffd::GpuDeformer* gpu =
            splats && !force_cpu ? ffd::gpu_deformer<ffd::GpuDeformer>(reg, "ffd_system") : nullptr;
        if (gpu) {
            gfx::reserve_buffer(splats->deformed, "splats.deformed",
                                std::max<std::size_t>(n, 1) * sizeof(gpu::GpuSplat));
            auto pass_scope = profiling::gpu_scope(reg, "ffd.compute");  // names the pass for the profiler
            gpu->reset_stats();
            GLuint in = splats->rest.id();
            bool ok = true;
            if (lattices.empty() && n > 0)
                glCopyNamedBufferSubData(in, splats->deformed.id(), 0, 0,
                                         GLsizeiptr(n * sizeof(gpu::GpuSplat)));
            for (std::size_t d = 0; d < lattices.size(); ++d) {
                if (Status s =
                        gpu->dispatch(*lattices[d], framed.entities[d].bits(), inputs.stamps.lattices[d],
                                      cloud.origin, in, splats->deformed.id(), std::uint32_t(n));
                    !s) {
                    log::warn("ffd_system: ", s.message(), " (lattice skipped)");
                    if (d == 0 && n > 0)
                        glCopyNamedBufferSubData(in, splats->deformed.id(), 0, 0,
                                                 GLsizeiptr(n * sizeof(gpu::GpuSplat)));
                    else if (d == 0) ok = false;
                    in = splats->deformed.id();
                    continue;
                }
                in = splats->deformed.id();
            }
            if (ok) {
                // The inverted count arrives a few frames later (collect_gpu_stats); until then `inverted`
                // keeps the latest count that arrived.
                reg.resource<FfdGpuState>().queue_stats(*gpu, e, out.version);
                gfx::set_deformed(*splats, gfx::Residency::deformed_gpu);
                out.gpu_valid = true;
                out.cpu_valid = false;
                out.positions.clear(), out.normals.clear(), out.axis_u.clear(), out.axis_v.clear();
                ++stats->gpu_runs, stats->gpu_sync_readbacks = gpu->sync_readbacks();
                continue;
            }
        }

        // CPU path: the one CPU deformation step (also what picking asks for).
        ffd::deform_cloud(cloud, lattices, out, "ffd_system");
        out.inverted_version = out.version;
        out.gpu_valid = false;
        if (splats) {  // the resident cloud draws this output from now on (state deformed_cpu)
            gfx::upload_deformed_splats(*splats, cloud, {out.positions, out.normals, out.axis_u, out.axis_v},
                                        store->keep_cpu);
            if (auto* rs = reg.try_resource<gfx::ResidencyStats>()) ++rs->deformed_uploads;
        }
        ++stats->cpu_runs, ++stats->cpu_splat_passes;
    }
}

}  // namespace sffd
