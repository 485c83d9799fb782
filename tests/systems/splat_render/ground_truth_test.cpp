// Ground-truth ray tracer (ground_truth.h) against analytic facts, and the image metrics (image_compare.h)
// against hand-computed values.
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include <gtest/gtest.h>

#include "runtime/assets/builtin_scenes.h"
#include <random>

#include "systems/ffd/deform.h"
#include "systems/splat_render/camera_math.h"
#include "systems/splat_render/cpu_cull.h"
#include "systems/splat_render/splat_pack.h"
#include "systems/splat_render/ground_truth.h"
#include "systems/splat_render/image_compare.h"
#include "systems/splat_render/nearest_point.h"
#include "runtime/scene/point_columns.h"

namespace sffd::render {
namespace {

// Unit sphere at the origin seen from +Z at distance `d`, 45 deg vertical field of view, one light from
// the eye's direction (white, intensity 1) and ambient 0.2.
ReferenceScene axis_scene(int w, int h, double d, const SplatTexture& texture) {
    ReferenceScene s;
    s.width = w, s.height = h;
    Camera cam;
    cam.eye = glm::dvec3(0.0, 0.0, d);
    cam.target = glm::dvec3(0.0);
    cam.fov_y_degrees = 45.0f;
    cam.near_plane = 0.1f;
    cam.far_plane = 100.0f;
    s.view = view_matrix(cam);
    s.projection = projection_matrix(cam, double(w) / double(h));
    s.texture = &texture;  // and SplatMaterial's defaults
    s.lights.ambient = glm::dvec3(0.2);
    s.lights.to_light = {glm::dvec3(0.0, 0.0, 1.0)};
    s.lights.color = {glm::dvec3(1.0)};
    return s;
}

// A 4 x 2 texture of distinct colours (sRGB bytes).
SplatTexture four_by_two() {
    SplatTexture m;
    m.width = 4, m.height = 2;
    for (int i = 0; i < 8; ++i) {
        const auto b = std::uint8_t(20 + 28 * i);
        m.rgba8.insert(m.rgba8.end(), {b, std::uint8_t(255 - b), std::uint8_t(7 * i), 255});
    }
    return m;
}

double decode(std::uint8_t c) {
    const double v = c / 255.0;
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

TEST(GroundTruth, CentrePixelSeesTheExpectedUvNormalDepthAndShade) {
    const SplatTexture m = four_by_two();
    const ReferenceScene s = axis_scene(65, 65, 4.0, m);  // odd size: pixel (32, 32) is on the view axis
    auto img = render_reference(s);
    ASSERT_TRUE(img) << img.message();
    const std::size_t k = img->index(32, 32);
    ASSERT_EQ(img->color[k].w, 1.0f);
    EXPECT_NEAR(img->depth[k], 3.0, 1e-5);  // eye at 4, surface at z = 1
    EXPECT_NEAR(img->normal[k].z, 1.0, 1e-6);
    // Hit (0, 0, 1): longitude atan2(1, 0) = pi/2 -> u = 0.25, colatitude pi/2 -> v = 0.5. In the 4 x 2
    // texture that is the corner of texels (0..1, 0..1): bilinear weights 1/4 each (magnified: level 0).
    EXPECT_NEAR(sphere_uv(glm::dvec3(0, 0, 1)).x, 0.25, 1e-12);
    EXPECT_NEAR(sphere_uv(glm::dvec3(0, 0, 1)).y, 0.5, 1e-12);
    for (int c = 0; c < 3; ++c) {
        double albedo = 0.0;
        for (int t : {0, 1, 4, 5}) albedo += 0.25 * decode(m.rgba8[std::size_t(4 * t + c)]);
        // n = l = to_eye: ndl = 1, n.h = 1 -> spec = specular. colour = albedo (ambient + 1) + specular.
        EXPECT_NEAR(img->color[k][c], albedo * 1.2 + double(SplatMaterial{}.specular), 2e-5)
            << "channel " << c;
    }
}

// A mesh (ExactMesh): the square |x|, |y| <= 1 at z = 1 as two triangles, uv = (0.25 + x / 8, 0.5 + y / 4),
// seen like the sphere above. Its centre pixel hits (0, 0, 1) with the sphere's uv, normal and depth there,
// so it must get the same colour; its coverage is the square's image exactly; its far corners' uvs follow
// the affine map.
TEST(GroundTruth, MeshPathMatchesTheAnalyticSquare) {
    const SplatTexture m = four_by_two();
    ReferenceScene s = axis_scene(65, 65, 4.0, m);
    ExactMesh mesh;
    mesh.positions = {{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};
    for (const glm::dvec3& p : mesh.positions) mesh.uvs.emplace_back(0.25 + p.x / 8.0, 0.5 + p.y / 4.0);
    mesh.triangles = {0, 1, 2, 0, 2, 3};
    s.mesh = &mesh;
    auto img = render_reference(s);
    ASSERT_TRUE(img) << img.message();
    auto sphere = render_reference(axis_scene(65, 65, 4.0, m));
    ASSERT_TRUE(sphere) << sphere.message();
    const std::size_t k = img->index(32, 32);
    ASSERT_EQ(img->color[k].w, 1.0f);
    EXPECT_NEAR(img->depth[k], 3.0, 1e-5);
    EXPECT_NEAR(img->normal[k].z, 1.0, 1e-6);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(img->color[k][c], sphere->color[k][c], 1e-5) << "channel " << c;
    // Coverage: the pixel centre's ray hits the square (pixels within 1e-3 of its edge skipped).
    const glm::dmat4 inv_view = glm::inverse(s.view);
    int covered = 0, wrong = 0;
    for (int y = 0; y < 65; ++y)
        for (int x = 0; x < 65; ++x) {
            const double nx = 2.0 * (x + 0.5) / 65 - 1.0, ny = 2.0 * (64 - y + 0.5) / 65 - 1.0;
            const glm::dvec3 d =
                glm::dmat3(inv_view) * glm::dvec3(nx / s.projection[0][0], ny / s.projection[1][1], -1.0);
            const glm::dvec3 p = glm::dvec3(0, 0, 4) + d * (3.0 / -d.z);
            const double edge = std::max(std::abs(p.x), std::abs(p.y));
            if (std::abs(edge - 1.0) < 1e-3) continue;
            const bool in = edge < 1.0;
            covered += in;
            wrong += in != (img->color[img->index(x, y)].w > 0.0f);
            if (in) {
                EXPECT_NEAR(img->depth[img->index(x, y)], 3.0, 1e-5);
            }
        }
    EXPECT_GT(covered, 200);
    EXPECT_EQ(wrong, 0);
    // A bad index is an error, not a crash.
    mesh.triangles = {0, 1, 7};
    auto bad = render_reference(s);
    ASSERT_FALSE(bad.ok());
    EXPECT_NE(bad.message().find("index out of range"), std::string::npos) << bad.message();
}

// The mesh path under FFD: a lattice stretching x by 1.5 (Bernstein reproduces the linear map) traces the
// subdivided, deformed square; it must look like the square built stretched (same uvs per vertex), traced
// at rest, up to the tessellation's float rounding.
TEST(GroundTruth, DeformedMeshPathMatchesThePreStretchedMesh) {
    const SplatTexture m = four_by_two();
    ExactMesh square, stretched;
    square.positions = {{-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1}};
    for (const glm::dvec3& p : square.positions) square.uvs.emplace_back(0.25 + p.x / 8.0, 0.5 + p.y / 4.0);
    square.triangles = {0, 1, 2, 0, 2, 3};
    stretched = square;
    for (glm::dvec3& p : stretched.positions) p.x *= 1.5;
    Lattice lattice = make_lattice(glm::dvec3(-1.2, -1.2, -0.2),
                                   {glm::dvec3(2.4, 0, 0), glm::dvec3(0, 2.4, 0), glm::dvec3(0, 0, 2.4)},
                                   glm::ivec3(2, 2, 2));
    for (glm::dvec3& c : lattice.current) c.x *= 1.5;
    ReferenceScene deformed = axis_scene(96, 64, 4.0, m), direct = axis_scene(96, 64, 4.0, m);
    deformed.mesh = &square;
    deformed.lattices = {lattice};
    direct.mesh = &stretched;
    ReferenceSettings rs;
    rs.mesh_triangle_budget = 2000;  // 18 x 18 sub-triangles per triangle
    auto a = render_reference(deformed, rs);
    auto b = render_reference(direct, rs);
    ASSERT_TRUE(a.ok()) << a.message();
    ASSERT_TRUE(b.ok()) << b.message();
    auto cmp = compare_images(*a, *b);
    ASSERT_TRUE(cmp.ok());
    std::printf("deformed square vs pre-stretched square: %.2f dB, %zu px (%zu in one only)\n", cmp->psnr,
                cmp->pixels, cmp->pixels_one);
    EXPECT_GT(cmp->pixels, 2000u);
    EXPECT_LE(cmp->pixels_one, 2u);  // a pixel centre exactly on the edge may round either way
    EXPECT_GT(cmp->psnr_both, 60.0);
}

// Anisotropic filtering in the reference: an isotropic footprint is plain trilinear; a 4:1 footprint whose
// long axis runs along v, over a texture constant along v (columns of random colours), filters at the
// short axis's level: equal to trilinear with the long derivative divided by 4, sharper than trilinear.
TEST(GroundTruth, AnisotropicReferenceFilterProbesAlongTheMajorAxis) {
    SplatTexture m;
    m.width = m.height = 64;
    std::mt19937 rng(7);
    std::vector<std::uint8_t> column(64 * 3);
    for (auto& c : column) c = std::uint8_t(rng() & 255u);
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x)
            m.rgba8.insert(m.rgba8.end(), {column[3 * x], column[3 * x + 1], column[3 * x + 2], 255});
    const ReferenceTexture t(m);
    const glm::dvec2 uv(0.4137, 0.61), dx(3.0 / 64, 0.0), dy(0.0, 12.0 / 64);
    const glm::dvec4 iso = t.anisotropic(uv, dx, glm::dvec2(0.0, 3.0 / 64), 16),
                     tri = t.trilinear(uv, dx, glm::dvec2(0.0, 3.0 / 64));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(iso[c], tri[c], 1e-12);
    const glm::dvec4 an = t.anisotropic(uv, dx, dy, 16), sharp = t.trilinear(uv, dx, dy / 4.0),
                     blurred = t.trilinear(uv, dx, dy);
    double differs = 0.0;
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(an[c], sharp[c], 1e-6) << c;
        differs += std::abs(an[c] - blurred[c]);
    }
    EXPECT_GT(differs, 1e-3);  // trilinear alone blurs at the long axis's level
}

TEST(GroundTruth, SilhouetteIsTheAnalyticDisc) {
    SplatTexture m;  // untextured: base colour
    const int w = 201, h = 201;
    const double d = 3.0;
    const ReferenceScene s = axis_scene(w, h, d, m);
    auto img = render_reference(s);
    ASSERT_TRUE(img) << img.message();
    // Angular radius asin(1/d); on screen tan(asin(1/d)) / tan(fov/2) * h/2 pixels.
    const double r_px = std::tan(std::asin(1.0 / d)) / std::tan(glm::radians(22.5)) * h / 2.0;
    int mismatches = 0, covered = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const double dx = x + 0.5 - w / 2.0, dy = y + 0.5 - h / 2.0;
            const double r = std::sqrt(dx * dx + dy * dy);
            const bool inside = img->covered(x, y);
            covered += inside;
            if (std::abs(r - r_px) > 0.01 && inside != (r < r_px)) ++mismatches;
        }
    EXPECT_EQ(mismatches, 0);
    EXPECT_NEAR(covered, std::numbers::pi * r_px * r_px, 2.0 * std::numbers::pi * r_px * 0.5);
    // The rim is lit by ambient and a grazing light: darker than the centre, never black.
    EXPECT_GT(img->color[img->index(100, 100)].x, img->color[img->index(100, 100 - int(r_px) + 1)].x);
}

// A lattice that scales space by 1.5 about the origin is an affine map, which Bernstein lattices reproduce
// exactly: the traced tessellation of F(sphere) must match the analytic sphere of radius 1.5, texture
// coordinates included (the uv of a deformed point is the uv of its rest point).
TEST(GroundTruth, DeformedPathMatchesTheAnalyticScaledSphere) {
    const SplatTexture tex = [] {
        SplatTexture m;
        const assets::Image img = assets::make_sphere_texture(256, 128);
        m.width = img.width, m.height = img.height, m.rgba8 = img.rgba8;
        return m;
    }();
    ReferenceScene scaled = axis_scene(160, 120, 6.0, tex);
    Lattice l =
        assets::make_box_lattice(glm::dvec3(-1.1), glm::dvec3(1.1), glm::ivec3(4), LatticeBasis::bernstein);
    for (std::size_t i = 0; i < l.size(); ++i) l.current[i] = 1.5 * l.rest[i];
    scaled.lattices = {l};
    ReferenceSettings fine;
    fine.longitude_steps = 1024, fine.colatitude_steps = 512;
    auto traced = render_reference(scaled, fine);
    ASSERT_TRUE(traced) << traced.message();
    ReferenceScene analytic = axis_scene(160, 120, 6.0, tex);
    analytic.radius = 1.5;
    auto exact = render_reference(analytic);
    ASSERT_TRUE(exact) << exact.message();
    auto cmp = compare_images(*traced, *exact);
    ASSERT_TRUE(cmp) << cmp.message();
    EXPECT_GT(cmp->pixels, 4000u);  // pi * 37.4^2 px
    std::printf("traced vs analytic: PSNR %.2f dB, SSIM %.5f\n", cmp->psnr, cmp->ssim);
    EXPECT_GT(cmp->psnr, 45.0);
    EXPECT_GT(cmp->ssim, 0.995);
    int coverage_diff = 0;
    for (std::size_t k = 0; k < exact->color.size(); ++k)
        coverage_diff += (exact->color[k].w > 0) != (traced->color[k].w > 0);
    EXPECT_LE(coverage_diff, 4);  // only pixel centres within float rounding of the silhouette
}

TEST(GroundTruth, ReferenceSceneOfTheBuiltinSphere) {
    ecs::Registry reg;
    ASSERT_TRUE(assets::load_builtin_scene(reg, "sphere"));
    auto s = reference_scene(reg, 320, 180);
    ASSERT_TRUE(s) << s.message();
    EXPECT_EQ(s->radius, 1.0);
    EXPECT_EQ(s->center, glm::dvec3(0.0));
    EXPECT_TRUE(s->lattices.empty());  // at rest: the analytic path
    ASSERT_EQ(s->lights.to_light.size(), 1u);
    ecs::Registry empty;
    auto none = reference_scene(empty, 320, 180);
    ASSERT_FALSE(none);
    EXPECT_NE(none.message().find("no point cloud with an exact surface"), std::string::npos);
}

// Hidden and deleted splats: the surface they stand for is not traced (its nearest rest splat is gone),
// the rest of the image is unchanged.
TEST(GroundTruth, SurfaceOfGoneSplatsIsNotTraced) {
    ecs::Registry reg;
    ASSERT_TRUE(assets::load_builtin_scene(reg, "sphere"));
    auto plain_scene = reference_scene(reg, 160, 90);
    ASSERT_TRUE(plain_scene) << plain_scene.message();
    EXPECT_TRUE(plain_scene->point_gone.empty());
    auto plain = render_reference(*plain_scene);
    ASSERT_TRUE(plain) << plain.message();
    ecs::Entity sphere;
    reg.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud&) { sphere = e; });
    const SplatCloud& cloud = reg.get<SplatCloud>(sphere);
    PointFlags flags;
    for (const glm::vec3& p : cloud.positions)
        flags.bits.push_back(p.y > 0.0f ? std::uint8_t(kPointHidden) : std::uint8_t(0));
    reg.emplace<PointFlags>(sphere, flags);
    auto gone_scene = reference_scene(reg, 160, 90);
    ASSERT_TRUE(gone_scene) << gone_scene.message();
    ASSERT_EQ(gone_scene->point_gone.size(), cloud.size());
    auto gone = render_reference(*gone_scene);
    ASSERT_TRUE(gone) << gone.message();
    // Top half (y > 0 on the sphere, upright camera) uncovered, the bottom half unchanged, a band between.
    int top = 0, bottom = 0, bottom_same = 0, top_covered = 0;
    const glm::dmat4 inv_view = glm::inverse(plain_scene->view);
    const glm::dvec3 eye(inv_view[3]);
    for (int y = 0; y < plain->height; ++y)
        for (int x = 0; x < plain->width; ++x) {
            const std::size_t k = plain->index(x, y);
            if (plain->color[k].w == 0.0f) continue;
            // The hit's world point from its view depth along the ray.
            const double nx = 2.0 * (x + 0.5) / plain->width - 1.0,
                         ny = 2.0 * (plain->height - 1 - y + 0.5) / plain->height - 1.0;
            const glm::dvec3 dir =
                glm::dmat3(inv_view) *
                glm::dvec3(nx / plain_scene->projection[0][0], ny / plain_scene->projection[1][1], -1.0);
            const glm::dvec3 p = eye + dir * double(plain->depth[k]);
            if (p.y > 0.05) ++top, top_covered += gone->color[k].w > 0.0f;
            if (p.y < -0.05) ++bottom, bottom_same += gone->color[k] == plain->color[k];
        }
    EXPECT_GT(top, 500);
    EXPECT_GT(bottom, 500);
    EXPECT_EQ(top_covered, 0);
    EXPECT_EQ(bottom_same, bottom);
}

