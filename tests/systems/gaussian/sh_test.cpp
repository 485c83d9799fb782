// SH basis (3DGS conventions) and SH rotation.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "systems/gaussian/components.h"
#include "systems/gaussian/sh.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;

constexpr double kPi = 3.14159265358979323846;

TEST(Sh, BasisIsOrthonormalOnTheSphere) {
    // ∫ Y_i Y_j dΩ = δ_ij checks every constant and polynomial independently of the rotation code.
    // Midpoint rule in θ (cos-weighted) and φ: error ~1e-5 at this resolution.
    const int nt = 300, np = 600;
    double gram[16][16] = {};
    double y[16];
    for (int a = 0; a < nt; ++a) {
        const double th = (a + 0.5) * kPi / nt, w = std::sin(th) * (kPi / nt) * (2 * kPi / np);
        for (int b = 0; b < np; ++b) {
            const double ph = (b + 0.5) * 2 * kPi / np;
            sh_basis(3, glm::dvec3(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)),
                     y);
            for (int i = 0; i < 16; ++i)
                for (int j = 0; j < 16; ++j) gram[i][j] += w * y[i] * y[j];
        }
    }
    for (int i = 0; i < 16; ++i)
        for (int j = 0; j < 16; ++j) EXPECT_NEAR(gram[i][j], i == j ? 1.0 : 0.0, 2e-4) << i << "," << j;
}

TEST(Sh, BandOneOrderAndSignsFollow3dgs) {
    // The 3DGS basis orders band 1 as (y, z, x) with signs (−, +, −) (the trap of sh-lib #1 and
    // nerfstudio #3010): coefficient 1 with value 1 dims the colour seen along +y by C1.
    float c[4 * 3] = {};
    c[1 * 3 + 0] = 1.0f;  // k = 1, red
    EXPECT_NEAR(sh_color(1, c, {0, 1, 0}).x, 0.5 - kShC1, 1e-7);
    EXPECT_NEAR(sh_color(1, c, {0, -1, 0}).x, 0.5 + kShC1, 1e-7);
    EXPECT_NEAR(sh_color(1, c, {1, 0, 0}).x, 0.5, 1e-7);
    float z[4 * 3] = {};
    z[2 * 3 + 1] = 1.0f;  // k = 2, green: +z
    EXPECT_NEAR(sh_color(1, z, {0, 0, 1}).y, 0.5 + kShC1, 1e-7);
    float x[4 * 3] = {};
    x[3 * 3 + 2] = 1.0f;  // k = 3, blue: −x
    EXPECT_NEAR(sh_color(1, x, {1, 0, 0}).z, 0.5 - kShC1, 1e-7);
    // DC only: 0.5 + C0 dc, clamped at 0.
    float dc[3] = {1.0f, -10.0f, 0.0f};
    const glm::vec3 col = sh_color(0, dc, {0, 0, 1});
    EXPECT_NEAR(col.x, 0.5 + kShC0, 1e-7);
    EXPECT_EQ(col.y, 0.0f);
    EXPECT_NEAR(col.z, 0.5, 1e-7);
}

TEST(Sh, SampleMatricesAreWellConditioned) {
    for (int l = 1; l <= 3; ++l) EXPECT_LT(sh_sample_condition(l), 100.0) << "band " << l;
}

glm::dmat3 random_rotation(std::mt19937& rng) {
    std::normal_distribution<double> n;
    return glm::mat3_cast(glm::normalize(glm::dquat(n(rng), n(rng), n(rng), n(rng))));
}

glm::vec3 random_dir(std::mt19937& rng) {
    std::normal_distribution<float> n;
    return glm::normalize(glm::vec3(n(rng), n(rng), n(rng)));
}

// Raw SH value (without the +0.5 and the clamp) so negative values are compared too.
glm::dvec3 sh_value(int degree, const float* c, const glm::dvec3& d) {
    double y[16];
    sh_basis(degree, d, y);
    glm::dvec3 v(0.0);
    for (int k = 0; k < sh_coeffs(degree); ++k) v += y[k] * glm::dvec3(c[k * 3], c[k * 3 + 1], c[k * 3 + 2]);
    return v;
}

TEST(Sh, RotationMatchesDirectEvaluationOfTheRotatedFunction) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1, 1);
    for (int degree = 1; degree <= 3; ++degree)
        for (int t = 0; t < 50; ++t) {
            glm::dmat3 r = random_rotation(rng);
            if (t % 2) r[0] = -r[0];  // reflections (inverted cells) too
            std::vector<float> c(std::size_t(sh_coeffs(degree)) * 3), out(c.size());
            for (float& v : c) v = u(rng);
            sh_rotate(sh_rotation(r, degree), c.data(), out.data());
            for (int s = 0; s < 200; ++s) {
                const glm::dvec3 d(random_dir(rng));
                const glm::dvec3 rotated = sh_value(degree, out.data(), d);
                const glm::dvec3 direct = sh_value(degree, c.data(), glm::transpose(r) * d);  // f(Rᵀd)
                EXPECT_LT(glm::length(rotated - direct), 2e-5) << "degree " << degree;
            }
        }
}

TEST(Sh, QuarterTurnMovesAnXLobeToY) {
    // f(d) = d.x has coefficient k=3 equal to −1/C1. Turning it 90° about +z gives f(Rᵀd) = d.y,
    // coefficient k=1 equal to −1/C1: a check on geometry, independent of the basis matrices.
    float c[4 * 3] = {}, out[4 * 3];
    for (int ch = 0; ch < 3; ++ch) c[3 * 3 + ch] = float(-1.0 / kShC1);
    const glm::dmat3 rz = glm::mat3_cast(glm::angleAxis(kPi / 2, glm::dvec3(0, 0, 1)));
    sh_rotate(sh_rotation(rz, 1), c, out);
    for (int ch = 0; ch < 3; ++ch) {
        EXPECT_NEAR(out[1 * 3 + ch], -1.0 / kShC1, 1e-5);
        EXPECT_NEAR(out[2 * 3 + ch], 0.0, 1e-6);
        EXPECT_NEAR(out[3 * 3 + ch], 0.0, 1e-6);
    }
}

TEST(Sh, RotationsCompose) {
    std::mt19937 rng(6);
    const glm::dmat3 a = random_rotation(rng), b = random_rotation(rng);
    std::vector<float> c(48), ab(48), step(48);
    std::uniform_real_distribution<float> u(-1, 1);
    for (float& v : c) v = u(rng);
    sh_rotate(sh_rotation(a * b, 3), c.data(), ab.data());
    sh_rotate(sh_rotation(b, 3), c.data(), step.data());
    sh_rotate(sh_rotation(a, 3), step.data(), step.data());  // in place
    for (std::size_t i = 0; i < c.size(); ++i) EXPECT_NEAR(ab[i], step[i], 1e-5);
    // Identity leaves coefficients unchanged.
    sh_rotate(sh_rotation(glm::dmat3(1.0), 3), c.data(), step.data());
    for (std::size_t i = 0; i < c.size(); ++i) EXPECT_NEAR(step[i], c[i], 1e-6);
}

}  // namespace
