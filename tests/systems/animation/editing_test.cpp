// The editor-facing API: set/delete/list keys, tracks, play/pause/scrub.
#include <gtest/gtest.h>

#include "systems/animation/editing.h"

namespace sffd {
namespace {

TEST(AnimationEditing, SetKeyInsertsSortedAndReplacesAtSameTime) {
    AnimationTrack t;
    EXPECT_EQ(set_key(t, {1.0, {1, 0, 0}, Interpolation::linear, Easing::none}), 0u);
    EXPECT_EQ(set_key(t, {0.5, {2, 0, 0}, Interpolation::linear, Easing::none}), 0u);
    EXPECT_EQ(set_key(t, {2.0, {3, 0, 0}, Interpolation::linear, Easing::none}), 2u);
    ASSERT_EQ(t.keys.size(), 3u);
    EXPECT_EQ(t.keys[0].time, 0.5);
    EXPECT_EQ(t.keys[1].time, 1.0);
    // Replace the key at 1.0 (a time computed slightly differently still hits it); its time is kept.
    EXPECT_EQ(set_key(t, {1.0 + 1e-9, {9, 9, 9}, Interpolation::step, Easing::ease_in}), 1u);
    ASSERT_EQ(t.keys.size(), 3u);
    EXPECT_EQ(t.keys[1].time, 1.0);
    EXPECT_EQ(t.keys[1].value, glm::dvec3(9, 9, 9));
    EXPECT_EQ(t.keys[1].interpolation, Interpolation::step);
    EXPECT_EQ(t.keys[1].easing, Easing::ease_in);
}

TEST(AnimationEditing, DeleteAndFindKey) {
    AnimationTrack t;
    set_key(t, {0.0, {}, Interpolation::linear, Easing::none});
    set_key(t, {1.0, {}, Interpolation::linear, Easing::none});
    EXPECT_EQ(find_key(t, 1.0), std::optional<std::size_t>(1));
    EXPECT_FALSE(find_key(t, 0.5).has_value());
    EXPECT_FALSE(delete_key(t, 0.5));
    EXPECT_TRUE(delete_key(t, 0.0));
    ASSERT_EQ(t.keys.size(), 1u);
    EXPECT_EQ(t.keys[0].time, 1.0);
}

TEST(AnimationEditing, ListKeysSortedByTimeThenTrack) {
    AnimationClip clip;
    const std::size_t a = add_stretch_track(clip, "a", {0});
    const std::size_t b = add_twist_track(clip, "b", {1}, {0, 1, 0});
    EXPECT_EQ(clip.tracks[b].kind, TrackKind::twist);
    EXPECT_FALSE(clip.tracks[b].has_pivot);
    set_key(clip.tracks[a], {1.0, {}, Interpolation::linear, Easing::none});
    set_key(clip.tracks[a], {0.0, {}, Interpolation::linear, Easing::none});
    set_key(clip.tracks[b], {0.5, {}, Interpolation::linear, Easing::none});
    set_key(clip.tracks[b], {1.0, {}, Interpolation::linear, Easing::none});
    const std::vector<KeyRef> keys = list_keys(clip);
    ASSERT_EQ(keys.size(), 4u);
    EXPECT_EQ(keys[0].time, 0.0);
    EXPECT_EQ(keys[1].track, b);
    EXPECT_EQ(keys[1].time, 0.5);
    EXPECT_EQ(keys[2].track, a);
    EXPECT_EQ(keys[2].key, 1u);
    EXPECT_EQ(keys[3].track, b);
    EXPECT_EQ(keys[3].key, 1u);
}

TEST(AnimationEditing, PlayPauseScrubMoveTheAnchor) {
    AnimationState s;
    s.raw_time = 1.25;  // as written by the system for the last frame
    pause(s);
    EXPECT_FALSE(s.playing);
    EXPECT_EQ(s.anchor_time, 1.25);
    scrub(s, 0.5);
    EXPECT_EQ(s.anchor_time, 0.5);
    EXPECT_FALSE(s.rebase);  // paused: no clock anchor needed
    play(s);
    EXPECT_TRUE(s.playing);
    EXPECT_TRUE(s.rebase);
    EXPECT_EQ(s.anchor_time, 0.5);
    // Scrub then pause before any frame ran: the scrubbed time wins over the stale raw_time.
    scrub(s, 0.75);
    pause(s);
    EXPECT_EQ(s.anchor_time, 0.75);
}

}  // namespace
}  // namespace sffd
