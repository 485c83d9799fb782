// GPU deformation of 3D Gaussians (systems/gaussian/gpu_deform.h, shaders/gaussian/deform.comp) against
// the CPU deformation gaussian::deform (double-precision Jacobi, ShMode::rotate_view) on a headless EGL
// context. Covariances are compared as matrices Σ = R S Sᵀ Rᵀ (a quaternion and its axis order are not
// unique). Stated tolerances: centres 5e-6 (lattice size 2), Σ 3e-5 relative to its largest entry, SH
// frames 1e-5 per entry (float on the GPU vs double on the CPU from the same float J; llvmpipe measures
// at most 6e-7, 4e-6 and 4e-7: the margin is for GPUs' less exact inversesqrt/division).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>
#include <random>

#include <glm/gtc/quaternion.hpp>

#include "runtime/ecs/registry.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/dispatch.h"
#include "runtime/gfx/gl.h"
#include "systems/ffd/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/gaussian/gaussian_math.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/gaussian/gpu_deform.h"
#include "systems/gaussian/gpu_store.h"
#include "systems/residency/residency_system.h"
#include "tests/test_util/headless_gl.h"
#include "tests/systems/gaussian/test_math.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;

// Bernstein lattices use two shapes only (4x3x5 and 3x3x3): each shape and kernel is a specialised program
// whose first compile on llvmpipe takes tens of seconds on a loaded machine (Mesa caches it on disk).
class GaussianGpuDeform : public sffd::test::HeadlessGlTest {
protected:
    void SetUp() override {
        HeadlessGlTest::SetUp();
        if (IsSkipped() || HasFatalFailure()) return;
        sffd::test::emplace_made(deformer, GpuGaussianDeformer::create());
        errors_at_start = gfx::debug_error_count();
    }
    void TearDown() override {
        deformer.reset();
        if (ctx) {
            EXPECT_EQ(gfx::debug_error_count(), errors_at_start)
                << "GL errors reported by the debug callback";
        }
    }
    std::uint64_t errors_at_start = 0;
    std::optional<GpuGaussianDeformer> deformer;
};

GaussianCloud random_cloud(std::size_t n, int degree, float extent, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1, 1);
    std::normal_distribution<float> nd;
    GaussianCloud g;
    g.origin = glm::dvec3(0.25, -0.5, 0.125);  // positions relative to a non-zero origin
    g.sh_degree = degree;
    for (std::size_t i = 0; i < n; ++i) {
        g.positions.emplace_back(extent * u(rng) - 0.25f, extent * u(rng) + 0.5f, extent * u(rng) - 0.125f);
        // Thin and round ones: anisotropy up to 1:100, some with two equal scales.
        const float s = 0.02f * (1.2f + u(rng));
        if (i % 7 == 0) g.scales.emplace_back(s, s, 0.1f * s);
        else g.scales.emplace_back(s, 0.03f * (1.2f + u(rng)), 0.01f * s * (1.5f + u(rng)));
        g.rotations.push_back(glm::normalize(glm::quat(nd(rng), nd(rng), nd(rng), nd(rng))));
        g.opacities.push_back(0.5f + 0.4f * u(rng));
        for (int k = 0; k < sh_coeffs(degree) * 3; ++k) g.sh.push_back(0.5f * u(rng));
    }
    return g;
}

Lattice box_lattice(LatticeBasis basis, glm::ivec3 div) {
    return ffd::make_lattice({-1, -1, -1}, {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)},
                             div, basis);
}
Lattice twisted(LatticeBasis basis, glm::ivec3 div) {
    Lattice l = box_lattice(basis, div);
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.7, glm::dvec3(0.0));
    for (glm::dvec3& p : l.current) p.x += 0.15 * p.y * p.y;
    return l;
}
Lattice stretched(LatticeBasis basis, glm::ivec3 div) {
    Lattice l = box_lattice(basis, div);
    for (std::size_t c = 0; c < l.size(); ++c) {
        glm::dvec3& p = l.current[c];
        p = glm::dvec3(1.8 * p.x, 0.7 * p.y + 0.2 * p.x * p.z, p.z + 0.1 * p.x);
    }
    return l;
}

