// 3D Gaussian entities in scene files and in `splatffd render`: a scene with a Gaussian
// cloud, a lattice and a twist clip saves, loads and renders the deformed Gaussians (equal to deforming
// then rendering, different from rest), also through the engine's frame (systems/engine); bad Gaussian
// files in a scene name the file; the command renders Gaussian files to frames. Headless EGL (llvmpipe
// here).
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>

#include <glm/gtc/quaternion.hpp>

#include "runtime/assets/formats/surface/export.h"
#include "runtime/assets/scene.h"
#include "runtime/core/file_io.h"
#include "runtime/gfx/context.h"
#include "runtime/scene/components.h"
#include "runtime/scene/lattice.h"
#include "systems/animation/animation_system.h"
#include "systems/animation/components.h"
#include "systems/animation/paper_demo.h"
#include "systems/animation/scene_extension.h"
#include "systems/engine/engine.h"
#include "systems/engine/engine_frame.h"
#include "systems/ffd/lattice.h"
#include "systems/gaussian/from_splats.h"
#include "systems/gaussian/gaussian_deform.h"
#include "runtime/assets/formats/gaussian/gaussian_gltf.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_scene.h"
#include "systems/gaussian/gaussian_system.h"
#include "systems/gaussian/reference_render.h"
#include "systems/splat_render/image_io.h"
#include "systems/splat_render/splat_render.h"
#include "systems/residency/residency_system.h"
#include "tests/systems/splat_render/test_scenes.h"
#include "tests/test_util/run_tool.h"
#include "tests/test_util/gl_required.h"

