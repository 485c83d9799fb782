// The built-in demo clip: four cases in sequence, local cases pin the outer layer, rest between cases.
#include <gtest/gtest.h>

#include <numbers>

#include <glm/gtc/quaternion.hpp>

#include "systems/animation/evaluate.h"
#include "systems/animation/paper_demo.h"
#include "tests/systems/animation/test_util.h"

namespace sffd {
namespace {

const Lattice& demo_lattice() {
    static const Lattice l =
        test::make_lattice({10, 10, 10}, glm::dvec3(-1.0, -1.2, -0.9), glm::dvec3(2.0, 2.4, 1.8));
    return l;
}

double frame_time(int k) { return k / paper_demo_fps; }

bool on_outer_layer(const Lattice& l, std::size_t idx) {
    const int n1 = l.divisions.z + 1, m1 = l.divisions.y + 1;
    const int k = int(idx) % n1, j = (int(idx) / n1) % m1, i = int(idx) / (n1 * m1);
    return i == 0 || j == 0 || k == 0 || i == l.divisions.x || j == l.divisions.y || k == l.divisions.z;
}

TEST(PaperDemo, FourCasesOverNinetySixFrames) {
    const Lattice& l = demo_lattice();
    const AnimationClip clip = make_paper_demo_clip(l);
    EXPECT_EQ(clip.duration, 4.0);
    EXPECT_EQ(clip.mode, PlayMode::loop);
    ASSERT_TRUE(validate_clip(clip, l.rest.size()).ok());
    // Rest at every case boundary.
    for (int k : {0, 24, 48, 72}) EXPECT_EQ(evaluate_pose(clip, l, frame_time(k)), l.rest) << "frame " << k;
    // Each case moves something at its peak (frame 12 of its second) and only its own tracks are active.
    for (int c = 0; c < 4; ++c) {
        const auto pose = evaluate_pose(clip, l, frame_time(24 * c + 12));
        std::size_t moved = 0, moved_outer = 0;
        for (std::size_t i = 0; i < pose.size(); ++i)
            if (glm::length(pose[i] - l.rest[i]) > 1e-9) {
                ++moved;
                moved_outer += on_outer_layer(l, i);
            }
        EXPECT_GT(moved, 20u) << "case " << c;
        if (c < 2) EXPECT_EQ(moved_outer, 0u) << "local case " << c << " moved the pinned outer layer";
        else EXPECT_GT(moved_outer, 100u) << "global case " << c;
    }
}

TEST(PaperDemo, PeaksMatchTheDocumentedShapes) {
    const Lattice& l = demo_lattice();
    const AnimationClip clip = make_paper_demo_clip(l);
    const glm::dvec3 T = l.axes[1];  // up
    // Local stretch peak: the bound block moved by exactly 0.4 T, everything else at rest.
    {
        const auto pose = evaluate_pose(clip, l, frame_time(12));
        const auto& pts = clip.tracks[0].points;
        for (std::size_t i = 0; i < pose.size(); ++i) {
            const bool bound = std::find(pts.begin(), pts.end(), i) != pts.end();
            // (near, not equal: the compiler may fuse the reference's multiply-add)
            if (bound) EXPECT_NEAR(glm::length(pose[i] - (l.rest[i] + 0.4 * T)), 0.0, 1e-15);
            else EXPECT_EQ(pose[i], l.rest[i]);
        }
    }
    // Global stretch peak: an affine stretch along T about the middle plane, by 40%.
    {
        const auto pose = evaluate_pose(clip, l, frame_time(60));
        const double mid = l.origin.y + 0.5 * T.y;
        for (std::size_t i = 0; i < pose.size(); ++i) {
            EXPECT_NEAR(pose[i].y, mid + 1.4 * (l.rest[i].y - mid), 1e-12);
            EXPECT_EQ(pose[i].x, l.rest[i].x);
            EXPECT_EQ(pose[i].z, l.rest[i].z);
        }
    }
    // Global twist peak: layer j turned by (2j/m - 1) 90 degrees about the central T axis.
    {
        const auto pose = evaluate_pose(clip, l, frame_time(84));
        const glm::dvec3 centre = l.origin + 0.5 * (l.axes[0] + l.axes[1] + l.axes[2]);
        for (int j = 0; j <= 10; ++j) {
            const double deg = (2.0 * j / 10.0 - 1.0) * 90.0;
            const glm::dquat q = glm::angleAxis(deg * std::numbers::pi / 180.0, glm::dvec3(0, 1, 0));
            for (int i = 0; i <= 10; i += 5)
                for (int k = 0; k <= 10; k += 2) {
                    const std::size_t idx = l.index(i, j, k);
                    EXPECT_NEAR(glm::length(pose[idx] - (centre + q * (l.rest[idx] - centre))), 0.0, 1e-12);
                }
        }
    }
}

}  // namespace
}  // namespace sffd
