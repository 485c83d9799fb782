// The editor's input system driven by InputEvents, exactly as the window and the replayer drive it:
// click selection through Embree picking, box select, stretch and twist drags, pins, undo/redo.
#include "systems/editor/editor_system.h"

#include <cmath>
#include <cstring>
#include <numbers>

#include <glm/gtc/quaternion.hpp>
#include <gtest/gtest.h>

#include "systems/animation/animation_system.h"
#include "systems/animation/components.h"
#include "runtime/scene/components.h"
#include "systems/ffd/components.h"
#include "systems/ffd/deform.h"
#include "systems/gaussian/components.h"
#include "systems/picking/components.h"
#include "systems/picking/picking_system.h"
#include "systems/splat_render/splat_render.h"

using namespace sffd;
using namespace sffd::editor;

namespace {

struct Scene {
    ecs::Registry reg;
    ecs::Entity lattice;
    ecs::Entity cloud;
    EditorState* state = nullptr;
    std::uint64_t frame = 0;

    Scene() {
        // A lattice 3x3x3 cells around the unit cube [-1,1]^3, and a small point cloud (a sphere of radius
        // 0.5) inside it, so the inner control points are not hidden behind the surface from the camera.
        lattice = reg.create();
        reg.emplace<Lattice>(
            lattice,
            make_lattice({-1, -1, -1}, {glm::dvec3(2, 0, 0), glm::dvec3(0, 2, 0), glm::dvec3(0, 0, 2)},
                         {3, 3, 3}));
        cloud = reg.create();
        SplatCloud& c = reg.emplace<SplatCloud>(cloud);
        for (int a = 0; a < 40; ++a)
            for (int b = 0; b < 20; ++b) {
                const double th = a * 2 * std::numbers::pi / 40, ph = (b + 0.5) * std::numbers::pi / 20;
                const glm::vec3 n(std::sin(ph) * std::cos(th), std::cos(ph), std::sin(ph) * std::sin(th));
                c.positions.push_back(0.15f * n);
                c.normals.push_back(n);
                const glm::vec3 u = glm::normalize(
                    glm::cross(n, std::abs(n.y) < 0.9f ? glm::vec3(0, 1, 0) : glm::vec3(1, 0, 0)));
                c.axis_u.push_back(0.03f * u);
                c.axis_v.push_back(0.03f * glm::cross(n, u));
            }
        const ecs::Entity cam = reg.create();
        Camera& camera = reg.emplace<Camera>(cam);
        camera.eye = {0.6, 0.8, 6.0};
        camera.target = {0, 0, 0};
        state = &setup_editor(reg, Viewport{800, 600});
    }
    const Camera& camera() { return reg.get<Camera>(state->camera); }
    glm::dvec2 pixel_of(std::size_t control_point) {
        return glm::dvec2(
            project_to_pixel(camera(), state->viewport, reg.get<Lattice>(lattice).current[control_point]));
    }
    // One frame of the engine's editor steps: input, then the picking phase (picking, then the gestures
    // that waited for their pick).
    void frame_once(std::vector<InputEvent> events) {
        for (auto& e : events) e.frame = frame;
        state->events = std::move(events);
        const FrameContext f{frame, frame / 60.0, 1 / 60.0};
        editor_input_system(reg, f);
        picking::picking_system(reg, f);
        editor_pick_system(reg, f);
        ++frame;
    }
    // The events, and as many frames as the events that wait for a pick need.
    void run(std::vector<InputEvent> events) {
        frame_once(std::move(events));
        while (!state->deferred.empty()) frame_once({});
    }
    static InputEvent move(glm::dvec2 p) {
        InputEvent e;
        e.kind = InputKind::move;
        e.position = p;
        return e;
    }
    static InputEvent press(std::uint8_t m = 0, MouseButton b = MouseButton::left) {
        InputEvent e;
        e.kind = InputKind::press;
        e.button = b;
        e.modifiers = m;
        return e;
    }
    static InputEvent release(MouseButton b = MouseButton::left) {
        InputEvent e;
        e.kind = InputKind::release;
        e.button = b;
        return e;
    }
    static InputEvent key(const char* k, std::uint8_t m = 0) {
        InputEvent e;
        e.kind = InputKind::key;
        e.key = k;
        e.modifiers = m;
        return e;
    }
    void click(glm::dvec2 p, std::uint8_t m = 0) { run({move(p), press(m), release()}); }
    std::vector<std::uint32_t> selection() {
        const auto* s = reg.try_get<picking::LatticeSelection>(lattice);
        return s ? s->indices : std::vector<std::uint32_t>{};
    }
    const Lattice& lat() { return reg.get<Lattice>(lattice); }
};

bool bit_equal(const std::vector<glm::dvec3>& a, const std::vector<glm::dvec3>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(glm::dvec3)) == 0;
}