namespace {

using namespace sffd;
using namespace sffd::gaussian;
namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
    const fs::path d =
        fs::temp_directory_path() / ("sffd_gaussian_scene_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

int run(const std::string& args, std::string* output = nullptr) {
    const sffd::test::CliRun r = sffd::test::run_headless(args);
    if (output) *output = r.out;
    return r.code;
}

// A test sphere as Gaussians (a closed, coloured surface a twist visibly moves).
GaussianCloud sphere_gaussians() {
    SplatCloud s = render::test::fibonacci_sphere(6000, 1.0, 0.8);
    for (std::size_t i = 0; i < s.size(); ++i) {  // colour by height and longitude so a twist shows
        const glm::vec3 p = s.positions[i];
        const auto r = std::uint32_t(127.5f * (p.y + 1.0f)), g = std::uint32_t(127.5f * (p.x + 1.0f));
        s.colors[i] = 0xff000000u | (0x40u << 16) | (g << 8) | r;
    }
    return gaussians_from_splats(s);
}

Camera test_camera() {
    Camera c;
    c.eye = {0.0, 0.8, 4.0}, c.target = {0.0, 0.0, 0.0}, c.up = {0, 1, 0};
    c.fov_y_degrees = 40.0f, c.near_plane = 0.1f, c.far_plane = 20.0f;
    return c;
}

// Saves a scene: the Gaussian file sphere.ply (written here), a 5³ lattice around it bound as its
// deformer, the paper demo clip on the lattice (frames 72-95: global twist), the test camera.
fs::path write_scene(const fs::path& dir, const GaussianCloud& g) {
    const fs::path ply = dir / "sphere.ply";
    EXPECT_TRUE(write_ply(ply, g));
    ecs::Registry reg;
    register_gaussian_scene_hooks(SceneHooks::in(reg));
    register_animation_scene_hooks(SceneHooks::in(reg));
    auto e = load_gaussian_entity(reg, ply);
    EXPECT_TRUE(e) << e.message();
    // Written in the engine's orientation (y up), so stored in the scene as shown, without the turn a
    // y-down capture gets on loading (capture_up.h): the references below render the file's coordinates.
    if (e) reg.get<Transform>(*e) = Transform{};
    const ecs::Entity lat = reg.create();
    const Lattice l = ffd::make_lattice(
        {-1.3, -1.3, -1.3}, {glm::dvec3(2.6, 0, 0), glm::dvec3(0, 2.6, 0), glm::dvec3(0, 0, 2.6)}, {4, 4, 4});
    reg.emplace<Name>(lat, Name{"box"});
    reg.emplace<Lattice>(lat, l);
    reg.emplace<AnimationClip>(lat, make_paper_demo_clip(l));
    reg.emplace<AnimationState>(lat);
    reg.emplace<Deformers>(*e, Deformers{{lat}});
    reg.emplace<Camera>(reg.create(), test_camera());
    const fs::path scene = dir / "scene.gltf";
    const Status saved = save_scene(reg, scene);
    EXPECT_TRUE(saved) << saved.message();
    return scene;
}

class GaussianScene : public testing::Test {
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
};

ReferenceImage display_premultiplied(const render::FrameImage& f) {
    ReferenceImage r;
    r.width = f.width, r.height = f.height;
    for (const glm::vec4& c : f.color) {
        r.color.push_back(
            glm::vec3(render::linear_to_srgb(c.x), render::linear_to_srgb(c.y), render::linear_to_srgb(c.z)) *
            c.w);
        r.transmittance.push_back(1.0f - c.w);
    }
    return r;
}

TEST_F(GaussianScene, SavesAndLoadsTheGaussianEntityWithItsLatticeAndClip) {
    const fs::path dir = fresh_dir("roundtrip");
    const GaussianCloud g = sphere_gaussians();
    const fs::path scene = write_scene(dir, g);
    ecs::Registry reg;
    register_gaussian_scene_hooks(SceneHooks::in(reg));
    register_animation_scene_hooks(SceneHooks::in(reg));
    ASSERT_TRUE(load_scene(reg, scene.string()));
    ASSERT_EQ(reg.count<GaussianCloud>(), 1u);
    ecs::Entity e = ecs::null_entity;
    reg.view<const GaussianCloud>().each([&](ecs::Entity x, const GaussianCloud&) { e = x; });
    const GaussianCloud& loaded = reg.get<GaussianCloud>(e);
    EXPECT_EQ(loaded.size(), g.size());
    EXPECT_EQ(reg.get<Name>(e).value, "sphere");
    ASSERT_TRUE(reg.has<Deformers>(e));
    ASSERT_EQ(reg.get<Deformers>(e).lattices.size(), 1u);
    const ecs::Entity lat = reg.get<Deformers>(e).lattices[0];
    EXPECT_TRUE(reg.has<Lattice>(lat));
    EXPECT_TRUE(reg.has<AnimationClip>(lat));
    EXPECT_EQ(fs::path(reg.get<GaussianSource>(e).path), fs::absolute(dir / "sphere.ply").lexically_normal());
    // Saved again from the loaded registry (elsewhere): still one Gaussian entity referring to the file,
    // which is now outside the scene's folder: read only with --allow-outside-resources (the rule of
    // every resource a file names).
    const fs::path dir2 = fresh_dir("roundtrip2");
    ASSERT_TRUE(save_scene(reg, dir2 / "again.glb"));
    ecs::Registry refused;
    register_gaussian_scene_hooks(SceneHooks::in(refused));
    register_animation_scene_hooks(SceneHooks::in(refused));
    const Status outside = load_scene(refused, (dir2 / "again.glb").string());
    ASSERT_FALSE(outside);
    EXPECT_NE(outside.message().find("outside the file's folder"), std::string::npos) << outside.message();
    set_allow_outside_resources(true);
    ecs::Registry again;
    register_gaussian_scene_hooks(SceneHooks::in(again));
    register_animation_scene_hooks(SceneHooks::in(again));
    const Status allowed = load_scene(again, (dir2 / "again.glb").string());
    set_allow_outside_resources(false);
    ASSERT_TRUE(allowed) << allowed.message();
    EXPECT_EQ(again.count<GaussianCloud>(), 1u);
    EXPECT_EQ(again.count<Deformers>(), 1u);
    // A cloud made in memory (no file) is embedded in the scene (scene_embed_test.cpp checks the data).
    ecs::Registry mem;
    register_gaussian_scene_hooks(SceneHooks::in(mem));
    register_animation_scene_hooks(SceneHooks::in(mem));
    const ecs::Entity m = mem.create();
    mem.emplace<Name>(m, Name{"made"});
    mem.emplace<GaussianCloud>(m, g);
    ASSERT_TRUE(save_scene(mem, dir2 / "mem.gltf"));
    EXPECT_FALSE(fs::exists(dir2 / "made.gaussians.ply"));
    ecs::Registry mem2;
    register_gaussian_scene_hooks(SceneHooks::in(mem2));
    register_animation_scene_hooks(SceneHooks::in(mem2));
    ASSERT_TRUE(load_scene(mem2, (dir2 / "mem.gltf").string()));
    EXPECT_EQ(mem2.count<GaussianCloud>(), 1u);
}

TEST_F(GaussianScene, AnimatedTwistRendersTheDeformedGaussians) {
    if (!context()) SFFD_GL_UNAVAILABLE("no headless GL 4.5 context");
    const fs::path dir = fresh_dir("twist");
    const fs::path scene = write_scene(dir, sphere_gaussians());
    ecs::Registry reg;
    register_gaussian_scene_hooks(SceneHooks::in(reg));
    register_animation_scene_hooks(SceneHooks::in(reg));
    ASSERT_TRUE(load_scene(reg, scene.string()));
    render::RenderSettings s;
    s.width = 160, s.height = 120;
    reg.set_resource<render::RenderSettings>(s);
    auto frame_at = [&](int k) {
        const FrameContext fc{std::uint64_t(k), double(k) / paper_demo_fps, 1.0 / paper_demo_fps};
        animation_system(reg, fc);
        residency_system(reg, fc);
        gaussian_deform_system(reg, fc);
        render::render_system(reg, fc);
        auto img = render::capture_frame(reg);
        EXPECT_TRUE(img.ok());
        return img.ok() ? display_premultiplied(*img) : ReferenceImage{};
    };
    const ReferenceImage rest = frame_at(0);
    const ReferenceImage twisted = frame_at(84);  // global twist peak
    ecs::Entity e = ecs::null_entity;
    reg.view<const GaussianCloud>().each([&](ecs::Entity x, const GaussianCloud&) { e = x; });
    // Deform then render, independently: the lattice as the clip left it, gaussian::deform, the CPU
    // reference.
    const Lattice& lattice = reg.get<Lattice>(reg.get<Deformers>(e).lattices[0]);
    GaussianCloud deformed;
    ASSERT_TRUE(deform(lattice, reg.get<GaussianCloud>(e), deformed));
    ReferenceOptions o;
    o.width = 160, o.height = 120, o.near_plane = test_camera().near_plane;
    const ReferenceImage expected = render_reference(deformed, test_camera(), o);
    const ReferenceImage at_rest = render_reference(reg.get<GaussianCloud>(e), test_camera(), o);
    const double p_deformed = psnr(expected, twisted), p_rest = psnr(rest, twisted),
                 p_rest_ref = psnr(at_rest, rest);
    std::printf(
        "twisted scene frame 84: PSNR %.1f dB vs deform-then-render, %.1f dB vs the rest frame; rest frame "
        "vs reference %.1f dB\n",
        p_deformed, p_rest, p_rest_ref);
    EXPECT_GT(p_deformed, 40.0);
    EXPECT_GT(p_rest_ref, 40.0);
    EXPECT_LT(p_rest, 30.0);
    render::release_render_state(reg);
}

TEST_F(GaussianScene, BadGaussianFileInASceneNamesTheFile) {
    const fs::path dir = fresh_dir("bad");
    const fs::path scene = write_scene(dir, sphere_gaussians());
    // Truncate the Gaussian file the scene refers to.
    const fs::path ply = dir / "sphere.ply";
    fs::resize_file(ply, fs::file_size(ply) / 2);
    ecs::Registry reg;
    register_gaussian_scene_hooks(SceneHooks::in(reg));
    register_animation_scene_hooks(SceneHooks::in(reg));
    const Status st = load_scene(reg, scene.string());
    ASSERT_FALSE(st);
    std::printf("%s\n", st.message().c_str());
    EXPECT_NE(st.message().find(scene.string()), std::string::npos) << st.message();
    EXPECT_NE(st.message().find("sphere.ply"), std::string::npos) << st.message();
    EXPECT_EQ(reg.count<GaussianCloud>(), 0u);  // nothing half-loaded
    std::string out;
    EXPECT_EQ(run("render " + scene.string() + " --out " + (dir / "frames").string() + " --size 32x24", &out),
              1);
    EXPECT_NE(out.find("sphere.ply"), std::string::npos) << out;
    // A missing Gaussian file.
    fs::remove(ply);
    const Status missing = load_scene(reg, scene.string());
    ASSERT_FALSE(missing);
    EXPECT_NE(missing.message().find("no such Gaussian file"), std::string::npos) << missing.message();
}

// Channels of the display-space (premultiplied) images that differ by more than 8 of 255.
std::size_t differing_channels(const ReferenceImage& a, const ReferenceImage& b) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.color.size() && i < b.color.size(); ++i)
        for (int c = 0; c < 3; ++c) n += std::abs(a.color[i][c] - b.color[i][c]) * 255.0f > 8.0f;
    return n;
}

