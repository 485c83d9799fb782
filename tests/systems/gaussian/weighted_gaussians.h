// Weighted Gaussians against the double reference (tests/systems/ffd/weights_reference.h): the centre
// X + w (X' − X), the covariance J_w Σ J_wᵀ, and the SH frame (view mode) or the rotated coefficients by
// the polar rotation of J_w. Shared by the CPU and GL tests of the Gaussian paths.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "systems/gaussian/components.h"
#include "systems/gaussian/sh.h"
#include "tests/systems/ffd/weights_reference.h"

namespace sffd::test {

// n Gaussians inside `l` (local coordinates in [0.05, 0.95]), anisotropic, random rotations, SH `degree`.
inline GaussianCloud gaussians_inside(const Lattice& l, std::size_t n, int degree, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0.05, 0.95);
    std::uniform_real_distribution<float> u(-1, 1);
    std::normal_distribution<float> nd;
    GaussianCloud g;
    g.origin = glm::dvec3(0.25, -0.5, 0.125);
    g.sh_degree = degree;
    for (std::size_t i = 0; i < n; ++i) {
        const glm::dvec3 w = l.origin + u01(rng) * l.axes[0] + u01(rng) * l.axes[1] + u01(rng) * l.axes[2];
        g.positions.push_back(glm::vec3(w - g.origin));
        g.scales.emplace_back(0.05f + 0.02f * u(rng), 0.02f + 0.01f * u(rng), 0.008f + 0.004f * u(rng));
        g.rotations.push_back(glm::normalize(glm::quat(nd(rng), nd(rng), nd(rng), nd(rng))));
        g.opacities.push_back(0.6f + 0.3f * u(rng));
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(0.5f * u(rng));
    }
    return g;
}

// Weights 0, 0.5 and 1 in runs (whole SIMD blocks and mixed ones), and random ones.
inline std::vector<float> gaussian_weights(std::size_t n, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    std::vector<float> w(n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t run = (i / 16) % 4;
        w[i] = run == 0 ? 0.0f : run == 1 ? 0.5f : run == 2 ? 1.0f : (i % 5 == 2 ? 0.0f : u(rng));
    }
    return w;
}

inline glm::dmat3 covariance(const glm::vec3& s, const glm::quat& q) {
    const glm::dmat3 r = glm::mat3_cast(glm::dquat(q));
    const glm::dmat3 rs(r[0] * double(s.x), r[1] * double(s.y), r[2] * double(s.z));
    return rs * glm::transpose(rs);
}

struct GaussianErrors {
    double position = 0, covariance = 0, frame = 0, sh = 0, displacement = 0;
};

// `out` is `in` deformed by `l` with `weights` (frames: out.sh_frames, else rotated out.sh). Weight-0
// Gaussians must be their input bit for bit (`exact_rest`; the GPU's read-back carries them unchanged too).
inline GaussianErrors weighted_gaussian_errors(const Lattice& l, const GaussianCloud& in,
                                               const GaussianCloud& out, const std::vector<float>& weights,
                                               bool frames) {
    GaussianErrors e;
    const std::size_t K3 = std::size_t(sh_coeffs(in.sh_degree)) * 3;
    for (std::size_t i = 0; i < in.size(); ++i) {
        const glm::dvec3 x = in.origin + glm::dvec3(in.positions[i]);
        const ffd::test::WeightedRef r = ffd::test::weighted_bernstein(l, x, double(weights[i]));
        EXPECT_TRUE(r.inside);
        if (weights[i] == 0.0f) {
            EXPECT_EQ(std::memcmp(&out.positions[i], &in.positions[i], sizeof(glm::vec3)), 0) << i;
            EXPECT_EQ(std::memcmp(&out.scales[i], &in.scales[i], sizeof(glm::vec3)), 0) << i;
            EXPECT_EQ(std::memcmp(&out.rotations[i], &in.rotations[i], sizeof(glm::quat)), 0) << i;
            if (frames && !out.sh_frames.empty()) EXPECT_EQ(out.sh_frames[i], glm::mat3(1.0f)) << i;
            if (!frames) EXPECT_EQ(std::memcmp(&out.sh[i * K3], &in.sh[i * K3], K3 * sizeof(float)), 0) << i;
            continue;
        }
        e.displacement = std::max(e.displacement, glm::length(r.position - x));
        e.position =
            std::max(e.position, glm::length(out.origin + glm::dvec3(out.positions[i]) - r.position));
        const glm::dmat3 want =
            r.jacobian * covariance(in.scales[i], in.rotations[i]) * glm::transpose(r.jacobian);
        const glm::dmat3 got = covariance(out.scales[i], out.rotations[i]);
        double num = 0, den = 0;
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k)
                num += (got[c][k] - want[c][k]) * (got[c][k] - want[c][k]), den += want[c][k] * want[c][k];
        e.covariance = std::max(e.covariance, std::sqrt(num / den));
        const glm::dmat3 R = ffd::test::ref_polar_rotation(r.jacobian);
        if (frames) {
            for (int c = 0; c < 3; ++c)
                e.frame = std::max(e.frame, glm::length(glm::dvec3(out.sh_frames[i][c]) - R[c]));
        } else if (in.sh_degree > 0) {
            std::vector<float> rotated(K3);
            gaussian::sh_rotate(gaussian::sh_rotation(R, in.sh_degree), &in.sh[i * K3], rotated.data());
            for (std::size_t k = 0; k < K3; ++k)
                e.sh = std::max(e.sh, double(std::abs(rotated[k] - out.sh[i * K3 + k])));
        }
    }
    return e;
}

}  // namespace sffd::test
