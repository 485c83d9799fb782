// Point mode through the real editor (`splatffd view --headless --replay`): tests/data/editor/
// point_separate.txt lassos the top half of the sphere through it (x-ray), separates it into an entity of
// its own, fits a lattice to the part (shift+a) and twists it 45 degrees about y. Against the same run
// without the edits (only the overlay turned off, as in the session), on the surface splat sphere and on
// the Gaussian sphere:
//   - every pixel of the bottom half farther than `margin` from the cut (the plane the lasso's bottom
//     edge spans with the eye: through the sphere's centre, normal the camera's up) is exactly the same,
//     colour and depth: the original cloud and its own lattice are untouched by the separation;
//   - the top half changed.
// Where a pixel lies is read from the unedited frame's depth (the view-axis Z of its EXR) through the
// scene's camera, the one the editor uses.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "runtime/assets/scene.h"
#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "systems/editor/editor_system.h"
#include "systems/engine/engine_frame.h"
#include "systems/splat_render/image_io.h"
#include "tests/test_util/run_tool.h"

using namespace sffd;
namespace fs = std::filesystem;

namespace {

const std::string session = std::string(SFFD_TEST_DATA_DIR) + "/editor/point_separate.txt";
constexpr int frames = 40;
const Viewport viewport{1280, 720};

struct Dir {
    fs::path path;
    explicit Dir(const std::string& name) {
        path = fs::temp_directory_path() / ("sffd_point_view_" + name + "_" + std::to_string(::getpid()));
        fs::remove_all(path);
        fs::create_directories(path);
    }
    ~Dir() {
        if (!::testing::Test::HasFailure()) fs::remove_all(path);
    }
};

// `view SCENE` headless with a replay; the last frame as EXR. Returns the log.
std::string view(const std::string& scene, const fs::path& replay, const fs::path& exr) {
    const test::CliRun r = test::run_headless(
        "view " + scene + " --headless --size 1280x720 --quality preview --frames " + std::to_string(frames) +
        " --replay " + replay.string() + " --out " + exr.string());
    EXPECT_EQ(r.code, 0) << r.out;
    return r.out;
}

struct Opened {
    Camera camera;       // the camera the editor opens the scene with (setup_editor)
    double lowest_part;  // the lowest world y of the points the lasso takes
};

// The lasso's bottom edge (screen row 360, the sphere's centre) and the eye span the cut plane: it holds
// the camera's right and forward directions, so its normal is the camera's up. The lasso (x-ray) takes
// every point on its upper side; a twist about y keeps each point's height (the lattice's y coordinates
// do not change, and a Bernstein lattice reproduces linear functions), so no point of the part ever goes
// below the lowest of them.
glm::dvec3 cut_normal(const Camera& cam) {
    const glm::dvec3 forward = glm::normalize(cam.target - cam.eye);
    return glm::cross(glm::normalize(glm::cross(forward, cam.up)), forward);
}

Opened open(const std::string& scene) {
    ecs::Registry reg;
    reg.set_resource<SceneHooks>(engine_scene_hooks());
    EXPECT_TRUE(load_scene(reg, scene).ok());
    editor::EditorState& state = editor::setup_editor(reg, viewport);
    Opened o{reg.get<Camera>(state.camera), 1e300};
    const glm::dvec3 up = cut_normal(o.camera);
    auto scan = [&](ecs::Entity e, const auto& cloud) {
        const glm::dmat4 model = model_matrix(reg.try_get<Transform>(e));
        for (const glm::vec3& q : cloud.positions) {
            const glm::dvec3 p = glm::dvec3(model * glm::dvec4(cloud.origin + glm::dvec3(q), 1.0));
            if (glm::dot(p - o.camera.target, up) > 0.0) o.lowest_part = std::min(o.lowest_part, p.y);
        }
    };
    reg.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& c) { scan(e, c); });
    reg.view<const GaussianCloud>().each([&](ecs::Entity e, const GaussianCloud& c) { scan(e, c); });
    return o;
}

struct Counts {
    std::size_t bottom = 0, bottom_changed = 0, top = 0, top_changed = 0;
    std::string first;
};

// Bottom: pixels showing a point more than `margin` below the part's lowest point; top: above the cut.
Counts compare(const render::FrameImage& plain, const render::FrameImage& edited, const Opened& o,
               double margin) {
    const Camera& cam = o.camera;
    const glm::dvec3 forward = glm::normalize(cam.target - cam.eye), up = cut_normal(cam);
    Counts c;
    for (int y = 0; y < plain.height; ++y)
        for (int x = 0; x < plain.width; ++x) {
            const std::size_t i = plain.index(x, y);
            if (!std::isfinite(plain.depth[i])) continue;
            const Ray ray = pixel_ray(cam, viewport, {x + 0.5, y + 0.5});
            const glm::dvec3 p =
                ray.origin + ray.direction * (double(plain.depth[i]) / glm::dot(ray.direction, forward));
            const bool same = plain.color[i] == edited.color[i] && plain.depth[i] == edited.depth[i];
            if (p.y < o.lowest_part - margin) {
                ++c.bottom;
                if (!same && c.bottom_changed++ == 0)
                    c.first = "pixel " + std::to_string(x) + "," + std::to_string(y) + " at y " +
                              std::to_string(p.y);
            } else if (glm::dot(p - cam.target, up) > margin) {
                ++c.top;
                c.top_changed += !same;
            }
        }
    return c;
}

