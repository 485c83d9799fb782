// `splatffd pick` end to end: runs the built binary on the built-in sphere and checks its JSON against
// the scene itself (a control point's projection, the sphere's surface), plus misses and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "runtime/assets/scene.h"
#include "runtime/ecs/registry.h"
#include "systems/ffd/components.h"
#include "systems/gaussian/capture_up.h"
#include "systems/gaussian/components.h"
#include "runtime/assets/formats/gaussian/gaussian_io.h"
#include "systems/gaussian/gaussian_scene.h"
#include "systems/picking/gaussian_source.h"
#include "systems/picking/screen_view.h"
#include "systems/picking/world_space.h"
#include "systems/splat_render/camera_math.h"

namespace sffd::picking {
namespace {

struct CliRun {
    int exit_code = -1;
    std::string out;  // stdout and stderr
};

CliRun run_pick(const std::string& global, const std::string& args) {
    const std::string cmd =
        std::string(SFFD_BINARY_DIR) + "/tools/splatffd " + global + " pick " + args + " 2>&1";
    CliRun r;
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return r;
    std::array<char, 4096> buf{};
    while (std::fgets(buf.data(), int(buf.size()), p)) r.out += buf.data();
    const int status = pclose(p);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}
CliRun run_pick(const std::string& args) { return run_pick("", args); }

struct Sphere {
    ecs::Registry reg;
    ecs::Entity lattice;
    ScreenView view;
    Sphere() {
        reg.set_resource<SceneHooks>();  // assets' own formats only
        const Status st = load_scene(reg, "sphere");
        EXPECT_TRUE(st) << (st ? "" : st.message());
        reg.view<const Lattice>().each([&](ecs::Entity e, const Lattice&) { lattice = e; });
        view = make_screen_view(render::scene_camera(reg, 320.0 / 240.0), {320, 240});
    }
};

TEST(PickCli, ControlPointAtItsProjectedPixel) {
    Sphere s;
    const std::vector<glm::dvec3> points = control_points_world(s.reg, s.lattice);
    const Lattice& l = s.reg.get<Lattice>(s.lattice);
    // The on-screen control point whose projection is farthest from every other one; pick at the pixel it
    // falls in, in x-ray mode (so whether the sphere hides it does not matter).
    std::vector<glm::dvec2> screen(points.size(), glm::dvec2(-1e9));
    for (std::size_t i = 0; i < points.size(); ++i)
        if (const auto q = project(s.view, points[i])) screen[i] = q->screen;
    std::size_t target = 0;
    double best = -1.0;
    for (std::size_t i = 0; i < points.size(); ++i) {
        if (screen[i].x < 0 || screen[i].y < 0 || screen[i].x >= 320 || screen[i].y >= 240) continue;
        double nearest = 1e9;
        for (std::size_t k = 0; k < points.size(); ++k)
            if (k != i) nearest = std::min(nearest, glm::length(screen[k] - screen[i]));
        if (nearest > best) best = nearest, target = i;
    }
    ASSERT_GT(best, 4.0) << "control points too crowded on screen for an unambiguous pick";
    const glm::ivec2 pixel(glm::floor(screen[target]));
    const CliRun r = run_pick("sphere --xray --size 320x240 --at " + std::to_string(pixel.x) + "," +
                              std::to_string(pixel.y));
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_TRUE(j["hit"].get<bool>());
    EXPECT_EQ(j["kind"], "control_point");
    EXPECT_EQ(j["entity"].get<std::uint32_t>(), s.lattice.index);
    EXPECT_EQ(j["index"].get<std::size_t>(), target);
    const int n1 = l.divisions.z + 1, m1 = l.divisions.y + 1;
    EXPECT_EQ(j["lattice_ijk"],
              nlohmann::json::array({int(target) / (m1 * n1), (int(target) / n1) % m1, int(target) % n1}));
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(j["position"][a].get<double>(), points[target][a], 1e-9);
    EXPECT_NEAR(j["distance"].get<double>(), glm::length(points[target] - s.view.camera.eye), 1e-9);
}

TEST(PickCli, SurfaceHitLiesOnTheUnitSphereOnThePixelRay) {
    Sphere s;
    const std::vector<glm::dvec3> points = control_points_world(s.reg, s.lattice);
    const auto c = project(s.view, glm::dvec3(0.0));
    ASSERT_TRUE(c);
    // A pixel near the sphere's centre whose ray passes no control point closer than 0.05 (their pick
    // spheres are 0.018): then only the surface can be hit (tolerance 0 turns off the screen rule).
    glm::ivec2 pixel(-1);
    Ray ray;
    for (int d = 0; d < 40 && pixel.x < 0; ++d) {
        const glm::ivec2 cand(glm::floor(c->screen + glm::dvec2(7.0 + d, 5.0 + d / 2)));
        ray = ray_through(s.view, glm::dvec2(cand) + 0.5);
        bool clear = true;
        for (const glm::dvec3& p : points)
            clear = clear && glm::length(glm::cross(p - ray.origin, ray.direction)) > 0.05;
        if (clear) pixel = cand;
    }
    ASSERT_GE(pixel.x, 0) << "no clear pixel found";
    const CliRun r = run_pick("sphere --size 320x240 --tolerance 0 --at " + std::to_string(pixel.x) + "," +
                              std::to_string(pixel.y));
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const auto j = nlohmann::json::parse(r.out);
    ASSERT_TRUE(j["hit"].get<bool>()) << r.out;
    ASSERT_EQ(j["kind"], "surface");
    const glm::dvec3 p{j["position"][0].get<double>(), j["position"][1].get<double>(),
                       j["position"][2].get<double>()};
    EXPECT_NEAR(glm::length(p), 1.0, 0.01);  // on the unit sphere, up to the splats' flatness
    EXPECT_LT(j["index"].get<std::size_t>(), 59650u);
    EXPECT_NEAR(glm::length(glm::cross(p - ray.origin, ray.direction)), 0.0, 1e-5);  // on the pixel's ray
    EXPECT_NEAR(j["distance"].get<double>(), glm::length(p - ray.origin), 1e-5);
    EXPECT_LT(glm::dot(p, ray.direction), 0.0);  // the front side, facing the camera
}

TEST(PickCli, MissIsHitFalseAndExitZero) {
    const CliRun r = run_pick("sphere --size 320x240 --at 0,0");
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_EQ(nlohmann::json::parse(r.out), nlohmann::json::parse(R"({"hit":false,"pixel":[0,0]})"));
}

TEST(PickCli, BadInputExitCodesAndMessages) {
    CliRun r = run_pick("/nonexistent/scene.ply --at 1,1");
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_NE(r.out.find("/nonexistent/scene.ply"), std::string::npos) << r.out;
    r = run_pick("sphere");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.out.find("--at X,Y is required"), std::string::npos) << r.out;
    r = run_pick("sphere --at 3");
    EXPECT_EQ(r.exit_code, 2);
    r = run_pick("sphere --at 1,1 --size 0x10");
    EXPECT_EQ(r.exit_code, 2);
    r = run_pick("sphere --at 400,10 --size 320x240");
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.out.find("outside the 320x240 viewport"), std::string::npos) << r.out;
}

