// Point marks in the surface render (runtime/gfx/point_marks.h): hidden and deleted splats are never drawn
// on either cull path, HQ or preview, and a cloud with some hidden draws exactly the image of the cloud
// without them (point_subset.h); a flag edit uploads only the marks, page by page, and re-deforms nothing;
// the selection tint changes only the selected splats' pixels; the weight overlay colours by weight.
#include <gtest/gtest.h>

#include <numeric>

#include "runtime/gfx/residency.h"
#include "runtime/gfx/splat_pack.h"
#include "runtime/gfx/splat_store.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_pages.h"
#include "runtime/scene/point_subset.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/preview_budget.h"
#include "systems/splat_render/cpu_cull.h"
#include "tests/systems/splat_render/gl_fixture.h"
#include "tests/systems/splat_render/test_scenes.h"

namespace sffd::render::test {
namespace {

constexpr int kW = 160, kH = 120;

// One scene per case (a registry is not movable): the fixture's camera and light, clouds added.
struct Scene {
    ecs::Registry reg;
    Scene() {
        Camera c;
        c.eye = glm::dvec3(0.0, 0.0, 3.0);
        c.near_plane = 0.05f, c.far_plane = 20.0f;
        reg.emplace<Camera>(reg.create(), c);
        reg.emplace<DirectionalLight>(
            reg.create(),
            DirectionalLight{glm::normalize(glm::vec3(0.3f, 0.5f, 1.0f)), glm::vec3(1.0f), 1.0f});
        reg.emplace<AmbientLight>(reg.create(), AmbientLight{glm::vec3(1.0f), 0.2f});
    }
    ~Scene() { release_render_state(reg); }
    ecs::Entity add(SplatCloud cloud) {
        const ecs::Entity e = reg.create();
        reg.emplace<SplatCloud>(e, std::move(cloud));
        SplatMaterial m;
        m.specular = 0.0f;  // colours are albedo times light: the overlays' channels stay apart
        reg.emplace<SplatMaterial>(e, m);
        return e;
    }
    // One frame (residency, then the deformation when `deform`, then the render) read back.
    FrameImage draw(Quality q, CullPath path, bool selection = false, bool weights = false,
                    bool deform = false) {
        RenderSettings rs;
        rs.quality = q, rs.width = kW, rs.height = kH, rs.cull_path = path, rs.aux_outputs = true;
        rs.show_selection = selection, rs.show_weights = weights;
        reg.set_resource<RenderSettings>(rs);
        residency_system(reg, FrameContext{});
        if (deform) ffd_system(reg, FrameContext{});
        render_system(reg, FrameContext{});
        auto img = capture_frame(reg);
        EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.message());
        return img.ok() ? std::move(*img) : FrameImage{};
    }
    // A lattice around the unit sphere deforming cloud `e` (one control point moved).
    void add_lattice(ecs::Entity e) {
        const ecs::Entity le = reg.create();
        Lattice l =
            make_lattice({-1.1, -1.1, -1.1},
                         {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {4, 4, 4});
        l.current[0] += glm::dvec3(0.1, 0.0, 0.0);
        reg.emplace<Lattice>(le, std::move(l));
        reg.emplace<Deformers>(e, Deformers{{le}});
    }
};

class PointMarks_ : public GlRenderTest {
protected:
    // The sphere's flags: `bits` on every splat with x > 0 (the right half as the camera sees it).
    static PointFlags right_half(const SplatCloud& cloud, std::uint8_t bits) {
        PointFlags f;
        f.bits.assign(cloud.size(), 0);
        for (std::size_t i = 0; i < cloud.size(); ++i)
            if (cloud.positions[i].x > 0.0f) f.bits[i] = bits;
        return f;
    }
    // Covered pixels right of the centre column by more than `margin_px`.
    static int covered_right_of(const FrameImage& img, int margin_px) {
        int k = 0;
        for (int y = 0; y < img.height; ++y)
            for (int x = img.width / 2 + margin_px; x < img.width; ++x) k += img.covered(x, y);
        return k;
    }
    static bool identical(const FrameImage& a, const FrameImage& b) {
        if (a.color.size() != b.color.size() || a.color.empty()) return false;
        for (std::size_t i = 0; i < a.color.size(); ++i)
            if (a.color[i] != b.color[i] ||
                !(a.depth[i] == b.depth[i] || (std::isinf(a.depth[i]) && std::isinf(b.depth[i]))))
                return false;
        return true;
    }
};

// Hidden or deleted: the same bytes as the sphere without those splats, every path, HQ and preview.
TEST_F(PointMarks_, GoneSplatsDrawTheImageOfTheCloudWithoutThem) {
    const SplatCloud sphere = fibonacci_sphere(20000, 1.0, 0.8, 0xff4080c0u);
    for (const std::uint8_t bits : {std::uint8_t(kPointHidden), std::uint8_t(kPointDeleted)})
        for (const CullPath path : {CullPath::cpu, CullPath::compute})
            for (const Quality q : {Quality::hq, Quality::preview}) {
                SCOPED_TRACE(testing::Message()
                             << "bits " << int(bits) << " compute " << (path == CullPath::compute) << " hq "
                             << (q == Quality::hq));
                const PointFlags flags = right_half(sphere, bits);
                auto subset = subset_points(sphere, points_with(&flags, sphere.size(), 0, kPointGone));
                ASSERT_TRUE(subset.ok()) << subset.message();
                FrameImage expected, whole, marked;
                {
                    Scene a;
                    a.add(std::move(*subset));
                    expected = a.draw(q, path);
                }
                {
                    Scene b;
                    const ecs::Entity e = b.add(sphere);
                    whole = b.draw(q, path);
                    b.reg.emplace<PointFlags>(e, flags);
                    marked = b.draw(q, path, true);
                }
                EXPECT_TRUE(identical(marked, expected));
                EXPECT_EQ(covered_right_of(marked, 4), 0);
                EXPECT_GT(covered_right_of(whole, 4), 2000);  // the splats were there to hide
            }
}

// Both culls drop the same splats and draw the same marked frame, textured or not, tinted or not.
TEST_F(PointMarks_, CpuAndComputeCullsAgreeOnMarks) {
    for (const bool textured : {false, true}) {
        SplatCloud sphere = fibonacci_sphere(20000);
        if (textured) add_checker(sphere);
        Scene sc;
        const ecs::Entity e = sc.add(sphere);
        PointFlags flags = right_half(sphere, kPointHidden);
        for (std::size_t i = 0; i < sphere.size(); i += 3) flags.bits[i] |= kPointSelected;
        sc.reg.emplace<PointFlags>(e, flags);
        for (const Quality q : {Quality::hq, Quality::preview})
            for (const bool overlay : {false, true}) {
                SCOPED_TRACE(testing::Message() << "textured " << textured << " hq " << (q == Quality::hq)
                                                << " overlay " << overlay);
                const FrameImage cpu = sc.draw(q, CullPath::cpu, overlay, overlay);
                const FrameImage gpu = sc.draw(q, CullPath::compute, overlay, overlay);
                const ImageDiff d = image_diff(cpu, gpu);
                EXPECT_LE(d.coverage_mismatch, kW * kH / 1000);
                EXPECT_LT(d.mean_color, 2e-3);
                EXPECT_EQ(covered_right_of(cpu, 4), 0);
                EXPECT_EQ(covered_right_of(gpu, 4), 0);
                EXPECT_GT(d.covered_a, 2000);
            }
    }
}

// Selecting and hiding points of a deformed cloud: the marks alone are uploaded, only the pages edited;
// the deformation runs no more and no splat is uploaded again.
TEST_F(PointMarks_, AFlagEditUploadsOnlyTheMarksOfItsPagesAndDeformsNothing) {
    const std::size_t n = kPagePoints + 30000;  // two pages
    Scene sc;
    const ecs::Entity e = sc.add(fibonacci_sphere(n));
    sc.add_lattice(e);
    auto& reg = sc.reg;
    const auto frame = [&] { (void)sc.draw(Quality::hq, CullPath::automatic, true, false, true); };
    frame();
    frame();
    const FfdStats ffd_before = reg.resource<FfdStats>();
    const gfx::ResidencyStats before = reg.resource<gfx::ResidencyStats>();
    const auto resident = [&]() -> const gfx::GpuSplats& {
        return reg.resource<gfx::GpuSplatStore>().clouds.at(e);
    };
    const std::uint64_t deformed_version = resident().deformed_version;
    EXPECT_EQ(before.marks_uploads, 0u);  // no flags yet: no marks buffer
    EXPECT_FALSE(resident().marks);

    // The first flags: every page (the buffer is made).
    reg.emplace<PointFlags>(e, PointFlags{std::vector<std::uint8_t>(n, 0)});
    mark_points_changed(reg, e, PointColumn::selection, 0, n);
    frame();
    auto stats = reg.resource<gfx::ResidencyStats>();
    EXPECT_EQ(stats.marks_uploads, 1u);
    EXPECT_EQ(stats.marks_points, n);
    EXPECT_FALSE(resident().marks_state.any_selected());

    // A selection in the second page only: that page's marks.
    {
        PointFlags& f = reg.patch<PointFlags>(e);
        for (std::size_t i = kPagePoints + 10; i < kPagePoints + 500; ++i) f.bits[i] |= kPointSelected;
    }
    mark_points_changed(reg, e, PointColumn::selection, kPagePoints + 10, 490);
    frame();
    stats = reg.resource<gfx::ResidencyStats>();
    EXPECT_EQ(stats.marks_uploads, 2u);
    EXPECT_EQ(stats.marks_points, n + (n - kPagePoints));
    EXPECT_TRUE(resident().marks_state.any_selected());

    // Hiding in the first page: that page's marks.
    {
        PointFlags& f = reg.patch<PointFlags>(e);
        for (std::size_t i = 0; i < 100; ++i) f.bits[i] |= kPointHidden;
    }
    mark_points_changed(reg, e, PointColumn::visibility, 0, 100);
    frame();
    stats = reg.resource<gfx::ResidencyStats>();
    EXPECT_EQ(stats.marks_uploads, 3u);
    EXPECT_EQ(stats.marks_points, n + (n - kPagePoints) + kPagePoints);
    EXPECT_TRUE(resident().marks_state.any_gone());

    // An edit without a mark: every page again (unmarked edits stay correct).
    {
        PointFlags& f = reg.patch<PointFlags>(e);
        f.bits[1] = 0;
    }
    frame();
    stats = reg.resource<gfx::ResidencyStats>();
    EXPECT_EQ(stats.marks_uploads, 4u);
    EXPECT_EQ(stats.marks_points, 2 * n + (n - kPagePoints) + kPagePoints);

    // Nothing else moved: no rest or deformed upload, no deformation.
    EXPECT_EQ(stats.rest_uploads, before.rest_uploads);
    EXPECT_EQ(stats.deformed_uploads, before.deformed_uploads);
    const FfdStats& ffd_after = reg.resource<FfdStats>();
    EXPECT_EQ(ffd_after.cpu_runs, ffd_before.cpu_runs);
    EXPECT_EQ(ffd_after.gpu_runs, ffd_before.gpu_runs);
    EXPECT_EQ(ffd_after.pages_redeformed, ffd_before.pages_redeformed);
    EXPECT_EQ(resident().deformed_version, deformed_version);

    // Flags removed: the buffer goes.
    reg.remove<PointFlags>(e);
    frame();
    EXPECT_FALSE(resident().marks);
}

// The tint changes exactly the selected splats' pixels (away from the boundary) and only when asked.
TEST_F(PointMarks_, SelectionTintChangesOnlyTheSelectedSplatsPixels) {
    const SplatCloud sphere = fibonacci_sphere(20000, 1.0, 0.8, 0xff4060a0u);
    for (const CullPath path : {CullPath::cpu, CullPath::compute})
        for (const Quality q : {Quality::hq, Quality::preview}) {
            SCOPED_TRACE(testing::Message()
                         << "compute " << (path == CullPath::compute) << " hq " << (q == Quality::hq));
            Scene sc;
            const ecs::Entity e = sc.add(sphere);
            const FrameImage plain = sc.draw(q, path, true);  // no flags: nothing to tint
            sc.reg.emplace<PointFlags>(e, right_half(sphere, kPointSelected));
            EXPECT_TRUE(identical(sc.draw(q, path, false), plain));  // selected but not shown
            const FrameImage tinted = sc.draw(q, path, true);
            int left_changed = 0, right_changed = 0, right = 0, yellower = 0;
            for (int y = 0; y < kH; ++y)
                for (int x = 0; x < kW; ++x) {
                    if (!plain.covered(x, y)) continue;
                    const std::size_t i = plain.index(x, y);
                    const bool changed = tinted.color[i] != plain.color[i];
                    if (x < kW / 2 - 4) left_changed += changed;
                    if (x >= kW / 2 + 4) {
                        ++right, right_changed += changed;
                        // Half way to (1, 0.85, 0): more red, less blue.
                        yellower +=
                            tinted.color[i].x > plain.color[i].x && tinted.color[i].z < plain.color[i].z;
                    }
                }
            EXPECT_EQ(left_changed, 0);
            EXPECT_GT(right, 1000);
            EXPECT_EQ(right_changed, right);
            EXPECT_EQ(yellower, right);
            // Coverage and depth are the plain frame's: the tint is colour only.
            const ImageDiff d = image_diff(tinted, plain);
            EXPECT_EQ(d.coverage_mismatch, 0);
            EXPECT_EQ(d.max_depth, 0.0);
        }
}

// The weight overlay: weight 0 blue, 1 red (lit), on both culls, textured or not.
TEST_F(PointMarks_, WeightOverlayColoursByWeight) {
    for (const bool textured : {false, true}) {
        SplatCloud sphere = fibonacci_sphere(20000);
        if (textured) add_checker(sphere);
        Scene sc;
        const ecs::Entity e = sc.add(sphere);
        PointWeights w;
        for (const glm::vec3& p : sphere.positions) w.values.push_back(p.x > 0.0f ? 1.0f : 0.0f);
        sc.reg.emplace<PointWeights>(e, w);
        for (const CullPath path : {CullPath::cpu, CullPath::compute})
            for (const Quality q : {Quality::hq, Quality::preview}) {
                SCOPED_TRACE(testing::Message()
                             << "textured " << textured << " compute " << (path == CullPath::compute)
                             << " hq " << (q == Quality::hq));
                const FrameImage img = sc.draw(q, path, false, true);
                int blue = 0, red = 0, left = 0, right = 0;
                for (int y = 0; y < kH; ++y)
                    for (int x = 0; x < kW; ++x) {
                        if (!img.covered(x, y)) continue;
                        const glm::vec4 c = img.color[img.index(x, y)];
                        if (x < kW / 2 - 4) ++left, blue += c.z > 0.05f && c.x < 1e-3f && c.y < 1e-3f;
                        if (x >= kW / 2 + 4) ++right, red += c.x > 0.05f && c.y < 1e-3f && c.z < 1e-3f;
                    }
                EXPECT_GT(left, 1000);
                EXPECT_GT(right, 1000);
                EXPECT_EQ(blue, left);
                EXPECT_EQ(red, right);
            }
    }
}

// A textured cloud under an overlay is drawn flat, each splat in its centre's texel: the unselected half
// looks like the same cloud with those texels baked into its colours, on both culls.
TEST_F(PointMarks_, ATexturedCloudUnderAnOverlayShowsItsCentresTexels) {
    SplatCloud textured = fibonacci_sphere(20000);
    add_checker(textured);
    SplatCloud baked = textured;
    const TexelView texels{textured.texture.rgba8.data(), textured.texture.width, textured.texture.height};
    for (std::size_t i = 0; i < baked.size(); ++i) {
        const glm::vec3 c = sample_texture(texels, baked.uvs[i], 0);
        baked.colors[i] = std::uint32_t(gfx::encode_srgb8(c.x)) | std::uint32_t(gfx::encode_srgb8(c.y)) << 8 |
                          std::uint32_t(gfx::encode_srgb8(c.z)) << 16 | 0xff000000u;
    }
    baked.texture = {};
    for (const CullPath path : {CullPath::cpu, CullPath::compute})
        for (const Quality q : {Quality::hq, Quality::preview}) {
            SCOPED_TRACE(testing::Message()
                         << "compute " << (path == CullPath::compute) << " hq " << (q == Quality::hq));
            FrameImage expected, overlay;
            {
                Scene sc;
                sc.add(baked);
                expected = sc.draw(q, path);
            }
            {
                Scene sc;
                const ecs::Entity e = sc.add(textured);
                sc.reg.emplace<PointFlags>(e, right_half(textured, kPointSelected));
                overlay = sc.draw(q, path, true);
            }
            double diff = 0.0;
            int left = 0, coverage = 0;
            for (int y = 0; y < kH; ++y)
                for (int x = 0; x < kW / 2 - 4; ++x) {
                    coverage += expected.covered(x, y) != overlay.covered(x, y);
                    if (!expected.covered(x, y) || !overlay.covered(x, y)) continue;
                    const std::size_t i = expected.index(x, y);
                    const glm::vec3 d = glm::abs(glm::vec3(expected.color[i]) - glm::vec3(overlay.color[i]));
                    diff += double(std::max({d.x, d.y, d.z})), ++left;
                }
            ASSERT_GT(left, 1000);
            EXPECT_EQ(coverage, 0);
            EXPECT_LT(diff / left, 4e-3);  // the baked colours are 8-bit sRGB, the texels filtered in float
        }
}

// A budgeted preview (the subset on the GPU, state preview_cpu) reads the marks through its indices.
TEST_F(PointMarks_, ABudgetedPreviewDrawsNoGoneSplat) {
    const SplatCloud sphere = fibonacci_sphere(60000);
    Scene sc;
    const ecs::Entity e = sc.add(sphere);
    sc.add_lattice(e);
    sc.reg.emplace<PointFlags>(e, right_half(sphere, kPointDeleted));
    PreviewBudget budget;
    budget.points = 5000, budget.active = true;
    sc.reg.set_resource<PreviewBudget>(budget);
    FfdSettings ffd;
    ffd.force_cpu = true;  // the preview subset is the CPU path's
    sc.reg.set_resource<FfdSettings>(ffd);
    for (const CullPath path : {CullPath::cpu, CullPath::compute}) {
        const FrameImage img = sc.draw(Quality::preview, path, false, false, true);
        const gfx::GpuSplats& gpu = sc.reg.resource<gfx::GpuSplatStore>().clouds.at(e);
        ASSERT_EQ(gpu.state, gfx::Residency::preview_cpu);
        EXPECT_EQ(gfx::resident_marks_mode(gpu), SFFD_MARKS_PRESENT | SFFD_MARKS_INDEXED);
        EXPECT_EQ(covered_right_of(img, 6), 0) << "compute " << (path == CullPath::compute);
        int left = 0;
        for (int y = 0; y < kH; ++y)
            for (int x = 0; x < kW / 2 - 6; ++x) left += img.covered(x, y);
        EXPECT_GT(left, 1000);
    }
}

}  // namespace
}  // namespace sffd::render::test
