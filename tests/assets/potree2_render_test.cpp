// A Potree 2 octree's full detail renders as the cloud it was built from: the built-in sphere (textured,
// uv frames, its clip's lattice) through the engine's frame, once as loaded and once with its cloud
// replaced by read_potree2() of its octree; PSNR over the object (systems/splat_render/image_compare.h).
#include <gtest/gtest.h>

#include <optional>

#include "runtime/assets/formats/surface/potree2.h"
#include "runtime/assets/formats/surface/potree2_write.h"
#include "runtime/assets/scene.h"
#include "runtime/gfx/context.h"
#include "systems/engine/engine.h"
#include "systems/engine/engine_frame.h"
#include "systems/splat_render/image_compare.h"
#include "systems/splat_render/splat_render.h"
#include "tests/assets/test_util.h"
#include "tests/test_util/gl_required.h"

using namespace sffd;

namespace {
constexpr int kWidth = 320, kHeight = 180;

Result<render::FrameImage> render_sphere(gfx::GlContext& ctx, const SplatCloud* replace) {
    ecs::Registry registry;
    use_engine_scene_hooks(registry);
    if (Status s = load_scene(registry, "sphere"); !s) return s.error();
    registry.each_entity([&](ecs::Entity e) {
        if (SplatCloud* c = registry.try_get<SplatCloud>(e); c && replace) *c = *replace;
    });
    render::RenderSettings settings;
    settings.width = kWidth, settings.height = kHeight;
    registry.set_resource<render::RenderSettings>(settings);
    const Schedule schedule = make_engine_schedule({.present = false});
    auto image = render_engine_frame(registry, schedule, ctx, {.frame = 0});
    render::release_render_state(registry);
    return image;
}
}  // namespace

TEST(Potree2Render, FullDetailRendersAsThePlainCloud) {
    auto c = gfx::create_context({.headless = true, .width = kWidth, .height = kHeight});
    if (!c) SFFD_GL_UNAVAILABLE(c.message());
    std::optional<SplatCloud> sphere;
    {
        ecs::Registry registry;
        use_engine_scene_hooks(registry);
        ASSERT_TRUE(load_scene(registry, "sphere"));
        registry.each_entity([&](ecs::Entity e) {
            if (const SplatCloud* s = registry.try_get<SplatCloud>(e)) sphere = *s;
        });
    }
    ASSERT_TRUE(sphere);
    const auto dir = test::fresh_dir("potree2_render", "sphere");
    assets::Potree2BuildOptions o;
    o.max_leaf = 1024, o.grid_cells = 16;  // several levels for 59,650 splats
    auto built =
        assets::build_potree2(assets::cloud_splat_source(*sphere, "sphere"), dir / "metadata.json", o);
    ASSERT_TRUE(built) << built.message();
    EXPECT_GT(built->depth, 1);
    auto octree = assets::open_potree2(dir / "metadata.json");
    ASSERT_TRUE(octree) << octree.message();
    auto full = assets::read_potree2(*octree);
    ASSERT_TRUE(full) << full.message();
    auto plain = render_sphere(*c, nullptr);
    ASSERT_TRUE(plain) << plain.message();
    auto lod = render_sphere(*c, &*full);
    ASSERT_TRUE(lod) << lod.message();
    auto cmp = render::compare_images(*lod, *plain);
    ASSERT_TRUE(cmp) << cmp.message();
    EXPECT_GT(cmp->pixels, std::size_t(kWidth * kHeight / 10));
    EXPECT_GE(cmp->psnr, 40.0) << "SSIM " << cmp->ssim;
    std::printf("full detail vs plain: PSNR %.2f dB, SSIM %.5f over %zu pixels\n", cmp->psnr, cmp->ssim,
                cmp->pixels);
    // The coarsest cut draws fewer, larger splats over the same surface.
    auto coarse = assets::read_potree2_nodes(*octree, assets::potree2_level_cut(*octree, 1));
    ASSERT_TRUE(coarse) << coarse.message();
    auto lod1 = render_sphere(*c, &*coarse);
    ASSERT_TRUE(lod1) << lod1.message();
    auto cmp1 = render::compare_images(*lod1, *plain);
    ASSERT_TRUE(cmp1) << cmp1.message();
    std::printf("level 0-1 cut (%zu of %zu splats) vs plain: PSNR %.2f dB, SSIM %.5f\n", coarse->size(),
                full->size(), cmp1->psnr, cmp1->ssim);
    EXPECT_GT(cmp1->psnr, 15.0) << "the coarse cut still shows the sphere";
    EXPECT_LT(cmp1->psnr, cmp->psnr) << "and is not the full detail";
}