// A 3DGS PLY of four Gaussians written here: picked through `splatffd --up y pick FILE`, seen from the
// camera `render` frames a Gaussian file with (load_scene's default view of it). Written y up, and read
// so (--up y: not turned, systems/gaussian/capture_up.h), so the reference below works in the file's
// coordinates.
struct GaussianFile {
    std::filesystem::path path;
    GaussianCloud cloud;
    ScreenView view;
    GaussianFile() {
        path = std::filesystem::temp_directory_path() /
               ("sffd_pick_gauss_" + std::to_string(::getpid()) + ".ply");
        const glm::vec3 centres[3] = {{-1, 0, 0}, {0.5f, 0.2f, 0.3f}, {1, 0, -0.5f}};
        for (int i = 0; i < 3; ++i) {
            cloud.positions.push_back(centres[i]);
            cloud.scales.emplace_back(0.15f, 0.1f, 0.05f * float(i + 1));
            cloud.rotations.push_back(glm::normalize(glm::quat(1.0f, 0.3f * float(i), 0.2f, -0.1f)));
            cloud.opacities.push_back(0.3f + 0.3f * float(i));
            for (int c = 0; c < 3; ++c) cloud.sh.push_back(0.2f);
        }
        // A big faint floater just in front of Gaussian 0 (inside the bounding box below): the first
        // ellipsoid on Gaussian 0's pixel, but Gaussian 0 contributes more.
        cloud.positions.emplace_back(-1.0f, 0.0f, 0.3f);
        cloud.scales.emplace_back(0.3f, 0.3f, 0.3f);
        cloud.rotations.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
        cloud.opacities.push_back(0.08f);
        for (int c = 0; c < 3; ++c) cloud.sh.push_back(0.2f);
        EXPECT_TRUE(gaussian::write_ply(path, cloud));
        // The camera `render` and `pick` see the file through: load_scene's default view of a Gaussian file
        // (the Gaussian scene hooks, which splatffd's main registers).
        gaussian::set_capture_up(gaussian::CaptureUp::plus_y);
        ecs::Registry reg;
        gaussian::register_gaussian_scene_hooks(SceneHooks::in(reg));
        const Status st = load_scene(reg, path.string());
        gaussian::set_capture_up(gaussian::CaptureUp::minus_y);
        EXPECT_TRUE(st) << (st ? "" : st.message());
        view = make_screen_view(render::scene_camera(reg, 320.0 / 240.0), {320, 240});
    }
    ~GaussianFile() { std::filesystem::remove(path); }
};

