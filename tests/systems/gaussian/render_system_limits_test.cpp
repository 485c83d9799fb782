// 3D Gaussians through the whole frame (residency, the GPU lattice deformation, the render system's
// Gaussian pass) under a small GL_MAX_SHADER_STORAGE_BLOCK_SIZE (gfx::ScopedLimits): clouds whose every
// per-Gaussian buffer needs 3+ storage blocks (odd counts, so the last range is partial; offsets aligned to
// 256 bytes, no divisor of the 48-byte Gaussians) are deformed and drawn range by range, and the frame is
// bit for bit the frame under the real limit: the same shaders compute every value from the same inputs
// in the same order (the deformation per Gaussian, the blend front to back); only the bindings and the
// number of dispatches and draws change. Headless EGL (llvmpipe here).
#include <gtest/gtest.h>

#include <optional>
#include <random>
#include <string>

#include <glm/gtc/quaternion.hpp>

#include "runtime/core/log.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/limits.h"
#include "runtime/gfx/residency.h"
#include "runtime/scene/components.h"
#include "systems/ffd/ffd_system.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/gaussian/gpu_store.h"
#include "systems/residency/residency_system.h"
#include "systems/splat_render/gaussian_pass.h"
#include "systems/splat_render/image_io.h"
#include "systems/splat_render/splat_render.h"
#include "tests/systems/gaussian/random_cloud.h"
#include "tests/test_util/gl_required.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;

class GaussianFrameLimits : public testing::Test {
protected:
    static void SetUpTestSuite() {
        auto c = gfx::create_context({.headless = true, .width = 16, .height = 16});
        if (c) context().emplace(std::move(*c));
    }
    static void TearDownTestSuite() { context().reset(); }
    static std::optional<gfx::GlContext>& context() {
        static std::optional<gfx::GlContext> c;
        return c;
    }
    void SetUp() override {
        if (!context()) SFFD_GL_UNAVAILABLE("no headless GL 4.5 context");
    }
};

// How a cloud is deformed before it is drawn.
enum class Deform { none, gpu_frames, gpu_coefficients };

const char* name(Deform d) {
    return d == Deform::none         ? "rest"
           : d == Deform::gpu_frames ? "GPU deformed, SH frames"
                                     : "GPU deformed, SH rotated";
}

struct Frame {
    render::FrameImage image;
    std::uint32_t gaussians = 0;
    render::GaussianPassStats pass;
    gfx::Residency state = gfx::Residency::rest;
};

// One frame of a fresh scene (camera, the cloud, with `deform` a twisted lattice deforming it on the GPU):
// residency, deformation and render phases, read back.
Frame one_frame(const GaussianCloud& cloud, Deform deform, int w, int h) {
    ecs::Registry reg;
    Camera cam;
    cam.eye = {0.3, 0.4, 4.0}, cam.target = {0.0, 0.0, 0.0}, cam.up = {0, 1, 0};
    cam.fov_y_degrees = 40.0f, cam.near_plane = 0.1f, cam.far_plane = 20.0f;
    reg.emplace<Camera>(reg.create(), cam);
    const ecs::Entity e = reg.create();
    reg.emplace<GaussianCloud>(e, cloud);
    if (deform != Deform::none) {
        reg.set_resource<FfdSettings>().force_gpu = true;  // llvmpipe would choose the CPU path
        reg.set_resource<GaussianDeformSettings>().gpu_sh =
            deform == Deform::gpu_frames ? ShMode::rotate_view : ShMode::rotate_coefficients;
        Lattice l = ffd::make_lattice({-1.5, -1.5, -1.5},
                                      {glm::dvec3(3, 0, 0), glm::dvec3(0, 3, 0), glm::dvec3(0, 0, 3)},
                                      {3, 3, 3}, LatticeBasis::bspline);
        ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.5, glm::dvec3(0.0));
        const ecs::Entity lattice = reg.create();
        reg.emplace<Lattice>(lattice, std::move(l));
        reg.emplace<Deformers>(e, Deformers{{lattice}});
    }
    render::RenderSettings s;
    s.width = w, s.height = h, s.quality = render::Quality::hq;
    reg.set_resource<render::RenderSettings>(s);
    residency_system(reg, FrameContext{});
    gaussian_deform_system(reg, FrameContext{});
    render::render_system(reg, FrameContext{});
    Frame f;
    auto img = render::capture_frame(reg);
    EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.message());
    if (img.ok()) f.image = std::move(*img);
    f.gaussians = reg.resource<render::RenderStats>().gaussians;
    f.pass = render::gaussian_pass_stats(reg);
    f.state = reg.resource<GpuGaussianStore>().clouds.at(e).state;
    render::release_render_state(reg);
    gaussian_release_gpu(reg);
    return f;
}

