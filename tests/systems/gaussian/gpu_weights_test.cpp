// Per-Gaussian weights on the compute path (shaders/gaussian/deform.comp with FFD_WEIGHTS): centres,
// covariances J_w Σ J_wᵀ, frames (view mode) and rotated coefficients against the double reference, and
// the CPU path to 1e-5; weight 0 is the input unchanged.
#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gpu_deform.h"
#include "tests/systems/gaussian/weighted_gaussians.h"
#include "tests/test_util/headless_gl.h"

namespace sffd::gaussian {
namespace {

class GaussianWeightsGl : public sffd::test::HeadlessGlTest {};

TEST_F(GaussianWeightsGl, ComputePassBlendsLikeTheReferenceAndTheCpu) {
    std::optional<GpuGaussianDeformer> gpu;
    sffd::test::emplace_made(gpu, GpuGaussianDeformer::create());
    const Lattice l = ffd::test::weighted_test_lattice({4, 3, 5});
    const GaussianCloud in = test::gaussians_inside(l, 2000, 1, 13u);
    const std::vector<float> w = test::gaussian_weights(in.size(), 6u);
    for (ShMode mode : {ShMode::rotate_view, ShMode::rotate_coefficients}) {
        SCOPED_TRACE(mode == ShMode::rotate_view ? "frames" : "coefficients");
        auto out = deform_on_gpu(*gpu, {&l}, in, mode, nullptr, w);
        ASSERT_TRUE(out) << out.message();
        const test::GaussianErrors e =
            test::weighted_gaussian_errors(l, in, *out, w, mode == ShMode::rotate_view);
        EXPECT_GT(e.displacement, 0.1);
        EXPECT_LT(e.position, 1e-5);
        EXPECT_LT(e.covariance, 5e-4);
        if (mode == ShMode::rotate_view) EXPECT_LT(e.frame, 2e-4);
        else EXPECT_LT(e.sh, 2e-4);
        DeformOptions options;
        options.sh = mode;
        options.weights = w.data();
        GaussianCloud cpu;
        ASSERT_TRUE(deform(l, in, cpu, options));
        double worst = 0;
        for (std::size_t i = 0; i < in.size(); ++i)
            worst = std::max(worst, double(glm::length(cpu.positions[i] - out->positions[i])));
        EXPECT_LT(worst, 1e-5);  // CPU and GPU agree
    }
}

}  // namespace
}  // namespace sffd::gaussian