std::uint32_t idx(const Lattice& l, int i, int j, int k) {
    return static_cast<std::uint32_t>(l.index(i, j, k));
}

}  // namespace

TEST(EditorSystem, ClickShiftClickCtrlClickAndEmptyClick) {
    Scene s;
    const std::uint32_t a = idx(s.lat(), 1, 1, 2), b = idx(s.lat(), 2, 2, 2);
    s.click(s.pixel_of(a));
    EXPECT_EQ(s.selection(), std::vector<std::uint32_t>{a});
    s.click(s.pixel_of(b), mods::shift);
    EXPECT_EQ(s.selection(), (std::vector<std::uint32_t>{std::min(a, b), std::max(a, b)}));
    s.click(s.pixel_of(a), mods::ctrl);
    EXPECT_EQ(s.selection(), std::vector<std::uint32_t>{b});
    s.click({3.0, 3.0});  // empty space (top-left corner)
    EXPECT_TRUE(s.selection().empty());
    // Every selection change was one undo step.
    EXPECT_EQ(s.state->undo.size(), 4u);
    s.run({Scene::key("z", mods::ctrl)});
    EXPECT_EQ(s.selection(), std::vector<std::uint32_t>{b});
}

// A click posts a pick in the input phase; the picking phase answers it and the selection changes right
// after, in the same frame.
TEST(EditorSystem, ClickSelectsWhenThePickingPhaseAnswers) {
    Scene s;
    const std::uint32_t a = idx(s.lat(), 1, 1, 2);
    s.state->events = {Scene::move(s.pixel_of(a)), Scene::press(), Scene::release()};
    const FrameContext f{0, 0.0, 1 / 60.0};
    editor_input_system(s.reg, f);
    EXPECT_TRUE(s.selection().empty()) << "the input phase only posts the pick";
    ASSERT_EQ(s.reg.resource<picking::PickRequests>().pending.size(), 1u);
    ASSERT_EQ(s.state->pending_picks.size(), 1u);
    picking::picking_system(s.reg, f);
    EXPECT_TRUE(s.selection().empty());
    editor_pick_system(s.reg, f);
    EXPECT_EQ(s.selection(), std::vector<std::uint32_t>{a});
    EXPECT_TRUE(s.state->pending_picks.empty());
}

// Events after a pick-dependent gesture wait for the next frame, so they see what the pick did: a click
// and then Escape (deselect) in one frame leave nothing selected.
TEST(EditorSystem, EventsAfterAPickRunAfterItsAnswer) {
    Scene s;
    const std::uint32_t a = idx(s.lat(), 1, 1, 2);
    s.frame_once({Scene::move(s.pixel_of(a)), Scene::press(), Scene::release(), Scene::key("escape")});
    EXPECT_EQ(s.selection(), std::vector<std::uint32_t>{a});
    ASSERT_EQ(s.state->deferred.size(), 1u);
    s.frame_once({});
    EXPECT_TRUE(s.selection().empty());
    EXPECT_TRUE(s.state->deferred.empty());
    EXPECT_EQ(s.state->undo.size(), 2u);  // select, deselect
}

// Brush dabs of one frame each post a pick and are all answered in that frame's picking phase.
TEST(EditorSystem, BrushDabsAreAnsweredInThePickingPhase) {
    Scene s;
    s.run({Scene::key("b")});
    const glm::dvec2 centre = glm::dvec2(project_to_pixel(s.camera(), s.state->viewport, glm::dvec3(0.0)));
    s.frame_once({Scene::move(centre), Scene::press(), Scene::move(centre + glm::dvec2(3, 0)),
                  Scene::move(centre + glm::dvec2(-3, 0))});
    EXPECT_TRUE(s.state->deferred.empty()) << "brush moves do not wait";
    EXPECT_EQ(s.reg.resource<picking::PickResults>().answers.size(), 3u);
    EXPECT_FALSE(s.selection().empty()) << "the dabs on the sphere selected the control points around it";
    s.run({Scene::release()});
}

// Alt+click sets the twist pivot at the surface point the picking phase found.
TEST(EditorSystem, AltClickSetsThePivotAtThePickedSurfacePoint) {
    Scene s;
    const glm::dvec2 centre = glm::dvec2(project_to_pixel(s.camera(), s.state->viewport, glm::dvec3(0.0)));
    s.run({Scene::move(centre), Scene::press(mods::alt), Scene::release()});
    ASSERT_TRUE(s.state->has_picked_pivot);
    EXPECT_EQ(s.state->pivot_mode, PivotMode::picked_point);
    // On the front of the sphere of radius 0.15 (splat discs: within their half-size of it).
    EXPECT_NEAR(glm::length(s.state->picked_pivot), 0.15, 0.02);
    EXPECT_GT(glm::dot(s.state->picked_pivot, s.camera().eye), 0.0);
}

