// Coverage under deformation (elliptical axes from the lattice's Jacobian close the gaps that fixed-radius
// splats open), splats beyond the point-size limit, splats centred just off-screen, texture lookup at uv.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

#include "runtime/gfx/splat_store.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform.h"
#include "systems/splat_render/splat_pack.h"
#include "systems/ffd/lattice.h"
#include "tests/systems/splat_render/gl_fixture.h"
#include "tests/systems/splat_render/test_scenes.h"
#include "systems/residency/residency_system.h"

using namespace sffd;
using namespace sffd::render;
using namespace sffd::render::test;

namespace {

constexpr std::size_t paper_splats = 59650;

// Deforms `cloud` through a 2x2x2-division Bernstein lattice around the unit sphere whose control points
// are scaled `factor` times along x: x' = factor * x inside (Bernstein reproduces linear maps exactly).
SplatCloud stretch_x(const SplatCloud& cloud, double factor) {
    Lattice lattice = ffd::make_lattice(glm::dvec3(-1.2),
                                        {glm::dvec3(2.4, 0, 0), glm::dvec3(0, 2.4, 0), glm::dvec3(0, 0, 2.4)},
                                        glm::ivec3(2, 2, 2));
    for (glm::dvec3& p : lattice.current) p.x *= factor;
    SplatCloud out = cloud;
    ffd::PointsIn in{cloud.positions.data(), cloud.normals.data(), cloud.axis_u.data(),
                     cloud.axis_v.data(),    cloud.size(),         cloud.origin};
    ffd::PointsOut o{out.positions.data(), out.normals.data(), out.axis_u.data(), out.axis_v.data()};
    auto stats = ffd::deform(lattice, in, o);
    EXPECT_TRUE(stats.ok()) << (stats.ok() ? "" : stats.message());
    if (stats.ok()) {
        EXPECT_EQ(stats->inside, cloud.size());
    }
    return out;
}

}  // namespace

class Coverage_ : public GlRenderTest {};

TEST_F(Coverage_, SphereStretchedTwiceByALatticeStaysClosed) {
    const Camera cam = add_camera(6.0);
    add_light({-1.0f, -0.3f, -0.5f});
    const SplatCloud stretched = stretch_x(fibonacci_sphere(paper_splats), 2.0);
    // The lattice stretched the axes along x: tangent axes gained length, normals tilted by J^-T.
    add_cloud(stretched);
    for (Quality q : {Quality::hq, Quality::preview}) {
        const FrameImage img = render(q, 512, 512);
        const Coverage c = ellipsoid_coverage(img, cam, glm::dvec3(2.0, 1.0, 1.0));
        EXPECT_GT(c.inside, 40000);
        EXPECT_EQ(c.holes, 0) << (q == Quality::hq ? "hq" : "preview");
        EXPECT_EQ(c.far_side, 0) << (q == Quality::hq ? "hq" : "preview");
    }
}

