// animation_system over a registry: change stamps, determinism of sequences, playback controls.
#include <gtest/gtest.h>

#include "runtime/app/clock.h"
#include "runtime/core/log.h"
#include "systems/animation/animation_system.h"
#include "systems/animation/editing.h"
#include "systems/animation/evaluate.h"
#include "systems/animation/paper_demo.h"
#include "tests/systems/animation/test_util.h"

namespace sffd {
namespace {

AnimationClip ramp_clip(PlayMode mode) {
    AnimationClip clip;
    clip.duration = 1.0;
    clip.mode = mode;
    const std::size_t s = add_stretch_track(clip, "s", {13});
    set_key(clip.tracks[s], {0.0, {0, 0, 0}, Interpolation::linear, Easing::none});
    set_key(clip.tracks[s], {1.0, {1, 0, 0}, Interpolation::linear, Easing::none});
    return clip;
}

TEST(AnimationSystem, PatchesTheLatticeOnlyWhenThePoseChanges) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<Lattice>(e, test::make_lattice({2, 2, 2}));
    attach_clip(reg, e, ramp_clip(PlayMode::once));
    const glm::dvec3 rest13 = reg.get<Lattice>(e).rest[13];

    animation_system(reg, {0, 0.0, 0.0});
    const std::uint64_t v0 = reg.version<Lattice>(e);
    animation_system(reg, {1, 0.0, 0.0});  // same time: same pose, no stamp
    EXPECT_EQ(reg.version<Lattice>(e), v0);
    animation_system(reg, {2, 0.25, 0.25});
    const std::uint64_t v1 = reg.version<Lattice>(e);
    EXPECT_GT(v1, v0);
    EXPECT_EQ(reg.get<Lattice>(e).current[13], rest13 + glm::dvec3(0.25, 0, 0));
    EXPECT_EQ(reg.get<AnimationState>(e).time, 0.25);
    animation_system(reg, {3, 5.0, 0.0});  // once: clamps at 1.0
    animation_system(reg, {4, 6.0, 0.0});  // still 1.0: no stamp
    const std::uint64_t v2 = reg.version<Lattice>(e);
    EXPECT_GT(v2, v1);
    animation_system(reg, {5, 7.0, 0.0});
    EXPECT_EQ(reg.version<Lattice>(e), v2);
    EXPECT_EQ(reg.get<Lattice>(e).current[13], rest13 + glm::dvec3(1, 0, 0));
}

// An un-keyed edit is shown at its own clip time only, whatever frames came before (frame k alone is
// frame k of a sequence), and comes back whenever the clip reaches that time again.
TEST(AnimationSystem, AnUnkeyedEditShowsAtItsClipTimeOnly) {
    const auto run = [](const std::vector<double>& times) {
        ecs::Registry reg;
        const ecs::Entity e = reg.create();
        reg.emplace<Lattice>(e, test::make_lattice({2, 2, 2}));
        attach_clip(reg, e, ramp_clip(PlayMode::loop));
        UnkeyedEdit edit{0.25, reg.get<Lattice>(e).rest};
        edit.points[4] += glm::dvec3(0, 0, 0.5);
        reg.emplace<UnkeyedEdit>(e, edit);
        std::vector<std::vector<glm::dvec3>> poses;
        std::uint64_t frame = 0;
        for (double t : times) {
            animation_system(reg, {frame++, t, 0.0});
            poses.push_back(reg.get<Lattice>(e).current);
        }
        return std::make_pair(poses, edit.points);
    };
    const auto [sequence, edited] = run({0.0, 0.25, 0.5, 1.25});
    const auto [alone, ignored] = run({1.25});
    const glm::dvec3 rest4 = test::make_lattice({2, 2, 2}).rest[4];
    EXPECT_EQ(sequence[0][4], rest4) << "another time: the clip's pose";
    EXPECT_EQ(sequence[1], edited) << "its time: the edit";
    EXPECT_EQ(sequence[2][4], rest4);
    EXPECT_EQ(sequence[3], edited) << "the loop's next pass of 0.25 s shows it again";
    EXPECT_EQ(alone[0], sequence[3]) << "the same alone as in the sequence";
}

// The animation is the one writer of an animated lattice's current: a write by anyone else is replaced by
// the clip's pose in the next animation phase (edits go through keys or the un-keyed edit), while paused too.
TEST(AnimationSystem, KeyEditsShowWhilePausedAndOtherWritesOfThePoseAreReplaced) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<Lattice>(e, test::make_lattice({2, 2, 2}));
    attach_clip(reg, e, ramp_clip(PlayMode::loop));
    animation_system(reg, {0, 0.5, 0.0});
    pause(reg.patch<AnimationState>(e));
    animation_system(reg, {1, 0.6, 0.1});
    const glm::dvec3 rest13 = reg.get<Lattice>(e).rest[13];
    EXPECT_EQ(reg.get<Lattice>(e).current[13], rest13 + glm::dvec3(0.5, 0, 0));
    // A write of another point straight into current does not survive the next frame, paused as it is...
    const std::uint64_t before = reg.version<Lattice>(e);
    reg.patch<Lattice>(e).current[0] += glm::dvec3(0.1);
    animation_system(reg, {2, 0.7, 0.1});
    EXPECT_EQ(reg.get<Lattice>(e).current[0], reg.get<Lattice>(e).rest[0]);
    EXPECT_EQ(reg.get<Lattice>(e).current[13], rest13 + glm::dvec3(0.5, 0, 0));
    EXPECT_GT(reg.version<Lattice>(e), before + 1) << "the pose was written back";
    const std::uint64_t restored = reg.version<Lattice>(e);
    animation_system(reg, {3, 0.75, 0.05});
    EXPECT_EQ(reg.version<Lattice>(e), restored) << "and then left alone";
    // ...the same edit as an un-keyed edit at the paused time is shown (and the clip's pose elsewhere).
    UnkeyedEdit edit{0.5, reg.get<Lattice>(e).current};
    edit.points[0] += glm::dvec3(0.1);
    reg.emplace<UnkeyedEdit>(e, edit);
    animation_system(reg, {4, 0.8, 0.05});
    EXPECT_EQ(reg.get<Lattice>(e).current, edit.points);
    reg.remove<UnkeyedEdit>(e);
    // ...a key edit changes the pose and is applied at once (from the rest lattice).
    set_key(reg.patch<AnimationClip>(e).tracks[0], {1.0, {3, 0, 0}, Interpolation::linear, Easing::none});
    animation_system(reg, {5, 0.85, 0.05});
    EXPECT_EQ(reg.get<Lattice>(e).current[13], rest13 + glm::dvec3(1.5, 0, 0));
    EXPECT_EQ(reg.get<Lattice>(e).current[0], reg.get<Lattice>(e).rest[0]);
}