using sffd::test::max_abs;

glm::dmat3 sigma(const GaussianCloud& g, std::size_t i) {
    return covariance(glm::dvec3(g.scales[i]), glm::dquat(g.rotations[i]));
}

bool all_finite(const GaussianCloud& g) {
    auto fin = [](float v) {
        std::uint32_t b;
        std::memcpy(&b, &v, 4);
        return (b & 0x7f800000u) != 0x7f800000u;
    };
    for (std::size_t i = 0; i < g.size(); ++i) {
        for (int a = 0; a < 3; ++a)
            if (!fin(g.positions[i][a]) || !fin(g.scales[i][a])) return false;
        for (int a = 0; a < 4; ++a)
            if (!fin(g.rotations[i][a])) return false;
        if (!fin(g.opacities[i])) return false;
        if (!g.sh_frames.empty())
            for (int c = 0; c < 3; ++c)
                for (int r = 0; r < 3; ++r)
                    if (!fin(g.sh_frames[i][c][r])) return false;
    }
    return true;
}

// CPU reference: every lattice in order, in place, view-direction mode (frames compose).
GaussianCloud cpu_deform(const std::vector<const Lattice*>& ls, const GaussianCloud& in,
                         ShMode mode = ShMode::rotate_view) {
    GaussianCloud g = in;
    DeformOptions o;
    o.sh = mode;
    for (const Lattice* l : ls) EXPECT_TRUE(deform(*l, g, g, o));
    return g;
}

struct Errors {
    double centre = 0, sigma = 0, frame = 0;
};
Errors compare(const GaussianCloud& gpu, const GaussianCloud& cpu, const char* what) {
    Errors e;
    EXPECT_EQ(gpu.size(), cpu.size());
    if (!cpu.sh_frames.empty()) {
        EXPECT_EQ(gpu.sh, cpu.sh) << what;  // coefficients untouched in view mode
    }
    double esh = 0.0;
    for (std::size_t k = 0; k < gpu.sh.size() && k < cpu.sh.size(); ++k)
        esh = std::max(esh, double(std::abs(gpu.sh[k] - cpu.sh[k])));
    EXPECT_LT(esh, 5e-5)
        << what;  // rotated coefficients (|c| <= 0.5; llvmpipe: 8.5e-6, A_l⁻¹ amplifies rounding)
    EXPECT_EQ(gpu.sh_frames.size(), cpu.sh_frames.size()) << what;
    for (std::size_t i = 0; i < gpu.size(); ++i) {
        EXPECT_EQ(gpu.opacities[i], cpu.opacities[i]) << what << " " << i;
        e.centre = std::max(e.centre, double(glm::length(gpu.positions[i] - cpu.positions[i])));
        const glm::dmat3 expect = sigma(cpu, i);
        e.sigma = std::max(e.sigma, max_abs(sigma(gpu, i) - expect) / max_abs(expect));
        if (i < gpu.sh_frames.size() && i < cpu.sh_frames.size())
            e.frame = std::max(e.frame, max_abs(glm::dmat3(gpu.sh_frames[i]) - glm::dmat3(cpu.sh_frames[i])));
    }
    std::printf(
        "%s: max centre error %.2e, max relative Σ error %.2e, max frame error %.2e, max SH error %.2e\n",
        what, e.centre, e.sigma, e.frame, esh);
    EXPECT_LT(e.centre, 5e-6) << what;
    EXPECT_LT(e.sigma, 3e-5) << what;
    EXPECT_LT(e.frame, 1e-5) << what;
    return e;
}