// Independent reference for one Gaussian and a ray, from Σ⁻¹ = (R S² Rᵀ)⁻¹: the entry distance into
// (p − c)ᵀ Σ⁻¹ (p − c) = k(α)² (−1 on a miss), the centre's depth along the ray, and the largest alpha
// along the line, min(0.99, α exp(−m²/2)) with m² = wᵀΣ⁻¹w − (wᵀΣ⁻¹d)² / dᵀΣ⁻¹d.
struct RayGaussian {
    double entry = -1.0, depth = 0.0, alpha = 0.0;
};
RayGaussian ray_gaussian(const GaussianCloud& g, std::size_t i, const Ray& ray) {
    const glm::dmat3 R = glm::mat3_cast(glm::dquat(g.rotations[i]));
    const glm::dvec3 s(g.scales[i]);
    const glm::dmat3 inv =
        glm::inverse(R * glm::dmat3(s.x * s.x, 0, 0, 0, s.y * s.y, 0, 0, 0, s.z * s.z) * glm::transpose(R));
    const double k = gaussian_pick_sigmas(double(g.opacities[i]));
    const glm::dvec3 w = ray.origin - glm::dvec3(g.positions[i]), d = glm::normalize(ray.direction);
    const double a = glm::dot(d, inv * d), b = glm::dot(w, inv * d), c = glm::dot(w, inv * w) - k * k;
    RayGaussian r;
    r.depth = -glm::dot(w, d);
    r.alpha = std::min(0.99, double(g.opacities[i]) * std::exp(-0.5 * (glm::dot(w, inv * w) - b * b / a)));
    if (b * b - a * c >= 0.0) r.entry = (-b - std::sqrt(b * b - a * c)) / a;
    return r;
}