// Pixels whose colour, depth or normal differ bitwise.
std::size_t differing(const render::FrameImage& a, const render::FrameImage& b) {
    if (a.color.size() != b.color.size()) return std::max(a.color.size(), b.color.size());
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.color.size(); ++i)
        n += !(a.color[i] == b.color[i]) ||
             (a.depth.size() == b.depth.size() && !a.depth.empty() &&
              !(a.depth[i] == b.depth[i] || (a.depth[i] != a.depth[i] && b.depth[i] != b.depth[i])));
    return n;
}

std::size_t covered(const render::FrameImage& f) {
    std::size_t n = 0;
    for (const glm::vec4& c : f.color) n += c.w > 0.0f;
    return n;
}

// The frame under the real limit and under `small`, compared; the cloud drawn whole both times on the
// same blend, never refused.
void expect_same_frame(const GaussianCloud& g, Deform deform, int w, int h, const gfx::GlLimits& small,
                       bool tiles, const std::string& what) {
    const Frame whole = one_frame(g, deform, w, h);
    log::ScopedLogCapture capture;
    Frame limited;
    {
        gfx::ScopedLimits scope(small);
        limited = one_frame(g, deform, w, h);
    }
    EXPECT_EQ(whole.gaussians, g.size()) << what;
    EXPECT_EQ(limited.gaussians, g.size()) << what;
    EXPECT_FALSE(capture.contains("not drawn")) << what;
    EXPECT_FALSE(capture.contains("GL_MAX_SHADER_STORAGE_BLOCK_SIZE")) << what;  // nothing fell back
    const gfx::Residency state = deform == Deform::none ? gfx::Residency::rest : gfx::Residency::deformed_gpu;
    EXPECT_EQ(whole.state, state) << what;
    EXPECT_EQ(limited.state, state) << what;
    EXPECT_EQ(limited.pass.tile_clouds, tiles ? 1u : 0u) << what;
    EXPECT_EQ(whole.pass.tile_clouds, tiles ? 1u : 0u) << what;
    EXPECT_GT(covered(limited.image), limited.image.color.size() / 4) << what;
    EXPECT_EQ(differing(limited.image, whole.image), 0u) << what;
}

}  // namespace

// The quads' route (a cloud under the coverage budget), SH degree 0 and 3, at rest and deformed on the
// GPU (SH frames, or coefficients rotated into their own buffer): 10001 Gaussians under a 12,288-byte
// block, where even the 4-byte keys and order take 4 blocks (the GPU sort is not used on llvmpipe: the
// CPU sort reads the keys back without binding them).
TEST_F(GaussianFrameLimits, QuadRouteAcrossBlocksDrawsTheUnlimitedFrame) {
    constexpr std::size_t n = 10001;
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 12288;
    small.ssbo_offset_alignment = 256;
    ASSERT_GT(n * sizeof(std::uint32_t), 3 * std::uint64_t(small.max_ssbo_block_size));
    for (int degree : {0, 3}) {
        GaussianCloud g = test::seeded_random_cloud(31, n, degree);
        for (glm::vec3& s : g.scales) s *= 0.3f;  // under the quads' coverage budget
        for (Deform d : {Deform::none, Deform::gpu_frames, Deform::gpu_coefficients}) {
            if (degree == 0 && d == Deform::gpu_coefficients) continue;  // degree 0 has nothing to rotate
            expect_same_frame(g, d, 96, 72, small, false,
                              "degree " + std::to_string(degree) + ", " + name(d));
        }
    }
}

// The tile route (a cloud covering hundreds of images: 400 large overlapping Gaussians in front of the
// camera, 4601 behind it, culled), whose counts and entries fit a 24,000-byte block while the projection
// (and with degree 3 the SH, Gaussians and frames) takes 4+: the tile blend runs once per range of the
// depth order and draws the unlimited frame.
TEST_F(GaussianFrameLimits, TileRouteAcrossBlocksDrawsTheUnlimitedFrame) {
    constexpr std::size_t n = 5001, visible = 400;
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 24000;
    small.ssbo_offset_alignment = 256;
    ASSERT_GT(n * 16, 3 * std::uint64_t(small.max_ssbo_block_size));
    for (int degree : {0, 3}) {
        GaussianCloud g = test::seeded_random_cloud(37, n, degree);
        std::mt19937 rng(41);
        std::uniform_real_distribution<float> u(0, 1);
        for (std::size_t i = 0; i < n; ++i) {
            if (i < visible) g.scales[i] = glm::vec3(0.3f + 0.3f * u(rng), 0.2f + 0.3f * u(rng), 0.3f);
            else g.positions[i].z += 7.0f;  // behind the eye
            g.opacities[i] = 0.1f + 0.3f * u(rng);
        }
        for (Deform d : {Deform::none, Deform::gpu_frames})
            expect_same_frame(g, d, 64, 48, small, true, "degree " + std::to_string(degree) + ", " + name(d));
    }
}