TEST(EditorSystem, BoxSelectTakesThePointsInsideTheRectangle) {
    Scene s;
    // A rectangle around the projections of the two front inner points (k = 2 is nearer the camera at +z).
    const std::uint32_t a = idx(s.lat(), 1, 1, 2), b = idx(s.lat(), 2, 1, 2);
    const glm::dvec2 pa = s.pixel_of(a), pb = s.pixel_of(b);
    const glm::dvec2 lo = glm::min(pa, pb) - 4.0, hi = glm::max(pa, pb) + 4.0;
    s.run({Scene::move(lo), Scene::press(), Scene::move((lo + hi) * 0.5), Scene::move(hi), Scene::release()});
    const auto sel = s.selection();
    EXPECT_NE(std::find(sel.begin(), sel.end(), a), sel.end());
    EXPECT_NE(std::find(sel.begin(), sel.end(), b), sel.end());
    for (std::uint32_t c : sel) {  // nothing outside the rectangle
        const glm::dvec2 p = s.pixel_of(c);
        EXPECT_TRUE(p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y) << c;
    }
}

// The box select's visibility test is picking's too: it runs in the picking phase, not in the input phase.
TEST(EditorSystem, BoxSelectIsAppliedInThePickingPhase) {
    Scene s;
    const std::uint32_t a = idx(s.lat(), 1, 1, 2);
    const glm::dvec2 p = s.pixel_of(a);
    s.state->events = {Scene::move(p - 3.0), Scene::press(), Scene::move(p + 3.0), Scene::release()};
    const FrameContext f{0, 0.0, 1 / 60.0};
    editor_input_system(s.reg, f);
    EXPECT_TRUE(s.selection().empty());
    EXPECT_EQ(s.reg.try_resource<picking::PickingState>(), nullptr) << "the input phase casts no ray";
    picking::picking_system(s.reg, f);
    editor_pick_system(s.reg, f);
    EXPECT_EQ(s.selection(), std::vector<std::uint32_t>{a});
}

TEST(EditorSystem, StretchDragMovesTheSelectionAlongXAndUndoRedoAreBitExact) {
    Scene s;
    const std::uint32_t a = idx(s.lat(), 1, 1, 2), b = idx(s.lat(), 2, 1, 2);
    s.click(s.pixel_of(a));
    s.click(s.pixel_of(b), mods::shift);
    const std::vector<glm::dvec3> rest = s.lat().current;
    s.run({Scene::key("g"), Scene::key("x")});
    EXPECT_EQ(s.state->move_axis, AxisMode::x);
    // Drag from the selection's centroid image to the image of a point 0.4 further along x.
    const glm::dvec3 c = 0.5 * (rest[a] + rest[b]);
    const glm::dvec2 from = glm::dvec2(project_to_pixel(s.camera(), s.state->viewport, c));
    const glm::dvec2 to =
        glm::dvec2(project_to_pixel(s.camera(), s.state->viewport, c + glm::dvec3(0.4, 0, 0)));
    s.run({Scene::move(from), Scene::press(), Scene::move(glm::mix(from, to, 0.5))});
    EXPECT_GT(s.lat().current[a].x, rest[a].x);  // live while dragging
    s.run({Scene::move(to), Scene::release()});
    const std::vector<glm::dvec3> edited = s.lat().current;
    for (std::size_t p = 0; p < rest.size(); ++p) {
        const bool moved = p == a || p == b;
        EXPECT_NEAR(edited[p].x - rest[p].x, moved ? 0.4 : 0.0, 1e-9) << p;
        EXPECT_EQ(edited[p].y, rest[p].y);
        EXPECT_EQ(edited[p].z, rest[p].z);
    }
    s.run({Scene::key("z", mods::ctrl)});
    EXPECT_TRUE(bit_equal(s.lat().current, rest));
    s.run({Scene::key("z", mods::ctrl | mods::shift)});
    EXPECT_TRUE(bit_equal(s.lat().current, edited));
}