TEST_F(GaussianGpuDeform, MatchesCpuOnBernsteinAndBsplineLatticesWithSeveralDeformers) {
    const GaussianCloud cloud = random_cloud(4000, 2, 1.15f, 3);  // some Gaussians outside the box
    for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline}) {
        const Lattice tw = twisted(basis, {4, 3, 5}), st = stretched(basis, {3, 3, 3});
        const std::vector<std::vector<const Lattice*>> cases = {{&tw}, {&st}, {&tw, &st}, {&st, &tw, &st}};
        for (const auto& ls : cases) {
            GpuDeformStats stats;
            auto gpu = deform_on_gpu(*deformer, ls, cloud, ShMode::rotate_view, &stats);
            ASSERT_TRUE(gpu) << gpu.message();
            const std::string what = std::string(basis == LatticeBasis::bernstein ? "bernstein" : "bspline") +
                                     ", " + std::to_string(ls.size()) + " deformer(s)";
            compare(*gpu, cpu_deform(ls, cloud), what.c_str());
            EXPECT_GT(stats.inside, 0u);
            EXPECT_EQ(stats.not_finite, 0u);
            EXPECT_TRUE(all_finite(*gpu));
        }
    }
}

TEST_F(GaussianGpuDeform, NeedlesWithTwoTinyAxesKeepThemFiniteAndSmall) {
    // Two axes 1e-10 of the third: their columns' dot products are under float's normal range (the pass
    // takes the rotation's angle from them divided by the larger first; a GPU may flush what stays
    // subnormal). Every Gaussian finite, none dropped, the small axes of their size, Σ as on the CPU.
    GaussianCloud cloud = random_cloud(3000, 2, 1.0f, 9);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(1.0f, 1.5f);
    for (glm::vec3& s : cloud.scales) s = glm::vec3(0.05f, 0.05e-10f * u(rng), 0.05e-10f * u(rng));
    const Lattice tw = twisted(LatticeBasis::bernstein, {4, 3, 5});
    GpuDeformStats stats;
    auto gpu = deform_on_gpu(*deformer, {&tw}, cloud, ShMode::rotate_view, &stats);
    ASSERT_TRUE(gpu) << gpu.message();
    EXPECT_EQ(stats.not_finite, 0u);
    EXPECT_GT(stats.inside, 1000u);
    ASSERT_TRUE(all_finite(*gpu));
    compare(*gpu, cpu_deform({&tw}, cloud), "needles");
    for (std::size_t i = 0; i < gpu->size(); ++i) {
        glm::vec3 s = gpu->scales[i];
        std::sort(&s[0], &s[0] + 3);
        EXPECT_GT(s.x, 0.05e-10f * 0.2f) << i;
        EXPECT_LT(s.y, 0.05e-10f * 1.5f * 3.0f) << i;
        EXPECT_GT(s.z, 0.05f * 0.3f) << i;
    }
}

TEST_F(GaussianGpuDeform, EveryControlPointKernelAgreesForBothBases) {
    const GaussianCloud cloud = random_cloud(1500, 1, 0.95f, 5);
    for (LatticeBasis basis : {LatticeBasis::bernstein, LatticeBasis::bspline}) {
        const Lattice l = twisted(basis, {4, 3, 5});
        const GaussianCloud cpu = cpu_deform({&l}, cloud);
        for (ffd::GpuBernsteinKernel k : {ffd::GpuBernsteinKernel::direct, ffd::GpuBernsteinKernel::shared,
                                          ffd::GpuBernsteinKernel::packed}) {
            deformer->set_bernstein_kernel(k);
            auto gpu = deform_on_gpu(*deformer, {&l}, cloud, ShMode::rotate_view);
            ASSERT_TRUE(gpu) << gpu.message();
            // Bernstein has no packed layout: it reads its points directly.
            const bool direct = basis == LatticeBasis::bernstein && k == ffd::GpuBernsteinKernel::packed;
            EXPECT_EQ(deformer->last_bernstein_kernel(), direct ? ffd::GpuBernsteinKernel::direct : k);
            const char* names[] = {"automatic", "direct kernel", "shared-memory kernel", "packed kernel"};
            const std::string what =
                std::string(basis == LatticeBasis::bernstein ? "bernstein " : "bspline ") + names[int(k)];
            compare(*gpu, cpu, what.c_str());
        }
    }
}

