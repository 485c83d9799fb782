// The Gaussian deformation pass (systems/gaussian/gpu_deform.cpp) on a hardware GPU's terms:
// - the memory barriers GL 4.5 §7.12.2 asks for (runtime/gfx/barrier.h records them): llvmpipe finishes
//   every command before the next, so a missing bit shows only on a GPU;
// - clouds whose Gaussians, SH frames or coefficients exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE (simulated
//   with a small limit, gfx::ScopedLimits) run in element ranges and give exactly the one-dispatch result
//   (the same program computes each Gaussian from the same inputs, on any implementation).
#include <gtest/gtest.h>

#include <optional>
#include <random>
#include <string>
#include <vector>

#include "runtime/gfx/barrier.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/limits.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/gpu_deform.h"
#include "systems/gaussian/sh.h"
#include "tests/test_util/headless_gl.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;

class GaussianDeformGpuTerms : public sffd::test::HeadlessGlTest {
protected:
    void SetUp() override {
        HeadlessGlTest::SetUp();
        if (IsSkipped() || HasFatalFailure()) return;
        sffd::test::emplace_made(deformer, GpuGaussianDeformer::create());
    }
    void TearDown() override { deformer.reset(); }
    std::optional<GpuGaussianDeformer> deformer;
};

GaussianCloud cloud_of(std::size_t n, int degree, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    std::normal_distribution<float> nd;
    GaussianCloud g;
    g.origin = glm::dvec3(0.25, -0.5, 0.125);
    g.sh_degree = degree;
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.emplace_back(0.9f * u(rng), 0.9f * u(rng), 0.9f * u(rng));
        g.scales.emplace_back(0.02f * (1.2f + u(rng)), 0.03f * (1.2f + u(rng)), 0.005f * (1.5f + u(rng)));
        g.rotations.push_back(glm::normalize(glm::quat(nd(rng), nd(rng), nd(rng), nd(rng))));
        g.opacities.push_back(0.5f + 0.4f * u(rng));
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(0.5f * u(rng));
    }
    return g;
}

// B-spline lattices: the generic program (no per-shape compile, which is slow on llvmpipe).
Lattice twisted_box(glm::dvec3 origin) {
    Lattice l = ffd::make_lattice(origin - glm::dvec3(1.0),
                                  {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)}, {3, 4, 3},
                                  LatticeBasis::bspline);
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.7, origin);
    return l;
}

}  // namespace

// Per lattice: a write-after-read barrier before the dispatch (the last frame's projection read the
// buffers it overwrites), then the bits for every later reader: SSBO loads (the next lattice in place, the
// projection), vertex fetches, and buffer updates (read-backs, copies, the statistics copy).
TEST_F(GaussianDeformGpuTerms, DeformationIssuesTheRequiredBarriersInOrder) {
    const GaussianCloud cloud = cloud_of(500, 1, 3);
    const Lattice a = twisted_box(cloud.origin), b = twisted_box(cloud.origin + glm::dvec3(0.1));
    for (ShMode mode : {ShMode::rotate_view, ShMode::rotate_coefficients}) {
        gfx::BarrierLog log;
        auto out = deform_on_gpu(*deformer, {&a, &b}, cloud, mode);
        ASSERT_TRUE(out) << out.message();
        std::string all;
        for (const gfx::BarrierRecord& r : log.records())
            all += r.site + " " + gfx::barrier_bit_names(r.bits) + "\n";
        constexpr std::uint32_t after =
            GL_SHADER_STORAGE_BARRIER_BIT | GL_VERTEX_ATTRIB_ARRAY_BARRIER_BIT | GL_BUFFER_UPDATE_BARRIER_BIT;
        EXPECT_EQ(log.count("gaussian.deform.reuse"), 2u) << all;
        EXPECT_EQ(log.count("gaussian.deform"), 2u) << all;
        EXPECT_EQ(log.bits_at("gaussian.deform.reuse") & GL_SHADER_STORAGE_BARRIER_BIT,
                  std::uint32_t(GL_SHADER_STORAGE_BARRIER_BIT))
            << all;
        // Each dispatch's result barrier carries every bit (not just their union over the two).
        for (const gfx::BarrierRecord& r : log.records()) {
            if (r.site == "gaussian.deform") {
                EXPECT_EQ(r.bits & after, after) << all;
            }
        }
        // Order: reuse, deform, reuse, deform (the second lattice reads the first's output in place).
        std::vector<std::string> sites;
        for (const gfx::BarrierRecord& r : log.records())
            if (r.site.rfind("gaussian.deform", 0) == 0) sites.push_back(r.site);
        const std::vector<std::string> expected = {"gaussian.deform.reuse", "gaussian.deform",
                                                   "gaussian.deform.reuse", "gaussian.deform"};
        EXPECT_EQ(sites, expected) << all;
    }
}