// The grid's nearest point against brute force (inside, outside, duplicates, a NaN point).
TEST(GroundTruth, NearestPointIsTheBruteForceNearest) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::vector<glm::dvec3> pts(3000);
    for (auto& p : pts) p = glm::dvec3(u(rng), 0.3 * u(rng), u(rng));
    pts[10] = pts[11];
    pts[20].x = std::numeric_limits<double>::quiet_NaN();  // never found
    const NearestPoint grid(pts);
    for (int q = 0; q < 2000; ++q) {
        const glm::dvec3 x(2.5 * u(rng), 2.5 * u(rng), 2.5 * u(rng));
        double best = 1e300;
        for (const auto& p : pts) best = std::min(best, glm::distance(p, x));
        const std::size_t k = grid.nearest(x);
        ASSERT_LT(k, pts.size());
        EXPECT_EQ(glm::distance(pts[k], x), best) << q;
    }
    EXPECT_EQ(NearestPoint().nearest(glm::dvec3(0.0)), std::numeric_limits<std::size_t>::max());
    EXPECT_EQ(grid.nearest(glm::dvec3(std::numeric_limits<double>::quiet_NaN())),
              std::numeric_limits<std::size_t>::max());
}

// FrameImage of w x 1 grey pixels given in sRGB (alpha 1; alpha 0 where grey < 0).
FrameImage grey_row(std::initializer_list<double> srgb) {
    FrameImage f;
    f.width = int(srgb.size()), f.height = 1;
    for (double g : srgb) {
        const float lin = g < 0 ? 0.0f : srgb_to_linear(float(g));
        f.color.push_back(glm::vec4(lin, lin, lin, g < 0 ? 0.0f : 1.0f));
    }
    return f;
}

