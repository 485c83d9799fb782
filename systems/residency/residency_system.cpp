#include "systems/residency/residency_system.h"

#include <vector>

#include "runtime/core/log.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/residency.h"
#include "runtime/gfx/splat_pack.h"
#include "runtime/gfx/splat_store.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gpu_store.h"
#include "systems/gaussian/gpu_upload.h"

namespace sffd {

namespace {

template <class T>
T& resource(ecs::Registry& reg) {
    if (auto* r = reg.try_resource<T>()) return *r;
    return reg.set_resource<T>();
}

// The machinery both kinds share: drop entries whose entity or authored component is gone, upload each
// authored cloud whose change stamp moved (upload(gpu, cloud, version) -> bool), and send a cloud that lost
// its deformers back to its rest data. The kinds differ only in their upload function.
template <class Cloud, class Store, class Upload>
void sync(ecs::Registry& reg, Store& store, gfx::ResidencyStats& stats, Upload&& upload) {
    for (auto it = store.clouds.begin(); it != store.clouds.end();) {
        if (reg.valid(it->first) && reg.has<Cloud>(it->first)) {
            ++it;
        } else {
            it = store.clouds.erase(it);
            ++stats.dropped;
        }
    }
    reg.template view<const Cloud>().each([&](ecs::Entity e, const Cloud& cloud) {
        auto& gpu = store.clouds[e];
        const std::uint64_t version = reg.version<Cloud>(e);
        if (!gpu.rest || gpu.rest_version != version) {
            upload(gpu, cloud, version);
            ++stats.rest_uploads;
        }
        if (gpu.is_deformed() && !reg.has<Deformers>(e)) gfx::drop_deformed(gpu);
    });
}

}  // namespace

void residency_system(ecs::Registry& reg, const FrameContext&) {
    if (!gfx::context_current()) return;
    auto& stats = resource<gfx::ResidencyStats>(reg);

    // Surface splats. CPU mirrors of what the buffers hold are kept where the cull runs on the CPU (a
    // software rasterizer: splat_render's automatic cull path); the upload packed them anyway.
    auto& splats = resource<gfx::GpuSplatStore>(reg);
    splats.keep_cpu = gfx::software_rasterizer();
    sync<SplatCloud>(reg, splats, stats,
                     [&](gfx::GpuSplats& gpu, const SplatCloud& cloud, std::uint64_t version) {
                         gfx::upload_rest_splats(gpu, cloud, version, splats.keep_cpu);
                     });

    // 3D Gaussians: rest + SH. A cloud whose arrays disagree is refused once per change (nothing drawn).
    auto& gaussians = resource<gaussian::GpuGaussianStore>(reg);
    sync<GaussianCloud>(reg, gaussians, stats,
                        [](gaussian::GpuGaussians& gpu, const GaussianCloud& cloud, std::uint64_t version) {
                            if (Status s = gaussian::upload_rest(gpu, cloud, version); !s) {
                                log::warn("residency_system: ", s.message(), " (cloud not drawn)");
                                gfx::set_rest(gpu, version, 0);
                            }
                        });
}

}  // namespace sffd