TEST(EditorSystem, TwistDragRotatesAboutTheViewAxisThroughTheCentroid) {
    Scene s;
    s.state->scope = ToolScope::global;  // all points, pins ignored: the paper's global twist
    const std::vector<glm::dvec3> rest = s.lat().current;
    s.run({Scene::key("r"), Scene::key("z")});
    EXPECT_EQ(s.state->twist_axis, AxisMode::z);
    const glm::dvec2 centre = glm::dvec2(project_to_pixel(s.camera(), s.state->viewport, glm::dvec3(0.0)));
    // Sweep a quarter turn counter-clockwise on screen around the pivot, in small steps.
    std::vector<InputEvent> ev{Scene::move(centre + glm::dvec2(120, 0)), Scene::press()};
    for (int step = 1; step <= 9; ++step) {
        const double a = step * std::numbers::pi / 18;
        ev.push_back(Scene::move(centre + 120.0 * glm::dvec2(std::cos(a), -std::sin(a))));
    }
    ev.push_back(Scene::release());
    s.run(ev);
    // The camera is slightly off-axis, so the on-screen angle about the projected pivot is close to,
    // but not exactly, the world angle: check it is a rotation about z through the centroid.
    const glm::dvec3 p = s.lat().current[0], r = rest[0];
    EXPECT_NEAR(p.z, r.z, 1e-12);
    EXPECT_NEAR(glm::length(glm::dvec2(p)), glm::length(glm::dvec2(r)), 1e-9);
    const double angle = std::atan2(p.y, p.x) - std::atan2(r.y, r.x);
    EXPECT_NEAR(std::remainder(angle, 2 * std::numbers::pi), std::numbers::pi / 2, 0.08);
    ASSERT_EQ(s.state->undo.size(), 1u);
    EXPECT_EQ(s.state->undo.at(0).label(), "twist");
}

TEST(EditorSystem, PinnedOuterLayerIsNotMovedUntilUnpinned) {
    Scene s;
    const std::uint32_t corner = idx(s.lat(), 0, 0, 3), inner = idx(s.lat(), 1, 1, 2);
    s.click(s.pixel_of(corner));
    s.click(s.pixel_of(inner), mods::shift);
    ASSERT_EQ(s.selection().size(), 2u);
    s.run({Scene::key("g")});
    ASSERT_TRUE(apply_stretch(s.reg, *s.state, {0.0, 0.25, 0.0}));
    EXPECT_EQ(s.lat().current[corner], s.lat().rest[corner]);
    EXPECT_NEAR(s.lat().current[inner].y - s.lat().rest[inner].y, 0.25, 1e-15);
    s.run({Scene::key("p")});  // unpin: one key
    EXPECT_FALSE(s.state->pin_outer_layer);
    ASSERT_TRUE(apply_stretch(s.reg, *s.state, {0.0, 0.25, 0.0}));
    EXPECT_NEAR(s.lat().current[corner].y - s.lat().rest[corner].y, 0.25, 1e-15);
}

TEST(EditorSystem, EscapeCancelsADragWithoutAnUndoStep) {
    Scene s;
    const std::uint32_t a = idx(s.lat(), 1, 2, 2);
    s.click(s.pixel_of(a));
    const std::size_t steps = s.state->undo.size();
    const std::vector<glm::dvec3> before = s.lat().current;
    s.run({Scene::key("g"), Scene::move(s.pixel_of(a)), Scene::press(),
           Scene::move(s.pixel_of(a) + glm::dvec2(40, 10))});
    EXPECT_FALSE(bit_equal(s.lat().current, before));
    s.run({Scene::key("escape"), Scene::release()});
    EXPECT_TRUE(bit_equal(s.lat().current, before));
    EXPECT_EQ(s.state->undo.size(), steps);
}

TEST(EditorSystem, OrbitPanZoomMoveTheCamera) {
    Scene s;
    const Camera before = s.camera();
    s.run({Scene::move({400, 300}), Scene::press(0, MouseButton::right), Scene::move({450, 300}),
           Scene::release(MouseButton::right)});
    EXPECT_NEAR(glm::length(s.camera().eye - s.camera().target), glm::length(before.eye - before.target),
                1e-9);
    EXPECT_GT(glm::length(s.camera().eye - before.eye), 0.1);
    InputEvent wheel;
    wheel.kind = InputKind::scroll;
    wheel.scroll = 3;
    const double d0 = glm::length(s.camera().eye - s.camera().target);
    s.run({wheel});
    EXPECT_LT(glm::length(s.camera().eye - s.camera().target), d0);
}