TEST(ImageCompare, PsnrAndSsimOfHandComputedCases) {
    // Grey 0.5 vs 0.25 everywhere: MSE = 0.0625, PSNR = 10 log10(16) = 12.041 dB. Constant images have no
    // variance, so SSIM = (2 mu_a mu_b + C1) / (mu_a^2 + mu_b^2 + C1) = (0.25 + 1e-4) / (0.3125 + 1e-4).
    auto r = compare_images(grey_row({0.5, 0.5, 0.5}), grey_row({0.25, 0.25, 0.25}));
    ASSERT_TRUE(r) << r.message();
    EXPECT_EQ(r->pixels, 3u);
    EXPECT_NEAR(r->mse, 0.0625, 1e-6);
    EXPECT_NEAR(r->psnr, 10.0 * std::log10(16.0), 1e-4);
    EXPECT_NEAR(r->ssim, (0.25 + 1e-4) / (0.3125 + 1e-4), 1e-5);
    // One differing pixel of two: MSE = 0.25^2 / 2.
    auto half = compare_images(grey_row({0.5, 0.75}), grey_row({0.5, 0.5}));
    ASSERT_TRUE(half);
    EXPECT_NEAR(half->psnr, 10.0 * std::log10(2.0 / 0.0625), 1e-4);
}

