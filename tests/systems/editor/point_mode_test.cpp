// Point mode through the editor's input system, driven by replayed events exactly as `splatffd view
// --replay` drives it (no GL: picking with Embree, point_select's shown points through picking's own CPU
// deformation): the mode switch and today's keys, every selection tool against point_select called
// directly, the commands, every operation as one undo step with undo/redo to identical flags, separation
// with a lattice on the part undone and redone, weights from the selection, and the replay format.
#include <algorithm>
#include <cmath>
#include <cstring>

#include <gtest/gtest.h>

#include "runtime/assets/scene.h"
#include "runtime/scene/components.h"
#include "runtime/scene/point_columns.h"
#include "systems/editor/editor_system.h"
#include "systems/editor/point_mode.h"
#include "systems/editor/point_weights.h"
#include "systems/ffd/components.h"
#include "systems/picking/components.h"
#include "systems/picking/picking_system.h"
#include "systems/splat_render/splat_render.h"

using namespace sffd;
using namespace sffd::editor;

namespace {

struct Scene {
    ecs::Registry reg;
    ecs::Entity sphere = ecs::null_entity;
    EditorState* state = nullptr;
    std::uint64_t frame = 0;

    Scene() {
        reg.set_resource<SceneHooks>();  // the assets' own formats: the built-in sphere
        EXPECT_TRUE(load_scene(reg, "sphere").ok());
        reg.view<SplatCloud>().each([&](ecs::Entity e, SplatCloud&) { sphere = e; });
        state = &setup_editor(reg, Viewport{1280, 720});
    }
    void frame_once() {
        const FrameContext f{frame, frame / 60.0, 1 / 60.0};
        editor_input_system(reg, f);
        picking::picking_system(reg, f);
        editor_pick_system(reg, f);
        ++frame;
    }
    // Replays a recording whose frames count from the scene's current frame, until every event ran.
    void replay(const std::string& text) {
        auto events = parse_input_recording(text, "test.txt");
        ASSERT_TRUE(events) << events.message();
        for (InputEvent& e : *events) e.frame += frame;
        state->replay = InputReplayer(std::move(*events));
        while (!state->replay->finished() || !state->deferred.empty()) frame_once();
        frame_once();
    }
    picking::ScreenView view() const {
        return picking::make_screen_view(reg.get<Camera>(state->camera), {1280, 720});
    }
    std::vector<std::uint32_t> selected(ecs::Entity e) const { return point_select::selected_points(reg, e); }
    std::size_t lattice_selected() const {
        const auto* sel = reg.try_get<picking::LatticeSelection>(state->active_lattice);
        return sel ? sel->indices.size() : 0;
    }
    std::vector<std::uint8_t> flags(ecs::Entity e) const {
        const PointFlags* f = reg.try_get<PointFlags>(e);
        return f ? f->bits : std::vector<std::uint8_t>{};
    }
    // What point_select gives for the region, with its own caches, as a check of the editor's gesture.
    std::vector<std::uint32_t> expected(const point_select::ScreenRegion& region, bool visible_only) {
        point_select::PointSelectState fresh;
        point_select::ScreenOptions o;
        o.visible_only = visible_only;
        return point_select::points_in_region(reg, fresh, sphere, view(), region, o);
    }
};

constexpr const char* point_mode_on = "0 key tab ctrl\n";

TEST(PointMode, CtrlTabSwitchesAndTodaysKeysStayInLatticeMode) {
    Scene s;
    auto& render = s.reg.set_resource<render::RenderSettings>();
    EXPECT_EQ(s.state->mode, EditMode::lattice);
    s.replay("0 key a shift\n");  // a second lattice: tab cycles them, as before
    const ecs::Entity second = s.state->active_lattice;
    s.replay("0 key tab\n");
    EXPECT_NE(s.state->active_lattice, second);
    EXPECT_EQ(s.state->mode, EditMode::lattice);
    EXPECT_FALSE(render.show_selection);
    s.replay(point_mode_on);
    EXPECT_EQ(s.state->mode, EditMode::points);
    EXPECT_NE(s.state->status.find("point mode"), std::string::npos) << s.state->status;
    EXPECT_TRUE(render.show_selection);  // the renderer tints the selection in point mode only
    EXPECT_FALSE(render.show_weights);
    s.replay("0 set view.weights 1\n");
    EXPECT_TRUE(render.show_weights);
    s.replay("0 key g\n");  // a lattice-mode key does nothing here
    EXPECT_EQ(s.state->tool, Tool::select);
    EXPECT_NE(s.state->status.find("lattice-mode key"), std::string::npos);
    s.replay("0 key a\n");  // all points, not all control points
    EXPECT_EQ(s.selected(s.sphere).size(), 59650u);
    EXPECT_EQ(s.lattice_selected(), 0u);
    s.replay("0 key tab ctrl\n1 key a\n");
    EXPECT_EQ(s.state->mode, EditMode::lattice);
    EXPECT_FALSE(render.show_selection);
    EXPECT_EQ(s.lattice_selected(), 1331u);
    EXPECT_EQ(s.selected(s.sphere).size(), 59650u);  // the points keep theirs
}

TEST(PointMode, BoxLassoAndPolygonSelectWhatPointSelectSays) {
    Scene s;
    s.replay(point_mode_on);
    std::size_t steps = s.state->undo.size();
    // Box, visible only.
    s.replay("0 move 560 280\n1 press left\n2 move 600 320\n3 move 700 420\n4 release left\n");
    const auto box = s.expected(point_select::rect_region({560, 280}, {700, 420}), true);
    EXPECT_GT(box.size(), 500u);
    EXPECT_EQ(s.selected(s.sphere), box);
    EXPECT_EQ(s.state->undo.size(), ++steps);
    // The same box in x-ray (t) takes the back too; shift adds, ctrl removes, ctrl+shift intersects.
    s.replay("0 key t\n1 move 560 280\n2 press left shift\n3 move 700 420\n4 release left shift\n");
    const auto xray = s.expected(point_select::rect_region({560, 280}, {700, 420}), false);
    EXPECT_GT(xray.size(), box.size() + 400);
    EXPECT_EQ(s.selected(s.sphere), xray);
    s.replay("0 move 560 280\n1 press left ctrl+shift\n2 move 630 420\n3 release left ctrl+shift\n");
    const auto half = s.expected(point_select::rect_region({560, 280}, {630, 420}), false);
    EXPECT_EQ(s.selected(s.sphere), half);
    s.replay("0 move 560 280\n1 press left ctrl\n2 move 600 420\n3 release left ctrl\n");
    const auto left = s.expected(point_select::rect_region({560, 280}, {600, 420}), false);
    std::vector<std::uint32_t> rest;
    std::set_difference(half.begin(), half.end(), left.begin(), left.end(), std::back_inserter(rest));
    EXPECT_EQ(s.selected(s.sphere), rest);
    // Lasso (l): the drag's path as a polygon.
    s.replay(
        "0 key l\n1 move 500 300\n2 press left\n3 move 700 280\n4 move 760 420\n5 move 560 460\n"
        "6 release left\n");
    EXPECT_EQ(
        s.selected(s.sphere),
        s.expected(point_select::polygon_region({{500, 300}, {700, 280}, {760, 420}, {560, 460}}), false));
    // Polygon (shift+l): clicked corners, Enter closes.
    s.replay(
        "0 key l shift\n1 move 520 250\n2 press left\n3 release left\n4 move 760 260\n5 press left\n"
        "6 release left\n7 move 640 470\n8 press left\n9 release left\n10 key enter\n");
    EXPECT_EQ(s.selected(s.sphere),
              s.expected(point_select::polygon_region({{520, 250}, {760, 260}, {640, 470}}), false));
    steps += 5;
    EXPECT_EQ(s.state->undo.size(), steps);
    // Undo walks back through them: the x-ray box, then the visible box.
    for (int k = 0; k < 4; ++k) s.replay("0 key z ctrl\n");
    EXPECT_EQ(s.selected(s.sphere), xray);
    s.replay("0 key z ctrl\n");
    EXPECT_EQ(s.selected(s.sphere), box);
}

TEST(PointMode, BrushSphereColourAndClick) {
    Scene s;
    s.replay(point_mode_on + std::string("1 set point.brush_radius 20\n2 key b\n"));
    const std::size_t steps = s.state->undo.size();
    s.replay("0 move 600 360\n1 press left\n2 move 640 360\n3 move 680 360\n4 release left\n");
    std::vector<std::uint32_t> want;
    for (double x : {600.0, 640.0, 680.0}) {
        const auto dab = s.expected(point_select::circle_region({x, 360}, 20), true);
        std::vector<std::uint32_t> merged;
        std::set_union(want.begin(), want.end(), dab.begin(), dab.end(), std::back_inserter(merged));
        want = std::move(merged);
    }
    EXPECT_EQ(s.selected(s.sphere), want);
    EXPECT_EQ(s.state->undo.size(), steps + 1);  // the stroke is one step
    // Click (q): one point; shift+click adds another; ctrl+click removes it again; empty space clears.
    s.replay("0 key q\n1 move 640 360\n2 press left\n3 release left\n");
    ASSERT_EQ(s.selected(s.sphere).size(), 1u);
    const std::uint32_t first = s.selected(s.sphere)[0];
    s.replay("0 move 700 300\n1 press left shift\n2 release left shift\n");
    EXPECT_EQ(s.selected(s.sphere).size(), 2u);
    s.replay("0 move 700 300\n1 press left ctrl\n2 release left ctrl\n");
    EXPECT_EQ(s.selected(s.sphere), std::vector<std::uint32_t>{first});
    s.replay("0 move 40 40\n1 press left\n2 release left\n");
    EXPECT_TRUE(s.selected(s.sphere).empty());
    // Sphere (shift+b): press on the surface, no drag: the set radius about the picked point.
    s.replay("0 set point.sphere_radius 0.3\n1 key b shift\n2 move 640 360\n3 press left\n4 release left\n");
    const auto in_sphere = s.selected(s.sphere);
    ASSERT_GT(in_sphere.size(), 100u);
    const Camera& cam = s.reg.get<Camera>(s.state->camera);
    const glm::dvec3 front = glm::normalize(cam.eye);  // the unit sphere's point facing the eye at the centre
    const SplatCloud& cloud = s.reg.get<SplatCloud>(s.sphere);
    for (std::uint32_t i : in_sphere)
        EXPECT_LT(glm::length(glm::dvec3(cloud.positions[i]) - front), 0.3 + 0.02);
    // Colour (e): the clicked point's colour within the tolerance, every point of the cloud.
    s.replay("0 set point.colour_tolerance 0.05\n1 key e\n2 move 640 360\n3 press left\n4 release left\n");
    const auto by_colour = s.selected(s.sphere);
    ASSERT_FALSE(by_colour.empty());
    const glm::vec3 c = *point_select::point_colour(s.reg, s.sphere, by_colour[by_colour.size() / 2]);
    // Every selected point within twice the tolerance of any other (all within it of the clicked one).
    for (std::uint32_t i : by_colour)
        EXPECT_LE(glm::length(*point_select::point_colour(s.reg, s.sphere, i) - c), 0.1 + 1e-6);
    EXPECT_LT(by_colour.size(), 59650u);
}

TEST(PointMode, AllNoneInvertGrowShrink) {
    Scene s;
    s.replay(point_mode_on +
             std::string("1 key t\n2 move 600 320\n3 press left\n4 move 680 400\n5 release left\n"));
    const std::size_t boxed = s.selected(s.sphere).size();
    ASSERT_GT(boxed, 100u);
    s.replay("0 set point.grow_distance 0.05\n1 key equal ctrl\n");
    const std::size_t grown = s.selected(s.sphere).size();
    EXPECT_GT(grown, boxed);
    s.replay("0 key plus ctrl\n");  // the keypad's +
    EXPECT_GT(s.selected(s.sphere).size(), grown);
    s.replay("0 key minus ctrl\n1 key minus ctrl\n");
    EXPECT_LT(s.selected(s.sphere).size(), grown);
    s.replay("0 key i ctrl\n");
    const std::size_t inverted = s.selected(s.sphere).size();
    EXPECT_GT(inverted, 59650u / 2);
    s.replay("0 key a alt\n");
    EXPECT_TRUE(s.selected(s.sphere).empty());
    s.replay("0 key a\n");
    EXPECT_EQ(s.selected(s.sphere).size(), 59650u);
    s.replay("0 key z ctrl\n1 key z ctrl\n");
    EXPECT_EQ(s.selected(s.sphere).size(), inverted);
}

TEST(PointMode, EveryOperationIsOneUndoStepAndUndoRedoRestoresTheFlags) {
    Scene s;
    s.replay(point_mode_on +
             std::string("1 key t\n2 move 600 320\n3 press left\n4 move 680 400\n5 release left\n"));
    const std::size_t chosen = s.selected(s.sphere).size();
    const auto selected_flags = s.flags(s.sphere);
    struct Op {
        const char* keys;
        const char* label;
    };
    for (const Op& op :
         {Op{"0 key h\n", "hide"}, Op{"0 key x\n", "delete"}, Op{"0 key delete\n", "delete"}}) {
        const std::size_t steps = s.state->undo.position();  // an undone step is dropped by the next
        s.replay(op.keys);
        ASSERT_EQ(s.state->undo.position(), steps + 1) << op.keys;
        ASSERT_EQ(s.state->undo.size(), steps + 1) << op.keys;
        EXPECT_EQ(s.state->undo.at(steps).label(), op.label);
        const point_edit::PointCounts c = point_edit::count_points(s.reg, s.sphere);
        EXPECT_EQ(std::string(op.label) == "hide" ? c.hidden : c.deleted, chosen);
        EXPECT_EQ(c.selected, 0u);
        const auto after = s.flags(s.sphere);
        s.replay("0 key z ctrl\n");
        EXPECT_EQ(s.flags(s.sphere), selected_flags);
        s.replay("0 key z ctrl+shift\n");
        EXPECT_EQ(s.flags(s.sphere), after);
        s.replay("0 key z ctrl\n");
    }
    // Unhide (alt+h) after a hide.
    s.replay("0 key h\n1 key h alt\n");
    EXPECT_EQ(point_edit::count_points(s.reg, s.sphere).hidden, 0u);
    EXPECT_EQ(s.state->undo.at(s.state->undo.position() - 1).label(), "unhide all");
    s.replay("0 key z ctrl\n1 key z ctrl\n");
    EXPECT_EQ(s.flags(s.sphere), selected_flags);
    // Duplicate (shift+d): a new entity with copies, the original untouched and still selected.
    const std::size_t entities = s.reg.count<SplatCloud>();
    s.replay("0 key d shift\n");
    EXPECT_EQ(s.reg.count<SplatCloud>(), entities + 1);
    const ecs::Entity copy = s.state->selected_entity;
    ASSERT_TRUE(s.reg.valid(copy));
    EXPECT_EQ(s.reg.get<Name>(copy).value, "sphere.copy");
    EXPECT_EQ(s.reg.get<SplatCloud>(copy).positions.size(), chosen);
    EXPECT_EQ(s.flags(s.sphere), selected_flags);
    s.replay("0 key z ctrl\n");
    EXPECT_EQ(s.reg.count<SplatCloud>(), entities);
    EXPECT_FALSE(s.reg.valid(copy));
    s.replay("0 key y ctrl\n");
    EXPECT_EQ(s.reg.count<SplatCloud>(), entities + 1);
    EXPECT_EQ(s.reg.get<SplatCloud>(s.state->selected_entity).positions.size(), chosen);
}

TEST(PointMode, SeparationWithALatticeOnThePartUndoesAndRedoes) {
    Scene s;
    s.replay(point_mode_on +
             std::string("1 key t\n2 move 300 40\n3 press left\n4 move 980 360\n5 release left\n"));
    const auto before_flags = s.flags(s.sphere);
    const std::size_t top = s.selected(s.sphere).size();
    ASSERT_GT(top, 20000u);
    const std::size_t steps = s.state->undo.size();
    s.replay(
        "0 key p\n1 key a shift\n2 key tab ctrl\n3 key a\n4 key r\n5 key y\n6 key 4\n7 key 5\n8 key enter\n");
    ASSERT_EQ(s.state->undo.size(), steps + 4);  // separate, add lattice, select all, twist
    // The separation's step: at most 2 bytes a separated point (point_edit's bound) and a constant.
    EXPECT_LE(s.state->undo.at(steps).bytes(), 2 * top + 1024);
    EXPECT_LE(s.state->undo.at(steps - 1).bytes(), 2 * top + 1024);  // the lasso's selection step
    const ecs::Entity part = s.state->selected_entity;
    ASSERT_TRUE(s.reg.valid(part));
    EXPECT_EQ(s.reg.get<Name>(part).value, "sphere.part");
    EXPECT_EQ(s.reg.get<SplatCloud>(part).positions.size(), top);
    EXPECT_EQ(point_edit::count_points(s.reg, s.sphere).deleted, top);
    ASSERT_EQ(s.reg.get<Deformers>(part).lattices.size(), 1u);
    const ecs::Entity lattice = s.reg.get<Deformers>(part).lattices[0];
    EXPECT_EQ(s.state->active_lattice, lattice);
    const Lattice twisted = s.reg.get<Lattice>(lattice);
    EXPECT_NE(twisted.current, twisted.rest);
    const std::vector<glm::vec3> part_points = s.reg.get<SplatCloud>(part).positions;

    for (int k = 0; k < 4; ++k) s.replay("0 key z ctrl\n");
    EXPECT_FALSE(s.reg.valid(part));
    EXPECT_FALSE(s.reg.valid(lattice));
    EXPECT_EQ(s.reg.count<SplatCloud>(), 1u);
    EXPECT_EQ(s.reg.count<Lattice>(), 1u);
    EXPECT_EQ(s.flags(s.sphere), before_flags);  // selected again, none deleted

    for (int k = 0; k < 4; ++k) s.replay("0 key y ctrl\n");
    const ecs::Entity part2 = s.state->undo.resolve(part);
    ASSERT_TRUE(s.reg.valid(part2));
    EXPECT_NE(part2, part);
    EXPECT_EQ(s.state->selected_entity, part2);
    EXPECT_EQ(s.reg.get<SplatCloud>(part2).positions, part_points);
    ASSERT_TRUE(s.reg.has<Deformers>(part2));
    ASSERT_EQ(s.reg.get<Deformers>(part2).lattices.size(), 1u);
    const ecs::Entity lattice2 = s.reg.get<Deformers>(part2).lattices[0];
    ASSERT_TRUE(s.reg.valid(lattice2));
    EXPECT_EQ(lattice2, s.state->undo.resolve(lattice));
    const Lattice& again = s.reg.get<Lattice>(lattice2);
    ASSERT_EQ(again.current.size(), twisted.current.size());
    EXPECT_EQ(std::memcmp(again.current.data(), twisted.current.data(),
                          twisted.current.size() * sizeof(glm::dvec3)),
              0);
    EXPECT_EQ(point_edit::count_points(s.reg, s.sphere).deleted, top);
    // And back once more: a second round trip through new ids.
    for (int k = 0; k < 4; ++k) s.replay("0 key z ctrl\n");
    EXPECT_EQ(s.reg.count<SplatCloud>(), 1u);
    EXPECT_EQ(s.flags(s.sphere), before_flags);
    for (int k = 0; k < 4; ++k) s.replay("0 key y ctrl\n");
    EXPECT_EQ(s.reg.count<SplatCloud>(), 2u);
    EXPECT_EQ(s.reg.get<SplatCloud>(s.state->undo.resolve(part)).positions, part_points);
}

TEST(PointMode, WeightsFromTheSelectionFallOffAndUndo) {
    Scene s;
    s.replay(point_mode_on +
             std::string("1 key t\n2 move 600 320\n3 press left\n4 move 680 400\n5 release left\n"
                         "6 set weight.radius 0.2\n7 set weight.falloff linear\n8 key w shift\n"));
    const PointWeights* w = s.reg.try_get<PointWeights>(s.sphere);
    ASSERT_TRUE(w);
    ASSERT_EQ(w->values.size(), 59650u);
    const auto sel = s.selected(s.sphere);
    const SplatCloud& cloud = s.reg.get<SplatCloud>(s.sphere);
    std::size_t between = 0;
    for (std::size_t i = 0; i < cloud.positions.size(); i += 7) {
        double d = 1e300;
        for (std::uint32_t k : sel)
            d = std::min(d, glm::length(glm::dvec3(cloud.positions[i]) - glm::dvec3(cloud.positions[k])));
        const double want = d <= 0.2 ? 1.0 - d / 0.2 : 0.0;  // linear
        EXPECT_NEAR(w->values[i], want, 1e-6) << i;
        between += want > 0.0 && want < 1.0;
    }
    EXPECT_GT(between, 100u);
    const std::vector<float> painted = w->values;
    s.replay("0 key z ctrl\n");
    EXPECT_TRUE(s.reg.get<PointWeights>(s.sphere).values.empty());  // as before: weight 1 everywhere
    s.replay("0 key y ctrl\n");
    EXPECT_EQ(s.reg.get<PointWeights>(s.sphere).values, painted);
    s.replay("0 key w alt\n");
    EXPECT_TRUE(s.reg.get<PointWeights>(s.sphere).values.empty());
    s.replay("0 key z ctrl\n");
    EXPECT_EQ(s.reg.get<PointWeights>(s.sphere).values, painted);
}

TEST(PointMode, DistanceToTheSelectionIsTheBruteForceOne) {
    std::vector<glm::dvec3> world;
    std::uint32_t seed = 12345;
    auto next = [&] { return (seed = seed * 1664525u + 1013904223u) / 4294967296.0; };
    for (int i = 0; i < 3000; ++i) world.emplace_back(next() * 2 - 1, next() * 2 - 1, next() * 2 - 1);
    std::vector<std::uint32_t> selected;
    for (std::uint32_t i = 0; i < world.size(); i += 37) selected.push_back(i);
    for (double radius : {0.05, 0.3, 1.0}) {
        const std::vector<double> d = distance_to_selection(world, selected, radius);
        for (std::size_t i = 0; i < world.size(); ++i) {
            double best = 1e300;
            for (std::uint32_t k : selected) best = std::min(best, glm::distance(world[i], world[k]));
            if (best <= radius) EXPECT_EQ(d[i], best) << i << " radius " << radius;
            else EXPECT_TRUE(std::isinf(d[i])) << i << " radius " << radius;
        }
    }
}

TEST(PointMode, ReplayFieldsAndKeysRoundTrip) {
    const char* text =
        "1 set point.mode intersect\n2 set weight.falloff sharp\n3 set view.lattice 0\n4 key plus ctrl\n"
        "5 set point.brush_radius 12.5\n6 key tab ctrl\n";
    auto events = parse_input_recording(text, "t.txt");
    ASSERT_TRUE(events) << events.message();
    auto again = parse_input_recording(format_input_recording(*events), "again.txt");
    ASSERT_TRUE(again) << again.message();
    EXPECT_EQ(*again, *events);
    EXPECT_FALSE(parse_input_recording("1 set point.mode sometimes\n", "bad.txt"));
    EXPECT_FALSE(parse_input_recording("1 set point.nothing 1\n", "bad.txt"));
    Scene s;
    s.replay(text);
    EXPECT_EQ(s.state->points.settings.mode, PointMode::intersect);
    EXPECT_EQ(s.state->points.settings.weight_falloff, Falloff::sharp);
    EXPECT_EQ(s.state->points.settings.brush_radius_px, 12.5);
    EXPECT_FALSE(s.state->show_lattice);
    EXPECT_EQ(s.state->mode, EditMode::points);
}

}  // namespace