// Degree 2: 108 bytes of coefficients a Gaussian, so the ranges' offsets must step by whole alignment
// units of three strides at once (48-byte Gaussians and frames, 108-byte SH).
TEST_F(GaussianDeformGpuTerms, CloudOverTheBlockSizeDeformsInRangesExactlyAsOneDispatch) {
    const GaussianCloud cloud = cloud_of(3000, 2, 7);
    const Lattice a = twisted_box(cloud.origin), b = twisted_box(cloud.origin + glm::dvec3(0.05, -0.1, 0));
    for (ShMode mode : {ShMode::rotate_view, ShMode::rotate_coefficients}) {
        const char* what = mode == ShMode::rotate_view ? "frames" : "coefficients";
        GpuDeformStats whole_stats, batched_stats;
        auto whole = deform_on_gpu(*deformer, {&a, &b}, cloud, mode, &whole_stats);
        ASSERT_TRUE(whole) << whole.message();
        gfx::GlLimits small = gfx::limits();
        small.max_ssbo_block_size = 40'000;  // 370 Gaussians of SH (fewer after alignment): 9+ batches
        const std::uint64_t errors = gfx::debug_error_count();
        auto batched = [&] {
            gfx::ScopedLimits scope(small);
            return deform_on_gpu(*deformer, {&a, &b}, cloud, mode, &batched_stats);
        }();
        ASSERT_TRUE(batched) << batched.message();
        EXPECT_EQ(gfx::debug_error_count(), errors) << what << ": a range bound past a buffer or misaligned";
        EXPECT_EQ(batched_stats.inside, whole_stats.inside) << what;
        EXPECT_EQ(batched_stats.inverted, whole_stats.inverted) << what;
        EXPECT_GT(whole_stats.inside, cloud.size()) << what;  // the second lattice holds most of them too
        ASSERT_EQ(batched->size(), whole->size());
        std::size_t moved = 0;
        for (std::size_t i = 0; i < cloud.size(); ++i) {
            ASSERT_EQ(batched->positions[i], whole->positions[i]) << what << " " << i;
            ASSERT_EQ(batched->rotations[i], whole->rotations[i]) << what << " " << i;
            ASSERT_EQ(batched->scales[i], whole->scales[i]) << what << " " << i;
            ASSERT_EQ(batched->opacities[i], whole->opacities[i]) << what << " " << i;
            moved += whole->positions[i] != cloud.positions[i];
        }
        EXPECT_GT(moved, cloud.size() / 2) << what;
        EXPECT_EQ(batched->sh, whole->sh) << what;
        EXPECT_EQ(batched->sh_frames, whole->sh_frames) << what;
        if (mode == ShMode::rotate_coefficients) {
            EXPECT_NE(whole->sh, cloud.sh);
        } else {
            EXPECT_EQ(whole->sh_frames.size(), cloud.size());
        }
    }
}

TEST_F(GaussianDeformGpuTerms, RefusesNamingTheLimitWhenNotOneGaussianFits) {
    const GaussianCloud cloud = cloud_of(50, 0, 11);
    const Lattice a = twisted_box(cloud.origin);
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 32;  // less than one 48-byte Gaussian
    gfx::ScopedLimits scope(small);
    auto out = deform_on_gpu(*deformer, {&a}, cloud, ShMode::rotate_view);
    ASSERT_FALSE(out);
    EXPECT_NE(out.message().find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE"), std::string::npos) << out.message();
}