TEST(ImageCompare, MaskIsThePixelsCoveredInEitherImage) {
    // Pixel 2 is background in both: ignored. Pixel 1 is covered in one only: compared against black.
    auto r = compare_images(grey_row({0.5, 0.5, -1}), grey_row({0.5, -1, -1}));
    ASSERT_TRUE(r);
    EXPECT_EQ(r->pixels, 2u);
    EXPECT_NEAR(r->mse, 0.25 / 2.0, 1e-6);
    auto whole = compare_images(grey_row({0.5, 0.5, -1}), grey_row({0.5, -1, -1}), false);
    ASSERT_TRUE(whole);
    EXPECT_EQ(whole->pixels, 3u);
}

// The interior: 5 x 5 neighbourhoods covered in both, the reference's normals turning < 10 degrees, the
// first image's normals agreeing. 12 x 12, crease at x = 6: x in {2, 3, 8, 9}, y in 2..9 (32 pixels);
// the first image showing another surface at (2, 2) removes the 6 whose neighbourhood holds it.
TEST(ImageCompare, InteriorAvoidsSilhouettesCreasesAndOtherSurfaces) {
    FrameImage a, b;
    for (FrameImage* f : {&a, &b}) {
        f->width = f->height = 12;
        f->color.assign(144, glm::vec4(0.5f, 0.5f, 0.5f, 1.0f));
        f->depth.assign(144, 1.0f);
        f->normal.resize(144);
        for (int y = 0; y < 12; ++y)
            for (int x = 0; x < 12; ++x)
                f->normal[f->index(x, y)] = x < 6 ? glm::vec3(0, 0, 1) : glm::vec3(1, 0, 0);
    }
    a.color[a.index(3, 5)] = glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);  // one interior pixel differs
    auto r = compare_images(a, b);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->pixels_interior, 32u);
    const double d = linear_to_srgb(0.5f);  // the difference in display values, per channel
    EXPECT_NEAR(r->psnr_interior, 10.0 * std::log10(32.0 / (d * d)), 1e-9);
    a.normal[a.index(2, 2)] = glm::vec3(0, 1, 0);
    r = compare_images(a, b);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->pixels_interior, 26u);
}