TEST(AnimationSystem, ScrubAndPlayContinueFromTheScrubbedTime) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<Lattice>(e, test::make_lattice({2, 2, 2}));
    attach_clip(reg, e, ramp_clip(PlayMode::loop));
    animation_system(reg, {0, 10.0, 0.0});
    EXPECT_EQ(reg.get<AnimationState>(e).time, 0.0);  // 10 s loops to 0
    scrub(reg.patch<AnimationState>(e), 0.25);        // while playing
    animation_system(reg, {1, 10.5, 0.5});
    EXPECT_EQ(reg.get<AnimationState>(e).time, 0.25);
    animation_system(reg, {2, 10.75, 0.25});
    EXPECT_EQ(reg.get<AnimationState>(e).time, 0.5);
    pause(reg.patch<AnimationState>(e));
    animation_system(reg, {3, 11.0, 0.25});
    EXPECT_EQ(reg.get<AnimationState>(e).time, 0.5);
    scrub(reg.patch<AnimationState>(e), 0.125);
    animation_system(reg, {4, 11.5, 0.5});
    EXPECT_EQ(reg.get<AnimationState>(e).time, 0.125);
    play(reg.patch<AnimationState>(e));
    animation_system(reg, {5, 12.0, 0.5});
    EXPECT_EQ(reg.get<AnimationState>(e).time, 0.125);
    animation_system(reg, {6, 12.25, 0.25});
    EXPECT_EQ(reg.get<AnimationState>(e).time, 0.375);
    set_speed(reg.patch<AnimationState>(e), 2.0);  // re-anchors: no jump
    animation_system(reg, {7, 12.5, 0.25});
    EXPECT_EQ(reg.get<AnimationState>(e).time, 0.375);
    animation_system(reg, {8, 12.75, 0.25});
    EXPECT_EQ(reg.get<AnimationState>(e).time, 0.875);
}

