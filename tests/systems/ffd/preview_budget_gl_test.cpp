// The preview budget through the frame (residency, ffd_system / gaussian_deform_system, render_system) on
// a headless context: a budgeted preview of a large cloud keeps the full frame's coverage, the still frame
// after it is the frame drawn without any preview, and picking and the deformation output see every point
// deformed after a moving preview.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "runtime/gfx/splat_store.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform_cloud.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/preview_budget.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/from_splats.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/gaussian/gpu_store.h"
#include "systems/picking/gaussian_source.h"
#include "systems/picking/pick_cache.h"
#include "systems/picking/splat_source.h"
#include "tests/systems/splat_render/gl_fixture.h"
#include "tests/systems/splat_render/test_scenes.h"

using namespace sffd;
using namespace sffd::render;
using namespace sffd::render::test;

namespace {

constexpr std::size_t kSplats = 200'000;
constexpr std::uint32_t kBudget = 20'000;
constexpr double kStretch = 1.5;  // along x: the lattice maps the unit sphere onto an ellipsoid exactly

Camera camera() {
    Camera c;
    c.eye = glm::dvec3(0.0, 0.0, 5.0);
    c.near_plane = 0.05f;
    c.far_plane = 20.0f;
    return c;
}

// A scene in `r`: the camera, a light, and `cloud` (a SplatCloud or a GaussianCloud) in a 2x2x2
// Bernstein lattice stretched kStretch times along x (linear maps are reproduced exactly, so the analytic
// ellipsoid is the reference). Returns the cloud and the lattice.
// The deformation runs on the CPU path, the only one with a preview budget (a GPU deforms every point):
// what the engine picks on a software rasterizer, forced so that a hardware GPU tests the same thing.
template <class Cloud>
std::pair<ecs::Entity, ecs::Entity> scene(ecs::Registry& r, Cloud cloud) {
    r.set_resource<FfdSettings>(FfdSettings{.force_cpu = true});
    r.emplace<Camera>(r.create(), camera());
    r.emplace<DirectionalLight>(r.create(), DirectionalLight{{-1.0f, -0.3f, -0.5f}, glm::vec3(1.0f), 1.0f});
    r.emplace<AmbientLight>(r.create(), AmbientLight{glm::vec3(1.0f), 0.1f});
    const ecs::Entity e = r.create();
    r.emplace<Cloud>(e, std::move(cloud));
    const ecs::Entity le = r.create();
    Lattice l = make_lattice(
        {-1.1, -1.1, -1.1}, {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {2, 2, 2});
    for (glm::dvec3& p : l.current) p.x *= kStretch;
    r.emplace<Lattice>(le, std::move(l));
    r.emplace<Deformers>(e, Deformers{{le}});
    return {e, le};
}

// One frame of the engine's phases that matter here; `moving`: the front end's preview frame.
FrameImage frame(ecs::Registry& r, Quality q, bool moving, int size = 384) {
    set_preview_active(r, moving);
    if (auto* b = r.try_resource<PreviewBudget>()) b->points = kBudget;
    RenderSettings s;
    s.quality = q, s.width = size, s.height = size, s.aux_outputs = true;
    r.set_resource<RenderSettings>(s);
    residency_system(r, FrameContext{});
    ffd_system(r, FrameContext{});
    gaussian_deform_system(r, FrameContext{});
    render_system(r, FrameContext{});
    auto img = capture_frame(r);
    EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.message());
    return img.ok() ? std::move(img.value()) : FrameImage{};
}

// Moves the lattice a little (a new deformation every frame, as while dragging).
void nudge(ecs::Registry& r, ecs::Entity le, double dx) {
    for (glm::dvec3& p : r.patch<Lattice>(le).current) p.x += dx;
}

const glm::dvec3 kEllipsoid(kStretch, 1.0, 1.0);

// `still` (an HQ frame after moving previews) against the HQ frame of a fresh scene of `gaussians` whose
// lattice moved by `dx` with no preview ever drawn: the same coverage, and equal but for float rounding.
void expect_plain_still_frame(const FrameImage& still, const GaussianCloud& gaussians, double dx) {
    ecs::Registry other;
    const auto [g, le] = scene(other, gaussians);
    nudge(other, le, dx);
    const FrameImage plain = frame(other, Quality::hq, false);
    release_render_state(other);
    const ImageDiff d = image_diff(still, plain);
    EXPECT_EQ(d.coverage_mismatch, 0);
    EXPECT_GT(d.psnr, 60.0);
}

class PreviewBudget_ : public GlRenderTest {};

double hole_fraction(const Coverage& c) { return c.inside ? double(c.holes) / double(c.inside) : 1.0; }

}  // namespace