TEST(ImageCompare, IdenticalImagesAreInfiniteAndOne) {
    const FrameImage a = grey_row({0.1, 0.9, 0.3, -1, 0.7});
    auto r = compare_images(a, a);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->psnr, std::numeric_limits<double>::infinity());
    EXPECT_NEAR(r->ssim, 1.0, 1e-12);
    auto bad = compare_images(a, grey_row({0.1}));
    ASSERT_FALSE(bad);
    EXPECT_EQ(bad.message(), "images differ in size: 5x1 vs 1x1");
}

// The built-in sphere's uv frames: the rim point c + s axis_u + t axis_v, pushed onto the sphere, has the uv
// that the frame predicts (first order: within 5% of the frame's uv step; the second-order term grows like
// the splat radius times cot(colatitude)), away from the poles and the seam.
TEST(UvFrame, BuiltinSphereFramesPredictTheUvOfTheRim) {
    const SplatCloud c = assets::make_sphere_cloud(20000);
    ASSERT_EQ(c.uv_axes.size(), c.size());
    int checked = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        const glm::dvec2 uv0 = glm::dvec2(c.uvs[i]);
        if (uv0.y < 0.3 || uv0.y > 0.7 || uv0.x < 0.05 || uv0.x > 0.95) continue;
        for (double a = 0.0; a < 6.28; a += 0.7) {
            const double s = std::cos(a), t = std::sin(a);
            const glm::dvec3 p =
                glm::dvec3(c.positions[i]) + s * glm::dvec3(c.axis_u[i]) + t * glm::dvec3(c.axis_v[i]);
            const glm::dvec2 exact = sphere_uv(glm::normalize(p));
            const glm::dvec4 f(c.uv_axes[i]);
            const glm::dvec2 step = s * glm::dvec2(f.x, f.y) + t * glm::dvec2(f.z, f.w);
            ASSERT_LT(glm::length(uv0 + step - exact), 0.05 * glm::length(step) + 1e-6) << i;
            ++checked;
        }
    }
    EXPECT_GT(checked, 30000);
}