TEST_F(GaussianGpuDeform, RotatedCoefficientsMatchCpuRotation) {
    // ShMode::rotate_coefficients on the GPU: each band rotated by the polar rotation, chained deformers
    // rotating the previous output, against the CPU's per-band matrices (sh_rotation), degrees 1..3.
    for (int degree = 1; degree <= 3; ++degree) {
        const GaussianCloud cloud = random_cloud(2500, degree, 1.1f, 23 + unsigned(degree));
        const Lattice tw = twisted(LatticeBasis::bernstein, {4, 3, 5}),
                      st = stretched(LatticeBasis::bspline, {3, 3, 3});
        GpuDeformStats stats;
        auto gpu = deform_on_gpu(*deformer, {&tw, &st}, cloud, ShMode::rotate_coefficients, &stats);
        ASSERT_TRUE(gpu) << gpu.message();
        EXPECT_TRUE(gpu->sh_frames.empty());
        const GaussianCloud cpu = cpu_deform({&tw, &st}, cloud, ShMode::rotate_coefficients);
        EXPECT_NE(gpu->sh, cloud.sh);  // something was rotated
        compare(*gpu, cpu, ("coefficients, degree " + std::to_string(degree)).c_str());
    }
}

TEST_F(GaussianGpuDeform, EachCombinationOfOutputsRunsItsOwnProgram) {
    // One deformer, one lattice shape: the program is specialised by what a dispatch writes (frames; the
    // coefficients of one degree), so a program reused across combinations would leave frames or
    // coefficients unwritten or rotate the wrong number of them. Degree 0 writes neither; it runs first
    // and last, around the others.
    const Lattice tw = twisted(LatticeBasis::bernstein, {4, 3, 5});
    const std::pair<int, ShMode> cases[] = {
        {0, ShMode::rotate_view},         {1, ShMode::rotate_view}, {1, ShMode::rotate_coefficients},
        {3, ShMode::rotate_coefficients}, {2, ShMode::rotate_view}, {0, ShMode::rotate_view}};
    unsigned seed = 41;
    for (const auto& [degree, mode] : cases) {
        const GaussianCloud cloud = random_cloud(1200, degree, 1.1f, seed++);
        auto gpu = deform_on_gpu(*deformer, {&tw}, cloud, mode);
        ASSERT_TRUE(gpu) << gpu.message();
        const bool frames = mode == ShMode::rotate_view && degree > 0;
        const std::string what = "degree " + std::to_string(degree) + (frames ? ", frames" : "") +
                                 (mode == ShMode::rotate_coefficients ? ", coefficients" : "");
        if (frames) {
            EXPECT_EQ(gpu->sh_frames.size(), cloud.size()) << what;
        }
        if (mode == ShMode::rotate_coefficients) {
            EXPECT_NE(gpu->sh, cloud.sh) << what;
        }
        GaussianCloud cpu = cpu_deform({&tw}, cloud, mode);
        if (degree == 0) cpu.sh_frames.clear();  // no view-dependent colour: the GPU keeps no frames
        compare(*gpu, cpu, what.c_str());
    }
}

