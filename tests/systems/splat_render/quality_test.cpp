// Image quality of the textured built-in sphere against its ground truth (ground_truth.h): the issue-14
// targets, PSNR >= 38 dB in HQ and >= 30 dB in preview, at rest and at the demo clip's local stretch and
// global twist peaks. Rendered at 640 x 360 (the command-line measurements in RESULTS.md are 1280 x 720)
// so the test stays a few seconds on llvmpipe; the deformed ground truth uses a 1024 x 512 tessellation.
#include <cstdio>
#include <filesystem>

#include "runtime/app/clock.h"
#include "runtime/assets/builtin_scenes.h"
#include "systems/animation/animation_system.h"
#include "systems/animation/editing.h"
#include "systems/animation/paper_demo.h"
#include "systems/ffd/deform.h"
#include "systems/ffd/ffd_system.h"
#include "systems/splat_render/ground_truth.h"
#include "systems/splat_render/image_compare.h"
#include "runtime/assets/import.h"
#include "tests/assets/test_util.h"
#include "tests/assets/textured_box.h"
#include "tests/systems/splat_render/gl_fixture.h"
#include "systems/residency/residency_system.h"

namespace sffd::render::test {
namespace {

namespace fs = std::filesystem;

class Quality_ : public GlRenderTest {
protected:
    // The converted box `cloud` with its mesh `g` as the ExactMesh ground truth (positions relative to the
    // cloud's origin), the box tests' camera and light.
    ecs::Entity add_box_and_its_mesh(const assets::Geometry& g, SplatCloud cloud) {
        const ecs::Entity e = reg.create();
        ExactMesh mesh;
        for (const glm::dvec3& p : g.positions) mesh.positions.push_back(p - cloud.origin);
        mesh.uvs = g.uvs;
        mesh.triangles = g.triangles;
        reg.emplace<SplatCloud>(e, std::move(cloud));
        reg.emplace<ExactMesh>(e, std::move(mesh));
        Camera cam;
        cam.eye = glm::dvec3(0.9, 0.8, 2.4);
        cam.near_plane = 0.05f;
        reg.emplace<Camera>(reg.create(), cam);
        add_light({-0.4f, -0.6f, -0.7f}, 0.15f);
        return e;
    }
    // Both qualities against the mesh ground truth `ref`: most pixels are face interior, and there the
    // PSNR is at least `hq_db` / `preview_db`.
    void expect_interior_matches(const FrameImage& ref, int w, int h, const char* what, double hq_db,
                                 double preview_db) {
        for (Quality q : {Quality::hq, Quality::preview}) {
            const FrameImage img = render(q, w, h);
            auto cmp = compare_images(img, ref);
            ASSERT_TRUE(cmp.ok()) << cmp.message();
            const char* name = q == Quality::hq ? "hq" : "preview";
            std::printf(
                "%s %s vs its mesh ground truth: PSNR %.2f dB (covered in both %.2f dB, %zu px covered in "
                "one only), "
                "interior %.2f dB over %zu of %zu px\n",
                what, name, cmp->psnr, cmp->psnr_both, cmp->pixels_one, cmp->psnr_interior,
                cmp->pixels_interior, cmp->pixels);
            EXPECT_GT(cmp->pixels_interior, cmp->pixels * 3 / 4) << name;
            EXPECT_GE(cmp->psnr_interior, q == Quality::hq ? hq_db : preview_db) << name;
        }
    }
    // The built-in sphere with the demo clip on its lattice (what `splatffd render sphere` loads).
    void load_sphere() {
        ASSERT_TRUE(assets::load_builtin_scene(reg, "sphere"));
        std::vector<ecs::Entity> lattices;
        reg.view<const Lattice>().each([&](ecs::Entity e, const Lattice&) { lattices.push_back(e); });
        ASSERT_EQ(lattices.size(), 1u);
        attach_clip(reg, lattices[0], make_paper_demo_clip(reg.get<Lattice>(lattices[0])));
    }
    // Frame k as `splatffd render --frames k:k` makes it (animation, deformation, rendering), and the
    // ground truth of the same pose.
    std::pair<FrameImage, FrameImage> frame(long k, Quality quality, int w, int h) {
        Clock clock(ClockSettings{.fixed_dt = 1.0 / paper_demo_fps});
        clock.seek(double(k) / paper_demo_fps);
        FrameContext f = clock.tick();
        f.frame = std::uint64_t(k);
        animation_system(reg, f);
        residency_system(reg, f);
        ffd_system(reg, f);
        RenderSettings s;
        s.quality = quality, s.width = w, s.height = h, s.aux_outputs = true;
        reg.set_resource<RenderSettings>(s);
        render_system(reg, f);
        auto img = capture_frame(reg);
        EXPECT_TRUE(img.ok()) << (img.ok() ? "" : img.message());
        auto scene = reference_scene(reg, w, h);
        EXPECT_TRUE(scene.ok()) << (scene.ok() ? "" : scene.message());
        if (!img.ok() || !scene.ok()) return {};
        EXPECT_EQ(scene->lattices.empty(), k == 0) << "frame " << k << ": the clip should deform the sphere";
        ReferenceSettings rs;
        rs.longitude_steps = 1024, rs.colatitude_steps = 512;
        auto ref = render_reference(*scene, rs);
        EXPECT_TRUE(ref.ok()) << (ref.ok() ? "" : ref.message());
        return {std::move(img.value()), ref.ok() ? std::move(ref.value()) : FrameImage{}};
    }
};

TEST_F(Quality_, TexturedSphereMeetsThePsnrTargetsAgainstTheGroundTruth) {
    load_sphere();
    // 0: rest; 12: local stretch at its peak (frames 9-15); 84: global twist at its peak (frames 81-87).
    for (long k : {0L, 12L, 84L}) {
        for (Quality q : {Quality::hq, Quality::preview}) {
            auto [img, ref] = frame(k, q, 640, 360);
            auto cmp = compare_images(img, ref);
            ASSERT_TRUE(cmp.ok()) << cmp.message();
            const char* name = q == Quality::hq ? "hq" : "preview";
            std::printf("frame %ld %s: PSNR %.2f dB, SSIM %.4f, %zu px (%zu covered in one only)\n", k, name,
                        cmp->psnr, cmp->ssim, cmp->pixels, cmp->pixels_one);
            EXPECT_GT(cmp->pixels, 25000u);  // the sphere is ~210 px across at this size
            EXPECT_GE(cmp->psnr, q == Quality::hq ? 38.0 : 30.0) << "frame " << k << " " << name;
            // The silhouette agrees with the exact one but for a pixel-wide fringe in places.
            EXPECT_LT(double(cmp->pixels_one), 0.01 * double(cmp->pixels)) << "frame " << k << " " << name;
        }
    }
}

// The CPU cull draws one-colour footprints flat (CpuCullResult::flat_records); the compute cull textures
// every sprite. Both images must agree.
TEST_F(Quality_, FlatColouredSpritesLookLikeTexturedOnes) {
    load_sphere();
    for (Quality q : {Quality::hq, Quality::preview}) {
        FrameImage img[2];
        for (int compute = 0; compute < 2; ++compute) {
            release_render_state(reg);
            img[compute] = render(q, 640, 360, true, compute ? CullPath::compute : CullPath::cpu);
            const RenderStats& stats = reg.resource<RenderStats>();
            EXPECT_EQ(stats.cpu_culled_clouds, compute ? 0u : 1u);
        }
        auto cmp = compare_images(img[0], img[1]);
        ASSERT_TRUE(cmp.ok());
        std::printf("%s: flat + textured vs all textured: PSNR %.2f dB\n",
                    q == Quality::hq ? "hq" : "preview", cmp->psnr);
        EXPECT_GT(cmp->psnr, 45.0);
        EXPECT_EQ(cmp->pixels_one, 0u);
    }
}

// A textured mesh converted to splats (mesh sampling keeps the texture and gives each splat a
// uv frame) shows its checker per pixel: every pixel of the box's front face, away from cell and face
// edges, has the colour of the checker cell its ray hits, in HQ and preview. The cells (8 texels, about
// 16 x 90 px here) are not much taller than a splat, so one colour per splat (the same cloud without uv
// frames: HQ blends its neighbours' colours) gets many pixels wrong: the check that this test sees it.
TEST_F(Quality_, ConvertedTexturedMeshShowsItsCheckerPerPixel) {
    constexpr int kTexels = 256, kCells = 32;
    auto g = assets::read_geometry(
        sffd::test::write_textured_box(sffd::test::fresh_dir("render", "textured_box"), kTexels, kCells));
    ASSERT_TRUE(g.ok()) << g.message();
    assets::ImportOptions opt;
    opt.splats = 4000;
    auto converted = assets::make_splat_cloud(*g, opt);
    ASSERT_TRUE(converted.ok()) << converted.message();
    ASSERT_EQ(converted->uv_axes.size(), converted->size());
    const sffd::test::BoxFace front = sffd::test::textured_box_faces()[0];  // z = 0.25, facing +z
    Camera cam;
    cam.eye = glm::dvec3(0.0, 0.0, 2.0);
    cam.near_plane = 0.05f;
    reg.emplace<Camera>(reg.create(), cam);
    reg.emplace<AmbientLight>(reg.create(), AmbientLight{glm::vec3(1.0f), 1.0f});  // albedo shows
    const std::vector<std::uint8_t> texels = sffd::test::checker_texels(kTexels, kCells);
    const int w = 512, h = 288;
    auto wrong_fraction = [&](const FrameImage& img, const char* what) {
        int checked = 0, wrong = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const glm::dvec3 d = pixel_ray(cam, x, y, w, h);
                const glm::dvec3 p = cam.eye + d * ((front.corner.z - cam.eye.z) / d.z);
                const glm::dvec2 st = front.st(p);
                if (st.x < 0.03 || st.x > 0.97 || st.y < 0.05 || st.y > 0.95) continue;  // the face's border
                const glm::dvec2 t = front.uv(p) * double(kTexels);                      // texel coordinates
                const double cell = double(kTexels / kCells);
                auto edge = [&](double c) {
                    const double r = std::fmod(c, cell);
                    return std::min(r, cell - r);
                };
                if (edge(t.x) < 1.5 || edge(t.y) < 1.5) continue;  // within the filter's reach of a cell edge
                const std::uint8_t* want = &texels[(std::size_t(t.y) * kTexels + std::size_t(t.x)) * 4];
                ++checked;
                const glm::vec4 c = img.color[img.index(x, y)];
                for (int k = 0; k < 3; ++k)
                    if (std::abs(int(encode_srgb8(c[k])) - int(want[k])) > 12) {
                        ++wrong;
                        break;
                    }
            }
        std::printf("%s: %d of %d pixels off their checker cell's colour\n", what, wrong, checked);
        EXPECT_GT(checked, 15000) << what;
        return checked ? double(wrong) / checked : 1.0;
    };
    const ecs::Entity e = add_cloud(*converted, SplatMaterial{.specular = 0.0f});
    for (Quality q : {Quality::hq, Quality::preview}) {
        const char* name = q == Quality::hq ? "hq, per-pixel texture" : "preview, per-pixel texture";
        EXPECT_LT(wrong_fraction(render(q, w, h), name), 0.002) << name;
    }
    // Without the uv frame every fragment takes the splat centre's colour: the checker edges break up.
    release_render_state(reg);
    reg.get<SplatCloud>(e).uv_axes.clear();
    EXPECT_GT(wrong_fraction(render(Quality::hq, w, h), "hq, one colour per splat"), 0.05);
}

// The same kind of converted box against its mesh ground truth (ExactMesh: the OBJ's triangles through
// Embree, textured through their uvs, lit like the splats). Inside the faces the splats reproduce the
// ground truth (texture filtered per pixel, flat shading); the error is at the box's silhouette and
// creases, where flat discs overshoot the edges (no clipping of splats at sharp edges).
TEST_F(Quality_, ConvertedTexturedMeshAgainstItsMeshGroundTruth) {
    const fs::path obj =
        sffd::test::write_textured_box(sffd::test::fresh_dir("render", "textured_box_gt"), 256, 16);
    auto g = assets::read_geometry(obj);
    ASSERT_TRUE(g.ok()) << g.message();
    assets::ImportOptions opt;
    opt.splats = 20000;
    auto converted = assets::make_splat_cloud(*g, opt);
    ASSERT_TRUE(converted.ok()) << converted.message();
    const ecs::Entity e = add_box_and_its_mesh(*g, std::move(*converted));
    const int w = 640, h = 360;
    auto scene = reference_scene(reg, w, h);
    ASSERT_TRUE(scene.ok()) << scene.message();
    ASSERT_NE(scene->mesh, nullptr);
    auto ref = render_reference(*scene);
    ASSERT_TRUE(ref.ok()) << ref.message();
    expect_interior_matches(*ref, w, h, "box", 45.0, 40.0);
    // Without the uv frames (one colour per splat) the interior no longer matches.
    release_render_state(reg);
    reg.get<SplatCloud>(e).uv_axes.clear();
    auto flat = compare_images(render(Quality::hq, w, h), *ref);
    ASSERT_TRUE(flat.ok());
    std::printf("box hq without uv frames: interior %.2f dB\n", flat->psnr_interior);
    EXPECT_LT(flat->psnr_interior, 35.0);
}

// Under FFD: the converted box twisted by a lattice (the splats through ffd::deform: positions, normals,
// axes; the uv frames ride on the axes) against the mesh ground truth deformed by the same lattice
// (each triangle subdivided, its vertices through the same deformation).
TEST_F(Quality_, TwistedConvertedMeshAgainstItsTwistedMeshGroundTruth) {
    auto g = assets::read_geometry(
        sffd::test::write_textured_box(sffd::test::fresh_dir("render", "textured_box_twist"), 256, 16));
    ASSERT_TRUE(g.ok()) << g.message();
    assets::ImportOptions opt;
    opt.splats = 20000;
    auto cloud = assets::make_splat_cloud(*g, opt);
    ASSERT_TRUE(cloud.ok()) << cloud.message();
    // A twist about x: the control points turn by up to +-0.5 rad from one end to the other.
    Lattice lattice = make_lattice(glm::dvec3(-1.2, -0.7, -0.45),
                                   {glm::dvec3(2.4, 0, 0), glm::dvec3(0, 1.4, 0), glm::dvec3(0, 0, 0.9)},
                                   glm::ivec3(4, 3, 3));
    for (glm::dvec3& c : lattice.current) {
        const double a = 0.5 * c.x / 1.2, ca = std::cos(a), sa = std::sin(a);
        c = glm::dvec3(c.x, ca * c.y - sa * c.z, sa * c.y + ca * c.z);
    }
    SplatCloud& c = *cloud;
    const ffd::PointsIn in{c.positions.data(), c.normals.data(), c.axis_u.data(),
                           c.axis_v.data(),    c.size(),         c.origin};
    const ffd::PointsOut out{c.positions.data(), c.normals.data(), c.axis_u.data(), c.axis_v.data()};
    auto st = ffd::deform(lattice, in, out);
    ASSERT_TRUE(st.ok()) << st.message();
    ASSERT_EQ(st->inside, c.size());
    add_box_and_its_mesh(*g, std::move(c));
    const int w = 640, h = 360;
    auto scene = reference_scene(reg, w, h);
    ASSERT_TRUE(scene.ok()) << scene.message();
    scene->lattices = {lattice};  // the cloud above was deformed directly, not through Deformers
    auto ref = render_reference(*scene);
    ASSERT_TRUE(ref.ok()) << ref.message();
    expect_interior_matches(*ref, w, h, "twisted box", 40.0, 35.0);
}

}  // namespace
}  // namespace sffd::render::test
