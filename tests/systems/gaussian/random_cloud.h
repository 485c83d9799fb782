// A seeded random Gaussian cloud the GL tests share: each test file keeps its own seed, so its images and
// the thresholds measured on them stay the same.
#pragma once

#include <algorithm>
#include <cstddef>
#include <numeric>
#include <random>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/quaternion.hpp>

#include "systems/gaussian/components.h"

namespace sffd::test {

// `n` Gaussians: centres uniform in [-extent, extent]^3, anisotropic scales (0.02-0.14), random rotations,
// opacities 0.25-0.95, SH of `degree` with coefficients in [-0.6, 0.6].
inline GaussianCloud seeded_random_cloud(unsigned seed, std::size_t n, int degree, float extent = 1.0f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    GaussianCloud g;
    g.sh_degree = degree;
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.emplace_back(extent * u(rng), extent * u(rng), extent * u(rng));
        g.scales.emplace_back(0.08f + 0.06f * u(rng), 0.03f + 0.02f * u(rng), 0.05f);
        g.rotations.push_back(glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng))));
        g.opacities.push_back(0.6f + 0.35f * u(rng));
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(0.6f * u(rng));
    }
    return g;
}

// seeded_random_cloud(41, n, degree) ordered by height, so that pages are horizontal slabs.
inline GaussianCloud slab_cloud(std::size_t n, int degree) {
    const GaussianCloud g = seeded_random_cloud(41, n, degree);
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return g.positions[a].y < g.positions[b].y; });
    GaussianCloud s;
    s.sh_degree = degree;
    const std::size_t k3 = std::size_t(sh_coeffs(degree)) * 3;
    for (std::size_t i : order) {
        s.positions.push_back(g.positions[i]), s.scales.push_back(g.scales[i]);
        s.rotations.push_back(g.rotations[i]), s.opacities.push_back(g.opacities[i]);
        s.sh.insert(s.sh.end(), g.sh.begin() + std::ptrdiff_t(i * k3),
                    g.sh.begin() + std::ptrdiff_t((i + 1) * k3));
    }
    return s;
}

}  // namespace sffd::test