TEST_F(PreviewBudget_, BudgetedPreviewCoversTheSurfaceLikeTheFullPreview) {
    const Camera cam = camera();
    const auto [cloud, le] = scene(reg, fibonacci_sphere(kSplats));
    const FrameImage full = frame(reg, Quality::preview, false);
    const Coverage cf = ellipsoid_coverage(full, cam, kEllipsoid);
    nudge(reg, le, 0.0);  // an edit that moves nothing: a full output serves still frames only after it
    const FrameImage budgeted = frame(reg, Quality::preview, true);
    ASSERT_EQ(reg.resource<FfdStats>().preview_runs, 1u);
    EXPECT_EQ(reg.resource<RenderStats>().splats, kBudget);  // a tenth of the splats drawn
    const Coverage cb = ellipsoid_coverage(budgeted, cam, kEllipsoid);
    ASSERT_GT(cb.inside, 20000);
    std::printf("hole fraction: full preview %.5f, budgeted %.5f (%d of %d pixels); far side %d / %d\n",
                hole_fraction(cf), hole_fraction(cb), cb.holes, cb.inside, cf.far_side, cb.far_side);
    EXPECT_LE(hole_fraction(cb), hole_fraction(cf) + 1e-3);
    EXPECT_LE(cb.far_side, cf.far_side + cb.inside / 1000);
    // The same subset without the enlargement leaves much of the surface open: the enlargement closes it.
    const std::vector<std::uint32_t> kept = reg.get<DeformedSplats>(cloud).subset.indices;
    ASSERT_EQ(kept.size(), kBudget);
    SplatCloud sparse;
    const SplatCloud& all = reg.get<SplatCloud>(cloud);
    for (std::uint32_t i : kept) {
        sparse.positions.push_back(all.positions[i]), sparse.normals.push_back(all.normals[i]);
        sparse.axis_u.push_back(all.axis_u[i]), sparse.axis_v.push_back(all.axis_v[i]);
    }
    ecs::Registry other;
    scene(other, std::move(sparse));
    const Coverage cs = ellipsoid_coverage(frame(other, Quality::preview, false), cam, kEllipsoid);
    release_render_state(other);
    std::printf("hole fraction of the subset unenlarged: %.5f\n", hole_fraction(cs));
    EXPECT_GT(hole_fraction(cs), 0.1);
}

TEST_F(PreviewBudget_, StillFrameAfterAMovingPreviewIsTheFrameWithoutPreview) {
    const auto [cloud, le] = scene(reg, fibonacci_sphere(kSplats));
    for (int i = 0; i < 3; ++i) {  // dragging: every frame a budgeted preview of a new deformation
        nudge(reg, le, 0.01);
        (void)frame(reg, Quality::preview, true);
    }
    EXPECT_EQ(reg.resource<FfdStats>().preview_runs, 3u);
    const FrameImage still_hq = frame(reg, Quality::hq, false);            // the editor's refine frame
    const FrameImage still_preview = frame(reg, Quality::preview, false);  // rest quality preview

    ecs::Registry other;
    const auto [c2, l2] = scene(other, fibonacci_sphere(kSplats));
    for (int i = 0; i < 3; ++i) nudge(other, l2, 0.01);
    const FrameImage plain_hq = frame(other, Quality::hq, false);
    const FrameImage plain_preview = frame(other, Quality::preview, false);
    release_render_state(other);
    // The CPU cull's frames repeat bit for bit: the same frame exactly.
    EXPECT_EQ(still_hq.color, plain_hq.color);
    EXPECT_EQ(still_hq.depth, plain_hq.depth);
    EXPECT_EQ(still_preview.color, plain_preview.color);
}

TEST_F(PreviewBudget_, PickingAndTheDeformedOutputSeeEveryPointAfterAMovingPreview) {
    const auto [cloud, le] = scene(reg, fibonacci_sphere(kSplats));
    (void)frame(reg, Quality::preview, false);
    nudge(reg, le, 0.05);
    (void)frame(reg, Quality::preview, true);
    ASSERT_EQ(reg.resource<FfdStats>().preview_runs, 1u);
    // The reference: every point through the current lattice.
    DeformedSplats want;
    const Lattice* lattices[] = {&reg.get<Lattice>(le)};
    ffd::deform_cloud(reg.get<SplatCloud>(cloud), lattices, want);
    EXPECT_FALSE(reg.get<DeformedSplats>(cloud).cpu_valid);  // holds the subset: nobody reads it as the cloud
    picking::PickCache cache;
    const picking::SplatSource src = picking::splat_source(reg, cloud, cache);
    ASSERT_EQ(src.positions.size(), kSplats);
    EXPECT_TRUE(std::equal(src.positions.begin(), src.positions.end(), want.positions.begin()));
    // The still frame writes the whole output again (what exports and `render` read).
    (void)frame(reg, Quality::hq, false);
    const DeformedSplats& after = reg.get<DeformedSplats>(cloud);
    ASSERT_TRUE(after.cpu_valid);
    EXPECT_EQ(after.positions, want.positions);
    EXPECT_EQ(after.axis_u, want.axis_u);
    EXPECT_EQ(reg.resource<gfx::GpuSplatStore>().clouds.at(cloud).drawn_count(), kSplats);
}

