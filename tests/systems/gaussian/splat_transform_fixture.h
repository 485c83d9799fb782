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
#include <sstream>
#include <string>

#include "systems/gaussian/components.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
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

// Writes `g` (SH degree 3) to `out` with the official SPZ library (the WebAssembly build inside
// splat-transform, through niantic_spz.mjs, told the input is the 3DGS PLY frame), version `version` ("" the
// library's default), its JSON input in `json`. Returns the script's exit status.
inline int write_with_official_spz(const GaussianCloud& g, const fs::path& json, const fs::path& out,
                                   const std::string& version = "") {
    std::ostringstream j;
    j.precision(9);
    auto list = [&](const char* key, auto&& value, std::size_t count) {
        j << '"' << key << "\":[";
        for (std::size_t k = 0; k < count; ++k) j << (k ? "," : "") << value(k);
        j << "],";
    };
    const std::size_t n = g.size();
    list(
        "positions", [&](std::size_t k) { return g.positions[k / 3][int(k % 3)]; }, n * 3);
    list(
        "scales", [&](std::size_t k) { return std::log(g.scales[k / 3][int(k % 3)]); }, n * 3);
    list(
        "rotations",
        [&](std::size_t k) {
            const glm::quat q = g.rotations[k / 4];
            return k % 4 == 0 ? q.w : q[int(k % 4 - 1)];
        },
        n * 4);
    list(
        "alphas", [&](std::size_t k) { return gaussian::logit(g.opacities[k]); }, n);
    list(
        "colors", [&](std::size_t k) { return g.sh[(k / 3) * 48 + k % 3]; }, n * 3);
    list(
        "sh", [&](std::size_t k) { return g.sh[(k / 45) * 48 + 3 + k % 45]; }, n * 45);
    // Appended piecewise: GCC 12 flags operator+(const char*, string&&) with a false -Wrestrict.
    std::string text = "{";
    text += j.str();
    text += "\"n\":";
    text += std::to_string(n);
    text += ",\"degree\":3}";
    std::ofstream(json) << text;
    const fs::path dist =
        fs::path(tool()).parent_path().parent_path() / "@playcanvas" / "splat-transform" / "dist";
    const std::string script = std::string(SFFD_TEST_DATA_DIR) + "/../systems/gaussian/niantic_spz.mjs";
    std::string command = "node " + script + " " + dist.string() + " " + json.string() + " " + out.string();
    if (!version.empty()) command += " " + version;
    return std::system(command.c_str());
}

// `back` (read from an SPZ the official library wrote from `g`) is `g` within SPZ's quantisation. The library
// turns a rotation R into S R S (S = diag(1, -1, -1)), we into S R: the same covariance (S D S = D for a
// diagonal D), so covariances are compared, not quaternions.
inline void expect_official_spz_reads_as(const GaussianCloud& back, const GaussianCloud& g) {
    ASSERT_EQ(back.size(), g.size());
    for (std::size_t i = 0; i < g.size(); ++i) {
        EXPECT_LT(glm::length(back.positions[i] - g.positions[i]), 2e-3f) << i;
        const glm::dmat3 sa = gaussian::covariance(glm::dvec3(back.scales[i]), glm::dquat(back.rotations[i]));
        const glm::dmat3 sb = gaussian::covariance(glm::dvec3(g.scales[i]), glm::dquat(g.rotations[i]));
        EXPECT_LT(test::max_abs(sa - sb), 0.1 * test::max_abs(sb)) << i;  // log scales in steps of 1/16
        EXPECT_NEAR(back.opacities[i], g.opacities[i], 1.0 / 255 + 1e-6) << i;
        for (int k = 0; k < 48; ++k)  // DC in steps of 1/(255·0.15), SH in steps of 1/128
            EXPECT_NEAR(back.sh[i * 48 + std::size_t(k)], g.sh[i * 48 + std::size_t(k)], k < 3 ? 0.02 : 0.01)
                << i << " " << k;
    }
}

}  // namespace sffd::test::splat_transform
