// GL renderer of Gaussians against the CPU reference renderer (headless EGL; llvmpipe here). The two
// share conventions and pixel boxes; they differ by float vs double arithmetic and, on the quad path, the
// reference's early stop at T < 1e-4, which the blending hardware cannot do (the tile path does it).
// Stated bound: PSNR > 40 dB on every scene, for every sort and blend path; the CPU and GPU sorts give
// bit-identical images (same stable order), and the tile path matches the quad path within the same bound.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include <glm/gtc/quaternion.hpp>

#include "runtime/assets/builtin_scenes.h"
#include "runtime/gfx/context.h"
#include "runtime/gfx/gl.h"
#include "runtime/gfx/shader.h"
#include "runtime/gfx/gl_object.h"
#include "runtime/gfx/limits.h"
#include "systems/ffd/lattice.h"
#include "systems/ffd/operations.h"
#include "systems/gaussian/from_splats.h"
#include "systems/gaussian/gaussian_deform.h"
#include "systems/splat_render/gaussian_draw.h"
#include "tests/systems/gaussian/random_cloud.h"
#include "tests/systems/gaussian/gl_renderer_fixture.h"
#include "systems/gaussian/reference_render.h"
#include "systems/gaussian/sh.h"
#include "shaders/gaussian/gaussian_layout.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;
using render::BlendPath;
using render::gpu_sort_preferred;
using render::quad_coverage_budget;
using render::read_covered_pixels;
using render::SortPath;
using test::GaussianHarness;
using test::render_gl;

class GaussianGl : public sffd::test::GaussianGlRendererTest<sffd::test::HeadlessGlTest> {};

Camera camera_at(glm::dvec3 eye, glm::dvec3 target = glm::dvec3(0.0), float fov = 40.0f) {
    Camera c;
    c.eye = eye, c.target = target, c.up = {0, 1, 0}, c.fov_y_degrees = fov;
    return c;
}

GaussianCloud random_cloud(std::size_t n, int degree) { return test::seeded_random_cloud(17, n, degree); }

void compare(GaussianHarness& r, const GaussianCloud& g, const Camera& cam, ReferenceOptions o,
             const char* what) {
    const ReferenceImage ref = render_reference(g, cam, o);
    std::optional<ReferenceImage> cpu_quads;
    for (BlendPath blend : {BlendPath::quads, BlendPath::tiles})
        for (SortPath sort : {SortPath::cpu, SortPath::gpu}) {
            r.sort_path = sort, r.blend_path = blend;
            auto gl = render_gl(r, g, cam, o);
            ASSERT_TRUE(gl) << gl.message();
            EXPECT_EQ(r.gpu_sort_used, sort == SortPath::gpu);
            const double p = psnr(ref, *gl);
            // Coverage must agree too (a blank GL image of a mostly empty scene would still score well).
            std::size_t covered_ref = 0, covered_gl = 0;
            for (std::size_t k = 0; k < ref.transmittance.size(); ++k) {
                covered_ref += ref.transmittance[k] < 0.5f;
                covered_gl += gl->transmittance[k] < 0.5f;
            }
            const char* path = blend == BlendPath::tiles
                                   ? (sort == SortPath::gpu ? "tiles, GPU sort" : "tiles, CPU sort")
                                   : (sort == SortPath::gpu ? "quads, GPU sort" : "quads, CPU sort");
            std::printf("%s (%s): PSNR %.1f dB, covered pixels %zu (reference %zu), tile entries %llu\n",
                        what, path, p, covered_gl, covered_ref, (unsigned long long)r.tile_entries);
            EXPECT_GT(p, 40.0) << what << ", " << path;
            EXPECT_GT(covered_ref, ref.transmittance.size() / 20) << what;
            EXPECT_NEAR(double(covered_gl), double(covered_ref), 0.01 * double(covered_ref) + 5)
                << what << ", " << path;
            if (!cpu_quads) {
                cpu_quads = std::move(*gl);
            } else if (blend == BlendPath::quads) {
                EXPECT_EQ(gl->color, cpu_quads->color) << what << ": the GPU sort changed the image";
            } else {
                EXPECT_GT(psnr(*cpu_quads, *gl), 40.0) << what << ", " << path << " vs the quad path";
            }
        }
    r.sort_path = SortPath::automatic, r.blend_path = BlendPath::quads;
}