// A half-resolution preview (RenderSettings::preview_divider 2) renders a quarter of the pixels and is read
// back at full size, each frame pixel as a 2x2 block: the same closed sphere in the same place, depth and
// normals scaled up with the colour, and HQ frames unaffected by the setting.
TEST_F(Coverage_, HalfResolutionPreviewShowsTheSameSphereAtFullSize) {
    const Camera cam = add_camera(6.0);
    add_light({-1.0f, -0.3f, -0.5f});
    add_cloud(fibonacci_sphere(paper_splats));
    const FrameImage full = render(Quality::preview, 512, 384);
    const FrameImage hq = render(Quality::hq, 512, 384);
    preview_divider = 2;
    const FrameImage half = render(Quality::preview, 512, 384);
    ASSERT_EQ(half.width, 512);
    ASSERT_EQ(half.height, 384);
    const Coverage c = ellipsoid_coverage(half, cam, glm::dvec3(1.0));
    const Coverage full_c = ellipsoid_coverage(full, cam, glm::dvec3(1.0));
    EXPECT_GT(c.inside, 15000);
    EXPECT_NEAR(c.inside, full_c.inside, 0.01 * full_c.inside) << "the sphere's pixels, at full size";
    EXPECT_EQ(c.holes, 0);
    EXPECT_EQ(c.far_side, 0);
    int blocks = 0, uniform = 0, covered_both = 0, covered_either = 0;
    for (int y = 0; y + 1 < half.height; y += 2)
        for (int x = 0; x + 1 < half.width; x += 2) {
            const std::size_t i = half.index(x, y);
            bool same = true;
            for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{0, 1}, std::pair{1, 1}}) {
                const std::size_t j = half.index(x + dx, y + dy);
                same &= half.color[j] == half.color[i] && half.normal[j] == half.normal[i] &&
                        (half.depth[j] == half.depth[i]);
            }
            ++blocks, uniform += same ? 1 : 0;
        }
    EXPECT_EQ(uniform, blocks) << "every frame pixel is a 2x2 block";
    for (std::size_t i = 0; i < half.color.size(); ++i) {
        const bool a = full.color[i].w > 0.0f, b = half.color[i].w > 0.0f;
        covered_both += a && b ? 1 : 0, covered_either += a || b ? 1 : 0;
    }
    EXPECT_GT(double(covered_both) / covered_either, 0.99) << "the same silhouette, to its edge pixels";
    const FrameImage hq_divided = render(Quality::hq, 512, 384);
    EXPECT_EQ(hq_divided.color, hq.color) << "HQ frames always render at full size";
}

// A reduced preview of a textured sphere colours each splat once (RenderSettings::
// reduced_preview_flat_texture): the same pixels covered as with per-pixel lookups, no holes, and
// colours within a small mean of them (a splat spans about two of the frame's pixels and as many texels
// of its level); the per-pixel frame differs from it, so the setting took effect.
TEST_F(Coverage_, ReducedPreviewColoursTexturedSplatsOnceWithoutChangingCoverage) {
    const Camera cam = add_camera(6.0);
    add_light({-1.0f, -0.3f, -0.5f});
    SplatCloud sphere = fibonacci_sphere(paper_splats);
    add_checker(sphere);
    add_cloud(std::move(sphere));
    preview_divider = 2;
    const FrameImage flat = render(Quality::preview, 512, 384);
    reduced_preview_flat_texture = false;
    const FrameImage per_pixel = render(Quality::preview, 512, 384);
    const Coverage c = ellipsoid_coverage(flat, cam, glm::dvec3(1.0));
    EXPECT_GT(c.inside, 15000);
    EXPECT_EQ(c.holes, 0);
    EXPECT_EQ(c.far_side, 0);
    const ImageDiff d = image_diff(flat, per_pixel);
    EXPECT_EQ(d.coverage_mismatch, 0);
    EXPECT_GT(d.mean_color, 1e-4) << "the per-pixel frame is the same: the setting did nothing";
    EXPECT_LT(d.mean_color, 0.03);
}

TEST_F(Coverage_, FixedRadiusSplatsWouldOpenHolesUnderTheSameStretch) {
    const Camera cam = add_camera(6.0);
    add_light({-1.0f, -0.3f, -0.5f});
    const SplatCloud rest = fibonacci_sphere(paper_splats);
    SplatCloud fixed = stretch_x(rest, 2.0);
    // Same deformed centres and normals, but discs of the rest radius (axes not deformed).
    for (std::size_t i = 0; i < fixed.size(); ++i) {
        const float r = glm::length(rest.axis_u[i]);
        const glm::vec3 n = glm::normalize(fixed.normals[i]);
        const glm::vec3 a = std::abs(n.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0);
        const glm::vec3 t = glm::normalize(glm::cross(a, n));
        fixed.axis_u[i] = t * r;
        fixed.axis_v[i] = glm::cross(n, t) * r;
    }
    add_cloud(fixed);
    const FrameImage img = render(Quality::hq, 512, 512);
    const Coverage c = ellipsoid_coverage(img, cam, glm::dvec3(2.0, 1.0, 1.0));
    // Thousands of uncovered pixels or far-side pixels showing through.
    EXPECT_GT(c.holes + c.far_side, c.inside / 50) << "holes " << c.holes << " far side " << c.far_side;
}

