// What the tests against @playcanvas/splat-transform share (label `slow`; skipped with the reason when node
// or the package is missing: tools/fetch_splat_transform.sh): where the tool is, a scratch folder per test
// binary, running it, the skip, and a small capture to convert.
#pragma once

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_math.h"
#include "tests/systems/gaussian/test_math.h"

namespace sffd::test::splat_transform {

namespace fs = std::filesystem;

// $SPLAT_TRANSFORM, else the package tools/fetch_splat_transform.sh installs in the content cache.
inline std::string tool() {
    if (const char* env = std::getenv("SPLAT_TRANSFORM")) return env;
    const char* cache = std::getenv("SPLATFFD_CACHE_DIR");
    const fs::path base =
        cache ? fs::path(cache) : fs::path(SFFD_TEST_DATA_DIR) / ".." / ".." / "content" / "cache";
    return (base / "splat-transform" / "node_modules" / ".bin" / "splat-transform").string();
}

// `name` in a scratch folder of this process; `folder` keeps test binaries that run at once apart.
inline fs::path temp(const std::string& folder, const std::string& name) {
    const fs::path d = fs::temp_directory_path() / (folder + "_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

// Runs splat-transform with `options` then `args` (its log in `folder`); "" on success, else its output.
inline std::string run(const std::string& folder, const std::string& options, const std::string& args) {
    const std::string log = temp(folder, "log.txt").string();
    const int rc = std::system((tool() + " -w " + options + args + " >" + log + " 2>&1").c_str());
    if (rc == 0) return "";
    std::ifstream f(log);
    return "splat-transform " + args + " failed:\n" + std::string(std::istreambuf_iterator<char>(f), {});
}

// Skips a test when node or the package is missing, saying which.
class Fixture : public ::testing::Test {
protected:
    void SetUp() override {
        if (std::system("node --version >/dev/null 2>&1") != 0) GTEST_SKIP() << "node is not installed";
        if (!fs::exists(tool()))
            GTEST_SKIP() << "splat-transform not installed at " << tool()
                         << " (run tools/fetch_splat_transform.sh)";
    }
};

// A small capture: a ball of Gaussians with view-dependent colour, in front of a camera on -z.
inline GaussianCloud capture(std::size_t n, float sh_amplitude, unsigned seed = 5) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    GaussianCloud g;
    g.sh_degree = 3;
    for (std::size_t i = 0; i < n; ++i) {
        glm::vec3 p(u(rng), u(rng), u(rng));
        if (glm::length(p) > 1.0f) p = glm::normalize(p);
        g.positions.push_back(p);
        g.scales.emplace_back(0.04f + 0.03f * u(rng), 0.03f + 0.02f * u(rng), 0.06f + 0.03f * u(rng));
        g.rotations.push_back(glm::normalize(glm::quat(u(rng), u(rng), u(rng), u(rng))));
        g.opacities.push_back(0.6f + 0.35f * u(rng));
        for (int k = 0; k < 16; ++k)
            for (int c = 0; c < 3; ++c) g.sh.push_back(k == 0 ? 1.2f * u(rng) : sh_amplitude * u(rng));
    }
    return g;
}

// Gaussian by Gaussian: centres, covariances, opacities and SH within `tol` (covariance relative).
inline void expect_close(const GaussianCloud& a, const GaussianCloud& b, double tol) {
    ASSERT_EQ(a.size(), b.size());
    ASSERT_EQ(a.sh_degree, b.sh_degree);
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_LT(glm::length(glm::dvec3(a.positions[i]) - glm::dvec3(b.positions[i])), tol) << i;
        const glm::dmat3 sa = gaussian::covariance(glm::dvec3(a.scales[i]), glm::dquat(a.rotations[i]));
        const glm::dmat3 sb = gaussian::covariance(glm::dvec3(b.scales[i]), glm::dquat(b.rotations[i]));
        EXPECT_LT(test::max_abs(sa - sb), tol * test::max_abs(sa)) << i;
        EXPECT_NEAR(a.opacities[i], b.opacities[i], tol) << i;
    }
    for (std::size_t k = 0; k < a.sh.size(); ++k) EXPECT_NEAR(a.sh[k], b.sh[k], tol) << k;
}

}  // namespace sffd::test::splat_transform