TEST_F(GaussianGl, MatchesCpuReference) {
    ReferenceOptions o;
    o.width = 160, o.height = 120;
    o.background = {0.1f, 0.2f, 0.3f};
    compare(*renderer, random_cloud(3000, 3), camera_at({0.5, 0.7, 3.5}), o, "random degree 3");
    // The converted sphere, stretched and twisted by a lattice (deformed covariances and SH).
    GaussianCloud sphere = gaussians_from_splats(assets::make_sphere_cloud(20000));
    Lattice l = ffd::make_lattice(
        {-1.1, -1.1, -1.1}, {glm::dvec3(2.2, 0, 0), glm::dvec3(0, 2.2, 0), glm::dvec3(0, 0, 2.2)}, {4, 4, 4});
    ffd::twist_graded(l, ffd::all_control_points(l), {0, 1, 0}, 0.8, glm::dvec3(0.0));
    for (glm::dvec3& p : l.current) p.x *= 1.6;
    GaussianCloud deformed;
    ASSERT_TRUE(deform(l, sphere, deformed));
    o.width = 200, o.height = 150;
    compare(*renderer, deformed, camera_at({0.0, 1.0, 5.0}), o, "deformed sphere");
    // View-direction mode: SH evaluated at frameᵀ d on the GPU as in the reference.
    GaussianCloud view;
    DeformOptions vo;
    vo.sh = ShMode::rotate_view;
    GaussianCloud colourful = random_cloud(2000, 2);
    ASSERT_TRUE(deform(l, colourful, view, vo));
    ASSERT_FALSE(view.sh_frames.empty());
    compare(*renderer, view, camera_at({0.0, 1.0, 4.0}), o, "view-direction SH frames");
    // Far from the origin (the view matrix carries the cloud origin in double).
    GaussianCloud far = random_cloud(500, 1);
    far.origin = glm::dvec3(1e5, -2e4, 3e4);
    compare(*renderer, far, camera_at(far.origin + glm::dvec3(0, 0, 3.0), far.origin), o,
            "far from the origin");
}

TEST_F(GaussianGl, LargeCloudsAreDispatchedAsAGrid) {
    // Clouds beyond 64 x 65,535 Gaussians need a 2D dispatch; with 3 groups per row, 3,000 Gaussians
    // take a 3 x 16 grid (the last row partly empty) and must render exactly as in one row, on every
    // path (the GPU sort's blocks and the tile passes go through the same grid).
    ReferenceOptions o;
    o.width = 96, o.height = 72;
    const GaussianCloud g = random_cloud(3000, 1);
    const Camera cam = camera_at({0.2, 0.3, 3.5});
    for (BlendPath blend : {BlendPath::quads, BlendPath::tiles})
        for (SortPath sort : {SortPath::cpu, SortPath::gpu}) {
            renderer->sort_path = sort, renderer->blend_path = blend;
            renderer->max_groups_x = 65535;
            auto one_row = render_gl(*renderer, g, cam, o);
            ASSERT_TRUE(one_row) << one_row.message();
            renderer->max_groups_x = 3;
            auto grid = render_gl(*renderer, g, cam, o);
            ASSERT_TRUE(grid) << grid.message();
            EXPECT_EQ(grid->color, one_row->color);
            EXPECT_GT(psnr(*grid, render_reference(g, cam, o)), 40.0);
        }
}