// A disc of radius 0.5 two units from the camera spans about 0.6 of the frame's height (309 px at 512): the
// frame is sized from this implementation's GL_POINT_SIZE_RANGE so the disc is at least 1.2x the largest
// sprite (llvmpipe: 255 px, frame 512; GPUs allow larger sprites, so the frame grows with them).
TEST_F(Coverage_, SplatLargerThanThePointSizeLimitIsDrawnWhole) {
    GLfloat range[2] = {1.0f, 1.0f};
    glGetFloatv(GL_POINT_SIZE_RANGE, range);
    GLint max_viewport[2] = {0, 0}, max_texture = 0;
    glGetIntegerv(GL_MAX_VIEWPORT_DIMS, max_viewport);
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_texture);
    const double disc_fraction = 309.0 / 512.0;
    const int size = std::max(512, int(std::ceil(1.2 * double(range[1]) / disc_fraction)));
    if (size > std::min({max_viewport[0], max_viewport[1], max_texture, 8192}))
        GTEST_SKIP() << "needs a frame 1.2x GL_POINT_SIZE_RANGE's maximum (" << range[1]
                     << " px) / 0.6 = " << size
                     << " px, beyond GL_MAX_VIEWPORT_DIMS / GL_MAX_TEXTURE_SIZE (or 8192)";
    add_camera(2.0);
    add_light({0.0f, 0.0f, -1.0f});
    SplatCloud one;
    one.positions = {glm::vec3(0.0f)};
    one.normals = {glm::vec3(0, 0, 1)};
    one.axis_u = {glm::vec3(0.5f, 0, 0)};
    one.axis_v = {glm::vec3(0, 0.5f, 0)};
    add_cloud(one);
    const Camera cam = reg.get<Camera>(*[&] {
        std::optional<ecs::Entity> e;
        reg.view<const Camera>().each([&](ecs::Entity id, const Camera&) { e = id; });
        return e;
    }());
    const double radius_px = 0.5 * disc_fraction * size;
    ASSERT_GT(2.0 * radius_px, 1.19 * double(range[1]));
    for (Quality q : {Quality::hq, Quality::preview}) {
        const FrameImage img = render(q, size, size);
        const RenderStats stats = reg.resource<RenderStats>();
        EXPECT_EQ(stats.visible_quads, 1u);  // wider than the largest point sprite: drawn as a quad
        EXPECT_EQ(stats.visible_points, 0u);
        // pixel_ray() of gl_fixture.h with its matrices built once (a GPU's frame may hold 17M pixels).
        const glm::dmat4 proj = projection_matrix(cam, 1.0);
        const glm::dmat3 to_world = glm::dmat3(glm::inverse(view_matrix(cam)));
        int expected = 0, got = 0, mismatched = 0;
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                const double nx = (x + 0.5) / size * 2.0 - 1.0, ny = 1.0 - (y + 0.5) / size * 2.0;
                const glm::dvec3 d = to_world * glm::dvec3(nx / proj[0][0], ny / proj[1][1], -1.0);
                const glm::dvec3 p = cam.eye + d * (cam.eye.z / -d.z);
                const bool in = glm::length(glm::dvec2(p)) <= 0.5;
                expected += in;
                got += img.covered(x, y);
                mismatched += in != img.covered(x, y);
            }
        EXPECT_GT(expected, int(0.95 * std::numbers::pi * radius_px * radius_px));
        EXPECT_LE(mismatched, 2 * int(2 * std::numbers::pi * radius_px * 0.02) + 8)
            << "expected " << expected << " got " << got;
    }
}

