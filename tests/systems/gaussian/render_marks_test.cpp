// Point marks on 3D Gaussians in the render system (runtime/gfx/point_marks.h, marks.comp): hidden and
// deleted Gaussians are never drawn (every sort and blend path: the image of the cloud without them), a
// flag edit uploads the marks only and re-deforms nothing, the selection tint and the weight overlay
// colour only the Gaussians they should. Headless EGL (llvmpipe here).
#include <gtest/gtest.h>

#include <optional>

#include <glm/gtc/quaternion.hpp>

#include "runtime/gfx/context.h"
#include "runtime/gfx/residency.h"
#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "runtime/scene/point_columns.h"
#include "runtime/scene/point_pages.h"
#include "runtime/scene/point_subset.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/gaussian/gpu_store.h"
#include "systems/residency/residency_system.h"
#include "systems/splat_render/gaussian_draw.h"
#include "systems/splat_render/gaussian_pass.h"
#include "systems/splat_render/splat_render.h"
#include "tests/systems/gaussian/random_cloud.h"
#include "tests/test_util/gl_required.h"

namespace {

using namespace sffd;

class GaussianMarks : public testing::Test {
protected:
    static void SetUpTestSuite() {
        auto c = gfx::create_context({.headless = true, .width = 16, .height = 16});
        if (c) context().emplace(std::move(*c));
    }
    static void TearDownTestSuite() { context().reset(); }
    static std::optional<gfx::GlContext>& context() {
        static std::optional<gfx::GlContext> c;
        return c;
    }
    void SetUp() override {
        if (!context()) SFFD_GL_UNAVAILABLE("no headless GL 4.5 context");
    }
    void TearDown() override {
        if (holder) render::release_render_state(*holder);
    }

    // A fresh scene (a registry is not movable: the old one is destroyed in place).
    void reset(GaussianCloud cloud) {
        if (holder) render::release_render_state(*holder);
        holder.emplace();
        Camera c;
        c.eye = {0.0, 0.0, 4.0}, c.target = {0.0, 0.0, 0.0}, c.up = {0, 1, 0};
        c.fov_y_degrees = 40.0f, c.near_plane = 0.1f, c.far_plane = 20.0f;
        reg().emplace<Camera>(reg().create(), c);
        entity = reg().create();
        reg().emplace<GaussianCloud>(entity, std::move(cloud));
    }
    render::FrameImage frame(render::Quality q = render::Quality::hq, bool selection = false,
                             bool weights = false, render::SortPath sort = render::SortPath::automatic,
                             render::BlendPath blend = render::BlendPath::quads) {
        render::RenderSettings s;
        s.width = 96, s.height = 72, s.quality = q, s.aux_outputs = true;
        s.show_selection = selection, s.show_weights = weights;
        reg().set_resource<render::RenderSettings>(s);
        if (auto r = render::gaussian_pass_renderer(reg()); r.ok())
            (*r)->sort_path = sort, (*r)->blend_path = blend;
        residency_system(reg(), FrameContext{});
        gaussian_deform_system(reg(), FrameContext{});
        render::render_system(reg(), FrameContext{});
        auto img = render::capture_frame(reg());
        EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.message());
        return img.ok() ? std::move(*img) : render::FrameImage{};
    }
    ecs::Registry& reg() { return *holder; }
    std::optional<ecs::Registry> holder;
    ecs::Entity entity;
};

bool same(const render::FrameImage& a, const render::FrameImage& b) { return a.color == b.color; }

// One Gaussian of a flat colour (DC only), isotropic.
void add_blob(GaussianCloud& g, glm::vec3 at, float sigma, glm::vec3 rgb) {
    g.positions.push_back(at);
    g.scales.push_back(glm::vec3(sigma));
    g.rotations.push_back(glm::quat(1, 0, 0, 0));
    g.opacities.push_back(0.9f);
    for (int k = 0; k < 3; ++k) g.sh.push_back((rgb[k] - 0.5f) / 0.28209479f);
}

TEST_F(GaussianMarks, GoneGaussiansDrawTheImageOfTheCloudWithoutThem) {
    const GaussianCloud cloud = test::seeded_random_cloud(31, 3000, 1);
    PointFlags flags;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        flags.bits.push_back(cloud.positions[i].x > 0.0f ? std::uint8_t(i % 2 ? kPointHidden : kPointDeleted)
                                                         : std::uint8_t(0));
    auto subset = subset_points(cloud, points_with(&flags, cloud.size(), 0, kPointGone));
    ASSERT_TRUE(subset.ok()) << subset.message();
    for (const render::Quality q : {render::Quality::hq, render::Quality::preview})
        for (const render::SortPath sort : {render::SortPath::cpu, render::SortPath::gpu})
            for (const render::BlendPath blend : {render::BlendPath::quads, render::BlendPath::tiles}) {
                SCOPED_TRACE(testing::Message() << "hq " << (q == render::Quality::hq) << " gpu sort "
                                                << (sort == render::SortPath::gpu) << " tiles "
                                                << (blend == render::BlendPath::tiles));
                reset(*subset);
                const render::FrameImage expected = frame(q, false, false, sort, blend);
                const std::uint64_t expected_pixels = render::gaussian_pass_stats(reg()).covered_pixels;
                reset(cloud);
                const render::FrameImage whole = frame(q, false, false, sort, blend);
                reg().emplace<PointFlags>(entity, flags);
                const render::FrameImage marked = frame(q, true, false, sort, blend);
                EXPECT_TRUE(same(marked, expected));
                // The covered pixels that choose quads or tiles are the subset's too.
                EXPECT_EQ(render::gaussian_pass_stats(reg()).covered_pixels, expected_pixels);
                EXPECT_GT(expected_pixels, 0u);
                EXPECT_FALSE(same(whole, expected));  // the hidden ones were drawn before
                // Unhidden again: the whole cloud's image.
                reg().remove<PointFlags>(entity);
                EXPECT_TRUE(same(frame(q, false, false, sort, blend), whole));
            }
}

