// One frame of reference for clouds and lattices, on a headless context (llvmpipe here): the compute
// passes (forced, as llvmpipe would pick the CPU) deform a moved cloud through a moved lattice exactly as
// the CPU path does, for surface splats and Gaussians; and a moved cloud with its lattice at rest draws
// the same image as the unmoved one seen from a camera moved with it (it used to be cut to a sliver by
// the screen rectangle of a deformed box left at the origin).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "runtime/scene/camera.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/from_splats.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/picking/gaussian_source.h"
#include "systems/picking/pick_cache.h"
#include "systems/picking/splat_source.h"
#include "tests/systems/splat_render/gl_fixture.h"
#include "tests/systems/splat_render/test_scenes.h"

using namespace sffd;
using namespace sffd::render;
using namespace sffd::render::test;

namespace {

Transform make_transform(glm::dvec3 t, glm::dvec3 axis, double angle, glm::dvec3 s) {
    Transform x;
    x.translation = t;
    x.rotation = glm::angleAxis(angle, glm::normalize(axis));
    x.scale = s;
    return x;
}
const Transform kCloudT = make_transform({0.6, -0.3, 0.4}, {1, 2, 3}, 0.7, {1.3, 0.8, 1.1});
const Transform kLatticeT = make_transform({-0.3, 0.5, 0.2}, {0, 1, 1}, -0.5, {0.9, 1.2, 1.05});

// A 3x3x3 lattice on [-1.1, 1.1]^3 (its own frame), twisted about y.
Lattice twisted_lattice() {
    Lattice l = make_lattice(
        glm::dvec3(-1.1), {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {3, 3, 3});
    for (int i = 0; i <= 3; ++i)
        for (int j = 0; j <= 3; ++j)
            for (int k = 0; k <= 3; ++k) {
                glm::dvec3& p = l.current[l.index(i, j, k)];
                const double a = 0.9 * (double(j) / 3.0 - 0.5);
                p = glm::dvec3(std::cos(a) * p.x + std::sin(a) * p.z, p.y,
                               -std::sin(a) * p.x + std::cos(a) * p.z);
            }
    return l;
}

class TransformFrame_ : public GlRenderTest {
protected:
    // cloud (Cloud: SplatCloud or GaussianCloud) moved by kCloudT, bound to a twisted lattice moved by
    // kLatticeT.
    template <class Cloud>
    ecs::Entity moved_scene(ecs::Registry& r, Cloud cloud) {
        const ecs::Entity e = r.create();
        r.emplace<Cloud>(e, std::move(cloud));
        r.emplace<Transform>(e, kCloudT);
        const ecs::Entity le = r.create();
        r.emplace<Lattice>(le, twisted_lattice());
        r.emplace<Transform>(le, kLatticeT);
        r.emplace<Deformers>(e, Deformers{{le}});
        return e;
    }
    static void deform(ecs::Registry& r, bool gpu) {
        r.set_resource<FfdSettings>(FfdSettings{.force_cpu = !gpu, .force_gpu = gpu});
        residency_system(r, FrameContext{});
        ffd_system(r, FrameContext{});
        gaussian_deform_system(r, FrameContext{});
    }
    // One frame of the phases that matter (residency, deformation, render), read back.
    FrameImage frame(ecs::Registry& r, int w = 320, int h = 240) {
        RenderSettings s;
        s.quality = Quality::hq, s.width = w, s.height = h, s.aux_outputs = true;
        r.set_resource<RenderSettings>(s);
        deform(r, false);
        render_system(r, FrameContext{});
        auto img = capture_frame(r);
        EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.message());
        return img.ok() ? std::move(img.value()) : FrameImage{};
    }
    template <class Cloud>
    FrameImage rest_lattice_frame(Cloud cloud, const Transform* cloud_t, const Transform* lattice_t,
                                  glm::dvec3 camera_shift) {
        ecs::Registry r;
        Camera cam;
        // From afar with a narrow field (as a scene camera framing several objects): a box left at the
        // origin no longer covers the moved cloud's image.
        cam.eye = glm::dvec3(0, 0, 9.0) + camera_shift, cam.target = camera_shift;
        cam.fov_y_degrees = 20.0f;
        cam.near_plane = 0.05f, cam.far_plane = 20.0f;
        r.emplace<Camera>(r.create(), cam);
        r.emplace<DirectionalLight>(r.create(),
                                    DirectionalLight{{-1.0f, -0.3f, -0.5f}, glm::vec3(1.0f), 1.0f});
        const ecs::Entity e = r.create();
        r.emplace<Cloud>(e, std::move(cloud));
        if (cloud_t) r.emplace<Transform>(e, *cloud_t);
        const ecs::Entity le = r.create();
        r.emplace<Lattice>(
            le,
            make_lattice(glm::dvec3(-1.1),
                         {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {4, 4, 4}));
        if (lattice_t) r.emplace<Transform>(le, *lattice_t);
        r.emplace<Deformers>(e, Deformers{{le}});
        FrameImage img = frame(r);
        release_render_state(r);
        gaussian_release_gpu(r), ffd_release_gpu(r);
        return img;
    }
};

double world_distance(const glm::dmat4& m, const glm::dvec3& oa, const glm::vec3& a, const glm::dvec3& ob,
                      const glm::vec3& b) {
    return glm::length(glm::dvec3(m * glm::dvec4(oa + glm::dvec3(a), 1.0)) -
                       glm::dvec3(m * glm::dvec4(ob + glm::dvec3(b), 1.0)));
}

}  // namespace

// The compute pass and the CPU path, both fed the lattice in the cloud's frame, agree for a moved cloud
// in a moved, twisted lattice (the CPU path itself is checked against the world-space reference in
// transform_frame_test.cpp).
TEST_F(TransformFrame_, GpuDeformationOfAMovedSplatCloudEqualsTheCpuPath) {
    ecs::Registry cpu, gpu;
    const ecs::Entity a = moved_scene(cpu, fibonacci_sphere(4000));
    const ecs::Entity b = moved_scene(gpu, fibonacci_sphere(4000));
    deform(cpu, false);
    deform(gpu, true);
    ASSERT_TRUE(ffd::output_on_gpu(gpu, b));
    const DeformedSplats& want = cpu.get<DeformedSplats>(a);
    picking::PickCache cache;
    const picking::SplatSource got = picking::splat_source(gpu, b, cache);
    ASSERT_EQ(got.kind, picking::SplatSource::Kind::gpu_read_back);
    ASSERT_EQ(got.positions.size(), want.positions.size());
    const glm::dmat4 m = model_matrix(&kCloudT);
    double worst = 0, worst_n = 0;
    std::size_t moved = 0;
    const SplatCloud& rest = cpu.get<SplatCloud>(a);
    for (std::size_t i = 0; i < want.positions.size(); ++i) {
        worst =
            std::max(worst, world_distance(m, want.origin, want.positions[i], got.origin, got.positions[i]));
        worst_n = std::max(worst_n, double(glm::length(want.normals[i] - got.normals[i])));
        moved += glm::length(want.positions[i] - rest.positions[i]) > 1e-3f;
    }
    EXPECT_LT(worst, 2e-5);
    EXPECT_LT(worst_n, 1e-4);
    EXPECT_GT(moved, want.positions.size() / 10);                       // the twist reaches the cloud
    EXPECT_EQ(gpu.get<DeformedSplats>(b).bounds_min, want.bounds_min);  // one world box for both paths
    EXPECT_EQ(gpu.get<DeformedSplats>(b).bounds_max, want.bounds_max);
    ffd_release_gpu(gpu);
}

TEST_F(TransformFrame_, GpuDeformationOfMovedGaussiansEqualsTheCpuPath) {
    ecs::Registry cpu, gpu;
    const ecs::Entity a = moved_scene(cpu, gaussian::gaussians_from_splats(fibonacci_sphere(4000)));
    const ecs::Entity b = moved_scene(gpu, gaussian::gaussians_from_splats(fibonacci_sphere(4000)));
    deform(cpu, false);
    deform(gpu, true);
    ASSERT_TRUE(gaussian::output_on_gpu(gpu, b));
    const GaussianCloud& want = cpu.get<DeformedGaussians>(a).cloud;
    picking::PickCache cache;
    const picking::GaussianSource got = picking::gaussian_source(gpu, b, cache);
    ASSERT_EQ(got.kind, picking::GaussianSource::Kind::gpu_read_back);
    ASSERT_EQ(got.positions.size(), want.size());
    const glm::dmat4 m = model_matrix(&kCloudT);
    double worst = 0, worst_cov = 0;
    for (std::size_t i = 0; i < want.size(); ++i) {
        worst =
            std::max(worst, world_distance(m, want.origin, want.positions[i], got.origin, got.positions[i]));
        const glm::dmat3 s0 = gaussian::covariance(glm::dvec3(want.scales[i]), glm::dquat(want.rotations[i]));
        const glm::dmat3 s1 = gaussian::covariance(glm::dvec3(got.scales[i]), glm::dquat(got.rotations[i]));
        double err = 0, norm = 0;
        for (int r = 0; r < 3; ++r)
            for (int k = 0; k < 3; ++k)
                err = std::max(err, std::abs(s0[r][k] - s1[r][k])), norm = std::max(norm, std::abs(s0[r][k]));
        worst_cov = std::max(worst_cov, err / norm);
    }
    EXPECT_LT(worst, 2e-5);
    EXPECT_LT(worst_cov, 1e-4);
    gaussian_release_gpu(gpu);
}

// A cloud moved 3 units along x, its lattice at rest (left at the origin, or moved with it), seen from a
// camera moved with it: the same pixels covered as the unmoved cloud from the unmoved camera (the moved
// one used to show a sliver of about 8% of them). Surface splats and Gaussians.
TEST_F(TransformFrame_, AMovedCloudWithItsLatticeAtRestCoversWhatTheUnmovedOneDoes) {
    const Transform moved = make_transform({3, 0, 0}, {0, 1, 0}, 0.0, {1, 1, 1});
    const glm::dvec3 shift(3, 0, 0);
    // Textured: the GL rasteriser, which the screen rectangle limits (the CPU one draws untextured clouds).
    SplatCloud sphere = fibonacci_sphere(20000);
    add_checker(sphere);
    const FrameImage still = rest_lattice_frame(sphere, nullptr, nullptr, glm::dvec3(0));
    const FrameImage g_still = rest_lattice_frame(gaussian::gaussians_from_splats(fibonacci_sphere(20000)),
                                                  nullptr, nullptr, glm::dvec3(0));
    for (const bool lattice_moved : {false, true}) {
        const Transform* lt = lattice_moved ? &moved : nullptr;
        const FrameImage img = rest_lattice_frame(sphere, &moved, lt, shift);
        const ImageDiff d = image_diff(still, img);
        EXPECT_GT(d.covered_a, 10000) << "the unmoved sphere fills a good part of the frame";
        EXPECT_LT(d.coverage_mismatch, d.covered_a / 200) << "lattice moved: " << lattice_moved;
        EXPECT_GT(d.psnr, 40.0) << "lattice moved: " << lattice_moved;
        const FrameImage g =
            rest_lattice_frame(gaussian::gaussians_from_splats(fibonacci_sphere(20000)), &moved, lt, shift);
        const ImageDiff gd = image_diff(g_still, g);
        EXPECT_GT(gd.covered_a, 10000);
        EXPECT_LT(gd.coverage_mismatch, gd.covered_a / 200) << "Gaussians, lattice moved: " << lattice_moved;
    }
}