TEST_F(Coverage_, SplatsCentredJustOffScreenCoverTheBorder) {
    const Camera& cam_ref = add_camera(2.0);
    const Camera cam = cam_ref;
    add_light({0.0f, 0.0f, -1.0f});
    // The frame sees |x|, |y| <= tan(22.5 deg) * 2 on the z = 0 plane. A ring of splats centred 0.03 outside
    // that square, radius 0.06: only they can cover the outermost pixels.
    const double edge = std::tan(std::numbers::pi / 8.0) * 2.0;
    SplatCloud ring;
    auto add = [&](double x, double y) {
        ring.positions.emplace_back(float(x), float(y), 0.0f);
        ring.normals.emplace_back(0, 0, 1);
        ring.axis_u.emplace_back(0.06f, 0, 0);
        ring.axis_v.emplace_back(0, 0.06f, 0);
    };
    for (double s = -0.95; s <= 0.95; s += 0.04) {
        add(edge + 0.03, s), add(-edge - 0.03, s), add(s, edge + 0.03), add(s, -edge - 0.03);
    }
    add_cloud(ring);
    for (Quality q : {Quality::hq, Quality::preview}) {
        const int n = 256;
        const FrameImage img = render(q, n, n);
        int uncovered = 0;
        for (int i = 0; i < n; ++i)
            for (int k : {0, 1, n - 2, n - 1}) {
                uncovered += !img.covered(i, k);
                uncovered += !img.covered(k, i);
            }
        EXPECT_EQ(uncovered, 0) << (q == Quality::hq ? "hq" : "preview");
        EXPECT_FALSE(img.covered(n / 2, n / 2));
        EXPECT_GT(reg.resource<RenderStats>().visible_quads, 0u);
        (void)cam;
    }
}

TEST_F(Coverage_, TextureColoursLandWhereTheUvSays) {
    // Quadrants: u < 0.5 / >= 0.5 and v < 0.5 / >= 0.5 in four colours; lit by ambient only (albedo shows).
    const ecs::Entity ce = reg.create();
    Camera cam;
    cam.eye = glm::dvec3(-2.9, 0.7, 0.2);
    cam.near_plane = 0.05f;
    reg.emplace<Camera>(ce, cam);
    reg.emplace<AmbientLight>(reg.create(), AmbientLight{glm::vec3(1.0f), 1.0f});
    SplatCloud sphere = fibonacci_sphere(paper_splats);
    const int tw = 64, th = 32;
    const std::uint8_t quad_colors[4][3] = {{230, 20, 20}, {20, 200, 20}, {20, 20, 230}, {230, 230, 20}};
    sphere.texture.width = tw, sphere.texture.height = th;
    for (int y = 0; y < th; ++y)
        for (int x = 0; x < tw; ++x) {
            const int q = (x >= tw / 2 ? 1 : 0) + (y >= th / 2 ? 2 : 0);
            for (int c = 0; c < 3; ++c) sphere.texture.rgba8.push_back(quad_colors[q][c]);
            sphere.texture.rgba8.push_back(255);
        }
    add_cloud(std::move(sphere), SplatMaterial{.specular = 0.0f});
    for (Quality q : {Quality::hq, Quality::preview}) {
        const FrameImage img = render(q, 384, 384);
        int checked = 0, wrong = 0;
        int seen[4] = {0, 0, 0, 0};
        for (int y = 0; y < img.height; ++y)
            for (int x = 0; x < img.width; ++x) {
                const glm::dvec3 d = pixel_ray(cam, x, y, img.width, img.height);
                if (!hit_ellipsoid(cam.eye, d, glm::dvec3(0.97))) continue;
                const glm::dvec3 p = cam.eye + d * *hit_ellipsoid(cam.eye, d, glm::dvec3(1.0));
                double u = std::atan2(p.z, p.x) / (2.0 * std::numbers::pi);
                if (u < 0) u += 1.0;
                const double v = std::asin(std::clamp(p.y, -1.0, 1.0)) / std::numbers::pi + 0.5;
                const auto near = [](double a, double b) { return std::abs(a - b) < 0.03; };
                if (near(u, 0.5) || near(u, 0.0) || near(u, 1.0) || near(v, 0.5)) continue;  // texel borders
                const int quadrant = (u >= 0.5 ? 1 : 0) + (v >= 0.5 ? 2 : 0);
                ++checked;
                ++seen[quadrant];
                const glm::vec4 c = img.color[img.index(x, y)];
                for (int k = 0; k < 3; ++k)
                    if (std::abs(double(encode_srgb8(c[k])) - quad_colors[quadrant][k]) > 12) {
                        ++wrong;
                        break;
                    }
            }
        EXPECT_GT(checked, 30000);
        for (int k = 0; k < 4; ++k) EXPECT_GT(seen[k], 2000) << "quadrant " << k << " not in view";
        EXPECT_LT(wrong, checked / 200) << (q == Quality::hq ? "hq" : "preview");
    }
}

