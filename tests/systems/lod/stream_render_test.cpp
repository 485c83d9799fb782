// A streamed hierarchy's full-detail render is the plain render of the same file: the built-in sphere as
// a Potree 2 octree and procedural Gaussians as a streamed SOG, each drawn through the engine's frame once
// streamed (every frame waiting for its cut, error 0, no splat budget: what `render` does) and once read
// whole, from the same camera, at rest and under the same twisted lattice (the deformers see the drawn
// cut as any cloud). PSNR over the object (systems/splat_render/image_compare.h).
#include <gtest/gtest.h>

#include <cstdio>
#include <optional>

#include "runtime/assets/formats/lod/lod_build.h"
#include "runtime/assets/formats/surface/potree2_write.h"
#include "runtime/assets/scene.h"
#include "runtime/gfx/context.h"
#include "runtime/scene/lattice.h"
#include "systems/engine/engine.h"
#include "systems/engine/engine_frame.h"
#include "systems/ffd/operations.h"
#include "systems/lod/streaming.h"
#include "systems/splat_render/image_compare.h"
#include "systems/splat_render/splat_render.h"
#include "tests/assets/test_util.h"
#include "tests/test_util/gl_required.h"

using namespace sffd;
namespace fs = std::filesystem;

namespace {
constexpr int kWidth = 320, kHeight = 180;

// Renders `file` from `camera`, streamed or whole, under a twisted 4^3 lattice around `lo`..`hi` (the
// cloud's frame) when `twist`.
Result<render::FrameImage> render_file(gfx::GlContext& ctx, const fs::path& file, bool streamed,
                                       const Camera& camera,
                                       std::optional<std::pair<glm::dvec3, glm::dvec3>> twist) {
    ecs::Registry registry;
    use_engine_scene_hooks(registry);
    render::RenderSettings settings;
    settings.width = kWidth, settings.height = kHeight;
    registry.set_resource<render::RenderSettings>(settings);
    if (streamed) {
        lod::StreamSettings s;
        s.options.splat_budget = std::uint64_t(1) << 40, s.options.tau_pixels = 0.0;
        s.wait = true;
        lod::enable_streaming(registry, s);
    }
    if (Status st = load_scene(registry, file.string()); !st) return st.error();
    std::vector<ecs::Entity> clouds;
    registry.each_entity([&](ecs::Entity e) {
        if (registry.has<SplatCloud>(e) || registry.has<GaussianCloud>(e)) clouds.push_back(e);
        if (Camera* c = registry.try_get<Camera>(e)) *c = camera;
    });
    if (clouds.size() != 1) return make_error("expected one cloud");
    if (streamed != registry.has<lod::StreamedCloud>(clouds[0]))
        return make_error("streamed or not as asked");
    if (twist) {
        const auto [lo, hi] = *twist;
        const glm::dvec3 pad = 0.05 * (hi - lo);
        const glm::dvec3 size = hi - lo + 2.0 * pad;
        Lattice l = make_lattice(
            lo - pad, {glm::dvec3(size.x, 0, 0), glm::dvec3(0, size.y, 0), glm::dvec3(0, 0, size.z)},
            glm::ivec3(3), LatticeBasis::bernstein);
        ffd::twist_graded(l, ffd::all_control_points(l), glm::dvec3(0, 1, 0), 1.2 / size.y);
        const ecs::Entity le = registry.create();
        registry.emplace<Lattice>(le, std::move(l));
        if (const Transform* t = registry.try_get<Transform>(clouds[0])) registry.emplace<Transform>(le, *t);
        registry.emplace<Deformers>(clouds[0], Deformers{{le}});
    }
    const Schedule schedule = make_engine_schedule({.present = false});
    auto image = render_engine_frame(registry, schedule, ctx, {.frame = 0});
    render::release_render_state(registry);
    return image;
}

void expect_same_render(gfx::GlContext& ctx, const fs::path& file, const Camera& camera,
                        std::optional<std::pair<glm::dvec3, glm::dvec3>> twist, const char* what) {
    auto plain = render_file(ctx, file, false, camera, twist);
    ASSERT_TRUE(plain) << plain.message();
    auto streamed = render_file(ctx, file, true, camera, twist);
    ASSERT_TRUE(streamed) << streamed.message();
    auto cmp = render::compare_images(*streamed, *plain);
    ASSERT_TRUE(cmp) << cmp.message();
    EXPECT_GT(cmp->pixels, std::size_t(kWidth * kHeight / 10)) << what;
    EXPECT_GE(cmp->psnr, 40.0) << what << ": SSIM " << cmp->ssim;
    std::printf("%s: streamed full detail vs whole file: PSNR %.2f dB, SSIM %.5f over %zu pixels\n", what,
                cmp->psnr, cmp->ssim, cmp->pixels);
}

Camera looking_at(glm::dvec3 eye, glm::dvec3 target) {
    Camera c;
    c.eye = eye, c.target = target;
    c.near_plane = 0.05f, c.far_plane = 200.0f;
    return c;
}
}  // namespace

TEST(LodStreamRender, PotreeFullDetailMatchesTheWholeFile) {
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
    const auto dir = test::fresh_dir("lod_stream_render", "sphere");
    assets::Potree2BuildOptions o;
    o.max_leaf = 1024, o.grid_cells = 16;
    ASSERT_TRUE(
        assets::build_potree2(assets::cloud_splat_source(*sphere, "sphere"), dir / "metadata.json", o));
    glm::dvec3 lo(1e30), hi(-1e30);
    for (const auto& p : sphere->positions) {
        lo = glm::min(lo, sphere->origin + glm::dvec3(p));
        hi = glm::max(hi, sphere->origin + glm::dvec3(p));
    }
    const glm::dvec3 mid = 0.5 * (lo + hi);
    const Camera cam = looking_at(mid + glm::dvec3(0.6, 0.4, 1.0) * glm::length(hi - lo), mid);
    expect_same_render(*c, dir / "metadata.json", cam, std::nullopt, "Potree 2 sphere");
    expect_same_render(*c, dir / "metadata.json", cam, std::pair{lo, hi}, "Potree 2 sphere, twisted");
}

TEST(LodStreamRender, StreamedSogFullDetailMatchesTheWholeFile) {
    auto c = gfx::create_context({.headless = true, .width = kWidth, .height = kHeight});
    if (!c) SFFD_GL_UNAVAILABLE(c.message());
    const auto dir = test::fresh_dir("lod_stream_render", "gaussians");
    lod::LodBuildOptions o;
    o.levels = 3, o.chunk_count = 2048;
    ASSERT_TRUE(lod::build_streamed_sog(lod::synthetic_gaussian_source(20000), dir / "lod-meta.json", o));
    // The synthetic sphere has radius 10 about the origin (the capture's upright turn keeps it there).
    const Camera cam = looking_at(glm::dvec3(14.0, 9.0, 24.0), glm::dvec3(0.0));
    expect_same_render(*c, dir / "lod-meta.json", cam, std::nullopt, "streamed SOG");
    expect_same_render(*c, dir / "lod-meta.json", cam, std::pair{glm::dvec3(-10.5), glm::dvec3(10.5)},
                       "streamed SOG, twisted");
}