TEST_F(GaussianGpuDeform, RigidLatticeMotionMovesGaussiansRigidly) {
    // Every control point turned by Q about the origin and moved by t: the Bernstein map is exactly
    // x -> Q x + t, so every Gaussian inside must come out as Q μ + t, Q Σ Qᵀ, frame Q.
    const GaussianCloud cloud = random_cloud(3000, 3, 0.7f, 9);
    Lattice l = box_lattice(LatticeBasis::bernstein, {4, 3, 5});
    const glm::dvec3 axis = glm::normalize(glm::dvec3(0.3, 1.0, -0.4));
    ffd::twist(l, ffd::all_control_points(l), axis, 1.1, glm::dvec3(0.0));
    const glm::dvec3 t(0.4, -0.2, 0.3);
    ffd::stretch(l, ffd::all_control_points(l), t);
    const glm::dmat3 q = glm::mat3_cast(glm::angleAxis(1.1, axis));
    GpuDeformStats stats;
    auto gpu = deform_on_gpu(*deformer, {&l}, cloud, ShMode::rotate_view, &stats);
    ASSERT_TRUE(gpu) << gpu.message();
    EXPECT_EQ(stats.inside, cloud.size());
    EXPECT_EQ(stats.inverted, 0u);
    double ec = 0, es = 0, ef = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const glm::dvec3 p = cloud.origin + glm::dvec3(cloud.positions[i]);
        const glm::dvec3 expect = q * p + t - cloud.origin;
        ec = std::max(ec, glm::length(glm::dvec3(gpu->positions[i]) - expect));
        const glm::dmat3 s = q * sigma(cloud, i) * glm::transpose(q);
        es = std::max(es, max_abs(sigma(*gpu, i) - s) / max_abs(s));
        ef = std::max(ef, max_abs(glm::dmat3(gpu->sh_frames[i]) - q));
        EXPECT_EQ(gpu->opacities[i], cloud.opacities[i]);
    }
    std::printf("rigid: max centre error %.2e, max relative Σ error %.2e, max frame error %.2e\n", ec, es,
                ef);
    EXPECT_LT(ec, 5e-6);
    EXPECT_LT(es, 2e-5);
    EXPECT_LT(ef, 1e-5);
}