TEST_F(GaussianMarks, AFlagEditUploadsOnlyTheMarksAndDeformsNothing) {
    reset(test::seeded_random_cloud(37, 2000, 1));
    const ecs::Entity le = reg().create();
    reg().emplace<Lattice>(
        le, make_lattice({-1.5, -1.5, -1.5}, {glm::dvec3(3, 0, 0), glm::dvec3(0, 3, 0), glm::dvec3(0, 0, 3)},
                         {2, 2, 2}));
    reg().get<Lattice>(le).current[0] += glm::dvec3(0.2, 0.0, 0.0);
    reg().emplace<Deformers>(entity, Deformers{{le}});
    frame();
    frame();
    const GaussianDeformStats deform_before = reg().resource<GaussianDeformStats>();
    const gfx::ResidencyStats before = reg().resource<gfx::ResidencyStats>();
    const std::size_t n = reg().get<GaussianCloud>(entity).size();
    reg().emplace<PointFlags>(entity, PointFlags{std::vector<std::uint8_t>(n, 0)});
    mark_points_changed(reg(), entity, PointColumn::selection, 0, n);
    frame(render::Quality::hq, true);
    {
        PointFlags& f = reg().patch<PointFlags>(entity);
        f.bits[7] |= kPointHidden;
    }
    mark_points_changed(reg(), entity, PointColumn::visibility, 7, 1);
    frame(render::Quality::hq, true);
    const gfx::ResidencyStats& after = reg().resource<gfx::ResidencyStats>();
    EXPECT_EQ(after.marks_uploads, before.marks_uploads + 2);
    EXPECT_EQ(after.rest_uploads, before.rest_uploads);
    EXPECT_EQ(after.deformed_uploads, before.deformed_uploads);
    const GaussianDeformStats& deform_after = reg().resource<GaussianDeformStats>();
    EXPECT_EQ(deform_after.cpu_runs, deform_before.cpu_runs);
    EXPECT_EQ(deform_after.gpu_runs, deform_before.gpu_runs);
    EXPECT_EQ(deform_after.pages_redeformed, deform_before.pages_redeformed);
    EXPECT_TRUE(reg().resource<gaussian::GpuGaussianStore>().clouds.at(entity).marks_state.any_gone());
}

// Two blobs far apart: the selected one is tinted (more red, less blue), the other's pixels unchanged;
// the weights paint them blue (0) and red (1).
TEST_F(GaussianMarks, SelectionTintAndWeightsColourOnlyTheirGaussians) {
    GaussianCloud g;
    add_blob(g, {-0.8f, 0.0f, 0.0f}, 0.15f, {0.3f, 0.5f, 0.8f});
    add_blob(g, {0.8f, 0.0f, 0.0f}, 0.15f, {0.3f, 0.5f, 0.8f});
    reset(g);
    const render::FrameImage plain = frame();
    reg().emplace<PointFlags>(entity, PointFlags{{0, kPointSelected}});
    EXPECT_TRUE(same(frame(render::Quality::hq, false), plain));
    const render::FrameImage tinted = frame(render::Quality::hq, true);
    reg().emplace<PointWeights>(entity, PointWeights{{0.0f, 1.0f}});
    const render::FrameImage weights = frame(render::Quality::hq, false, true);
    int left = 0, right = 0, left_changed = 0, right_yellower = 0, blue = 0, red = 0;
    for (int y = 0; y < plain.height; ++y)
        for (int x = 0; x < plain.width; ++x) {
            const std::size_t i = plain.index(x, y);
            if (plain.color[i].w < 0.2f) continue;  // the blobs' cores
            const glm::vec4 p = plain.color[i], t = tinted.color[i], w = weights.color[i];
            if (x < plain.width / 2) {
                ++left, left_changed += t != p;
                blue += w.z > 0.1f && w.z > 4.0f * std::max(w.x, w.y);
            } else {
                ++right, right_yellower += t.x > p.x && t.z < p.z;
                red += w.x > 0.1f && w.x > 4.0f * std::max(w.y, w.z);
            }
        }
    EXPECT_GT(left, 20);
    EXPECT_GT(right, 20);
    EXPECT_EQ(left_changed, 0);
    EXPECT_EQ(right_yellower, right);
    EXPECT_EQ(blue, left);
    EXPECT_EQ(red, right);
}

}  // namespace
