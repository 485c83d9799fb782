// The overlay's CPU side (which control points show as selected / pinned / inside the object's box) and
// the timeline's set key / delete key through the editor (undoable), without a window.
#include <gtest/gtest.h>

#include <algorithm>

#include "runtime/scene/components.h"
#include "systems/animation/components.h"
#include "systems/animation/editing.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/lattice_overlay.h"
#include "systems/editor/selection_edit.h"
#include "systems/ffd/components.h"

using namespace sffd;
using namespace sffd::editor;

namespace {
struct Scene {
    ecs::Registry reg;
    ecs::Entity lattice;
    EditorState* state;
    Scene() {
        lattice = reg.create();
        reg.emplace<Lattice>(
            lattice,
            make_lattice({-1, -1, -1}, {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)},
                         {4, 4, 4}));
        // A cloud whose box is [-0.6, 0.6]^3: the 27 control points at -0.5, 0, 0.5 per axis are inside.
        const ecs::Entity cloud = reg.create();
        SplatCloud& c = reg.emplace<SplatCloud>(cloud);
        c.positions = {glm::vec3(-0.6f), glm::vec3(0.6f), glm::vec3(0.0f)};
        reg.emplace<Camera>(reg.create());
        state = &setup_editor(reg, Viewport{640, 480});
    }
};
glm::vec4 colour_of(const OverlayGeometry& g, std::size_t i) { return g.points[i].color; }
}  // namespace

TEST(LatticeOverlay, ColoursShowSelectionPinsAndTheObjectsBox) {
    Scene s;
    const Lattice& l = s.reg.get<Lattice>(s.lattice);
    const std::uint32_t selected = static_cast<std::uint32_t>(l.index(2, 2, 2));
    set_selection(s.reg, *s.state, s.lattice, {selected}, "select");
    const OverlayGeometry g = build_lattice_overlay(s.reg, *s.state, s.lattice);
    ASSERT_EQ(g.points.size(), l.size());
    EXPECT_EQ(g.lines.size(), 2u * 3u * 4u * 5u * 5u);  // 3 directions x 4 segments x 5x5 rows, 2 ends each
    int inside = 0;
    for (std::size_t c = 0; c < l.size(); ++c) {
        const glm::vec4 col = colour_of(g, c);
        if (c == selected) EXPECT_EQ(col, overlay_selected);
        else if (col == overlay_inside) ++inside;
    }
    EXPECT_EQ(inside, 26);  // 27 inside the box, one of them selected
    EXPECT_EQ(colour_of(g, l.index(0, 2, 2)), overlay_pinned);
    EXPECT_GT(g.points[selected].size, g.points[l.index(1, 1, 1)].size);
    // Unpinned (or global scope): the outer layer is shown as an ordinary point outside the box.
    s.state->pin_outer_layer = false;
    EXPECT_EQ(colour_of(build_lattice_overlay(s.reg, *s.state, s.lattice), l.index(0, 2, 2)),
              overlay_outside);
}

TEST(LatticeOverlay, CageOnlyDrawsTheBoxEdgesAndTheSelection) {
    Scene s;
    const Lattice& l = s.reg.get<Lattice>(s.lattice);
    const std::uint32_t centre = static_cast<std::uint32_t>(l.index(2, 2, 2));
    set_selection(s.reg, *s.state, s.lattice, {centre}, "select");
    InputEvent key;
    key.kind = InputKind::key;
    key.key = "t";
    key.modifiers = mods::shift;
    s.state->events = {key};
    editor_input_system(s.reg, FrameContext{});
    ASSERT_TRUE(s.state->lattice_cage_only);
    EXPECT_FALSE(s.state->xray) << "shift+t is the cage, t alone x-ray";
    const OverlayGeometry g = build_lattice_overlay(s.reg, *s.state, s.lattice);
    EXPECT_EQ(g.lines.size(), 2u * 12u * 4u);        // 12 box edges of 4 segments, 2 ends each
    EXPECT_EQ(g.points.size(), 8u + 12u * 3u + 1u);  // corners, edge points, and the selected centre
    // Every line end lies on an edge of the box [-1, 1]^3 (two coordinates at +-1).
    for (const OverlayVertex& v : g.lines) {
        const glm::dvec3 w = g.anchor + glm::dvec3(v.position);
        const int on = int(std::abs(std::abs(w.x) - 1.0) < 1e-6) + int(std::abs(std::abs(w.y) - 1.0) < 1e-6) +
                       int(std::abs(std::abs(w.z) - 1.0) < 1e-6);
        EXPECT_GE(on, 2);
    }
    // The selected centre is still shown, small and translucent, so select-all does not hide the model.
    int faint = 0;
    for (const OverlayVertex& v : g.points)
        if (glm::vec3(v.color) == glm::vec3(overlay_selected) && v.size == 3.0f && v.color.w < 0.5f) ++faint;
    EXPECT_EQ(faint, 1);
}