TEST_F(GaussianGpuDeform, DegenerateLatticesGiveNoNaN) {
    const GaussianCloud cloud = random_cloud(2000, 1, 0.9f, 11);
    // (1) Every control point flattened onto y = 0: J is singular inside up to float rounding (its y row
    //     is ~1e-7, so the 1e-12 singularity rule may or may not fire: either way the result must be
    //     finite); the Gaussians become flat (smallest scale ~0), their Σ matches the CPU's, the frames
    //     are finite rotations or reflections (the polar factor of a rank-2 map is defined up to the sign
    //     of its third axis).
    Lattice flat = box_lattice(LatticeBasis::bernstein, {3, 3, 3});
    for (glm::dvec3& p : flat.current) p.y = 0.0;
    GpuDeformStats stats;
    auto gpu = deform_on_gpu(*deformer, {&flat}, cloud, ShMode::rotate_view, &stats);
    ASSERT_TRUE(gpu) << gpu.message();
    EXPECT_TRUE(all_finite(*gpu));
    EXPECT_EQ(stats.not_finite, 0u);
    std::printf("flattened lattice: %zu inside, %zu counted singular\n", stats.inside, stats.degenerate);
    const GaussianCloud cpu = cpu_deform({&flat}, cloud);
    std::size_t checked = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const glm::dvec3 p = cloud.origin + glm::dvec3(cloud.positions[i]);
        if (std::abs(p.x) >= 1 || std::abs(p.y) >= 1 || std::abs(p.z) >= 1) continue;
        ++checked;
        EXPECT_NEAR(double(gpu->positions[i].y) + cloud.origin.y, 0.0, 1e-6) << i;
        EXPECT_LT(gpu->scales[i].z, 1e-6f * gpu->scales[i].x) << i;  // the collapsed axis, last (descending)
        const glm::dmat3 f(gpu->sh_frames[i]);
        EXPECT_LT(max_abs(glm::transpose(f) * f - glm::dmat3(1.0)), 1e-3) << i;
        const glm::dmat3 expect = sigma(cpu, i);
        EXPECT_LT(max_abs(sigma(*gpu, i) - expect), 1e-4 * max_abs(expect)) << i;
        EXPECT_EQ(gpu->opacities[i], cloud.opacities[i]);
    }
    EXPECT_GT(checked, cloud.size() / 2);
    // (1b) Degenerate Gaussians through a regular lattice: all scales 0, one scale 0 (and, from
    //      random_cloud, two equal scales): finite, and the same Σ as the CPU.
    GaussianCloud thin = cloud;
    for (std::size_t i = 0; i < thin.size(); ++i) {
        if (i % 5 == 0) thin.scales[i] = glm::vec3(0.0f);
        if (i % 5 == 1) thin.scales[i].y = 0.0f;
    }
    const Lattice tw = twisted(LatticeBasis::bspline, {3, 3, 3});
    auto thin_gpu = deform_on_gpu(*deformer, {&tw}, thin, ShMode::rotate_view, &stats);
    ASSERT_TRUE(thin_gpu) << thin_gpu.message();
    EXPECT_TRUE(all_finite(*thin_gpu));
    EXPECT_EQ(stats.not_finite, 0u);
    const GaussianCloud thin_cpu = cpu_deform({&tw}, thin);
    for (std::size_t i = 0; i < thin.size(); ++i) {
        const glm::dmat3 expect = sigma(thin_cpu, i);
        EXPECT_LE(max_abs(sigma(*thin_gpu, i) - expect), 3e-5 * max_abs(expect)) << i;
        if (i % 5 == 0) {
            EXPECT_EQ(thin_gpu->scales[i], glm::vec3(0.0f)) << i;
        }
    }

    // (2) A control point at 1e39: finite in double (the lattice is valid) but not in float, so the GPU's
    //     results near it overflow. Those Gaussians are written transparent with scale 0 and counted; no
    //     NaN or infinity reaches the buffer.
    Lattice huge = box_lattice(LatticeBasis::bernstein, {3, 3, 3});
    huge.current[21].x =
        1e39;  // control point (1,1,1): Bernstein support is global, every inside Gaussian depends on it
    ASSERT_TRUE(ffd::validate(huge));
    auto bad = deform_on_gpu(*deformer, {&huge}, cloud, ShMode::rotate_view, &stats);
    ASSERT_TRUE(bad) << bad.message();
    EXPECT_TRUE(all_finite(*bad));
    EXPECT_GT(stats.not_finite, 0u);
    std::size_t transparent = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i)
        if (bad->opacities[i] == 0.0f) {
            ++transparent;
            EXPECT_EQ(bad->scales[i], glm::vec3(0.0f));
        }
    EXPECT_EQ(transparent, stats.not_finite);
}

TEST_F(GaussianGpuDeform, TwoDimensionalDispatchGridCoversEveryGaussian) {
    // 3 groups per row instead of 65,535: the 2D grid path of clouds over 4.19M Gaussians, on 2,000.
    const GaussianCloud cloud = random_cloud(2000, 1, 0.9f, 13);
    const Lattice l = twisted(LatticeBasis::bernstein, {4, 3, 5});
    const Lattice b = twisted(LatticeBasis::bspline, {4, 4, 4});
    for (ffd::GpuBernsteinKernel k : {ffd::GpuBernsteinKernel::direct, ffd::GpuBernsteinKernel::shared,
                                      ffd::GpuBernsteinKernel::packed}) {
        deformer->set_bernstein_kernel(k);
        auto full = deform_on_gpu(*deformer, {&l, &b}, cloud, ShMode::rotate_view);
        ASSERT_TRUE(full) << full.message();
        std::optional<Result<GaussianCloud>> grid;
        {
            gfx::ScopedDispatchLimit limit(3);
            grid.emplace(deform_on_gpu(*deformer, {&l, &b}, cloud, ShMode::rotate_view));
        }
        ASSERT_TRUE(*grid) << grid->message();
        const GaussianCloud& g = **grid;
        EXPECT_EQ(g.positions, full->positions);
        EXPECT_EQ(g.scales, full->scales);
        EXPECT_EQ(g.sh_frames, full->sh_frames);
        compare(g, cpu_deform({&l, &b}, cloud), "2D grid");
    }
}