TEST(EditorSystem, ResampleKeepsTheShapeAndUndoRestoresTheLattice) {
    Scene s;
    const std::uint32_t a = idx(s.lat(), 1, 2, 1);
    s.click(s.pixel_of(a));
    s.run({Scene::key("g")});
    ASSERT_TRUE(apply_stretch(s.reg, *s.state, {0.2, -0.1, 0.3}));
    const Lattice before = s.lat();
    ASSERT_TRUE(resample_lattice(s.reg, *s.state, {5, 4, 6}));
    EXPECT_EQ(s.lat().divisions, glm::ivec3(5, 4, 6));
    EXPECT_TRUE(s.selection().empty());  // indices of the old grid mean nothing in the new one
    // Same deformation (Bernstein degree elevation is exact), checked against ffd's reference evaluator.
    for (const glm::dvec3 p : {glm::dvec3(0.1, 0.2, -0.3), glm::dvec3(-0.7, 0.5, 0.6), glm::dvec3(0.0)}) {
        const auto x0 = ffd::reference_point(before, p), x1 = ffd::reference_point(s.lat(), p);
        EXPECT_NEAR(glm::length(x0.position - x1.position), 0.0, 1e-12);
    }
    s.run({Scene::key("z", mods::ctrl)});
    EXPECT_EQ(s.lat().divisions, before.divisions);
    EXPECT_TRUE(bit_equal(s.lat().current, before.current));
    EXPECT_EQ(s.selection(), std::vector<std::uint32_t>{a});
}

// Typed values after g / r (Blender habit), through key events as the window and replays send them.
namespace {

std::vector<InputEvent> keys(std::initializer_list<const char*> names) {
    std::vector<InputEvent> out;
    for (const char* k : names) out.push_back(Scene::key(k));
    return out;
}

}  // namespace

TEST(EditorSystem, TypedMoveAlongAnAxisAfterG) {
    Scene s;
    s.run({Scene::key("a")});  // select all: the inner 2x2x2 points are editable (outer layer pinned)
    const std::vector<glm::dvec3> rest = s.lat().current;
    const std::vector<std::uint32_t> editable = editable_selection(s.reg, *s.state);
    ASSERT_EQ(editable.size(), 8u);
    // An AnimationState on the lattice: space while typing must not start playback.
    s.reg.emplace<AnimationState>(s.lattice).playing = false;
    s.run(keys({"g", "z", "0", "period", "2", "5", "backspace"}));
    EXPECT_TRUE(s.state->typed.active);
    EXPECT_NE(s.state->status.find("move z: 0.2_"), std::string::npos) << s.state->status;
    EXPECT_TRUE(bit_equal(s.lat().current, rest)) << "nothing moves before Enter";
    s.run(keys({"space", "enter"}));
    EXPECT_FALSE(s.reg.get<AnimationState>(s.lattice).playing) << "space went to the entry, not play/pause";
    EXPECT_FALSE(s.state->typed.active);
    for (std::size_t p = 0; p < rest.size(); ++p) {
        const bool moved = std::find(editable.begin(), editable.end(), std::uint32_t(p)) != editable.end();
        const glm::dvec3 want = rest[p] + (moved ? glm::dvec3(0, 0, 0.2) : glm::dvec3(0));
        EXPECT_EQ(s.lat().current[p], want) << p;
    }
    EXPECT_EQ(s.state->undo.size(), 2u);  // select all, stretch
}

TEST(EditorSystem, TypedMoveWithThreeValuesAndNegativeNumbers) {
    Scene s;
    s.run({Scene::key("a")});
    const std::vector<glm::dvec3> rest = s.lat().current;
    const std::uint32_t inner = idx(s.lat(), 1, 1, 1);
    s.run(keys({"g", "minus", "0", "period", "5", "space", "0", "comma", "1"}));
    EXPECT_TRUE(s.state->typed.active);
    s.run(keys({"enter"}));
    EXPECT_EQ(s.lat().current[inner], rest[inner] + glm::dvec3(-0.5, 0, 1));
}

TEST(EditorSystem, TypedTwistAboutXMatchesTheNumericEntry) {
    Scene typed, reference;
    for (Scene* s : {&typed, &reference}) s->run({Scene::key("a")});
    typed.run(keys({"r", "x", "4", "5", "enter"}));
    reference.run({Scene::key("r"), Scene::key("x")});
    reference.run({Scene::key("escape")});  // ends the entry (reference uses the text event below)
    ASSERT_FALSE(reference.selection().empty());
    InputEvent text;
    text.kind = InputKind::text;
    text.key = "45";
    reference.run({text});
    EXPECT_EQ(typed.state->twist_axis, AxisMode::x);
    EXPECT_TRUE(bit_equal(typed.lat().current, reference.lat().current));
    EXPECT_FALSE(bit_equal(typed.lat().current, typed.lat().rest));
}