// The Gaussian picked along `ray`: nearest entry (first_ellipsoid) or largest blending weight α T in
// centre-depth order (most_visible). 99 when none.
std::uint32_t expected_pick(const GaussianCloud& g, const Ray& ray, bool first, double& t) {
    std::vector<std::pair<RayGaussian, std::uint32_t>> hits;
    for (std::uint32_t i = 0; i < g.size(); ++i)
        if (const RayGaussian r = ray_gaussian(g, i, ray); r.entry >= 0.0) hits.emplace_back(r, i);
    std::uint32_t best = 99;
    t = std::numeric_limits<double>::infinity();
    if (first) {
        for (const auto& [r, i] : hits)
            if (r.entry < t) t = r.entry, best = i;
        return best;
    }
    std::sort(hits.begin(), hits.end(),
              [](const auto& a, const auto& b) { return a.first.depth < b.first.depth; });
    double T = 1.0, best_w = 0.0;
    for (const auto& [r, i] : hits) {
        if (r.alpha * T > best_w) best_w = r.alpha * T, best = i, t = r.entry;
        T *= 1.0 - r.alpha;
    }
    return best;
}

TEST(PickCli, GaussianFileHitsTheGaussianOnThePixelRay) {
    GaussianFile f;
    int differ = 0;  // pixels where the two rules pick different Gaussians (the file is built to have one)
    for (const bool first : {false, true}) {
        for (std::uint32_t target = 0; target < 3; ++target) {
            const auto px = project(f.view, glm::dvec3(f.cloud.positions[target]));
            ASSERT_TRUE(px.has_value());
            const glm::ivec2 pixel(glm::floor(px->screen));
            const CliRun r =
                run_pick("--up y", f.path.string() + " --size 320x240 --at " + std::to_string(pixel.x) + "," +
                                       std::to_string(pixel.y) + (first ? " --first-gaussian" : ""));
            ASSERT_EQ(r.exit_code, 0) << r.out;
            const auto j = nlohmann::json::parse(r.out);
            ASSERT_TRUE(j["hit"].get<bool>()) << r.out;
            EXPECT_EQ(j["kind"], "gaussian");
            EXPECT_EQ(j["name"], f.path.stem().string());
            const Ray ray = ray_through(f.view, glm::dvec2(pixel) + 0.5);
            double t = 0.0, t_other = 0.0;
            const std::uint32_t expect = expected_pick(f.cloud, ray, first, t);
            differ += expect != expected_pick(f.cloud, ray, !first, t_other);
            ASSERT_LT(expect, 4u);
            EXPECT_EQ(j["index"].get<std::uint32_t>(), expect)
                << "pixel of Gaussian " << target << (first ? ", first" : "");
            EXPECT_NEAR(j["distance"].get<double>(), t, 1e-4);
            EXPECT_NEAR(j["opacity"].get<double>(), double(f.cloud.opacities[expect]), 1e-6);
            const glm::dvec3 p{j["position"][0].get<double>(), j["position"][1].get<double>(),
                               j["position"][2].get<double>()};
            EXPECT_NEAR(glm::length(p - (ray.origin + t * glm::normalize(ray.direction))), 0.0, 1e-4);
        }
    }
    EXPECT_GT(differ, 0) << "the scene no longer tells the two rules apart";
    // A corner pixel sees nothing.
    const CliRun miss = run_pick("--up y", f.path.string() + " --size 320x240 --at 0,0");
    ASSERT_EQ(miss.exit_code, 0) << miss.out;
    EXPECT_FALSE(nlohmann::json::parse(miss.out)["hit"].get<bool>());
}

TEST(PickCli, BadGaussianFileNamesTheFile) {
    const auto path =
        std::filesystem::temp_directory_path() / ("sffd_pick_bad_" + std::to_string(::getpid()) + ".splat");
    {
        FILE* f = std::fopen(path.string().c_str(), "wb");
        ASSERT_NE(f, nullptr);
        std::fputs("not 32 bytes", f);
        std::fclose(f);
    }
    const CliRun r = run_pick(path.string() + " --at 1,1");
    std::filesystem::remove(path);
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_NE(r.out.find(path.string() + ":"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace sffd::picking
