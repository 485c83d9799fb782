// The demo clip on the built-in sphere, deformed through the FFD system's CPU path: each case really
// changes the surface at its peak, the sphere is back at rest between cases, the local cases leave the
// lattice boundary fixed (no seam), and the global stretch is the documented 40% stretch along T (up).
#include <gtest/gtest.h>

#include <algorithm>

#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "systems/animation/components.h"
#include "systems/animation/evaluate.h"
#include "systems/animation/paper_demo.h"
#include "systems/animation/scene_extension.h"
#include "systems/ffd/deform.h"

namespace sffd {
namespace {

struct Sphere {
    ecs::Registry reg;
    ecs::Entity cloud = ecs::null_entity, lattice = ecs::null_entity;
    Sphere() {
        register_animation_scene_hooks(SceneHooks::in(reg));  // the built-in sphere gets its demo clip
        EXPECT_TRUE(load_scene(reg, "sphere").ok());
        reg.view<SplatCloud>().each([&](ecs::Entity e, SplatCloud&) { cloud = e; });
        reg.view<Lattice>().each([&](ecs::Entity e, Lattice&) { lattice = e; });
    }
    // Deformed world positions at frame k of the demo (24 fps).
    std::vector<glm::dvec3> at_frame(int k) {
        Lattice l = reg.get<Lattice>(lattice);
        l.current = evaluate_pose(reg.get<AnimationClip>(lattice), l, k / paper_demo_fps);
        const SplatCloud& c = reg.get<SplatCloud>(cloud);
        std::vector<glm::vec3> out(c.size());
        ffd::PointsIn in{c.positions.data(), nullptr, nullptr, nullptr, c.size(), c.origin};
        ffd::PointsOut o{out.data(), nullptr, nullptr, nullptr};
        EXPECT_TRUE(ffd::deform(l, in, o, ffd::Backend::fast).ok());
        std::vector<glm::dvec3> world(out.size());
        for (std::size_t i = 0; i < out.size(); ++i) world[i] = c.origin + glm::dvec3(out[i]);
        return world;
    }
    std::vector<glm::dvec3> rest() {
        const SplatCloud& c = reg.get<SplatCloud>(cloud);
        std::vector<glm::dvec3> world(c.size());
        for (std::size_t i = 0; i < c.size(); ++i) world[i] = c.origin + glm::dvec3(c.positions[i]);
        return world;
    }
};

double max_move(const std::vector<glm::dvec3>& a, const std::vector<glm::dvec3>& b) {
    double m = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, glm::length(a[i] - b[i]));
    return m;
}

TEST(PaperDemoDeform, EachCaseVisiblyDeformsTheSphereAndReturnsToRest) {
    Sphere s;
    ASSERT_TRUE(s.reg.valid(s.cloud) && s.reg.valid(s.lattice));
    ASSERT_TRUE(s.reg.has<AnimationClip>(s.lattice));
    const auto rest = s.rest();
    for (int k : {0, 24, 48, 72}) EXPECT_LT(max_move(s.at_frame(k), rest), 1e-5) << "frame " << k;
    // Unit sphere: every case moves some part of the surface by at least 0.1 at its peak.
    for (int k : {12, 36, 60, 84}) EXPECT_GT(max_move(s.at_frame(k), rest), 0.1) << "frame " << k;
}

TEST(PaperDemoDeform, GlobalStretchIsFortyPercentAlongT) {
    Sphere s;
    const Lattice& l = s.reg.get<Lattice>(s.lattice);
    const glm::dvec3 U = glm::normalize(l.axes[1]);  // up
    const glm::dvec3 mid = l.origin + 0.5 * l.axes[1];
    const auto rest = s.rest();
    const auto peak = s.at_frame(60);
    double worst = 0.0;
    for (std::size_t i = 0; i < rest.size(); ++i) {
        const glm::dvec3 expect = rest[i] + 0.4 * glm::dot(rest[i] - mid, U) * U;
        worst = std::max(worst, glm::length(peak[i] - expect));
    }
    EXPECT_LT(worst, 1e-5);
}

TEST(PaperDemoDeform, LocalCasesLeaveTheLatticeBoundaryFixed) {
    Sphere s;
    Lattice l = s.reg.get<Lattice>(s.lattice);
    const AnimationClip& clip = s.reg.get<AnimationClip>(s.lattice);
    for (int k : {6, 12, 30, 36}) {  // rising and peak of local stretch and local twist
        l.current = evaluate_pose(clip, l, k / paper_demo_fps);
        ASSERT_NE(l.current, l.rest);
        // Points on each of the six faces of the box do not move: no seam where the surface leaves it.
        double worst = 0.0;
        for (int face = 0; face < 6; ++face)
            for (double a = 0.05; a < 1.0; a += 0.15)
                for (double b = 0.05; b < 1.0; b += 0.15) {
                    glm::dvec3 stu;
                    stu[face / 2] = face % 2;
                    stu[(face / 2 + 1) % 3] = a;
                    stu[(face / 2 + 2) % 3] = b;
                    const glm::dvec3 x = l.origin + stu.x * l.axes[0] + stu.y * l.axes[1] + stu.z * l.axes[2];
                    worst = std::max(worst, glm::length(ffd::reference_point(l, x).position - x));
                }
        EXPECT_LT(worst, 1e-12) << "frame " << k;
    }
}

}  // namespace
}  // namespace sffd