TEST_F(GaussianGpuDeform, SystemGpuPathWritesTheStoreWithoutReadBack) {
    ecs::Registry reg;
    reg.set_resource<FfdSettings>().force_gpu = true;  // llvmpipe would choose the CPU path
    auto& settings = reg.set_resource<GaussianDeformSettings>();
    const ecs::Entity e = reg.create(), a = reg.create(), b = reg.create();
    const GaussianCloud cloud = random_cloud(1500, 2, 0.9f, 17);
    reg.emplace<GaussianCloud>(e, cloud);
    reg.emplace<Lattice>(a, twisted(LatticeBasis::bernstein, {3, 3, 3}));
    reg.emplace<Lattice>(b, stretched(LatticeBasis::bspline, {3, 3, 3}));
    reg.emplace<Deformers>(e, Deformers{{a, b}});
    // One frame's residency and deformation phases (residency_system uploads the rest cloud).
    const auto frame = [&] { residency_system(reg, {}), gaussian_deform_system(reg, {}); };
    frame();
    const DeformedGaussians& d = reg.get<DeformedGaussians>(e);
    EXPECT_TRUE(gaussian::output_on_gpu(reg, e));
    EXPECT_TRUE(d.cloud.positions.empty());  // no CPU copy
    auto& store = reg.resource<GpuGaussianStore>();
    GpuGaussians& g = store.clouds.at(e);
    EXPECT_EQ(g.state, gfx::Residency::deformed_gpu);
    EXPECT_TRUE(g.has_frames());
    EXPECT_EQ(g.sh_source, ShSource::frames);
    EXPECT_EQ(g.count, cloud.size());
    EXPECT_EQ(g.draw_buffer(), g.deformed.id());
    const std::uint64_t v0 = g.deformed_version;
    auto check = [&](const char* what) {
        auto back = read_back(g, cloud.origin);
        ASSERT_TRUE(back) << back.message();
        compare(*back, cpu_deform({&reg.get<Lattice>(a), &reg.get<Lattice>(b)}, cloud), what);
    };
    check("system, first frame");
    // The statistics arrive without a read-back: a later frame polls the fence (glFinish stands in for
    // frames passing) and fills DeformedGaussians; they equal the CPU's counts.
    EXPECT_FALSE(d.stats_arrived);
    glFinish();
    frame();  // nothing moved: only the statistics are collected
    EXPECT_EQ(g.deformed_version, v0);
    EXPECT_TRUE(d.stats_arrived);
    {
        GaussianCloud c = cloud;
        std::size_t inverted = 0, degenerate = 0;
        for (ecs::Entity le : {a, b}) {
            auto st = deform(reg.get<Lattice>(le), c, c,
                             DeformOptions{ffd::Backend::automatic, true, ShMode::rotate_view});
            ASSERT_TRUE(st);
            inverted += st->inverted, degenerate += st->degenerate;
        }
        EXPECT_EQ(d.inverted, inverted);
        EXPECT_EQ(d.degenerate, degenerate);
        EXPECT_EQ(d.not_finite, 0u);
    }
    // Lattice edits: re-deformed on the GPU, no new upload of the cloud, no read-back by the system.
    for (int k = 0; k < 3; ++k) {
        ffd::twist(reg.patch<Lattice>(a), {0, 1, 2, 3}, {0, 0, 1}, 0.1);
        frame();
    }
    EXPECT_EQ(g.deformed_version, v0 + 3);
    EXPECT_EQ(reg.resource<GaussianDeformStats>().gpu_runs, 4u);
    EXPECT_EQ(reg.resource<gfx::ResidencyStats>().rest_uploads, 1u);
    EXPECT_EQ(reg.resource<GaussianDeformStats>().gpu_sync_readbacks, 0u);
    EXPECT_EQ(reg.resource<GaussianDeformStats>().cpu_runs, 0u);
    check("system, after lattice edits");
    frame();  // nothing moved
    EXPECT_EQ(g.deformed_version, v0 + 3);
    // Coefficient mode: re-deformed into deformed_sh, the frames no longer claimed.
    settings.gpu_sh = ShMode::rotate_coefficients;
    frame();
    EXPECT_EQ(g.deformed_version, v0 + 4);
    EXPECT_TRUE(g.sh_source == ShSource::rotated && !g.has_frames());
    EXPECT_EQ(g.sh_buffer(), g.deformed_sh.id());
    {
        auto back = read_back(g, cloud.origin);
        ASSERT_TRUE(back) << back.message();
        compare(*back,
                cpu_deform({&reg.get<Lattice>(a), &reg.get<Lattice>(b)}, cloud, ShMode::rotate_coefficients),
                "system, coefficients");
    }
    EXPECT_EQ(reg.resource<gfx::ResidencyStats>().rest_uploads, 1u);
    EXPECT_EQ(reg.resource<GaussianDeformStats>().gpu_sync_readbacks, 0u);
    // Forced CPU: DeformedGaussians carries the arrays and the store draws their upload, not a GPU result.
    reg.resource<FfdSettings>() = FfdSettings{.force_cpu = true};
    frame();
    EXPECT_FALSE(gaussian::output_on_gpu(reg, e));
    EXPECT_EQ(reg.get<DeformedGaussians>(e).cloud.size(), cloud.size());
    EXPECT_EQ(g.state, gfx::Residency::deformed_cpu);
    EXPECT_EQ(g.deformed_version, v0 + 5);
    EXPECT_EQ(g.sh_source, ShSource::rotated);  // the CPU default: coefficients rotated
    {
        auto back = read_back(g, cloud.origin);
        ASSERT_TRUE(back) << back.message();
        GaussianCloud uploaded = reg.get<DeformedGaussians>(e).cloud;
        uploaded.opacities = cloud.opacities;  // a deformation carries the authored opacities
        compare(*back, uploaded, "system, CPU output uploaded");
    }
    // The cloud loses its deformers: residency draws the authored cloud again.
    reg.remove<Deformers>(e);
    residency_system(reg, {});
    EXPECT_EQ(g.state, gfx::Residency::rest);
    EXPECT_EQ(g.draw_buffer(), g.rest.id());
    EXPECT_EQ(reg.resource<GaussianDeformStats>().cpu_runs, 1u);
    gaussian_release_gpu(reg);
}

TEST_F(GaussianGpuDeform, SystemAutomaticChoiceFollowsFfdSystem) {
    // Automatic: the CPU path on a software rasterizer, the GPU path on a hardware GPU.
    ecs::Registry reg;
    reg.set_resource<GaussianDeformSettings>();
    const ecs::Entity e = reg.create(), a = reg.create();
    reg.emplace<GaussianCloud>(e, random_cloud(300, 1, 0.9f, 19));
    reg.emplace<Lattice>(a, twisted(LatticeBasis::bernstein, {3, 3, 3}));
    reg.emplace<Deformers>(e, Deformers{{a}});
    residency_system(reg, {});
    gaussian_deform_system(reg, {});
    if (gfx::software_rasterizer()) {
        EXPECT_EQ(reg.resource<GaussianDeformStats>().cpu_runs, 1u);
        EXPECT_FALSE(gaussian::output_on_gpu(reg, e));
    } else {
        EXPECT_EQ(reg.resource<GaussianDeformStats>().gpu_runs, 1u);
        EXPECT_TRUE(gaussian::output_on_gpu(reg, e));
    }
    gaussian_release_gpu(reg);
}

}  // namespace