// Why the uv frame survives FFD: the FFD maps a splat's axes by its Jacobian, so the deformed rim point
// c' + s u' + t v' is F(c + s u + t v) to first order, and the rest point (hence the uv) of a deformed rim
// point is the rest rim point. Checked for a random lattice with the CPU deformation the renderer uses.
TEST(UvFrame, DeformedAxesMapTheRestRimToTheDeformedRim) {
    const SplatCloud c = assets::make_sphere_cloud(2000);
    Lattice l =
        assets::make_box_lattice(glm::dvec3(-1.2), glm::dvec3(1.2), glm::ivec3(4), LatticeBasis::bernstein);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> jitter(-0.15, 0.15);
    for (glm::dvec3& p : l.current) p += glm::dvec3(jitter(rng), jitter(rng), jitter(rng));
    const std::size_t n = c.size();
    std::vector<glm::vec3> pos(n), au(n), av(n);
    ASSERT_TRUE(ffd::deform(l, {c.positions.data(), nullptr, c.axis_u.data(), c.axis_v.data(), n, c.origin},
                            {pos.data(), nullptr, au.data(), av.data()}));
    // The rim points themselves, deformed as points.
    std::vector<glm::vec3> rim(n);
    for (double a : {0.3, 2.1, 4.4}) {
        for (std::size_t i = 0; i < n; ++i)
            rim[i] = c.positions[i] + float(std::cos(a)) * c.axis_u[i] + float(std::sin(a)) * c.axis_v[i];
        std::vector<glm::vec3> moved(n);
        ASSERT_TRUE(ffd::deform(l, {rim.data(), nullptr, nullptr, nullptr, n, c.origin},
                                {moved.data(), nullptr, nullptr, nullptr}));
        for (std::size_t i = 0; i < n; ++i) {
            const glm::dvec3 predicted =
                glm::dvec3(pos[i]) + std::cos(a) * glm::dvec3(au[i]) + std::sin(a) * glm::dvec3(av[i]);
            const double step = glm::length(predicted - glm::dvec3(pos[i]));
            ASSERT_LT(glm::length(predicted - glm::dvec3(moved[i])), 0.05 * step) << i;
        }
    }
}