// The renderer draws the deformer's output, not the authored cloud: the FFD system's GPU buffer
// (GpuSplatStore::deformed, state deformed_gpu) and its CPU output (DeformedSplats uploaded, state
// deformed_cpu) both show the stretch.
TEST_F(Coverage_, DrawsTheDeformersOutputInsteadOfTheRestCloud) {
    const Camera cam = add_camera(6.0);
    add_light({-1.0f, -0.3f, -0.5f});
    const SplatCloud rest = fibonacci_sphere(paper_splats);
    const SplatCloud stretched = stretch_x(rest, 2.0);
    const ecs::Entity e = add_cloud(rest);
    reg.emplace<Deformers>(e);  // a deformed cloud (a cloud without deformers is drawn at rest)

    // CPU path: DeformedSplats with cpu_valid, uploaded as ffd_system's CPU path does.
    DeformedSplats& d = reg.emplace<DeformedSplats>(e);
    d.positions = stretched.positions, d.normals = stretched.normals;
    d.axis_u = stretched.axis_u, d.axis_v = stretched.axis_v;
    d.cpu_valid = true, d.version = 1;
    d.bounds_min = glm::dvec3(-2.1, -1.1, -1.1), d.bounds_max = glm::dvec3(2.1, 1.1, 1.1);
    residency_system(reg, FrameContext{});
    {
        auto& store = reg.resource<gfx::GpuSplatStore>();
        gfx::upload_deformed_splats(store.clouds.at(e), rest, {d.positions, d.normals, d.axis_u, d.axis_v},
                                    store.keep_cpu);
    }
    FrameImage img = render(Quality::hq, 256, 256);
    Coverage c = ellipsoid_coverage(img, cam, glm::dvec3(2.0, 1.0, 1.0));
    EXPECT_GT(c.inside, 10000);
    EXPECT_EQ(c.holes, 0);
    EXPECT_EQ(c.far_side, 0);

    // GPU path: the FFD pass wrote `deformed` (here: the unit sphere again) and marked it valid.
    reg.remove<DeformedSplats>(e);
    auto& gpu = reg.resource<gfx::GpuSplatStore>().clouds.at(e);
    const std::vector<gpu::GpuSplat> packed = pack_splats(rest);
    glNamedBufferSubData(gpu.deformed.id(), 0, GLsizeiptr(packed.size() * sizeof(gpu::GpuSplat)),
                         packed.data());
    gfx::set_deformed(gpu, gfx::Residency::deformed_gpu);
    img = render(Quality::hq, 256, 256);
    c = ellipsoid_coverage(img, cam, glm::dvec3(1.0));
    EXPECT_EQ(c.holes, 0);
    EXPECT_EQ(c.far_side, 0);
    int outside_unit_sphere = 0;
    for (int y = 0; y < img.height; ++y)
        for (int x = 0; x < img.width; ++x)
            outside_unit_sphere += img.covered(x, y) &&
                                   !hit_ellipsoid(cam.eye, pixel_ray(cam, x, y, 256, 256), glm::dvec3(1.03));
    EXPECT_EQ(outside_unit_sphere, 0);
}

