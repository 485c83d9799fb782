// A Gaussian file and the scene `convert IN OUT.glb --lattice fit` makes from it open with the same
// automatic camera: the same Camera once loaded, and the same image from `splatffd render`.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

#include "runtime/assets/scene.h"
#include "runtime/scene/camera.h"
#include "runtime/scene/components.h"
#include "systems/gaussian/components.h"
#include "systems/gaussian/gaussian_scene.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_scene.h"
#include "tests/test_util/gl_required.h"
#include "tests/test_util/run_tool.h"

namespace {

namespace fs = std::filesystem;
using namespace sffd;

fs::path temp(const std::string& name) {
    const fs::path d = fs::temp_directory_path() / ("sffd_scene_camera_" + std::to_string(getpid()));
    fs::create_directories(d);
    return d / name;
}

// Exit code and stdout + stderr of `splatffd ARGS`.
std::pair<int, std::string> run(const std::string& args) {
    const test::CliRun r = test::run(args);
    return {r.code, r.out};
}

// An off-centre, lopsided cloud (a half shell around (0.5, 2, -1), y down as captures are stored), so the
// capture's up turn and the bounds decide where the camera looks.
GaussianCloud lopsided(std::size_t n) {
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(-1, 1);
    GaussianCloud g;
    while (g.size() < n) {
        glm::vec3 p(u(rng), u(rng), u(rng));
        if (glm::length(p) < 0.1f || glm::length(p) > 1.0f || p.y < -0.2f) continue;
        g.positions.push_back(glm::vec3(0.5f, 2.0f, -1.0f) +
                              0.7f * glm::normalize(p) * glm::vec3(1.5f, 1, 1));
        g.scales.emplace_back(0.05f, 0.04f, 0.03f);
        g.rotations.emplace_back(1, 0, 0, 0);
        g.opacities.push_back(0.9f);
        g.sh.insert(g.sh.end(), {0.8f, 0.2f * u(rng), -0.3f});
    }
    return g;
}

Camera loaded_camera(const fs::path& p) {
    ecs::Registry r;
    gaussian::register_gaussian_scene_hooks(SceneHooks::in(r));  // the fitted scene holds Gaussians
    const Status s = load_scene(r, p.string());
    EXPECT_TRUE(s) << s.message();
    EXPECT_EQ(r.count<Camera>(), 1u) << p;
    Camera c;
    r.view<const Camera>().each([&](const Camera& cam) { c = cam; });
    return c;
}

TEST(SceneCamera, CaptureAndItsFittedSceneOpenWithTheSameCamera) {
    const fs::path g = temp("g.ply"), scene = temp("s.glb");
    const GaussianCloud cloud = lopsided(3000);
    ASSERT_TRUE(gaussian::write_ply(g, cloud));
    auto [code, out] = run("convert " + g.string() + " " + scene.string() + " --lattice fit");
    ASSERT_EQ(code, 0) << out;

    const Camera a = loaded_camera(g), b = loaded_camera(scene);
    EXPECT_EQ(a.eye, b.eye);
    EXPECT_EQ(a.target, b.target);
    EXPECT_EQ(a.up, b.up);
    EXPECT_EQ(a.fov_y_degrees, b.fov_y_degrees);
    EXPECT_EQ(a.near_plane, b.near_plane);
    EXPECT_EQ(a.far_plane, b.far_plane);
    // Aimed at the cloud as shown (turned upright: y and z negated), not at its stored coordinates.
    glm::dvec3 lo(1e30), hi(-1e30);
    for (const glm::vec3& p : cloud.positions) {
        const glm::dvec3 w(p.x, -p.y, -p.z);
        lo = glm::min(lo, w), hi = glm::max(hi, w);
    }
    EXPECT_LT(glm::length(a.target - 0.5 * (lo + hi)), 0.2)
        << a.target.x << " " << a.target.y << " " << a.target.z;

    std::tie(code, out) = run("render " + g.string() + " --size 160x120 --out " + temp("A").string());
    if (code != 0 && out.find("EGL") != std::string::npos) SFFD_GL_UNAVAILABLE(out);
    ASSERT_EQ(code, 0) << out;
    std::tie(code, out) = run("render " + scene.string() + " --size 160x120 --out " + temp("B").string());
    ASSERT_EQ(code, 0) << out;
    std::tie(code, out) = run("compare " + (temp("A") / "frame_0000.exr").string() + " " +
                              (temp("B") / "frame_0000.exr").string());
    ASSERT_EQ(code, 0) << out;
    const std::size_t at = out.find("psnr_db=");
    ASSERT_NE(at, std::string::npos) << out;
    const std::string psnr = out.substr(at + 8, out.find(' ', at) - at - 8);
    EXPECT_TRUE(psnr == "inf" || std::stod(psnr) >= 40.0) << out;
}

}  // namespace