// uniform_texel_radius against a brute-force Chebyshev distance to the nearest "edge" texel (border, or
// another colour among its 8 neighbours), and the property the cull relies on: every texel closer than
// that distance has the centre's colour.
TEST(TextureRegions, UniformRadiusIsTheChebyshevDistanceToAColourChange) {
    const int w = 41, h = 29;
    std::mt19937 rng(3);
    std::vector<std::uint8_t> tex(std::size_t(w * h) * 4, 255);
    // Rectangles of three colours over a grey field.
    for (int r = 0; r < 12; ++r) {
        const int x0 = int(rng() % w), y0 = int(rng() % h), x1 = std::min(w, x0 + 2 + int(rng() % 15)),
                  y1 = std::min(h, y0 + 2 + int(rng() % 10));
        const auto c = std::uint8_t(60 * (1 + rng() % 3));
        for (int y = y0; y < y1; ++y)
            for (int x = x0; x < x1; ++x) tex[std::size_t(y * w + x) * 4] = c;
    }
    auto colour = [&](int x, int y) { return tex[std::size_t(y * w + x) * 4]; };
    auto edge = [&](int x, int y) {
        if (x == 0 || y == 0 || x == w - 1 || y == h - 1) return true;
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx)
                if (colour(x + dx, y + dy) != colour(x, y)) return true;
        return false;
    };
    const std::vector<std::uint16_t> d = uniform_texel_radius(tex.data(), w, h);
    ASSERT_EQ(d.size(), std::size_t(w * h));
    int interior = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            int best = 1 << 30;
            for (int yy = 0; yy < h; ++yy)
                for (int xx = 0; xx < w; ++xx)
                    if (edge(xx, yy)) best = std::min(best, std::max(std::abs(xx - x), std::abs(yy - y)));
            ASSERT_EQ(int(d[std::size_t(y * w + x)]), best) << x << "," << y;
            interior += best > 1;
            for (int yy = std::max(0, y - best + 1); yy < std::min(h, y + best); ++yy)
                for (int xx = std::max(0, x - best + 1); xx < std::min(w, x + best); ++xx)
                    ASSERT_EQ(colour(xx, yy), colour(x, y));
        }
    EXPECT_GT(interior, 100);
}