// The animated scene through the engine's frame (make_engine_schedule + render_engine_frame: what
// `splatffd render` runs for each frame, without the command): frame 84 (twist peak) differs from the
// rest frame, and frame 84 rendered alone equals frame 84 rendered after frame 83.
TEST_F(GaussianScene, AnimatedSceneThroughTheEngineFrame) {
    if (!context()) SFFD_GL_UNAVAILABLE("no headless GL 4.5 context");
    const fs::path dir = fresh_dir("engine");
    const fs::path scene = write_scene(dir, sphere_gaussians());
    const Schedule schedule = make_engine_schedule({.present = false});
    auto render_frames = [&](std::vector<std::uint64_t> ks) {
        std::vector<ReferenceImage> out;
        ecs::Registry reg;
        register_gaussian_scene_hooks(SceneHooks::in(reg));
        register_animation_scene_hooks(SceneHooks::in(reg));
        const Status loaded = load_scene(reg, scene.string());
        EXPECT_TRUE(loaded) << loaded.message();
        render::RenderSettings s;
        s.width = 64, s.height = 48;
        reg.set_resource<render::RenderSettings>(s);
        for (std::uint64_t k : ks) {
            auto image = render_engine_frame(reg, schedule, *context(), {.frame = k, .fps = paper_demo_fps});
            EXPECT_TRUE(image) << image.message();
            out.push_back(image ? display_premultiplied(*image) : ReferenceImage{});
        }
        render::release_render_state(reg);
        return out;
    };
    const std::vector<ReferenceImage> sequence = render_frames({83, 84});
    const std::vector<ReferenceImage> rest = render_frames({0});
    const std::vector<ReferenceImage> alone = render_frames({84});
    ASSERT_EQ(sequence[1].color.size(), std::size_t(64 * 48));
    const std::size_t moved = differing_channels(sequence[1], rest[0]);
    std::printf("engine frame 84 vs rest: %zu differing channels; vs frame 83: %zu\n", moved,
                differing_channels(sequence[1], sequence[0]));
    EXPECT_GT(moved, 200u) << "the twist moved the colours";
    EXPECT_EQ(differing_channels(sequence[1], alone[0]), 0u) << "frame 84 depends on its index only";
}

