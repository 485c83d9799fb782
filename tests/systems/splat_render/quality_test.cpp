// Image quality of the textured built-in sphere against its ground truth (ground_truth.h): the issue-14
// targets, PSNR >= 38 dB in HQ and >= 30 dB in preview, at rest and at the demo clip's local stretch and
// global twist peaks. Rendered at 640 x 360 (the command-line measurements in RESULTS.md are 1280 x 720)
// so the test stays a few seconds on llvmpipe; the deformed ground truth uses a 1024 x 512 tessellation.
#include <cstdio>

#include "runtime/app/clock.h"
#include "runtime/assets/builtin_scenes.h"
#include "systems/animation/animation_system.h"
#include "systems/animation/editing.h"
#include "systems/animation/paper_demo.h"
#include "systems/ffd/ffd_system.h"
#include "systems/splat_render/ground_truth.h"
#include "systems/splat_render/image_compare.h"
#include "tests/systems/splat_render/gl_fixture.h"

namespace sffd::render::test {
namespace {

class Quality_ : public GlRenderTest {
protected:
    // The built-in sphere with the demo clip on its lattice (what `splatffd render sphere` loads).
    void load_sphere() {
        ASSERT_TRUE(assets::load_builtin_scene(reg, "sphere"));
        std::vector<ecs::Entity> lattices;
        reg.view<const Lattice>().each([&](ecs::Entity e, const Lattice&) { lattices.push_back(e); });
        ASSERT_EQ(lattices.size(), 1u);
        attach_clip(reg, lattices[0], make_paper_demo_clip(reg.get<Lattice>(lattices[0])));
    }
    // Frame k as `splatffd render --frames k:k` makes it (animation, deformation, rendering), and the
    // ground truth of the same pose.
    std::pair<FrameImage, FrameImage> frame(long k, Quality quality, int w, int h) {
        Clock clock(ClockSettings{.fixed_dt = 1.0 / paper_demo_fps});
        clock.seek(double(k) / paper_demo_fps);
        FrameContext f = clock.tick();
        f.frame = std::uint64_t(k);
        animation_system(reg, f);
        ffd_system(reg, f);
        RenderSettings s;
        s.quality = quality, s.width = w, s.height = h, s.aux_outputs = true;
        reg.set_resource<RenderSettings>(s);
        render_system(reg, f);
        auto img = capture_frame(reg);
        EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.message());
        auto scene = reference_scene(reg, w, h);
        EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.message());
        if (!img.ok() || !scene.ok()) return {};
        EXPECT_EQ(scene->lattices.empty(), k == 0) << "frame " << k << ": the clip should deform the sphere";
        ReferenceSettings rs;
        rs.longitude_steps = 1024, rs.colatitude_steps = 512;
        auto ref = render_reference(*scene, rs);
        EXPECT_TRUE(ref.ok()) << (ref.ok() ? "" : ref.message());
        return {std::move(img.value()), ref.ok() ? std::move(ref.value()) : FrameImage{}};
    }
};

TEST_F(Quality_, TexturedSphereMeetsThePsnrTargetsAgainstTheGroundTruth) {
    load_sphere();
    // 0: rest; 12: local stretch at its peak (frames 9-15); 84: global twist at its peak (frames 81-87).
    for (long k : {0L, 12L, 84L}) {
        for (Quality q : {Quality::hq, Quality::preview}) {
            auto [img, ref] = frame(k, q, 640, 360);
            auto cmp = compare_images(img, ref);
            ASSERT_TRUE(cmp.ok()) << cmp.message();
            const char* name = q == Quality::hq ? "hq" : "preview";
            std::printf("frame %ld %s: PSNR %.2f dB, SSIM %.4f, %zu px (%zu covered in one only)\n", k, name, cmp->psnr,
                        cmp->ssim, cmp->pixels, cmp->pixels_one);
            EXPECT_GT(cmp->pixels, 25000u);  // the sphere is ~210 px across at this size
            EXPECT_GE(cmp->psnr, q == Quality::hq ? 38.0 : 30.0) << "frame " << k << " " << name;
            // The silhouette agrees with the exact one but for a pixel-wide fringe in places.
            EXPECT_LT(double(cmp->pixels_one), 0.01 * double(cmp->pixels)) << "frame " << k << " " << name;
        }
    }
}

// The CPU cull draws one-colour footprints flat (CpuCullResult::flat_records); the compute cull textures
// every sprite. Both images must agree.
TEST_F(Quality_, FlatColouredSpritesLookLikeTexturedOnes) {
    load_sphere();
    for (Quality q : {Quality::hq, Quality::preview}) {
        FrameImage img[2];
        for (int compute = 0; compute < 2; ++compute) {
            release_render_state(reg);
            img[compute] = render(q, 640, 360, true, compute ? CullPath::compute : CullPath::automatic);
            const RenderStats& stats = reg.resource<RenderStats>();
            EXPECT_EQ(stats.cpu_culled_clouds, compute ? 0u : 1u);
        }
        auto cmp = compare_images(img[0], img[1]);
        ASSERT_TRUE(cmp.ok());
        std::printf("%s: flat + textured vs all textured: PSNR %.2f dB\n", q == Quality::hq ? "hq" : "preview", cmp->psnr);
        EXPECT_GT(cmp->psnr, 45.0);
        EXPECT_EQ(cmp->pixels_one, 0u);
    }
}

}  // namespace
}  // namespace sffd::render::test