TEST_F(PreviewBudget_, GaussiansPreviewASubsetAndTheStillFrameIsUnchanged) {
    const std::size_t n = kSplats / 4;
    const GaussianCloud gaussians = gaussian::gaussians_from_splats(fibonacci_sphere(n));
    const auto [g, le] = scene(reg, gaussians);
    (void)frame(reg, Quality::preview, true);
    nudge(reg, le, 0.02);
    const FrameImage moving = frame(reg, Quality::preview, true);
    EXPECT_EQ(reg.resource<GaussianDeformStats>().preview_runs, 2u);
    EXPECT_EQ(reg.resource<RenderStats>().gaussians, kBudget);
    int covered = 0;
    for (int y = 0; y < moving.height; ++y)
        for (int x = 0; x < moving.width; ++x) covered += moving.covered(x, y);
    EXPECT_GT(covered, 10000);
    // Picking sees every Gaussian, deformed by the current lattice (x' = 1.5 x + 0.02 inside).
    picking::PickCache cache;
    const picking::GaussianSource src = picking::gaussian_source(reg, g, cache);
    ASSERT_EQ(src.positions.size(), n);
    for (std::size_t i = 0; i < n; i += 997)
        EXPECT_NEAR(double(src.positions[i].x), double(gaussians.positions[i].x) * kStretch + 0.02, 1e-4)
            << i;
    const FrameImage still = frame(reg, Quality::hq, false);
    EXPECT_EQ(reg.get<DeformedGaussians>(g).cloud.size(), n);

    expect_plain_still_frame(still, gaussians, 0.02);
}

// A moving preview draws the subset's DC colour only (degree 0: no SH rotation, upload or evaluation);
// the still frame after it draws every Gaussian at the cloud's full degree, exactly as without a preview.
TEST_F(PreviewBudget_, GaussianPreviewDrawsDegreeZeroAndTheStillFrameTheFullDegree) {
    const std::size_t n = kSplats / 4;
    GaussianCloud gaussians = gaussian::gaussians_from_splats(fibonacci_sphere(n));
    ASSERT_EQ(gaussians.sh_degree, 0);
    // Degree 3 with strong view-dependent terms: the DC term kept, the others varying per Gaussian.
    constexpr int kDegree = 3;
    const auto K = std::size_t(sh_coeffs(kDegree));
    std::vector<float> sh(n * K * 3, 0.0f);
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t k = 0; k < K; ++k)
            for (std::size_t c = 0; c < 3; ++c)
                sh[(i * K + k) * 3 + c] =
                    k == 0 ? gaussians.sh[i * 3 + c] : 0.3f * float(std::sin(double(i * 7 + k * 3 + c)));
    gaussians.sh = std::move(sh);
    gaussians.sh_degree = kDegree;
    const auto [g, le] = scene(reg, gaussians);
    (void)frame(reg, Quality::preview, true);
    nudge(reg, le, 0.02);
    const FrameImage moving = frame(reg, Quality::preview, true);
    const gaussian::GpuGaussians& gpu = reg.resource<gaussian::GpuGaussianStore>().clouds.at(g);
    EXPECT_EQ(gpu.state, gfx::Residency::preview_cpu);
    EXPECT_EQ(gpu.drawn_sh_degree(), 0);
    EXPECT_EQ(reg.resource<RenderStats>().gaussians, kBudget);
    int covered = 0;
    for (int y = 0; y < moving.height; ++y)
        for (int x = 0; x < moving.width; ++x) covered += moving.covered(x, y);
    EXPECT_GT(covered, 10000);

    const FrameImage still = frame(reg, Quality::hq, false);
    EXPECT_NE(gpu.state, gfx::Residency::preview_cpu);
    EXPECT_EQ(gpu.drawn_sh_degree(), kDegree);
    expect_plain_still_frame(still, gaussians, 0.02);
}