TEST(EditorSystem, TypedEntryEscapeCancelsAndKeepsTheSelection) {
    Scene s;
    s.run({Scene::key("a")});
    const std::vector<std::uint32_t> sel = s.selection();
    const std::vector<glm::dvec3> rest = s.lat().current;
    s.run(keys({"g", "x", "1", "escape"}));
    EXPECT_FALSE(s.state->typed.active);
    EXPECT_EQ(s.selection(), sel) << "Escape cancelled the entry, it did not deselect";
    s.run(keys({"enter"}));
    EXPECT_TRUE(bit_equal(s.lat().current, rest));
    // Another key ends the entry unapplied and does its usual job; ctrl+q still quits.
    s.run(keys({"g", "x", "1", "t"}));
    EXPECT_FALSE(s.state->typed.active);
    EXPECT_TRUE(s.state->xray);
    s.run(keys({"g", "1"}));
    s.run({Scene::key("q", mods::ctrl)});
    EXPECT_TRUE(s.state->request_quit);
    EXPECT_TRUE(bit_equal(s.lat().current, rest));
    // A bad entry says why and changes nothing.
    s.run(keys({"g", "y", "1", "space", "2", "enter"}));
    EXPECT_NE(s.state->status.find("typed move"), std::string::npos) << s.state->status;
    EXPECT_TRUE(bit_equal(s.lat().current, rest));
}

// Auto-key and the warning before play replaces an un-keyed edit.
TEST(EditorSystem, PlayWarnsBeforeDiscardingAnUnkeyedEdit) {
    Scene s;
    s.run({Scene::key("a")});
    s.run(keys({"g", "z", "0", "period", "2", "enter", "k"}));  // keyed stretch: the lattice gets a clip
    ASSERT_TRUE(s.reg.has<AnimationClip>(s.lattice));
    ASSERT_FALSE(s.reg.get<AnimationState>(s.lattice).playing);
    EXPECT_FALSE(s.reg.valid(s.state->unkeyed));
    s.run(keys({"right", "g", "z", "0", "period", "1", "enter"}));  // un-keyed edit at 1/24 s
    EXPECT_EQ(s.state->unkeyed, s.lattice);
    s.run(keys({"space"}));
    EXPECT_FALSE(s.reg.get<AnimationState>(s.lattice).playing) << "first play only warns";
    EXPECT_NE(s.state->status.find("un-keyed"), std::string::npos) << s.state->status;
    s.run(keys({"space"}));
    EXPECT_TRUE(s.reg.get<AnimationState>(s.lattice).playing) << "second play plays";
    s.run(keys({"space"}));  // pause
    EXPECT_FALSE(s.reg.get<AnimationState>(s.lattice).playing);
    // Keying the edit removes the warning.
    s.run(keys({"g", "z", "0", "period", "1", "enter", "k", "space"}));
    EXPECT_TRUE(s.reg.get<AnimationState>(s.lattice).playing) << s.state->status;
}

// An un-keyed edit belongs to the clip time it was made at: scrubbing away shows the clip's pose, back
// shows the edit; undo takes it back with the stretch, keying it hands the time back to the clip.
TEST(EditorSystem, AnUnkeyedEditComesBackAtItsClipTime) {
    Scene s;
    const auto animate = [&] { animation_system(s.reg, FrameContext{s.frame, s.frame / 60.0, 1 / 60.0}); };
    s.run({Scene::key("a")});
    s.run(keys({"g", "z", "0", "period", "2", "enter", "k"}));  // keyed: the lattice gets a clip
    animate();
    s.run(keys({"right"}));
    animate();
    const std::vector<glm::dvec3> clip_pose = s.lat().current;
    s.run(keys({"g", "z", "0", "period", "1", "enter"}));  // un-keyed at 1/24 s
    animate();
    ASSERT_TRUE(s.reg.has<UnkeyedEdit>(s.lattice));
    EXPECT_NEAR(s.reg.get<UnkeyedEdit>(s.lattice).time, 1.0 / 24.0, 1e-12);
    const std::vector<glm::dvec3> edited = s.lat().current;
    ASSERT_NE(edited, clip_pose);
    s.run(keys({"right"}));
    animate();
    EXPECT_NE(s.lat().current, edited) << "another time: the clip's pose";
    s.run(keys({"left"}));
    animate();
    EXPECT_EQ(s.lat().current, edited) << "back at its time: the edit";
    s.run({Scene::key("z", mods::ctrl)});
    EXPECT_FALSE(s.reg.has<UnkeyedEdit>(s.lattice)) << "undone with the stretch";
    s.run({Scene::key("z", mods::ctrl | mods::shift)});
    ASSERT_TRUE(s.reg.has<UnkeyedEdit>(s.lattice));
    s.run(keys({"k"}));
    EXPECT_FALSE(s.reg.has<UnkeyedEdit>(s.lattice)) << "keyed: the clip's pose from now on";
}