// The command on a Gaussian file: told apart from a surface PLY by its properties, framed, --camera and
// --turntable (the engine's frame itself is tested above, without the command).
TEST_F(GaussianScene, RenderCommandOnGaussianFiles) {
    if (!context()) SFFD_GL_UNAVAILABLE("no headless GL 4.5 context");
    const fs::path dir = fresh_dir("command");
    write_scene(dir, sphere_gaussians());
    std::string out;
    ASSERT_EQ(run("render " + (dir / "sphere.ply").string() + " --out " + (dir / "file").string() +
                      " --size 64x48 --turntable 2",
                  &out),
              0)
        << out;
    for (const char* f : {"frame_0000.png", "frame_0001.png"}) {
        auto png = render::read_png(dir / "file" / f);
        ASSERT_TRUE(png) << png.message();
        std::size_t covered = 0;
        for (std::size_t k = 3; k < png->pixels.size(); k += 4) covered += png->pixels[k] > 128;
        EXPECT_GT(covered, 64u * 48u / 10) << f;
    }
    ASSERT_EQ(run("render " + (dir / "sphere.ply").string() + " --out " + (dir / "cam").string() +
                      " --size 64x48 --camera 0,0,5,0,0,0,0,1,0,40",
                  &out),
              0)
        << out;
    auto cam = render::read_png(dir / "cam" / "frame_0000.png");
    ASSERT_TRUE(cam) << cam.message();
}