// The CPU cull moves the built-in sphere's sprites whose footprint is one texture colour to the flat list
// (most of a checker's cells) and keeps the rest textured; without the distance map nothing is flat, and
// the two lists together are the same sprites.
TEST(TextureRegions, CpuCullDrawsOneColourFootprintsFlat) {
    const SplatCloud cloud = assets::make_sphere_cloud();
    const std::vector<gpu::GpuSplat> splats = pack_splats(cloud);
    Camera cam;
    cam.eye = glm::dvec3(0.0, 0.0, 4.0);
    gpu::FrameBlock f = camera_frame_block(view_matrix(cam), projection_matrix(cam, 16.0 / 9.0), 1280, 720,
                                           0.1f, 255.0f, true);
    f.params.w = 1.0f;
    f.counts.y = 1;
    f.light_dir[0] = glm::vec4(0, 0, 1, 0);
    f.light_color[0] = glm::vec4(1.0f);
    const std::vector<std::uint16_t> radius =
        uniform_texel_radius(cloud.texture.rgba8.data(), cloud.texture.width, cloud.texture.height);
    for (bool lit : {false, true}) {
        f.counts.w = lit ? 1u : 0u;
        TexelView texels{cloud.texture.rgba8.data(), cloud.texture.width, cloud.texture.height,
                         cloud.uv_axes.data(), radius.data()};
        CpuCullResult with, without;
        cull_splats_cpu(splats, f, texels, with);
        texels.uniform_radius = nullptr;
        cull_splats_cpu(splats, f, texels, without);
        EXPECT_EQ(without.visible_flat, 0u);
        EXPECT_EQ(with.visible_records + with.visible_flat, without.visible_records);
        EXPECT_GT(with.visible_flat, without.visible_records / 3) << "lit " << lit;
        EXPECT_GT(with.visible_records, without.visible_records / 10)
            << "lit " << lit;  // edges stay textured
    }
}

}  // namespace
}  // namespace sffd::render