// A sprite-sized splat covers exactly the pixels whose centres lie in its analytic disc: the sprite's
// size bound (the screen box of the projected ellipse, no margin) leaves nothing out, at several sub-pixel
// positions, facing the camera or tilted 70-75 degrees (thin ellipses, one along a screen diagonal, where
// the box is far smaller than the disc's bounding ball), with the CPU cull and with the compute pass.
TEST_F(Coverage_, SpriteCoversExactlyItsAnalyticDisc) {
    const Camera& cam_ref = add_camera(2.0);
    const Camera cam = cam_ref;
    add_light({0.0f, 0.0f, -1.0f});
    const ecs::Entity e = reg.create();
    // Rodrigues: v rotated by `angle` about the unit axis a.
    auto rotate = [](glm::dvec3 v, glm::dvec3 a, double angle) {
        return v * std::cos(angle) + glm::cross(a, v) * std::sin(angle) +
               a * glm::dot(a, v) * (1.0 - std::cos(angle));
    };
    const double deg = std::numbers::pi / 180.0;
    const glm::vec3 normals[] = {
        glm::normalize(glm::vec3(0.2f, 0.1f, 1.0f)),
        glm::vec3(rotate({0, 0, 1}, {1, 0, 0}, 75.0 * deg)),
        glm::vec3(rotate({0, 0, 1},
                         glm::normalize(glm::dvec3(std::cos(30.0 * deg), std::sin(30.0 * deg), 0.0)),
                         70.0 * deg)),
    };
    for (const glm::vec3 normal : normals)
        for (const glm::vec3 centre :
             {glm::vec3(0.0f), glm::vec3(0.1037f, -0.0711f, 0.0f), glm::vec3(-0.3013f, 0.2559f, 0.05f)}) {
            SplatCloud one;
            one.positions = {centre};
            one.normals = {normal};
            const glm::vec3 t = glm::normalize(glm::cross(glm::vec3(0, 1, 0.3f), one.normals[0]));
            one.axis_u = {t * 0.05f};
            one.axis_v = {glm::cross(one.normals[0], t) * 0.05f};
            if (reg.has<SplatCloud>(e)) reg.remove<SplatCloud>(e);
            reg.emplace<SplatCloud>(e, one);
            for (CullPath path : {CullPath::cpu, CullPath::compute})
                for (Quality q : {Quality::hq, Quality::preview}) {
                    const FrameImage img = render(q, 512, 512, true, path);
                    EXPECT_EQ(reg.resource<RenderStats>().visible_points, 1u);
                    EXPECT_EQ(reg.resource<RenderStats>().cpu_culled_clouds, path == CullPath::cpu ? 1u : 0u);
                    int expected = 0, mismatched = 0;
                    for (int y = 0; y < 512; ++y)
                        for (int x = 0; x < 512; ++x) {
                            const glm::dvec3 d = pixel_ray(cam, x, y, 512, 512);
                            const glm::dvec3 n(one.normals[0]);
                            const double t_hit = glm::dot(glm::dvec3(centre) - cam.eye, n) / glm::dot(d, n);
                            const glm::dvec3 p = cam.eye + d * t_hit - glm::dvec3(centre);
                            const bool in = glm::length(p) <= 0.05;
                            expected += in;
                            mismatched += in != img.covered(x, y);
                        }
                    EXPECT_GT(expected, 150);
                    EXPECT_LE(mismatched, 2)
                        << "normal " << normal.x << "," << normal.y << "," << normal.z << " centre "
                        << centre.x << "," << centre.y << (q == Quality::hq ? " hq" : " preview")
                        << (path == CullPath::cpu ? " cpu" : " compute");
                }
        }
}