TEST_F(GaussianGl, ProjectionOverTheBlockSizeRunsInRanges) {
    // Degree 3: 192 bytes of SH a Gaussian. Under a 200,000-byte GL_MAX_SHADER_STORAGE_BLOCK_SIZE the
    // projection binds its per-Gaussian buffers range by range (the sort payload offset by the range's
    // first Gaussian); the projections, sort and tiles still fit whole. Each Gaussian is projected by the
    // same program from the same inputs, so the image is exactly the unlimited one, on every path.
    ReferenceOptions o;
    o.width = 96, o.height = 72;
    const GaussianCloud g = random_cloud(3000, 3);
    const Camera cam = camera_at({0.2, 0.3, 3.5});
    gfx::GlLimits small = gfx::limits();
    small.max_ssbo_block_size = 200'000;
    for (BlendPath blend : {BlendPath::quads, BlendPath::tiles})
        for (SortPath sort : {SortPath::cpu, SortPath::gpu}) {
            renderer->sort_path = sort, renderer->blend_path = blend;
            auto whole = render_gl(*renderer, g, cam, o);
            ASSERT_TRUE(whole) << whole.message();
            auto ranged = [&] {
                gfx::ScopedLimits scope(small);
                return render_gl(*renderer, g, cam, o);
            }();
            ASSERT_TRUE(ranged) << ranged.message();
            EXPECT_EQ(ranged->color, whole->color);
            EXPECT_GT(psnr(*ranged, render_reference(g, cam, o)), 40.0);
        }
    small.max_ssbo_block_size = 100;  // not one Gaussian's SH: refused, naming the limit
    gfx::ScopedLimits scope(small);
    auto refused = render_gl(*renderer, g, cam, o);
    ASSERT_FALSE(refused);
    EXPECT_NE(refused.message().find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE (100)"), std::string::npos)
        << refused.message();
}

TEST_F(GaussianGl, OffscreenGaussiansAreCulledBeforeTheSort) {
    // A camera looking at one corner of the cloud: Gaussians whose pixel box misses the image get the
    // not-drawn key and are not counted in the indirect draw; the image still matches the reference.
    ReferenceOptions o;
    o.width = 80, o.height = 60;
    const GaussianCloud g = random_cloud(4000, 0);
    const Camera cam = camera_at({0.6, 0.6, 1.8}, {0.6, 0.6, 0.0}, 30.0f);
    auto img = render_gl(*renderer, g, cam, o);
    ASSERT_TRUE(img) << img.message();
    GLuint command[4] = {};
    glGetNamedBufferSubData(renderer->draw.id(), 0, sizeof(command), command);
    // Expected drawn count, from the reference's own rule (in front of the near plane, box on the image):
    // counted here in double, so allow a few boundary cases either way.
    std::size_t expected = 0;
    const glm::dmat4 view = glm::lookAt(cam.eye, cam.target, cam.up);
    const double f = o.height / (2.0 * std::tan(glm::radians(double(cam.fov_y_degrees)) * 0.5));
    for (std::size_t i = 0; i < g.size(); ++i) {
        const glm::dvec3 t(view * glm::dvec4(glm::dvec3(g.positions[i]), 1.0));
        if (-t.z < o.near_plane) continue;
        const double px = o.width * 0.5 + f * t.x / -t.z, py = o.height * 0.5 - f * t.y / -t.z;
        const double margin = 3.0 * f * 0.14 / -t.z + 2.0;  // 3 sigma of the largest scale, plus rounding
        expected +=
            px + margin >= 0.0 && px - margin <= o.width && py + margin >= 0.0 && py - margin <= o.height;
    }
    EXPECT_EQ(command[0], 4u);
    EXPECT_LE(command[1], expected) << "Gaussians off the image were drawn";
    EXPECT_LT(command[1], g.size() / 2);
    EXPECT_GT(command[1], 0u);
    EXPECT_GT(psnr(*img, render_reference(g, cam, o)), 40.0);
}

TEST_F(GaussianGl, PreviewFootprintDropsOnlySubPixelGaussians) {
    // Half the cloud far under a pixel: with min_footprint_px = 1 (the moving preview) they are not drawn
    // and the image is the one of the large half alone; with 0 (the still frame) every Gaussian is drawn.
    ReferenceOptions o;
    o.width = 96, o.height = 72;
    GaussianCloud g = random_cloud(2000, 1), big = g;
    const GaussianCloud small_half = random_cloud(2000, 1);
    for (std::size_t i = 0; i < small_half.size(); ++i) {
        g.positions.push_back(small_half.positions[i] * 0.5f);
        g.scales.push_back(glm::vec3(2e-4f));
        g.rotations.push_back(small_half.rotations[i]);
        g.opacities.push_back(0.9f);
        for (int k = 0; k < 4 * 3; ++k) g.sh.push_back(small_half.sh[i * 12 + std::size_t(k)] + 0.4f);
    }
    const Camera cam = camera_at({0.3, 0.4, 3.0});
    auto drawn = [&] {
        GLuint command[4] = {};
        glGetNamedBufferSubData(renderer->draw.id(), 0, sizeof(command), command);
        return command[1];
    };
    renderer->min_footprint_px = 0.0f;
    auto all = render_gl(*renderer, g, cam, o);
    ASSERT_TRUE(all) << all.message();
    const GLuint drawn_all = drawn();
    auto big_only = render_gl(*renderer, big, cam, o);
    ASSERT_TRUE(big_only) << big_only.message();
    const GLuint drawn_big = drawn();
    renderer->min_footprint_px = 1.0f;
    auto preview = render_gl(*renderer, g, cam, o);
    ASSERT_TRUE(preview) << preview.message();
    EXPECT_EQ(drawn(), drawn_big);
    EXPECT_GT(drawn_all, drawn_big + 1500);
    EXPECT_GT(psnr(*preview, *big_only), 60.0);
    EXPECT_LT(psnr(*all, *big_only), 50.0);  // the small ones do show when drawn
    renderer->min_footprint_px = 0.0f;
}

TEST_F(GaussianGl, TransparentGaussiansAreCulled) {
    // Opacity below 1/255 can never pass the 1/255 alpha threshold: not drawn, not sorted. The whole
    // cloud is on the image, so the drawn count is exactly the opaque enough ones.
    ReferenceOptions o;
    o.width = 64, o.height = 48;
    GaussianCloud g = random_cloud(3000, 0);
    std::size_t opaque = 0;
    for (std::size_t i = 0; i < g.size(); ++i) {
        if (i % 3 == 0) g.opacities[i] = i % 2 ? 0.0f : 0.003f;  // 0.003 < 1/255 = 0.00392
        opaque += g.opacities[i] >= 1.0f / 255.0f;
    }
    const Camera cam = camera_at({0.0, 0.0, 7.0});
    for (SortPath sort : {SortPath::cpu, SortPath::gpu}) {
        renderer->sort_path = sort;
        auto img = render_gl(*renderer, g, cam, o);
        ASSERT_TRUE(img) << img.message();
        GLuint command[4] = {};
        glGetNamedBufferSubData(renderer->draw.id(), 0, sizeof(command), command);
        EXPECT_EQ(command[1], opaque);
        EXPECT_GT(psnr(*img, render_reference(g, cam, o)), 40.0);
    }
}

// Non-finite centres, opacities, scales and rotations (a deformation can make them) are culled by their
// bit patterns (project.comp), not by comparisons GLSL leaves undefined for NaN: exactly the finite
// Gaussians are drawn, and the image holds no NaN.
TEST_F(GaussianGl, NonFiniteGaussiansAreCulled) {
    ReferenceOptions o;
    o.width = 64, o.height = 48;
    GaussianCloud g = random_cloud(600, 0);
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    std::size_t finite = 0;
    for (std::size_t i = 0; i < g.size(); ++i) {
        switch (i % 6) {
            case 0: g.opacities[i] = nan; break;
            case 1: g.positions[i].x = nan; break;
            case 2: g.scales[i].y = inf; break;
            case 3: g.rotations[i].w = nan; break;
            default: ++finite;
        }
    }
    const Camera cam = camera_at({0.0, 0.0, 7.0});
    for (SortPath sort : {SortPath::cpu, SortPath::gpu}) {
        renderer->sort_path = sort;
        auto img = render_gl(*renderer, g, cam, o);
        ASSERT_TRUE(img) << img.message();
        GLuint command[4] = {};
        glGetNamedBufferSubData(renderer->draw.id(), 0, sizeof(command), command);
        EXPECT_EQ(command[1], finite);
        for (const glm::vec3& c : img->color) ASSERT_FALSE(glm::any(glm::isnan(c)));
    }
}

TEST_F(GaussianGl, EmptyCloudGivesTheBackground) {
    ReferenceOptions o;
    o.width = o.height = 8;
    o.background = {0.25f, 0.5f, 1.0f};
    GaussianCloud empty;
    for (BlendPath blend : {BlendPath::quads, BlendPath::tiles})
        for (SortPath sort : {SortPath::cpu, SortPath::gpu}) {
            renderer->sort_path = sort, renderer->blend_path = blend;
            auto img = render_gl(*renderer, empty, camera_at({0, 0, 3}), o);
            ASSERT_TRUE(img) << img.message();
            for (const glm::vec3& c : img->color) EXPECT_EQ(c, o.background);
        }
}

// Quads and tiles visit only the bounding box of the part of each Gaussian that can reach α >= 1/255
// (footprint.glsl): thin Gaussians turned every 15 degrees in the image plane, at opacities down to 0.01
// (where that part is far inside the 3σ square), must cover exactly the reference's pixels, tips included,
// on both blend paths.
TEST_F(GaussianGl, QuadsAndTilesCoverEveryPixelOfThinGaussiansAtEveryAngleAndOpacity) {
    GaussianCloud g;
    g.sh_degree = 0;
    const float opacity[4] = {0.01f, 0.05f, 0.3f, 0.99f};
    for (int row = 0; row < 4; ++row)
        for (int col = 0; col < 12; ++col) {
            const float angle = glm::radians(15.0f * float(col));
            g.positions.emplace_back(-1.21f + 0.22f * float(col), -0.36f + 0.24f * float(row), 0.0f);
            g.scales.emplace_back(0.035f, 0.002f + 0.002f * float(row), 0.01f);
            g.rotations.emplace_back(std::cos(0.5f * angle), 0.0f, 0.0f, std::sin(0.5f * angle));
            g.opacities.push_back(opacity[row]);
            for (float c : {0.9f, 0.5f, 0.2f}) g.sh.push_back(c);
        }
    ReferenceOptions o;
    o.width = 720, o.height = 360;  // 3σ along a Gaussian: 17 pixels
    const Camera cam = camera_at({0, 0, 3});
    const ReferenceImage ref = render_reference(g, cam, o);
    for (BlendPath blend : {BlendPath::quads, BlendPath::tiles}) {
        renderer->blend_path = blend;
        auto img = render_gl(*renderer, g, cam, o);
        ASSERT_TRUE(img) << img.message();
        std::size_t covered = 0, missed = 0, extra = 0;
        for (std::size_t k = 0; k < ref.transmittance.size(); ++k) {
            const bool in_ref = ref.transmittance[k] < 1.0f, in_gl = img->transmittance[k] < 1.0f;
            covered += in_ref, missed += in_ref && !in_gl, extra += in_gl && !in_ref;
        }
        const char* path = blend == BlendPath::tiles ? "tiles" : "quads";
        std::printf("thin Gaussians, %s: %zu pixels covered, %zu missed, %zu extra; %llu tile entries\n",
                    path, covered, missed, extra, (unsigned long long)renderer->tile_entries);
        EXPECT_GT(covered, 5000u) << path;
        EXPECT_LE(missed, 2u) << path;  // a pixel on the α = 1/255 edge may fall either way in float
        EXPECT_LE(extra, 2u) << path;
        EXPECT_GT(psnr(ref, *img), 50.0) << path;
    }
    renderer->blend_path = BlendPath::quads;
}

// The coverage that chooses between quads and tiles (gl_render.h: quad_coverage_budget) counts the pixels
// the passes visit, not the 3σ squares: faint axis-aligned Gaussians, whose visible part (α >= 1/255) is
// 1.4σ wide where the square is 3σ of the longer axis, count a small part of their squares but never
// fewer pixels than they are seen in.
TEST_F(GaussianGl, CoverageCountsTheVisitedPixelsNotTheSquares) {
    GaussianCloud g;
    g.sh_degree = 0;
    for (int col = 0; col < 10; ++col) {
        g.positions.emplace_back(-1.0f + 0.22f * float(col), 0.0f, 0.0f);
        g.scales.emplace_back(0.03f, 0.01f, 0.01f);
        g.rotations.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
        g.opacities.push_back(0.01f);
        for (float c : {0.9f, 0.5f, 0.2f}) g.sh.push_back(c);
    }
    ReferenceOptions o;
    o.width = 720, o.height = 360;
    const Camera cam = camera_at({0, 0, 3});
    const ReferenceImage ref = render_reference(g, cam, o);
    std::size_t seen = 0;
    for (float t : ref.transmittance) seen += t < 1.0f;
    // Each square: side 2·ceil(3σ) + 1 at least, σ = 0.03 at distance 3 with the focal length below.
    const double focal = 0.5 * o.height / std::tan(glm::radians(20.0));
    const double side = 2.0 * std::ceil(3.0 * 0.03 * focal / 3.0) + 1.0;
    const double squares = 10.0 * side * side;
    renderer->blend_path = BlendPath::quads;
    auto img = render_gl(*renderer, g, cam, o);
    ASSERT_TRUE(img) << img.message();
    const std::uint64_t counted = read_covered_pixels(*renderer);  // the last projection's count
    std::printf("faint Gaussians: %zu pixels seen, %llu counted, squares %.0f\n", seen,
                (unsigned long long)counted, squares);
    EXPECT_GT(seen, 100u);
    EXPECT_GE(counted, seen);
    EXPECT_LT(double(counted), 0.25 * squares);
    // The tile path sorts and blends one entry per (tile, Gaussian) its box touches: a square 31 pixels
    // wide touches at least 2 x 2 tiles of 16, the visible part of these fewer; the same pixels are drawn.
    ASSERT_GE(side, 2.0 * SFFD_GAUSS_TILE - 1.0);
    renderer->blend_path = BlendPath::tiles;
    auto tiled = render_gl(*renderer, g, cam, o);
    renderer->blend_path = BlendPath::quads;
    ASSERT_TRUE(tiled) << tiled.message();
    std::printf("faint Gaussians: %llu tile entries (squares: at least 40)\n",
                (unsigned long long)renderer->tile_entries);
    EXPECT_LT(renderer->tile_entries, 40u);
    EXPECT_GT(psnr(ref, *tiled), 50.0);
    std::size_t seen_tiled = 0;
    for (float t : tiled->transmittance) seen_tiled += t < 1.0f;
    EXPECT_EQ(seen_tiled, seen);
}

TEST_F(GaussianGl, OneGaussianOnEveryPath) {
    // One element: the sorts' trivial case; the tile path with a Gaussian spanning several tiles.
    ReferenceOptions o;
    o.width = 70, o.height = 50;  // not multiples of the 16-pixel tile
    GaussianCloud g = random_cloud(1, 2);
    g.positions[0] = glm::vec3(0.0f);
    g.scales[0] = glm::vec3(0.3f, 0.2f, 0.1f);
    const Camera cam = camera_at({0, 0, 3});
    const ReferenceImage ref = render_reference(g, cam, o);
    for (BlendPath blend : {BlendPath::quads, BlendPath::tiles})
        for (SortPath sort : {SortPath::cpu, SortPath::gpu}) {
            renderer->sort_path = sort, renderer->blend_path = blend;
            auto img = render_gl(*renderer, g, cam, o);
            ASSERT_TRUE(img) << img.message();
            EXPECT_GT(psnr(ref, *img), 40.0);
            if (blend == BlendPath::tiles) {
                EXPECT_GT(renderer->tile_entries, 4u);
            }
        }
}

TEST_F(GaussianGl, AutomaticSortFollowsTheRasterizer) {
    renderer->sort_path = SortPath::automatic;
    ReferenceOptions o;
    o.width = o.height = 16;
    auto img = render_gl(*renderer, random_cloud(100, 0), camera_at({0, 0, 3}), o);
    ASSERT_TRUE(img) << img.message();
    EXPECT_EQ(renderer->software, gfx::software_rasterizer());
    EXPECT_EQ(renderer->gpu_sort_used, gpu_sort_preferred(*renderer));
    if (!renderer->software) {
        EXPECT_TRUE(renderer->gpu_sort_used) << "hardware GPUs sort on the GPU";
    }
}

// The tile path's emit pass writes exactly the slots the count pass gave each Gaussian, whatever box it
// computes itself: GLSL lets two programs round the same expressions differently, so the two may
// disagree. Here the slots are given directly: Gaussian 0 (box in tile 0) gets three, Gaussian 1 (box
// over tiles 0 and 1) one, Gaussian 2 (tile 6) one. Unfilled slots take tile id 8 (one past the 4x2
// tiles), the one slot of Gaussian 1 its first tile, and nothing is written past a Gaussian's slots or
// the capacity. The ranges pass then gives tile id 8 no range and writes nothing past the 8 tiles.
TEST_F(GaussianGl, TileEmitWritesExactlyItsSlotsAndRangesSkipTheUnfilledOnes) {
    auto emit = gfx::load_compute_program("splat_render/gaussian/tile_emit.comp", "test.tile_emit");
    ASSERT_TRUE(emit) << emit.message();
    auto ranges = gfx::load_compute_program("splat_render/gaussian/tile_ranges.comp", "test.tile_ranges");
    ASSERT_TRUE(ranges) << ranges.message();
    auto buffer = [](const auto& data, const char* label) {
        gfx::Buffer b = gfx::Buffer::create(label);
        glNamedBufferData(b.id(), GLsizeiptr(data.size() * sizeof(data[0])), data.data(), GL_DYNAMIC_COPY);
        return b;
    };
    auto read = [](const gfx::Buffer& b, std::size_t count) {
        std::vector<std::uint32_t> out(count);
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
        glGetNamedBufferSubData(b.id(), 0, GLsizeiptr(count * sizeof(std::uint32_t)), out.data());
        return out;
    };
    // 64x32 pixels: 4x2 tiles. Pixel centres, 3σ radius 3: boxes 5..11, 13..19 and 37..43 x 21..27.
    const std::vector<glm::vec4> centres = {{8, 8, 1, 3}, {16, 8, 1, 3}, {40, 24, 1, 3}};
    const std::vector<glm::vec4> conics(3, glm::vec4(1, 0, 1, 1));  // unit conic, opaque: the box is 3σ
    const std::vector<std::uint32_t> order = {0, 1, 2}, draw = {4, 3, 0, 0}, offsets = {0, 3, 4, 5};
    const std::uint32_t guard = 0xDEADBEEFu;
    const std::vector<std::uint32_t> blank(7, guard);  // 5 slots and 2 past the capacity
    gfx::Buffer c = buffer(centres, "test.centres"), q = buffer(conics, "test.conics"),
                o = buffer(order, "test.order"), d = buffer(draw, "test.draw"),
                t = buffer(offsets, "test.offsets"), keys = buffer(blank, "test.keys"),
                values = buffer(blank, "test.values");
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_PROJ_CENTER, c.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_TILE_CONIC, q.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_ORDER, o.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_DRAW, d.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_TOUCHED, t.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_TILE_KEYS, keys.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_TILE_VALUES, values.id());
    const GLuint e = emit->id();
    glProgramUniform1ui(e, glGetUniformLocation(e, "u_count"), 3);
    glProgramUniform1ui(e, glGetUniformLocation(e, "u_capacity"), 5);
    glProgramUniform2f(e, glGetUniformLocation(e, "u_size"), 64.0f, 32.0f);
    glProgramUniform2ui(e, glGetUniformLocation(e, "u_tiles"), 4, 2);
    glUseProgram(e);
    glDispatchCompute(1, 1, 1);
    EXPECT_EQ(read(keys, 7), (std::vector<std::uint32_t>{0, 8, 8, 0, 6, guard, guard}));
    EXPECT_EQ(read(values, 7), (std::vector<std::uint32_t>{0, 0, 0, 1, 2, guard, guard}));

    // The entries sorted by tile id, as the radix sort leaves them; 8 tiles cleared to empty, 2 guards.
    const std::vector<std::uint32_t> sorted = {0, 0, 6, 8, 8};
    std::vector<std::uint32_t> cleared(2 * 10, 0);
    for (std::size_t k = 16; k < 20; ++k) cleared[k] = guard;
    gfx::Buffer sk = buffer(sorted, "test.sorted"), rb = buffer(cleared, "test.ranges");
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_TILE_KEYS, sk.id());
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, SFFD_GAUSS_SSBO_RANGES, rb.id());
    const GLuint r = ranges->id();
    glProgramUniform1ui(r, glGetUniformLocation(r, "u_entries"), 5);
    glProgramUniform1ui(r, glGetUniformLocation(r, "u_tile_count"), 8);
    glUseProgram(r);
    glDispatchCompute(1, 1, 1);
    std::vector<std::uint32_t> expected(2 * 10, 0);
    expected[1] = 2, expected[12] = 2, expected[13] = 3;  // tile 0: [0, 2), tile 6: [2, 3)
    for (std::size_t k = 16; k < 20; ++k) expected[k] = guard;
    EXPECT_EQ(read(rb, 20), expected);
    glUseProgram(0);
}

}  // namespace