// The overlay's draws: the faint pass through the surface, then the visible part; with x-ray one pass at
// full strength; while the view previews with a light overlay, no hidden edges, and they are back at rest.
TEST(LatticeOverlay, LightOverlayDropsOnlyTheHiddenEdgesAndOnlyWhilePreviewing) {
    Scene s;
    auto count = [](const std::vector<OverlayDraw>& draws, bool lines, bool depth_test) {
        return std::count_if(draws.begin(), draws.end(), [&](const OverlayDraw& d) {
            return d.lines == lines && d.depth_test == depth_test;
        });
    };
    EditorState& st = *s.state;
    for (bool light : {false, true})
        for (bool previewing : {false, true}) {
            st.light_overlay_while_moving = light, st.previewing = previewing;
            const std::vector<OverlayDraw> d = overlay_draws(st);
            const bool hidden_edges = !(light && previewing);
            EXPECT_EQ(count(d, true, false), hidden_edges ? 1 : 0) << light << previewing;
            EXPECT_EQ(count(d, false, false), 1) << "hidden points stay";
            EXPECT_EQ(count(d, true, true), 1) << "visible edges stay";
            EXPECT_EQ(count(d, false, true), 1) << "visible points stay";
            for (const OverlayDraw& x : d) EXPECT_FLOAT_EQ(x.strength, x.depth_test ? 1.0f : 0.3f);
            // Each faint draw comes before the full-strength draws, which cover it where the part is seen.
            ASSERT_FALSE(d.empty());
            EXPECT_TRUE(
                std::is_partitioned(d.begin(), d.end(), [](const OverlayDraw& x) { return !x.depth_test; }));
        }
    st.xray = true;
    st.light_overlay_while_moving = st.previewing = true;
    const std::vector<OverlayDraw> x = overlay_draws(st);
    EXPECT_EQ(count(x, true, false), 1) << "x-ray shows every edge, moving or not";
    EXPECT_EQ(count(x, false, false), 1);
    EXPECT_EQ(x.size(), 2u);
    for (const OverlayDraw& d : x) EXPECT_EQ(d.strength, 1.0f);
}

TEST(EditorKeys, SetKeyRecordsTheLastStretchAndUndoRemovesIt) {
    Scene s;
    const Lattice& l = s.reg.get<Lattice>(s.lattice);
    const std::uint32_t p = static_cast<std::uint32_t>(l.index(2, 1, 2));
    EXPECT_FALSE(key_last_edit(s.reg, *s.state));  // nothing edited yet
    set_selection(s.reg, *s.state, s.lattice, {p}, "select");
    ASSERT_TRUE(apply_stretch(s.reg, *s.state, {0.0, 0.25, 0.0}));
    ASSERT_TRUE(key_last_edit(s.reg, *s.state));
    ASSERT_TRUE(s.reg.has<AnimationClip>(s.lattice));
    const AnimationClip& clip = s.reg.get<AnimationClip>(s.lattice);
    ASSERT_EQ(clip.tracks.size(), 1u);
    EXPECT_EQ(clip.tracks[0].kind, TrackKind::stretch);
    EXPECT_EQ(clip.tracks[0].points, std::vector<std::uint32_t>{p});
    ASSERT_EQ(clip.tracks[0].keys.size(), 1u);
    EXPECT_EQ(clip.tracks[0].keys[0].value, glm::dvec3(0.0, 0.25, 0.0));
    EXPECT_FALSE(s.reg.get<AnimationState>(s.lattice).playing);  // keys do not start playback
    // Delete the key at the current time, then undo both steps: the clip is gone again.
    ASSERT_TRUE(delete_keys_at_time(s.reg, *s.state));
    EXPECT_TRUE(s.reg.get<AnimationClip>(s.lattice).tracks[0].keys.empty());
    undo(s.reg, *s.state);
    EXPECT_EQ(s.reg.get<AnimationClip>(s.lattice).tracks[0].keys.size(), 1u);
    undo(s.reg, *s.state);
    EXPECT_FALSE(s.reg.has<AnimationClip>(s.lattice));
    EXPECT_FALSE(s.reg.has<AnimationState>(s.lattice));
}

// Keying a twist at two times must give one track with two keys, even though the pivot (the selection's
// centroid, recomputed after the first twist) comes back a rounding error away: two one-key tracks would
// never animate.
TEST(EditorKeys, TwistKeyedAtTwoTimesIsOneTrackWithTwoKeys) {
    Scene s;
    const Lattice& l = s.reg.get<Lattice>(s.lattice);
    const std::vector<std::uint32_t> top = {
        static_cast<std::uint32_t>(l.index(1, 3, 1)), static_cast<std::uint32_t>(l.index(3, 3, 1)),
        static_cast<std::uint32_t>(l.index(1, 3, 3)), static_cast<std::uint32_t>(l.index(3, 3, 3))};
    set_selection(s.reg, *s.state, s.lattice, top, "select");
    ASSERT_TRUE(apply_twist(s.reg, *s.state, 30.0));
    ASSERT_TRUE(key_last_edit(s.reg, *s.state));
    AnimationState& playhead = s.reg.patch<AnimationState>(s.lattice);
    scrub(playhead, 1.0);
    playhead.time = 1.0;  // what the animation system derives from the scrub on the next frame
    ASSERT_TRUE(apply_twist(s.reg, *s.state, 45.0));
    // What a drifted centroid looks like, should this platform's rounding happen to cancel.
    s.state->last_edit.pivot += glm::dvec3(1e-13, -1e-13, 0.0);
    ASSERT_TRUE(key_last_edit(s.reg, *s.state));
    const AnimationClip& clip = s.reg.get<AnimationClip>(s.lattice);
    ASSERT_EQ(clip.tracks.size(), 1u);
    EXPECT_EQ(clip.tracks[0].kind, TrackKind::twist);
    EXPECT_EQ(clip.tracks[0].keys.size(), 2u);
    // A twist about another pivot (well beyond rounding) is another track.
    s.state->last_edit.pivot += glm::dvec3(0.5, 0.0, 0.0);
    ASSERT_TRUE(key_last_edit(s.reg, *s.state));
    EXPECT_EQ(s.reg.get<AnimationClip>(s.lattice).tracks.size(), 2u);
}