// `margin`: a splat's reach (a surface splat's radius is 0.012, a Gaussian's 3 sigma about 0.05).
void separate_and_twist(const std::string& scene, const Dir& dir, double margin) {
    const fs::path plain_replay = dir.path / "plain.txt", plain = dir.path / "plain.exr",
                   edited = dir.path / "edited.exr";
    std::ofstream(plain_replay) << "1 set view.lattice 0\n";
    view(scene, plain_replay, plain);
    const std::string log = view(scene, session, edited);
    EXPECT_NE(log.find(".part.lattice' on '"), std::string::npos) << log;
    EXPECT_NE(log.find("twisted 729 control points by 45 degrees"), std::string::npos) << log;
    auto a = render::read_exr(plain);
    auto b = render::read_exr(edited);
    ASSERT_TRUE(a.ok()) << a.message();
    ASSERT_TRUE(b.ok()) << b.message();
    ASSERT_EQ(a->width, 1280);
    ASSERT_EQ(b->width, 1280);
    const Opened o = open(scene);
    EXPECT_LT(o.lowest_part, 0.0);
    for (double m : {0.0, 0.02, 0.05, 0.1}) {
        const Counts c = compare(*a, *b, o, m);
        std::printf("lowest %.3f margin %.2f: bottom %zu changed %zu; top %zu changed %zu %s\n",
                    o.lowest_part, m, c.bottom, c.bottom_changed, c.top, c.top_changed, c.first.c_str());
    }
    const Counts c = compare(*a, *b, o, margin);
    EXPECT_GT(c.bottom, 15000u);
    EXPECT_EQ(c.bottom_changed, 0u) << c.first;
    EXPECT_GT(c.top_changed, c.top / 2) << c.top_changed << " of " << c.top;
}

}  // namespace

TEST(PointView, SeparatedTopHalfTwistsWithItsOwnLatticeAndTheBottomStaysBitExact) {
    Dir dir("sphere");
    separate_and_twist("sphere", dir, 0.02);
}

TEST(PointView, SameOnTheGaussianSphere) {
    Dir dir("gaussians");
    const fs::path g = dir.path / "g.ply";
    const test::CliRun r = test::run("convert sphere " + g.string() + " --gaussians --splats 20000");
    ASSERT_EQ(r.code, 0) << r.out;
    separate_and_twist(g.string(), dir, 0.05);
}

// Weights from a selection and hidden points are kept by ctrl+s (the scene's _WEIGHT and _FLAGS): a box,
// shift+w, then h hides the same points, which all have weight 1.
TEST(PointView, SavedSceneKeepsPaintedWeightsAndHiddenPoints) {
    Dir dir("weights");
    const fs::path replay = dir.path / "weights.txt", saved = dir.path / "weights.glb",
                   exr = dir.path / "w.exr";
    std::ofstream(replay) << "1 key tab ctrl\n2 key t\n3 move 600 320\n4 press left\n5 move 680 400\n"
                             "6 release left\n8 set weight.radius 0.3\n9 set weight.falloff linear\n"
                             "10 key w shift\n12 key h\n14 key s ctrl\n";
    const test::CliRun r = test::run_headless(
        "view sphere --headless --size 1280x720 --quality preview --frames 18 "
        "--replay " +
        replay.string() + " --save " + saved.string() + " --out " + exr.string());
    ASSERT_EQ(r.code, 0) << r.out;
    ecs::Registry reg;
    reg.set_resource<SceneHooks>(engine_scene_hooks());
    ASSERT_TRUE(load_scene(reg, saved.string()).ok());
    std::size_t clouds = 0, hidden = 0, ones = 0, zeros = 0, between = 0, hidden_not_one = 0;
    reg.view<const SplatCloud>().each([&](ecs::Entity e, const SplatCloud& c) {
        ++clouds;
        const PointWeights* w = reg.try_get<PointWeights>(e);
        const PointFlags* f = reg.try_get<PointFlags>(e);
        ASSERT_TRUE(w && w->values.size() == c.positions.size());
        ASSERT_TRUE(f && f->bits.size() == c.positions.size());
        for (std::size_t i = 0; i < c.positions.size(); ++i) {
            const float v = w->values[i];
            ones += v == 1.0f, zeros += v == 0.0f, between += v > 0.0f && v < 1.0f;
            if (f->bits[i] & kPointHidden) ++hidden, hidden_not_one += v != 1.0f;
        }
    });
    EXPECT_EQ(clouds, 1u);
    EXPECT_GT(hidden, 500u);
    EXPECT_EQ(hidden_not_one, 0u);
    EXPECT_EQ(ones, hidden);
    EXPECT_GT(between, 500u);
    EXPECT_GT(zeros, 30000u);
}
