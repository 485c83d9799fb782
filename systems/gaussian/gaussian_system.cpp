#include "systems/gaussian/gaussian_system.h"

#include <optional>
#include <unordered_map>
#include <vector>

#include <EGL/egl.h>
#include <GLFW/glfw3.h>

#include "runtime/app/pass_timer.h"
#include "runtime/core/log.h"
#include "runtime/gfx/context.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform_inputs.h"
#include "systems/ffd/ffd_system.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gpu_deform.h"
#include "systems/gaussian/gpu_store.h"

namespace sffd {

namespace {

// The system's GPU state (a registry resource: its GL objects live as long as the registry's).
struct GaussianGpuState {
    std::optional<gaussian::GpuGaussianDeformer> deformer;
    bool unavailable = false;  // compile failed once: stay on the CPU path
    // Statistics in flight (queue_stats tag -> the output they were counted for).
    struct Pending {
        ecs::Entity cloud;
        std::uint64_t version = 0;
    };
    std::unordered_map<std::uint64_t, Pending> pending;
    std::uint64_t next_tag = 1;
};

// Counts of earlier GPU runs that have arrived (never waits): they apply to the output they were counted
// for if it has not been rewritten since. Statistics, not data: no change stamp.
void collect_gpu_stats(ecs::Registry& reg) {
    auto* st = reg.try_resource<GaussianGpuState>();
    if (!st || !st->deformer || st->pending.empty()) return;
    for (const gaussian::GpuGaussianDeformer::TaggedStats& t : st->deformer->poll_stats()) {
        auto it = st->pending.find(t.tag);
        if (it == st->pending.end()) continue;
        const GaussianGpuState::Pending p = it->second;
        st->pending.erase(it);
        if (t.stats.not_finite)
            log::warn("gaussian_deform_system: ", t.stats.not_finite, " Gaussians deformed to non-finite values (drawn transparent)");
        DeformedGaussians* out = reg.valid(p.cloud) ? reg.try_get<DeformedGaussians>(p.cloud) : nullptr;
        if (!out || out->version != p.version) continue;
        out->inverted = t.stats.inverted;
        out->degenerate = t.stats.degenerate;
        out->not_finite = t.stats.not_finite;
        out->stats_arrived = true;
    }
}

bool gl_context_current() { return eglGetCurrentContext() != EGL_NO_CONTEXT || glfwGetCurrentContext() != nullptr; }

gaussian::GpuGaussianDeformer* gpu_deformer(ecs::Registry& reg) {
    auto* st = reg.try_resource<GaussianGpuState>();
    if (!st) st = &reg.set_resource<GaussianGpuState>();
    if (st->unavailable) return nullptr;
    if (!st->deformer) {
        auto d = gaussian::GpuGaussianDeformer::create();
        if (!d) {
            log::warn("gaussian_deform_system: GPU path unavailable, deforming on the CPU (", d.message(), ")");
            st->unavailable = true;
            return nullptr;
        }
        st->deformer.emplace(std::move(*d));
    }
    return &*st->deformer;
}

}  // namespace

void gaussian_release_gpu(ecs::Registry& registry) { registry.erase_resource<GaussianGpuState>(); }

void gaussian_deform_system(ecs::Registry& reg, const FrameContext&) {
    // The backend choice of ffd_system (systems/ffd/ffd_system.h): GPU when a GL context is current,
    // except on a software rasterizer (llvmpipe runs the "GPU" on the same CPU cores, slower than the
    // TBB path) unless FfdSettings::force_gpu; never with FfdSettings::force_cpu.
    const FfdSettings* settings = reg.try_resource<FfdSettings>();
    GaussianDeformSettings* counters = reg.try_resource<GaussianDeformSettings>();
    const gaussian::ShMode gpu_sh = counters ? counters->gpu_sh : gaussian::ShMode::rotate_view;
    const gaussian::ShMode cpu_sh = counters ? counters->cpu_sh : gaussian::ShMode::rotate_coefficients;
    const bool force_gpu = settings && settings->force_gpu;
    const bool have_gl = gl_context_current();
    const bool force_cpu = (settings && settings->force_cpu) || (have_gl && !force_gpu && gfx::software_rasterizer());
    if (have_gl) collect_gpu_stats(reg);
    // Collect first: emplacing DeformedGaussians while iterating is a structural change.
    std::vector<ecs::Entity> clouds;
    reg.view<const GaussianCloud, const Deformers>().each(
        [&](ecs::Entity e, const GaussianCloud&, const Deformers&) { clouds.push_back(e); });
    for (ecs::Entity e : clouds) {
        const GaussianCloud& cloud = reg.get<GaussianCloud>(e);
        const ffd::DeformInputs inputs = ffd::deform_inputs<GaussianCloud>(reg, e);
        const std::vector<ecs::Entity>& lattices = inputs.lattices;
        const DeformedGaussians* seen = reg.try_get<DeformedGaussians>(e);
        const bool gpu_path = have_gl && !force_cpu;
        const auto sh_mode = std::uint8_t(gpu_path ? gpu_sh : cpu_sh);
        if (seen && seen->seen == inputs.stamps && seen->seen_force_cpu == force_cpu && seen->seen_sh_mode == sh_mode)
            continue;  // nothing moved
        if (!seen) reg.emplace<DeformedGaussians>(e);
        DeformedGaussians& out = reg.patch<DeformedGaussians>(e);
        out.seen = inputs.stamps;
        out.seen_force_cpu = force_cpu;
        out.seen_sh_mode = sh_mode;
        out.inverted = out.degenerate = out.not_finite = 0;
        out.stats_arrived = false;
        ++out.version;

        // GPU path: the authored cloud goes to GpuGaussianStore::rest when its change stamp moved (the
        // only per-Gaussian CPU work, once per cloud change), then one dispatch per lattice into
        // `deformed` (+ `frames` or `deformed_sh` when the SH have view-dependent terms). No read-back.
        if (gpu_path) {
            if (gaussian::GpuGaussianDeformer* gpu = gpu_deformer(reg)) {
                auto* store = reg.try_resource<gaussian::GpuGaussianStore>();
                if (!store) store = &reg.set_resource<gaussian::GpuGaussianStore>();
                gaussian::GpuGaussians& g = store->clouds[e];
                Status up;
                if (!g.rest || g.rest_version != inputs.stamps.cloud || g.count != cloud.size()) {
                    up = gaussian::upload_rest(g, cloud, inputs.stamps.cloud);
                    if (counters) ++counters->rest_uploads;
                }
                if (up) {
                    std::vector<const Lattice*> ls;
                    std::vector<std::uint64_t> keys;
                    for (ecs::Entity le : lattices) ls.push_back(&reg.get<Lattice>(le)), keys.push_back(le.bits());
                    auto pass_scope = profiling::gpu_scope(reg, "gaussian.deform");
                    gpu->reset_stats();
                    if (Status s = gpu->deform(g, cloud.origin, ls, keys, inputs.stamps.lattices, gpu_sh); !s)
                        log::warn("gaussian_deform_system: ", s.message(), " (lattice skipped)");
                    // The counts arrive a few frames later (collect_gpu_stats); nothing waits for them.
                    auto& state = reg.resource<GaussianGpuState>();
                    const std::uint64_t tag = state.next_tag++;
                    if (gpu->queue_stats(tag)) state.pending[tag] = {e, out.version};
                    out.on_gpu = true;
                    out.cloud = GaussianCloud{};
                    out.cloud.origin = cloud.origin;
                    out.cloud.sh_degree = cloud.sh_degree;
                    if (counters) ++counters->gpu_runs, counters->gpu_sync_readbacks = gpu->sync_readbacks();
                    continue;
                }
                log::warn("gaussian_deform_system: ", up.message(), " (deforming on the CPU)");
            }
        }

        // CPU path (TBB).
        out.on_gpu = false;
        if (auto* store = reg.try_resource<gaussian::GpuGaussianStore>())
            if (auto it = store->clouds.find(e); it != store->clouds.end())
                it->second.has_deformed = it->second.deformed_on_gpu = it->second.has_frames = it->second.has_deformed_sh = false;
        // Opacities are not copied (a deformation never changes them): readers use the authored cloud's.
        out.cloud.origin = cloud.origin;
        out.cloud.sh_degree = cloud.sh_degree;
        out.cloud.positions = cloud.positions;
        out.cloud.scales = cloud.scales;
        out.cloud.rotations = cloud.rotations;
        out.cloud.sh = cloud.sh;
        out.cloud.opacities.clear();
        out.cloud.sh_frames.clear();
        for (ecs::Entity le : lattices) {
            auto stats = gaussian::deform(reg.get<Lattice>(le), out.cloud, out.cloud, {ffd::Backend::automatic, false, cpu_sh});
            if (!stats) {
                log::warn("gaussian_deform_system: ", stats.message(), " (lattice skipped)");
                continue;
            }
            out.inverted += stats->inverted;
            out.degenerate += stats->degenerate;
        }
        out.stats_arrived = true;
        if (counters) ++counters->cpu_runs;
    }
}

}  // namespace sffd