// Frame k of a fixed-step sequence == frame k evaluated alone in a fresh registry, bit for bit.
TEST(AnimationSystem, SequencesAreDeterministic) {
    const Lattice lattice =
        test::make_lattice({10, 10, 10}, glm::dvec3(-1.3, 0.2, 5.0), glm::dvec3(2.6, 2.1, 3.3));
    ClockSettings settings;
    settings.fixed_dt = 1.0 / paper_demo_fps;

    ecs::Registry seq;
    const ecs::Entity e = seq.create();
    seq.emplace<Lattice>(e, lattice);
    attach_clip(seq, e, make_paper_demo_clip(lattice));
    Clock clock(settings);
    std::vector<std::vector<glm::dvec3>> frames;
    for (int k = 0; k < 2 * paper_demo_frames + 7; ++k) {  // past one loop
        const FrameContext ctx = clock.tick(0.0);
        animation_system(seq, ctx);
        frames.push_back(seq.get<Lattice>(e).current);
    }
    for (int k : {0, 1, 13, 30, 47, 60, 83, 95, 96, 150, 198}) {
        ecs::Registry alone;
        const ecs::Entity a = alone.create();
        alone.emplace<Lattice>(a, lattice);
        attach_clip(alone, a, make_paper_demo_clip(lattice));
        Clock c(settings);
        c.seek(k / paper_demo_fps);
        FrameContext ctx = c.tick(0.0);
        ASSERT_EQ(ctx.time, double(k) * settings.fixed_dt);
        animation_system(alone, ctx);
        const auto& got = alone.get<Lattice>(a).current;
        ASSERT_EQ(got.size(), frames[std::size_t(k)].size());
        for (std::size_t i = 0; i < got.size(); ++i)
            ASSERT_TRUE(test::same_bits(got[i], frames[std::size_t(k)][i]))
                << "frame " << k << " point " << i;
    }
    // And the loop really repeats: frame k and k+96 are the same pose (to rounding: (k+96)/24 - 4 is not
    // bit-identical to k/24).
    for (int k : {5, 40, 70, 90})
        for (std::size_t i = 0; i < frames[0].size(); ++i)
            ASSERT_NEAR(
                glm::length(frames[std::size_t(k)][i] - frames[std::size_t(k + paper_demo_frames)][i]), 0.0,
                1e-12);
}

TEST(AnimationSystem, InvalidClipIsReportedOnceAndNotApplied) {
    ecs::Registry reg;
    const ecs::Entity e = reg.create();
    reg.emplace<Lattice>(e, test::make_lattice({1, 1, 1}));
    AnimationClip clip = ramp_clip(PlayMode::loop);  // binds point 13 of a 2x2x2 lattice: out of range
    clip.name = "bad";
    attach_clip(reg, e, clip);
    log::ScopedLogCapture capture;
    animation_system(reg, {0, 0.5, 0.0});
    animation_system(reg, {1, 0.6, 0.1});
    EXPECT_EQ(capture.entries().size(), 1u);
    EXPECT_TRUE(capture.contains(
        "animation_system(): clip 'bad': tracks[0]: control point 13 out of range (lattice has 8)"));
    EXPECT_EQ(reg.get<Lattice>(e).current, reg.get<Lattice>(e).rest);
    EXPECT_FALSE(reg.get<AnimationState>(e).error.empty());
}

}  // namespace
}  // namespace sffd
