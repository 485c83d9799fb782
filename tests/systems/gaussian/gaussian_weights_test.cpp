// Per-Gaussian weights (PointWeights) through the CPU Gaussian path, on every SIMD target: centres,
// covariances J_w Σ J_wᵀ and the SH (frames in view mode, rotated coefficients otherwise, by the polar
// rotation of J_w) against the test's own double reference; weight 0 is the input bit for bit, weight 1 the
// unweighted output byte for byte; the deformation system reads the entity's weights.
#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "runtime/ecs/registry.h"
#include "runtime/scene/point_columns.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gaussian_system.h"
#include "tests/systems/gaussian/weighted_gaussians.h"
#include "tests/test_util/simd_targets.h"

namespace sffd::gaussian {
namespace {

class GaussianWeights : public sffd::test::EverySimdTarget {};

TEST_P(GaussianWeights, ZeroHalfAndOneBlendCentreCovarianceAndShLikeTheReference) {
    const Lattice l = ffd::test::weighted_test_lattice({4, 3, 5});
    const GaussianCloud in = test::gaussians_inside(l, 1200, 2, 7u);
    const std::vector<float> w = test::gaussian_weights(in.size(), 3u);
    for (bool reference_shapes : {false, true})
        for (ShMode mode : {ShMode::rotate_coefficients, ShMode::rotate_view}) {
            SCOPED_TRACE(std::string(reference_shapes ? "double shapes" : "float kernel") +
                         (mode == ShMode::rotate_view ? ", frames" : ", coefficients"));
            DeformOptions options;
            options.sh = mode;
            options.reference_shapes = reference_shapes;
            options.weights = w.data();
            GaussianCloud out;
            auto st = deform(l, in, out, options);
            ASSERT_TRUE(st) << st.message();
            EXPECT_EQ(st->not_finite, 0u);
            const test::GaussianErrors e =
                test::weighted_gaussian_errors(l, in, out, w, mode == ShMode::rotate_view);
            EXPECT_GT(e.displacement, 0.1);
            EXPECT_LT(e.position, 1e-5);
            EXPECT_LT(e.covariance, 2e-4);
            if (mode == ShMode::rotate_view) EXPECT_LT(e.frame, 1e-4);
            else EXPECT_LT(e.sh, 1e-4);
        }
}

TEST_P(GaussianWeights, WeightOneIsTheUnweightedOutputBitForBit) {
    const Lattice l = ffd::test::weighted_test_lattice({5, 4, 3});
    const GaussianCloud in = test::gaussians_inside(l, 777, 1, 9u);
    const std::vector<float> ones(in.size(), 1.0f);
    for (ShMode mode : {ShMode::rotate_coefficients, ShMode::rotate_view}) {
        DeformOptions options;
        options.sh = mode;
        GaussianCloud plain, weighted;
        ASSERT_TRUE(deform(l, in, plain, options));
        options.weights = ones.data();
        ASSERT_TRUE(deform(l, in, weighted, options));
        auto same = [](const auto& a, const auto& b) {
            // Empty columns compare equal without memcmp, which must not be given null pointers.
            return a.size() == b.size() &&
                   (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
        };
        EXPECT_TRUE(same(plain.positions, weighted.positions) && same(plain.scales, weighted.scales) &&
                    same(plain.rotations, weighted.rotations) && same(plain.sh, weighted.sh) &&
                    same(plain.sh_frames, weighted.sh_frames));
    }
}

SFFD_INSTANTIATE_EVERY_SIMD_TARGET(GaussianWeights);

// The system's CPU path (and its budgeted preview's subset) reads the entity's PointWeights; replacing them
// re-deforms.
TEST(GaussianWeightsSystem, DeformationSystemReadsTheEntityWeights) {
    ecs::Registry reg;
    reg.set_resource<FfdSettings>().force_cpu = true;
    const Lattice l = ffd::test::weighted_test_lattice({3, 3, 3});
    const GaussianCloud in = test::gaussians_inside(l, 3000, 1, 5u);
    const ecs::Entity le = reg.create();
    reg.emplace<Lattice>(le, l);
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, in);
    reg.emplace<Deformers>(e, Deformers{{le}});
    reg.emplace<PointWeights>(e, PointWeights{test::gaussian_weights(in.size(), 4u)});
    gaussian_deform_system(reg, {});
    auto check = [&](const char* what) {
        SCOPED_TRACE(what);
        const DeformedGaussians& out = reg.get<DeformedGaussians>(e);
        ASSERT_EQ(out.cloud.size(), in.size());
        const test::GaussianErrors err =
            test::weighted_gaussian_errors(l, in, out.cloud, reg.get<PointWeights>(e).values, false);
        EXPECT_LT(err.position, 1e-5);
        EXPECT_LT(err.covariance, 2e-4);
        EXPECT_LT(err.sh, 1e-4);
    };
    check("first run");
    reg.patch<PointWeights>(e).values.assign(in.size(), 0.5f);
    gaussian_deform_system(reg, {});
    check("weights replaced");
}

}  // namespace
}  // namespace sffd::gaussian
