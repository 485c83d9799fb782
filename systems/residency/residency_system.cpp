#include "systems/residency/residency_system.h"

#include <vector>

#include "runtime/core/log.h"
#include "runtime/gfx/residency.h"
#include "runtime/gfx/splat_store.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_pages.h"
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

template <class Cloud, class Store>
ecs::ScopedConnection drop_with(ecs::Registry& reg) {
    return reg.on_destroy<Cloud>().connect([](ecs::Registry& r, ecs::Entity e) {
        auto* store = r.try_resource<Store>();
        if (!store || store->clouds.erase(e) == 0) return;
        if (auto* stats = r.try_resource<gfx::ResidencyStats>()) ++stats->dropped;
    });
}

// The machinery both kinds share: upload each authored cloud whose change stamp moved
// (upload(gpu, cloud, version)), and send a cloud that lost its deformers back to its rest data. The kinds
// differ only in their upload function.
template <class Cloud, class Store, class Upload>
void sync(ecs::Registry& reg, Store& store, gfx::ResidencyStats& stats, Upload&& upload) {
    reg.template view<const Cloud>().each([&](ecs::Entity e, const Cloud& cloud) {
        auto& gpu = store.clouds[e];
        const std::uint64_t version = reg.version<Cloud>(e);
        if (!gpu.rest || gpu.rest_version != version) {
            upload(gpu, cloud, version);
            ++stats.rest_uploads;
        }
        if (gpu.is_deformed() && !reg.has<Deformers>(e)) gfx::drop_deformed(gpu);
        // The per-point marks (flags and weights for drawing), page by page; nothing else is uploaded
        // for an edit of them, and a cloud without either column gets no buffer.
        const ecs::Registry& r = reg;  // read-only
        const gfx::PointMarkSources marks{r.try_get<PointFlags>(e), r.try_get<PointWeights>(e),
                                          r.try_get<PointPages>(e), r.version<PointFlags>(e),
                                          r.version<PointWeights>(e)};
        if (const std::size_t packed = gfx::sync_point_marks(gpu, cloud.size(), marks); packed > 0) {
            ++stats.marks_uploads;
            stats.marks_points += packed;
        }
    });
}

}  // namespace

void residency_system(ecs::Registry& reg, const FrameContext&) {
    if (!gfx::context_current()) return;
    auto& stats = resource<gfx::ResidencyStats>(reg);
    if (!reg.try_resource<ResidencyConnections>())
        reg.set_resource<ResidencyConnections>(
            ResidencyConnections{drop_with<SplatCloud, gfx::GpuSplatStore>(reg),
                                 drop_with<GaussianCloud, gaussian::GpuGaussianStore>(reg)});

    // Surface splats: the splats, and a textured cloud's texture and uv frames, each by its one upload
    // function. No CPU mirror of them is kept: the CPU reads the buffers (gfx::read_splats_on_cpu).
    auto& splats = resource<gfx::GpuSplatStore>(reg);
    sync<SplatCloud>(reg, splats, stats,
                     [&](gfx::GpuSplats& gpu, const SplatCloud& cloud, std::uint64_t version) {
                         gfx::upload_rest_splats(gpu, cloud, version);
                         gfx::upload_splat_texture(gpu, cloud, version);
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