TEST(EditorSystem, AutoKeyKeysEveryEditAtTheClipTime) {
    Scene s;
    s.run({Scene::key("a")});
    s.run(keys({"n"}));
    EXPECT_TRUE(s.state->auto_key);
    s.run(keys({"g", "z", "0", "period", "2", "enter"}));
    ASSERT_TRUE(s.reg.has<AnimationClip>(s.lattice));
    s.run(keys({"right"}));
    animation_system(s.reg,
                     FrameContext{s.frame, s.frame / 60.0, 1 / 60.0});  // the clip time follows the scrub
    ASSERT_NEAR(s.reg.get<AnimationState>(s.lattice).time, 1.0 / 24.0, 1e-12);
    s.run(keys({"g", "z", "0", "period", "1", "enter"}));
    const AnimationClip& clip = s.reg.get<AnimationClip>(s.lattice);
    ASSERT_EQ(clip.tracks.size(), 1u);
    ASSERT_EQ(clip.tracks[0].keys.size(), 2u);
    EXPECT_DOUBLE_EQ(clip.tracks[0].keys[0].time, 0.0);
    EXPECT_NEAR(clip.tracks[0].keys[1].time, 1.0 / 24.0, 1e-12);
    EXPECT_EQ(clip.tracks[0].keys[0].value, glm::dvec3(0, 0, 0.2));
    EXPECT_EQ(clip.tracks[0].keys[1].value, glm::dvec3(0, 0, 0.1));
    EXPECT_FALSE(s.reg.valid(s.state->unkeyed));
    s.run(keys({"space"}));
    EXPECT_TRUE(s.reg.get<AnimationState>(s.lattice).playing) << "nothing un-keyed: plays at once";
    s.run(keys({"space", "n"}));
    EXPECT_FALSE(s.state->auto_key);
}

// Preview while moving, HQ once the view has rested refine_after frames (RenderSettings through the
// registry).
TEST(EditorSystem, PreviewWhileDraggingRefinesToHqAtRest) {
    Scene s;
    auto& settings = s.reg.set_resource<render::RenderSettings>();
    settings.quality = render::Quality::hq;
    s.run({});
    EXPECT_EQ(settings.quality, render::Quality::hq) << "a still view starts in HQ";
    // Orbit drag (right button): preview from the first moving frame.
    s.run({Scene::move({300, 300}), Scene::press(0, MouseButton::right)});
    s.run({Scene::move({340, 310})});
    EXPECT_EQ(settings.quality, render::Quality::preview);
    EXPECT_TRUE(s.state->previewing);
    s.run({Scene::release(MouseButton::right)});  // the first still frame
    EXPECT_EQ(settings.quality, render::Quality::preview);
    for (int f = 2; f < s.state->refine_after; ++f) {
        s.run({});
        EXPECT_EQ(settings.quality, render::Quality::preview) << "still frame " << f;
    }
    s.run({});
    EXPECT_EQ(settings.quality, render::Quality::hq) << "rested " << s.state->refine_after << " frames";
    EXPECT_FALSE(s.state->previewing);
    // The wheel and a stretch drag count as movement too; a view started in preview stays preview.
    s.run({[] {
        InputEvent e;
        e.kind = InputKind::scroll;
        e.scroll = 1;
        return e;
    }()});
    EXPECT_EQ(settings.quality, render::Quality::preview);
    s.state->preview_while_moving = false;
    s.run({});
    EXPECT_EQ(settings.quality, render::Quality::hq) << "switched off: always the rest quality";
    Scene p;
    auto& ps = p.reg.set_resource<render::RenderSettings>();
    ps.quality = render::Quality::preview;
    p.run({Scene::move({300, 300}), Scene::press(0, MouseButton::right), Scene::move({350, 300})});
    for (int f = 0; f < 12; ++f) p.run({});
    EXPECT_EQ(ps.quality, render::Quality::preview);
}