TEST_F(GaussianScene, EditorAddsALatticeToAGaussianFileAndSavesTheDeformedScene) {
    if (!context()) SFFD_GL_UNAVAILABLE("no headless GL 4.5 context");
    // `splatffd view g.ply` (headless, replayed keys: shift+a fits a lattice, select all, move the inner
    // points by 0.3 in x, ctrl+s): the saved scene refers to g.ply, binds the lattice, and renders the
    // Gaussians deformed (different from the file alone).
    const fs::path dir = fresh_dir("editor");
    ASSERT_TRUE(write_ply(dir / "g.ply", sphere_gaussians()));
    const std::string replay = std::string(SFFD_TEST_DATA_DIR) + "/editor/lattice_add.txt";
    std::string out;
    ASSERT_EQ(run("view " + (dir / "g.ply").string() +
                      " --headless --no-ui --quality preview --frames 14 --replay " + replay + " --save " +
                      (dir / "edited.glb").string(),
                  &out),
              0)
        << out;
    ecs::Registry reg;
    register_gaussian_scene_hooks(SceneHooks::in(reg));
    register_animation_scene_hooks(SceneHooks::in(reg));
    ASSERT_TRUE(load_scene(reg, (dir / "edited.glb").string()));
    ASSERT_EQ(reg.count<GaussianCloud>(), 1u);
    ASSERT_EQ(reg.count<Lattice>(), 1u);
    ecs::Entity e = ecs::null_entity;
    reg.view<const GaussianCloud>().each([&](ecs::Entity x, const GaussianCloud&) { e = x; });
    ASSERT_TRUE(reg.has<Deformers>(e));
    const Lattice& l = reg.get<Lattice>(reg.get<Deformers>(e).lattices.at(0));
    std::size_t moved = 0;
    for (std::size_t k = 0; k < l.rest.size(); ++k)
        moved += std::abs(l.current[k].x - l.rest[k].x - 0.3) < 1e-9;
    EXPECT_EQ(moved, 729u);  // the 9^3 inner points of the default 11^3 fit
    // The saved scene and the file alone through the engine's frame: the Gaussians are drawn deformed.
    const Schedule schedule = make_engine_schedule({.present = false});
    auto first_frame = [&](const fs::path& file) {
        ecs::Registry r;
        register_gaussian_scene_hooks(SceneHooks::in(r));
        register_animation_scene_hooks(SceneHooks::in(r));
        const Status loaded = load_scene(r, file.string());
        EXPECT_TRUE(loaded) << loaded.message();
        render::RenderSettings s;
        s.width = 96, s.height = 72;
        r.set_resource<render::RenderSettings>(s);
        auto image = render_engine_frame(r, schedule, *context(), {.frame = 0, .fps = paper_demo_fps});
        EXPECT_TRUE(image) << image.message();
        render::release_render_state(r);
        return image ? display_premultiplied(*image) : ReferenceImage{};
    };
    EXPECT_GT(differing_channels(first_frame(dir / "edited.glb"), first_frame(dir / "g.ply")), 100u);
}

TEST_F(GaussianScene, GaussianFilesAreToldApartFromSurfaceFiles) {
    const fs::path dir = fresh_dir("kinds");
    const GaussianCloud g = sphere_gaussians();
    ASSERT_TRUE(write_ply(dir / "g.ply", g));
    ASSERT_TRUE(write_glb(dir / "g.glb", g));
    ASSERT_TRUE(assets::save_splat_ply(render::test::fibonacci_sphere(500), dir / "surface.ply"));
    for (const char* f : {"g.ply", "g.glb"}) {
        ecs::Registry reg;
        register_gaussian_scene_hooks(SceneHooks::in(reg));
        register_animation_scene_hooks(SceneHooks::in(reg));
        ASSERT_TRUE(load_scene(reg, (dir / f).string())) << f;
        EXPECT_EQ(reg.count<GaussianCloud>(), 1u) << f;
        EXPECT_EQ(reg.count<SplatCloud>(), 0u) << f;
        EXPECT_EQ(reg.count<Camera>(), 1u) << f;  // a default view, like an imported point cloud
        reg.view<const GaussianCloud>().each(
            [&](const GaussianCloud& c) { EXPECT_EQ(c.size(), g.size()) << f; });
    }
    ecs::Registry reg;
    register_gaussian_scene_hooks(SceneHooks::in(reg));
    register_animation_scene_hooks(SceneHooks::in(reg));
    ASSERT_TRUE(load_scene(reg, (dir / "surface.ply").string()));
    EXPECT_EQ(reg.count<GaussianCloud>(), 0u);
    EXPECT_EQ(reg.count<SplatCloud>(), 1u);
    // Our own scene files are never taken for KHR Gaussian files, even when they hold Gaussian entities.
    reg.emplace<GaussianCloud>(reg.create(), g);
    ASSERT_TRUE(save_scene(reg, dir / "scene.glb"));
    EXPECT_FALSE(is_gaussian_scene_file(dir / "scene.glb"));
    EXPECT_TRUE(is_gaussian_scene_file(dir / "g.glb"));
    EXPECT_FALSE(is_gaussian_scene_file(dir / "surface.ply"));
    // A bad Gaussian file opened directly: `file: problem`, nothing created.
    fs::resize_file(dir / "g.ply", 300);
    ecs::Registry bad;
    register_gaussian_scene_hooks(SceneHooks::in(bad));
    register_animation_scene_hooks(SceneHooks::in(bad));
    const Status st = load_scene(bad, (dir / "g.ply").string());
    ASSERT_FALSE(st);
    EXPECT_EQ(st.message().rfind((dir / "g.ply").string(), 0), 0u) << st.message();
    EXPECT_EQ(bad.count<GaussianCloud>(), 0u);
    std::string out;
    EXPECT_EQ(
        run("render " + (dir / "g.ply").string() + " --out " + (dir / "frames").string() + " --size 32x24",
            &out),
        1);
    EXPECT_NE(out.find((dir / "g.ply").string() + ":"), std::string::npos) << out;
}

}  // namespace