// Half-resolution preview: the divider is 2 only in the frames that preview because of movement, never at
// rest and never for a view whose rest quality is preview (that would halve every frame).
TEST(EditorSystem, HalfResolutionPreviewOnlyWhileMoving) {
    Scene s;
    auto& settings = s.reg.set_resource<render::RenderSettings>();
    settings.quality = render::Quality::hq;
    s.state->half_resolution_preview = true;
    s.run({});
    EXPECT_EQ(settings.preview_divider, 1) << "still";
    s.run({Scene::move({300, 300}), Scene::press(0, MouseButton::right)});
    s.run({Scene::move({340, 310})});
    ASSERT_EQ(settings.quality, render::Quality::preview);
    EXPECT_EQ(settings.preview_divider, 2) << "orbiting";
    s.state->half_resolution_preview = false;
    s.run({Scene::move({360, 310})});
    EXPECT_EQ(settings.preview_divider, 1) << "switched off while moving";
    s.state->half_resolution_preview = true;
    s.run({Scene::release(MouseButton::right)});
    for (int f = 0; f <= s.state->refine_after; ++f) s.run({});
    EXPECT_EQ(settings.quality, render::Quality::hq);
    EXPECT_EQ(settings.preview_divider, 1) << "refined at rest";
    Scene p;
    auto& ps = p.reg.set_resource<render::RenderSettings>();
    ps.quality = render::Quality::preview;
    p.state->half_resolution_preview = true;
    p.run({Scene::move({300, 300}), Scene::press(0, MouseButton::right), Scene::move({350, 300})});
    EXPECT_EQ(ps.preview_divider, 1) << "a view that rests in preview keeps its resolution";
}

// A click on a 3D Gaussian selects its cloud entity, through the same picking phase.
TEST(EditorSystem, ClickOnAGaussianSelectsItsCloud) {
    Scene s;
    const ecs::Entity blob = s.reg.create();
    GaussianCloud& g = s.reg.emplace<GaussianCloud>(blob);
    g.positions.emplace_back(2.0f, 0.0f, 0.0f);  // beside the lattice, in view
    g.scales.emplace_back(0.2f, 0.2f, 0.2f);
    g.rotations.emplace_back(1.0f, 0.0f, 0.0f, 0.0f);
    g.opacities.push_back(1.0f);
    g.sh = {0.3f, 0.3f, 0.3f};
    s.click(glm::dvec2(project_to_pixel(s.camera(), s.state->viewport, glm::dvec3(2.0, 0.0, 0.0))));
    EXPECT_EQ(s.state->selected_entity, blob);
    EXPECT_TRUE(s.selection().empty());
}

// The scene's box, asked every frame by the overlay and the Lattice panel, comes from a cache that is
// recomputed only for clouds whose stamps moved, and is exact whether the cache is current or not.
TEST(EditorSceneBounds, CacheFollowsEditsTransformsAndRemovalsAndPassesOverOnlyWhatChanged) {
    ecs::Registry reg;
    const ecs::Entity a = reg.create(), b = reg.create();
    SplatCloud& ca = reg.emplace<SplatCloud>(a);
    ca.positions = {{-1, 0, 0}, {2, 1, 0}};
    GaussianCloud& gb = reg.emplace<GaussianCloud>(b);
    gb.origin = glm::dvec3(10, 0, 0);
    gb.positions = {{0, -3, 0}, {1, 0, 5}};
    auto expect_box = [&](glm::dvec3 want_lo, glm::dvec3 want_hi, const char* what) {
        glm::dvec3 lo, hi;
        ASSERT_TRUE(scene_bounds(reg, lo, hi)) << what;
        EXPECT_EQ(lo, want_lo) << what;
        EXPECT_EQ(hi, want_hi) << what;
    };
    expect_box({-1, -3, 0}, {11, 1, 5}, "no cache yet");
    update_scene_bounds_cache(reg);
    const SceneBoundsCache& cache = reg.resource<SceneBoundsCache>();
    EXPECT_EQ(cache.computed, 2u);
    expect_box({-1, -3, 0}, {11, 1, 5}, "cached");
    update_scene_bounds_cache(reg);
    EXPECT_EQ(cache.computed, 2u) << "nothing moved: nothing passed over again";

    // An edit through patch: exact before the cache catches up, then only that cloud is passed over.
    reg.patch<SplatCloud>(a).positions.push_back({-4, 0, 0});
    expect_box({-4, -3, 0}, {11, 1, 5}, "edited, cache stale");
    update_scene_bounds_cache(reg);
    EXPECT_EQ(cache.computed, 3u);
    expect_box({-4, -3, 0}, {11, 1, 5}, "edited, cached");

    // A Transform added to the Gaussians moves their box.
    Transform t;
    t.translation = glm::dvec3(0, 0, 100);
    reg.emplace<Transform>(b, t);
    expect_box({-4, -3, 0}, {11, 1, 105}, "moved, cache stale");
    update_scene_bounds_cache(reg);
    EXPECT_EQ(cache.computed, 4u);
    expect_box({-4, -3, 0}, {11, 1, 105}, "moved, cached");

    // A removed cloud leaves the box and the cache.
    reg.destroy(b);
    reg.flush();
    expect_box({-4, 0, 0}, {2, 1, 0}, "Gaussians removed");
    update_scene_bounds_cache(reg);
    EXPECT_EQ(cache.entries.size(), 1u);
}
